//! pbrt-v4's light BVH (`BVHLightSampler`): the lights that have bounds (point, spot, area)
//! in a tree (four children a node) of their bounds, emission cones and power; a light is chosen by walking
//! down from the root, taking each child in proportion to an importance that bounds what its
//! lights can send to the shading point. Choosing and its probability are O(depth). Lights
//! without bounds (distant, infinite) are chosen uniformly beside the tree.

use crate::accel::Geometry;
use crate::geometry::Vec3;
use crate::light::Light;
use glam::Vec4;

mod bounds;
use bounds::safe_sqrt;
pub use bounds::LightBounds;

/// Where a light is chosen from: the shading point and its shading normal (zero for a point
/// in a medium, where no cosine applies).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightContext {
    /// The shading point.
    pub p: Vec3,
    /// The shading normal, or zero.
    pub n: Vec3,
}

/// Up to four children of a node, side by side so that their importances are computed at
/// once (one SIMD lane each): what [`Node::importance`] needs of each child's bounds, derived
/// once, and each child's link and range of lights. An empty slot has no power.
#[derive(Clone, Copy, Debug)]
struct Node {
    cx: Vec4,
    cy: Vec4,
    cz: Vec4,
    /// Radius of the sphere around each child's bounds, and its square.
    radius: Vec4,
    radius2: Vec4,
    /// Axis of each child's normals' cone.
    wx: Vec4,
    wy: Vec4,
    wz: Vec4,
    /// Emitted power (0: empty slot).
    phi: Vec4,
    /// The reciprocal of pbrt-v4's floor on the squared distance (half the bounds' diagonal).
    inv_d2_floor: Vec4,
    /// Cosine and sine of the normals' spread.
    cos_theta_o: Vec4,
    sin_theta_o: Vec4,
    /// Cosine of the emission's spread past the normals.
    cos_theta_e: Vec4,
    /// 1 where the child emits on both sides of its normals, else 0.
    two_sided: Vec4,
    /// Per child: [`LEAF`] and the light's index, or the child node's index; [`EMPTY`].
    links: [u32; 4],
    /// Per child: its lights, `LightBvh::order[start..end]`.
    starts: [u32; 4],
    ends: [u32; 4],
}

const LEAF: u32 = 1 << 31;
const EMPTY: u32 = u32::MAX;
const INDEX: u32 = LEAF - 1;

impl Node {
    /// A node of empty slots.
    fn empty() -> Self {
        Self {
            cx: Vec4::ZERO,
            cy: Vec4::ZERO,
            cz: Vec4::ZERO,
            radius: Vec4::ZERO,
            radius2: Vec4::ZERO,
            wx: Vec4::ZERO,
            wy: Vec4::ZERO,
            wz: Vec4::ONE,
            phi: Vec4::ZERO,
            inv_d2_floor: Vec4::ONE,
            cos_theta_o: Vec4::ONE,
            sin_theta_o: Vec4::ZERO,
            cos_theta_e: Vec4::ZERO,
            two_sided: Vec4::ZERO,
            links: [EMPTY; 4],
            starts: [0; 4],
            ends: [0; 4],
        }
    }

    /// Puts a child with bounds `b`, link `link` and lights `range` in slot `k`.
    fn set(&mut self, k: usize, b: &LightBounds, link: u32, range: (usize, usize)) {
        let c = b.centroid();
        self.cx[k] = c.x;
        self.cy[k] = c.y;
        self.cz[k] = c.z;
        self.radius2[k] = b.lo.distance_squared(c);
        self.radius[k] = self.radius2[k].sqrt();
        self.wx[k] = b.w.x;
        self.wy[k] = b.w.y;
        self.wz[k] = b.w.z;
        self.phi[k] = b.phi;
        self.inv_d2_floor[k] = 2.0 / (b.hi - b.lo).length();
        self.cos_theta_o[k] = b.cos_theta_o;
        self.sin_theta_o[k] = safe_sqrt(1.0 - b.cos_theta_o * b.cos_theta_o);
        self.cos_theta_e[k] = b.cos_theta_e;
        self.two_sided[k] = if b.two_sided { 1.0 } else { 0.0 };
        self.links[k] = link;
        self.starts[k] = range.0 as u32;
        self.ends[k] = range.1 as u32;
    }

