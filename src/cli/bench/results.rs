//! What a bench measures: a row per scene, method, budget and mode (means over its seeds), and
//! the sampler-cost measures.

use super::{CommandTime, Mode};
use crate::cli::stats::median;
use crate::metrics::Metrics;

/// One row of the results.
#[derive(Clone, Debug)]
pub struct Row {
    /// Scene label.
    pub scene: String,
    /// Method label.
    pub method: String,
    /// How it was budgeted.
    pub mode: Mode,
    /// The budget (equal-time: the budget whose baseline time it was given).
    pub spp: u32,
    /// How many seeds its figures are the means over.
    pub seeds: usize,
    /// What the run measured (the means over its seeds), or why it (one of them) failed.
    pub outcome: Result<Measured, String>,
}

/// What a successful run measured.
#[derive(Clone, Debug)]
pub struct Measured {
    /// Render plus reconstruction time, from its stats file, plus an external method's
    /// command's.
    pub seconds: f64,
    /// An external method's command's share of `seconds`.
    pub command_seconds: Option<f64>,
    /// How that share was counted.
    pub command_time: Option<CommandTime>,
    /// The reconstruction's share of `seconds` (after the render's time limit, like a
    /// command's).
    pub reconstruct_seconds: f64,
    /// Samples taken.
    pub samples: u64,
    /// Samples per pixel reached.
    pub spp_reached: f64,
    /// Error against the reference.
    pub metrics: Metrics,
    /// Peak resident memory of the run's process.
    pub peak_rss_mb: f64,
}

/// The sampler's share of wall time of one method on one scene at one budget.
#[derive(Clone, Debug)]
pub struct CostRow {
    /// Scene label.
    pub scene: String,
    /// Method label.
    pub method: String,
    /// The budget.
    pub spp: u32,
    /// Each run's figures, or why a run failed.
    pub outcome: Result<Vec<SamplerCost>, String>,
}

/// What one `--sampler-cost` run reported.
#[derive(Clone, Copy, Debug)]
pub struct SamplerCost {
    /// Its `sampler_share`.
    pub share: f64,
    /// Its `seconds.rerender`: a render by a fresh sampler.
    pub rerender: f64,
    /// Its `seconds.replay`: the same points traced without the sampler.
    pub replay: f64,
}

/// A sampler-cost measure over its runs.
#[derive(Clone, Copy, Debug)]
pub(super) struct CostSummary {
    /// How many runs.
    pub(super) runs: usize,
    /// The median share.
    pub(super) share: f64,
    /// The least share.
    pub(super) least: f64,
    /// The largest share.
    pub(super) largest: f64,
    /// The median seconds of a render by a fresh sampler.
    pub(super) rerender: f64,
    /// The median seconds of a replay.
    pub(super) replay: f64,
}

impl Measured {
    /// The means of `runs` (one per seed; the largest peak memory), or the first failure.
    pub(super) fn mean_of(runs: Vec<Result<Measured, String>>) -> Result<Measured, String> {
        let runs = runs.into_iter().collect::<Result<Vec<_>, String>>()?;
        let n = runs.len().max(1) as f64;
        let mean = |f: fn(&Measured) -> f64| runs.iter().map(f).sum::<f64>() / n;
        Ok(Measured {
            seconds: mean(|r| r.seconds),
            command_seconds: runs
                .iter()
                .map(|r| r.command_seconds)
                .sum::<Option<f64>>()
                .map(|t| t / n),
            command_time: runs.first().and_then(|r| r.command_time),
            reconstruct_seconds: mean(|r| r.reconstruct_seconds),
            samples: mean(|r| r.samples as f64).round() as u64,
            spp_reached: mean(|r| r.spp_reached),
            metrics: Metrics {
                mse: mean(|r| r.metrics.mse),
                relmse: mean(|r| r.metrics.relmse),
                psnr: mean(|r| r.metrics.psnr),
                mean: mean(|r| r.metrics.mean),
                reference_mean: mean(|r| r.metrics.reference_mean),
            },
            peak_rss_mb: runs.iter().map(|r| r.peak_rss_mb).fold(0.0, f64::max),
        })
    }
}

impl CostRow {
    /// Its runs summed up, or why one failed.
    pub(super) fn summary(&self) -> Result<CostSummary, &str> {
        let runs = self.outcome.as_deref().map_err(String::as_str)?;
        let of = |f: fn(&SamplerCost) -> f64| runs.iter().map(f).collect::<Vec<_>>();
        let mut shares = of(|r| r.share);
        let share = median(&mut shares);
        Ok(CostSummary {
            runs: runs.len(),
            share,
            // Sorted by the median.
            least: shares.first().copied().unwrap_or(f64::NAN),
            largest: shares.last().copied().unwrap_or(f64::NAN),
            rerender: median(&mut of(|r| r.rerender)),
            replay: median(&mut of(|r| r.replay)),
        })
    }
}

/// Everything a bench measured.
#[derive(Clone, Debug)]
pub struct BenchResults {
    /// The equal-spp and equal-time runs.
    pub rows: Vec<Row>,
    /// The sampler-cost measures.
    pub costs: Vec<CostRow>,
}
