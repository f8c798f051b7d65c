//! `acr merge OUT INPUTS...`: either sample ranges of one crop (mergeable EXRs from
//! `acr render --mergeable --sample-offset K`), whose weighted sums add up to the render of all
//! their samples, or crops of one frame, rendered apart (`--cropwindow`, `--pixelbounds`, or a
//! Film cropwindow), placed by their EXR data windows into the whole frame, as pbrt-v4's
//! `imgtool assemble` does (every pixel of the frame from exactly one input).

use super::mergeable::Sums;
use crate::exr_channels::read_attribute;
use crate::geometry::Spectrum;
use crate::image_io::{is_exr, read_image_with_frame, write_image, Frame, RgbImage};
use std::path::{Path, PathBuf};

/// Merges `inputs`, sample ranges of one crop or crops of one frame, into `output`.
pub fn command(output: &Path, inputs: &[PathBuf]) -> Result<(), String> {
    if inputs.is_empty() {
        return Err("acr merge needs at least one input image".to_owned());
    }
    if let Some(total) = sample_ranges(inputs)? {
        return write_sums(output, &total);
    }
    let (image, owner) = assemble_crops(inputs)?;
    check_one_scene(inputs)?;
    check_covered(&image, &owner)?;
    write_image(output, &image).map_err(|e| format!("{}: {e}", output.display()))
}

/// The sums of `inputs` added, when they are sample ranges of one crop (mergeable EXRs of
/// the same crop, their ranges apart); `None` when they are not.
fn sample_ranges(inputs: &[PathBuf]) -> Result<Option<Sums>, String> {
    let read = |p: &PathBuf| Sums::read(p).map_err(|e| format!("{}: {e}", p.display()));
    let first = if is_exr(&inputs[0]) {
        read(&inputs[0])?
    } else {
        None
    };
    let Some(mut total) = first else {
        return Ok(None);
    };
    if inputs.len() > 1 && inputs.iter().all(|p| p == &inputs[0]) {
        return Err("the same sample range given more than once".to_owned());
    }
    let same_crop =
        |s: &Sums| (s.frame, s.width, s.height) == (total.frame, total.width, total.height);
    let ranges = inputs[1..]
        .iter()
        .map(|p| Ok((p, read(p)?)))
        .collect::<Result<Vec<_>, String>>()?;
    if !ranges
        .iter()
        .all(|(_, s)| s.as_ref().is_some_and(same_crop))
    {
        return Ok(None);
    }
    check_apart(&inputs[0], &total, &ranges)?;
    for (p, s) in &ranges {
        if let Some(s) = s {
            total.add(s).map_err(|e| format!("{}: {e}", p.display()))?;
        }
    }
    Ok(Some(total))
}

/// Fails when two sample ranges overlap: `first`'s (`total`) and the others'.
fn check_apart(
    first: &Path,
    total: &Sums,
    ranges: &[(&PathBuf, Option<Sums>)],
) -> Result<(), String> {
    let mut known: Vec<(std::ops::Range<u64>, &Path)> = ranges
        .iter()
        .filter_map(|(p, s)| Some((s.as_ref()?.range()?, p.as_path())))
        .collect();
    if let Some(r) = total.range() {
        known.push((r, first));
    }
    known.sort_by_key(|(r, _)| (r.start, r.end));
    for pair in known.windows(2) {
        let ((a, pa), (b, pb)) = (&pair[0], &pair[1]);
        if b.start < a.end {
            return Err(format!(
                "{} holds samples {}..{} and {} samples {}..{}: sample ranges must not overlap \
                 (render the next range with --sample-offset {})",
                pa.display(),
                a.start,
                a.end,
                pb.display(),
                b.start,
                b.end,
                a.end
            ));
        }
    }
    Ok(())
}

/// The crops `inputs` placed into their frame by their data windows, and which input (1 on)
/// each pixel came from (0: none). Crops of different frames or that overlap are errors.
fn assemble_crops(inputs: &[PathBuf]) -> Result<(RgbImage, Vec<u32>), String> {
    let mut frame: Option<Frame> = None;
    let mut image = RgbImage::new(0, 0);
    let mut owner: Vec<u32> = Vec::new();
    for (k, path) in inputs.iter().enumerate() {
        let (crop, f) =
            read_image_with_frame(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let first = *frame.get_or_insert(f);
        if (f.width, f.height) != (first.width, first.height) {
            return Err(format!(
                "{}: a crop of a {}x{} frame, not of the {}x{} frame of {}",
                path.display(),
                f.width,
                f.height,
                first.width,
                first.height,
                inputs[0].display()
            ));
        }
        if image.pixels.is_empty() {
            image = RgbImage::new(f.width, f.height);
            owner = vec![0; f.width * f.height];
        }
        for y in 0..crop.height {
            for x in 0..crop.width {
                let i = (f.y0 + y) * f.width + f.x0 + x;
                if owner[i] != 0 {
                    return Err(format!(
                        "{}: pixel ({}, {}) is also in {}; crops must not overlap",
                        path.display(),
                        f.x0 + x,
                        f.y0 + y,
                        inputs[owner[i] as usize - 1].display()
                    ));
                }
                owner[i] = k as u32 + 1;
                image.pixels[i] = crop.pixels[y * crop.width + x];
            }
        }
    }
    Ok((image, owner))
}

/// Fails when the inputs that carry a `sceneHash` were rendered from different scenes.
fn check_one_scene(inputs: &[PathBuf]) -> Result<(), String> {
    let mut scenes = inputs
        .iter()
        .filter_map(|p| Some((p, read_attribute(p, "sceneHash")?)));
    if let Some((first, hash)) = scenes.next() {
        if let Some((other, _)) = scenes.find(|(_, h)| *h != hash) {
            return Err(format!(
                "{} was rendered from another scene than {} (their sceneHash attributes differ)",
                other.display(),
                first.display()
            ));
        }
    }
    Ok(())
}

/// Fails when a pixel of the frame is in no input (`owner` 0).
fn check_covered(image: &RgbImage, owner: &[u32]) -> Result<(), String> {
    if let Some(i) = owner.iter().position(|&o| o == 0) {
        let missing = owner.iter().filter(|&&o| o == 0).count();
        let w = image.width;
        return Err(format!(
            "{missing} pixels of the {}x{} frame are in no input, the first at ({}, {})",
            w,
            image.height,
            i % w,
            i / w
        ));
    }
    Ok(())
}

/// Writes merged sample ranges: a mergeable EXR again (so merges chain), or the image alone
/// in another format.
fn write_sums(output: &Path, total: &Sums) -> Result<(), String> {
    if is_exr(output) {
        return total
            .write(output)
            .map_err(|e| format!("{}: {e}", output.display()));
    }
    let image = RgbImage {
        width: total.width,
        height: total.height,
        pixels: total
            .image()
            .into_iter()
            .map(|[r, g, b]| Spectrum::new(r, g, b))
            .collect(),
    };
    write_image(output, &image).map_err(|e| format!("{}: {e}", output.display()))
}
