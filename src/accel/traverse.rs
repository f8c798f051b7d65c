//! Walks of obvhs's compressed wide BVH (its node layout, built by obvhs or by `wide.rs`) with
//! our own node test and our own order: the eight children's boxes in one 8-lane pass where
//! the CPU has AVX2, and the children a ray enters visited nearest first from a stack that
//! keeps each one's entry distance, so that an entry lying beyond a hit found since it was
//! pushed is dropped without loading its node (obvhs's walk, made for GPUs, orders children by
//! the ray's octant only and visits every child it pushed). Each lane computes obvhs's box test
//! in obvhs's order of operations, so the children entered are obvhs's; the closest hit is
//! the same distance, and only which of two hits at the same distance wins can differ.

use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::Ray;
use std::mem::MaybeUninit;

/// obvhs's floor on a box's entry distance (`cwbvh::node::EPSILON`, private to it).
const NODE_EPSILON: f32 = 0.0001;

/// A target of the walk marked as a leaf: its primitives' count in bits 29-30, the first's
/// index below. Otherwise the target is a node's index.
const LEAF: u32 = 1 << 31;

/// The most primitives a geometry may have for leaf targets to name them.
pub(super) const MAX_PRIMITIVES: usize = 1 << 29;

/// The children of `node` that `ray` enters before `ray.tmax` (a bit per slot, empty slots
/// never set) and every slot's entry distance (meaningful where the bit is set).
#[inline(always)]
fn enter(node: &CwBvhNode, ray: &Ray) -> (u32, [f32; 8]) {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        // SAFETY: the target has AVX2 (checked at compile time above).
        unsafe { enter_avx2(node, ray) }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    {
        enter_scalar(node, ray)
    }
}

