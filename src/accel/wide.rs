//! A compressed wide BVH (obvhs's `CwBvh` layout) built top-down by binned SAH, one wide node
//! at a time.
//!
//! obvhs builds a binary BVH (PLOC), then converts it into the wide one by a cost table over
//! every binary node; on a million triangles that conversion was more than half the build
//! (docs/BENCHMARKS.md). Here a node's children are made directly, as Embree's wide builders
//! make them: the node's primitives are split by binned SAH, then the child with the largest
//! surface is split again, until eight children or every child fits a leaf. Children keep the
//! order they were made in: our walks (`traverse.rs`) order them by distance, so the octant
//! slots of obvhs's converter (for its own traversal's order) are not computed.

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use rayon::prelude::*;
use std::mem::MaybeUninit;

/// Most primitives in a leaf: the CWBVH encoding's limit.
const LEAF_MAX: usize = 3;

/// Bins of the SAH sweep: 32 traced a million triangles 2% faster than 16 for 2% more build.
const BINS: usize = 32;

/// Sets of at most this many primitives are split by an exact sweep along one axis.
const SMALL: usize = 16;

/// Below this tree depth the SAH decides; deeper, splits are at the median, so no tree is deeper
/// than obvhs's traversal stack (32 entries) can follow.
const SAH_DEPTH: u32 = 20;

/// One primitive while building: its box and its index in the input.
#[derive(Clone, Copy)]
#[repr(C, align(16))]
struct Item {
    lo: [f32; 3],
    index: u32,
    hi: [f32; 3],
    _pad: f32,
}

impl Item {
    fn lo(&self) -> Vec3A {
        Vec3A::from_array(self.lo)
    }
    fn hi(&self) -> Vec3A {
        Vec3A::from_array(self.hi)
    }
    fn aabb(&self) -> Aabb {
        Aabb::new(self.lo(), self.hi())
    }
    /// Twice the centroid: the SAH only compares centroids, so the halving is skipped.
    fn centroid2(&self) -> Vec3A {
        self.lo() + self.hi()
    }
}

/// A set of primitives: a range of the items, its bounds and the bounds of its centroids.
#[derive(Clone, Copy)]
struct Set {
    start: usize,
    end: usize,
    bounds: Aabb,
    centroids: Aabb,
}

impl Set {
    fn len(&self) -> usize {
        self.end - self.start
    }
}

/// A wide BVH over `count` primitives whose boxes `bounds` gives, in obvhs's layout:
/// `primitive_indices` maps leaf order to the primitives' indices. `count` must not be zero.
#[cfg(test)]
pub fn build_wide(count: usize, bounds: impl Fn(usize) -> Aabb + Sync) -> CwBvh {
    let mut scratch: Vec<Item> = Vec::with_capacity(count);
    build_wide_in(count, bounds, scratch.spare_capacity_mut())
}

/// [`build_wide`] with the builder's records (32 bytes a primitive) in `scratch`, which must
/// hold at least as many bytes, aligned to 16: the caller's buffer for what it writes after
/// the build (on a million triangles, 8,000 fewer pages faulted in than a buffer each).
pub fn build_wide_in<T>(
    count: usize,
    bounds: impl Fn(usize) -> Aabb + Sync,
    scratch: &mut [MaybeUninit<T>],
) -> CwBvh {
    assert!(count > 0, "a BVH over nothing");
    assert!(std::mem::align_of::<T>() % std::mem::align_of::<Item>() == 0);
    let bytes = std::mem::size_of_val(scratch);
    assert!(
        bytes >= count * std::mem::size_of::<Item>(),
        "scratch too small"
    );
    // SAFETY: the memory is `scratch`'s, borrowed mutably for as long as the view, aligned
    // for `Item` (checked above) and large enough for `count` of them; `MaybeUninit` makes no
    // claim on its contents.
    let slots: &mut [MaybeUninit<Item>] = unsafe {
        std::slice::from_raw_parts_mut(scratch.as_mut_ptr().cast::<MaybeUninit<Item>>(), count)
    };
    slots.par_iter_mut().enumerate().for_each(|(i, slot)| {
        let b = bounds(i);
        slot.write(Item {
            lo: b.min.to_array(),
            index: i as u32,
            hi: b.max.to_array(),
            _pad: 0.0,
        });
    });
    // SAFETY: every slot was written just above.
    let items: &mut [Item] =
        unsafe { &mut *(std::ptr::from_mut::<[MaybeUninit<Item>]>(slots) as *mut [Item]) };
    let root = set_of(items, 0, items.len());
    let tree = subtree(items, root, 0);
    CwBvh {
        nodes: tree.nodes,
        primitive_indices: tree.order,
        total_aabb: root.bounds,
        exact_node_aabbs: None,
        uses_spatial_splits: false,
    }
}

