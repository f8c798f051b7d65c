//! `polynomial`: the paper's reconstruction (docs/algorithm.md §5, §10). Each cluster of cells is
//! fitted with one additive Legendre polynomial over the active dims (`crate::polynomial_fit`),
//! and a pixel is the integral of the models over the cells it covers: for each cell, the
//! share of the pixel's volume it covers times its cluster's mean over the overlap. After the
//! cluster sampler it uses that sampler's cells and clusters; after any other sampler the film
//! collects cells (1 pixel, no cut of the time and lens dims) and the clusters are grown from
//! them with the sampler's code and default knobs.
//!
//! With `features` on, the film keeps first-hit features in its own cells (one per pixel)
//! whatever the sampler, the fit's clusters are merged by noise where the features agree too
//! (`cells/by_noise.rs`), and each cluster's model has a linear term per feature
//! (`polynomial_fit.rs`).

use super::{BoxFilter, Filter, FilterBuild, FilterKernel, FilterReport, SamplerOutput};
use crate::cells::build::{initial_clustering, Initial};
use crate::cells::by_noise::{grow_by_noise_with, NoiseClusters};
use crate::cells::grid::MAX_DIMS;
use crate::cells::{CellGrid, CellSums, CellView};
use crate::film::{Film, Spectrum};
use crate::first_hit::Features;
use crate::partition::Partition;
use crate::polynomial_fit::{Fit, FitCell, FitSettings, MAX_DEGREE};
use crate::prefilter::prefilter_features;
use crate::registry::{float_in, int_in, one_of, Choice, Entry, Kind, ParamSpec, PluginInfo};
use crate::sampler::ClusterSettings;
use acr_parser::{ParamType, Result};
use rayon::prelude::*;
use std::sync::Mutex;

/// The polynomial reconstruction.
#[derive(Debug)]
pub struct PolynomialFilter {
    /// Degree per dim; None: 2 in image-only space, 1 above (the paper's finding).
    degree: Option<u32>,
    ridge: f64,
    clamp: bool,
    /// Standard errors beyond which a cell keeps its departure from the model (0: never).
    significance: f64,
    /// The film splats with a box of one pixel: its pixel means are the fallback for a pixel
    /// whose cells have no usable sample.
    kernel: BoxFilter,
    /// Clusters fitted at each degree by the last reconstruction.
    fitted: Mutex<[u64; MAX_DEGREE as usize + 1]>,
    /// The clusters of the last reconstruction, per pixel.
    partition: Mutex<Option<Partition>>,
    /// The fit's own clustering (ω, most cells), grown from the cells even where the sampler
    /// gives one; None: the sampler's clusters, or the sampler's defaults.
    own: Option<(f64, u32)>,
    /// With z > 0: the fit's clusters merged by noise at z standard errors (`by_noise.rs`).
    noise_z: f64,
    /// Clusters merged by noise with fewer cells than this join their most alike neighbour
    /// where the noise test allows it.
    min_cells: u32,
    /// With Some(tolerance): regress on first-hit features, in clusters whose features agree
    /// within the tolerance.
    features: Option<f64>,
    /// How a cell weighs in its cluster's fit.
    weights: CellWeights,
    /// The feature prefilter's radius in cells (0: off) and its kappa ([`prefilter_features`]).
    prefilter: (u32, f64),
}

/// How a cell weighs in its cluster's least squares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellWeights {
    /// Its sample count (the paper's): an adaptive sampler chose it from the same values.
    Count,
    /// Every sampled cell alike: the weight does not depend on the values.
    Uniform,
}

/// Standard errors of the noise test when features are on and `noise` is not set.
pub const FEATURE_NOISE_Z: f64 = 8.0;

/// The features' tolerance when features are on and `featuretolerance` is not set: with every
/// feature prefiltered, 0.2 measured below 0.1 and 0.3 on defocus at 8 spp
/// (docs/reconstruction.md).
pub const FEATURE_TOLERANCE: f64 = 0.2;

/// The feature prefilter's radius in cells, by default. Measured (seeds 1-3, 8 spp,
/// cluster+polynomial over stratified+gaussian): radius 1 took depth-of-field from 0.54 to 0.45
/// and motion-dof from 0.71 to 0.57 with motion blur and the Cornell box unchanged; radius 2
/// lost a little of that.
pub const PREFILTER_RADIUS: u32 = 1;