    /// pbrt-v4's `LightBounds::Importance` of the four children at once: an upper bound on
    /// what each child's lights send to `ctx`, up to a common factor: power over the squared
    /// distance, times the cosine of the smallest angle any emitter could make with the
    /// direction to the point (zero outside every emission cone), times the cosine bound at
    /// the receiving surface. Also returns the squared distances to the children's centres.
    ///
    /// Every sine and cosine of an angle at the point is a length in the unnormalised
    /// direction `d` times one reciprocal square root of `|d|^2`: sin w = sqrt(|d|^2 -
    /// (d.w)^2) / |d|, cos b = sqrt(|d|^2 - r^2) / |d|, sin b = r / |d|, so the square roots
    /// run side by side rather than after the normalisation (see docs/BENCHMARKS.md, "The
    /// light BVH's choice and the small rows").
    #[inline(always)]
    fn importance(&self, ctx: LightContext) -> (Vec4, Vec4) {
        let dx = Vec4::splat(ctx.p.x) - self.cx;
        let dy = Vec4::splat(ctx.p.y) - self.cy;
        let dz = Vec4::splat(ctx.p.z) - self.cz;
        let dist2 = dx * dx + dy * dy + dz * dz;
        // 1/|d| (0 at the centre, where every direction then counts as inside the bounds),
        // and the floored squared one's reciprocal (infinite for a point at a point light,
        // whose importance is then 0).
        let away = dist2.cmpgt(Vec4::ZERO);
        let inv = Vec4::select(away, rsqrt4(dist2), Vec4::ZERO);
        let inv_d2 = Vec4::select(away, (inv * inv).min(self.inv_d2_floor), self.inv_d2_floor);
        let dw = self.wx * dx + self.wy * dy + self.wz * dz;
        let dw = Vec4::select(self.two_sided.cmpgt(Vec4::ZERO), dw.abs(), dw);
        let cos_w = dw * inv;
        let sin_w = safe_sqrt4(dist2 - dw * dw) * inv;
        // The cone from the point that holds each child's sphere (every direction inside it).
        let inside = dist2.cmplt(self.radius2);
        let cos_b = Vec4::select(
            inside,
            Vec4::NEG_ONE,
            safe_sqrt4(dist2 - self.radius2) * inv,
        );
        let sin_b = Vec4::select(inside, Vec4::ZERO, self.radius * inv);
        let (cos_o, sin_o) = (self.cos_theta_o, self.sin_theta_o);
        let below = cos_w.cmpgt(cos_o);
        let cos_x = Vec4::select(below, Vec4::ONE, cos_w * cos_o + sin_w * sin_o);
        let sin_x = Vec4::select(below, Vec4::ZERO, sin_w * cos_o - cos_w * sin_o);
        let cos_p = cos_sub_clamped4(sin_x, cos_x, sin_b, cos_b);
        let mut importance = Vec4::select(
            cos_p.cmple(self.cos_theta_e),
            Vec4::ZERO,
            self.phi * cos_p * inv_d2,
        );
        if ctx.n != Vec3::ZERO {
            let dn = (dx * ctx.n.x + dy * ctx.n.y + dz * ctx.n.z).abs();
            let cos_i = dn * inv;
            let sin_i = safe_sqrt4(dist2 - dn * dn) * inv;
            importance *= cos_sub_clamped4(sin_i, cos_i, sin_b, cos_b);
        }
        let ok = importance.is_finite_mask() & importance.cmpgt(Vec4::ZERO);
        (Vec4::select(ok, importance, Vec4::ZERO), dist2)
    }

    /// Whether the choice among child `k`'s lights may be made by power alone, seen from a
    /// point at squared distance `dist2` from its centre: its emitters face within
    /// [`SETTLED_COS`] of one direction and its bounding sphere's radius is at most
    /// 1/[`SETTLED_DISTANCE`] of the distance, so that its own children's importances would
    /// differ by little more than their power.
    #[inline(always)]
    fn settled(&self, k: usize, dist2: f32) -> bool {
        self.cos_theta_o[k] >= SETTLED_COS
            && dist2 >= SETTLED_DISTANCE * SETTLED_DISTANCE * self.radius2[k]
    }
}