/// [`enter`] one slot at a time, each as a lane of [`enter_avx2`] computes it.
#[cfg_attr(all(target_arch = "x86_64", target_feature = "avx2"), allow(dead_code))]
#[inline(always)]
fn enter_scalar(node: &CwBvhNode, ray: &Ray) -> (u32, [f32; 8]) {
    let dir_inv = node.compute_extent() * ray.inv_direction;
    let orig = (glam::Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
    let negative = [
        ray.direction.x < 0.0,
        ray.direction.y < 0.0,
        ray.direction.z < 0.0,
    ];
    let planes = [
        (&node.child_min_x, &node.child_max_x),
        (&node.child_min_y, &node.child_max_y),
        (&node.child_min_z, &node.child_max_z),
    ];
    let mut mask = 0;
    let mut entry = [0.0f32; 8];
    for (slot, e) in entry.iter_mut().enumerate() {
        let t: [[f32; 2]; 3] = std::array::from_fn(|a| {
            let (lo, hi) = (planes[a].0[slot] as f32, planes[a].1[slot] as f32);
            let (near, far) = if negative[a] { (hi, lo) } else { (lo, hi) };
            // Multiply then add, unfused, as obvhs does.
            [near * dir_inv[a] + orig[a], far * dir_inv[a] + orig[a]]
        });
        let tmin = t[0][0].max(t[1][0].max(t[2][0])).max(NODE_EPSILON);
        let tmax = t[0][1].min(t[1][1].min(t[2][1])).min(ray.tmax);
        *e = tmin;
        if tmin <= tmax && node.child_meta[slot] != 0 {
            mask |= 1 << slot;
        }
    }
    (mask, entry)
}

/// [`enter`] on eight lanes: each child's quantised planes widened from bytes, scaled and
/// offset into ray distances exactly as obvhs's `intersect_ray_simd` does per lane.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
unsafe fn enter_avx2(node: &CwBvhNode, ray: &Ray) -> (u32, [f32; 8]) {
    use std::arch::x86_64::*;
    let dir_inv = node.compute_extent() * ray.inv_direction;
    let orig = (glam::Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
    let bytes = |v: &[u8; 8]| _mm256_cvtepu8_epi32(_mm_loadl_epi64(v.as_ptr() as *const __m128i));
    // Eight bytes to eight floats.
    let q = |v: &[u8; 8]| _mm256_cvtepi32_ps(bytes(v));
    let axis = |lo: &[u8; 8], hi: &[u8; 8], negative: bool, d: f32, o: f32| {
        let (q_lo, q_hi) = (q(lo), q(hi));
        let (near, far) = if negative { (q_hi, q_lo) } else { (q_lo, q_hi) };
        let (d, o) = (_mm256_set1_ps(d), _mm256_set1_ps(o));
        // Multiply then add, unfused, as obvhs does.
        (
            _mm256_add_ps(_mm256_mul_ps(near, d), o),
            _mm256_add_ps(_mm256_mul_ps(far, d), o),
        )
    };
    let (tmin_x, tmax_x) = axis(
        &node.child_min_x,
        &node.child_max_x,
        ray.direction.x < 0.0,
        dir_inv.x,
        orig.x,
    );
    let (tmin_y, tmax_y) = axis(
        &node.child_min_y,
        &node.child_max_y,
        ray.direction.y < 0.0,
        dir_inv.y,
        orig.y,
    );
    let (tmin_z, tmax_z) = axis(
        &node.child_min_z,
        &node.child_max_z,
        ray.direction.z < 0.0,
        dir_inv.z,
        orig.z,
    );
    let tmin = _mm256_max_ps(tmin_x, _mm256_max_ps(tmin_y, tmin_z));
    let tmax = _mm256_min_ps(tmax_x, _mm256_min_ps(tmax_y, tmax_z));
    let tmin = _mm256_max_ps(tmin, _mm256_set1_ps(NODE_EPSILON));
    let tmax = _mm256_min_ps(tmax, _mm256_set1_ps(ray.tmax));
    let hit = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(tmin, tmax)) as u32;
    // Empty slots (meta byte zero) have zero planes, which a ray may well cross.
    let empty = _mm256_cmpeq_epi32(bytes(&node.child_meta), _mm256_setzero_si256());
    let empty = _mm256_movemask_ps(_mm256_castsi256_ps(empty)) as u32;
    let mut entry = [0.0f32; 8];
    _mm256_storeu_ps(entry.as_mut_ptr(), tmin);
    (hit & !empty, entry)
}

/// The walk's target for the child in `slot` of `node`: a node's index, or a leaf.
#[inline(always)]
fn target(node: &CwBvhNode, slot: u32) -> u32 {
    if node.imask & (1 << slot) != 0 {
        // Inner children are stored in slot order from the node's child base.
        node.child_base_idx + (u32::from(node.imask) & ((1 << slot) - 1)).count_ones()
    } else {
        let meta = u32::from(node.child_meta[slot as usize]);
        let first = node.primitive_base_idx + (meta & 0x1f);
        LEAF | (meta >> 5).count_ones() << 29 | first
    }
}

/// The primitives of a leaf target.
#[inline(always)]
fn leaf_range(target: u32) -> std::ops::Range<usize> {
    let first = (target & (MAX_PRIMITIVES as u32 - 1)) as usize;
    first..first + ((target >> 29) & 3) as usize
}

/// Room for the entries a walk holds: at most seven per level of the tree (obvhs's trees, like
/// its own traversal's stack, stay within 32 levels; the wide builder's too).
const STACK: usize = 7 * 64 + 8;

/// Pending targets, each with its entry distance's bits above (distances are positive, so the
/// bits order as the distances do).
struct Stack {
    entries: [MaybeUninit<u64>; STACK],
    len: usize,
}

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        Self {
            entries: [MaybeUninit::uninit(); STACK],
            len: 0,
        }
    }

    #[inline(always)]
    fn push(&mut self, entry: u64) {
        // Indexing checks the bound: a tree deeper than the stack stops the walk loudly.
        self.entries[self.len] = MaybeUninit::new(entry);
        self.len += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<u64> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every entry below `len` was written by `push`.
        Some(unsafe { self.entries[self.len].assume_init() })
    }
}

/// The entries of the children `mask` names, sorted farthest first with `sort` (else in slot
/// order); gives their count.
#[inline(always)]
fn children(
    node: &CwBvhNode,
    mut mask: u32,
    entry: &[f32; 8],
    out: &mut [u64; 8],
    sort: bool,
) -> usize {
    let mut n = 0;
    while mask != 0 {
        let slot = mask.trailing_zeros();
        mask &= mask - 1;
        let key = u64::from(entry[slot as usize].to_bits()) << 32 | u64::from(target(node, slot));
        // Insertion, farthest first.
        let mut i = n;
        while sort && i > 0 && out[i - 1] < key {
            out[i] = out[i - 1];
            i -= 1;
        }
        out[i] = key;
        n += 1;
    }
    n
}

