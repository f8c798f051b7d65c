//! Images side by side: per scene, the reference and each method's image, tone-mapped alike
//! and labelled, in one PNG, and the same panels cropped to the window where they differ most
//! and enlarged, for judging reconstructions by eye (docs/BENCHMARKS.md, "Images side by side").

use super::report::register_font;
use crate::image_io::{read_image, RgbImage};
use crate::spectrum::{linear_to_srgb, luminance};
use std::path::{Path, PathBuf};

/// Height of a panel's label strip, in pixels.
const LABEL_H: u32 = 20;
/// Height of the title strip.
const TITLE_H: u32 = 24;
/// Pixels between panels.
const GAP: u32 = 4;
/// The enlarged crop's height is at least this many pixels.
const CROP_H: u32 = 192;

/// A panel: its label and its tone-mapped 8-bit pixels, row-major.
struct Panel {
    /// Its label.
    label: String,
    /// sRGB pixels.
    pixels: Vec<[u8; 3]>,
}

/// A window of the image, in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Window {
    /// Left column.
    x: usize,
    /// Top row.
    y: usize,
    /// Width and height.
    side: usize,
}

/// Writes `OUT/NAME.png` (the reference then every image of `images`, each a label and a file,
/// side by side, the crop outlined) and `OUT/NAME-crop.png` (the crop, enlarged). An image
/// that is missing (its run failed) or of another size is left out, named in the title.
pub(super) fn write_gallery(
    out: &Path,
    name: &str,
    title: &str,
    reference: &RgbImage,
    images: &[(String, PathBuf)],
) -> Result<(), String> {
    let (w, h) = (reference.width, reference.height);
    if w == 0 || h == 0 {
        return Err("empty reference".to_owned());
    }
    let scale = exposure(reference);
    let mut panels = vec![Panel {
        label: "reference".to_owned(),
        pixels: tone_map(reference, scale),
    }];
    let mut missing = Vec::new();
    for (label, path) in images {
        match read_image(path, false) {
            Ok(img) if img.width == w && img.height == h => panels.push(Panel {
                label: label.clone(),
                pixels: tone_map(&img, scale),
            }),
            _ => missing.push(label.as_str()),
        }
    }
    let title = if missing.is_empty() {
        title.to_owned()
    } else {
        format!("{title} (no image: {})", missing.join(", "))
    };
    let side = (w.min(h) / 4).max(16).min(w.min(h));
    let crop = busiest_window(&panels, w, h, side);
    let full = Window {
        x: 0,
        y: 0,
        side: 0,
    };
    draw(
        &out.join(format!("{name}.png")),
        &title,
        &panels,
        (w, h),
        full,
        1,
        Some(crop),
    )?;
    let zoom = (CROP_H as usize).div_ceil(side).max(1) as u32;
    let crop_title = format!(
        "crop x {}..{}, y {}..{}",
        crop.x,
        crop.x + side,
        crop.y,
        crop.y + side
    );
    draw(
        &out.join(format!("{name}-crop.png")),
        &crop_title,
        &panels,
        (w, h),
        crop,
        zoom,
        None,
    )
}

/// One scale for every panel: the reference's 99th-percentile luminance maps to 1, so that a
/// few bright pixels (a light) do not darken the rest.
fn exposure(reference: &RgbImage) -> f32 {
    let mut lum: Vec<f32> = reference
        .pixels
        .iter()
        .map(|&c| luminance(c))
        .filter(|l| l.is_finite())
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    let k = (lum.len() - 1) * 99 / 100;
    let (_, p99, _) = lum.select_nth_unstable_by(k, f32::total_cmp);
    if *p99 > 0.0 {
        1.0 / *p99
    } else {
        1.0
    }
}

/// `img` times `scale`, clamped, in sRGB's 8 bits; NaN as black.
fn tone_map(img: &RgbImage, scale: f32) -> Vec<[u8; 3]> {
    let q = |v: f32| {
        let v = if v.is_nan() { 0.0 } else { v * scale };
        (linear_to_srgb(v.clamp(0.0, 1.0)) * 255.0).round() as u8
    };
    img.pixels
        .iter()
        .map(|c| [q(c.x), q(c.y), q(c.z)])
        .collect()
}

