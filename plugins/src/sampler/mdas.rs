//! `mdas`: multidimensional adaptive sampling (Hachisuka et al., "Multidimensional Adaptive
//! Sampling and Reconstruction for Ray Tracing", SIGGRAPH 2008), re-implemented from the paper
//! over acr's rendering space (x, y in pixels, then the active time and lens dims).
//!
//! A kd-tree covers the space. After a uniform first round (`initspp` per pixel), each round
//! gives one sample to each of the leaves whose error (the luminance contrast of its samples
//! times its volume) is within `factor` of the largest; a round has between a quarter and one
//! sample per pixel in all. A new sample is the farthest of 8 random candidates in the leaf
//! from the leaf's samples. A leaf holding more than `leafsamples` samples is split at their
//! median along its longest axis (time and lens lengths counted as `dimscale` pixels per unit).
//! The image integrates the leaves' means over each pixel's footprint (the paper's anisotropic
//! reconstruction, with the leaf as the kernel): a pixel is the sum over the leaves it
//! overlaps of mean x overlap area x the leaf's extent in time and lens.

// Channel and dim loops index several small arrays at once, as the formulas do.
#![allow(clippy::needless_range_loop)]

use super::{
    pixel_key, Pcg32, PixelCursor, Sampler, SamplerBuild, SamplerReport, SamplerSetup,
    BATCH_SAMPLES,
};
use crate::cells::grid::MAX_DIMS;
use crate::film::{luminance, Film, Spectrum};
use crate::registry::{float_in, int_in, Choice, Entry, Kind, ParamSpec, PluginInfo};
use crate::space::{in_pixel, RenderingSpace, SamplePoint};
use acr_parser::{ParamType, Result};

/// Salt of this sampler's keys.
const SALT: u64 = 0x6d64_6173;

/// Candidates tried for each new sample.
const CANDIDATES: usize = 8;

/// Deepest split: below this a leaf keeps its samples however many.
const MAX_DEPTH: u32 = 48;

/// A traced sample: its coordinates (x, y in pixels, then the active dims) and radiance.
#[derive(Clone, Copy, Debug)]
struct Sample {
    at: [f32; MAX_DIMS],
    l: [f32; 3],
}

/// A node of the kd-tree.
#[derive(Clone, Debug)]
struct Node {
    lo: [f32; MAX_DIMS],
    hi: [f32; MAX_DIMS],
    depth: u32,
    /// Radiance sum and count of every sample below, for the mean of a leaf left empty.
    sum: [f64; 3],
    count: u32,
    kind: NodeKind,
}

#[derive(Clone, Debug)]
enum NodeKind {
    Leaf {
        samples: Vec<u32>,
        error: f64,
    },
    Inner {
        axis: usize,
        split: f32,
        children: [u32; 2],
    },
}

/// The sampler.
pub struct MdasSampler {
    space: RenderingSpace,
    dims: usize,
    spp: u32,
    /// The samples per pixel it plans for: `spp`, or fewer under a time plan.
    plan_spp: u32,
    /// The first, uniform round's walk, pass by pass over every pixel (its count is the
    /// first round's `initspp`, which a time plan may shorten).
    first: PixelCursor,
    /// Whether `initspp` was given (then a time plan keeps it).
    init_given: bool,
    seed: u64,
    /// Which interleaved stream of sample indices it gives.
    stream: super::IndexStream,
    leaf_samples: usize,
    factor: f64,
    dim_scale: f32,
    nodes: Vec<Node>,
    samples: Vec<Sample>,
    /// Points of the round under way, sorted by row, not yet given out.
    pending: Vec<SamplePoint>,
    pending_at: usize,
    /// Samples given out.
    given: u64,
    /// Sample indices given per pixel.
    per_pixel: Vec<u32>,
    rounds: u64,
    halted: bool,
    /// Points of the first round observed so far (dropped ones included).
    init_observed: u64,
    /// Whether the first round's samples have been split into a tree.
    built: bool,
}

impl MdasSampler {
    fn budget(&self) -> u64 {
        self.space.pixels() * u64::from(self.plan_spp)
    }

    /// The first round's points: its count (which a time plan may have shortened) per pixel.
    fn first_round(&self) -> u64 {
        self.space.pixels() * u64::from(self.first.spp())
    }

    /// Splits the first round's samples, held in the root, into a tree.
    fn build_tree(&mut self) {
        self.built = true;
        self.split_if_full(0);
    }