/// Buckets per axis of the split search (pbrt-v4's value).
const BUCKETS: usize = 12;
/// Past this depth (in four-way levels) the build splits at the middle only, so that every
/// path fits in 64 bits (two bits a level).
const SAH_DEPTH: u32 = 16;
/// See [`Node::settled`]: within about 26 degrees.
const SETTLED_COS: f32 = 0.9;
/// See [`Node::settled`].
const SETTLED_DISTANCE: f32 = 8.0;

/// Where a light stands in the tree.
const OUTSIDE: u32 = u32::MAX;
const INFINITE: u32 = u32::MAX - 1;

/// pbrt-v4's `BVHLightSampler`, four children a node (see the module's documentation).
pub struct LightBvh {
    nodes: Vec<Node>,
    /// The lights in the tree, in the order of its leaves (each child's lights are a range).
    order: Vec<u32>,
    /// Running sums of the lights' power in that order (n + 1 values, from 0).
    cdf: Vec<f64>,
    /// Lights without bounds, chosen uniformly beside the tree.
    infinite: Vec<u32>,
    /// Per light: the path from the root to its leaf (two bits a level: the child taken).
    trails: Vec<u64>,
    /// Per light: its place in `order`, or [`OUTSIDE`] (no power), or [`INFINITE`].
    position: Vec<u32>,
}

impl LightBvh {
    /// Builds the tree over `lights`.
    pub fn new(lights: &[Light], world: &Geometry) -> Self {
        let mut infinite = Vec::new();
        let mut bounded = Vec::new();
        let mut position = vec![OUTSIDE; lights.len()];
        for (i, light) in lights.iter().enumerate() {
            match LightBounds::of(light, world) {
                None => {
                    infinite.push(i as u32);
                    position[i] = INFINITE;
                }
                Some(b)
                    if b.phi > 0.0
                        && b.phi.is_finite()
                        && b.lo.is_finite()
                        && b.hi.is_finite()
                        && i < INDEX as usize =>
                {
                    bounded.push((i as u32, b))
                }
                // No power, or not finite: never chosen (it sends nothing, or the scene's
                // checks have already warned).
                Some(_) => {}
            }
        }
        let mut bvh = Self {
            nodes: Vec::with_capacity(bounded.len() / 2 + 1),
            order: Vec::with_capacity(bounded.len()),
            cdf: Vec::with_capacity(bounded.len() + 1),
            infinite,
            trails: vec![0; lights.len()],
            position,
        };
        if !bounded.is_empty() {
            bvh.build(&mut bounded, 0, 0, 0);
        }
        // The build left each subtree's lights together in `bounded`.
        let mut sum = 0.0f64;
        bvh.cdf.push(0.0);
        for (k, (light, b)) in bounded.iter().enumerate() {
            bvh.order.push(*light);
            bvh.position[*light as usize] = k as u32;
            sum += b.phi as f64;
            bvh.cdf.push(sum);
        }
        bvh
    }

