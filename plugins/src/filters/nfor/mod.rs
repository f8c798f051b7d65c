//! `nfor`: nonlinearly weighted first-order regression (Bitterli et al. 2016), the design
//! docs/reconstruction.md describes. The film keeps two halves of each pixel's samples (by
//! index parity) with their first-hit features; the features are prefiltered by NL-means
//! across the halves; each half's colour is regressed on the features in a window, weighted
//! by NL-means on the other half's colour, at several bandwidths; the unfiltered mean and the
//! fits are candidates, and each pixel takes the one whose MSE, estimated from the halves,
//! is lowest, the choice smoothed.

// Small fixed-size channel and matrix loops read clearest with indices.
#![allow(clippy::needless_range_loop)]

mod nlmeans;
mod planes;
mod regression;
mod selection;

use super::{BandPlan, BoxFilter, Filter, FilterBuild, FilterKernel, SamplerOutput};
use crate::film::{Film, PixelBuffers, Spectrum};
use crate::first_hit::FEATURES;
use crate::registry::{float_in, int_in, Choice, Entry, Kind, ParamSpec, PluginInfo};
use acr_parser::{ParamType, Result};
use nlmeans::{nl_means, Guide};
use planes::{depth_scale, FeatureHalves, Inputs, Planes, TILE, VARIANCE_RADIUS};
use regression::Regression;
use selection::{candidate_mse, select, Candidate, Selected, Smoothing};
use std::ops::Range;

/// The regression window's radius by default.
pub const RADIUS: u32 = 3;
/// The NL-means patch radius by default (NFOR's and Tungsten's).
pub const PATCH: u32 = 3;
/// The feature prefilter's window radius by default: 2 measured within 3% of 3 on the five
/// scenes at 8 and 64 spp, at about half the prefilter's time (docs/reconstruction.md, "Cost").
pub const PREFILTER_RADIUS: u32 = 2;
/// The radius of the window that smooths the MSE estimates and the choice.
pub const SELECT_RADIUS: u32 = 3;
/// The ridge on the slopes, relative to the weights' sum.
pub const RIDGE: f64 = 1e-3;
/// The rows of a band by default: the image is filtered a band of rows at a time, each with
/// a halo of the windows' reach, so that the filter's planes are a band's, not the image's
/// (docs/reconstruction.md, "Memory"). A render by bands takes fewer on images over
/// 2 x BAND rows ([`NforFilter::render_band`]).
pub const BAND: u32 = 256;
/// The regressions' fits on every STRIDE-th pixel in each direction by default
/// (docs/reconstruction.md, "Cost").
pub const STRIDE: u32 = 2;
/// The NL-means bandwidths of the regression's candidates. NFOR's are 0.5 and 1 with a
/// variance shared by the halves; with each half's own (unbiased) variance, 1 and 2 measured
/// lower (docs/reconstruction.md).
const BANDWIDTHS: [f32; 2] = [1.0, 2.0];
/// The unfiltered mean's estimated MSE (its variance) is taken at this multiple in the
/// choice. The lowest of noisy estimates is chosen, so the choice favours estimates that came
/// out low by chance, and a pixel's variance from its few samples is the noisiest of them
/// (heavy-tailed light is mostly missed at 8 samples). Measured against 1 (8 spp, MSE over
/// stratified+gaussian's): indirect-room 0.077 to 0.061, depth-of-field 0.241 to 0.231,
/// motion-blur 0.210 to 0.202, the Cornell box 0.114 to 0.110; 4 was within 5% of 2.
const MEAN_MSE_FACTOR: f32 = 2.0;
/// The second pass's bandwidth (NFOR's).
const SECOND_PASS_K: f32 = 1.0;
/// The feature prefilter's bandwidth (NFOR's).
const PREFILTER_K: f32 = 0.5;

