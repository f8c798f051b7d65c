//! pbrt-v4's light BVH (`BVHLightSampler`): the lights that have bounds (point, spot, area)
//! in a binary tree of their bounds, emission cones and power; a light is chosen by walking
//! down from the root, taking each child in proportion to an importance that bounds what its
//! lights can send to the shading point. Choosing and its probability are O(depth). Lights
//! without bounds (distant, infinite) are chosen uniformly beside the tree.

use crate::accel::{Geometry, PrimKind};
use crate::geometry::Vec3;
use crate::light::Light;
use crate::shapes::triangle::shading_normal;
use glam::Vec4;
use std::f32::consts::PI;

/// Where a light is chosen from: the shading point and its shading normal (zero for a point
/// in a medium, where no cosine applies).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightContext {
    /// The shading point.
    pub p: Vec3,
    /// The shading normal, or zero.
    pub n: Vec3,
}

/// A cone of directions: unit axis `w` and the cosine of its half-angle.
#[derive(Clone, Copy, Debug, PartialEq)]
struct DirectionCone {
    w: Vec3,
    cos_theta: f32,
}

impl DirectionCone {
    /// Every direction.
    const SPHERE: Self = Self {
        w: Vec3::Z,
        cos_theta: -1.0,
    };

    /// The smallest cone (as pbrt-v4 computes it) holding both.
    fn union(a: Self, b: Self) -> Self {
        let theta_a = safe_acos(a.cos_theta);
        let theta_b = safe_acos(b.cos_theta);
        let theta_d = angle_between(a.w, b.w);
        if (theta_d + theta_b).min(PI) <= theta_a {
            return a;
        }
        if (theta_d + theta_a).min(PI) <= theta_b {
            return b;
        }
        let theta_o = (theta_a + theta_d + theta_b) / 2.0;
        if theta_o >= PI {
            return Self::SPHERE;
        }
        // Rotate a's axis towards b's by theta_o - theta_a.
        let wr = a.w.cross(b.w);
        if wr.length_squared() == 0.0 {
            return Self::SPHERE;
        }
        let rotation = glam::Quat::from_axis_angle(wr.normalize(), theta_o - theta_a);
        Self {
            w: (rotation * a.w).normalize(),
            cos_theta: theta_o.cos(),
        }
    }
}

/// What bounds a light's (or a group of lights') emission, as pbrt-v4's `LightBounds`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// Spatial bounds: least corner.
    lo: Vec3,
    /// Spatial bounds: greatest corner.
    hi: Vec3,
    /// Axis of the cone of surface normals (or emission directions).
    w: Vec3,
    /// Emitted power (an upper bound; a sum for a group).
    phi: f32,
    /// Cosine of the spread of the normals around `w`.
    cos_theta_o: f32,
    /// Cosine of the angle past the normals over which light is emitted.
    cos_theta_e: f32,
    /// Emits on both sides of its normals.
    two_sided: bool,
}

impl LightBounds {
    /// The bounds of `light`; `None` for lights without a position (distant, infinite).
    pub fn of(light: &Light, world: &Geometry) -> Option<Self> {
        match light {
            Light::Point { pos, intensity } => Some(Self {
                lo: *pos,
                hi: *pos,
                w: Vec3::Z,
                phi: 4.0 * PI * intensity.max_element(),
                cos_theta_o: -1.0,
                cos_theta_e: 0.0,
                two_sided: false,
            }),
            Light::Spot {
                pos,
                light_from_world,
                intensity,
                cos_total,
                cos_falloff_start,
            } => Some(Self {
                lo: *pos,
                hi: *pos,
                w: light_from_world
                    .transpose()
                    .transform_vector3(Vec3::Z)
                    .normalize(),
                phi: 4.0 * PI * intensity.max_element(),
                cos_theta_o: *cos_falloff_start,
                cos_theta_e: (safe_acos(*cos_total) - safe_acos(*cos_falloff_start)).cos(),
                two_sided: false,
            }),
            Light::Distant { .. } | Light::Infinite { .. } => None,
            Light::Area {
                shape,
                l_emit,
                two_sided,
                area,
            } => {
                let (lo, hi) = world.kind_bounds(shape.kind);
                let normals = normal_bounds(world, shape.kind);
                Some(Self {
                    lo,
                    hi,
                    w: normals.w,
                    phi: l_emit.max_element() * area * PI,
                    cos_theta_o: normals.cos_theta,
                    cos_theta_e: 0.0,
                    // Normals that disagree in side across a triangle: emission on either side.
                    two_sided: *two_sided || normals.cos_theta < -0.5,
                })
            }
        }
    }