/// Sets of more primitives than this have their inner children built in parallel (few in tests,
/// so that small test scenes take the parallel path too).
const PARALLEL_MIN: usize = if cfg!(test) { 64 } else { 1 << 15 };

/// A subtree: its nodes (its root first) and its primitives' indices in leaf order.
struct Subtree {
    nodes: Vec<CwBvhNode>,
    order: Vec<u32>,
}

/// The subtree over `set`, whose range is relative to `items`.
fn subtree(items: &mut [Item], set: Set, depth: u32) -> Subtree {
    let mut builder = Builder {
        items,
        nodes: vec![CwBvhNode::default()],
        order: Vec::new(),
    };
    if set.len() < PARALLEL_MIN {
        builder.emit(0, set, depth);
        return Subtree {
            nodes: builder.nodes,
            order: builder.order,
        };
    }
    let inner = builder.fill(0, set, depth);
    let Builder {
        items,
        mut nodes,
        mut order,
    } = builder;
    // The inner children's ranges are disjoint: each builds from its own slice.
    let mut slices = Vec::with_capacity(inner.len());
    let mut rest = items;
    let mut offset = 0;
    let mut by_start: Vec<(usize, Set)> = inner.into_iter().enumerate().collect();
    by_start.sort_by_key(|(_, c)| c.start);
    for (k, c) in by_start {
        let (_, tail) = rest.split_at_mut(c.start - offset);
        let (mine, tail) = tail.split_at_mut(c.len());
        let local = Set {
            start: 0,
            end: c.len(),
            ..c
        };
        slices.push((k, mine, local));
        rest = tail;
        offset = c.end;
    }
    let mut built: Vec<(usize, Subtree)> = slices
        .into_par_iter()
        .map(|(k, mine, local)| (k, subtree(mine, local, depth + 1)))
        .collect();
    built.sort_by_key(|(k, _)| *k);
    // The children's roots sit together after the root; each child's other nodes follow.
    let first = nodes.len() - built.len();
    let (mut base, mut prims) = (nodes.len(), order.len());
    let mut shifts = Vec::with_capacity(built.len());
    for (_, sub) in &built {
        shifts.push((base as u32, prims as u32));
        base += sub.nodes.len() - 1;
        prims += sub.order.len();
    }
    // A node's children at local index c (>= 1) move to base + c - 1.
    let shift = |n: &CwBvhNode, (base, prims): (u32, u32)| CwBvhNode {
        child_base_idx: (base + n.child_base_idx).saturating_sub(1),
        primitive_base_idx: n.primitive_base_idx + prims,
        ..*n
    };
    for (k, (_, sub)) in built.iter().enumerate() {
        nodes[first + k] = shift(&sub.nodes[0], shifts[k]);
    }
    // The rest is copied on every thread, each child's part into its own room (at the root,
    // megabytes copied and faulted in on one thread otherwise).
    let (old_nodes, old_order) = (nodes.len(), order.len());
    nodes.reserve_exact(base - old_nodes);
    order.reserve_exact(prims - old_order);
    let mut node_room = &mut nodes.spare_capacity_mut()[..base - old_nodes];
    let mut order_room = &mut order.spare_capacity_mut()[..prims - old_order];
    let mut parts = Vec::with_capacity(built.len());
    for ((_, sub), &s) in built.iter().zip(&shifts) {
        let (n, rest) = std::mem::take(&mut node_room).split_at_mut(sub.nodes.len() - 1);
        node_room = rest;
        let (o, rest) = std::mem::take(&mut order_room).split_at_mut(sub.order.len());
        order_room = rest;
        parts.push((n, o, sub, s));
    }
    parts.into_par_iter().for_each(|(n, o, sub, s)| {
        for (dst, node) in n.iter_mut().zip(&sub.nodes[1..]) {
            dst.write(shift(node, s));
        }
        for (dst, &i) in o.iter_mut().zip(&sub.order) {
            dst.write(i);
        }
    });
    // SAFETY: the parts cover the new room exactly, and each of their slots was written above.
    unsafe {
        nodes.set_len(base);
        order.set_len(prims);
    }
    Subtree { nodes, order }
}

/// The bounds and centroid bounds of `items[start..end]`.
fn set_of(items: &[Item], start: usize, end: usize) -> Set {
    let mut bounds = Aabb::empty();
    let mut centroids = Aabb::empty();
    for it in &items[start..end] {
        bounds = bounds.union(&it.aabb());
        centroids.extend(it.centroid2());
    }
    Set {
        start,
        end,
        bounds,
        centroids,
    }
}

