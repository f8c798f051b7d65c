//! The cluster sampler's knobs: their defaults (each measured), the registry's declaration
//! and the parsing of a scene's or the command line's values.

use super::ClusterSampler;
use crate::cells::build::ClusterParams;
use crate::registry::{
    error_at_param, float_in, int_in, one_of, Choice, Entry, Kind, ParamSpec, PluginInfo,
};
use crate::sampler::{IndexStream, Sampler, SamplerBuild, SamplerSetup};
use acr_parser::{ParamType, Result};

/// How the next clusters to sample are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Priority {
    /// Error per sample, err(Ω) × cells(Ω) / samples(Ω): a cluster whose error does not fall
    /// when sampled cannot take every sample.
    PerSample,
    /// The paper's rule: the largest err(Ω).
    Paper,
    /// By the reconstruction's estimated error (`guide "reconstruction"`): the cluster's
    /// summed error at the end of the first stage times its samples then, over its samples
    /// squared: what one more sample takes off an error that falls as one over the samples.
    Guided,
}

/// The cluster sampler's knobs (docs/plugins.md; `acr plugins` lists them with their defaults).
#[derive(Clone, Copy, Debug)]
pub struct ClusterSettings {
    /// Samples per pixel, on average: the budget is spp × pixels.
    pub spp: u32,
    /// ω of eq. 10: larger is stricter, so clusters are smaller.
    pub omega: f64,
    /// Pixels per image cell side (0.5 is the paper's quarter pixel).
    pub cell_size: f64,
    /// Intervals per non-image dim.
    pub bins: u32,
    /// Samples per pixel of the first, uniform stage.
    pub init_spp: u32,
    /// Fewest samples any pixel ends with.
    pub min_spp: u32,
    /// Most cells in one cluster.
    pub max_cluster_cells: u32,
    /// Weights of the gradient, variance, position and level parts of the feature distance.
    pub weights: [f64; 4],
    /// How clusters are chosen for sampling.
    pub priority: Priority,
    /// Keep each pixel's points evenly spread over the pixel and its time and lens dims (the
    /// pixel's Owen-scrambled Sobol sequence, which the first stage started: however many
    /// points a pixel ends with, they stay stratified), and adapt only how many points each
    /// pixel gets. A splatting
    /// filter weighs every point of a pixel alike, so points crowded into some cells would pull
    /// the pixel toward those cells' radiance, and points drawn at random in a cell lose the
    /// stratification a pixel's sequence has.
    pub even_pixels: bool,
    /// Log-compress g and s (ln(1 + x) after scaling), so that a few extreme cells do not
    /// dominate the distances and the priority.
    pub log_features: bool,
    /// Sum each cell's radiance and sample positions, for a reconstruction that reads the
    /// cells (the polynomial filter); the sampler itself needs only counts and luminance.
    pub keep_radiance: bool,
    /// Which interleaved stream of sample indices it gives (see [`IndexStream`]).
    pub stream: IndexStream,
    /// Whether `init_spp` was given (then `--noise-threshold` keeps it).
    pub init_given: bool,
    /// With `--noise-threshold`, a cluster whose own relative error is below the threshold
    /// leaves the queue (measured: more error per sample than letting the priority run).
    pub settle: bool,
    /// The colour (parity of column + row, from the space's corner) of the pixels whose
    /// adaptive samples it places, when it is one half of an unbiased pair (see
    /// `crossed.rs`); a sample drawn at a pixel of the other colour goes to its partner
    /// pixel in the same row (or column). `None`: every pixel.
    pub colour: Option<u32>,
    /// Place the rounds by the reconstruction's estimated error, read once after the first
    /// stage (`guide "reconstruction"`, see `guided.rs`), each pixel's samples in pairs of
    /// consecutive indices.
    pub guided: bool,
}

impl ClusterSettings {
    /// The defaults for a budget of `spp` samples per pixel.
    pub fn new(spp: u32) -> Self {
        Self {
            spp,
            omega: 0.7,
            cell_size: 1.0,
            // Our first reading of the paper had 2 (docs/algorithm.md §2). Measured with acr bench
            // over the 3D, 4D and 5D scenes at 4, 8 and 16 spp (geometric mean of the MSE ratio to
            // stratified+gaussian): bins 1 0.79 (worst case 0.93), 2 0.82 (1.22), 3 1.12
            // (1.50); with a splatting filter, cells cut in time and lens hold one or two
            // samples each and their features are mostly noise. bins 1 also has a quarter to
            // an eighth of the cells, so the sampler costs less (5D, 8 spp: 35% of wall time
            // against 53%).
            bins: 1,
            init_spp: crate::sampler::first_stage_spp(spp, 1),
            min_spp: 1,
            max_cluster_cells: 64,
            // Measured with acr bench (docs/BENCHMARKS.md, "Cluster sampler knobs"): over
            // motion-blur-3d, depth-of-field-4d and motion-dof-5d at 4, 8 and 16 spp, the
            // geometric mean of the MSE ratio to stratified+gaussian fell from 0.98 at
            // posweight 1 to 0.90 at 1/4, 0.86 at 1/16 and 0.83 at 1/64 (0.84 at 0);
            // gradweight and varweight 1/4 or 4 moved it by -3% to +5%.
            weights: [1.0, 1.0, 1.0 / 64.0, 1.0],
            priority: Priority::PerSample,
            even_pixels: true,
            // Measured: geometric-mean MSE ratio 0.98 with, 1.07 without (posweight 1/4:
            // 0.90 with, 0.99 without); motion-blur-3d at 16 spp 0.92 with, 1.38 without.
            log_features: true,
            keep_radiance: true,
            stream: IndexStream::ALL,
            init_given: false,
            settle: false,
            colour: None,
            guided: false,
        }
    }

