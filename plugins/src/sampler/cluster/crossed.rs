//! The cluster sampler without selection bias (`unbiased`, docs/algorithm.md §8). A pixel whose
//! count is decided from its own samples is biased: where the rare outcome is the bright one,
//! a pixel whose first samples agree looks settled and keeps its dark estimate. Here the
//! pixels are coloured as a checkerboard and two instances of the sampler share the work: each
//! learns only the other colour's first-stage samples, and places the adaptive samples of its
//! own colour from them. So a pixel's count is a function of other pixels' samples alone, and
//! the plain mean of its own samples (one Owen-scrambled Sobol sequence, so they stay
//! stratified) is unbiased. The decisions are made from the first stage only: learning from
//! later rounds would let a pixel's values reach its own count through the counts of its
//! neighbours (measured on the two-stream design; see docs/rivals.md).

use super::{ClusterSampler, Phase};
use crate::cells::CellView;
use crate::partition::Partition;
use crate::sampler::{alternate, PixelPattern, Sampler, SamplerReport};
use crate::space::SamplePoint;
use std::collections::VecDeque;

impl ClusterSampler {
    /// This sampler as the half of an unbiased pair ([`Crossed`]) that places the
    /// adaptive samples of the pixels of colour `colour` (0 or 1): its budget is theirs.
    pub(super) fn for_colour(mut self, colour: u32) -> Self {
        self.settings.colour = Some(colour);
        self.state.remaining = self.adaptive_budget();
        self
    }

    /// The samples its rounds are to give: what the first stage leaves of the budget of the
    /// pixels it places (those of its colour, in an unbiased pair).
    pub(super) fn adaptive_budget(&self) -> u64 {
        self.own_pixels() * u64::from(self.settings.spp - self.settings.init_spp)
    }

    /// Whether its next call ends its first stage and clusters.
    pub(super) fn about_to_cluster(&self) -> bool {
        self.state.phase == Phase::Init && !self.state.init.cursor().has_next()
    }

    /// The pixels whose adaptive samples it places: all, or those of its colour.
    pub(super) fn own_pixels(&self) -> u64 {
        let pixels = self.space.pixels();
        match self.settings.colour {
            None => pixels,
            Some(0) => pixels.div_ceil(2),
            Some(_) => pixels / 2,
        }
    }
}

/// The pixel (column, row from the space's corner) of colour `colour` nearest `(col, row)`:
/// itself, or its partner in the same row (the column's lowest bit flipped, or the column
/// before at an odd width's last one), or in a one-column space the same in the column.
#[inline]
pub(super) fn own_colour(col: u32, row: u32, colour: u32, width: u32, height: u32) -> (u32, u32) {
    if (col + row) & 1 == colour {
        return (col, row);
    }
    let partner = |v: u32, n: u32| {
        if v ^ 1 < n {
            v ^ 1
        } else {
            v.saturating_sub(1)
        }
    };
    if width > 1 {
        (partner(col, width), row)
    } else {
        (col, partner(row, height))
    }
}

/// Two cluster samplers, one per pixel colour, each placing its colour's samples from the
/// other colour's first stage.
pub struct Crossed {
    halves: [ClusterSampler; 2],
    /// Per batch given and not yet observed, oldest first: which half made it, and whether it
    /// was that half's first stage.
    given: VecDeque<(usize, bool)>,
    /// The half asked next.
    turn: usize,
    /// Halves whose budget is spent.
    done: [bool; 2],
    /// The half that gave the last batch.
    last: Option<usize>,
    /// A half to halt once it has given its next batch (see [`Sampler::halt`]).
    halt_after_next: Option<usize>,
}

impl Crossed {
    /// The pair `halves`, the first placing the pixels of colour 0, the second colour 1 (their
    /// settings' `colour`).
    pub fn new(halves: [ClusterSampler; 2]) -> Self {
        debug_assert_eq!(halves[0].settings.colour, Some(0));
        debug_assert_eq!(halves[1].settings.colour, Some(1));
        Self {
            halves,
            given: VecDeque::new(),
            turn: 0,
            done: [false; 2],
            last: None,
            halt_after_next: None,
        }
    }

    /// The two halves, for the tests.
    #[cfg(test)]
    pub(super) fn halves(&self) -> &[ClusterSampler; 2] {
        &self.halves
    }

    /// The half to ask next: by turns, skipping a half that has nothing more to give and one
    /// about to cluster while the other's first stage is not all observed
    /// (`first_unobserved(other)`), when the other can go instead.
    fn next_half(&self, first_unobserved: impl Fn(usize) -> bool) -> Option<usize> {
        let live = |h: usize| !self.done[h] && self.halves[h].state.phase != Phase::Done;
        // Guided, a half about to cluster also waits for the map, which needs both halves'
        // first stages.
        let waits = |h: usize| {
            let half = &self.halves[h];
            half.about_to_cluster() && (first_unobserved(1 - h) || half.awaits_guide())
        };
        let order = [self.turn, 1 - self.turn];
        order
            .into_iter()
            .find(|&h| live(h) && !waits(h))
            .or_else(|| order.into_iter().find(|&h| live(h)))
    }
}

