//! The cluster sampler under a time limit that adapts (docs/algorithm.md §9): the render loop
//! tells it, after every batch, how many samples per pixel its measured speed says fit in the
//! time left, and it plans its first stage and its rounds for that instead of for its budget
//! (planned for `--spp 64`, a first stage of 16 spp would spend the whole time and never
//! adapt).

use super::{ClusterSampler, Phase, PixelPattern};
use crate::sampler::first_stage_spp;

impl ClusterSampler {
    /// The fewest first-stage samples per pixel it can still end that stage at: the passes
    /// given and the one under way, or, once the stage is over, what it gave.
    pub(super) fn init_floor(&self) -> u32 {
        match self.state.phase {
            Phase::Init => self.state.init.cursor().floor(),
            _ => self.settings.init_spp,
        }
    }

    /// Plans for `spp` samples per pixel in all (at most its budget): while the first stage
    /// is under way it shrinks to its share of them (a quarter unless `initspp` was given; not
    /// below `floor`, `minspp`, or 2 in an unbiased pair), and the rounds get the rest of
    /// them, less what they gave.
    pub(super) fn plan_budget(&mut self, spp: u32, floor: u32) {
        let s = &self.settings;
        let spp = spp.clamp(1, s.spp);
        if self.state.phase == Phase::Init {
            let lowest = if s.colour.is_some() { 2 } else { 1 };
            let share = if s.init_given {
                s.init_spp
            } else {
                first_stage_spp(spp, lowest)
            };
            let mut init = share.max(s.min_spp).max(floor).min(s.init_spp);
            if s.guided {
                init = super::guided::even_up(init, s.init_spp);
            }
            self.settings.init_spp = self.state.init.cursor_mut().shorten(init);
        }
        let planned = self.own_pixels() * u64::from(spp.saturating_sub(self.settings.init_spp));
        self.state.remaining = planned.saturating_sub(self.state.given_adaptive);
    }
}
