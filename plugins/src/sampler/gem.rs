//! `gem`: greedy error minimization (Rousselle, Knaus and Zwicker, "Adaptive Sampling and
//! Reconstruction using Greedy Error Minimization", SIGGRAPH Asia 2011), re-implemented from the
//! paper. Each pixel keeps the mean and the variance of the mean of its samples. A bank of
//! Gaussian filters at sqrt(2)-spaced scales filters both; per pixel, the scale is chosen by a
//! bias-variance test (a coarser scale is taken while its change from the finer one is within
//! what the noise explains). The estimated error of the chosen scale (variance plus squared
//! bias, relative to the value) steers each round's samples to the worst pixels.

// Channel and dim loops index several small arrays at once, as the formulas do.
#![allow(clippy::needless_range_loop)]

use super::pixel_rounds::{self, PixelMethod, PixelMoments};
use super::{SamplerBuild, SamplerSetup};
use crate::film::Spectrum;
use crate::registry::{float_in, int_in, Choice, Entry, Kind, ParamSpec, PluginInfo};
use crate::space::RenderingSpace;
use acr_parser::{ParamType, Result};

/// Salt of this sampler's per-pixel keys.
const SALT: u64 = 0x6765_6d00;

/// The method's settings.
#[derive(Clone, Copy, Debug)]
pub struct Gem {
    /// Filter scales.
    scales: u32,
    /// Standard deviation of the finest Gaussian, in pixels.
    sigma0: f64,
    /// A coarser scale is accepted while its squared change is at most this times the sum of
    /// the two scales' variances.
    gamma: f64,
    /// The image through symmetric weights made from the pixels' chosen scales instead of
    /// each pixel gathering at its own, so that the image mean is the mean of the pixel
    /// means whatever the scales (`unbiased`; docs/rivals.md).
    symmetric: bool,
}

/// One pixel's filtered value at one scale and that value's variance.
#[derive(Clone, Copy, Debug, Default)]
struct Filtered {
    value: [f64; 3],
    var: f64,
}

impl Gem {
    /// The filtered value and variance of every pixel at scale `k` (a separable Gaussian of
    /// std sigma0 * sqrt(2)^k, truncated at 3 std, weights renormalised at the borders).
    fn filter(
        &self,
        space: &RenderingSpace,
        m: &PixelMoments,
        var: &[f64],
        k: u32,
    ) -> Vec<Filtered> {
        let (w, h) = (space.width() as usize, space.height() as usize);
        let sigma = self.sigma0 * 2f64.sqrt().powi(k as i32);
        let r = (3.0 * sigma).ceil() as i64;
        let kernel: Vec<f64> = (-r..=r)
            .map(|d| (-(d * d) as f64 / (2.0 * sigma * sigma)).exp())
            .collect();
        // Pass 1 along x: weighted sums of means (w), of variances (w^2), and the weights.
        let mut tmp = vec![([0.0f64; 3], 0.0f64, 0.0f64); w * h];
        for y in 0..h {
            for x in 0..w {
                let mut acc = ([0.0; 3], 0.0, 0.0);
                for (j, kw) in kernel.iter().enumerate() {
                    let xx = x as i64 + j as i64 - r;
                    if xx < 0 || xx >= w as i64 {
                        continue;
                    }
                    let i = y * w + xx as usize;
                    let mean = m.mean(i);
                    for c in 0..3 {
                        acc.0[c] += kw * mean[c];
                    }
                    acc.1 += kw * kw * var[i];
                    acc.2 += kw;
                }
                tmp[y * w + x] = acc;
            }
        }
        // Pass 2 along y; the variance of a weighted mean is sum w^2 var / (sum w)^2, and the
        // separable weights multiply.
        let mut out = vec![Filtered::default(); w * h];
        for y in 0..h {
            for x in 0..w {
                let (mut v, mut vv, mut sw) = ([0.0; 3], 0.0, 0.0);
                for (j, kw) in kernel.iter().enumerate() {
                    let yy = y as i64 + j as i64 - r;
                    if yy < 0 || yy >= h as i64 {
                        continue;
                    }
                    let t = &tmp[yy as usize * w + x];
                    for c in 0..3 {
                        v[c] += kw * t.0[c];
                    }
                    vv += kw * kw * t.1;
                    sw += kw * t.2;
                }
                let sw = sw.max(1e-300);
                out[y * w + x] = Filtered {
                    value: v.map(|a| a / sw),
                    var: vv / (sw * sw),
                };
            }
        }
        out
    }

