//! The cluster sampler under `--noise-threshold` (docs/algorithm.md §9): a first stage of what
//! every pixel must have, and each cluster's own relative error, by which a cluster settles
//! when `settle` is on.

use super::{ClusterSampler, Phase, SobolSampler, SALT};

impl ClusterSampler {
    /// Stops where the error is below `threshold` (with `settle`), once the cells hold
    /// `min_spp` samples; before the first batch, the first stage shrinks to `min_spp` (Cycles'
    /// adaptive_min_samples) unless `initspp` was given, so that the threshold steers the
    /// rest: planned for the whole budget, it would spend a quarter of it before adapting.
    pub(super) fn settle_at_noise(&mut self, threshold: f64, min_spp: u32) {
        self.state.noise = Some((threshold, min_spp));
        let unstarted =
            self.state.phase == Phase::Init && self.state.pixel_count.iter().all(|&n| n == 0);
        if unstarted && !self.settings.init_given {
            let s = &mut self.settings;
            s.init_spp = s.init_spp.min(min_spp.max(s.min_spp)).clamp(1, s.spp);
            if s.guided {
                s.init_spp = super::guided::even_up(s.init_spp, s.spp);
            }
            self.state.init =
                SobolSampler::new(self.space, s.init_spp, self.seed ^ SALT).with_stream(s.stream);
            self.state.remaining = self.adaptive_budget();
        }
    }
}