    /// A point's coordinates in the tree's space.
    fn coords(&self, q: &SamplePoint) -> [f32; MAX_DIMS] {
        let mut at = [0.0; MAX_DIMS];
        at[0] = q.film[0];
        at[1] = q.film[1];
        let mut d = 2;
        if self.space.dims.time {
            at[d] = q.time;
            d += 1;
        }
        if self.space.dims.lens {
            at[d] = q.lens[0];
            at[d + 1] = q.lens[1];
        }
        at
    }

    /// The point at `at`, in the pixel that holds it (its index set later).
    fn point(&self, at: &[f32; MAX_DIMS]) -> SamplePoint {
        let s = &self.space;
        let px = (at[0].floor() as i64).clamp(i64::from(s.x0), i64::from(s.x1) - 1) as u32;
        let py = (at[1].floor() as i64).clamp(i64::from(s.y0), i64::from(s.y1) - 1) as u32;
        let mut q = SamplePoint {
            pixel: [px, py],
            index: 0,
            film: [
                in_pixel(px, at[0] - px as f32),
                in_pixel(py, at[1] - py as f32),
            ],
            time: 0.5,
            lens: [0.5; 2],
        };
        let mut d = 2;
        if s.dims.time {
            q.time = at[d].clamp(0.0, crate::space::ONE_MINUS_EPSILON);
            d += 1;
        }
        if s.dims.lens {
            q.lens = [
                at[d].clamp(0.0, crate::space::ONE_MINUS_EPSILON),
                at[d + 1].clamp(0.0, crate::space::ONE_MINUS_EPSILON),
            ];
        }
        q
    }

    /// Length of axis `a` of a box, time and lens in `dim_scale` pixels per unit.
    fn length(&self, lo: &[f32; MAX_DIMS], hi: &[f32; MAX_DIMS], a: usize) -> f32 {
        let l = hi[a] - lo[a];
        if a < 2 {
            l
        } else {
            l * self.dim_scale
        }
    }

    /// The leaf's error: the luminance contrast of its samples times its volume (pixels x
    /// scaled units); a leaf of fewer than two samples counts as full contrast.
    fn leaf_error(&self, node: &Node, samples: &[u32]) -> f64 {
        let volume: f64 = (0..self.dims)
            .map(|a| f64::from(self.length(&node.lo, &node.hi, a)))
            .product();
        if samples.len() < 2 {
            return volume;
        }
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for &i in samples {
            let y = f64::from(luminance(Spectrum::from_array(self.samples[i as usize].l)));
            lo = lo.min(y);
            hi = hi.max(y);
        }
        let contrast = (hi - lo) / (hi + lo + 1e-4);
        contrast * volume
    }

    /// Adds sample `i` to the tree, splitting the leaf it lands in when full.
    fn insert(&mut self, i: u32) {
        let s = self.samples[i as usize];
        let mut n = 0usize;
        loop {
            let node = &mut self.nodes[n];
            node.count += 1;
            for c in 0..3 {
                node.sum[c] += f64::from(s.l[c]);
            }
            match &mut node.kind {
                NodeKind::Inner {
                    axis,
                    split,
                    children,
                } => {
                    n = children[usize::from(s.at[*axis] >= *split)] as usize;
                }
                NodeKind::Leaf { samples, .. } => {
                    samples.push(i);
                    break;
                }
            }
        }
        self.split_if_full(n);
    }