    /// Per pixel: the chosen scale's value, its estimated squared error and the coarsest
    /// scale's luminance (what the relative error is taken against: a pixel's own noisy value
    /// would send more samples to pixels whose first samples happened to be dark, and so bias
    /// the image up; measured +2.2% mean on motion-blur at 8 spp).
    fn select(&self, space: &RenderingSpace, m: &PixelMoments) -> Vec<Selected> {
        let var = m.vars_of_mean();
        let bank: Vec<Vec<Filtered>> = (0..self.scales)
            .map(|k| self.filter(space, m, &var, k))
            .collect();
        let lum = |v: &[f64; 3]| 0.212671 * v[0] + 0.715160 * v[1] + 0.072169 * v[2];
        (0..var.len())
            .map(|i| {
                let mut k = 0;
                let mut bias2 = 0.0;
                while k + 1 < bank.len() {
                    let (a, b) = (&bank[k][i], &bank[k + 1][i]);
                    let d = lum(&b.value) - lum(&a.value);
                    // The change is noise if within gamma times the two variances.
                    if d * d > self.gamma * (a.var + b.var) {
                        break;
                    }
                    bias2 += d * d;
                    k += 1;
                }
                let f = &bank[k][i];
                Selected {
                    scale: k,
                    value: f.value,
                    error: f.var + bias2,
                    coarse: lum(&bank[bank.len() - 1][i].value),
                }
            })
            .collect()
    }

    /// The image through symmetric weights: between pixels i and j, the smaller of i's
    /// weight on j and j's weight on i at their chosen scales (each a Gaussian truncated at 3
    /// std, normalised over the taps inside the image); each pixel keeps the rest of its unit
    /// weight for itself. Rows and columns then both sum to 1: a flat region stays flat and
    /// the image sums to the sum of the pixel means whatever the scales. Gathered each at its
    /// own scale, a pixel whose samples scatter widely (a firefly) picks a coarse scale and
    /// its value is replaced by its neighbours', its excess lost, which darkens the image
    /// where the rare outcome is the bright one (measured: docs/rivals.md).
    fn symmetric(&self, space: &RenderingSpace, m: &PixelMoments) -> Vec<[f64; 3]> {
        let (w, h) = (space.width() as usize, space.height() as usize);
        let scales: Vec<usize> = self.select(space, m).iter().map(|s| s.scale).collect();
        let bank: Vec<Taps> = (0..self.scales)
            .map(|k| Taps::new(self.sigma0 * 2f64.sqrt().powi(k as i32), w, h))
            .collect();
        let mut out = vec![[0.0f64; 3]; w * h];
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let ti = &bank[scales[i]];
                let mut own = 1.0;
                let mut acc = [0.0f64; 3];
                let r = ti.r as usize;
                for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
                    for xx in x.saturating_sub(r)..(x + r + 1).min(w) {
                        let j = yy * w + xx;
                        if j == i {
                            continue;
                        }
                        let tj = &bank[scales[j]];
                        let wt = ti.weight(x, y, xx, yy).min(tj.weight(xx, yy, x, y));
                        if wt > 0.0 {
                            own -= wt;
                            let mean = m.mean(j);
                            for c in 0..3 {
                                acc[c] += wt * mean[c];
                            }
                        }
                    }
                }
                let mean = m.mean(i);
                for c in 0..3 {
                    out[i][c] = acc[c] + own * mean[c];
                }
            }
        }
        out
    }
}

/// One scale's Gaussian, truncated at 3 std, with each row's and column's sum over the taps
/// that land inside the image (its weights normalised there).
struct Taps {
    r: i64,
    kernel: Vec<f64>,
    /// Sum of the taps inside [0, w) around each column.
    col: Vec<f64>,
    /// Sum of the taps inside [0, h) around each row.
    row: Vec<f64>,
}

