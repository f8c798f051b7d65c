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
use crate::cluster::build::initial_clustering;
use crate::cluster::clusters::UNASSIGNED;
use crate::cluster::features::Squashed;
use crate::cluster::grid::MAX_DIMS;
use crate::cluster::queue::{BucketQueue, Queued};
use crate::cluster::{CellGrid, CellSums, CellView, Clustering, FeatureScale};
use crate::partition::Partition;
use crate::space::{RenderingSpace, SamplePoint};
use rayon::prelude::*;

mod crossed;
mod draw;
mod noise;
mod plan;
mod update;
use update::{CellUpdate, Change};
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

/// Where the sampler is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Init,
    Adaptive,
    Done,
}

/// A planned round, until it is observed.
#[derive(Default)]
struct Round {
    /// How many points it has.
    points: usize,
    /// Its points' cells and in-cell offsets, in batch order: kept only by a sampler that
    /// learns its own rounds' values (see [`ClusterSampler::learns_own_rounds`]).
    cells: Vec<(u32, [f32; MAX_DIMS])>,
    /// The queue entries of the clusters it sampled, as picked, in order.
    picked: Vec<Queued>,
    /// Room for their ids, which the update after the round lists (reused).
    ids: Vec<u32>,
}

impl Round {
    /// The ids of the clusters it sampled, in the order picked, in its reused buffer.
    fn picked_ids(&mut self) -> Vec<u32> {
        let mut ids = std::mem::take(&mut self.ids);
        ids.clear();
        ids.extend(self.picked.iter().map(|e| e.id));
        ids
    }
}

