//! The cluster sampler without selection bias (`unbiased`, issue 26, item 3). A pixel whose
//! count is decided from its own samples is biased: where the rare outcome is the bright one,
//! a pixel whose first samples agree looks settled and keeps its dark estimate. Here the
//! pixels are coloured as a checkerboard and two instances of the sampler share the work: each
//! learns only the other colour's first-stage samples, and places the adaptive samples of its
//! own colour from them. So a pixel's count is a function of other pixels' samples alone, and
//! the plain mean of its own samples (one Owen-scrambled Sobol sequence, so they stay
//! stratified) is unbiased. The decisions are made from the first stage only: learning from
//! later rounds would let a pixel's values reach its own count through the counts of its
//! neighbours (measured on the two-stream design; see the README).

use super::{ClusterSampler, Phase};
use crate::cluster::CellView;
use crate::partition::Partition;
use crate::sampler::{Sampler, SamplerReport};
use crate::space::SamplePoint;
use std::collections::VecDeque;

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
        }
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
        // The halves alternate batch by batch. Their first stages are alike (every pixel, in
        // the same passes), so each has handed over its last first-stage batch, and had the
        // other's observed, before it clusters.
        for _ in 0..2 {
            let h = self.turn;
            self.turn = 1 - h;
            if self.done[h] {
                continue;
            }
            if self.halves[h].next_batch(out) {
                // The call that ends the first stage clusters and plans the first round: the
                // phase after the call tells which the batch is.
                let first_stage = self.halves[h].phase == Phase::Init;
                if first_stage {
                    // Each half's first stage covers every pixel; it keeps its own colour's.
                    let (x0, y0) = (self.halves[h].space.x0, self.halves[h].space.y0);
                    let colour = h as u32;
                    out.retain(|q| (q.pixel[0] - x0 + q.pixel[1] - y0) & 1 == colour);
                }
                self.given.push_back((h, first_stage));
                return true;
            }
            self.done[h] = true;
        }
        false
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
        for h in &mut self.halves {
            h.halt();
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

    fn plans_ahead(&self) -> bool {
        (0..2)
            .filter(|&h| !self.done[h])
            .all(|h| self.halves[h].plans_ahead())
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
