//! The quadrics pbrt-v3 intersects but cannot sample: cone, paraboloid and hyperboloid. Each is
//! a profile (its implicit equation, azimuth, z range and differential geometry, one file per
//! shape); this file holds what they share: the object-space ray, the quadratic, the choice of
//! root, the cut by z range and azimuth, and the interaction in world space.

use super::cone::Cone;
use super::hyperboloid::Hyperboloid;
use super::paraboloid::Paraboloid;
use super::profile::Profile;
use super::quadric::{nearest_root, quadratic_roots, quadric_interaction};
use super::Transform;
use crate::geometry::{Ray, SurfaceInteraction, Vec3};
use acr_parser::{ParamList, ParamType, Result};

/// A profile placed in the world, cut at phi = phi_max.
#[derive(Clone, Debug)]
pub struct Placed<P> {
    /// The shape's own parameters.
    pub profile: P,
    /// Maximum azimuth in radians, in [0, 2 pi].
    pub phi_max: f32,
    /// Object to world.
    pub object_to_world: Transform,
    /// ReverseOrientation xor the transform swaps handedness.
    flip: bool,
}

/// Where a ray meets a surface of revolution (object space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RevolvedHit {
    /// Object-space hit point.
    pub p: Vec3,
    /// Its azimuth.
    pub phi: f32,
}

impl<P: Profile> Placed<P> {
    /// Places `profile`; `phi_max_deg` in degrees, clamped to [0, 360] as pbrt-v3 does.
    pub fn new(
        profile: P,
        phi_max_deg: f32,
        object_to_world: Transform,
        reverse_orientation: bool,
    ) -> Self {
        Self {
            profile,
            phi_max: super::quadric::phi_max_radians(phi_max_deg),
            flip: reverse_orientation ^ object_to_world.swaps_handedness(),
            object_to_world,
        }
    }

    /// World-space bounds.
    pub fn world_bound(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.profile.object_bound();
        self.object_to_world.bounds(lo, hi)
    }

    /// The closest hit with t in (0, t_max], as pbrt-v3: the quadratic in object space (in
    /// double precision, in place of pbrt-v3's EFloat), the hit point at the root in single
    /// precision, the farther root when the nearer is cut by the z range or phi_max.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, RevolvedHit)> {
        let o = self.object_to_world.inv_point(ray.o);
        let d = self.object_to_world.inv_vector(ray.d);
        let (a, b, c) = self.profile.coefficients(o.as_dvec3(), d.as_dvec3());
        // a = 0 (a ray along a paraboloid's axis, or parallel to a cone's side): one root,
        // which pbrt-v3's Quadratic finds too (its other root is infinite).
        let roots = if a == 0.0 {
            let t = -c / b;
            t.is_finite().then_some((t, t))?
        } else {
            quadratic_roots(a, b, c, b * b - 4.0 * a * c)?
        };
        let (z_min, z_max) = self.profile.z_range();
        nearest_root(roots, t_max, |t| {
            let p = o + d * t;
            let phi = self.profile.phi(p);
            let kept = p.z >= z_min && p.z <= z_max && phi <= self.phi_max;
            kept.then_some(RevolvedHit { p, phi })
        })
    }

    /// The interaction at a hit: the profile's parametrisation, n = normalize(dpdu x dpdv)
    /// flipped by ReverseOrientation xor handedness swap, in world space.
    pub fn interaction(&self, ray: &Ray, hit: &RevolvedHit) -> SurfaceInteraction {
        let (uv, dpdu, dpdv, second) = self.profile.geometry(hit.p, hit.phi, self.phi_max);
        quadric_interaction(
            &self.object_to_world,
            self.flip,
            ray,
            hit.p,
            uv,
            dpdu,
            dpdv,
            Some(second),
        )
    }
}

/// The three shapes, for the BVH's one primitive kind.
#[derive(Clone, Debug)]
pub enum Revolved {
    /// pbrt-v3's `cone`.
    Cone(Placed<Cone>),
    /// pbrt-v3's `paraboloid`.
    Paraboloid(Placed<Paraboloid>),
    /// pbrt-v3's `hyperboloid`.
    Hyperboloid(Placed<Hyperboloid>),
}

impl Revolved {
    /// World-space bounds.
    pub fn world_bound(&self) -> (Vec3, Vec3) {
        match self {
            Self::Cone(s) => s.world_bound(),
            Self::Paraboloid(s) => s.world_bound(),
            Self::Hyperboloid(s) => s.world_bound(),
        }
    }