struct Builder<'a> {
    items: &'a mut [Item],
    nodes: Vec<CwBvhNode>,
    /// Input indices in leaf order.
    order: Vec<u32>,
}

impl Builder<'_> {
    /// Fills node `index` with the children of `set`, then builds its inner children.
    fn emit(&mut self, index: usize, set: Set, depth: u32) {
        let first = self.nodes.len();
        let inner = self.fill(index, set, depth);
        for (k, c) in inner.into_iter().enumerate() {
            self.emit(first + k, c, depth + 1);
        }
    }

    /// Fills node `index` with the children of `set` (its leaves' primitives appended to the
    /// order, room made for its inner children) and gives the inner children, in slot order.
    fn fill(&mut self, index: usize, set: Set, depth: u32) -> Vec<Set> {
        let mut children = [set; 8];
        let mut count = 1;
        while count < 8 {
            // The child with the largest surface among those too large for a leaf.
            let pick = (0..count)
                .filter(|&i| children[i].len() > LEAF_MAX)
                .max_by(|&a, &b| {
                    half_area(&children[a].bounds).total_cmp(&half_area(&children[b].bounds))
                });
            let Some(i) = pick else { break };
            let (left, right) = self.split(children[i], depth);
            children[i] = left;
            children[count] = right;
            count += 1;
        }
        let mut node = quantized_node(&set.bounds);
        node.child_base_idx = self.nodes.len() as u32;
        node.primitive_base_idx = self.order.len() as u32;
        let mut inner = Vec::with_capacity(8);
        let mut leaf_prims = 0u8;
        // Children in the order they were made: our walks order them by distance
        // (`traverse.rs`), so the octant slots obvhs's own traversal orders by are not needed.
        for (slot, &c) in children[..count].iter().enumerate() {
            set_child_bounds(&mut node, &set.bounds, slot, &c.bounds);
            if c.len() <= LEAF_MAX {
                // The leaf's first primitive (from the node's base) and its count in unary.
                let unary = match c.len() {
                    1 => 0b0010_0000,
                    2 => 0b0110_0000,
                    _ => 0b1110_0000,
                };
                node.child_meta[slot] = leaf_prims | unary;
                leaf_prims += c.len() as u8;
                self.order
                    .extend(self.items[c.start..c.end].iter().map(|it| it.index));
            } else {
                node.imask |= 1 << slot;
                node.child_meta[slot] = (24 + slot as u8) | 0b0010_0000;
                inner.push(c);
            }
        }
        let first = self.nodes.len();
        self.nodes.resize(first + inner.len(), CwBvhNode::default());
        self.nodes[index] = node;
        inner
    }

    /// Splits `set` (of more than one primitive) in two non-empty sets: at the cheapest of the
    /// binned SAH planes, or at the median where the centroids coincide or the tree is deep.
    fn split(&mut self, set: Set, depth: u32) -> (Set, Set) {
        let extent = set.centroids.max - set.centroids.min;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        if extent[axis] <= 0.0 || depth >= SAH_DEPTH {
            return self.split_median(set, axis);
        }
        if set.len() <= SMALL {
            return self.split_small(set, axis);
        }
        // Binned along the axis of the widest centroid spread only, as pbrt-v4's builder bins.
        let min = set.centroids.min[axis];
        let scale = BINS as f32 / extent[axis];
        let bin_of = |it: &Item| {
            let c = it.centroid2()[axis];
            // The float-to-integer cast saturates, so a centroid at the maximum lands in the
            // last bin through the `min`.
            (((c - min) * scale) as usize).min(BINS - 1)
        };
        let bins = bin_items(&self.items[set.start..set.end], bin_of);
        // Cost of each plane (after bin k): area times count on both sides.
        let mut right = [(Aabb::empty(), 0u32); BINS];
        let mut acc = (Aabb::empty(), 0u32);
        for k in (1..BINS).rev() {
            acc = (acc.0.union(&bins[k].0), acc.1 + bins[k].1);
            right[k - 1] = acc;
        }
        let mut best: Option<(f32, usize, Aabb, Aabb)> = None;
        let mut left = (Aabb::empty(), 0u32);
        for k in 0..BINS - 1 {
            left = (left.0.union(&bins[k].0), left.1 + bins[k].1);
            let (r, n) = right[k];
            if left.1 == 0 || n == 0 {
                continue;
            }
            let cost = half_area(&left.0) * left.1 as f32 + half_area(&r) * n as f32;
            if best.is_none_or(|(c, ..)| cost < c) {
                best = Some((cost, k, left.0, r));
            }
        }
        let Some((_, plane, left_bounds, right_bounds)) = best else {
            return self.split_median(set, axis);
        };
        // Partition, and gather each side's centroid bounds on the way.
        let items = &mut self.items[set.start..set.end];
        let (mut lc, mut rc) = (Aabb::empty(), Aabb::empty());
        let (mut i, mut j) = (0, items.len());
        while i < j {
            let c = items[i].centroid2();
            if bin_of(&items[i]) <= plane {
                lc.extend(c);
                i += 1;
            } else {
                rc.extend(c);
                j -= 1;
                items.swap(i, j);
            }
        }
        let mid = set.start + i;
        (
            Set {
                start: set.start,
                end: mid,
                bounds: left_bounds,
                centroids: lc,
            },
            Set {
                start: mid,
                end: set.end,
                bounds: right_bounds,
                centroids: rc,
            },
        )
    }

    /// Splits a small `set` at the cheapest plane between its primitives sorted along `axis`:
    /// exact SAH on one axis, where binning's fixed cost would outweigh the sweep.
    fn split_small(&mut self, set: Set, axis: usize) -> (Set, Set) {
        let items = &mut self.items[set.start..set.end];
        let n = items.len();
        // Sorted by key, stably (the standard sort of so few items is an insertion sort, stable
        // too, so the order is the one sorting the items themselves gave): small keys move
        // rather than 32-byte items, and each key is computed once.
        let mut keyed = [(0.0f32, 0u8); SMALL];
        for (k, (slot, it)) in keyed.iter_mut().zip(items.iter()).enumerate() {
            *slot = (it.centroid2()[axis], k as u8);
        }
        let keyed = &mut keyed[..n];
        for i in 1..n {
            let x = keyed[i];
            let mut j = i;
            while j > 0 && x.0.total_cmp(&keyed[j - 1].0).is_lt() {
                keyed[j] = keyed[j - 1];
                j -= 1;
            }
            keyed[j] = x;
        }
        let mut sorted = [items[0]; SMALL];
        for (dst, &(_, k)) in sorted.iter_mut().zip(keyed.iter()) {
            *dst = items[k as usize];
        }
        items.copy_from_slice(&sorted[..n]);
        let mut right_area = [0.0f32; SMALL];
        let mut acc = Aabb::empty();
        for k in (1..n).rev() {
            acc = acc.union(&items[k].aabb());
            right_area[k] = half_area(&acc);
        }
        let mut acc = Aabb::empty();
        let mut best = (f32::INFINITY, n / 2);
        for k in 1..n {
            acc = acc.union(&items[k - 1].aabb());
            let cost = half_area(&acc) * k as f32 + right_area[k] * (n - k) as f32;
            if cost < best.0 {
                best = (cost, k);
            }
        }
        let mid = set.start + best.1;
        (
            set_of(self.items, set.start, mid),
            set_of(self.items, mid, set.end),
        )
    }

    /// Splits `set` at its median centroid along `axis` (by position in the items when every
    /// centroid is the same).
    fn split_median(&mut self, set: Set, axis: usize) -> (Set, Set) {
        let items = &mut self.items[set.start..set.end];
        let mid = items.len() / 2;
        items.select_nth_unstable_by(mid, |a, b| {
            a.centroid2()[axis].total_cmp(&b.centroid2()[axis])
        });
        let mid = set.start + mid;
        (
            set_of(self.items, set.start, mid),
            set_of(self.items, mid, set.end),
        )
    }
}

