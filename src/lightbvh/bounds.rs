//! What bounds a light's emission (pbrt-v4's `LightBounds` and `DirectionCone`): a box, a
//! cone of normals with the angle past it over which light leaves, and an upper bound on power.

use crate::accel::{Geometry, PrimKind};
use crate::geometry::Vec3;
use crate::light::Light;
use crate::shapes::triangle::shading_normal;
use std::f32::consts::PI;

/// A cone of directions: unit axis `w` and the cosine of its half-angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct DirectionCone {
    pub(super) w: Vec3,
    pub(super) cos_theta: f32,
}

impl DirectionCone {
    /// Every direction.
    pub(super) const SPHERE: Self = Self {
        w: Vec3::Z,
        cos_theta: -1.0,
    };

    /// The smallest cone (as pbrt-v4 computes it) holding both.
    pub(super) fn union(a: Self, b: Self) -> Self {
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
    pub(super) lo: Vec3,
    /// Spatial bounds: greatest corner.
    pub(super) hi: Vec3,
    /// Axis of the cone of surface normals (or emission directions).
    pub(super) w: Vec3,
    /// Emitted power (an upper bound; a sum for a group).
    pub(super) phi: f32,
    /// Cosine of the spread of the normals around `w`.
    pub(super) cos_theta_o: f32,
    /// Cosine of the angle past the normals over which light is emitted.
    pub(super) cos_theta_e: f32,
    /// Emits on both sides of its normals.
    pub(super) two_sided: bool,
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
            // As pbrt-v4's GoniometricLight::Bounds: a point light whose power is its mean over
            // the image (4 pi I times the mean of each pixel's largest channel), every direction.
            Light::Goniometric {
                pos,
                intensity,
                map,
                ..
            } => Some(Self {
                lo: *pos,
                hi: *pos,
                w: Vec3::Z,
                phi: 4.0
                    * PI
                    * map
                        .as_ref()
                        .map_or(intensity.max_element(), |m| m.mean_max(*intensity)),
                cos_theta_o: -1.0,
                cos_theta_e: 0.0,
                two_sided: false,
            }),
            // As pbrt-v4's ProjectionLight::Bounds: one axis (theta_o = 0) and the frustum's cone
            // past it; power as a point light's, times the image's mean, like the spot's (the
            // cone is accounted for by the importance).
            Light::Projection {
                pos,
                light_from_world,
                intensity,
                projection,
            } => {
                let (w, cos_e) = projection.world_cone(&light_from_world.inverse());
                let all = cos_e <= -1.0;
                Some(Self {
                    lo: *pos,
                    hi: *pos,
                    w,
                    phi: 4.0
                        * PI
                        * projection
                            .map()
                            .map_or(intensity.max_element(), |m| m.mean_max(*intensity)),
                    cos_theta_o: if all { -1.0 } else { 1.0 },
                    cos_theta_e: if all { 0.0 } else { cos_e },
                    two_sided: false,
                })
            }
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

    pub(super) fn centroid(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }

    pub(super) fn surface_area(&self) -> f32 {
        let d = self.hi - self.lo;
        2.0 * (d.x * d.y + d.x * d.z + d.y * d.z)
    }

    /// Both bounds together (a bound with no power adds nothing).
    pub(super) fn union(a: &Self, b: &Self) -> Self {
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
    pub(super) fn cost(&self, parent: (Vec3, Vec3), dim: usize) -> f32 {
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

#[inline]
pub(super) fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

#[inline]
pub(super) fn safe_acos(x: f32) -> f32 {
    x.clamp(-1.0, 1.0).acos()
}

/// The angle between two unit vectors, accurate near 0 and pi (pbrt-v4's `AngleBetween`).
pub(super) fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() / 2.0).clamp(-1.0, 1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).clamp(-1.0, 1.0).asin()
    }
}
