//! A large geometry's primitives split into spatially compact parts, each with its own BVH,
//! joined under one wide node.
//!
//! obvhs's builder holds, while it converts its binary BVH into the wide one, about 180 bytes
//! per primitive beside the result (the binary nodes and the conversion's cost table): 300 MB
//! at the peak of a million-triangle build, more than the scene itself. Built part by part,
//! that transient memory is a few parts'. The parts are halves of halves along the widest axis
//! of their centroids (at most eight), and a new root whose children are the parts' roots
//! joins their BVHs into one, so traversal is unchanged: one stack, one tree.

use super::Prim;
use crate::geometry::Vec3;
use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use std::ops::Range;

/// Most parts: the children of one wide node.
pub const MAX_PARTS: usize = 8;

/// Most primitives in one part: beyond this, a geometry is split (measured on a 1M-triangle
/// mesh, docs/BENCHMARKS.md: with two parts built at a time, 2^17 keeps the peak at 155 MB
/// where 2^18 reached 212 MB, at about the same build time).
pub const PART_PRIMS: usize = 1 << 17;

/// Reorders `prims` (with their centroids) so that each part is a contiguous range, and
/// returns the ranges: one when `prims` holds at most `max` primitives.
pub fn split_into_parts(
    prims: &mut [Prim],
    centroid: impl Fn(&Prim) -> Vec3,
    max: usize,
) -> Vec<Range<usize>> {
    if prims.len() <= max {
        return std::iter::once(0..prims.len()).collect();
    }
    let mut items: Vec<(Vec3, Prim)> = prims.iter().map(|p| (centroid(p), *p)).collect();
    let mut ranges = Vec::new();
    halve(&mut items, 0, max.max(1), &mut ranges);
    for (slot, (_, p)) in prims.iter_mut().zip(items) {
        *slot = p;
    }
    ranges
}

/// Splits `items` at the median centroid along its widest axis until each half fits `max`.
fn halve(items: &mut [(Vec3, Prim)], offset: usize, max: usize, ranges: &mut Vec<Range<usize>>) {
    if items.len() <= max {
        ranges.push(offset..offset + items.len());
        return;
    }
    let (lo, hi) = items.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), (c, _)| (lo.min(*c), hi.max(*c)),
    );
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    let (left, right) = items.split_at_mut(mid);
    halve(left, offset, max, ranges);
    halve(right, offset + mid, max, ranges);
}

/// One BVH over parts built apart: `(bvh, base)` where `base` is the leaf-order index of the
/// part's first primitive. The parts' roots become the children of a new root (quantized and
/// ordered by direction as obvhs's converter does); their other nodes follow, their indices
/// shifted. Primitive indices of the result are leaf order itself.
pub fn join_parts(mut parts: Vec<(CwBvh, u32)>) -> CwBvh {
    assert!(
        !parts.is_empty() && parts.len() <= MAX_PARTS,
        "{} parts",
        parts.len()
    );
    if parts.len() == 1 {
        let (mut bvh, _) = parts.pop().unwrap_or_else(|| unreachable!());
        bvh.primitive_indices = (0..bvh.primitive_indices.len() as u32).collect();
        return bvh;
    }
    let total = parts
        .iter()
        .fold(Aabb::empty(), |b, (bvh, _)| b.union(&bvh.total_aabb));
    let slots = direction_slots(&parts, total.center());
    let mut root = CwBvhNode {
        p: total.min.into(),
        child_base_idx: 1,
        ..Default::default()
    };
    // The quantization grid: a power of two per axis such that 255 steps span the box.
    let e = ((total.max - total.min).max(Vec3A::splat(1e-20)) / 255.0)
        .to_array()
        .map(|x| x.log2().ceil().exp2());
    root.e = e.map(|x| (x.to_bits() >> 23) as u8);
    let mut nodes = vec![root];
    let mut order = Vec::with_capacity(parts.len());
    for (slot, part) in slots.iter().enumerate() {
        let Some(k) = *part else { continue };
        let b = parts[k].0.total_aabb;
        let q = |v: Vec3A, round: fn(f32) -> f32| {
            let a = v - total.min;
            [0, 1, 2].map(|i| round(a[i] / e[i]).clamp(0.0, 255.0) as u8)
        };
        let (lo, hi) = (q(b.min, f32::floor), q(b.max, f32::ceil));
        let r = &mut nodes[0];
        (
            r.child_min_x[slot],
            r.child_min_y[slot],
            r.child_min_z[slot],
        ) = (lo[0], lo[1], lo[2]);
        (
            r.child_max_x[slot],
            r.child_max_y[slot],
            r.child_max_z[slot],
        ) = (hi[0], hi[1], hi[2]);
        r.imask |= 1 << slot;
        r.child_meta[slot] = (24 + slot as u8) | 0b0010_0000;
        order.push(k);
    }
    // The part roots, in slot order, then each part's other nodes.
    let mut first = 1 + order.len() as u32;
    let mut shifts = vec![0u32; parts.len()];
    for &k in &order {
        shifts[k] = first;
        first += parts[k].0.nodes.len() as u32 - 1;
    }
    let shift = |node: &CwBvhNode, k: usize, base: u32| CwBvhNode {
        // A node's children at c (>= 1 in the part) move to shifts[k] + c - 1.
        child_base_idx: (shifts[k] + node.child_base_idx).saturating_sub(1),
        primitive_base_idx: node.primitive_base_idx + base,
        ..*node
    };
    for &k in &order {
        let (bvh, base) = &parts[k];
        nodes.push(shift(&bvh.nodes[0], k, *base));
    }
    for &k in &order {
        let (bvh, base) = &parts[k];
        nodes.extend(bvh.nodes[1..].iter().map(|n| shift(n, k, *base)));
    }
    let count = parts
        .iter()
        .map(|(b, _)| b.primitive_indices.len())
        .sum::<usize>();
    CwBvh {
        nodes,
        primitive_indices: (0..count as u32).collect(),
        total_aabb: total,
        exact_node_aabbs: None,
        uses_spatial_splits: false,
    }
}