/// The feature prefilter's NL-means strength, by default: with every feature prefiltered, 2
/// measured lowest of 1, 2 and 3 on defocus at 8 spp, and within 1.2% of 3 on motion-dof,
/// where 1 was 14% higher (docs/reconstruction.md).
pub const PREFILTER_KAPPA: f64 = 2.0;

/// `mincells` by default: noise clusters of fewer cells join a neighbour that agrees within
/// the noise test. Measured (docs/reconstruction.md, seeds 1-5, 8 spp): 16 lowered the MSE by 10%
/// to 13% on motion blur, defocus, both and the room, and raised it 3% on the Cornell box.
pub const MIN_CLUSTER_CELLS: u32 = 16;

/// `significance` by default with features on: 0 (off). Keeping departures measured worse on
/// every bench scene with features (the room 4.7x the MSE at 8 spp, and 0.8% dark at 2 spp);
/// the features and the noise clusters already keep the edges it was for.
pub const FEATURE_SIGNIFICANCE: f64 = 0.0;

/// `significance` by default with features off (the paper's fit): 3, for the step edge of
/// `tests/polynomial.rs`.
pub const PLAIN_SIGNIFICANCE: f64 = 3.0;

impl PolynomialFilter {
    /// The filter with its knobs.
    pub fn new(degree: Option<u32>, ridge: f64, clamp: bool, significance: f64) -> Self {
        Self {
            degree,
            ridge,
            clamp,
            significance,
            kernel: BoxFilter::new(0.5, 0.5),
            fitted: Mutex::new([0; MAX_DEGREE as usize + 1]),
            partition: Mutex::new(None),
            own: None,
            noise_z: 0.0,
            min_cells: MIN_CLUSTER_CELLS,
            features: None,
            weights: CellWeights::Count,
            prefilter: (0, PREFILTER_KAPPA),
        }
    }

    /// With features: prefilters the cells' features within `radius` cells (0: off) with
    /// NL-means strength `kappa` before the clustering and the fit.
    pub fn with_prefilter(mut self, radius: u32, kappa: f64) -> Self {
        self.prefilter = (radius, kappa);
        self
    }

    /// Weighs cells in the fit by `weights`.
    pub fn with_weights(mut self, weights: CellWeights) -> Self {
        self.weights = weights;
        self
    }

    /// Regresses on first-hit features in clusters whose features agree within `tolerance`
    /// (None: off, the paper's method).
    pub fn with_features(mut self, tolerance: Option<f64>) -> Self {
        self.features = tolerance;
        self
    }

    /// Merges noise clusters of fewer than `min_cells` cells into a neighbour where the
    /// noise test allows it (1: never).
    pub fn with_min_cells(mut self, min_cells: u32) -> Self {
        self.min_cells = min_cells;
        self
    }

    /// Fits clusters merged by noise at `z` standard errors (0: off).
    pub fn with_noise_clusters(mut self, z: f64) -> Self {
        self.noise_z = z;
        self
    }

    /// Fits clusters grown here with `omega` and at most `max_cells` cells, whatever the
    /// sampler's clusters.
    pub fn with_own_clusters(mut self, omega: f64, max_cells: u32) -> Self {
        self.own = Some((omega, max_cells));
        self
    }