impl Sampler for Crossed {
    fn name(&self) -> &'static str {
        "cluster"
    }

    fn spp(&self) -> u32 {
        self.halves[0].settings.spp
    }

    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool {
        out.clear();
        // The halves alternate batch by batch; their first stages are alike (every pixel, in
        // the same passes). A half clusters from the other's whole first stage: while the
        // other's last first-stage batch is still being traced, the other goes first (its
        // own clustering reads this half's first stage, observed already). So each clustering
        // is planned while a batch is traced: before, the first half's was made while nothing
        // was (two clusterings of 12 ms each on motion-dof at 8 spp, one thread).
        let unobserved = &self.given;
        let first_unobserved = |g: usize| unobserved.iter().any(|&(h, first)| h == g && first);
        if let Some(h) = self.next_half(first_unobserved) {
            self.turn = h;
        }
        let halves = &mut self.halves;
        let given = alternate(&mut self.turn, &mut self.done, |h| {
            halves[h].next_batch(out)
        });
        let Some(h) = given else {
            return false;
        };
        // The call that ends the first stage clusters and plans the first round: the phase
        // after the call tells which the batch is.
        // (Each half's first stage makes its own colour's pixels' points only.)
        let first_stage = self.halves[h].state.phase == Phase::Init;
        self.given.push_back((h, first_stage));
        self.last = Some(h);
        if self.halt_after_next == Some(h) {
            self.halves[h].halt();
            self.halt_after_next = None;
        }
        true
    }

    fn observe(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        let Some((h, first_stage)) = self.given.pop_front() else {
            return;
        };
        if first_stage {
            self.halves[1 - h].observe_other(batch, radiance);
        }
        // Its own points' values are never learnt: only the counts it spent move its queue.
        self.halves[h].retire(batch);
    }

    fn halt(&mut self) {
        // The halves' batches pair up (the first's, then the second's over the same pixels).
        // When the first has given a batch whose mate is still to come, the second halts after
        // giving it, so that both end the same pass and every pixel has as many samples.
        if self.last == Some(0) && !self.done[1] {
            self.halves[0].halt();
            self.halt_after_next = Some(1);
        } else {
            for h in &mut self.halves {
                h.halt();
            }
        }
    }

    fn stop_at_noise(&mut self, threshold: f64, min_spp: u32) -> bool {
        // Each half's first stage shrinks as one sampler's does; settling reads its own cells,
        // which hold the other colour's first stage alone.
        for h in &mut self.halves {
            h.settle_at_noise(threshold, min_spp);
        }
        true
    }

    fn plan_for(&mut self, spp: u32) -> bool {
        // Both halves' first stages end at the same pass: the later of the two's floors.
        let floor = self.halves[0].init_floor().max(self.halves[1].init_floor());
        for h in &mut self.halves {
            h.plan_budget(spp, floor);
        }
        true
    }

    fn wants_guidance(&self) -> bool {
        // Once both first stages are in the film.
        self.given.is_empty() && self.halves.iter().all(ClusterSampler::awaits_guide)
    }

    fn guide(&mut self, error: &crate::sampler::ErrorMap) {
        for h in &mut self.halves {
            h.take_guide(error);
        }
    }

    fn plans_ahead(&self) -> bool {
        if self.halves.iter().any(ClusterSampler::awaits_guide) {
            return false;
        }
        // Asked ahead, the batch traced meanwhile is the only one unobserved at the call.
        let traced = self.given.back().copied();
        let first_unobserved = |g: usize| traced == Some((g, true));
        self.next_half(first_unobserved).is_some_and(|h| {
            let half = &self.halves[h];
            half.plans_ahead() || half.about_to_cluster()
        })
    }

    fn partition(&self) -> Option<&Partition> {
        self.halves[0].partition()
    }

    fn cells(&self) -> Option<CellView<'_>> {
        // Each half holds the other colour's first stage only: the film collects the cells.
        None
    }

    fn report(&self) -> SamplerReport {
        SamplerReport::combined(self.halves[0].report(), self.halves[1].report())
    }
}

#[cfg(test)]
mod tests {
    use super::own_colour;

    #[test]
    fn every_pixel_has_a_partner_of_the_other_colour_beside_it() {
        for (w, h) in [(1, 2), (1, 5), (2, 1), (3, 3), (4, 3), (7, 2)] {
            for row in 0..h {
                for col in 0..w {
                    for colour in 0..2 {
                        let (c, r) = own_colour(col, row, colour, w, h);
                        assert_eq!((c + r) & 1, colour, "{w}x{h} ({col}, {row})");
                        assert!(c < w && r < h);
                        assert!(c.abs_diff(col) + r.abs_diff(row) <= 1);
                    }
                }
            }
        }
    }
}
