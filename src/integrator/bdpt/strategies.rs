//! pbrt-v3's `visualizestrategies` and `visualizeweights`: one image per strategy (depth, s,
//! t), `bdpt_dDD_sSS_tTT.exr` beside the output, each the strategy's contributions splatted
//! where they land (at the camera sample's raster position, or for t = 1 where the light path
//! reaches the film), scaled as the film scales its splats. A debugging aid: the images are
//! summed under a lock from every thread, so their last bits may depend on the thread count.

use crate::geometry::{Spectrum, Vec2};
use crate::image_io::{write_image, RgbImage};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Mutex;

/// What the strategy images show.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visualize {
    /// Each strategy's contribution without its MIS weight (`visualizestrategies`).
    Strategies,
    /// Each strategy's weighted contribution (`visualizeweights`).
    Weights,
}

/// The images being summed: the film's size and, by (depth, s, t), the per-pixel sums.
struct Images {
    width: u32,
    height: u32,
    sums: BTreeMap<(usize, usize, usize), Vec<[f64; 3]>>,
}

/// The render's strategy images (one render at a time asks for them).
static IMAGES: Mutex<Option<Images>> = Mutex::new(None);

/// Starts empty strategy images for a film of `resolution`.
pub fn start(resolution: (u32, u32)) {
    if let Ok(mut g) = IMAGES.lock() {
        *g = Some(Images {
            width: resolution.0,
            height: resolution.1,
            sums: BTreeMap::new(),
        });
    }
}

/// Adds one sample's strategy contributions: (s, t, raster position, value).
pub fn add(contributions: &[(usize, usize, Vec2, Spectrum)]) {
    let Ok(mut g) = IMAGES.lock() else { return };
    let Some(images) = g.as_mut() else { return };
    let (w, h) = (images.width, images.height);
    for &(s, t, p, v) in contributions {
        let (x, y) = (p.x.floor(), p.y.floor());
        if !(x >= 0.0 && y >= 0.0 && x < w as f32 && y < h as f32 && v.is_finite()) {
            continue;
        }
        let sums = images
            .sums
            .entry((s + t - 2, s, t))
            .or_insert_with(|| vec![[0.0; 3]; (w * h) as usize]);
        let i = y as usize * w as usize + x as usize;
        for c in 0..3 {
            sums[i][c] += f64::from(v[c]);
        }
    }
}

/// Writes every strategy image beside `output` (pbrt-v3's names), its sums times `scale`
/// (full-film pixels over the light subpaths traced), and forgets them.
pub fn finish(output: &Path, scale: f64) -> Result<(), String> {
    let Some(images) = IMAGES.lock().ok().and_then(|mut g| g.take()) else {
        return Ok(());
    };
    let dir = output.parent().unwrap_or(Path::new(""));
    for ((depth, s, t), sums) in images.sums {
        let image = RgbImage {
            width: images.width as usize,
            height: images.height as usize,
            pixels: sums
                .iter()
                .map(|p| {
                    Spectrum::new(
                        (p[0] * scale) as f32,
                        (p[1] * scale) as f32,
                        (p[2] * scale) as f32,
                    )
                })
                .collect(),
        };
        let name = format!("bdpt_d{depth:02}_s{s:02}_t{t:02}.exr");
        write_image(&dir.join(&name), &image).map_err(|e| format!("{name}: {e}"))?;
    }
    Ok(())
}