    /// Clusters fitted at degree 0, 1 and 2 by the last reconstruction.
    pub fn fitted_by_degree(&self) -> [u64; MAX_DEGREE as usize + 1] {
        *self.fitted.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The image from `view`'s cells, clustered as given or as grown here.
    fn reconstruct_cells(&self, film: &Film, view: CellView<'_>) -> Vec<Spectrum> {
        let grid = view.grid;
        let (radius, kappa) = self.prefilter;
        let sums = view.sums;
        // The features the clusters and the fit read: their noise averaged out across
        // neighbours.
        let filtered;
        let cell_features = if radius > 0 && self.features.is_some() {
            filtered = prefilter_features(grid, sums, radius, kappa);
            &filtered
        } else {
            &sums.features
        };
        let features = self.features;
        let grown: Option<Initial>;
        let by_noise: NoiseClusters;
        let (cluster_cells, of_cell): (Vec<&[u32]>, &[u32]) = match (view.clustering, self.own) {
            _ if features.is_some() || self.noise_z > 0.0 => {
                let z = match self.noise_z {
                    z if z > 0.0 => z,
                    _ => FEATURE_NOISE_Z,
                };
                by_noise =
                    grow_by_noise_with(grid, sums, cell_features, z, features, self.min_cells);
                (
                    by_noise.clusters.iter().map(Vec::as_slice).collect(),
                    &by_noise.of_cell,
                )
            }
            (Some(c), None) => (
                c.clusters.iter().map(|c| c.cells.as_slice()).collect(),
                &c.of_cell,
            ),
            (_, own) => {
                let mut params = ClusterSettings::new(1).cluster_params();
                if let Some((omega, max_cells)) = own {
                    params.omega = omega;
                    params.max_cluster_cells = max_cells;
                }
                grown = Some(initial_clustering(grid, sums, &params));
                let c = &grown.as_ref().expect("just grown").clustering;
                (
                    c.clusters.iter().map(|c| c.cells.as_slice()).collect(),
                    &c.of_cell,
                )
            }
        };
        let n = grid.dims();
        let settings = FitSettings {
            degree: self
                .degree
                .unwrap_or(if n == 2 { 2 } else { 1 })
                .min(MAX_DEGREE),
            ridge: self.ridge,
            clamp: self.clamp,
            features: features.is_some() && sums.keeps_features(),
        };
        // Each cluster's model, and the per-sample noise variance of its cells.
        let (fits, noise): (Vec<Fit>, Vec<[f64; 3]>) = cluster_cells
            .par_iter()
            .map(|c| {
                let cells: Vec<FitCell> = c
                    .iter()
                    .map(|&i| fit_cell(grid, sums, cell_features, i as usize, self.weights))
                    .collect();
                let fit = Fit::new(&cells, n, &settings);
                let noise = pooled_noise(sums, c);
                (
                    refit(fit, cells, sums, c, &noise, n, &settings, self.significance),
                    noise,
                )
            })
            .unzip();
        let mut fitted = [0u64; MAX_DEGREE as usize + 1];
        for (c, f) in cluster_cells.iter().zip(&fits) {
            if !c.is_empty() && !f.is_empty() {
                fitted[f.degree() as usize] += 1;
            }
        }
        *self.fitted.lock().unwrap_or_else(|e| e.into_inner()) = fitted;
        let (w, h) = film.settings().size();
        let partition = Partition {
            width: w,
            height: h,
            cluster: (0..h)
                .flat_map(|py| (0..w).map(move |px| (px, py)))
                .map(|(px, py)| {
                    let (cx, cy) = grid.image_cell_of_pixel(px, py);
                    let first = (cy as usize * grid.shape()[0] as usize + cx as usize)
                        * grid.cells_per_image_cell();
                    of_cell[first]
                })
                .collect(),
        };
        *self.partition.lock().unwrap_or_else(|e| e.into_inner()) = Some(partition);
        let stats = film.pixel_stats();
        let stats = &*stats;
        (0..h)
            .into_par_iter()
            .flat_map_iter(|py| {
                let (fits, noise, stats) = (&fits, &noise, stats);
                (0..w).map(move |px| {
                    let model = Model {
                        features: cell_features,
                        grid,
                        sums,
                        of_cell,
                        fits,
                        noise,
                        significance: self.significance,
                    };
                    model.pixel(px, py).unwrap_or_else(|| {
                        // No usable sample in any of the pixel's cells: the film's mean.
                        stats[(py * w + px) as usize].mean()
                    })
                })
            })
            .collect()
    }
}

/// The fit's view of cell `i`, weighted by `weights`.
fn fit_cell(
    grid: &CellGrid,
    sums: &CellSums,
    features: &[Features],
    i: usize,
    weights: CellWeights,
) -> FitCell {
    let (lo, hi) = grid.bounds(i);
    let n = sums.count[i];
    let dims = sums.dims();
    let mut cell = FitCell {
        lo,
        hi,
        m1: [0.5; MAX_DIMS],
        m2: [1.0 / 3.0; MAX_DIMS],
        mean: [0.0; 3],
        features: sums.mean_features_of(features, i).unwrap_or_default(),
        weight: match weights {
            CellWeights::Count => f64::from(n),
            CellWeights::Uniform => f64::from(u8::from(n > 0)),
        },
    };
    if n > 0 {
        let inv = 1.0 / f64::from(n);
        for d in 0..dims {
            cell.m1[d] = f64::from(sums.offset[i * dims + d]) * inv;
            cell.m2[d] = f64::from(sums.offset_sq[i * dims + d]) * inv;
        }
        cell.mean = sums.rgb[i].map(|v| f64::from(v) * inv);
    }
    cell
}

/// The per-sample noise variance of a cluster, per channel: the within-cell sample variance
/// pooled over its cells (independent of how well the model fits them).
fn pooled_noise(sums: &CellSums, cells: &[u32]) -> [f64; 3] {
    let (mut ss, mut dof) = ([0.0f64; 3], 0.0f64);
    for &i in cells {
        let i = i as usize;
        let n = f64::from(sums.count[i]);
        if n < 2.0 {
            continue;
        }
        for (acc, (&s1, &s2)) in ss.iter_mut().zip(sums.rgb[i].iter().zip(&sums.rgb_sq[i])) {
            let (s1, s2) = (f64::from(s1), f64::from(s2));
            *acc += (s2 - s1 * s1 / n).max(0.0);
        }
        dof += n - 1.0;
    }
    if dof > 0.0 {
        ss.map(|v| v / dof)
    } else {
        [0.0; 3]
    }
}

/// The fit again without the cells that depart from `fit` by more than `significance`
/// standard errors in any channel, when they are fewer than half of the sampled cells: a
/// cluster that holds cells on both sides of an edge is then fitted to its majority side, and
/// the others keep their own means (see `Model::pixel`).
#[allow(clippy::too_many_arguments)]
fn refit(
    fit: Fit,
    mut cells: Vec<FitCell>,
    sums: &CellSums,
    ids: &[u32],
    noise: &[f64; 3],
    dims: usize,
    settings: &FitSettings,
    significance: f64,
) -> Fit {
    if significance <= 0.0 || fit.is_empty() {
        return fit;
    }
    let sampled = cells.iter().filter(|c| c.weight > 0.0).count();
    let mut outliers = 0;
    for (c, &i) in cells.iter_mut().zip(ids).filter(|(c, _)| c.weight > 0.0) {
        let v = fit.mean_over(&c.lo, &c.hi, Some(&c.features));
        let count = f64::from(sums.count[i as usize]);
        let far = (0..3).any(|ch| {
            let se = (noise[ch] / count).sqrt();
            (c.mean[ch] - v[ch]).abs() > significance * se
        });
        if far {
            c.weight = 0.0;
            outliers += 1;
        }
    }
    if outliers == 0 || 2 * outliers >= sampled {
        return fit;
    }
    Fit::new(&cells, dims, settings)
}

/// The fitted clusters over the grid: what a pixel is integrated from.
struct Model<'a> {
    /// The cells' feature sums the fit read (prefiltered or the cells' own).
    features: &'a [Features],
    grid: &'a CellGrid,
    sums: &'a CellSums,
    of_cell: &'a [u32],
    fits: &'a [Fit],
    noise: &'a [[f64; 3]],
    significance: f64,
}

