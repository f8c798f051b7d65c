//! pbrt-v3's pixel reconstruction filters: each sample is splatted into every pixel whose
//! centre lies within the filter's radius, weighted by the filter at the offset.

mod band_plan;
mod boxf;
mod gaussian;
mod mitchell;
mod nfor;
mod polynomial;
mod sinc;
mod triangle;

pub use band_plan::BandPlan;
pub use boxf::BoxFilter;
pub use gaussian::GaussianFilter;
pub use mitchell::MitchellFilter;
pub use nfor::NforFilter;
pub use polynomial::PolynomialFilter;
pub use sinc::LanczosSincFilter;
pub use triangle::TriangleFilter;

use crate::cells::CellView;
use crate::color::Spectrum;
use crate::film::Film;
pub use crate::kernel::FilterKernel;
use crate::partition::Partition;
use crate::registry::{Choice, Entry};
use acr_parser::{Error, ParamList, Result};

/// A reconstruction filter: turns the film into the image.
pub trait Filter: Send + Sync {
    /// The plugin's name (`box`, `gaussian`, ...).
    fn name(&self) -> &'static str;

    /// The kernel the film splats samples with while rendering (box of radius 0.5 for a
    /// filter that reconstructs from per-pixel statistics instead).
    fn kernel(&self) -> &dyn FilterKernel;

    /// The image, row-major over the film's (cropped) pixels, from the film and what the
    /// sampler hands over.
    fn reconstruct(&self, film: &Film, from: SamplerOutput<'_>) -> Vec<Spectrum>;

    /// The cells (`cellsize` pixels, `bins` per non-image dim) the film must collect for this
    /// filter when the sampler keeps none; None for a filter that needs no cells.
    fn cell_layout(&self) -> Option<(f64, u32)> {
        None
    }

    /// The clusters the last reconstruction fitted, per pixel of the cropped film (the
    /// cluster of the cell under each pixel's centre); None for a filter that fits none.
    fn fit_partition(&self) -> Option<Partition> {
        None
    }

    /// Whether the filter reads the samples' first-hit features from the film's cells: the
    /// film then collects cells with them, whatever the sampler keeps.
    fn reads_features(&self) -> bool {
        false
    }

    /// Whether the filter reads the film's per-pixel half buffers ([`Film::keep_pixel_buffers`]):
    /// the film then keeps them, with every sample's first-hit features, and the filter is
    /// given the whole film even when the sampler's streams are split.
    fn reads_pixel_buffers(&self) -> bool {
        false
    }

    /// Whether the reconstruction reads the means or deviations of the pixels' own samples
    /// ([`Film::pixel_stats`]) after a sampler that does not read the film
    /// ([`crate::Sampler::reads_film`]); one that does not lets the film count them only
    /// ([`Film::count_only`]). By default, it may.
    fn reads_pixel_stats(&self) -> bool {
        true
    }

    /// What the last reconstruction reports for the stats file (nothing, for a splatting
    /// filter).
    fn report(&self) -> FilterReport {
        FilterReport::default()
    }

    /// The reconstruction's own estimate of each pixel's squared error (row-major over the
    /// cropped film, in the image's units squared) from the film as it stands, for a sampler
    /// that sends samples where the reconstructed image is worst (docs/reconstruction.md);
    /// None for a filter that makes no such estimate.
    fn estimated_error(&self, _film: &Film) -> Option<Vec<f32>> {
        None
    }

    /// How the filter makes an image of `height` rows band by band in a render by bands
    /// (docs/reconstruction.md, "Rendering by bands"): each band of rows from those rows and
    /// its halo alone, so that the film need hold no more; None for a filter that needs the
    /// whole film at once.
    fn bands(&self, height: usize) -> Option<BandPlan> {
        let _ = height;
        None
    }

    /// The image's rows `rows` (crop rows, a band of [`Filter::bands`]'s layout), from a film
    /// that holds at least the rows [`BandPlan::read`] names; by default, from the whole film.
    fn reconstruct_rows(&self, film: &Film, rows: std::ops::Range<usize>) -> Vec<Spectrum> {
        let w = film.settings().size().0 as usize;
        let mut image = self.reconstruct(film, SamplerOutput::default());
        image.truncate(rows.end * w);
        image.split_off(rows.start * w)
    }
}

/// A reconstruction's figures for the stats file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FilterReport {
    /// Clusters fitted at degree 0, 1 and 2 (the polynomial reconstruction).
    pub fitted_by_degree: Option<[u64; 3]>,
}

/// What a sampler hands the reconstruction besides the film.
#[derive(Clone, Copy, Debug, Default)]
pub struct SamplerOutput<'a> {
    /// Its partition of the image into clusters, when it has one (an adaptive sampler).
    pub partition: Option<&'a Partition>,
    /// Its cells and clusters, when it keeps them.
    pub cells: Option<CellView<'a>>,
}