    /// Builds the node over `lights` (which start at `start` in the final order) and its
    /// subtrees, and returns the lights' bounds. A node takes the halves of the split, and
    /// the halves of each half that holds more than one light: up to four children.
    fn build(
        &mut self,
        lights: &mut [(u32, LightBounds)],
        start: usize,
        trail: u64,
        depth: u32,
    ) -> LightBounds {
        let index = self.nodes.len();
        self.nodes.push(Node::empty());
        let sah = depth < SAH_DEPTH;
        let mut groups: Vec<(usize, usize)> = Vec::with_capacity(4);
        if lights.len() == 1 {
            groups.push((0, 1));
        } else {
            let mid = split(lights, sah);
            for (a, b) in [(0, mid), (mid, lights.len())] {
                if b - a == 1 {
                    groups.push((a, b));
                } else {
                    let m = a + split(&mut lights[a..b], sah);
                    groups.extend([(a, m), (m, b)]);
                }
            }
        }
        let mut all: Option<LightBounds> = None;
        for (k, &(a, b)) in groups.iter().enumerate() {
            let range = (start + a, start + b);
            let trail = trail | (k as u64) << (2 * depth);
            let (bounds, link) = if b - a == 1 {
                let (light, bounds) = lights[a];
                self.trails[light as usize] = trail;
                (bounds, LEAF | light)
            } else {
                let child = self.nodes.len() as u32;
                let bounds = self.build(&mut lights[a..b], range.0, trail, depth + 1);
                (bounds, child)
            };
            self.nodes[index].set(k, &bounds, link, range);
            all = Some(all.map_or(bounds, |u| LightBounds::union(&u, &bounds)));
        }
        all.expect("a node has at least one light")
    }

    /// Probability of choosing among the lights without bounds.
    fn p_infinite(&self) -> f32 {
        let tree = usize::from(!self.nodes.is_empty());
        let n = self.infinite.len();
        if n == 0 {
            0.0
        } else {
            n as f32 / (n + tree) as f32
        }
    }

    /// Chooses a light at `ctx` with `u` in [0, 1): its index and probability; `None` when no
    /// light can reach the point.
    pub fn sample(&self, ctx: LightContext, u: f32) -> Option<(usize, f32)> {
        let p_inf = self.p_infinite();
        if u < p_inf {
            let n = self.infinite.len();
            let i = ((u / p_inf * n as f32) as usize).min(n - 1);
            return Some((self.infinite[i] as usize, p_inf / n as f32));
        }
        if self.nodes.is_empty() {
            return None;
        }
        let mut u = clamp_u((u - p_inf) / (1.0 - p_inf));
        let mut pmf = 1.0 - p_inf;
        let mut node = &self.nodes[0];
        loop {
            let (importance, dist2) = node.importance(ctx);
            let total = sum4(importance);
            if total == 0.0 {
                return None;
            }
            // The child whose part of the total holds u * total (past the last part, by
            // rounding: the last child that has one): the choice waits on no division.
            let target = u * total;
            let (mut k, mut below, mut start) = (4, 0.0, 0.0);
            for j in 0..4 {
                if importance[j] > 0.0 {
                    (k, start) = (j, below);
                    below += importance[j];
                    if target < below {
                        break;
                    }
                }
            }
            let w = importance[k];
            u = clamp_u((target - start) / w);
            pmf *= w / total;
            let link = node.links[k];
            if link & LEAF != 0 {
                return Some(((link & INDEX) as usize, pmf));
            }
            if node.settled(k, dist2[k]) {
                // By power within the child's range of the running sums.
                let (start, end) = (node.starts[k] as usize, node.ends[k] as usize);
                let power = self.cdf[end] - self.cdf[start];
                let target = self.cdf[start] + u as f64 * power;
                let i = start + self.cdf[start + 1..end].partition_point(|&c| c <= target);
                let p = (self.cdf[i + 1] - self.cdf[i]) / power;
                return Some((self.order[i] as usize, pmf * p as f32));
            }
            node = &self.nodes[link as usize];
        }
    }

    /// Probability that [`LightBvh::sample`] at `ctx` chooses light `light`.
    pub fn pmf(&self, ctx: LightContext, light: usize) -> f32 {
        let p_inf = self.p_infinite();
        let position = self.position.get(light).copied().unwrap_or(OUTSIDE);
        if position == INFINITE {
            return p_inf / self.infinite.len() as f32;
        }
        if position == OUTSIDE {
            return 0.0;
        }
        let mut pmf = 1.0 - p_inf;
        let mut trail = self.trails[light];
        let mut node = &self.nodes[0];
        loop {
            let (importance, dist2) = node.importance(ctx);
            let total = sum4(importance);
            if total == 0.0 {
                return 0.0;
            }
            let k = (trail & 3) as usize;
            trail >>= 2;
            pmf *= importance[k] / total;
            let link = node.links[k];
            if link & LEAF != 0 {
                return pmf;
            }
            if node.settled(k, dist2[k]) {
                let (start, end) = (node.starts[k] as usize, node.ends[k] as usize);
                let i = position as usize;
                let p = (self.cdf[i + 1] - self.cdf[i]) / (self.cdf[end] - self.cdf[start]);
                return pmf * p as f32;
            }
            node = &self.nodes[link as usize];
        }
    }