impl Model<'_> {
    /// Pixel (`px`, `py`) of the cropped film: the models' integral over the cells it covers,
    /// each weighted by the share of the pixel's volume it covers. A cell whose mean departs
    /// from its model by more than `significance` standard errors keeps that departure: the
    /// model of a smooth field cannot follow an edge through the cell (a cluster holding the
    /// cells on both sides of it, or a cell cut by it), and the cell's own samples then say
    /// more than the fit. None when no covered cell's cluster had a usable sample.
    fn pixel(&self, px: u32, py: u32) -> Option<Spectrum> {
        let grid = self.grid;
        let cs = grid.cell_size();
        let shape = grid.shape();
        let inner = grid.cells_per_image_cell();
        let span = |p: u32, d: usize| {
            let first = ((f64::from(p) / cs).floor() as u32).min(shape[d] - 1);
            let last = ((f64::from(p + 1) / cs).ceil() as u32).min(shape[d]);
            first..last.max(first + 1)
        };
        let (mut sum, mut weight) = ([0.0f64; 3], 0.0f64);
        let pixel_lo = [f64::from(px), f64::from(py)];
        for cy in span(py, 1) {
            for cx in span(px, 0) {
                let first = (cy as usize * shape[0] as usize + cx as usize) * inner;
                for i in first..first + inner {
                    let id = self.of_cell[i] as usize;
                    let fit = &self.fits[id];
                    if fit.is_empty() {
                        continue;
                    }
                    let (cell_lo, cell_hi) = grid.bounds(i);
                    let (mut lo, mut hi) = (cell_lo, cell_hi);
                    let mut volume = 1.0;
                    for d in 0..grid.dims() {
                        if d < 2 {
                            lo[d] = lo[d].max(pixel_lo[d]);
                            hi[d] = hi[d].min(pixel_lo[d] + 1.0);
                        }
                        volume *= (hi[d] - lo[d]).max(0.0);
                    }
                    if volume <= 0.0 {
                        continue;
                    }
                    let features = self.sums.mean_features_of(self.features, i);
                    let mut v = fit.mean_over(&lo, &hi, features.as_ref());
                    let count = self.sums.count[i];
                    if self.significance > 0.0 && count > 0 {
                        let whole = fit.mean_over(&cell_lo, &cell_hi, features.as_ref());
                        let n = f64::from(count);
                        for ch in 0..3 {
                            let mean = f64::from(self.sums.rgb[i][ch]) / n;
                            let r = mean - whole[ch];
                            let se = (self.noise[id][ch] / n).sqrt();
                            if r.is_finite() && r.abs() > self.significance * se {
                                v[ch] = (v[ch] + r).max(0.0);
                            }
                        }
                    }
                    for k in 0..3 {
                        sum[k] += volume * v[k];
                    }
                    weight += volume;
                }
            }
        }
        (weight > 0.0).then(|| {
            Spectrum::new(
                (sum[0] / weight) as f32,
                (sum[1] / weight) as f32,
                (sum[2] / weight) as f32,
            )
        })
    }
}