    /// The knobs of the clustering itself.
    pub fn cluster_params(&self) -> ClusterParams {
        ClusterParams {
            omega: self.omega,
            weights: self.weights,
            max_cluster_cells: self.max_cluster_cells,
            log_features: self.log_features,
        }
    }
}

/// The registry's entry.
pub(in crate::sampler) const ENTRY: Entry<SamplerBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Sampler,
        name: "cluster",
        doc: "adaptive cluster sampling: cells grouped by gradient, variance and position; \
              samples go to the clusters of highest error per sample",
        params: &[
            ParamSpec::new(
                "pixelsamples",
                ParamType::Integer,
                "16",
                "samples per pixel on average (--spp overrides); the budget is spp x pixels",
            ),
            ParamSpec::new(
                "omega",
                ParamType::Float,
                "0.7",
                "eq. 10's ω: a cell joins a cluster while ω|F - mean F| <= err; larger: smaller clusters",
            ),
            ParamSpec::new(
                "cellsize",
                ParamType::Float,
                "1",
                "pixels per cell side in x and y (0.5: quarter-pixel cells)",
            ),
            ParamSpec::new(
                "bins",
                ParamType::Integer,
                "1",
                "cells along each time and lens dim (1: no cut)",
            ),
            ParamSpec::new(
                "initspp",
                ParamType::Integer,
                "spp/4, at least 1",
                "samples per pixel of the first, uniform stage",
            ),
            ParamSpec::new(
                "minspp",
                ParamType::Integer,
                "1",
                "fewest samples a pixel ends with",
            ),
            ParamSpec::new(
                "maxclustercells",
                ParamType::Integer,
                "64",
                "most cells in one cluster",
            ),
            ParamSpec::new(
                "gradweight",
                ParamType::Float,
                "1",
                "weight of the affine-invariant gradient in the feature distance",
            ),
            ParamSpec::new(
                "varweight",
                ParamType::Float,
                "1",
                "weight of the cell variance in the feature distance",
            ),
            ParamSpec::new(
                "posweight",
                ParamType::Float,
                "0.015625",
                "weight of the cell position in the feature distance",
            ),
            ParamSpec::new(
                "levelweight",
                ParamType::Float,
                "1",
                "weight of the cell's mean luminance in the feature distance (not in the paper)",
            ),
            ParamSpec::new(
                "evenpixels",
                ParamType::Bool,
                "true",
                "spread each pixel's points evenly over it and its time and lens bins, as \
                 splatting filters need (false: sample the chosen cells themselves)",
            ),
            ParamSpec::new(
                "logfeatures",
                ParamType::Bool,
                "true",
                "log-compress the gradient and variance features, ln(1 + x)",
            ),
            ParamSpec::new(
                "priority",
                ParamType::String,
                "persample",
                "which clusters get samples: persample (err x cells / samples) or paper (err: \
                 the paper's rule, a comparison; measured 1.9x to 6.5x stratified's MSE, see \
                 docs/cluster-sampler.md)",
            ),
            ParamSpec::new(
                "settle",
                ParamType::Bool,
                "false",
                "with --noise-threshold, a cluster whose own relative error is below the \
                 threshold gets no more samples. A comparison: measured 1.1x to 1.4x the \
                 relative MSE at the same threshold, since the priority already gives few \
                 samples where the error is low; see docs/cluster-sampler.md",
            ),
            ParamSpec::new(
                "unbiased",
                ParamType::Bool,
                "true (false with pilot or streams)",
                "place each pixel's adaptive samples from other pixels' first-stage samples \
                 only (a checkerboard of two halves), so that no pixel's count depends on its \
                 own values and the image mean is unbiased",
            ),
            ParamSpec::new(
                "guide",
                ParamType::String,
                "none",
                "none, or reconstruction: after the first stage the rounds go to the clusters \
                 of largest summed estimated error of the reconstruction (the filter's own \
                 estimate, else each pixel's variance of the mean), read once, each pixel's \
                 samples in pairs of consecutive indices; see docs/cluster-sampler.md",
            ),
            crate::sampler::paired::STREAMS,
            crate::sampler::paired::PILOT,
        ],
    },
    build: build_streams,
};

