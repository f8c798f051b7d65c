//! `cluster`: the paper's adaptive sampler (docs/algorithm.md §1 to §4). It samples every
//! pixel `initspp` times (Owen-scrambled Sobol, stratified in every dim), groups the cells of
//! the rendering space into clusters by their features, then spends the rest of the budget in
//! rounds: the clusters of highest priority get a few samples each, spread over their cells;
//! the cells that received samples and their neighbours get new features, and cells that no
//! longer fit their cluster move (the paper's table 1). Every decision is made on one thread
//! in a fixed order, and the parallel parts compute pure functions of the cells, so the points
//! and the image do not depend on the thread count.

use super::sobol::Scramble;
use super::{
    mix64, next_batch_where, Pcg32, PixelPattern, Sampler, SamplerReport, SobolSampler,
    BATCH_SAMPLES,
};
use crate::cells::build::initial_clustering;
use crate::cells::grid::MAX_DIMS;
use crate::cells::queue::BucketQueue;
use crate::cells::{CellGrid, CellSums, CellView, Clustering};
use crate::partition::Partition;
use crate::space::{RenderingSpace, SamplePoint};
use rayon::prelude::*;

mod crossed;
mod draw;
mod guided;
mod noise;
mod plan;
mod scratch;
mod state;
mod update;
use scratch::Scratch;
use state::{Phase, Round, State};
mod settings;
#[cfg(test)]
use settings::build;
pub(super) use settings::ENTRY;
pub use settings::{ClusterSettings, Priority};

/// Salt of this sampler's random streams.
const SALT: u64 = 0x636c_7573;

/// Fewest and most samples a chosen cluster gets at a time (the paper's "4-16").
const CLUSTER_SAMPLES: (u64, u64) = (4, 16);

/// Smallest round, in samples: enough to keep every thread busy.
const MIN_ROUND: u64 = 4096;

/// The adaptive cluster sampler: its settings, the state it carries from call to call
/// (`state::State`) and the buffers it reuses from round to round (`scratch::Scratch`).
pub struct ClusterSampler {
    /// The settings in force.
    settings: ClusterSettings,
    /// The seed every random decision is drawn from.
    seed: u64,
    /// The rendering space it samples.
    space: RenderingSpace,
    /// Where it is, what it has learnt, what it has given.
    state: State,
    /// Buffers reused between rounds.
    scratch: Scratch,
}

impl ClusterSampler {
    /// A sampler over `space` with `settings`, every random decision drawn from `seed`.
    pub fn new(space: RenderingSpace, settings: ClusterSettings, seed: u64) -> Self {
        let mut settings = settings;
        settings.spp = settings.spp.max(1);
        settings.init_spp = settings
            .init_spp
            .max(settings.min_spp)
            .clamp(1, settings.spp);
        let grid = CellGrid::new(space, settings.cell_size, settings.bins);
        let sums = if settings.keep_radiance {
            CellSums::new(&grid)
        } else {
            CellSums::luminance_only(&grid)
        };
        let cells = grid.len();
        let pixels = space.pixels();
        let state = State {
            phase: Phase::Init,
            halted: false,
            init: SobolSampler::new(space, settings.init_spp, seed ^ SALT)
                .with_stream(settings.stream),
            grid,
            sums,
            levels: Vec::new(),
            squashed: Vec::new(),
            scale: None,
            clustering: None,
            pixel_count: vec![0; pixels as usize],
            // The whole image's until `for_colour` says otherwise.
            remaining: pixels * u64::from(settings.spp - settings.init_spp),
            given_adaptive: 0,
            queue: BucketQueue::new(),
            version: Vec::new(),
            in_flight: Default::default(),
            empty_cells: cells,
            rounds: 0,
            partition: None,
            noise: None,
            guide: None,
            cell_error: Vec::new(),
            first_per_cell: 0.0,
        };
        Self {
            settings,
            seed,
            space,
            state,
            scratch: Scratch::new(cells),
        }
    }

    /// The settings in force (after `minspp` raised `initspp` where needed).
    pub fn settings(&self) -> &ClusterSettings {
        &self.settings
    }

    /// The cell grid.
    pub fn grid(&self) -> &CellGrid {
        &self.state.grid
    }

    /// The cells' running sums.
    pub fn sums(&self) -> &CellSums {
        &self.state.sums
    }

    /// The clustering, once the first stage is done.
    pub fn clustering(&self) -> Option<&Clustering> {
        self.state.clustering.as_ref()
    }

    /// Bytes held by the sampler's per-cell and per-pixel state.
    pub fn bytes(&self) -> usize {
        self.state.bytes() + self.scratch.bytes()
    }

    /// Ends the first stage: every cell's level and features, their scales, the clusters.
    fn cluster(&mut self) {
        let initial = initial_clustering(
            &self.state.grid,
            &self.state.sums,
            &self.settings.cluster_params(),
        );
        self.state.squashed = initial.squashed;
        self.state.levels = initial.levels;
        self.state.scale = Some(initial.scale);
        let clustering = initial.clustering;
        self.state.version = vec![0; clustering.clusters.len()];
        self.state.clustering = Some(clustering);
        self.weigh_by_guide();
        let n = self.state.version.len() as u32;
        self.state.push_all(self.settings.priority, 0..n);
    }