impl Filter for PolynomialFilter {
    fn name(&self) -> &'static str {
        "polynomial"
    }

    fn kernel(&self) -> &dyn FilterKernel {
        &self.kernel
    }

    fn reconstruct(&self, film: &Film, from: SamplerOutput<'_>) -> Vec<Spectrum> {
        // With features, the film's cells: they hold them, whatever the sampler keeps.
        let film_first = self.features.is_some() && film.cells().is_some();
        let cells = if film_first {
            film.cells()
        } else {
            from.cells.or_else(|| film.cells())
        };
        match cells {
            Some(view) => self.reconstruct_cells(film, view),
            // No cells anywhere (a film made without them): the pixel means.
            None => film.pixels(),
        }
    }

    fn report(&self) -> FilterReport {
        FilterReport {
            fitted_by_degree: Some(self.fitted_by_degree()),
        }
    }

    fn cell_layout(&self) -> Option<(f64, u32)> {
        // The cluster sampler's default cells: one per pixel, time and lens not cut.
        Some((1.0, 1))
    }

    fn fit_partition(&self) -> Option<Partition> {
        self.partition
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }

    fn reads_features(&self) -> bool {
        self.features.is_some()
    }
}

/// The registry's entry.
pub(super) const ENTRY: Entry<FilterBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Filter,
        name: "polynomial",
        doc: "the paper's reconstruction: one additive Legendre polynomial per cluster of cells \
              (plus a linear term per first-hit feature unless features is false), fitted by \
              weighted least squares and integrated over each pixel",
        params: &[
            ParamSpec::new(
                "degree",
                ParamType::Integer,
                "2 (x, y only), 1 above",
                "degree per dim, 0 to 2 (0: each cluster's mean)",
            ),
            ParamSpec::new(
                "ridge",
                ParamType::Float,
                "1e-6",
                "ridge of the least squares, relative to the normal matrix's mean diagonal",
            ),
            ParamSpec::new(
                "significance",
                ParamType::Float,
                "0 with features, 3 without",
                "a cell whose mean departs from its cluster's model by more standard errors \
                 than this keeps the departure (0: never); without features it keeps the step \
                 edges a smooth fit would smear. With features a comparison: measured worse on \
                 every bench scene (the room 4.7x the MSE at 8 spp), the features keep the \
                 edges; see docs/reconstruction.md",
            ),
            ParamSpec::new(
                "omega",
                ParamType::Float,
                "the sampler's",
                "with features false: grow the fit's own clusters with this ω of eq. 10 \
                 (smaller: larger clusters)",
            ),
            ParamSpec::new(
                "maxclustercells",
                ParamType::Integer,
                "the sampler's",
                "with features false: most cells in one of the fit's own clusters",
            ),
            ParamSpec::new(
                "noise",
                ParamType::Float,
                "0 (off)",
                "fit clusters merged by noise instead: neighbours whose means agree within this \
                 many standard errors of their pooled noise",
            ),
            ParamSpec::new(
                "mincells",
                ParamType::Integer,
                "16",
                "with noise clusters: a cluster of fewer cells joins its most alike neighbour \
                 whose mean agrees within the noise test, features aside (1: never)",
            ),
            ParamSpec::new(
                "features",
                ParamType::Bool,
                "true",
                "regress on the first-hit features (albedo, normal, depth) too, in clusters \
                 merged by noise where the features agree (noise 8 unless set); false: the \
                 paper's fit, a comparison (see docs/reconstruction.md)",
            ),
            ParamSpec::new(
                "featuretolerance",
                ParamType::Float,
                "0.2",
                "with features: the most two clusters' mean features may differ to merge \
                 (albedo per channel, half the normal per axis, depth relative)",
            ),
            ParamSpec::new(
                "prefilter",
                ParamType::Integer,
                "1",
                "with features: average each cell's features with the cells within this many \
                 cells whose shading agrees and whose albedo, normal and depth differ by no \
                 more than their noise, before the fit (0: off)",
            ),
            ParamSpec::new(
                "kappa",
                ParamType::Float,
                "2",
                "the prefilter's strength: a neighbour whose feature differs by d (squared) \
                 weighs exp(-max(0, d - v) / (kappa^2 v + s^2)), v the two cells' noise, s 0 \
                 for albedo, 0.5 for the normal, 0.1 of the depth",
            ),
            ParamSpec::new(
                "weights",
                ParamType::String,
                "count",
                "a cell's weight in its cluster's fit: \"count\" (its samples, the paper's) \
                 or \"uniform\" (every sampled cell alike, independent of the values)",
            ),
            ParamSpec::new(
                "clamp",
                ParamType::Bool,
                "true",
                "clamp values to the range of the cluster's cell means",
            ),
        ],
    },
    build,
};