    /// Splits leaf `n` at its samples' median along its longest axis while it is too full,
    /// then sets the errors of the leaves made.
    fn split_if_full(&mut self, n: usize) {
        let (full, depth) = match &self.nodes[n].kind {
            NodeKind::Leaf { samples, .. } => {
                (samples.len() > self.leaf_samples, self.nodes[n].depth)
            }
            NodeKind::Inner { .. } => unreachable!("split_if_full on an inner node"),
        };
        if !full || depth >= MAX_DEPTH {
            self.update_error(n);
            return;
        }
        let (lo, hi) = (self.nodes[n].lo, self.nodes[n].hi);
        let axis = (0..self.dims)
            .max_by(|&a, &b| {
                self.length(&lo, &hi, a)
                    .total_cmp(&self.length(&lo, &hi, b))
                    .then(b.cmp(&a))
            })
            .unwrap_or(0);
        let NodeKind::Leaf { samples, .. } = std::mem::replace(
            &mut self.nodes[n].kind,
            NodeKind::Leaf {
                samples: Vec::new(),
                error: 0.0,
            },
        ) else {
            unreachable!()
        };
        let mut values: Vec<f32> = samples
            .iter()
            .map(|&i| self.samples[i as usize].at[axis])
            .collect();
        let mid = values.len() / 2;
        values.select_nth_unstable_by(mid, f32::total_cmp);
        let mut split = values[mid];
        // A median on the box's edge (repeated coordinates) would leave a side empty.
        if split <= lo[axis] || split >= hi[axis] {
            split = 0.5 * (lo[axis] + hi[axis]);
        }
        let (mut left, mut right) = (Vec::new(), Vec::new());
        for i in samples {
            if self.samples[i as usize].at[axis] < split {
                left.push(i);
            } else {
                right.push(i);
            }
        }
        let first = self.nodes.len() as u32;
        for (side, part) in [left, right].into_iter().enumerate() {
            let (mut clo, mut chi) = (lo, hi);
            if side == 0 {
                chi[axis] = split;
            } else {
                clo[axis] = split;
            }
            let (mut sum, mut count) = ([0.0; 3], 0);
            for &i in &part {
                for c in 0..3 {
                    sum[c] += f64::from(self.samples[i as usize].l[c]);
                }
                count += 1;
            }
            self.nodes.push(Node {
                lo: clo,
                hi: chi,
                depth: depth + 1,
                sum,
                count,
                kind: NodeKind::Leaf {
                    samples: part,
                    error: 0.0,
                },
            });
        }
        self.nodes[n].kind = NodeKind::Inner {
            axis,
            split,
            children: [first, first + 1],
        };
        self.split_if_full(first as usize);
        self.split_if_full(first as usize + 1);
    }

    fn update_error(&mut self, n: usize) {
        if let NodeKind::Leaf { samples, .. } = &self.nodes[n].kind {
            let e = self.leaf_error(&self.nodes[n], samples);
            if let NodeKind::Leaf { error, .. } = &mut self.nodes[n].kind {
                *error = e;
            }
        }
    }

    /// Plans the next adaptive round into `pending`; false when the budget is spent.
    fn plan_round(&mut self) -> bool {
        // A first round halted at a pass is all seen by now: split it for the reconstruction.
        if !self.built && self.halted {
            self.build_tree();
        }
        let left = self.budget().saturating_sub(self.given);
        if left == 0 || self.halted {
            return false;
        }
        let mut leaves: Vec<(f64, u32)> = self
            .nodes
            .iter()
            .enumerate()
            .filter_map(|(i, n)| match &n.kind {
                NodeKind::Leaf { error, .. } => Some((*error, i as u32)),
                NodeKind::Inner { .. } => None,
            })
            .collect();
        leaves.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let largest = leaves.first().map_or(0.0, |l| l.0);
        let within = leaves
            .iter()
            .take_while(|l| l.0 >= self.factor * largest)
            .count() as u64;
        let pixels = self.space.pixels();
        let n = within.clamp((pixels / 4).max(1), pixels.max(1)).min(left);
        self.rounds += 1;
        let mut ats = Vec::with_capacity(n as usize);
        for k in 0..n {
            let (_, leaf) = leaves[(k % leaves.len() as u64) as usize];
            ats.push(self.candidate(leaf as usize, k));
        }
        self.queue(ats);
        true
    }

    /// The farthest of [`CANDIDATES`] random points in leaf `n` from its samples.
    fn candidate(&self, n: usize, k: u64) -> [f32; MAX_DIMS] {
        let node = &self.nodes[n];
        let key = pixel_key([n as u32, k as u32], self.seed, SALT ^ self.rounds);
        let mut rng = Pcg32::new(key, self.rounds);
        let NodeKind::Leaf { samples, .. } = &node.kind else {
            unreachable!("candidates are drawn in leaves")
        };
        let mut best = (f32::NEG_INFINITY, node.lo);
        for _ in 0..CANDIDATES {
            let mut at = [0.0; MAX_DIMS];
            for a in 0..self.dims {
                let u = rng.next_f32();
                at[a] = node.lo[a] + u * (node.hi[a] - node.lo[a]);
            }
            let nearest = samples
                .iter()
                .map(|&i| {
                    let s = &self.samples[i as usize].at;
                    (0..self.dims)
                        .map(|a| {
                            let d = (s[a] - at[a]) * if a < 2 { 1.0 } else { self.dim_scale };
                            d * d
                        })
                        .sum::<f32>()
                })
                .fold(f32::INFINITY, f32::min);
            if nearest > best.0 {
                best = (nearest, at);
            }
        }
        best.1
    }

