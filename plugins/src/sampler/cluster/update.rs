//! Table 1's UpdateCluster, after each round of the cluster sampler as published: the cells
//! that got samples get new levels and features, and the cells that no longer fit their
//! cluster move. The unbiased pair's halves learn nothing after their first stage: for them it
//! only queues the clusters a round sampled again, with their new counts.

use super::scratch::{CellUpdate, Change, Scratch};
use super::state::{priority, State};
use super::Priority;
use crate::cells::cell_features::{level, raw_gradient, raw_variance};
use crate::cells::grid::MAX_DIMS;
use crate::cells::queue::Queued;
use rayon::prelude::*;

/// Changed cells whose clusters are read ahead of their moves at a time (see
/// [`crate::cells::Clustering::warm`]).
const WARM_RUN: usize = 16;

impl State {
    /// Table 1's UpdateCluster after a round: new levels and features for the cells that got
    /// samples (`scratch.touched`) and their face neighbours, then the cells that no longer fit
    /// move; the clusters changed and those of the round, `round_clusters`, are queued again by
    /// `rule`, and returned.
    pub(super) fn update(
        &mut self,
        scratch: &mut Scratch,
        rule: Priority,
        round_clusters: Vec<u32>,
    ) -> Vec<u32> {
        // The cells that got samples get new features; their neighbours' levels follow where
        // those are filled in from them (no samples of their own), but their features wait
        // until they are sampled: recomputing them too (table 1) cost 5 to 11 times as much
        // (one feature per face neighbour) for features that move by one cell's share.
        let mut dirty = std::mem::take(&mut scratch.dirty);
        dirty.clear();
        for (w, bits) in scratch.touched.iter_mut().enumerate() {
            while *bits != 0 {
                dirty.push((w * 64) as u32 + bits.trailing_zeros());
                *bits &= *bits - 1;
            }
        }
        if dirty.is_empty() {
            // Nothing sampled is learnt (the unbiased pair's halves after their first stage):
            // the round's clusters are queued again, no more.
            scratch.dirty = dirty;
            return self.requeue(&mut scratch.cluster_marks, rule, round_clusters);
        }
        let (grid, sums) = (&self.grid, &self.sums);
        let mut empty: Vec<u32> = Vec::new();
        if self.empty_cells > 0 {
            empty = dirty
                .par_iter()
                .flat_map_iter(|&c| {
                    let mut nbrs = Vec::with_capacity(2 * MAX_DIMS);
                    grid.neighbours(c as usize, &mut nbrs);
                    nbrs.retain(|&j| sums.count[j] == 0);
                    nbrs.into_iter().map(|j| j as u32)
                })
                .collect();
            empty.par_sort_unstable();
            empty.dedup();
            self.empty_cells = sums.count.par_iter().filter(|&&n| n == 0).count();
        }
        // Levels, and what else the features read of a touched cell's own sums, in one pass:
        // read again in the next pass, those sums had left the cache (a fifth of the features'
        // time at 700x700, by `perf annotate`).
        let mut updates = std::mem::take(&mut scratch.cell_updates);
        dirty
            .par_iter()
            .chain(empty.par_iter())
            .enumerate()
            .map(|(k, &i)| {
                let i = i as usize;
                let touched = k < dirty.len();
                CellUpdate {
                    level: level(grid, sums, i),
                    variance: if touched {
                        raw_variance(grid, sums, i)
                    } else {
                        0.0
                    },
                    samples: sums.count[i],
                }
            })
            .collect_into_vec(&mut updates);
        for (&i, f) in dirty.iter().chain(&empty).zip(&updates) {
            self.levels[i as usize] = f.level;
        }
        let mut nbrs = Vec::new();
        let grid = &self.grid;
        let levels = &self.levels;
        let scale = self.scale.expect("clustered");
        let n = grid.dims();
        let squashed = &self.squashed;
        // New raw features, and the old and new feature vectors of the cells whose features changed,
        // made in parallel: the moves below are the only serial part.
        let mut changes = std::mem::take(&mut scratch.changes);
        changes.clear();
        changes.par_extend(dirty.par_iter().zip(&updates).filter_map(|(&i, f)| {
            let i = i as usize;
            let g = raw_gradient(grid, levels, i);
            let q = scale.squash(g, f.variance, f.level);
            // What the serial moves below read of the cell, read here in parallel: at 1024x1024
            // those reads missed the cache one after another.
            (q != squashed[i]).then_some(Change {
                cell: i as u32,
                old: squashed[i],
                new: q,
                samples: f.samples,
            })
        }));
        scratch.cell_updates = updates;
        let clustering = self.clustering.as_mut().expect("clustered");
        let mut changed: Vec<u32> = round_clusters;
        for run in changes.chunks(WARM_RUN) {
            clustering.warm(run.iter().map(|c| c.cell as usize));
            for change in run {
                let i = change.cell as usize;
                let c = grid.coords(i);
                let (old, new) = (
                    scale.feature_of(n, &c, change.old),
                    scale.feature_of(n, &c, change.new),
                );
                self.squashed[i] = change.new;
                let samples = u64::from(change.samples);
                let (a, b) = clustering.update(grid, i, &old, &new, samples, &mut nbrs);
                changed.push(a);
                changed.extend(b);
            }
        }
        (scratch.dirty, scratch.changes) = (dirty, changes);
        self.requeue(&mut scratch.cluster_marks, rule, changed)
    }