/// pbrt-v3's filters: the film splats each sample with the kernel, and a pixel is the
/// weighted mean of what reached it.
#[derive(Clone, Debug)]
pub struct Splatting<K> {
    name: &'static str,
    kernel: K,
}

impl<K: FilterKernel> Splatting<K> {
    /// The splatting filter `name` with `kernel`.
    pub fn new(name: &'static str, kernel: K) -> Self {
        Self { name, kernel }
    }
}

impl<K: FilterKernel> Filter for Splatting<K> {
    fn name(&self) -> &'static str {
        self.name
    }

    fn kernel(&self) -> &dyn FilterKernel {
        &self.kernel
    }

    fn reads_pixel_stats(&self) -> bool {
        // Only after an adaptive sampler, which reads the film itself.
        false
    }

    fn reconstruct(&self, film: &Film, from: SamplerOutput<'_>) -> Vec<Spectrum> {
        match from.partition {
            // An adaptive sampler spread its samples unevenly over the image.
            Some(_) => filter_pixel_means(film, &self.kernel),
            None => film.pixels(),
        }
    }
}

/// The image from each pixel's own mean, filtered with `kernel` at pixel-centre offsets. Used
/// after an adaptive sampler: splatting weighs every sample alike, so a pixel with 60 samples
/// would outweigh a neighbour with 4 under a wide kernel and pull it toward its own value
/// (measured on motion-blur-3d at 16 spp: 4x stratified+gaussian's MSE when splatted). For
/// the box filter of radius 0.5 it is the splatted image itself.
pub fn filter_pixel_means(film: &Film, kernel: &dyn FilterKernel) -> Vec<Spectrum> {
    use rayon::prelude::*;
    let (w, h) = film.settings().size();
    let (w, h) = (w as i64, h as i64);
    let stats = film.pixel_stats();
    let stats = &*stats;
    let (rx, ry) = kernel.radius();
    let mut taps = Vec::new();
    for dy in -(ry.floor() as i64)..=ry.floor() as i64 {
        for dx in -(rx.floor() as i64)..=rx.floor() as i64 {
            let k = kernel.eval(dx as f32, dy as f32);
            if k != 0.0 {
                taps.push((dx, dy, f64::from(k)));
            }
        }
    }
    (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            let (taps, stats) = (&taps, stats);
            (0..w).map(move |x| {
                let (mut sum, mut weight) = ([0.0f64; 3], 0.0f64);
                for &(dx, dy, k) in taps {
                    let (qx, qy) = (x + dx, y + dy);
                    if qx < 0 || qy < 0 || qx >= w || qy >= h {
                        continue;
                    }
                    let s = &stats[(qy * w + qx) as usize];
                    if s.count == 0 {
                        continue;
                    }
                    let mean = s.mean();
                    for (acc, v) in sum.iter_mut().zip([mean.x, mean.y, mean.z]) {
                        *acc += k * f64::from(v);
                    }
                    weight += k;
                }
                if weight == 0.0 {
                    return Spectrum::ZERO;
                }
                // Negative lobes (Mitchell, sinc) can make a mean slightly negative.
                Spectrum::new(
                    (sum[0] / weight) as f32,
                    (sum[1] / weight) as f32,
                    (sum[2] / weight) as f32,
                )
                .max(Spectrum::ZERO)
            })
        })
        .collect()
}

/// Builds a filter from its checked parameters.
pub type FilterBuild = fn(&Choice) -> Result<Box<dyn Filter>>;

/// Every filter, by name: a new filter is one file and one line here.
pub static FILTERS: &[Entry<FilterBuild>] = &[
    boxf::ENTRY,
    triangle::ENTRY,
    gaussian::ENTRY,
    mitchell::ENTRY,
    sinc::ENTRY,
    polynomial::ENTRY,
    nfor::ENTRY,
];

/// Doc of the `xwidth` parameter every pbrt-v3 filter has.
pub(crate) const XWIDTH: &str = "half-width of the support in x, in pixels";
/// Doc of the `ywidth` parameter every pbrt-v3 filter has.
pub(crate) const YWIDTH: &str = "half-width of the support in y, in pixels";

/// The filter's half-widths (`xwidth`, `ywidth`), each in (0, 64] pixels.
pub(crate) fn radius(params: &ParamList, default: f64) -> Result<(f32, f32)> {
    let get = |name: &str| -> Result<f32> {
        let v = params.float_or(name, default)?;
        if !(v > 0.0 && v <= 64.0) {
            if let Some(p) = params.get(name) {
                return Err(Error::at(
                    &p.loc,
                    format!("{name} {v} is out of range (0, 64]"),
                ));
            }
        }
        Ok(v as f32)
    };
    Ok((get("xwidth")?, get("ywidth")?))
}