/// The part in each of the root's eight slots: obvhs's greedy assignment, a child to the
/// slot whose octant direction points least towards it, so that a ray's octant visits the
/// nearer parts first.
fn direction_slots(parts: &[(CwBvh, u32)], centre: Vec3A) -> [Option<usize>; 8] {
    let direction = |s: usize| {
        let sign = |bit: usize| if s & bit != 0 { -1.0 } else { 1.0 };
        Vec3A::new(sign(4), sign(2), sign(1))
    };
    let mut slots = [None; 8];
    let mut assigned = vec![false; parts.len()];
    loop {
        let mut best: Option<(f32, usize, usize)> = None;
        for (k, (bvh, _)) in parts.iter().enumerate() {
            if assigned[k] {
                continue;
            }
            let v = bvh.total_aabb.center() - centre;
            for (s, slot) in slots.iter().enumerate() {
                let cost = direction(s).dot(v);
                if slot.is_none() && best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, k, s));
                }
            }
        }
        let Some((_, k, s)) = best else { break };
        slots[s] = Some(k);
        assigned[k] = true;
    }
    slots
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::PrimKind;

    fn prims(n: usize) -> Vec<Prim> {
        (0..n)
            .map(|i| Prim {
                kind: PrimKind::Sphere(i as u32),
                surface: 0,
            })
            .collect()
    }

    /// A centroid per sphere index: a 3D grid, 10 per row and column.
    fn grid(p: &Prim) -> Vec3 {
        let PrimKind::Sphere(i) = p.kind else {
            unreachable!()
        };
        Vec3::new(
            (i % 10) as f32,
            (i / 10 % 10) as f32 * 3.0,
            (i / 100) as f32,
        )
    }

    #[test]
    fn small_geometries_stay_whole() {
        let mut p = prims(100);
        let before = p.clone();
        let ranges = split_into_parts(&mut p, grid, 100);
        assert_eq!(ranges.len(), 1);
        assert_eq!(ranges[0], 0..100);
        assert_eq!(p, before);
    }

    #[test]
    fn parts_cover_every_primitive_once_and_are_compact() {
        let mut p = prims(1000);
        let ranges = split_into_parts(&mut p, grid, 300);
        assert_eq!(ranges.len(), 4);
        assert_eq!(ranges.first().unwrap().start, 0);
        assert_eq!(ranges.last().unwrap().end, 1000);
        for w in ranges.windows(2) {
            assert_eq!(w[0].end, w[1].start);
        }
        assert!(ranges.iter().all(|r| r.len() <= 300));
        let mut seen: Vec<u32> = p
            .iter()
            .map(|q| match q.kind {
                PrimKind::Sphere(i) => i,
                _ => unreachable!(),
            })
            .collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..1000).collect::<Vec<_>>());
        // The first split is along y (extent 27): the first two parts lie below the median.
        let max_y = |r: &Range<usize>| p[r.clone()].iter().map(|q| grid(q).y).fold(0.0, f32::max);
        let min_y = |r: &Range<usize>| {
            p[r.clone()]
                .iter()
                .map(|q| grid(q).y)
                .fold(f32::INFINITY, f32::min)
        };
        assert!(max_y(&ranges[1]) <= min_y(&ranges[2]));
    }
}