/// Builds the sampler as two streams, each placed by the other's values (or as one, with
/// `streams 1`).
fn build_streams(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn crate::sampler::Sampler>> {
    crate::sampler::paired::wrap(c, setup, build)
}

/// Builds the sampler from its choice (the registry entry's `build`).
pub(super) fn build(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn Sampler>> {
    let p = &c.params;
    let spp = crate::sampler::pixel_samples(p, setup)?;
    let mut s = ClusterSettings::new(spp);
    s.keep_radiance = setup.reconstruction_reads_cells;
    s.stream = setup.stream;
    s.omega = float_in(p, "omega", s.omega, 1e-3..=1e3)?;
    s.cell_size = float_in(p, "cellsize", s.cell_size, 0.125..=64.0)?;
    s.bins = int_in(p, "bins", s.bins as i32, 1..=16)?;
    let max = i64::from(spp);
    // Unbiased unless it is one stream of a pilot or of two streams, which take the bias off
    // (or not) their own way.
    let whole = setup.stream == IndexStream::ALL;
    let unbiased = p.bool_or("unbiased", whole)? && setup.space.pixels() > 1;
    if unbiased && !whole {
        let message = "unbiased cannot be combined with a pilot or two streams";
        return Err(error_at_param(p, &["unbiased"], "cluster sampler", message));
    }
    s.guided = one_of(p, "guide", &["none", "reconstruction"])? == 1;
    if s.guided && !whole {
        let message = "guide cannot be combined with a pilot or two streams";
        return Err(error_at_param(p, &["guide"], "cluster sampler", message));
    }
    if unbiased {
        // Decisions read the first stage alone: two samples per pixel at least, so that each
        // cell has a variance (measured at 4 spp: MSE 0.70x and 0.76x that of one sample on
        // motion-blur and depth-of-field).
        s.init_spp = (spp / 4).max(2).min(spp);
    }
    if s.guided {
        // The estimate is read at the end of the first stage from each half's own variance:
        // two samples per half at least, else a reconstruction such as NFOR estimates its
        // error from one difference per pixel, mostly noise (docs/cluster-sampler.md, "Guided
        // by the reconstruction's error"). Below twice that budget it would leave no rounds
        // for the map to guide worth the name: the quarter stays.
        if spp >= 2 * super::guided::FIRST_STAGE_MIN {
            s.init_spp = s.init_spp.max(super::guided::FIRST_STAGE_MIN);
        }
    }
    s.init_spp = int_in(p, "initspp", s.init_spp as i32, 1..=max)?;
    if s.guided {
        // Every pixel's count even, so that its two halves (index parities) match.
        s.init_spp = super::guided::even_up(s.init_spp, spp);
    }
    s.init_given = p.get("initspp").is_some();
    s.settle = p.bool_or("settle", s.settle)?;
    s.min_spp = int_in(p, "minspp", s.min_spp as i32, 0..=max)?;
    s.max_cluster_cells = int_in(
        p,
        "maxclustercells",
        s.max_cluster_cells as i32,
        1..=1 << 24,
    )?;
    for (k, name) in ["gradweight", "varweight", "posweight", "levelweight"]
        .iter()
        .enumerate()
    {
        s.weights[k] = float_in(p, name, s.weights[k], 0.0..=1e6)?;
    }
    s.even_pixels = p.bool_or("evenpixels", true)?;
    s.log_features = p.bool_or("logfeatures", s.log_features)?;
    s.priority = match one_of(p, "priority", &["persample", "paper"])? {
        0 => Priority::PerSample,
        _ => Priority::Paper,
    };
    // Cells beyond what memory can hold are refused before anything is allocated.
    let grid_cells = {
        let along = |w: u32| (f64::from(w) / s.cell_size).ceil().max(1.0);
        along(setup.space.width())
            * along(setup.space.height())
            * f64::from(s.bins).powi(setup.space.dims.count() as i32 - 2)
    };
    if grid_cells > MAX_CELLS as f64 {
        let message = format!(
            "the cluster sampler's grid would have {grid_cells:.0} cells (most {MAX_CELLS}); \
             raise cellsize or lower bins"
        );
        return Err(error_at_param(
            p,
            &["cellsize", "bins"],
            "cluster sampler",
            message,
        ));
    }
    if unbiased {
        if !s.even_pixels {
            let message = "unbiased needs evenpixels: a pixel's points must be its own sequence";
            return Err(error_at_param(
                p,
                &["evenpixels"],
                "cluster sampler",
                message,
            ));
        }
        // Neither half's cells are what the reconstruction reads: the film collects them.
        s.keep_radiance = false;
        let half = |colour| ClusterSampler::new(setup.space, s, setup.seed).for_colour(colour);
        return Ok(Box::new(super::crossed::Crossed::new([half(0), half(1)])));
    }
    Ok(Box::new(ClusterSampler::new(setup.space, s, setup.seed)))
}

/// Most cells the grid may have: about 80 bytes each, so 2^26 cells stay within 6 GiB.
pub const MAX_CELLS: u64 = 1 << 26;
