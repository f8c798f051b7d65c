//! NFOR's per-pixel choice among candidate filterings by their estimated MSE, from the two
//! halves: a candidate that filtered half A from the other half's weights is compared with
//! half B, whose noise is independent of it (docs/reconstruction.md). The unfiltered mean is
//! always a candidate, its MSE its variance, so that where the noise is below the detail the
//! choice falls on the pixel itself.

// Small fixed-size channel and matrix loops read clearest with indices.
#![allow(clippy::needless_range_loop)]

use super::nlmeans::{nl_means, Guide};
use super::planes::Planes;

/// One candidate: its filtering of each half.
pub(crate) struct Candidate<'a> {
    pub halves: [&'a Planes; 2],
}

/// The estimated MSE (mean over the channels) of the mean of a candidate's two halves, into
/// channel `col` of `out`:
/// each half's squared difference from the other half less that half's variance, averaged,
/// less the variance the averaging removes (NFOR's estimate, as Tungsten computes it).
pub(crate) fn candidate_mse(
    c: &Candidate,
    halves: &[Planes; 2],
    half_var: &[Planes; 2],
    out: &mut Planes,
    col: usize,
) {
    let [fa, fb] = c.halves;
    let [a, b] = halves;
    for i in 0..a.w * a.h {
        out.px_mut(i)[col] = {
            let mut s = 0.0;
            for ch in 0..3 {
                let ma = (b.px(i)[ch] - fa.px(i)[ch]).powi(2) - half_var[1].px(i)[ch];
                let mb = (a.px(i)[ch] - fb.px(i)[ch]).powi(2) - half_var[0].px(i)[ch];
                let resid = 0.25 * (fa.px(i)[ch] - fb.px(i)[ch]).powi(2);
                s += 0.5 * (ma + mb) - resid;
            }
            s / 3.0
        };
    }
}

/// How the choice is smoothed: the guide (the pixel means and their variance), the window
/// and which pixels met a surface.
pub(crate) struct Smoothing<'a> {
    pub guide: Guide<'a>,
    pub radius: usize,
    pub hit: &'a [bool],
}

/// What the choice made.
pub(crate) struct Selected {
    /// The blend of the candidates, each half.
    pub halves: [Planes; 2],
    /// Its estimated MSE per pixel.
    pub mse: Vec<f32>,
    /// The first candidate's share of each pixel's blend.
    pub first_share: Vec<f32>,
}

/// The per-pixel blend of the candidates (each half), and its estimated MSE: the raw MSE maps
/// `stack` (one channel per candidate) are smoothed, each pixel picks the lowest, and the one-hot
/// choice maps are smoothed into blend weights.
pub(crate) fn select(
    candidates: &[Candidate],
    stack: Planes,
    smoothing: &Smoothing<'_>,
) -> Selected {
    let nc = candidates.len();
    let (w, h) = (candidates[0].halves[0].w, candidates[0].halves[0].h);
    let n = w * h;
    let smooth = nl_means(&stack, smoothing.guide, smoothing.radius, smoothing.hit);
    drop(stack);
    let mut choice = Planes::new(w, h, nc);
    for i in 0..n {
        let m = smooth.px(i);
        let best = (0..nc).fold(0, |b, c| if m[c] < m[b] { c } else { b });
        choice.px_mut(i)[best] = 1.0;
    }
    let weights = nl_means(&choice, smoothing.guide, smoothing.radius, smoothing.hit);
    drop(choice);
    let mut out = [Planes::new(w, h, 3), Planes::new(w, h, 3)];
    let mut mse = vec![0.0f32; n];
    for i in 0..n {
        let s = weights.px(i);
        for (c, cand) in candidates.iter().enumerate() {
            for (half, o) in out.iter_mut().enumerate() {
                let v = cand.halves[half].px(i);
                for ch in 0..3 {
                    o.px_mut(i)[ch] += s[c] * v[ch];
                }
            }
            mse[i] += s[c] * smooth.px(i)[c].max(0.0);
        }
    }
    Selected {
        halves: out,
        mse,
        first_share: (0..n).map(|i| weights.px(i)[0]).collect(),
    }
}