    fn centroid(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }

    fn surface_area(&self) -> f32 {
        let d = self.hi - self.lo;
        2.0 * (d.x * d.y + d.x * d.z + d.y * d.z)
    }

    /// Both bounds together (a bound with no power adds nothing).
    fn union(a: &Self, b: &Self) -> Self {
        if a.phi == 0.0 {
            return *b;
        }
        if b.phi == 0.0 {
            return *a;
        }
        let cone = DirectionCone::union(
            DirectionCone {
                w: a.w,
                cos_theta: a.cos_theta_o,
            },
            DirectionCone {
                w: b.w,
                cos_theta: b.cos_theta_o,
            },
        );
        Self {
            lo: a.lo.min(b.lo),
            hi: a.hi.max(b.hi),
            w: cone.w,
            phi: a.phi + b.phi,
            cos_theta_o: cone.cos_theta,
            cos_theta_e: a.cos_theta_e.min(b.cos_theta_e),
            two_sided: a.two_sided || b.two_sided,
        }
    }

    /// pbrt-v4's `EvaluateCost`: power times the measure of the emission directions times
    /// the surface area, stretched for thin boxes split along their short side.
    fn cost(&self, parent: (Vec3, Vec3), dim: usize) -> f32 {
        let theta_o = safe_acos(self.cos_theta_o);
        let theta_e = safe_acos(self.cos_theta_e);
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_theta_o = safe_sqrt(1.0 - self.cos_theta_o * self.cos_theta_o);
        let m_omega = 2.0 * PI * (1.0 - self.cos_theta_o)
            + PI / 2.0
                * (2.0 * theta_w * sin_theta_o
                    - (theta_o - 2.0 * theta_w).cos()
                    - 2.0 * theta_o * sin_theta_o
                    + self.cos_theta_o);
        let diagonal = parent.1 - parent.0;
        let kr = diagonal.max_element() / diagonal[dim];
        self.phi * m_omega * kr * self.surface_area()
    }
}

/// The cone of a primitive's emitting normals: a triangle's own (on the side its hits report),
/// every direction for the curved shapes and disks.
fn normal_bounds(world: &Geometry, kind: PrimKind) -> DirectionCone {
    let PrimKind::Triangle { mesh, tri } = kind else {
        return DirectionCone::SPHERE;
    };
    let m = &world.meshes[mesh as usize];
    let [p0, p1, p2] = m.vertices(tri as usize);
    let ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
    if ng == Vec3::ZERO {
        return DirectionCone::SPHERE;
    }
    if m.normals.is_some() {
        // Hits turn the geometric normal towards the interpolated shading normal; its side is
        // the same all over the triangle when the three vertices agree.
        let side =
            |b: [f32; 3]| shading_normal(m, tri as usize, b).map_or(0.0, |n| n.dot(ng).signum());
        let sides = [
            side([1.0, 0.0, 0.0]),
            side([0.0, 1.0, 0.0]),
            side([0.0, 0.0, 1.0]),
        ];
        return if sides.iter().all(|&s| s > 0.0) {
            DirectionCone {
                w: ng,
                cos_theta: 1.0,
            }
        } else if sides.iter().all(|&s| s < 0.0) {
            DirectionCone {
                w: -ng,
                cos_theta: 1.0,
            }
        } else {
            // Both sides: a sphere's cone, and the bounds emit on both sides.
            DirectionCone::SPHERE
        };
    }
    let w = if m.reverse_orientation ^ m.transform_swaps_handedness {
        -ng
    } else {
        ng
    };
    DirectionCone { w, cos_theta: 1.0 }
}

