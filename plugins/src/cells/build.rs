//! The first clustering of a grid of cells (docs/algorithm.md §3 and §4): every cell's
//! level and features, their scales, the tolerance of eq. 10 and the clusters grown by flood
//! fill. The cluster sampler runs it after its first stage; the polynomial reconstruction runs
//! it on the film's cells after any other sampler.

use super::cell_features::{level, raw, Squashed};
use super::clusters::distance;
use super::{CellGrid, CellSums, Clustering, FeatureScale, Membership};
use rayon::prelude::*;

/// The knobs of the clustering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterParams {
    /// ω of eq. 10.
    pub omega: f64,
    /// Weights of the gradient, variance, position and level parts of the feature distance.
    pub weights: [f64; 4],
    /// Most cells in one cluster.
    pub max_cluster_cells: u32,
    /// Log-compress g and s.
    pub log_features: bool,
}

/// What the first clustering computed, per cell and in all.
#[derive(Clone, Debug)]
pub struct Initial {
    /// Each cell's level (mean luminance, or its sampled neighbours').
    pub levels: Vec<f32>,
    /// Each cell's squashed gradient, variance and level, from which its feature is made.
    pub squashed: Vec<Squashed>,
    /// How raw features become weighted feature vectors.
    pub scale: FeatureScale,
    /// The clusters.
    pub clustering: Clustering,
}

/// Clusters the cells of `grid` from their sums.
pub fn initial_clustering(grid: &CellGrid, sums: &CellSums, params: &ClusterParams) -> Initial {
    let levels: Vec<f32> = (0..grid.len())
        .into_par_iter()
        .map(|i| level(grid, sums, i))
        .collect();
    let (g, s): (Vec<f32>, Vec<f32>) = (0..grid.len())
        .into_par_iter()
        .map(|i| raw(grid, sums, &levels, i))
        .unzip();
    let n = grid.dims();
    // Positions in units of the side of a cube of maxclustercells cells, so that a full
    // cluster spans about 1 in every dim whatever the resolution or bins.
    let unit = f64::from(params.max_cluster_cells).powf(1.0 / n as f64);
    let scale = FeatureScale::measure(
        sums,
        &g,
        &s,
        &levels,
        params.weights,
        unit,
        params.log_features,
    );
    let squashed: Vec<Squashed> = (0..grid.len())
        .into_par_iter()
        .map(|i| scale.squash(g[i], s[i], levels[i]))
        .collect();
    // The squashed values hold the logarithms, so a feature is cheap to make again each time
    // the flood fill below tests a cell.
    let feature = |i: usize| scale.feature_of(n, &grid.coords(i), squashed[i]);
    // The tolerance of eq. 10 is the typical distance between neighbouring cells' features
    // (the median, over sampled cells, of the distance to the next cell along x): a cluster
    // of one cell then takes neighbours that differ by noise and refuses those that differ by
    // an edge. Without noise it is one cell step.
    let mut steps: Vec<f64> = (0..grid.len())
        .into_par_iter()
        .filter(|&i| sums.count[i] > 0)
        .map(|i| {
            let c = grid.coords(i);
            let j = grid
                .step(i, &c, 0, true)
                .or_else(|| grid.step(i, &c, 0, false))
                .unwrap_or(i);
            distance(&feature(i), &feature(j))
        })
        .collect();
    let tolerance = if steps.is_empty() {
        scale.cell_step()
    } else {
        let k = steps.len() / 2;
        *steps.select_nth_unstable_by(k, f64::total_cmp).1
    }
    .max(scale.cell_step())
        * (1.0 + 1e-9);
    let rule = Membership {
        omega: params.omega,
        tolerance,
        max_cells: params.max_cluster_cells as usize,
    };
    let clustering = Clustering::grow(grid, rule, feature, |i| u64::from(sums.count[i]));
    Initial {
        levels,
        squashed,
        scale,
        clustering,
    }
}
