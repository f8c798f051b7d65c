//! Walks of obvhs's compressed wide BVH with our own node test: the eight children's boxes
//! in one 8-lane pass where the CPU has AVX2 (obvhs tests them as two 4-lane halves). The
//! walk itself is obvhs's (its `traverse!` macro), so children and primitives are visited in
//! the same order, and every lane computes what obvhs's test computes, in the same order of
//! operations: the same hits, bit for bit.

// obvhs's `traverse!` names `UVec2` unqualified.
use glam::UVec2;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::Ray;

/// obvhs's floor on a box's entry distance (`cwbvh::node::EPSILON`, private to it).
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
const NODE_EPSILON: f32 = 0.0001;

/// The children of `node` that `ray` enters before `ray.tmax`, as obvhs's hit mask: the
/// internal children's bits in the high byte (by traversal priority), the leaves' primitives
/// in the low 24 bits.
#[inline(always)]
fn node_hits(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        // SAFETY: the target has AVX2 (checked at compile time above).
        unsafe { node_hits_avx2(node, ray, oct_inv4) }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    {
        node.intersect_ray(ray, oct_inv4)
    }
}

/// [`node_hits`] on eight lanes: each child's quantised planes widened from bytes, scaled
/// and offset into ray distances exactly as obvhs's `intersect_ray_simd` does per lane.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
unsafe fn node_hits_avx2(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    use std::arch::x86_64::*;
    let dir_inv = node.compute_extent() * ray.inv_direction;
    let orig = (glam::Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
    // Eight bytes to eight floats.
    let q = |v: &[u8; 8]| {
        _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(
            v.as_ptr() as *const __m128i
        )))
    };
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
    let mut mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(tmin, tmax)) as u32;
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let mut hit_mask = 0u32;
    while mask != 0 {
        let shift = mask.trailing_zeros() * 8;
        mask &= mask - 1;
        let child_bits = ((child_bits8 >> shift) as u32) & 0xff;
        let bit_index = ((bit_index8 >> shift) as u32) & 0xff;
        hit_mask |= child_bits << bit_index;
    }
    hit_mask
}

/// obvhs's `CwBvh::ray_traverse` with [`node_hits`]: calls `hit_fn(ray, primitive)` for each
/// primitive in a leaf the ray enters, shortening the ray to every distance it returns that is
/// closer. Gives the closest such distance (`ray.tmax` when none).
#[inline(always)]
pub(super) fn closest<F: FnMut(&Ray, usize) -> f32>(bvh: &CwBvh, ray: Ray, mut hit_fn: F) -> f32 {
    let mut traverse_ray = ray;
    let mut state = bvh.new_traversal(ray.direction);
    let mut node;
    obvhs::traverse!(
        bvh,
        node,
        state,
        node_hits(node, &traverse_ray, state.oct_inv4),
        {
            let t = hit_fn(&traverse_ray, state.primitive_id as usize);
            if t < traverse_ray.tmax {
                traverse_ray.tmax = t;
            }
        }
    );
    traverse_ray.tmax
}

/// obvhs's `CwBvh::ray_traverse_miss` with [`node_hits`]: true when no call of `hit_fn` (as
/// in [`closest`]) returns a distance below `ray.tmax`; stops at the first that does.
#[inline(always)]
pub(super) fn misses<F: FnMut(&Ray, usize) -> f32>(bvh: &CwBvh, ray: Ray, mut hit_fn: F) -> bool {
    let mut state = bvh.new_traversal(ray.direction);
    let mut node;
    let mut miss = true;
    'outer: {
        obvhs::traverse!(bvh, node, state, node_hits(node, &ray, state.oct_inv4), {
            let t = hit_fn(&ray, state.primitive_id as usize);
            if t < ray.tmax {
                miss = false;
                break 'outer;
            }
        });
    }
    miss
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

    /// A node with random children's quantised planes (min at most max) around `p`.
    fn node(c: &mut Cases) -> CwBvhNode {
        let mut n = CwBvhNode {
            p: Vec3::new(c.signed(), c.signed(), c.signed()) * 4.0,
            e: [120 + c.byte() % 8, 120 + c.byte() % 8, 120 + c.byte() % 8],
            imask: c.byte(),
            child_meta: [0; 8],
            ..Default::default()
        };
        for i in 0..8 {
            n.child_meta[i] = c.byte();
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

    /// The node test (the 8-lane one where the build has AVX2) gives obvhs's own hit masks.
    #[test]
    fn node_test_gives_obvhs_hit_masks() {
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
            let ours = node_hits(&n, &ray, inv);
            assert_eq!(ours, n.intersect_ray(&ray, inv), "node {n:?} ray {ray:?}");
            hits += u32::from(ours != 0);
        }
        // The cases must exercise hits, not only misses.
        assert!(hits > 500, "only {hits} of the cases hit a child");
    }
}