    /// Queues points at `ats`: sorted by pixel row and column (the film's order), each given
    /// its pixel's next sample index.
    fn queue(&mut self, ats: Vec<[f32; MAX_DIMS]>) {
        let mut points: Vec<SamplePoint> = ats.iter().map(|at| self.point(at)).collect();
        points.sort_by_key(|q| (q.pixel[1], q.pixel[0]));
        for q in &mut points {
            let i = self.space.index_of(q.pixel);
            q.index = self.stream.index(self.per_pixel[i]);
            self.per_pixel[i] += 1;
        }
        self.pending = points;
        self.pending_at = 0;
    }

    /// The first round's next batch: a pass (or part of one) of uniform points.
    fn init_batch(&mut self) -> bool {
        let Some((pixels, indices)) = self.first.next() else {
            return false;
        };
        let mut ats = Vec::with_capacity((pixels.end - pixels.start) as usize * indices.len());
        for i in pixels {
            let p = self.space.pixel(i);
            for k in indices.clone() {
                let key = pixel_key(p, self.seed, SALT);
                // The stream's own indices, so that two streams draw different points.
                let k = self.stream.index(k);
                let mut rng = Pcg32::new(super::mix64(key ^ u64::from(k)), u64::from(k));
                let mut at = [0.0; MAX_DIMS];
                // Inside the pixel: p + u rounds up to p + 1 for u near 1, a point of the next.
                at[0] = in_pixel(p[0], rng.next_f32());
                at[1] = in_pixel(p[1], rng.next_f32());
                for a in at.iter_mut().take(self.dims).skip(2) {
                    *a = rng.next_f32();
                }
                ats.push(at);
            }
        }
        self.queue(ats);
        true
    }
}

impl Sampler for MdasSampler {
    fn name(&self) -> &'static str {
        "mdas"
    }

    fn spp(&self) -> u32 {
        self.spp
    }

    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool {
        out.clear();
        if self.pending_at >= self.pending.len() && !self.init_batch() && !self.plan_round() {
            return false;
        }
        let end = (self.pending_at + BATCH_SAMPLES as usize).min(self.pending.len());
        out.extend_from_slice(&self.pending[self.pending_at..end]);
        self.pending_at = end;
        self.given += out.len() as u64;
        true
    }

    fn observe(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        for (q, l) in batch.iter().zip(radiance) {
            if !self.built {
                self.init_observed += 1;
            }
            if !l.iter().all(|v| v.is_finite()) {
                continue;
            }
            self.samples.push(Sample {
                at: self.coords(q),
                l: *l,
            });
            let i = (self.samples.len() - 1) as u32;
            if self.built {
                self.insert(i);
            } else {
                // The first round arrives row by row: inserted one by one, its medians would
                // split along y ahead of the rows still to come and build a chain. It is kept
                // in the root and split once, whole.
                let root = &mut self.nodes[0];
                root.count += 1;
                for c in 0..3 {
                    root.sum[c] += f64::from(l[c]);
                }
                if let NodeKind::Leaf { samples, .. } = &mut root.kind {
                    samples.push(i);
                }
            }
        }
        // The first round's worth of points (its count, which a time plan may have shortened,
        // per pixel; a pilot's, for the stream it leads), seen, is split at once.
        if !self.built && self.init_observed >= self.first_round() {
            self.build_tree();
        }
    }

    fn halt(&mut self) {
        // The first round ends at the pass under way; no adaptive round starts after this.
        self.halted = true;
        self.first.halt();
    }

    fn plan_for(&mut self, spp: u32) -> bool {
        self.plan_spp = spp.clamp(1, self.spp);
        // The first round, while under way, shrinks to its share (not inside a pass).
        if !self.init_given {
            self.first.shorten(super::first_stage_spp(self.plan_spp, 1));
        }
        true
    }

    fn report(&self) -> SamplerReport {
        let leaves = self
            .nodes
            .iter()
            .filter(|n| matches!(n.kind, NodeKind::Leaf { .. }))
            .count();
        SamplerReport {
            clusters: Some(leaves as u64),
            cells: None,
            rounds: Some(self.rounds),
        }
    }

    fn reconstructs(&self) -> bool {
        true
    }

    fn reconstruct(&self, _film: &Film) -> Option<Vec<Spectrum>> {
        let s = &self.space;
        let (w, h) = (s.width() as usize, s.height() as usize);
        let mut image = vec![[0.0f64; 3]; w * h];
        // Depth first, carrying the nearest non-empty ancestor's mean for empty leaves.
        let mut stack = vec![(0usize, [0.0f64; 3])];
        while let Some((n, inherited)) = stack.pop() {
            let node = &self.nodes[n];
            let mean = if node.count > 0 {
                node.sum.map(|v| v / f64::from(node.count))
            } else {
                inherited
            };
            match &node.kind {
                NodeKind::Inner { children, .. } => {
                    stack.push((children[0] as usize, mean));
                    stack.push((children[1] as usize, mean));
                }
                NodeKind::Leaf { .. } => {
                    let extent: f64 = (2..self.dims)
                        .map(|a| f64::from(node.hi[a] - node.lo[a]))
                        .product();
                    let (x0, x1) = (f64::from(node.lo[0]), f64::from(node.hi[0]));
                    let (y0, y1) = (f64::from(node.lo[1]), f64::from(node.hi[1]));
                    let px = (x0.floor() as i64).max(i64::from(s.x0))
                        ..(x1.ceil() as i64).min(i64::from(s.x1));
                    for py in (y0.floor() as i64).max(i64::from(s.y0))
                        ..(y1.ceil() as i64).min(i64::from(s.y1))
                    {
                        let oy = (y1.min(py as f64 + 1.0) - y0.max(py as f64)).max(0.0);
                        for x in px.clone() {
                            let ox = (x1.min(x as f64 + 1.0) - x0.max(x as f64)).max(0.0);
                            let wgt = ox * oy * extent;
                            let i = (py - i64::from(s.y0)) as usize * w
                                + (x - i64::from(s.x0)) as usize;
                            for c in 0..3 {
                                image[i][c] += wgt * mean[c];
                            }
                        }
                    }
                }
            }
        }
        Some(image.into_iter().map(super::nonnegative_spectrum).collect())
    }
}

