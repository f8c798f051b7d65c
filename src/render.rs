//! The render loop (ARCHITECTURE.md): batches of sample points, traced in parallel with rayon,
//! added to the film in a fixed order, so the image depends on the scene, seed and budget only.

use crate::camera::CameraSample;
use crate::film::Film;
use crate::geometry::{is_valid_radiance, Spectrum, Vec2};
use crate::integrator::Integrator;
use crate::scene::Scene;
use crate::stream::SampleStream;
use acr_parser::{Error, PluginDesc, Result};
use acr_plugins::filters::{
    BoxFilter, GaussianFilter, LanczosSincFilter, MitchellFilter, TriangleFilter,
};
use acr_plugins::Kernel;
use rayon::prelude::*;

/// Samples per batch: enough to keep every thread busy, few enough to report progress often.
const BATCH_SAMPLES: usize = 1 << 15;

/// Largest accepted samples per pixel.
pub const MAX_SPP: u32 = 1 << 20;

/// The names of the filters acr knows.
pub const FILTERS: &[&str] = &["box", "triangle", "gaussian", "mitchell", "sinc"];

/// The pixel filter from the `PixelFilter` directive (pbrt-v3's default: box, radius 0.5).
pub fn kernel_from_desc(desc: Option<&PluginDesc>) -> Result<Kernel> {
    let Some(p) = desc else {
        return Ok(Kernel::Box(BoxFilter::new(0.5, 0.5)));
    };
    let params = &p.params;
    let radius = |default: f64| -> Result<(f32, f32)> {
        let rx = params.float_or("xwidth", default)? as f32;
        let ry = params.float_or("ywidth", default)? as f32;
        if !(rx > 0.0 && ry > 0.0 && rx <= 64.0 && ry <= 64.0) {
            return Err(Error::at(
                &p.loc,
                format!("filter radius {rx} x {ry} is out of range (0, 64]"),
            ));
        }
        Ok((rx, ry))
    };
    Ok(match p.kind.as_str() {
        "box" => {
            let (rx, ry) = radius(0.5)?;
            Kernel::Box(BoxFilter::new(rx, ry))
        }
        "triangle" => {
            let (rx, ry) = radius(2.0)?;
            Kernel::Triangle(TriangleFilter::new(rx, ry))
        }
        "gaussian" => {
            let (rx, ry) = radius(2.0)?;
            Kernel::Gaussian(GaussianFilter::new(
                rx,
                ry,
                params.float_or("alpha", 2.0)? as f32,
            ))
        }
        "mitchell" => {
            let (rx, ry) = radius(2.0)?;
            Kernel::Mitchell(MitchellFilter::new(
                rx,
                ry,
                params.float_or("B", 1.0 / 3.0)? as f32,
                params.float_or("C", 1.0 / 3.0)? as f32,
            ))
        }
        "sinc" => {
            let (rx, ry) = radius(4.0)?;
            Kernel::Sinc(LanczosSincFilter::new(
                rx,
                ry,
                params.float_or("tau", 3.0)? as f32,
            ))
        }
        other => {
            let hint = acr_parser::closest(other, FILTERS.iter().copied())
                .map_or(String::new(), |k| format!(" (did you mean {k}?)"));
            return Err(Error::at(
                &p.loc,
                format!(
                    "unknown filter \"{other}\"{hint}; known: {}",
                    FILTERS.join(", ")
                ),
            ));
        }
    })
}

/// Samples per pixel asked for by the `Sampler` directive (pbrt-v3's defaults).
pub fn spp_from_desc(desc: Option<&PluginDesc>) -> Result<u32> {
    let Some(p) = desc else {
        return Ok(16);
    };
    let params = &p.params;
    let spp = if p.kind == "stratified" {
        params.int_or("xsamples", 4)? as i64 * params.int_or("ysamples", 4)? as i64
    } else {
        params.int_or("pixelsamples", 16)? as i64
    };
    check_spp(spp, &p.loc)
}

fn check_spp(spp: i64, loc: &acr_parser::Loc) -> Result<u32> {
    if spp < 1 || spp > MAX_SPP as i64 {
        return Err(Error::at(
            loc,
            format!("{spp} samples per pixel is out of range (1 to {MAX_SPP})"),
        ));
    }
    Ok(spp as u32)
}

/// The raster position of offset `u` in [0, 1)^2 within pixel (px, py). Rounding can carry
/// `py + u.y` to `py + 1` (from row 1024 on, say); the result is kept inside the pixel, so that
/// a sample always lands in the pixel it was drawn for and batches stay sorted by row.
#[inline]
pub fn in_pixel(px: u32, py: u32, u: Vec2) -> Vec2 {
    let below = |i: u32| f32::from_bits((i as f32).to_bits() - 1);
    let p = Vec2::new(px as f32, py as f32) + u;
    p.min(Vec2::new(below(px + 1), below(py + 1)))
}

/// What a render produced besides the image.
#[derive(Clone, Debug, Default)]
pub struct RenderCounts {
    /// Samples traced.
    pub samples: u64,
    /// Rays traced (camera, continuation and shadow).
    pub rays: u64,
    /// Samples whose radiance was NaN, infinite or negative, dropped before the film.
    pub dropped: u64,
}

/// Renders `scene` at `spp` samples per pixel into `film`.
pub fn render(
    scene: &Scene,
    integrator: &Integrator,
    film: &mut Film,
    spp: u32,
    seed: u64,
    progress: Option<&indicatif::ProgressBar>,
) -> RenderCounts {
    let [x0, x1, y0, y1] = scene.film.crop;
    let width = (x1 - x0) as usize;
    let full_width = scene.film.resolution.0 as u64;
    let pixels = width * (y1 - y0) as usize;
    let spp_us = spp as usize;
    let total = pixels * spp_us;
    let dims = scene.dims;
    let mut counts = RenderCounts::default();
    let mut start = 0usize;
    if let Some(p) = progress {
        p.set_length(total as u64);
    }
    // Reused by every batch: a fresh half-megabyte vector per batch costs page faults.
    let mut results: Vec<(Vec2, Spectrum, u32)> = Vec::new();
    let mut valid: Vec<(Vec2, Spectrum)> = Vec::new();
    while start < total {
        // Whole pixels per batch, so a pixel's samples stay together.
        let end = (start + BATCH_SAMPLES.div_ceil(spp_us).max(1) * spp_us).min(total);
        (start..end)
            .into_par_iter()
            .map(|k| {
                let (pixel, index) = (k / spp_us, (k % spp_us) as u32);
                let px = x0 + (pixel % width) as u32;
                let py = y0 + (pixel / width) as u32;
                let key = py as u64 * full_width + px as u64;
                let mut stream = SampleStream::new(key, index, seed, 0);
                let film_pos = in_pixel(px, py, stream.next_2d());
                let time = if dims.time { stream.next_1d() } else { 0.5 };
                let lens = if dims.lens {
                    stream.next_2d()
                } else {
                    Vec2::splat(0.5)
                };
                let ray = scene.camera.generate_ray(&CameraSample {
                    film: film_pos,
                    lens,
                    time,
                });
                let r = integrator.li(scene, ray, &mut stream);
                (film_pos, r.l, r.rays)
            })
            .collect_into_vec(&mut results);
        valid.clear();
        for &(pos, l, rays) in &results {
            counts.rays += rays as u64;
            if is_valid_radiance(l) {
                valid.push((pos, l));
            } else {
                counts.dropped += 1;
            }
        }
        film.add_samples(&valid);
        counts.samples += (end - start) as u64;
        if let Some(p) = progress {
            p.set_position(end as u64);
        }
        start = end;
    }
    counts
}