fn build(c: &Choice) -> Result<Box<dyn Filter>> {
    let p = &c.params;
    let degree = match p.get("degree") {
        Some(_) => Some(int_in(p, "degree", 1, 0..=i64::from(MAX_DEGREE))?),
        None => None,
    };
    let ridge = float_in(p, "ridge", 1e-6, 0.0..=1.0)?;
    let clamp = p.bool_or("clamp", true)?;
    let with_features = p.bool_or("features", true)?;
    let significance = if with_features {
        FEATURE_SIGNIFICANCE
    } else {
        PLAIN_SIGNIFICANCE
    };
    let significance = float_in(p, "significance", significance, 0.0..=1e3)?;
    let mut f = PolynomialFilter::new(degree, ridge, clamp, significance)
        .with_noise_clusters(float_in(p, "noise", 0.0, 0.0..=1e3)?)
        .with_min_cells(int_in(
            p,
            "mincells",
            MIN_CLUSTER_CELLS as i32,
            1..=1 << 24,
        )?);
    let tolerance = float_in(p, "featuretolerance", FEATURE_TOLERANCE, 0.0..=1e3)?;
    if with_features {
        f = f.with_features(Some(tolerance));
    }
    let radius = int_in(p, "prefilter", PREFILTER_RADIUS as i32, 0..=8)?;
    let kappa = float_in(p, "kappa", PREFILTER_KAPPA, 1e-3..=1e3)?;
    f = f.with_prefilter(radius, kappa);
    f = f.with_weights(match one_of(p, "weights", &["count", "uniform"])? {
        0 => CellWeights::Count,
        _ => CellWeights::Uniform,
    });
    if p.get("omega").is_some() || p.get("maxclustercells").is_some() {
        let d = ClusterSettings::new(1);
        let omega = float_in(p, "omega", d.omega, 1e-3..=1e3)?;
        let max_cells = int_in(
            p,
            "maxclustercells",
            d.max_cluster_cells as i32,
            1..=1 << 24,
        )?;
        f = f.with_own_clusters(omega, max_cells);
    }
    Ok(Box::new(f))
}