/// A float parameter that must be finite.
pub(crate) fn finite(params: &ParamList, name: &str, default: f64) -> Result<f32> {
    let v = params.float_or(name, default)?;
    if !v.is_finite() {
        if let Some(p) = params.get(name) {
            return Err(Error::at(&p.loc, format!("{name} must be finite")));
        }
    }
    Ok(v as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Midpoint-rule integral over the support.
    fn integral(k: &dyn FilterKernel) -> f64 {
        let (rx, ry) = k.radius();
        let n = 400;
        let (dx, dy) = (2.0 * rx as f64 / n as f64, 2.0 * ry as f64 / n as f64);
        let mut sum = 0.0;
        for j in 0..n {
            for i in 0..n {
                let x = -rx as f64 + (i as f64 + 0.5) * dx;
                let y = -ry as f64 + (j as f64 + 0.5) * dy;
                sum += k.eval(x as f32, y as f32) as f64;
            }
        }
        sum * dx * dy
    }

    #[test]
    fn kernels_are_zero_outside_and_symmetric() {
        let kernels: [&dyn FilterKernel; 5] = [
            &BoxFilter::new(0.5, 0.5),
            &TriangleFilter::new(2.0, 2.0),
            &GaussianFilter::new(2.0, 2.0, 2.0),
            &MitchellFilter::new(2.0, 2.0, 1.0 / 3.0, 1.0 / 3.0),
            &LanczosSincFilter::new(4.0, 4.0, 3.0),
        ];
        for k in kernels {
            let (rx, ry) = k.radius();
            assert_eq!(k.eval(rx * 1.01, 0.0), 0.0);
            assert_eq!(k.eval(0.0, -ry * 1.01), 0.0);
            for (x, y) in [(0.3, 0.1), (0.45, -0.2), (0.1, 0.4)] {
                assert!((k.eval(x, y) - k.eval(-x, -y)).abs() < 1e-6);
            }
            assert!(integral(k) > 0.0);
        }
    }

    #[test]
    fn pixel_means_filtered_ignore_sample_counts() {
        use crate::film::FilmSettings;
        use glam::Vec2;
        // Two pixels, one with 60 samples of 1, one with 4 samples of 0: a wide gaussian
        // splat leans toward the crowded pixel, the filtered means weigh the pixels alike.
        let g = GaussianFilter::new(2.0, 2.0, 2.0);
        let mut film = Film::new(FilmSettings::with_resolution(2, 1), &g);
        let mut samples = Vec::new();
        for i in 0..60 {
            samples.push((Vec2::new(0.05 + i as f32 * 0.015, 0.5), Spectrum::ONE));
        }
        for i in 0..4 {
            samples.push((Vec2::new(1.1 + i as f32 * 0.2, 0.5), Spectrum::ZERO));
        }
        film.add_samples(&samples);
        let splat = film.pixels();
        let means = filter_pixel_means(&film, &g);
        let k = f64::from(g.eval(1.0, 0.0)) / f64::from(g.eval(0.0, 0.0));
        assert!(
            (f64::from(means[1].x) - k / (1.0 + k)).abs() < 1e-5,
            "{means:?}"
        );
        assert!(splat[1].x > means[1].x + 0.2, "{splat:?} vs {means:?}");
        // The box filter of radius 0.5: the splat itself.
        let b = BoxFilter::new(0.5, 0.5);
        let mut film = Film::new(FilmSettings::with_resolution(2, 1), &b);
        film.add_samples(&samples);
        assert_eq!(filter_pixel_means(&film, &b), film.pixels());
    }

    #[test]
    fn formulas_match_pbrt_v3() {
        let g = GaussianFilter::new(2.0, 2.0, 2.0);
        let e = (-2.0f32 * 4.0).exp();
        assert!((g.eval(1.0, 0.0) - ((-2.0f32).exp() - e) * (1.0 - e)).abs() < 1e-6);
        let t = TriangleFilter::new(2.0, 2.0);
        assert!((t.eval(0.5, 1.0) - 1.5 * 1.0).abs() < 1e-6);
        // Mitchell-Netravali with B = C = 1/3 at the centre: (6 - 2B) / 6 per axis.
        let m = MitchellFilter::new(2.0, 2.0, 1.0 / 3.0, 1.0 / 3.0);
        let c = (6.0 - 2.0 / 3.0) / 6.0;
        assert!((m.eval(0.0, 0.0) - c * c).abs() < 1e-6);
        let s = LanczosSincFilter::new(4.0, 4.0, 3.0);
        assert!((s.eval(0.0, 0.0) - 1.0).abs() < 1e-6);
        assert!(s.eval(1.0, 0.0).abs() < 1e-6);
        assert_eq!(BoxFilter::new(0.5, 0.5).eval(0.49, -0.49), 1.0);
    }
}
