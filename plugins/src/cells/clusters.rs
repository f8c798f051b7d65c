//! Clusters of cells (docs/algorithm.md §4, paper eq. 10-11): connected sets of cells with
//! similar features, grown by flood fill and kept up to date as cells change.

use super::cell_features::{CellFeature, CELL_FEATURE_LEN};
use super::grid::CellGrid;
use std::collections::VecDeque;

/// Marks a cell that belongs to no cluster yet.
pub const UNASSIGNED: u32 = u32::MAX;

/// The running sums of a set of features: count, sum and sum of squared norms.
#[derive(Clone, Copy, Debug, Default)]
pub struct Moments {
    n: f64,
    sum: [f64; CELL_FEATURE_LEN],
    sum_sq: f64,
}

impl Moments {
    /// The mean feature F̄.
    pub fn mean(&self) -> CellFeature {
        // One division, then products: the serial parts of clustering call this often.
        let inv = 1.0 / self.n.max(1.0);
        self.sum.map(|s| s * inv)
    }

    /// The error of eq. 11 in O(1): the root mean square of |F_a - F_b| over all ordered
    /// pairs, sqrt(2 Var F). It bounds eq. 11's mean distance from above and follows it for a
    /// given spread of features; the double loop would cost O(N²) per update.
    pub fn err(&self) -> f64 {
        if self.n < 2.0 {
            return 0.0;
        }
        let inv = 1.0 / self.n;
        let mean_sq: f64 = self.sum.iter().map(|s| (s * inv) * (s * inv)).sum();
        (2.0 * (self.sum_sq * inv - mean_sq)).max(0.0).sqrt()
    }

    fn add(&mut self, f: &CellFeature) {
        self.n += 1.0;
        for (s, v) in self.sum.iter_mut().zip(f) {
            *s += v;
        }
        self.sum_sq += f.iter().map(|v| v * v).sum::<f64>();
    }

    fn remove(&mut self, f: &CellFeature) {
        self.n -= 1.0;
        for (s, v) in self.sum.iter_mut().zip(f) {
            *s -= v;
        }
        self.sum_sq -= f.iter().map(|v| v * v).sum::<f64>();
    }

    /// These moments without one member `f`.
    fn without(mut self, f: &CellFeature) -> Self {
        self.remove(f);
        self
    }
}

/// One cluster: its cells and the moments of their features.
#[derive(Clone, Debug, Default)]
pub struct Cluster {
    /// Its cells, in no order.
    pub cells: Vec<u32>,
    /// Samples spent in it (drives the error per sample).
    pub samples: u64,
    /// Its features' moments.
    pub moments: Moments,
}

impl Cluster {
    /// The mean feature F̄.
    pub fn mean(&self) -> CellFeature {
        self.moments.mean()
    }

    /// The error of eq. 11 (see [`Moments::err`]).
    pub fn err(&self) -> f64 {
        self.moments.err()
    }
}

/// Euclidean distance of two features.
#[inline]
pub fn distance(a: &CellFeature, b: &CellFeature) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// The rule of eq. 10 and the size bound.
#[derive(Clone, Copy, Debug)]
pub struct Membership {
    /// ω: larger is stricter.
    pub omega: f64,
    /// Absolute tolerance, so that a cluster with err = 0 accepts a neighbour one cell away.
    pub tolerance: f64,
    /// Most cells in one cluster.
    pub max_cells: usize,
}

impl Membership {
    /// Eq. 10: whether a cell with feature `f` belongs with the cells of moments `m` (which
    /// do not include it: an outlier would otherwise widen the error that judges it).
    #[inline]
    pub fn accepts(&self, m: &Moments, f: &CellFeature) -> bool {
        self.omega * distance(f, &m.mean()) <= m.err() + self.tolerance
    }
}

/// The partition of every cell into clusters.
#[derive(Clone, Debug)]
pub struct Clustering {
    /// Each cell's cluster id.
    pub of_cell: Vec<u32>,
    slot: Vec<u32>,
    /// Clusters by id; a dead one has no cells.
    pub clusters: Vec<Cluster>,
    free: Vec<u32>,
    /// The membership rule.
    pub rule: Membership,
}