/// The NFOR reconstruction.
#[derive(Clone, Debug)]
pub struct NforFilter {
    radius: usize,
    patch: usize,
    prefilter_radius: usize,
    select_radius: usize,
    ridge: f32,
    /// The regressions fit every `stride`-th pixel in each direction.
    stride: usize,
    /// Whether NFOR's second pass runs.
    second_pass: bool,
    /// The rows of a band (0: the whole image at once; None: by default, [`BAND`], or in a
    /// render by bands [`NforFilter::render_band`]).
    band: Option<usize>,
    /// The film keeps pixel statistics only: a box of one pixel.
    kernel: BoxFilter,
}

impl Default for NforFilter {
    fn default() -> Self {
        Self::new(RADIUS, PATCH, PREFILTER_RADIUS, SELECT_RADIUS, RIDGE).with_second_pass(true)
    }
}

impl NforFilter {
    /// The filter with its windows' radii and ridge.
    pub fn new(radius: u32, patch: u32, prefilter: u32, select: u32, ridge: f64) -> Self {
        Self {
            radius: radius as usize,
            patch: patch as usize,
            prefilter_radius: prefilter as usize,
            select_radius: select as usize,
            ridge: ridge as f32,
            stride: STRIDE as usize,
            second_pass: true,
            band: None,
            kernel: BoxFilter::new(0.5, 0.5),
        }
    }

    /// The filter with its regressions' fits on every `stride`-th pixel in each direction.
    pub fn with_stride(mut self, stride: u32) -> Self {
        self.stride = stride.max(1) as usize;
        self
    }

    /// The filter with NFOR's second pass on or off.
    pub fn with_second_pass(mut self, on: bool) -> Self {
        self.second_pass = on;
        self
    }

    /// The filter with bands of `rows` rows, or by default ([`NforFilter::render_band`]).
    fn with_band_or_default(self, rows: Option<u32>) -> Self {
        match rows {
            Some(rows) => self.with_band(rows),
            None => self,
        }
    }

    /// The filter with bands of `rows` rows (0: the whole image at once).
    pub fn with_band(mut self, rows: u32) -> Self {
        self.band = Some(rows as usize);
        self
    }

    /// The rows of a band in a render by bands of an image of `height` rows, by default: the
    /// half buffers and the filter's planes of a band and its halo are about 370 bytes a
    /// pixel, the splatting film's whole image 60, so a band and its halo over a quarter of
    /// the image keep the peak near 1.5 times a splatting render's (docs/reconstruction.md,
    /// "Rendering by bands"): that many rows, on the tile grid, 64 to [`BAND`]. Images of
    /// up to 2 x BAND rows keep BAND (a band or two: smaller bands would cost time there).
    fn render_band(&self, height: usize, halo: usize) -> usize {
        if let Some(b) = self.band {
            return b;
        }
        let band = BAND as usize;
        if height <= 2 * band {
            return band;
        }
        ((height / 4).saturating_sub(2 * halo) / TILE * TILE).clamp(64, band)
    }

    /// How far, in pixels, the filtered value of a pixel reaches into its inputs: the sum of
    /// each step's windows (features prefiltered, the collaborative regression, the two
    /// smoothings of the choice, the second pass).
    fn reach(&self, second: bool) -> usize {
        let (r, p) = (self.radius, self.patch);
        let prefiltered = self.prefilter_radius + p;
        // Each fit reads its window's features and guide patches; its predictions go a
        // window further.
        let fits = 2 * r + prefiltered.max(p + VARIANCE_RADIUS as usize);
        // The choice's two NL-means smoothings have a patch of 1.
        let first = fits + 2 * (self.select_radius + 1);
        if second {
            2 * r + p + first
        } else {
            first
        }
    }

    /// The bands of `band` rows (with `second`, for the second pass's reach too): a halo that
    /// covers [`NforFilter::reach`], band and halo on the tile grid.
    fn plan(&self, band: usize, second: bool) -> BandPlan {
        BandPlan {
            rows: band.next_multiple_of(TILE),
            halo: self.reach(second).next_multiple_of(TILE),
        }
    }