impl Taps {
    fn new(sigma: f64, w: usize, h: usize) -> Self {
        let r = (3.0 * sigma).ceil() as i64;
        let kernel: Vec<f64> = (-r..=r)
            .map(|d| (-(d * d) as f64 / (2.0 * sigma * sigma)).exp())
            .collect();
        let sums = |n: usize| -> Vec<f64> {
            (0..n as i64)
                .map(|at| {
                    let (lo, hi) = ((at - r).max(0), (at + r).min(n as i64 - 1));
                    (lo..=hi).map(|t| kernel[(t - at + r) as usize]).sum()
                })
                .collect()
        };
        let (col, row) = (sums(w), sums(h));
        Self {
            r,
            kernel,
            col,
            row,
        }
    }

    /// The weight of pixel (x, y)'s gather on pixel (xx, yy): 0 beyond the truncation.
    fn weight(&self, x: usize, y: usize, xx: usize, yy: usize) -> f64 {
        let (dx, dy) = (xx as i64 - x as i64, yy as i64 - y as i64);
        if dx.abs() > self.r || dy.abs() > self.r {
            return 0.0;
        }
        let kx = self.kernel[(dx + self.r) as usize] / self.col[x];
        let ky = self.kernel[(dy + self.r) as usize] / self.row[y];
        kx * ky
    }
}

/// One pixel's choice: its scale, the value and estimated squared error there, and the
/// coarsest scale's luminance.
struct Selected {
    scale: usize,
    value: [f64; 3],
    error: f64,
    coarse: f64,
}

impl PixelMethod for Gem {
    const NAME: &'static str = "gem";

    fn error(&self, space: &RenderingSpace, m: &PixelMoments) -> Vec<f64> {
        self.select(space, m)
            .into_iter()
            .map(|s| {
                // Relative error; the floor keeps black pixels from claiming everything.
                let e = s.error / (s.coarse * s.coarse + 1e-3);
                if e.is_finite() {
                    e
                } else {
                    0.0
                }
            })
            .collect()
    }

    fn reconstruct(&self, space: &RenderingSpace, m: &PixelMoments) -> Vec<Spectrum> {
        if self.symmetric {
            return self
                .symmetric(space, m)
                .into_iter()
                .map(super::nonnegative_spectrum)
                .collect();
        }
        self.select(space, m)
            .into_iter()
            .map(|s| super::nonnegative_spectrum(s.value))
            .collect()
    }
}

fn build(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn super::Sampler>> {
    let p = &c.params;
    let method = Gem {
        scales: int_in(p, "scales", 5, 1..=12)?,
        sigma0: float_in(p, "sigma0", 0.5, 0.1..=8.0)?,
        gamma: float_in(p, "gamma", 1.0, 0.0..=1e6)?,
        symmetric: p.bool_or("unbiased", false)?,
    };
    pixel_rounds::build(method, p, setup, SALT)
}

/// The registry's entry.
pub(super) const ENTRY: Entry<SamplerBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Sampler,
        name: "gem",
        doc: "greedy error minimization (Rousselle et al. 2011, re-implemented): Gaussian filter \
              bank, per-pixel scale by a bias-variance test, rounds to the pixels of highest \
              relative error; reconstructs the image itself",
        params: &[
            pixel_rounds::ROUND_PARAMS[0],
            pixel_rounds::ROUND_PARAMS[1],
            pixel_rounds::ROUND_PARAMS[2],
            pixel_rounds::ROUND_PARAMS[3],
            ParamSpec::new(
                "scales",
                ParamType::Integer,
                "5",
                "Gaussian filters in the bank",
            ),
            ParamSpec::new(
                "sigma0",
                ParamType::Float,
                "0.5",
                "std of the finest filter, pixels (each next is sqrt(2) wider)",
            ),
            ParamSpec::new(
                "gamma",
                ParamType::Float,
                "1",
                "a coarser scale is kept while its squared change <= gamma x the variances",
            ),
            super::paired::STREAMS,
            super::paired::PILOT,
        ],
    },
    build: build_streams,
};

/// Builds the sampler as two streams, each placed by the other's values (or as one, with
/// `streams 1`).
fn build_streams(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn super::Sampler>> {
    super::paired::wrap(c, setup, build)
}
