//! The fit's feature prefilter: each cell's mean albedo averaged with its image-space
//! neighbours', as NFOR filters its features before regressing on them. The regression on
//! albedo gives a pixel back the noise of its own albedo where that albedo is noisy (a texture
//! blurred by the lens or by motion: 8 samples hit different texels); averaged over neighbours
//! whose depth and normal agree and whose albedo differs from it by no more than their noise,
//! a noisy albedo loses its noise, and a precise one (its samples agree) is left alone.

use crate::cluster::{CellGrid, CellSums};
use crate::color::{luminance, Spectrum};
use crate::first_hit::{Features, DEPTH, FEATURES, NORMAL};
use rayon::prelude::*;

/// Depth difference, relative to the larger depth, at which a neighbour's weight is 1/e.
const DEPTH_SCALE: f64 = 0.1;

/// Normal difference (Euclidean) at which a neighbour's weight is 1/e.
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

/// The variance of cell `i`'s mean albedo, averaged over the channels: 0 (nothing known, so
/// nothing filtered in) below two samples.
fn albedo_variance(sums: &CellSums, i: usize) -> f64 {
    let n = f64::from(sums.count[i]);
    if n < 2.0 {
        return 0.0;
    }
    let mut v = 0.0;
    for c in 0..3 {
        let sum = f64::from(sums.features[i][c]);
        let sq = f64::from(sums.albedo_sq[i][c]);
        v += ((sq - sum * sum / n) / (n - 1.0)).max(0.0) / n;
    }
    v / 3.0
}

/// The logarithm of the weight of neighbour features `fj` for a cell of features `fi`, apart
/// from counts and shading: depth and normal agreement, and NL-means on the albedo with `v`
/// the two cells' albedo variances of the mean summed (0: only an equal albedo agrees).
fn log_similarity(fi: &[f64; FEATURES], fj: &[f64; FEATURES], v: f64, kappa: f64) -> f64 {
    let larger = fi[DEPTH].abs().max(fj[DEPTH].abs()).max(1e-6);
    let dd = (fi[DEPTH] - fj[DEPTH]) / (DEPTH_SCALE * larger);
    let dn: f64 = (NORMAL..NORMAL + 3).map(|c| (fi[c] - fj[c]).powi(2)).sum();
    let d: f64 = (0..3).map(|c| (fi[c] - fj[c]).powi(2)).sum::<f64>() / 3.0;
    let albedo = if v > 0.0 {
        -(d - v).max(0.0) / (kappa * kappa * v)
    } else if d > 0.0 {
        f64::NEG_INFINITY
    } else {
        0.0
    };
    -dd * dd - dn / (NORMAL_SCALE * NORMAL_SCALE) + albedo
}

/// The feature sums of `sums` with each cell's albedo sum replaced by its count times the
/// weighted mean albedo of the cells within `radius` image cells (the same time and lens bins),
/// weighted by count, depth, normal and shading agreement and NL-means on the albedo itself: a
/// neighbour whose mean albedo differs by d (squared, over the channels) from the cell's weighs
/// exp(-max(0, d - v) / (kappa^2 v)), v the two cells' albedo variances of the mean summed.
/// Sums without features or radiance, or a radius of 0, are returned unchanged.
pub fn prefilter_albedo(
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
    // Per cell: its albedo's variance of the mean and the logarithm of its shading.
    let stats: Vec<[f64; 2]> = (0..grid.len())
        .into_par_iter()
        .map(|i| {
            let log_shading = sums
                .mean_features(i)
                .map_or(0.0, |f| shading(sums, i, &f).ln());
            [albedo_variance(sums, i), log_shading]
        })
        .collect();
    let r = i64::from(radius);
    out.par_iter_mut().enumerate().for_each(|(i, slot)| {
        let Some(fi) = sums.mean_features(i) else {
            return;
        };
        let (image_cell, k) = (i / inner, i % inner);
        let (cx, cy) = ((image_cell as i64) % w, (image_cell as i64) / w);
        let (mut acc, mut total) = ([0.0f64; 3], 0.0f64);
        for y in (cy - r).max(0)..=(cy + r).min(h - 1) {
            for x in (cx - r).max(0)..=(cx + r).min(w - 1) {
                let j = (y * w + x) as usize * inner + k;
                let Some(fj) = sums.mean_features(j) else {
                    continue;
                };
                let weight = if j == i {
                    f64::from(sums.count[j])
                } else {
                    let ds = (stats[i][1] - stats[j][1]) / SHADING_SCALE;
                    let log = log_similarity(&fi, &fj, stats[i][0] + stats[j][0], kappa);
                    f64::from(sums.count[j]) * (log - ds * ds).exp()
                };
                if weight.is_nan() || weight <= 0.0 {
                    continue;
                }
                for c in 0..3 {
                    acc[c] += weight * fj[c];
                }
                total += weight;
            }
        }
        let n = f64::from(sums.count[i]);
        for c in 0..3 {
            slot[c] = (acc[c] / total * n) as f32;
        }
    });
    out
}
