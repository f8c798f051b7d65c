//! `acr merge OUT INPUTS...`: crops of one frame, rendered apart (`--cropwindow`,
//! `--pixelbounds`, or a Film cropwindow), placed by their EXR data windows into the whole
//! frame, as pbrt-v4's `imgtool assemble` does. Every pixel of the frame must come from exactly
//! one input.

use crate::image_io::{read_image_with_frame, write_image, Frame, RgbImage};
use std::path::{Path, PathBuf};

/// Assembles the crops `inputs` into `output`.
pub fn command(output: &Path, inputs: &[PathBuf]) -> Result<(), String> {
    if inputs.is_empty() {
        return Err("acr merge needs at least one input image".to_owned());
    }
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
    write_image(output, &image).map_err(|e| format!("{}: {e}", output.display()))
}
