//! The stats file (`--stats`): one JSON object, as docs/cli.md lists its keys.

use serde::Serialize;

/// Seconds spent in each phase.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Seconds {
    /// Reading and parsing the scene files.
    pub parse: f64,
    /// Building the scene (BVH, lights, materials, textures).
    pub build: f64,
    /// Tracing samples (the sampler's time included).
    pub render: f64,
    /// Of the render, the wall time of the sampler's calls (choosing points, learning from
    /// them). A sampler that plans ahead is called while tracing goes on, and threads waiting
    /// in its calls take up tracing: then this is more than it adds (see `sampler_share`).
    pub sampler: f64,
    /// With `--sampler-cost`: the render again, its batches replayed by a sampler doing no work
    /// (the render loop alone, median of three).
    pub replay: Option<f64>,
    /// With `--sampler-cost`: the render again, by a fresh sampler (the render loop alone,
    /// median of three, alternating with the replays).
    pub rerender: Option<f64>,
    /// Reconstructing the image from the film.
    pub reconstruct: f64,
    /// Writing output files.
    pub write: f64,
    /// Wall time of the whole command.
    pub total: f64,
}

/// Everything the stats file reports.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Stats {
    /// The scene file.
    pub scene: String,
    /// Image width (after crop).
    pub width: u32,
    /// Image height (after crop).
    pub height: u32,
    /// Samples per pixel asked for.
    pub spp: u32,
    /// Samples traced.
    pub samples: u64,
    /// Rays traced (camera, continuation and shadow).
    pub rays: u64,
    /// Worker threads.
    pub threads: usize,
    /// Seed.
    pub seed: u64,
    /// Sampler name.
    pub sampler: String,
    /// Reconstruction filter name.
    pub filter: String,
    /// Integrator name.
    pub integrator: String,
    /// Who chose the sampler and filter: "scene" (the scene and the command line), or
    /// "auto:SAMPLER+FILTER" (`--pipeline auto`, or a time limit or noise threshold with
    /// neither named; docs/cli.md).
    pub pipeline: String,
    /// Active dimensions of the rendering space, e.g. ["x","y","t"].
    pub dims: Vec<String>,
    /// The time limit or the noise threshold stopped the render before its budget was spent.
    pub halted: bool,
    /// What stopped it: "time" or "noise" (null when the budget was spent).
    pub halted_by: Option<&'static str>,
    /// Clusters of the cluster sampler (null for other samplers).
    pub clusters: Option<u64>,
    /// Cells of the cluster sampler's grid (null for other samplers).
    pub cells: Option<u64>,
    /// Adaptive rounds of the cluster sampler (null for other samplers).
    pub rounds: Option<u64>,
    /// Clusters the polynomial reconstruction fitted at degree 0, 1 and 2 (null for other
    /// filters).
    pub fitted_by_degree: Option<[u64; 3]>,
    /// A render by bands (docs/reconstruction.md, "Rendering by bands"): the bands its filter
    /// made as the samples came in (null when the image was made at the end).
    pub bands: Option<u64>,
    /// Samples dropped for NaN, infinite or negative radiance.
    pub dropped_samples: u64,
    /// Time per phase.
    pub seconds: Seconds,
    /// With `--sampler-cost`: the share of the render's wall time the sampler added, the
    /// median over three back-to-back pairs of (rerender - replay) / rerender (0 if negative).
    pub sampler_share: Option<f64>,
    /// With `--sampler-cost`: each back-to-back pair's [rerender, replay] seconds, in the
    /// order run (`seconds.rerender`, `seconds.replay` and `sampler_share` are their medians).
    pub sampler_cost_pairs: Option<[[f64; 2]; 3]>,
    /// Millions of rays per second of render time.
    pub mrays_per_s: f64,
    /// Peak resident memory in MiB.
    pub peak_rss_mb: f64,
    /// The peak resident memory so far (MiB) when each phase ended: the first phase that
    /// reaches `peak_rss_mb` holds the peak.
    pub peak_rss_mb_by_phase: ByPhase,
    /// The resident memory (MiB) held when each phase ended.
    pub rss_mb_by_phase: ByPhase,
}

/// A figure at the end of each phase of a render.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct ByPhase {
    /// Reading and parsing the scene files.
    pub parse: f64,
    /// Building the scene.
    pub build: f64,
    /// The render loop (and `--sampler-cost`'s measure).
    pub render: f64,
    /// Reconstructing the image.
    pub reconstruct: f64,
    /// Writing the output files.
    pub write: f64,
}

/// The process's resident memory at one moment, in MiB.
#[derive(Clone, Copy, Debug, Default)]
pub struct Rss {
    /// The peak so far (Linux: VmHWM).
    pub peak: f64,
    /// What is resident now (Linux: VmRSS).
    pub held: f64,
}

impl Rss {
    /// Now; zeros where unknown.
    pub fn now() -> Self {
        let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        Self {
            peak: status_mb(&status, "VmHWM:"),
            held: status_mb(&status, "VmRSS:"),
        }
    }
}

/// The figure of `key` in `/proc/self/status`'s text, from kB to MiB; 0 where absent.
fn status_mb(status: &str, key: &str) -> f64 {
    status
        .lines()
        .find(|l| l.starts_with(key))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|kb| kb.parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0)
}

/// The median of `v` (the mean of the middle two for an even count); NaN when empty. Sorts
/// `v`.
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => v[n / 2],
        _ => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}

/// Peak resident set size of this process in MiB (Linux: VmHWM), or 0 where unknown.
pub fn peak_rss_mb() -> f64 {
    Rss::now().peak
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(&mut []).is_nan());
    }
}