    /// Plans the next round into `out`: clusters by priority, a few samples each, until the
    /// round holds its share of what is left.
    fn plan_round(&mut self, out: &mut Vec<SamplePoint>) {
        let mut target = (self.state.remaining / 16)
            .clamp(MIN_ROUND, BATCH_SAMPLES)
            .min(self.state.remaining);
        // Guided, samples go in pairs.
        let pairs = self.settings.guided;
        if pairs {
            target &= !1;
        }
        let Round {
            cells,
            mut picked,
            ids,
            ..
        } = self.scratch.spare.pop().unwrap_or_default();
        picked.clear();
        self.scratch.round_cells = cells;
        let mut picks: Vec<(u32, u64)> = Vec::new();
        let mut planned_total = 0;
        let mut deferred = Vec::new();
        while planned_total < target {
            let Some(mut top) = self.state.queue.pop() else {
                if deferred.is_empty() {
                    break;
                }
                for (priority, e) in deferred.drain(..) {
                    self.state.queue.push(priority, e);
                }
                continue;
            };
            // A live entry's cluster has cells: a cluster that loses its last one changes
            // version.
            if self.state.version[top.id as usize] != top.version {
                continue;
            }
            // A settled cluster leaves the queue; a move into or out of it queues it again.
            let settled = |(t, least)| self.state.relative_error(top.id, least) < t;
            if self.settings.settle && self.state.noise.is_some_and(settled) {
                continue;
            }
            let mut k = u64::from(top.cells)
                .clamp(CLUSTER_SAMPLES.0, CLUSTER_SAMPLES.1)
                .min(target - planned_total);
            if pairs {
                k &= !1;
            }
            picks.push((top.id, k));
            picked.push(top);
            planned_total += k;
            top.samples += k;
            let priority = state::priority(self.settings.priority, &top);
            match self.settings.priority {
                Priority::PerSample | Priority::Guided => self.state.queue.push(priority, top),
                // The paper's rule takes each cluster once per round, by largest error.
                Priority::Paper => deferred.push((priority, top)),
            }
        }
        for (priority, e) in deferred {
            self.state.queue.push(priority, e);
        }

        // Every planned sample is spent, whether or not it comes back valid.
        let clustering = self.state.clustering.as_mut().expect("clustered");
        for &(id, k) in &picks {
            clustering.spend(id, k);
        }
        if self.settings.even_pixels {
            self.draw_pixels(&picks, out);
            let (init, grid) = (&self.state.init, &self.state.grid);
            let seed = init.seed();
            let stream = self.settings.stream;
            // The pixel's next point of its sequence, labelled with the stream's index.
            let make = |q: &mut SamplePoint| {
                let local = q.index;
                *q = init.point(q.pixel, local, Scramble::of(q.pixel, seed));
                q.index = stream.index(local);
            };
            self.scratch.round_cells.clear();
            if self.learns_own_rounds() {
                self.scratch
                    .round_cells
                    .resize(out.len(), (0, [0.0; MAX_DIMS]));
                out.par_iter_mut()
                    .zip(self.scratch.round_cells.par_iter_mut())
                    .with_min_len(256)
                    .for_each(|(q, slot)| {
                        make(q);
                        let (cell, off) = grid.locate(q);
                        *slot = (cell as u32, off);
                    });
            } else {
                out.par_iter_mut().with_min_len(256).for_each(make);
            }
        } else {
            let mut rng = Pcg32::new(mix64(self.seed ^ SALT), self.state.rounds);
            self.draw_cells(&picks, &mut rng, out);
        }
        self.state.in_flight.push_back(Round {
            points: out.len(),
            cells: std::mem::take(&mut self.scratch.round_cells),
            picked,
            ids,
        });
        self.state.remaining -= planned_total;
        self.state.given_adaptive += planned_total;
        self.state.rounds += 1;
    }

    /// Whether its own rounds' values come back to it ([`Sampler::observe`]): not for a half
    /// of an unbiased pair or a stream of a paired sampler, whose values go to the other.
    fn learns_own_rounds(&self) -> bool {
        self.settings.colour.is_none() && self.settings.stream == super::IndexStream::ALL
    }

    fn finish(&mut self) {
        self.state.phase = Phase::Done;
        // Made once the rounds still in flight are observed.
        if self.state.partition.is_none() && self.state.in_flight.is_empty() {
            self.state.partition = self.state.make_partition(&self.space);
        }
    }
}