fn build(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn Sampler>> {
    let p = &c.params;
    let spp = super::pixel_samples(p, setup)?;
    let init_spp = super::first_stage_spp(spp, 1) as i32;
    let init_spp = int_in(p, "initspp", init_spp, 1..=i64::from(spp))?;
    let space = setup.space;
    let dims = space.dims.count();
    let mut lo = [0.0; MAX_DIMS];
    let mut hi = [1.0; MAX_DIMS];
    lo[0] = space.x0 as f32;
    hi[0] = space.x1 as f32;
    lo[1] = space.y0 as f32;
    hi[1] = space.y1 as f32;
    let sampler = MdasSampler {
        space,
        dims,
        spp,
        plan_spp: spp,
        first: PixelCursor::new(space, init_spp),
        init_given: p.get("initspp").is_some(),
        seed: setup.seed,
        stream: setup.stream,
        leaf_samples: int_in(p, "leafsamples", 8, 2..=1024)? as usize,
        factor: float_in(p, "factor", 0.25, 0.0..=1.0)?,
        dim_scale: float_in(p, "dimscale", 1.0, 1e-3..=1e3)? as f32,
        nodes: vec![Node {
            lo,
            hi,
            depth: 0,
            sum: [0.0; 3],
            count: 0,
            kind: NodeKind::Leaf {
                samples: Vec::new(),
                error: 0.0,
            },
        }],
        samples: Vec::new(),
        pending: Vec::new(),
        pending_at: 0,
        given: 0,
        per_pixel: vec![0; space.pixels() as usize],
        init_observed: 0,
        rounds: 1,
        halted: false,
        built: false,
    };
    Ok(Box::new(sampler))
}

/// The registry's entry.
pub(super) const ENTRY: Entry<SamplerBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Sampler,
        name: "mdas",
        doc: "multidimensional adaptive sampling (Hachisuka et al. 2008, re-implemented): kd-tree \
              over the active dims, samples to the leaves of highest contrast x volume, \
              reconstruction by integrating the leaves' means over each pixel; reconstructs the \
              image itself",
        params: &[
            super::PIXELSAMPLES_ON_AVERAGE,
            ParamSpec::new(
                "initspp",
                ParamType::Integer,
                "spp/4, at least 1",
                "samples per pixel of the first, uniform round",
            ),
            ParamSpec::new(
                "leafsamples",
                ParamType::Integer,
                "8",
                "a leaf with more samples is split at their median",
            ),
            ParamSpec::new(
                "factor",
                ParamType::Float,
                "0.25",
                "a round samples the leaves whose error is within this factor of the largest",
            ),
            ParamSpec::new(
                "dimscale",
                ParamType::Float,
                "1",
                "pixels one unit of time or lens counts as when choosing the longest axis",
            ),
            super::paired::STREAMS,
            super::paired::PILOT_ONLY,
        ],
    },
    build: build_streams,
};

/// Builds the sampler as two streams, each placed by the other's values (or as one, with
/// `streams 1`).
fn build_streams(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn super::Sampler>> {
    super::paired::wrap(c, setup, build)
}
