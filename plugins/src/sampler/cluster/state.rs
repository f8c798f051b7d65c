//! What the cluster sampler carries from call to call: where it is, what it has learnt of the
//! cells and their clusters, the queue of clusters by priority, and what it has given. Its
//! settings are [`super::ClusterSettings`]; the buffers it only reuses are
//! [`super::scratch::Scratch`].

use super::Priority;
use crate::cells::cell_features::Squashed;
use crate::cells::clusters::UNASSIGNED;
use crate::cells::grid::MAX_DIMS;
use crate::cells::queue::{BucketQueue, Queued};
use crate::cells::{CellGrid, CellSums, Clustering, FeatureScale};
use crate::film::relative_error_of;
use crate::partition::Partition;
use crate::sampler::{ErrorMap, SobolSampler};
use crate::space::RenderingSpace;
use std::collections::VecDeque;

/// Where the sampler is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Phase {
    /// The first stage: every pixel `initspp` times.
    Init,
    /// The rounds, cluster by priority.
    Adaptive,
    /// Nothing more to give.
    Done,
}

/// A planned round, until it is observed.
#[derive(Default)]
pub(super) struct Round {
    /// How many points it has.
    pub points: usize,
    /// Its points' cells and in-cell offsets, in batch order: kept only by a sampler that
    /// learns its own rounds' values (see `ClusterSampler::learns_own_rounds`).
    pub cells: Vec<(u32, [f32; MAX_DIMS])>,
    /// The queue entries of the clusters it sampled, as picked, in order.
    pub picked: Vec<Queued>,
    /// Room for their ids, which the update after the round lists (reused).
    pub ids: Vec<u32>,
}

impl Round {
    /// The ids of the clusters it sampled, in the order picked, in its reused buffer.
    pub fn picked_ids(&mut self) -> Vec<u32> {
        let mut ids = std::mem::take(&mut self.ids);
        ids.clear();
        ids.extend(self.picked.iter().map(|e| e.id));
        ids
    }
}

/// The sampler's state: everything a later call reads of an earlier one.
pub(super) struct State {
    /// Where the sampler is.
    pub phase: Phase,
    /// Whether the render asked it to stop (its first stage then ends where it is).
    pub halted: bool,
    /// The first stage's sampler, whose sequences the adaptive pixels continue.
    pub init: SobolSampler,
    /// The cells of the rendering space.
    pub grid: CellGrid,
    /// The cells' running sums.
    pub sums: CellSums,
    /// Each cell's level (its mean log luminance, or its neighbours' while it is empty).
    pub levels: Vec<f32>,
    /// The squashed (g, s, level) each cell's current feature was made with (its level may
    /// have moved since).
    pub squashed: Vec<Squashed>,
    /// The features' scales, fixed at the first clustering.
    pub scale: Option<FeatureScale>,
    /// The clusters, once the first stage is done.
    pub clustering: Option<Clustering>,
    /// Samples given to each pixel so far: the next sample's index there.
    pub pixel_count: Vec<u32>,
    /// Adaptive samples still to give.
    pub remaining: u64,
    /// Adaptive samples given so far.
    pub given_adaptive: u64,
    /// The clusters by priority (entries whose version is stale are skipped).
    pub queue: BucketQueue,
    /// Each cluster's version: an entry of an older one is stale.
    pub version: Vec<u32>,
    /// Rounds planned and not yet observed, oldest first: their points' cells and clusters.
    pub in_flight: VecDeque<Round>,
    /// Cells without samples, as of the last update (their levels follow their neighbours').
    pub empty_cells: usize,
    /// Rounds planned so far (each draws from its own random stream).
    pub rounds: u64,
    /// The final partition in image space, made once every round is observed.
    pub partition: Option<Partition>,
    /// With `--noise-threshold`: the threshold, and the samples each cell of a cluster needs
    /// before the cluster may settle.
    pub noise: Option<(f64, u32)>,
    /// The reconstruction's estimated error after the first stage, when guided and handed
    /// over, until the clustering reads it.
    pub guide: Option<ErrorMap>,
    /// Guided: each cell's estimated error after the first stage (empty otherwise).
    pub cell_error: Vec<f64>,
    /// Guided: the first stage's samples per cell of the pixels whose counts it decides
    /// (fewer in a half of an unbiased pair, which decides half the pixels).
    pub first_per_cell: f64,
}

/// The sampling priority of a queued cluster under `rule`.
pub(super) fn priority(rule: Priority, e: &Queued) -> f64 {
    match rule {
        Priority::Paper => e.weight,
        Priority::PerSample => e.weight / e.samples.max(1) as f64,
        Priority::Guided => {
            let n = e.samples.max(1) as f64;
            e.weight / (n * n)
        }
    }
}

impl State {
    /// Bytes held by the per-cell and per-pixel state.
    pub fn bytes(&self) -> usize {
        self.sums.bytes()
            + self.levels.capacity() * 4
            + self.squashed.capacity() * std::mem::size_of::<Squashed>()
            + self.pixel_count.capacity() * 4
            + self.clustering.as_ref().map_or(0, Clustering::bytes)
            + self.queue.bytes()
    }

    /// The queue entry of cluster `id` as it stands, with its priority under `rule`; none for
    /// a dead one.
    pub fn entry(&self, rule: Priority, id: u32) -> Option<(f64, Queued)> {
        let clustering = self.clustering.as_ref().expect("clustered");
        let c = &clustering.clusters[id as usize];
        if c.cells.is_empty() {
            return None;
        }
        let weight = match rule {
            Priority::Paper => c.err(),
            Priority::PerSample => {
                // A cluster of cells that agree has err 0 however noisy or curved they are:
                // its mean gradient and variance features count too.
                let mean = c.mean();
                let err = c.err() + mean[0].abs() + mean[1].abs() + clustering.rule.tolerance;
                err * c.cells.len() as f64
            }
            Priority::Guided => {
                // Its error as the samples it began with would leave it, times them.
                let error: f64 = c.cells.iter().map(|&i| self.cell_error[i as usize]).sum();
                error * self.first_per_cell * c.cells.len() as f64
            }
        };
        let e = Queued {
            id,
            version: self.version[id as usize],
            cells: c.cells.len() as u32,
            samples: c.samples,
            weight,
        };
        Some((priority(rule, &e), e))
    }

    /// Queues the clusters `ids` in the order given, by `rule`.
    pub fn push_all(&mut self, rule: Priority, ids: impl IntoIterator<Item = u32>) {
        for id in ids {
            if let Some((priority, e)) = self.entry(rule, id) {
                self.queue.push(priority, e);
            }
        }
    }

    /// The relative error of cluster `id`, as `--noise-threshold` defines it for an image:
    /// the mean over its cells of the standard error of the cell's mean luminance over
    /// (that mean + 0.01). Infinite while a cell has fewer than `least` samples (or two).
    pub fn relative_error(&self, id: u32, least: u32) -> f64 {
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

    /// The final partition of `space` in image space: each pixel takes the cluster of most of
    /// the cells at its centre (ties to the lower id), ids renumbered in order of first
    /// appearance.
    pub fn make_partition(&self, space: &RenderingSpace) -> Option<Partition> {
        let clustering = self.clustering.as_ref()?;
        let (w, h) = (space.width(), space.height());
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
}
