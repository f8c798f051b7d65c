//! The fit's feature prefilter: each cell's mean first-hit features (albedo, normal, depth)
//! averaged with its image-space neighbours', as NFOR filters its features before regressing
//! on them. The regression on a feature gives a pixel back the noise of its own feature where
//! that feature is noisy (a texture or a silhouette blurred by the lens or by motion: 8
//! samples hit different texels and surfaces); averaged over neighbours whose features differ
//! from it by no more than their noise, a noisy feature loses its noise, and a precise one
//! (its samples agree) keeps its edges.

use crate::cells::{CellGrid, CellSums};
use crate::color::{luminance, Spectrum};
use crate::first_hit::{Features, DEPTH, FEATURES, NORMAL};
use rayon::prelude::*;

/// Depth difference, relative to the larger depth, at which a neighbour's weight is 1/e when
/// both depths are exact.
const DEPTH_SCALE: f64 = 0.1;

/// Normal difference (Euclidean) at which a neighbour's weight is 1/e when both normals are
/// exact.
const NORMAL_SCALE: f64 = 0.5;

/// Difference of the logarithms of two cells' shading (mean luminance over mean albedo
/// luminance) at which a neighbour's weight is 1/e: neighbours whose radiance is not their
/// albedo times the same light (an emitter beside a wall) are not averaged.
const SHADING_SCALE: f64 = 0.5;

/// A cell's shading: its mean luminance over its mean albedo's (albedo floored at 0.01).
fn shading(sums: &CellSums, i: usize, albedo: &[f64]) -> f64 {
    let n = sums.count[i].max(1) as f32;
    let l = Spectrum::from_array(sums.rgb[i]) / n;
    let a = Spectrum::new(albedo[0] as f32, albedo[1] as f32, albedo[2] as f32);
    f64::from(luminance(l)).max(1e-6) / f64::from(luminance(a)).max(0.01)
}

/// The variances of cell `i`'s mean features, by group: albedo (averaged over the channels),
/// normal (summed over the axes) and depth; all 0 (nothing known, so nothing filtered in)
/// below two samples.
fn feature_variances(sums: &CellSums, i: usize) -> [f64; 3] {
    let n = f64::from(sums.count[i]);
    if n < 2.0 {
        return [0.0; 3];
    }
    let of = |k: usize| {
        let sum = f64::from(sums.features[i][k]);
        let sq = f64::from(sums.features_sq[i][k]);
        ((sq - sum * sum / n) / (n - 1.0)).max(0.0) / n
    };
    [
        (0..3).map(of).sum::<f64>() / 3.0,
        (NORMAL..NORMAL + 3).map(of).sum(),
        of(DEPTH),
    ]
}

/// The logarithm of NL-means' weight for a squared difference `d` between two means whose
/// variances sum to `v`, with `scale2` the squared difference that counts as alike even when
/// both are exact: -max(0, d - v) / (kappa^2 v + scale2); without variance or scale only an
/// equal value agrees.
fn nl_means(d: f64, v: f64, kappa: f64, scale2: f64) -> f64 {
    let denominator = kappa * kappa * v + scale2;
    if denominator > 0.0 {
        -(d - v).max(0.0) / denominator
    } else if d > 0.0 {
        f64::NEG_INFINITY
    } else {
        0.0
    }
}

/// The logarithm of the weight of neighbour features `fj` for a cell of features `fi`, apart
/// from counts and shading: NL-means on each feature group, `v` the two cells' variances of
/// the mean summed per group (albedo, normal, depth). Depth and normal count as alike within
/// their scales however exact; the albedo only within its noise.
fn log_similarity(fi: &[f64; FEATURES], fj: &[f64; FEATURES], v: [f64; 3], kappa: f64) -> f64 {
    let larger = fi[DEPTH].abs().max(fj[DEPTH].abs()).max(1e-6);
    let dd = (fi[DEPTH] - fj[DEPTH]).powi(2);
    let dn: f64 = (NORMAL..NORMAL + 3).map(|c| (fi[c] - fj[c]).powi(2)).sum();
    let da: f64 = (0..3).map(|c| (fi[c] - fj[c]).powi(2)).sum::<f64>() / 3.0;
    nl_means(da, v[0], kappa, 0.0)
        + nl_means(dn, v[1], kappa, NORMAL_SCALE * NORMAL_SCALE)
        + nl_means(dd, v[2], kappa, (DEPTH_SCALE * larger).powi(2))
}

/// The feature sums of `sums` with each cell's sums replaced by its count times the weighted
/// mean features of the cells within `radius` image cells (the same time and lens bins),
/// weighted by count, shading agreement and NL-means per feature group: a neighbour whose mean
/// differs by d (squared) from the cell's weighs exp(-max(0, d - v) / (kappa^2 v + s^2)), v the
/// two cells' variances of the mean summed, s 0 for the albedo and the depth and normal
/// scales above. Sums without features or radiance, or a radius of 0, are returned unchanged.
pub fn prefilter_features(
    grid: &CellGrid,
    sums: &CellSums,
    radius: u32,
    kappa: f64,
) -> Vec<Features> {
    let mut out = sums.features.clone();
    if radius == 0 || !sums.keeps_features() || sums.rgb.is_empty() {
        return out;
    }
    let shape = grid.shape();
    let (w, h) = (i64::from(shape[0]), i64::from(shape[1]));
    let inner = grid.cells_per_image_cell();
    // Per cell: its features' variances of the mean and the logarithm of its shading.
    let stats: Vec<([f64; 3], f64)> = (0..grid.len())
        .into_par_iter()
        .map(|i| {
            let log_shading = sums
                .mean_features(i)
                .map_or(0.0, |f| shading(sums, i, &f).ln());
            (feature_variances(sums, i), log_shading)
        })
        .collect();
    let r = i64::from(radius);
    out.par_iter_mut().enumerate().for_each(|(i, slot)| {
        let Some(fi) = sums.mean_features(i) else {
            return;
        };
        let (image_cell, k) = (i / inner, i % inner);
        let (cx, cy) = ((image_cell as i64) % w, (image_cell as i64) / w);
        let (mut acc, mut total) = ([0.0f64; FEATURES], 0.0f64);
        for y in (cy - r).max(0)..=(cy + r).min(h - 1) {
            for x in (cx - r).max(0)..=(cx + r).min(w - 1) {
                let j = (y * w + x) as usize * inner + k;
                let Some(fj) = sums.mean_features(j) else {
                    continue;
                };
                let weight = if j == i {
                    f64::from(sums.count[j])
                } else {
                    let ds = (stats[i].1 - stats[j].1) / SHADING_SCALE;
                    let v = [0, 1, 2].map(|g| stats[i].0[g] + stats[j].0[g]);
                    let log = log_similarity(&fi, &fj, v, kappa);
                    f64::from(sums.count[j]) * (log - ds * ds).exp()
                };
                if weight.is_nan() || weight <= 0.0 {
                    continue;
                }
                for (a, f) in acc.iter_mut().zip(&fj) {
                    *a += weight * f;
                }
                total += weight;
            }
        }
        let n = f64::from(sums.count[i]);
        for (s, a) in slot.iter_mut().zip(&acc) {
            *s = (a / total * n) as f32;
        }
    });
    out
}