/// The `side` x `side` window where the panels differ most: the largest sum over its pixels of
/// the panels' squared deviations from their mean (summed areas make every window one lookup).
fn busiest_window(panels: &[Panel], w: usize, h: usize, side: usize) -> Window {
    let n = panels.len() as f64;
    let mut sat = vec![0.0f64; (w + 1) * (h + 1)];
    for y in 0..h {
        let mut row = 0.0;
        for x in 0..w {
            let i = y * w + x;
            let mut d = 0.0;
            for c in 0..3 {
                let vals = panels.iter().map(|p| f64::from(p.pixels[i][c]));
                let mean = vals.clone().sum::<f64>() / n;
                d += vals.map(|v| (v - mean) * (v - mean)).sum::<f64>();
            }
            row += d;
            sat[(y + 1) * (w + 1) + x + 1] = sat[y * (w + 1) + x + 1] + row;
        }
    }
    let at = |x: usize, y: usize| sat[y * (w + 1) + x];
    let mut best = (f64::MIN, Window { x: 0, y: 0, side });
    for y in 0..=h - side {
        for x in 0..=w - side {
            let s = at(x + side, y + side) - at(x, y + side) - at(x + side, y) + at(x, y);
            if s > best.0 {
                best = (s, Window { x, y, side });
            }
        }
    }
    best.1
}

/// Draws the panels side by side into `path`: the window `region` of each (the whole image
/// when its side is 0) enlarged `zoom` times, under their labels and `title`, with `outline`
/// drawn on each.
fn draw(
    path: &Path,
    title: &str,
    panels: &[Panel],
    (w, h): (usize, usize),
    region: Window,
    zoom: u32,
    outline: Option<Window>,
) -> Result<(), String> {
    use plotters::prelude::*;
    register_font();
    let (rw, rh) = if region.side == 0 {
        (w, h)
    } else {
        (region.side, region.side)
    };
    let pw = rw as u32 * zoom;
    let ph = rh as u32 * zoom;
    let n = panels.len() as u32;
    let size = (n * pw + (n - 1) * GAP, TITLE_H + LABEL_H + ph);
    let root = BitMapBackend::new(path, size).into_drawing_area();
    let e = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let font = ("sans-serif", 15).into_font().color(&BLACK);
    root.draw(&Text::new(title.to_owned(), (4, 4), font.clone()))
        .map_err(|x| e(&x))?;
    let top = (TITLE_H + LABEL_H) as i32;
    for (k, p) in panels.iter().enumerate() {
        let left = (k as u32 * (pw + GAP)) as i32;
        root.draw(&Text::new(
            p.label.clone(),
            (left + 2, TITLE_H as i32 + 2),
            font.clone(),
        ))
        .map_err(|x| e(&x))?;
        for py in 0..ph as usize {
            let y = region.y + py / zoom as usize;
            for px in 0..pw as usize {
                let x = region.x + px / zoom as usize;
                let [r, g, b] = p.pixels[y * w + x];
                root.draw_pixel((left + px as i32, top + py as i32), &RGBColor(r, g, b))
                    .map_err(|x| e(&x))?;
            }
        }
        if let Some(o) = outline {
            let (x0, y0) = (left + o.x as i32, top + o.y as i32);
            let s = o.side as i32 - 1;
            root.draw(&Rectangle::new(
                [(x0, y0), (x0 + s, y0 + s)],
                RED.stroke_width(1),
            ))
            .map_err(|x| e(&x))?;
        }
    }
    root.present().map_err(|x| e(&x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_busiest_window_is_where_the_panels_disagree() {
        let (w, h) = (40, 30);
        let flat = Panel {
            label: "a".to_owned(),
            pixels: vec![[100; 3]; w * h],
        };
        let mut spot = Panel {
            label: "b".to_owned(),
            pixels: vec![[100; 3]; w * h],
        };
        for y in 20..26 {
            for x in 30..36 {
                spot.pixels[y * w + x] = [250, 0, 0];
            }
        }
        let win = busiest_window(&[flat, spot], w, h, 8);
        assert!(win.x <= 30 && win.x + 8 >= 36, "{win:?}");
        assert!(win.y <= 20 && win.y + 8 >= 26, "{win:?}");
    }

    #[test]
    fn tone_mapping_is_one_scale_for_all() {
        let img = RgbImage {
            width: 2,
            height: 1,
            pixels: vec![
                crate::geometry::Spectrum::splat(0.5),
                crate::geometry::Spectrum::new(f32::NAN, 2.0, 0.0),
            ],
        };
        let t = tone_map(&img, 2.0);
        assert_eq!(t[0], [255; 3]);
        assert_eq!(t[1], [0, 255, 0]);
    }
}