/// Up to four children of a node, side by side so that their importances are computed at
/// once (one SIMD lane each): what [`Node::importance`] needs of each child's bounds, derived
/// once, and each child's link and range of lights. An empty slot has no power.
#[derive(Clone, Copy, Debug)]
struct Node {
    cx: Vec4,
    cy: Vec4,
    cz: Vec4,
    /// Squared radius of the sphere around each child's bounds.
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
    #[inline(always)]
    fn importance(&self, ctx: LightContext) -> (Vec4, Vec4) {
        let dx = Vec4::splat(ctx.p.x) - self.cx;
        let dy = Vec4::splat(ctx.p.y) - self.cy;
        let dz = Vec4::splat(ctx.p.z) - self.cz;
        let dist2 = dx * dx + dy * dy + dz * dz;
        // Reciprocals rather than divisions: the distance's, and the floored squared one's
        // (infinite for a point at a point light, whose importance is then 0).
        let away = dist2.cmpgt(Vec4::ZERO);
        let inv = Vec4::select(away, dist2.sqrt().recip(), Vec4::ZERO);
        let inv_d2 = Vec4::select(away, (inv * inv).min(self.inv_d2_floor), self.inv_d2_floor);
        let (wix, wiy, wiz) = (dx * inv, dy * inv, dz * inv);
        let cos_w = self.wx * wix + self.wy * wiy + self.wz * wiz;
        let cos_w = Vec4::select(self.two_sided.cmpgt(Vec4::ZERO), cos_w.abs(), cos_w);
        let sin_w = safe_sqrt4(Vec4::ONE - cos_w * cos_w);
        // The cone from the point that holds each child's sphere (every direction inside it).
        let inside = dist2.cmplt(self.radius2);
        let sin2_b = self.radius2 * inv * inv;
        let cos_b = Vec4::select(inside, Vec4::NEG_ONE, safe_sqrt4(Vec4::ONE - sin2_b));
        let sin_b = Vec4::select(inside, Vec4::ZERO, safe_sqrt4(sin2_b));
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
            let cos_i = (wix * ctx.n.x + wiy * ctx.n.y + wiz * ctx.n.z).abs();
            let sin_i = safe_sqrt4(Vec4::ONE - cos_i * cos_i);
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
            // The child whose share of the total holds u (past the last share, by rounding:
            // the last child that has one).
            let (mut k, mut below, mut start) = (4, 0.0, 0.0);
            for j in 0..4 {
                if importance[j] > 0.0 {
                    (k, start) = (j, below);
                    below += importance[j] / total;
                    if u < below {
                        break;
                    }
                }
            }
            below = start;
            let p = importance[k] / total;
            u = clamp_u((u - below) / p);
            pmf *= p;
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

#[inline]
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

#[inline]
fn safe_acos(x: f32) -> f32 {
    x.clamp(-1.0, 1.0).acos()
}

/// The angle between two unit vectors, accurate near 0 and pi (pbrt-v4's `AngleBetween`).
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() / 2.0).clamp(-1.0, 1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).clamp(-1.0, 1.0).asin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::Geometry;
    use crate::geometry::Spectrum;
    use crate::light::AreaShape;
    use crate::shapes::{Transform, TriangleMesh};