impl Clustering {
    /// Grows clusters over the whole grid (paper section 5): from each unassigned cell in index
    /// order, a breadth-first flood fill that takes face neighbours passing eq. 10 against the
    /// running mean and error, up to `max_cells`.
    pub fn grow(
        grid: &CellGrid,
        rule: Membership,
        feature: impl Fn(usize) -> CellFeature,
        samples: impl Fn(usize) -> u64,
    ) -> Self {
        let len = grid.len();
        let mut s = Self {
            of_cell: vec![UNASSIGNED; len],
            slot: vec![0; len],
            clusters: Vec::new(),
            free: Vec::new(),
            rule,
        };
        let mut queue = VecDeque::new();
        let mut nbrs = Vec::with_capacity(2 * grid.dims());
        for seed in 0..len {
            if s.of_cell[seed] != UNASSIGNED {
                continue;
            }
            let id = s.new_cluster();
            s.insert(id, seed, &feature(seed), samples(seed));
            queue.clear();
            queue.push_back(seed);
            'fill: while let Some(c) = queue.pop_front() {
                nbrs.clear();
                grid.neighbours(c, &mut nbrs);
                for &j in &nbrs {
                    if s.clusters[id as usize].cells.len() >= rule.max_cells {
                        break 'fill;
                    }
                    if s.of_cell[j] != UNASSIGNED {
                        continue;
                    }
                    let f = feature(j);
                    if rule.accepts(&s.clusters[id as usize].moments, &f) {
                        s.insert(id, j, &f, samples(j));
                        queue.push_back(j);
                    }
                }
            }
        }
        s
    }

    /// How many clusters have cells.
    pub fn live(&self) -> usize {
        self.clusters.len() - self.free.len()
    }

    fn new_cluster(&mut self) -> u32 {
        if let Some(id) = self.free.pop() {
            return id;
        }
        self.clusters.push(Cluster::default());
        (self.clusters.len() - 1) as u32
    }

    fn insert(&mut self, id: u32, cell: usize, f: &CellFeature, samples: u64) {
        let c = &mut self.clusters[id as usize];
        self.slot[cell] = c.cells.len() as u32;
        c.cells.push(cell as u32);
        c.moments.add(f);
        c.samples += samples;
        self.of_cell[cell] = id;
    }

    fn take(&mut self, cell: usize, f: &CellFeature, samples: u64) {
        let id = self.of_cell[cell];
        let c = &mut self.clusters[id as usize];
        let k = self.slot[cell] as usize;
        c.cells.swap_remove(k);
        if let Some(&moved) = c.cells.get(k) {
            self.slot[moved as usize] = k as u32;
        }
        c.moments.remove(f);
        c.samples = c.samples.saturating_sub(samples);
        if c.cells.is_empty() {
            *c = Cluster::default();
            self.free.push(id);
        }
        self.of_cell[cell] = UNASSIGNED;
    }

    /// Cell `cell`'s feature changed from `old` to `new` (table 1's ReassignCells): its cluster's
    /// sums follow; if the cluster now refuses it, it moves to the face-neighbour cluster whose
    /// mean is nearest when that one accepts it, else it starts a cluster of its own. `samples`
    /// is what the cell carries with it. Returns the clusters changed (old, and new if moved).
    pub fn update(
        &mut self,
        grid: &CellGrid,
        cell: usize,
        old: &CellFeature,
        new: &CellFeature,
        samples: u64,
        nbrs: &mut Vec<usize>,
    ) -> (u32, Option<u32>) {
        let id = self.of_cell[cell];
        {
            let m = &mut self.clusters[id as usize].moments;
            m.remove(old);
            m.add(new);
        }
        let own = &self.clusters[id as usize];
        if own.cells.len() == 1 || self.rule.accepts(&own.moments.without(new), new) {
            return (id, None);
        }
        nbrs.clear();
        grid.neighbours(cell, nbrs);
        let mut best: Option<(f64, u32)> = None;
        for &j in nbrs.iter() {
            let other = self.of_cell[j];
            if other == id || other == UNASSIGNED {
                continue;
            }
            let d = distance(new, &self.clusters[other as usize].mean());
            if best.is_none_or(|(bd, bid)| d < bd || (d == bd && other < bid)) {
                best = Some((d, other));
            }
        }
        let target = match best {
            Some((_, b))
                if self.clusters[b as usize].cells.len() < self.rule.max_cells
                    && self.rule.accepts(&self.clusters[b as usize].moments, new) =>
            {
                b
            }
            _ => {
                // A cluster of its own; the id is taken before the old one may die, so the
                // two never coincide.
                let b = self.new_cluster();
                self.take(cell, new, samples);
                self.insert(b, cell, new, samples);
                return (id, Some(b));
            }
        };
        self.take(cell, new, samples);
        self.insert(target, cell, new, samples);
        (id, Some(target))
    }

    /// Reads the clusters of `cells`, so that the cache misses of a run of updates to those
    /// cells overlap rather than come one after another (the clusters are cold after tracing:
    /// the first read of each was over half the time of [`Self::update`], by `perf annotate`).
    pub fn warm(&self, cells: impl Iterator<Item = usize>) {
        // Every cache line of a cluster: it spans two or three.
        let touch =
            |c: &Cluster| c.moments.n + c.moments.sum[0] + c.moments.sum_sq + c.cells.len() as f64;
        let ids = cells.map(|i| self.of_cell[i] as usize);
        std::hint::black_box(ids.map(|id| touch(&self.clusters[id])).sum::<f64>());
    }

    /// Adds `n` spent samples to cluster `id`.
    pub fn spend(&mut self, id: u32, n: u64) {
        self.clusters[id as usize].samples += n;
    }

    /// Bytes held, for the memory budget.
    pub fn bytes(&self) -> usize {
        self.of_cell.capacity() * 4
            + self.slot.capacity() * 4
            + self.clusters.capacity() * std::mem::size_of::<Cluster>()
            + self
                .clusters
                .iter()
                .map(|c| c.cells.capacity() * 4)
                .sum::<usize>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::space::{Dims, RenderingSpace};

    fn grid(w: u32, h: u32) -> CellGrid {
        CellGrid::new(RenderingSpace::whole(w, h, Dims::default()), 1.0, 2)
    }

    #[test]
    fn err_is_the_rms_pairwise_distance() {
        let mut c = Cluster::default();
        let fs: Vec<CellFeature> = [0.0, 1.0, 3.0, 7.0]
            .iter()
            .map(|&v| {
                let mut f = [0.0; CELL_FEATURE_LEN];
                f[0] = v;
                f[1] = v * 0.5;
                f
            })
            .collect();
        for f in &fs {
            c.moments.add(f);
            c.cells.push(0);
        }
        let n = fs.len() as f64;
        let brute: f64 = fs
            .iter()
            .flat_map(|a| fs.iter().map(move |b| distance(a, b).powi(2)))
            .sum::<f64>()
            / (n * n);
        assert!((c.err() - brute.sqrt()).abs() < 1e-12);
        // And it bounds eq. 11's mean distance.
        let mean: f64 = fs
            .iter()
            .flat_map(|a| fs.iter().map(move |b| distance(a, b)))
            .sum::<f64>()
            / (n * n);
        assert!(c.err() >= mean);
    }

    #[test]
    fn flood_fill_splits_at_a_feature_step_and_bounds_size() {
        let g = grid(10, 4);
        let feature = |i: usize| {
            let c = g.coords(i);
            let mut f = [0.0; CELL_FEATURE_LEN];
            f[0] = if c[0] < 5 { 0.0 } else { 10.0 };
            f[3] = f64::from(c[0]) * 0.1;
            f[4] = f64::from(c[1]) * 0.1;
            f
        };
        let rule = Membership {
            omega: 0.7,
            tolerance: 0.1,
            max_cells: 1000,
        };
        let cl = Clustering::grow(&g, rule, feature, |_| 1);
        assert_eq!(cl.live(), 2);
        for i in 0..g.len() {
            let left = g.coords(i)[0] < 5;
            assert_eq!(cl.of_cell[i], if left { 0 } else { 1 });
        }
        let small = Clustering::grow(
            &g,
            Membership {
                max_cells: 3,
                ..rule
            },
            feature,
            |_| 1,
        );
        assert!(small.clusters.iter().all(|c| c.cells.len() <= 3));
        assert_eq!(
            small.clusters.iter().map(|c| c.cells.len()).sum::<usize>(),
            40
        );
    }

    #[test]
    fn a_refused_cell_moves_or_starts_a_cluster() {
        let g = grid(4, 1);
        let mut fs: Vec<CellFeature> = (0..4)
            .map(|x| {
                let mut f = [0.0; CELL_FEATURE_LEN];
                f[3] = f64::from(x) * 0.1;
                f
            })
            .collect();
        let rule = Membership {
            omega: 1.0,
            tolerance: 0.15,
            max_cells: 100,
        };
        let mut cl = Clustering::grow(&g, rule, |i| fs[i], |_| 2);
        assert_eq!(cl.live(), 1);
        let mut new = fs[3];
        new[0] = 50.0;
        let mut nb = Vec::new();
        let (old, moved) = cl.update(&g, 3, &fs[3], &new, 2, &mut nb);
        fs[3] = new;
        let moved = moved.expect("refused");
        assert_ne!(old, moved);
        assert_eq!(cl.live(), 2);
        assert_eq!(cl.clusters[moved as usize].cells, [3]);
        assert_eq!(cl.clusters[moved as usize].samples, 2);
        assert_eq!(cl.clusters[old as usize].samples, 6);
        // Its neighbour turning the same way joins it rather than start a third.
        let mut n2 = fs[2];
        n2[0] = 50.0;
        let (_, to) = cl.update(&g, 2, &fs[2], &n2, 2, &mut nb);
        assert_eq!(to, Some(moved));
        assert_eq!(cl.live(), 2);
    }
}