    /// The bands of a render by bands of an image of `height` rows.
    fn render_plan(&self, height: usize) -> BandPlan {
        let halo = self.plan(0, self.second_pass).halo;
        self.plan(self.render_band(height, halo), self.second_pass)
    }

    /// The filtered image and its estimated per-pixel MSE (bandwidths `ks`; with `second`,
    /// the second pass too), band by band: `take` gets each band's image and MSE (over the
    /// band's rows with their halo) and the band's own rows within them, top band first.
    /// Each band's halo covers [`NforFilter::reach`] and band and halo start on the tile grid,
    /// so every pixel is computed as from the whole image, byte for byte.
    fn by_bands(
        &self,
        b: &PixelBuffers,
        ks: &[f32],
        second: bool,
        mut take: impl FnMut(&Planes, &[f32], Range<usize>),
    ) {
        let h = b.size().1 as usize;
        let depth = depth_scale(b);
        let plan = self.plan(self.band.unwrap_or(BAND as usize), second);
        for band in plan.layout(h) {
            let rows = plan.read(&band, h);
            let (image, mse) = self.denoise(b, rows.clone(), depth, ks, second);
            take(&image, &mse, band.start - rows.start..band.end - rows.start);
        }
    }

    /// The filtered image and its estimated per-pixel MSE over the buffers' rows `rows`, as if
    /// they were the whole image (depth scaled by `depth`).
    fn denoise(
        &self,
        b: &PixelBuffers,
        rows: Range<usize>,
        depth: f32,
        ks: &[f32],
        second: bool,
    ) -> (Planes, Vec<f32>) {
        let (inp, feats) = Inputs::read(b, rows, depth);
        let hit = &inp.hit;
        // Features prefiltered across the halves: each half's features averaged with
        // weights from the other half's.
        let prefilter = |feats: &FeatureHalves, h: usize| {
            let guide = Guide {
                image: &feats.features[1 - h],
                variance: &feats.variance[1 - h],
                patch: self.patch,
                k2: PREFILTER_K * PREFILTER_K,
            };
            nl_means(&feats.features[h], guide, self.prefilter_radius, hit)
        };
        let mut feats = feats;
        let first_half = prefilter(&feats, 0);
        // Half 1's variance guided half 0 only: gone before half 1's planes are made.
        feats.variance[1] = Planes::new(0, 0, FEATURES);
        let prefiltered = [first_half, prefilter(&feats, 1)];
        drop(feats);
        // Each half fitted on the other half's prefiltered features with weights from the
        // other half's colour (Tungsten's crossing).
        let fits = [0, 1].map(|h| {
            let reg = Regression {
                color: &inp.color[h],
                features: &prefiltered[1 - h],
                hit,
                radius: self.radius,
                ridge: self.ridge,
                stride: self.stride,
            };
            let guide = Guide {
                image: &inp.color[1 - h],
                variance: &inp.color_var[1 - h],
                patch: self.patch,
                k2: 1.0,
            };
            reg.run(guide, ks)
        });
        let [fa, fb] = fits;
        let fitted: Vec<[Planes; 2]> = fa.into_iter().zip(fb).map(|(a, b)| [a, b]).collect();
        // The second pass regresses on the halves' mean features: the halves' own are done
        // with, and go before the choice's planes are made.
        let features = second.then(|| {
            prefiltered[0].map(FEATURES, |i, a, o| {
                for (k, o) in o.iter_mut().enumerate() {
                    *o = 0.5 * (a[k] + prefiltered[1].px(i)[k]);
                }
            })
        });
        drop(prefiltered);
        let [c0, c1] = &inp.color;
        let candidates: Vec<Candidate> = std::iter::once(Candidate { halves: [c0, c1] })
            .chain(fitted.iter().map(|[a, b]| Candidate { halves: [a, b] }))
            .collect();
        // Each candidate's estimated MSE, one channel each. The unfiltered mean's is its
        // variance, weighed by MEAN_MSE_FACTOR.
        let mut stack = Planes::new(inp.full.w, inp.full.h, candidates.len());
        for i in 0..inp.full_var.w * inp.full_var.h {
            stack.px_mut(i)[0] = inp.full_var.px(i).iter().sum::<f32>() / 3.0 * MEAN_MSE_FACTOR;
        }
        for (col, c) in candidates.iter().enumerate().skip(1) {
            candidate_mse(c, &inp.color, &inp.color_var, &mut stack, col);
        }
        let smoothing = Smoothing {
            guide: Guide {
                image: &inp.full,
                variance: &inp.full_var,
                patch: 1,
                k2: 1.0,
            },
            radius: self.select_radius,
            hit,
        };
        let sel = select(&candidates, stack, &smoothing);
        drop(candidates);
        drop(fitted);
        let [ra, rb] = &sel.halves;
        let first = ra.map(3, |i, a, o| {
            for c in 0..3 {
                o[c] = 0.5 * (a[c] + rb.px(i)[c]);
            }
        });
        let Some(features) = features else {
            return (first, sel.mse);
        };
        let image = self.second_pass(&inp, &sel, &first, &features);
        (image, sel.mse)
    }