    /// A small deterministic generator for test inputs.
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }
        fn vec(&mut self, scale: f32) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * 2.0 * scale - Vec3::splat(scale)
        }
    }

    /// `n` one-sided triangles scattered and turned every way, a point light, a spot light and
    /// a distant light; the world holding the triangles.
    fn scene(n: usize, seed: u64) -> (Vec<Light>, Geometry) {
        let mut rng = Lcg(seed);
        let mut positions = Vec::new();
        for _ in 0..n {
            let c = rng.vec(5.0);
            for _ in 0..3 {
                positions.push(c + rng.vec(0.3));
            }
        }
        let mesh = acr_parser::Mesh {
            positions: positions.iter().map(|p| p.to_array()).collect(),
            normals: None,
            uvs: None,
            indices: (0..3 * n as u32).collect(),
        };
        let mut world = Geometry::default();
        world
            .meshes
            .push(TriangleMesh::from_mesh(&mesh, &Transform::IDENTITY, false));
        let mut lights: Vec<Light> = (0..n)
            .map(|tri| {
                let kind = PrimKind::Triangle {
                    mesh: 0,
                    tri: tri as u32,
                };
                Light::Area {
                    shape: AreaShape { kind },
                    l_emit: Spectrum::new(1.0 + rng.next(), 1.0, 0.5),
                    two_sided: tri % 5 == 0,
                    area: crate::light::prim_area(&world, kind),
                }
            })
            .collect();
        lights.push(Light::Point {
            pos: Vec3::new(0.0, 6.0, 0.0),
            intensity: Spectrum::splat(20.0),
        });
        lights.push(Light::Spot {
            pos: Vec3::new(2.0, 6.0, 0.0),
            light_from_world: crate::light::spot_frame(Vec3::NEG_Y),
            intensity: Spectrum::splat(30.0),
            cos_total: 30f32.to_radians().cos(),
            cos_falloff_start: 25f32.to_radians().cos(),
        });
        lights.push(Light::Distant {
            w: Vec3::Y,
            radiance: Spectrum::ONE,
            world_radius: 10.0,
        });
        (lights, world)
    }

    fn contexts(count: usize, seed: u64) -> Vec<LightContext> {
        let mut rng = Lcg(seed);
        (0..count)
            .map(|i| LightContext {
                p: rng.vec(8.0),
                n: if i % 7 == 0 {
                    Vec3::ZERO
                } else {
                    rng.vec(1.0).normalize_or(Vec3::Z)
                },
            })
            .collect()
    }

    #[test]
    fn probabilities_sum_to_one_and_sampling_reports_them() {
        for n in [1, 2, 3, 5, 64, 1000] {
            let (lights, world) = scene(n, n as u64);
            let bvh = LightBvh::new(&lights, &world);
            for ctx in contexts(40, 7 + n as u64) {
                let pmfs: Vec<f32> = (0..lights.len()).map(|i| bvh.pmf(ctx, i)).collect();
                let total: f64 = pmfs.iter().map(|&p| p as f64).sum();
                // At most 1: as in pbrt-v4, the walk stops (no light) at a node whose bounds
                // prove that none of its lights reaches the point, and that mass is lost.
                assert!(total <= 1.0 + 1e-4, "n {n}: total {total}");
                // The distant light alone is chosen with 1/2, whatever the tree does.
                assert!(total >= 0.5 - 1e-6, "n {n}: total {total}");
                // Stratified u: the share of walks that choose nothing is the lost mass, and
                // every choice reports the probability pmf() gives it.
                let count = 4000;
                let mut none = 0;
                for j in 0..count {
                    match bvh.sample(ctx, (j as f32 + 0.5) / count as f32) {
                        Some((i, p)) => {
                            assert!(p > 0.0, "n {n}: chosen with probability 0");
                            let q = pmfs[i];
                            assert!((p - q).abs() <= 1e-5 * q, "n {n}: sample {p} != pmf {q}");
                        }
                        None => none += 1,
                    }
                }
                let lost = none as f64 / count as f64;
                assert!(
                    (lost - (1.0 - total)).abs() < 2e-3,
                    "n {n}: {lost} of the walks chose nothing, lost mass {}",
                    1.0 - total
                );
            }
        }
    }

    #[test]
    fn choices_follow_the_probabilities() {
        // 30 lights, one point; the frequencies of 200,000 stratified choices against pmf.
        let (lights, world) = scene(30, 3);
        let bvh = LightBvh::new(&lights, &world);
        let ctx = LightContext {
            p: Vec3::new(0.5, -1.0, 0.2),
            n: Vec3::Y,
        };
        let draws = 200_000;
        let mut counts = vec![0u32; lights.len()];
        for j in 0..draws {
            let u = (j as f32 + 0.5) / draws as f32;
            if let Some((i, _)) = bvh.sample(ctx, u) {
                counts[i] += 1;
            }
        }
        for (i, &c) in counts.iter().enumerate() {
            let expected = bvh.pmf(ctx, i) as f64 * draws as f64;
            assert!(
                (c as f64 - expected).abs() <= 4.0 + 1e-3 * expected,
                "light {i}: {c} choices, expected {expected}"
            );
        }
    }

    #[test]
    fn a_one_sided_emitter_is_never_chosen_from_behind() {
        // A triangle facing +z (counter-clockwise seen from +z) and a point light.
        let mesh = acr_parser::Mesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: None,
            uvs: None,
            indices: vec![0, 1, 2],
        };
        let mut world = Geometry::default();
        world
            .meshes
            .push(TriangleMesh::from_mesh(&mesh, &Transform::IDENTITY, false));
        let kind = PrimKind::Triangle { mesh: 0, tri: 0 };
        let lights = vec![
            Light::Area {
                shape: AreaShape { kind },
                l_emit: Spectrum::ONE,
                two_sided: false,
                area: 0.5,
            },
            Light::Point {
                pos: Vec3::new(0.0, 0.0, -5.0),
                intensity: Spectrum::ONE,
            },
        ];
        let bvh = LightBvh::new(&lights, &world);
        let behind = LightContext {
            p: Vec3::new(0.2, 0.2, -1.0),
            n: Vec3::Z,
        };
        assert_eq!(bvh.pmf(behind, 0), 0.0);
        assert_eq!(bvh.pmf(behind, 1), 1.0);
        let front = LightContext {
            p: Vec3::new(0.2, 0.2, 1.0),
            n: Vec3::Z,
        };
        assert!(bvh.pmf(front, 0) > 0.5, "{}", bvh.pmf(front, 0));
        // Alone, from behind, nothing can be chosen.
        let alone = LightBvh::new(&lights[..1], &world);
        assert_eq!(alone.sample(behind, 0.3), None);
        assert_eq!(alone.sample(front, 0.3).map(|(i, _)| i), Some(0));
    }

    /// pbrt-v4's `LightBounds::Importance`, transcribed on its own (scalar, with divisions),
    /// to check the tree's four-lane version against.
    fn pbrt_importance(b: &LightBounds, ctx: LightContext) -> f32 {
        let cos_sub = |sa: f32, ca: f32, sb: f32, cb: f32| {
            if ca > cb {
                1.0
            } else {
                ca * cb + sa * sb
            }
        };
        let sin_sub = |sa: f32, ca: f32, sb: f32, cb: f32| {
            if ca > cb {
                0.0
            } else {
                sa * cb - ca * sb
            }
        };
        let pc = (b.lo + b.hi) / 2.0;
        let d2 = ctx.p.distance_squared(pc).max((b.hi - b.lo).length() / 2.0);
        let wi = (ctx.p - pc).normalize();
        let mut cos_w = b.w.dot(wi);
        if b.two_sided {
            cos_w = cos_w.abs();
        }
        let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
        let r2 = b.lo.distance_squared(pc);
        let cos_b = if ctx.p.distance_squared(pc) < r2 {
            -1.0
        } else {
            (1.0 - r2 / ctx.p.distance_squared(pc)).max(0.0).sqrt()
        };
        let sin_b = (1.0 - cos_b * cos_b).max(0.0).sqrt();
        let sin_o = (1.0 - b.cos_theta_o * b.cos_theta_o).max(0.0).sqrt();
        let cos_x = cos_sub(sin_w, cos_w, sin_o, b.cos_theta_o);
        let sin_x = sin_sub(sin_w, cos_w, sin_o, b.cos_theta_o);
        let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
        if cos_p <= b.cos_theta_e {
            return 0.0;
        }
        let mut importance = b.phi * cos_p / d2;
        if ctx.n != Vec3::ZERO {
            let cos_i = wi.dot(ctx.n).abs();
            let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
            importance *= cos_sub(sin_i, cos_i, sin_b, cos_b);
        }
        importance.max(0.0)
    }

    #[test]
    fn importance_is_pbrt_v4_s() {
        let (lights, world) = scene(12, 5);
        let bounds: Vec<LightBounds> = lights
            .iter()
            .filter_map(|l| LightBounds::of(l, &world))
            .collect();
        // Single lights and unions of several, four to a node.
        let mut groups: Vec<LightBounds> = bounds.clone();
        for w in bounds.windows(3) {
            groups.push(LightBounds::union(&LightBounds::union(&w[0], &w[1]), &w[2]));
        }
        for chunk in groups.chunks(4) {
            let mut node = Node::empty();
            for (k, b) in chunk.iter().enumerate() {
                node.set(k, b, 0, (0, 1));
            }
            for ctx in contexts(200, 11) {
                let (lanes, _) = node.importance(ctx);
                for (k, b) in chunk.iter().enumerate() {
                    let want = pbrt_importance(b, ctx);
                    let got = lanes[k];
                    assert!(
                        (got - want).abs() <= 1e-3 * want.abs() + 1e-6,
                        "{got} != {want} at {ctx:?} for {b:?}"
                    );
                }
                for k in chunk.len()..4 {
                    assert_eq!(lanes[k], 0.0, "an empty slot has no importance");
                }
            }
        }
    }

    #[test]
    fn cone_union_holds_both_cones() {
        let mut rng = Lcg(9);
        for _ in 0..500 {
            let a = DirectionCone {
                w: rng.vec(1.0).normalize_or(Vec3::Z),
                cos_theta: rng.next() * 2.0 - 1.0,
            };
            let b = DirectionCone {
                w: rng.vec(1.0).normalize_or(Vec3::X),
                cos_theta: rng.next() * 2.0 - 1.0,
            };
            let u = DirectionCone::union(a, b);
            // Each cone's axis and its rim towards the other's axis lie within the union.
            for c in [a, b] {
                let slack = 1e-4;
                assert!(u.w.dot(c.w) >= u.cos_theta - slack);
                let angle = angle_between(u.w, c.w) + safe_acos(c.cos_theta);
                assert!(angle <= safe_acos(u.cos_theta) + 1e-3 || u.cos_theta <= -1.0);
            }
        }
    }

    #[test]
    fn degenerate_lights_stay_out_of_the_tree() {
        let lights = vec![
            Light::Point {
                pos: Vec3::ZERO,
                intensity: Spectrum::ZERO,
            },
            Light::Point {
                pos: Vec3::splat(f32::NAN),
                intensity: Spectrum::ONE,
            },
            Light::Point {
                pos: Vec3::ONE,
                intensity: Spectrum::ONE,
            },
        ];
        let bvh = LightBvh::new(&lights, &Geometry::default());
        let ctx = LightContext {
            p: Vec3::ZERO,
            n: Vec3::ZERO,
        };
        assert_eq!(bvh.pmf(ctx, 0), 0.0);
        assert_eq!(bvh.pmf(ctx, 1), 0.0);
        assert_eq!(bvh.pmf(ctx, 2), 1.0);
        assert_eq!(bvh.sample(ctx, 0.99).map(|(i, _)| i), Some(2));
        let none = LightBvh::new(&[], &Geometry::default());
        assert_eq!(none.sample(ctx, 0.5), None);
        assert_eq!(none.node_count(), 0);
    }
}