    /// The closest hit with t in (0, t_max].
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, RevolvedHit)> {
        match self {
            Self::Cone(s) => s.intersect(ray, t_max),
            Self::Paraboloid(s) => s.intersect(ray, t_max),
            Self::Hyperboloid(s) => s.intersect(ray, t_max),
        }
    }

    /// The interaction at a hit.
    pub fn interaction(&self, ray: &Ray, hit: &RevolvedHit) -> SurfaceInteraction {
        match self {
            Self::Cone(s) => s.interaction(ray, hit),
            Self::Paraboloid(s) => s.interaction(ray, hit),
            Self::Hyperboloid(s) => s.interaction(ray, hit),
        }
    }
}

/// Builds a `cone`, `paraboloid` or `hyperboloid` from its parameters with pbrt-v3's defaults.
/// The outer error is a malformed parameter; the inner one says why a shape with no surface
/// (zero radius or height, a flat or axial hyperboloid) is skipped.
pub fn from_params(
    kind: &str,
    params: &ParamList,
    object_to_world: Transform,
    reverse_orientation: bool,
) -> Result<std::result::Result<Revolved, String>> {
    let phi_max = params.float_or("phimax", 360.0)? as f32;
    let positive = |what: &str, v: f32| {
        (v > 0.0 && v.is_finite())
            .then_some(())
            .ok_or_else(|| format!("{kind}: {what} is {v}; the shape has no area and is skipped"))
    };
    Ok(match kind {
        "cone" => {
            let radius = params.float_or("radius", 1.0)? as f32;
            let height = params.float_or("height", 1.0)? as f32;
            positive("radius", radius)
                .and(positive("height", height))
                .map(|()| {
                    Revolved::Cone(Placed::new(
                        Cone { radius, height },
                        phi_max,
                        object_to_world,
                        reverse_orientation,
                    ))
                })
        }
        "paraboloid" => {
            let radius = params.float_or("radius", 1.0)? as f32;
            let z0 = params.float_or("zmin", 0.0)? as f32;
            let z1 = params.float_or("zmax", 1.0)? as f32;
            let s = Paraboloid::new(radius, z0, z1);
            positive("radius", radius)
                .and(positive("zmax", s.z_max))
                .and(positive("zmax - zmin", s.z_max - s.z_min.max(0.0)))
                .map(|()| {
                    Revolved::Paraboloid(Placed::new(
                        s,
                        phi_max,
                        object_to_world,
                        reverse_orientation,
                    ))
                })
        }
        _ => {
            let point = |name: &str, default: Vec3| -> Result<Vec3> {
                Ok(params.vec3(name, ParamType::Point3)?.map_or(default, |a| {
                    Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
                }))
            };
            let p1 = point("p1", Vec3::ZERO)?;
            let p2 = point("p2", Vec3::ONE)?;
            Hyperboloid::new(p1, p2)
                .map(|h| {
                    Revolved::Hyperboloid(Placed::new(
                        h,
                        phi_max,
                        object_to_world,
                        reverse_orientation,
                    ))
                })
                .ok_or_else(|| {
                    format!(
                        "hyperboloid: p1 {p1} and p2 {p2} sweep no hyperboloid (equal heights or \
                         a segment on the axis; pbrt-v3 loops for ever here); the shape is skipped"
                    )
                })
        }
    })
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::geometry::Mat4;

    /// The three shapes of `tests/data/pbrt-v3/revolvedcheck.cpp`, placed as there.
    fn shapes() -> [Revolved; 3] {
        let t0 = Mat4::from_translation(Vec3::new(0.2, -0.1, 0.3))
            * Mat4::from_rotation_x(30f32.to_radians());
        let t1 =
            Mat4::from_rotation_y(-20f32.to_radians()) * Mat4::from_scale(Vec3::new(1.0, 1.0, 1.5));
        let t2 = Mat4::from_translation(Vec3::new(0.0, 0.0, -0.4))
            * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let cone = Cone {
            radius: 0.8,
            height: 1.3,
        };
        let hyp = Hyperboloid::new(Vec3::new(0.4, 0.1, -0.5), Vec3::new(0.3, 0.6, 0.7)).unwrap();
        [
            Revolved::Cone(Placed::new(cone, 300.0, Transform::new(t0), false)),
            Revolved::Paraboloid(Placed::new(
                Paraboloid::new(0.9, 0.2, 1.1),
                270.0,
                Transform::new(t1),
                true,
            )),
            Revolved::Hyperboloid(Placed::new(hyp, 330.0, Transform::new(t2), false)),
        ]
    }

    /// Rays against pbrt-v3's own cone, paraboloid and hyperboloid (transformed, one reversed,
    /// one mirrored): the same hits and misses, t, point, normal, uv, dp/du, dp/dv, dn/du and
    /// dn/dv; the areas as pbrt-v3's `Area()`.
    #[test]
    fn hits_match_pbrt_v3() {
        let shapes = shapes();
        let data = include_str!("../../tests/data/pbrt-v3/revolved-hits.txt");
        let mut hits = [0; 3];
        for line in data.lines() {
            let w: Vec<&str> = line.split_whitespace().collect();
            if w[0] == "area" {
                let s: usize = w[1].parse().unwrap();
                let area = match &shapes[s] {
                    Revolved::Cone(c) => c.profile.object_area(c.phi_max),
                    Revolved::Paraboloid(c) => c.profile.object_area(c.phi_max),
                    Revolved::Hyperboloid(c) => c.profile.object_area(c.phi_max),
                };
                let want: f32 = w[2].parse().unwrap();
                close(area, want, 1e-5 * want);
                continue;
            }
            let f = |i: usize| -> f32 { w[i].parse().unwrap() };
            let v3 = |i: usize| Vec3::new(f(i), f(i + 1), f(i + 2));
            let s: usize = w[0].parse().unwrap();
            let ray = Ray::new(v3(1), v3(4), 0.0);
            let got = shapes[s].intersect(&ray, f32::INFINITY);
            if w[7] == "miss" {
                assert!(got.is_none(), "acr hits where pbrt-v3 misses:\n{line}");
                continue;
            }
            let (t, h) = got.unwrap_or_else(|| panic!("acr misses where pbrt-v3 hits:\n{line}"));
            hits[s] += 1;
            assert!((t - f(8)).abs() <= 1e-4 * f(8), "t {t}\n{line}");
            let si = shapes[s].interaction(&ray, &h);
            close_rel(si.p, v3(9), 1e-4, "p", line);
            close_rel(si.n, v3(12), 1e-4, "n", line);
            close(si.uv.x, f(15), 1e-4);
            close(si.uv.y, f(16), 1e-4);
            close_rel(si.dpdu, v3(17), 1e-4, "dpdu", line);
            close_rel(si.dpdv, v3(20), 1e-4, "dpdv", line);
            close_rel(si.dndu, v3(23), 1e-3, "dndu", line);
            close_rel(si.dndv, v3(26), 1e-3, "dndv", line);
        }
        assert_eq!(hits, [51, 49, 99]);
    }

    /// Hyperboloids with no surface are refused (pbrt-v3 loops for ever on them), and the
    /// points where pbrt-v3's derivatives divide by zero (cone apex, paraboloid vertex) give
    /// finite geometry.
    #[test]
    fn degenerate_parameters_are_refused() {
        assert!(Hyperboloid::new(Vec3::new(1.0, 0.0, 0.5), Vec3::new(0.0, 1.0, 0.5)).is_none());
        assert!(Hyperboloid::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0)).is_none());
        assert!(Hyperboloid::new(Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)).is_none());
        // pbrt-v3's default, p1 at the origin and p2 at (1, 1, 1), is a cone through the origin:
        // its coefficients divide by zero at every step and pbrt-v3 never returns.
        assert!(Hyperboloid::new(Vec3::ZERO, Vec3::ONE).is_none());
        // Apex and vertex: finite geometry where pbrt-v3 divides by zero.
        let cone = Placed::new(
            Cone {
                radius: 1.0,
                height: 1.0,
            },
            360.0,
            Transform::IDENTITY,
            false,
        );
        let ray = Ray::new(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z, 0.0);
        let (t, h) = cone.intersect(&ray, f32::INFINITY).unwrap();
        close(t, 2.0, 1e-6);
        let si = cone.interaction(&ray, &h);
        assert!(si.n.is_finite() && si.dpdv.is_finite() && si.dndu.is_finite());
        let para = Placed::new(
            Paraboloid::new(1.0, 0.0, 1.0),
            360.0,
            Transform::IDENTITY,
            false,
        );
        let (t, h) = para.intersect(&ray, f32::INFINITY).unwrap();
        close(t, 3.0, 1e-6);
        let si = para.interaction(&ray, &h);
        assert!(si.n.is_finite() && si.dpdv.is_finite() && si.dndv.is_finite());
    }
}