    /// Queues the clusters `changed` again by `rule` (each once, in the order of its first
    /// listing, found with the clear bits `marks`) with new versions, so that their older
    /// entries go stale; returns them.
    fn requeue(&mut self, marks: &mut Vec<u64>, rule: Priority, mut changed: Vec<u32>) -> Vec<u32> {
        first_listed(marks, &mut changed, |&id| id);
        self.renew(&mut changed);
        self.push_all(rule, changed.iter().copied());
        changed
    }

    /// [`Self::requeue`] for a sampler that learns nothing after its first stage (a half of an
    /// unbiased pair): its clusters' cells and weights stand, so the entries `picked` in a
    /// round are queued again as they were but for their new sample counts, without reading
    /// each cluster's features (which cost a sixth of the sampler's time); the same entries.
    pub(super) fn requeue_picked(
        &mut self,
        scratch: &mut Scratch,
        rule: Priority,
        picked: &mut Vec<Queued>,
        mut ids: Vec<u32>,
    ) -> Vec<u32> {
        first_listed(&mut scratch.cluster_marks, picked, |e| e.id);
        ids.clear();
        ids.extend(picked.iter().map(|e| e.id));
        if self.renew(&mut ids) {
            self.push_all(rule, ids.iter().copied());
            return ids;
        }
        // The counts first, in a loop of independent reads whose cache misses overlap (read
        // while queueing, each missed in turn: two thirds of this function's time).
        let clustering = self.clustering.as_ref().expect("clustered");
        let mut counts = std::mem::take(&mut scratch.counts);
        counts.clear();
        counts.extend(
            picked
                .iter()
                .map(|e| clustering.clusters[e.id as usize].samples),
        );
        for (e, &samples) in picked.iter().zip(&counts) {
            let e = Queued {
                version: self.version[e.id as usize],
                samples,
                ..*e
            };
            self.queue.push(priority(rule, &e), e);
        }
        scratch.counts = counts;
        ids
    }

    /// New versions for the clusters `changed` (listed once each); where the queue is mostly
    /// stale entries it is emptied and `changed` becomes every cluster: returns whether.
    fn renew(&mut self, changed: &mut Vec<u32>) -> bool {
        let clustering = self.clustering.as_ref().expect("clustered");
        let (live, count) = (clustering.live(), clustering.clusters.len());
        if self.version.len() < count {
            self.version.resize(count, 0);
        }
        for &id in changed.iter() {
            self.version[id as usize] = self.version[id as usize].wrapping_add(1);
        }
        if self.queue.len() > 2 * live + 1024 {
            // Mostly stale entries: rebuild.
            self.queue.clear();
            changed.clear();
            changed.extend(0..count as u32);
            return true;
        }
        false
    }
}

/// Keeps the first of the `items` with each id (`id_of`), in order: a bit per cluster in
/// `marks` (left clear) rather than a sort (4% of the sampler's instructions, by callgrind).
fn first_listed<T>(marks: &mut Vec<u64>, items: &mut Vec<T>, id_of: impl Fn(&T) -> u32) {
    let most = items
        .iter()
        .map(|t| id_of(t) as usize + 1)
        .max()
        .unwrap_or(0);
    if marks.len() < most.div_ceil(64) {
        marks.resize(most.div_ceil(64), 0);
    }
    items.retain(|t| {
        let id = id_of(t);
        let (word, bit) = (id as usize / 64, 1u64 << (id % 64));
        let first = marks[word] & bit == 0;
        marks[word] |= bit;
        first
    });
    for t in items.iter() {
        let id = id_of(t);
        marks[id as usize / 64] &= !(1u64 << (id % 64));
    }
}
