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