    /// NFOR's second pass: the first pass's image regressed again on the features, weighted
    /// by NL-means on itself with the halves' difference as its variance. Where the choice
    /// took the unfiltered mean, the mean keeps its share.
    fn second_pass(
        &self,
        inp: &Inputs,
        sel: &Selected,
        first: &Planes,
        features: &Planes,
    ) -> Planes {
        let [ra, rb] = &sel.halves;
        let var = ra.map(3, |i, a, o| {
            for c in 0..3 {
                o[c] = 0.25 * (a[c] - rb.px(i)[c]).powi(2);
            }
        });
        let reg = Regression {
            color: first,
            features,
            hit: &inp.hit,
            radius: self.radius,
            ridge: self.ridge,
            stride: self.stride,
        };
        let guide = Guide {
            image: first,
            variance: &var,
            patch: self.patch,
            k2: 1.0,
        };
        let second = reg.run(guide, &[SECOND_PASS_K]).remove(0);
        second.map(3, |i, v, o| {
            let s = sel.first_share[i];
            for c in 0..3 {
                o[c] = s * inp.full.px(i)[c] + (1.0 - s) * v[c];
            }
        })
    }
}

impl Filter for NforFilter {
    fn name(&self) -> &'static str {
        "nfor"
    }

    fn kernel(&self) -> &dyn FilterKernel {
        &self.kernel
    }

    fn reads_pixel_buffers(&self) -> bool {
        true
    }

    fn reconstruct(&self, film: &Film, _from: SamplerOutput<'_>) -> Vec<Spectrum> {
        let Some(b) = film.pixel_buffers() else {
            // A film without half buffers (a stream's own film): its pixel means.
            return film.pixel_stats().iter().map(|s| s.mean()).collect();
        };
        let (w, h) = b.size();
        let mut out = Vec::with_capacity(w as usize * h as usize);
        self.by_bands(b, &BANDWIDTHS, self.second_pass, |image, _, rows| {
            let span = &image.data[rows.start * image.w * 3..rows.end * image.w * 3];
            out.extend(
                span.chunks(3)
                    .map(|c| Spectrum::new(c[0], c[1], c[2]).max(Spectrum::ZERO)),
            );
        });
        out
    }

    fn bands(&self, height: usize) -> Option<BandPlan> {
        (self.band != Some(0)).then(|| self.render_plan(height))
    }

    fn reconstruct_rows(&self, film: &Film, rows: Range<usize>) -> Vec<Spectrum> {
        let Some(b) = film.pixel_buffers() else {
            let w = film.settings().size().0 as usize;
            let stats = film.pixel_stats();
            return stats[rows.start * w..rows.end * w]
                .iter()
                .map(|s| s.mean())
                .collect();
        };
        let h = b.size().1 as usize;
        let read = self.render_plan(h).read(&rows, h);
        let (image, _) = self.denoise(
            b,
            read.clone(),
            depth_scale(b),
            &BANDWIDTHS,
            self.second_pass,
        );
        let span = (rows.start - read.start) * image.w * 3..(rows.end - read.start) * image.w * 3;
        image.data[span]
            .chunks(3)
            .map(|c| Spectrum::new(c[0], c[1], c[2]).max(Spectrum::ZERO))
            .collect()
    }

    fn estimated_error(&self, film: &Film) -> Option<Vec<f32>> {
        // One bandwidth: half the regression's cost, for a sampler that asks mid-render.
        let b = film.pixel_buffers()?;
        let (w, h) = b.size();
        let mut out = Vec::with_capacity(w as usize * h as usize);
        self.by_bands(b, &BANDWIDTHS[..1], false, |_, mse, rows| {
            out.extend_from_slice(&mse[rows.start * w as usize..rows.end * w as usize]);
        });
        Some(out)
    }
}