/// The adaptive cluster sampler.
pub struct ClusterSampler {
    settings: ClusterSettings,
    seed: u64,
    space: RenderingSpace,
    phase: Phase,
    halted: bool,
    init: SobolSampler,
    grid: CellGrid,
    sums: CellSums,
    levels: Vec<f32>,
    /// The squashed (g, s, level) each cell's current feature was made with (its level may
    /// have moved since).
    squashed: Vec<Squashed>,
    scale: Option<FeatureScale>,
    clustering: Option<Clustering>,
    /// Samples given to each pixel so far: the next sample's index there.
    pixel_count: Vec<u32>,
    /// Adaptive samples still to give.
    remaining: u64,
    /// Adaptive samples given so far.
    given_adaptive: u64,
    queue: BucketQueue,
    version: Vec<u32>,
    /// The cell and in-cell offsets of each point of the round being planned (or of the
    /// first stage's batch being observed), in batch order.
    round_cells: Vec<(u32, [f32; MAX_DIMS])>,
    /// Rounds planned and not yet observed, oldest first: their points' cells and clusters.
    in_flight: std::collections::VecDeque<Round>,
    /// Observed rounds' buffers, for reuse.
    spare: Vec<Round>,
    /// The pixel (row << 32 | column, from the space's corner) of each point drawn in a
    /// round, in draw order (reused).
    drawn: Vec<u64>,
    /// A bit per cell: whether it got samples since the last update.
    touched: Vec<u64>,
    /// A bit per cluster, clear between updates: the update's scratch for listing each
    /// changed cluster once.
    cluster_marks: Vec<u64>,
    /// Cells without samples, as of the last update (their levels follow their neighbours').
    empty_cells: usize,
    /// The update's buffers, kept from round to round: fresh ones cost page faults.
    dirty: Vec<u32>,
    cell_updates: Vec<CellUpdate>,
    changes: Vec<Change>,
    /// The sample counts of the clusters a round picked (reused; see `requeue_picked`).
    counts: Vec<u64>,
    rounds: u64,
    partition: Option<Partition>,
    /// With `--noise-threshold`: the threshold, and the samples each cell of a cluster needs
    /// before the cluster may settle.
    noise: Option<(f64, u32)>,
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
        Self {
            init: SobolSampler::new(space, settings.init_spp, seed ^ SALT)
                .with_stream(settings.stream),
            // The whole image's until `for_colour` says otherwise.
            remaining: pixels * u64::from(settings.spp - settings.init_spp),
            given_adaptive: 0,
            settings,
            seed,
            space,
            phase: Phase::Init,
            halted: false,
            grid,
            sums,
            levels: Vec::new(),
            squashed: Vec::new(),
            scale: None,
            clustering: None,
            pixel_count: vec![0; pixels as usize],
            queue: BucketQueue::new(),
            version: Vec::new(),
            round_cells: Vec::new(),
            in_flight: Default::default(),
            spare: Vec::new(),
            drawn: Vec::new(),
            touched: vec![0; cells.div_ceil(64)],
            cluster_marks: Vec::new(),
            empty_cells: cells,
            dirty: Vec::new(),
            cell_updates: Vec::new(),
            changes: Vec::new(),
            counts: Vec::new(),
            rounds: 0,
            partition: None,
            noise: None,
        }
    }

    /// The settings in force (after `minspp` raised `initspp` where needed).
    pub fn settings(&self) -> &ClusterSettings {
        &self.settings
    }

    /// The cell grid.
    pub fn grid(&self) -> &CellGrid {
        &self.grid
    }

    /// The cells' running sums.
    pub fn sums(&self) -> &CellSums {
        &self.sums
    }

    /// The clustering, once the first stage is done.
    pub fn clustering(&self) -> Option<&Clustering> {
        self.clustering.as_ref()
    }

    /// Bytes held by the sampler's per-cell and per-pixel state.
    pub fn bytes(&self) -> usize {
        self.sums.bytes()
            + self.levels.capacity() * 4
            + self.squashed.capacity() * std::mem::size_of::<Squashed>()
            + self.touched.capacity() * 8
            + self.pixel_count.capacity() * 4
            + self.clustering.as_ref().map_or(0, Clustering::bytes)
            + self.queue.bytes()
    }

    /// The sampling priority of a queued cluster.
    fn priority(&self, e: &Queued) -> f64 {
        match self.settings.priority {
            Priority::Paper => e.weight,
            Priority::PerSample => e.weight / e.samples.max(1) as f64,
        }
    }

    /// The queue entry of cluster `id` as it stands, with its priority; none for a dead one.
    fn entry(&self, id: u32) -> Option<(f64, Queued)> {
        let clustering = self.clustering.as_ref().expect("clustered");
        let c = &clustering.clusters[id as usize];
        if c.cells.is_empty() {
            return None;
        }
        let weight = match self.settings.priority {
            Priority::Paper => c.err(),
            Priority::PerSample => {
                // A cluster of cells that agree has err 0 however noisy or curved they are:
                // its mean gradient and variance features count too.
                let mean = c.mean();
                let err = c.err() + mean[0].abs() + mean[1].abs() + clustering.rule.tolerance;
                err * c.cells.len() as f64
            }
        };
        let e = Queued {
            id,
            version: self.version[id as usize],
            cells: c.cells.len() as u32,
            samples: c.samples,
            weight,
        };
        Some((self.priority(&e), e))
    }

    /// Queues the clusters `ids` in the order given.
    fn push_all(&mut self, ids: impl IntoIterator<Item = u32>) {
        for id in ids {
            if let Some((priority, e)) = self.entry(id) {
                self.queue.push(priority, e);
            }
        }
    }

    /// Ends the first stage: every cell's level and features, their scales, the clusters.
    fn cluster(&mut self) {
        let initial = initial_clustering(&self.grid, &self.sums, &self.settings.cluster_params());
        self.squashed = initial.squashed;
        self.levels = initial.levels;
        self.scale = Some(initial.scale);
        let clustering = initial.clustering;
        self.version = vec![0; clustering.clusters.len()];
        self.clustering = Some(clustering);
        self.push_all(0..self.version.len() as u32);
    }

    /// Plans the next round into `out`: clusters by priority, a few samples each, until the
    /// round holds its share of what is left.
    fn plan_round(&mut self, out: &mut Vec<SamplePoint>) {
        let target = (self.remaining / 16)
            .clamp(MIN_ROUND, BATCH_SAMPLES)
            .min(self.remaining);
        let Round {
            cells,
            mut picked,
            ids,
            ..
        } = self.spare.pop().unwrap_or_default();
        picked.clear();
        self.round_cells = cells;
        let mut picks: Vec<(u32, u64)> = Vec::new();
        let mut planned_total = 0;
        let mut deferred = Vec::new();
        while planned_total < target {
            let Some(mut top) = self.queue.pop() else {
                if deferred.is_empty() {
                    break;
                }
                for (priority, e) in deferred.drain(..) {
                    self.queue.push(priority, e);
                }
                continue;
            };
            // A live entry's cluster has cells: a cluster that loses its last one changes
            // version.
            if self.version[top.id as usize] != top.version {
                continue;
            }
            // A settled cluster leaves the queue; a move into or out of it queues it again.
            let settled = |(t, least)| self.relative_error(top.id, least) < t;
            if self.settings.settle && self.noise.is_some_and(settled) {
                continue;
            }
            let k = u64::from(top.cells)
                .clamp(CLUSTER_SAMPLES.0, CLUSTER_SAMPLES.1)
                .min(target - planned_total);
            picks.push((top.id, k));
            picked.push(top);
            planned_total += k;
            top.samples += k;
            let priority = self.priority(&top);
            match self.settings.priority {
                Priority::PerSample => self.queue.push(priority, top),
                // The paper's rule takes each cluster once per round, by largest error.
                Priority::Paper => deferred.push((priority, top)),
            }
        }
        for (priority, e) in deferred {
            self.queue.push(priority, e);
        }

        // Every planned sample is spent, whether or not it comes back valid.
        let clustering = self.clustering.as_mut().expect("clustered");
        for &(id, k) in &picks {
            clustering.spend(id, k);
        }
        if self.settings.even_pixels {
            self.draw_pixels(&picks, out);
            let (init, grid) = (&self.init, &self.grid);
            let seed = init.seed();
            let stream = self.settings.stream;
            // The pixel's next point of its sequence, labelled with the stream's index.
            let make = |q: &mut SamplePoint| {
                let local = q.index;
                *q = init.point(q.pixel, local, Scramble::of(q.pixel, seed));
                q.index = stream.index(local);
            };
            self.round_cells.clear();
            if self.learns_own_rounds() {
                self.round_cells.resize(out.len(), (0, [0.0; MAX_DIMS]));
                out.par_iter_mut()
                    .zip(self.round_cells.par_iter_mut())
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
            let mut rng = Pcg32::new(mix64(self.seed ^ SALT), self.rounds);
            self.draw_cells(&picks, &mut rng, out);
        }
        self.in_flight.push_back(Round {
            points: out.len(),
            cells: std::mem::take(&mut self.round_cells),
            picked,
            ids,
        });
        self.remaining -= planned_total;
        self.given_adaptive += planned_total;
        self.rounds += 1;
    }

    /// Whether its own rounds' values come back to it ([`Sampler::observe`]): not for a half
    /// of an unbiased pair or a stream of a paired sampler, whose values go to the other.
    fn learns_own_rounds(&self) -> bool {
        self.settings.colour.is_none() && self.settings.stream == super::IndexStream::ALL
    }

    /// The final partition in image space: each pixel takes the cluster of most of the cells
    /// at its centre (ties to the lower id), ids renumbered in order of first appearance.
    fn make_partition(&self) -> Option<Partition> {
        let clustering = self.clustering.as_ref()?;
        let (w, h) = (self.space.width(), self.space.height());
        let inner = self.grid.cells_per_image_cell();
        let mut renumber = vec![UNASSIGNED; clustering.clusters.len()];
        let mut next = 0;
        let mut cluster = Vec::with_capacity(w as usize * h as usize);
        let mut votes: Vec<u32> = Vec::with_capacity(inner);
        for py in 0..h {
            for px in 0..w {
                let (cx, cy) = self.grid.image_cell_of_pixel(px, py);
                let mut c = [0; MAX_DIMS];
                c[0] = cx;
                c[1] = cy;
                let first = self.grid.index(&c);
                votes.clear();
                votes.extend((first..first + inner).map(|i| clustering.of_cell[i]));
                votes.sort_unstable();
                let mut best = (0, votes[0]);
                let mut run = 0;
                for (k, &v) in votes.iter().enumerate() {
                    run = if k > 0 && votes[k - 1] == v {
                        run + 1
                    } else {
                        1
                    };
                    if run > best.0 {
                        best = (run, v);
                    }
                }
                let id = &mut renumber[best.1 as usize];
                if *id == UNASSIGNED {
                    *id = next;
                    next += 1;
                }
                cluster.push(*id);
            }
        }
        Some(Partition {
            width: w,
            height: h,
            cluster,
        })
    }

    fn finish(&mut self) {
        self.phase = Phase::Done;
        // Made once the rounds still in flight are observed.
        if self.partition.is_none() && self.in_flight.is_empty() {
            self.partition = self.make_partition();
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
        if self.phase == Phase::Init {
            // Half of an unbiased pair: the first stage of its own colour's pixels only (the
            // other half makes the other's).
            let (x0, y0) = (self.space.x0, self.space.y0);
            let given = match self.settings.colour {
                Some(c) => {
                    next_batch_where(&mut self.init, out, |p| (p[0] - x0 + p[1] - y0) & 1 == c)
                }
                None => self.init.next_batch(out),
            };
            if given {
                for q in out.iter() {
                    let p = self.space.index_of(q.pixel);
                    self.pixel_count[p] += 1;
                }
                return true;
            }
            if self.space.pixels() == 0 {
                self.phase = Phase::Done;
                return false;
            }
            self.cluster();
            self.phase = if self.halted {
                Phase::Done
            } else {
                Phase::Adaptive
            };
        }
        if self.phase == Phase::Adaptive && !self.halted && self.remaining > 0 {
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
        let round = match self.in_flight.front() {
            Some(r) if r.points == batch.len() => self.in_flight.pop_front(),
            _ => None,
        };
        let Some(mut round) = round else {
            self.grid.locate_all(batch, &mut self.round_cells);
            self.sums.add_batch(&self.round_cells, radiance, None);
            return;
        };
        // NaN marks a dropped sample: it was spent (when planned) but tells nothing.
        self.sums.add_batch(&round.cells, radiance, None);
        for (&(cell, _), l) in round.cells.iter().zip(radiance) {
            if !l[0].is_nan() {
                self.touched[cell as usize / 64] |= 1 << (cell % 64);
            }
        }
        // A round is one batch: update now.
        let ids = round.picked_ids();
        round.ids = self.update(ids);
        self.spare.push(round);
        if self.phase == Phase::Done {
            self.finish();
        }
    }

    fn observe_other(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        // The other stream's points: their cells found here, their values learnt as this
        // sampler's own would be.
        let mut cells = std::mem::take(&mut self.round_cells);
        self.grid.locate_all(batch, &mut cells);
        self.sums.add_batch(&cells, radiance, None);
        if self.clustering.is_some() {
            for (&(cell, _), l) in cells.iter().zip(radiance) {
                if !l[0].is_nan() {
                    self.touched[cell as usize / 64] |= 1 << (cell % 64);
                }
            }
            self.update(Vec::new());
        }
        self.round_cells = cells;
    }

    fn retire(&mut self, batch: &[SamplePoint]) {
        // Its own round, traced for the other stream: only the clusters it sampled are queued
        // again with their new sample counts.
        let round = match self.in_flight.front() {
            Some(r) if r.points == batch.len() => self.in_flight.pop_front(),
            _ => None,
        };
        if let Some(mut round) = round {
            let ids = round.picked_ids();
            round.ids = if self.settings.colour.is_some() {
                // A half of an unbiased pair learns nothing after its first stage.
                self.requeue_picked(&mut round.picked, ids)
            } else {
                self.update(ids)
            };
            self.spare.push(round);
        }
        if self.phase == Phase::Done {
            self.finish();
        }
    }

    fn halt(&mut self) {
        self.halted = true;
        self.init.halt();
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

    fn plans_ahead(&self) -> bool {
        match self.phase {
            // The first stage's points depend on nothing observed, but the call after its
            // last batch makes the first clustering, which needs every batch observed.
            Phase::Init => self.init.cursor().has_next(),
            Phase::Adaptive => true,
            Phase::Done => false,
        }
    }

    fn partition(&self) -> Option<&Partition> {
        self.partition.as_ref()
    }

    fn cells(&self) -> Option<CellView<'_>> {
        self.settings.keep_radiance.then_some(CellView {
            grid: &self.grid,
            sums: &self.sums,
            clustering: self.clustering.as_ref(),
        })
    }

    fn keeps_cells(&self) -> bool {
        self.settings.keep_radiance
    }

    fn report(&self) -> SamplerReport {
        SamplerReport {
            clusters: self.clustering.as_ref().map(|c| c.live() as u64),
            cells: Some(self.grid.len() as u64),
            rounds: Some(self.rounds),
        }
    }
}

#[cfg(test)]
mod tests;