/// Calls `hit_fn(ray, primitive)` for each primitive in a leaf the ray enters, nearest leaf
/// first, shortening the ray to every distance it returns that is closer; with `ANY`, stops at
/// the first such distance. Gives the ray's final `tmax`.
#[inline(always)]
fn walk<const ANY: bool, F: FnMut(&Ray, usize) -> f32>(
    bvh: &CwBvh,
    mut ray: Ray,
    mut hit_fn: F,
) -> f32 {
    if bvh.nodes.is_empty() {
        return ray.tmax;
    }
    let mut stack = Stack::new();
    let mut current = 0u32;
    let mut kids = [0u64; 8];
    loop {
        if current & LEAF != 0 {
            for id in leaf_range(current) {
                let t = hit_fn(&ray, id);
                if t < ray.tmax {
                    ray.tmax = t;
                    if ANY {
                        return t;
                    }
                }
            }
        } else {
            let node = &bvh.nodes[current as usize];
            let (mask, entry) = enter(node, &ray);
            if mask != 0 {
                // A shadow ray stops at any hit: no order to keep, no distance to drop by.
                let n = children(node, mask, &entry, &mut kids, !ANY);
                for &k in &kids[..n - 1] {
                    stack.push(k);
                }
                current = kids[n - 1] as u32;
                continue;
            }
        }
        // The nearest pending target the ray still reaches.
        loop {
            let Some(e) = stack.pop() else {
                return ray.tmax;
            };
            if f32::from_bits((e >> 32) as u32) <= ray.tmax {
                current = e as u32;
                break;
            }
        }
    }
}

/// The closest hit's walk: calls `hit_fn(ray, primitive)` for each primitive in a leaf the
/// ray enters before its current `tmax`, which shrinks to every closer distance `hit_fn`
/// returns. Gives the closest such distance (`ray.tmax` when none).
#[inline(always)]
pub(super) fn closest<F: FnMut(&Ray, usize) -> f32>(bvh: &CwBvh, ray: Ray, hit_fn: F) -> f32 {
    walk::<false, F>(bvh, ray, hit_fn)
}

