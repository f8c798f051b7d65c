//! The cluster sampler under `--noise-threshold` (docs/algorithm.md §9): a first stage of what
//! every pixel must have, and each cluster's own relative error, by which a cluster settles
//! when `settle` is on.

use super::{ClusterSampler, Phase, SobolSampler, SALT};
use crate::film::relative_error_of;

impl ClusterSampler {
    /// Stops where the error is below `threshold` (with `settle`), once the cells hold
    /// `min_spp` samples; before the first batch, the first stage shrinks to `min_spp` (Cycles'
    /// adaptive_min_samples) unless `initspp` was given, so that the threshold steers the
    /// rest: planned for the whole budget, it would spend a quarter of it before adapting.
    pub(super) fn settle_at_noise(&mut self, threshold: f64, min_spp: u32) {
        self.noise = Some((threshold, min_spp));
        let unstarted = self.phase == Phase::Init && self.pixel_count.iter().all(|&n| n == 0);
        if unstarted && !self.settings.init_given {
            let s = &mut self.settings;
            s.init_spp = s.init_spp.min(min_spp.max(s.min_spp)).clamp(1, s.spp);
            self.init =
                SobolSampler::new(self.space, s.init_spp, self.seed ^ SALT).with_stream(s.stream);
            self.remaining = self.adaptive_budget();
        }
    }

    /// The relative error of cluster `id`, as `--noise-threshold` defines it for an image:
    /// the mean over its cells of the standard error of the cell's mean luminance over
    /// (that mean + 0.01). Infinite while a cell has fewer than `least` samples (or two).
    pub(super) fn relative_error(&self, id: u32, least: u32) -> f64 {
        let clustering = self.clustering.as_ref().expect("clustered");
        let cells = &clustering.clusters[id as usize].cells;
        let mut total = 0.0;
        for &c in cells {
            let c = c as usize;
            let n = self.sums.count[c];
            if n < least.max(2) {
                return f64::INFINITY;
            }
            let mean = self.sums.mean(c).unwrap_or(0.0);
            total += relative_error_of(mean, self.sums.variance(c) / f64::from(n));
        }
        total / cells.len().max(1) as f64
    }
}
