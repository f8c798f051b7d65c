//! `awr`: adaptive wavelet rendering (Overbeck, Donner and Ramamoorthi, SIGGRAPH Asia 2009),
//! re-implemented from the paper, in image space. The pixel means are taken through an
//! orthonormal 2x2 Haar pyramid (the image padded by its edge pixels to a power-of-two square),
//! and with them the variance of every coefficient (the mean of its pixels' variances of the
//! mean). The image is the inverse transform of the detail coefficients soft-thresholded at
//! `threshold` times their noise std. A coefficient's expected error after thresholding is
//! about min(detail^2, variance); spread over the pixels it covers, and relative to the pixel's
//! value, that is where each round's samples go: to the coefficients with both detail and
//! variance.

// Channel and dim loops index several small arrays at once, as the formulas do.
#![allow(clippy::needless_range_loop)]

use super::pixel_rounds::{self, PixelMethod, PixelMoments};
use super::{SamplerBuild, SamplerSetup};
use crate::film::Spectrum;
use crate::registry::{float_in, Choice, Entry, Kind, ParamSpec, PluginInfo};
use crate::space::RenderingSpace;
use acr_parser::{ParamType, Result};

/// Salt of this sampler's per-pixel keys.
const SALT: u64 = 0x6177_7200;

/// The method's settings.
#[derive(Clone, Copy, Debug)]
pub struct Awr {
    /// Soft threshold, in noise standard deviations.
    threshold: f64,
    /// The details of blocks across the image's edge (part image, part padding) are kept
    /// whole, so that the image sums to the sum of the pixel means (`unbiased`;
    /// docs/rivals.md).
    keep_edge_blocks: bool,
}

/// A coefficient: red, green, blue, luminance; and its noise variance (luminance).
#[derive(Clone, Copy, Debug, Default)]
struct Coeff {
    c: [f64; 4],
    var: f64,
}

/// One level of the pyramid: the three detail coefficients of each 2x2 block of the finer
/// approximation, on a `size` x `size` grid.
struct Level {
    size: usize,
    details: Vec<[Coeff; 3]>,
}

/// The forward transform of the padded image: the levels, finest first, and the coarsest
/// approximation (1 x 1).
fn forward(space: &RenderingSpace, m: &PixelMoments) -> (usize, Vec<Level>, Coeff) {
    let (w, h) = (space.width() as usize, space.height() as usize);
    let side = w.max(h).next_power_of_two();
    let var = m.vars_of_mean();
    let mut approx: Vec<Coeff> = (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side).min(w - 1), (i / side).min(h - 1));
            let j = y * w + x;
            let mean = m.mean(j);
            let lum = 0.212671 * mean[0] + 0.715160 * mean[1] + 0.072169 * mean[2];
            Coeff {
                c: [mean[0], mean[1], mean[2], lum],
                var: var[j],
            }
        })
        .collect();
    let mut levels = Vec::new();
    let mut n = side;
    while n > 1 {
        let s = n / 2;
        let mut next = vec![Coeff::default(); s * s];
        let mut details = vec![[Coeff::default(); 3]; s * s];
        for y in 0..s {
            for x in 0..s {
                let at = |dx: usize, dy: usize| approx[(2 * y + dy) * n + 2 * x + dx];
                let (p00, p01, p10, p11) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
                let var = (p00.var + p01.var + p10.var + p11.var) / 4.0;
                let mut a = Coeff {
                    var,
                    ..Coeff::default()
                };
                let mut d = [a; 3];
                for c in 0..4 {
                    let (x00, x01, x10, x11) = (p00.c[c], p01.c[c], p10.c[c], p11.c[c]);
                    a.c[c] = (x00 + x01 + x10 + x11) / 2.0;
                    d[0].c[c] = (x00 - x01 + x10 - x11) / 2.0;
                    d[1].c[c] = (x00 + x01 - x10 - x11) / 2.0;
                    d[2].c[c] = (x00 - x01 - x10 + x11) / 2.0;
                }
                next[y * s + x] = a;
                details[y * s + x] = d;
            }
        }
        levels.push(Level { size: s, details });
        approx = next;
        n = s;
    }
    (side, levels, approx[0])
}

impl PixelMethod for Awr {
    const NAME: &'static str = "awr";