    /// Nodes in the tree (for tests and stats).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }
}

/// The sum of the four lanes, in the same order wherever it is taken.
#[inline(always)]
fn sum4(v: Vec4) -> f32 {
    (v.x + v.y) + (v.z + v.w)
}

/// Keeps a remapped sample in [0, 1).
#[inline(always)]
fn clamp_u(u: f32) -> f32 {
    u.clamp(0.0, 1.0 - f32::EPSILON / 2.0)
}

/// 1/sqrt(x) lane by lane (infinite at 0).
#[inline(always)]
fn rsqrt4(x: Vec4) -> Vec4 {
    // Exact (a square root and a division), not the processor's estimate: the estimate's
    // bits differ between x86 vendors and from aarch64, and a render's bytes should not.
    x.sqrt().recip()
}

#[inline(always)]
fn safe_sqrt4(x: Vec4) -> Vec4 {
    x.max(Vec4::ZERO).sqrt()
}

/// cos(max(0, a - b)) from the sines and cosines of a and b, lane by lane.
#[inline(always)]
fn cos_sub_clamped4(sin_a: Vec4, cos_a: Vec4, sin_b: Vec4, cos_b: Vec4) -> Vec4 {
    Vec4::select(cos_a.cmpgt(cos_b), Vec4::ONE, cos_a * cos_b + sin_a * sin_b)
}

/// Reorders `lights` and returns where the second child's lights start: pbrt-v4's bucketed
/// split by the cost of [`LightBounds::cost`] over the three axes (or the middle, when no
/// split has a cost, or `sah` is false).
fn split(lights: &mut [(u32, LightBounds)], sah: bool) -> usize {
    let half = lights.len() / 2;
    if !sah {
        return half;
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for (_, b) in lights.iter() {
        lo = lo.min(b.lo);
        hi = hi.max(b.hi);
        clo = clo.min(b.centroid());
        chi = chi.max(b.centroid());
    }
    let bucket = |b: &LightBounds, dim: usize| -> usize {
        let offset = (b.centroid()[dim] - clo[dim]) / (chi[dim] - clo[dim]);
        ((BUCKETS as f32 * offset) as usize).min(BUCKETS - 1)
    };
    let mut best: Option<(f32, usize, usize)> = None;
    for dim in 0..3 {
        if chi[dim] == clo[dim] {
            continue;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (_, b) in lights.iter() {
            let k = bucket(b, dim);
            buckets[k] = Some(buckets[k].map_or(*b, |a| LightBounds::union(&a, b)));
        }
        let union_of = |range: &[Option<LightBounds>]| {
            range
                .iter()
                .flatten()
                .fold(None, |acc: Option<LightBounds>, b| {
                    Some(acc.map_or(*b, |a| LightBounds::union(&a, b)))
                })
        };
        for i in 1..BUCKETS - 1 {
            let cost_of = |b: Option<LightBounds>| b.map_or(0.0, |b| b.cost((lo, hi), dim));
            let cost = cost_of(union_of(&buckets[..=i])) + cost_of(union_of(&buckets[i + 1..]));
            if cost > 0.0 && best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, dim, i));
            }
        }
    }
    let Some((_, dim, split_bucket)) = best else {
        return half;
    };
    // A stable partition: lights in buckets up to the split first.
    let (first, second): (Vec<_>, Vec<_>) = lights
        .iter()
        .partition(|(_, b)| bucket(b, dim) <= split_bucket);
    let mid = first.len();
    if mid == 0 || mid == lights.len() {
        return half;
    }
    for (slot, item) in lights.iter_mut().zip(first.into_iter().chain(second)) {
        *slot = item;
    }
    mid
}

#[cfg(test)]
mod tests;