/// The shadow ray's walk: true when no call of `hit_fn` (as in [`closest`]) returns a
/// distance below `ray.tmax`; stops at the first that does.
#[inline(always)]
pub(super) fn misses<F: FnMut(&Ray, usize) -> f32>(bvh: &CwBvh, ray: Ray, hit_fn: F) -> bool {
    let tmax = ray.tmax;
    walk::<true, F>(bvh, ray, hit_fn) >= tmax
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec3, Vec3A};

    /// A small deterministic generator (xorshift64*), enough to spread the cases.
    struct Cases(u64);
    impl Cases {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }
        fn unit(&mut self) -> f32 {
            (self.next() >> 40) as f32 / (1u64 << 24) as f32
        }
        fn byte(&mut self) -> u8 {
            (self.next() >> 56) as u8
        }
        fn signed(&mut self) -> f32 {
            self.unit() * 2.0 - 1.0
        }
    }

    /// A node with random children's quantised planes (min at most max) around `p`, some
    /// slots empty.
    fn node(c: &mut Cases) -> CwBvhNode {
        let mut n = CwBvhNode {
            p: Vec3::new(c.signed(), c.signed(), c.signed()) * 4.0,
            e: [120 + c.byte() % 8, 120 + c.byte() % 8, 120 + c.byte() % 8],
            imask: c.byte(),
            child_meta: [0; 8],
            ..Default::default()
        };
        for i in 0..8 {
            n.child_meta[i] = if c.byte() < 40 { 0 } else { c.byte() };
            for (lo, hi) in [
                (&mut n.child_min_x, &mut n.child_max_x),
                (&mut n.child_min_y, &mut n.child_max_y),
                (&mut n.child_min_z, &mut n.child_max_z),
            ] {
                let (a, b) = (c.byte(), c.byte());
                lo[i] = a.min(b);
                hi[i] = a.max(b);
            }
        }
        n
    }

    /// obvhs's octant code of a direction, as its traversal computes it.
    fn oct_inv4(d: Vec3A) -> u32 {
        let oct = u32::from(d.x < 0.0) | u32::from(d.y < 0.0) << 1 | u32::from(d.z < 0.0) << 2;
        (7 - oct) * 0x0101_0101
    }

    /// obvhs's hit mask from the slots entered.
    fn obvhs_mask(n: &CwBvhNode, mut slots: u32, inv: u32) -> u32 {
        let (child_bits8, bit_index8) = n.get_child_and_index_bits(inv);
        let mut hit_mask = 0;
        while slots != 0 {
            let shift = slots.trailing_zeros() * 8;
            slots &= slots - 1;
            let child_bits = ((child_bits8 >> shift) as u32) & 0xff;
            hit_mask |= child_bits << (((bit_index8 >> shift) as u32) & 0xff);
        }
        hit_mask
    }

    /// The node test (the 8-lane one where the build has AVX2) enters the children obvhs's
    /// test enters, and agrees with the one-slot-at-a-time test bit for bit.
    #[test]
    fn node_test_enters_what_obvhs_enters() {
        let mut c = Cases(0x9e37_79b9_7f4a_7c15);
        let mut hits = 0;
        for _ in 0..20_000 {
            let n = node(&mut c);
            let o = Vec3A::new(c.signed(), c.signed(), c.signed()) * 8.0;
            let mut d = Vec3A::new(c.signed(), c.signed(), c.signed());
            if c.byte() < 128 {
                // Half the rays aimed near the node's corner, where its children lie.
                d = Vec3A::from(n.p) + Vec3A::new(c.unit(), c.unit(), c.unit()) * 2.0 - o;
            }
            if c.byte() < 32 {
                // Axis-aligned rays: zero components give infinite inverses.
                d.y = 0.0;
            }
            let ray = Ray::new(o, d.normalize_or(Vec3A::X), 0.0, 1.0 + 30.0 * c.unit());
            let inv = oct_inv4(ray.direction);
            let (mask, entry) = enter(&n, &ray);
            let (scalar_mask, scalar_entry) = enter_scalar(&n, &ray);
            assert_eq!(mask, scalar_mask, "node {n:?} ray {ray:?}");
            for s in 0..8 {
                if mask & (1 << s) != 0 {
                    assert_eq!(entry[s].to_bits(), scalar_entry[s].to_bits());
                    assert!(entry[s] >= NODE_EPSILON);
                }
            }
            let expected = n.intersect_ray(&ray, inv);
            assert_eq!(
                obvhs_mask(&n, mask, inv),
                expected,
                "node {n:?} ray {ray:?}"
            );
            hits += u32::from(expected != 0);
        }
        // The cases must exercise hits, not only misses.
        assert!(hits > 500, "only {hits} of the cases hit a child");
    }

    /// On obvhs's own trees over random triangles the walks find obvhs's closest distance and
    /// its shadow answer.
    #[test]
    fn walks_agree_with_obvhs_traversal() {
        use obvhs::triangle::Triangle;
        let mut c = Cases(0x2545_f491_4f6c_dd1d);
        let tris: Vec<Triangle> = (0..3000)
            .map(|_| {
                let p = Vec3A::new(c.signed(), c.signed(), c.signed()) * 5.0;
                let mut e = || Vec3A::new(c.signed(), c.signed(), c.signed()) * 0.4;
                Triangle {
                    v0: p,
                    v1: p + e(),
                    v2: p + e(),
                }
            })
            .collect();
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            obvhs::BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        let test = |r: &Ray, id: usize| {
            let t = tris[bvh.primitive_indices[id] as usize].intersect(r);
            if t < r.tmax {
                t
            } else {
                f32::INFINITY
            }
        };
        let mut hits = 0;
        for i in 0..20_000 {
            let o = Vec3A::new(c.signed(), c.signed(), c.signed()) * 7.0;
            let d = Vec3A::new(c.signed(), c.signed(), c.signed()).normalize_or(Vec3A::Y);
            let tmax = if i % 2 == 0 {
                f32::INFINITY
            } else {
                8.0 * c.unit()
            };
            let ray = Ray::new(o, d, 0.0, tmax);
            let mut expected = obvhs::ray::RayHit::none();
            let found = bvh.ray_traverse(ray, &mut expected, test);
            let ours = closest(&bvh, ray, test);
            assert_eq!(ours < tmax, found, "ray {i}");
            if found {
                assert_eq!(ours, expected.t, "ray {i}");
                hits += 1;
            }
            assert_eq!(misses(&bvh, ray, test), !found, "ray {i}");
            assert_eq!(bvh.ray_traverse_miss(ray, test), !found, "ray {i}");
        }
        assert!(hits > 2000, "only {hits} hits");
    }
}