    fn error(&self, space: &RenderingSpace, m: &PixelMoments) -> Vec<f64> {
        let (w, h) = (space.width() as usize, space.height() as usize);
        let (side, levels, top) = forward(space, m);
        // Per pixel of the padded square: the expected squared error of every coefficient
        // covering it, spread over the coefficient's pixels.
        let mut err = vec![top.var / (side * side) as f64; side * side];
        for level in &levels {
            let block = side / level.size;
            let area = (block * block) as f64;
            for y in 0..side {
                for x in 0..side {
                    let d = &level.details[(y / block) * level.size + x / block];
                    let r: f64 = d.iter().map(|c| (c.c[3] * c.c[3]).min(c.var)).sum();
                    err[y * side + x] += r / area;
                }
            }
        }
        // Relative to a 5x5 mean of the luminance, not the pixel's own noisy value, which would
        // send more samples to pixels whose first samples happened to be dark and so bias the
        // image up (as measured for gem).
        let lum: Vec<f64> = (0..w * h)
            .map(|i| {
                let v = m.mean(i);
                0.212671 * v[0] + 0.715160 * v[1] + 0.072169 * v[2]
            })
            .collect();
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let (mut sum, mut n) = (0.0, 0.0);
                for yy in y.saturating_sub(2)..(y + 3).min(h) {
                    for xx in x.saturating_sub(2)..(x + 3).min(w) {
                        sum += lum[yy * w + xx];
                        n += 1.0;
                    }
                }
                let smooth = sum / n;
                let e = err[y * side + x] / (smooth * smooth + 1e-3);
                if e.is_finite() {
                    e
                } else {
                    0.0
                }
            })
            .collect()
    }

    fn reconstruct(&self, space: &RenderingSpace, m: &PixelMoments) -> Vec<Spectrum> {
        let (w, h) = (space.width() as usize, space.height() as usize);
        let (side, levels, top) = forward(space, m);
        let soft = |c: f64, t: f64| c.signum() * (c.abs() - t).max(0.0);
        let mut approx = vec![top];
        let mut n = 1;
        for level in levels.iter().rev() {
            let s = level.size;
            debug_assert_eq!(s, n);
            let mut finer = vec![Coeff::default(); 4 * s * s];
            for y in 0..s {
                for x in 0..s {
                    let a = approx[y * s + x];
                    let d = &level.details[y * s + x];
                    // A detail sums to zero over its block: thresholding it moves value
                    // within the block, and between the image and the padding only when the
                    // block lies across the image's edge (measured +0.2% to +0.4% on a
                    // 320x240 image: docs/rivals.md).
                    let block = side / s;
                    let across = |at: usize, n: usize| at * block < n && (at + 1) * block > n;
                    let t = if self.keep_edge_blocks && (across(x, w) || across(y, h)) {
                        0.0
                    } else {
                        self.threshold * d[0].var.max(0.0).sqrt()
                    };
                    for c in 0..4 {
                        let (d1, d2, d3) =
                            (soft(d[0].c[c], t), soft(d[1].c[c], t), soft(d[2].c[c], t));
                        let a = a.c[c];
                        finer[2 * y * 2 * s + 2 * x].c[c] = (a + d1 + d2 + d3) / 2.0;
                        finer[2 * y * 2 * s + 2 * x + 1].c[c] = (a - d1 + d2 - d3) / 2.0;
                        finer[(2 * y + 1) * 2 * s + 2 * x].c[c] = (a + d1 - d2 - d3) / 2.0;
                        finer[(2 * y + 1) * 2 * s + 2 * x + 1].c[c] = (a - d1 - d2 + d3) / 2.0;
                    }
                }
            }
            approx = finer;
            n = 2 * s;
        }
        debug_assert_eq!(n, side);
        (0..w * h)
            .map(|i| {
                let c = approx[(i / w) * side + i % w].c;
                super::nonnegative_spectrum([c[0], c[1], c[2]])
            })
            .collect()
    }
}

fn build(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn super::Sampler>> {
    let p = &c.params;
    let method = Awr {
        threshold: float_in(p, "threshold", 1.0, 0.0..=100.0)?,
        keep_edge_blocks: p.bool_or("unbiased", false)?,
    };
    pixel_rounds::build(method, p, setup, SALT)
}

/// The registry's entry.
pub(super) const ENTRY: Entry<SamplerBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Sampler,
        name: "awr",
        doc: "adaptive wavelet rendering (Overbeck et al. 2009, re-implemented from the paper, \
              image space): Haar pyramid of pixel means and variances, rounds to the \
              coefficients with detail and variance, soft-thresholded reconstruction; \
              reconstructs the image itself",
        params: &[
            pixel_rounds::ROUND_PARAMS[0],
            pixel_rounds::ROUND_PARAMS[1],
            pixel_rounds::ROUND_PARAMS[2],
            pixel_rounds::ROUND_PARAMS[3],
            ParamSpec::new(
                "threshold",
                ParamType::Float,
                "1",
                "soft threshold of the detail coefficients, in noise standard deviations",
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