impl Sampler for ClusterSampler {
    fn name(&self) -> &'static str {
        "cluster"
    }

    fn spp(&self) -> u32 {
        self.settings.spp
    }

    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool {
        out.clear();
        if self.state.phase == Phase::Init {
            // Half of an unbiased pair: the first stage of its own colour's pixels only (the
            // other half makes the other's).
            let (x0, y0) = (self.space.x0, self.space.y0);
            let given = match self.settings.colour {
                Some(c) => next_batch_where(&mut self.state.init, out, |p| {
                    (p[0] - x0 + p[1] - y0) & 1 == c
                }),
                None => self.state.init.next_batch(out),
            };
            if given {
                for q in out.iter() {
                    let p = self.space.index_of(q.pixel);
                    self.state.pixel_count[p] += 1;
                }
                return true;
            }
            if self.space.pixels() == 0 {
                self.state.phase = Phase::Done;
                return false;
            }
            self.cluster();
            self.state.phase = if self.state.halted {
                Phase::Done
            } else {
                Phase::Adaptive
            };
        }
        if self.state.phase == Phase::Adaptive && !self.state.halted && self.state.remaining > 0 {
            self.plan_round(out);
            if !out.is_empty() {
                return true;
            }
        }
        self.finish();
        false
    }

    fn observe(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        // An adaptive point's cell is known from when it was made; the first stage's are
        // found here, in parallel.
        let round = match self.state.in_flight.front() {
            Some(r) if r.points == batch.len() => self.state.in_flight.pop_front(),
            _ => None,
        };
        let Some(mut round) = round else {
            self.state
                .grid
                .locate_all(batch, &mut self.scratch.round_cells);
            self.state
                .sums
                .add_batch(&self.scratch.round_cells, radiance, None);
            return;
        };
        // NaN marks a dropped sample: it was spent (when planned) but tells nothing.
        self.state.sums.add_batch(&round.cells, radiance, None);
        for (&(cell, _), l) in round.cells.iter().zip(radiance) {
            if !l[0].is_nan() {
                self.scratch.touched[cell as usize / 64] |= 1 << (cell % 64);
            }
        }
        // A round is one batch: update now.
        let ids = round.picked_ids();
        round.ids = self
            .state
            .update(&mut self.scratch, self.settings.priority, ids);
        self.scratch.spare.push(round);
        if self.state.phase == Phase::Done {
            self.finish();
        }
    }

    fn observe_other(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        // The other stream's points: their cells found here, their values learnt as this
        // sampler's own would be.
        let mut cells = std::mem::take(&mut self.scratch.round_cells);
        self.state.grid.locate_all(batch, &mut cells);
        self.state.sums.add_batch(&cells, radiance, None);
        if self.state.clustering.is_some() {
            for (&(cell, _), l) in cells.iter().zip(radiance) {
                if !l[0].is_nan() {
                    self.scratch.touched[cell as usize / 64] |= 1 << (cell % 64);
                }
            }
            let rule = self.settings.priority;
            self.state.update(&mut self.scratch, rule, Vec::new());
        }
        self.scratch.round_cells = cells;
    }

    fn retire(&mut self, batch: &[SamplePoint]) {
        // Its own round, traced for the other stream: only the clusters it sampled are queued
        // again with their new sample counts.
        let round = match self.state.in_flight.front() {
            Some(r) if r.points == batch.len() => self.state.in_flight.pop_front(),
            _ => None,
        };
        if let Some(mut round) = round {
            let ids = round.picked_ids();
            round.ids = if self.settings.colour.is_some() {
                // A half of an unbiased pair learns nothing after its first stage.
                let rule = self.settings.priority;
                self.state
                    .requeue_picked(&mut self.scratch, rule, &mut round.picked, ids)
            } else {
                self.state
                    .update(&mut self.scratch, self.settings.priority, ids)
            };
            self.scratch.spare.push(round);
        }
        if self.state.phase == Phase::Done {
            self.finish();
        }
    }

    fn halt(&mut self) {
        self.state.halted = true;
        self.state.init.halt();
    }

    fn stop_at_noise(&mut self, threshold: f64, min_spp: u32) -> bool {
        self.settle_at_noise(threshold, min_spp);
        true
    }

    fn plan_for(&mut self, spp: u32) -> bool {
        let floor = self.init_floor();
        self.plan_budget(spp, floor);
        true
    }

    fn wants_guidance(&self) -> bool {
        self.awaits_guide()
    }

    fn guide(&mut self, error: &crate::sampler::ErrorMap) {
        self.take_guide(error);
    }

    fn plans_ahead(&self) -> bool {
        match self.state.phase {
            // The first stage's points depend on nothing observed, but the call after its
            // last batch makes the first clustering, which needs every batch observed.
            Phase::Init => self.state.init.cursor().has_next(),
            Phase::Adaptive => true,
            Phase::Done => false,
        }
    }

    fn partition(&self) -> Option<&Partition> {
        self.state.partition.as_ref()
    }

    fn cells(&self) -> Option<CellView<'_>> {
        self.settings.keep_radiance.then_some(CellView {
            grid: &self.state.grid,
            sums: &self.state.sums,
            clustering: self.state.clustering.as_ref(),
        })
    }

    fn keeps_cells(&self) -> bool {
        self.settings.keep_radiance
    }

    fn report(&self) -> SamplerReport {
        SamplerReport {
            clusters: self.state.clustering.as_ref().map(|c| c.live() as u64),
            cells: Some(self.state.grid.len() as u64),
            rounds: Some(self.state.rounds),
        }
    }
}

#[cfg(test)]
mod tests;