/// The boxes and counts of `items` in the bins `bin_of` gives.
#[inline]
fn bin_items(items: &[Item], bin_of: impl Fn(&Item) -> usize) -> [(Aabb, u32); BINS] {
    // Two sets of bins, for alternate items, merged after: consecutive items (neighbours in a
    // mesh) mostly fall in one bin, and one set made each update wait for the last.
    if items.len() < 64 {
        // Few items: one set of bins, as the two sets' setting up would cost more.
        let mut bins = [(Aabb::empty(), 0u32); BINS];
        for it in items {
            let bin = &mut bins[bin_of(it)];
            bin.0 = bin.0.union(&it.aabb());
            bin.1 += 1;
        }
        return bins;
    }
    let mut twin = [[(Aabb::empty(), 0u32); BINS]; 2];
    for pair in items.chunks(2) {
        for (bins, it) in twin.iter_mut().zip(pair) {
            let bin = &mut bins[bin_of(it)];
            bin.0 = bin.0.union(&it.aabb());
            bin.1 += 1;
        }
    }
    merge_bins(twin[0], twin[1])
}

/// Two sets of bins over disjoint items, as one.
fn merge_bins(mut a: [(Aabb, u32); BINS], b: [(Aabb, u32); BINS]) -> [(Aabb, u32); BINS] {
    for (bin, other) in a.iter_mut().zip(&b) {
        *bin = (bin.0.union(&other.0), bin.1 + other.1);
    }
    a
}