/// The registry entry.
pub(crate) const ENTRY: Entry<FilterBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Filter,
        name: "nfor",
        doc: "NFOR (Bitterli et al. 2016): first-order regression on first-hit features, \
              NL-means weighted across two half buffers, bandwidth chosen per pixel by \
              estimated MSE, the unfiltered mean a candidate",
        params: &[
            ParamSpec::new(
                "radius",
                ParamType::Integer,
                "3",
                "the regression window's radius in pixels",
            ),
            ParamSpec::new(
                "secondpass",
                ParamType::Bool,
                "true",
                "NFOR's second pass: the first pass's image regressed again on the features",
            ),
            ParamSpec::new(
                "patch",
                ParamType::Integer,
                "3",
                "the NL-means patch radius in pixels",
            ),
            ParamSpec::new(
                "prefilter",
                ParamType::Integer,
                "2",
                "the feature prefilter's window radius in pixels (0: off)",
            ),
            ParamSpec::new(
                "selectradius",
                ParamType::Integer,
                "3",
                "the radius of the window smoothing the MSE estimates and the per-pixel choice",
            ),
            ParamSpec::new(
                "band",
                ParamType::Integer,
                "-1",
                "rows filtered at a time, each band with a halo of the windows' reach: less \
                 memory, more time; the image is the same (0: the whole image at once, no \
                 render by bands; -1: 256, or in a render by bands of over 512 rows a quarter \
                 of the image less the halo, 64 to 256)",
            ),
            ParamSpec::new(
                "stride",
                ParamType::Integer,
                "2",
                "the regressions fit every stride-th pixel in each direction (1: every pixel)",
            ),
            ParamSpec::new(
                "ridge",
                ParamType::Float,
                "0.001",
                "ridge on the regression's slopes, relative to the sum of weights",
            ),
        ],
    },
    build,
};

fn build(c: &Choice) -> Result<Box<dyn Filter>> {
    let p = &c.params;
    Ok(Box::new(
        NforFilter::new(
            int_in(p, "radius", RADIUS as i32, 0..=16)?,
            int_in(p, "patch", PATCH as i32, 0..=8)?,
            int_in(p, "prefilter", PREFILTER_RADIUS as i32, 0..=16)?,
            int_in(p, "selectradius", SELECT_RADIUS as i32, 0..=16)?,
            float_in(p, "ridge", RIDGE, 0.0..=1e3)?,
        )
        .with_second_pass(p.bool_or("secondpass", true)?)
        .with_band_or_default(match p.int_or("band", -1)? {
            // The default: by the image's height.
            -1 => None,
            _ => Some(int_in(p, "band", -1, 0..=1 << 16)?),
        })
        .with_stride(int_in(p, "stride", STRIDE as i32, 1..=4)? as u32),
    ))
}

#[cfg(test)]
mod tests;