/// Half the surface area of a box, zero for an empty one.
fn half_area(b: &Aabb) -> f32 {
    let d = (b.max - b.min).max(Vec3A::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// A node whose quantization grid spans `bounds`: per axis, the power of two such that 255
/// steps cover the box (obvhs's convention), children empty.
fn quantized_node(bounds: &Aabb) -> CwBvhNode {
    let e = ((bounds.max - bounds.min).max(Vec3A::splat(1e-20)) / 255.0)
        .to_array()
        .map(|x| x.log2().ceil().exp2());
    CwBvhNode {
        p: bounds.min.into(),
        e: e.map(|x| (x.to_bits() >> 23) as u8),
        ..Default::default()
    }
}

/// Writes `child`'s box, rounded outwards onto the grid of `node` (which spans `bounds`), into
/// `slot`.
fn set_child_bounds(node: &mut CwBvhNode, bounds: &Aabb, slot: usize, child: &Aabb) {
    let step = node.e.map(|b| f32::from_bits((b as u32) << 23));
    let q = |v: Vec3A, round: fn(f32) -> f32| {
        let a = v - bounds.min;
        [0, 1, 2].map(|i| round(a[i] / step[i]).clamp(0.0, 255.0) as u8)
    };
    let (lo, hi) = (q(child.min, f32::floor), q(child.max, f32::ceil));
    (
        node.child_min_x[slot],
        node.child_min_y[slot],
        node.child_min_z[slot],
    ) = (lo[0], lo[1], lo[2]);
    (
        node.child_max_x[slot],
        node.child_max_y[slot],
        node.child_max_z[slot],
    ) = (hi[0], hi[1], hi[2]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box of half-size `r` around `c`.
    fn cube(c: Vec3A, r: f32) -> Aabb {
        Aabb::new(c - Vec3A::splat(r), c + Vec3A::splat(r))
    }

    /// Builds over `boxes` and runs obvhs's validation: every node reached once, every
    /// primitive once, inside its leaf's box, and every box inside its parent's.
    fn check(boxes: &[Aabb]) -> CwBvh {
        let bvh = build_wide(boxes.len(), |i| boxes[i]);
        let mut seen = bvh.primitive_indices.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..boxes.len() as u32).collect::<Vec<_>>());
        let result = bvh.validate(boxes, false);
        assert_eq!(result.node_count, bvh.nodes.len());
        assert_eq!(result.prim_count, boxes.len());
        assert!(result.max_depth < 32, "depth {}", result.max_depth);
        bvh
    }

    #[test]
    fn random_boxes_make_a_valid_tree() {
        let mut k = 0u64;
        let mut f = move || {
            k += 1;
            (acr_plugins::rng::mix64(k) >> 40) as f32 / (1u64 << 24) as f32
        };
        for n in [1, 2, 3, 4, 5, 9, 17, 100, 5000] {
            let boxes: Vec<Aabb> = (0..n)
                .map(|_| cube(Vec3A::new(f(), f() * 10.0, f() * 0.01), f() * 0.05))
                .collect();
            let bvh = check(&boxes);
            // One leaf under the root for at most three primitives; inner nodes for many.
            let children = bvh.nodes[0].child_meta.iter().filter(|&&m| m != 0).count();
            assert_eq!(children == 1, n <= 3, "{n} boxes");
            if n >= 100 {
                assert_ne!(bvh.nodes[0].imask, 0, "{n} boxes");
            }
        }
    }

    #[test]
    fn degenerate_inputs_make_valid_shallow_trees() {
        // One point repeated (every centroid the same), flat boxes on a plane, and boxes that
        // double in size (a skewed SAH): each stays within the traversal stack's depth.
        let same = vec![cube(Vec3A::ONE, 0.0); 3000];
        check(&same);
        let flat: Vec<Aabb> = (0..3000)
            .map(|i| {
                let c = Vec3A::new((i % 50) as f32, 0.0, (i / 50) as f32);
                Aabb::new(c, c + Vec3A::new(1.0, 0.0, 1.0))
            })
            .collect();
        check(&flat);
        let skewed: Vec<Aabb> = (0..120)
            .map(|i| cube(Vec3A::splat(1.3f32.powi(i)), 1.0))
            .collect();
        check(&skewed);
    }
}
