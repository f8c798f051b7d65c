//! pbrt-v3's cylinder: x^2 + y^2 = r^2 around the object z axis, for z in [zmin, zmax] and
//! phi in [0, phimax] (no caps).

use super::quadric::{
    nearest_root, phi_max_radians, phi_of, quadratic_roots, quadric_interaction, world_area,
};
use super::Transform;
use crate::geometry::{Ray, SurfaceInteraction, Vec2, Vec3};

/// A cylinder shape (pbrt-v3 `cylinder`). Build it with [`Cylinder::new`].
#[derive(Clone, Debug)]
pub struct Cylinder {
    /// Radius.
    pub radius: f32,
    /// Lower end (object z).
    pub z_min: f32,
    /// Upper end (object z).
    pub z_max: f32,
    /// Maximum azimuth in radians, in [0, 2 pi].
    pub phi_max: f32,
    /// Object to world.
    pub object_to_world: Transform,
    /// The shape's ReverseOrientation flag.
    pub reverse_orientation: bool,
    /// ReverseOrientation xor the transform swaps handedness.
    flip: bool,
    /// World-space area.
    world_area: f32,
}

/// What [`Cylinder::interaction`] needs from [`Cylinder::intersect`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CylinderHit {
    /// Object-space hit point, re-projected onto the cylinder.
    pub p: Vec3,
    /// Its azimuth in [0, 2 pi).
    pub phi: f32,
}

impl Cylinder {
    /// From the shape's parameters (`phi_max_deg` in degrees), as pbrt-v3's constructor orders
    /// and clamps them.
    pub fn new(
        radius: f32,
        z_min: f32,
        z_max: f32,
        phi_max_deg: f32,
        object_to_world: Transform,
        reverse_orientation: bool,
    ) -> Self {
        let mut c = Self {
            radius,
            z_min: z_min.min(z_max),
            z_max: z_min.max(z_max),
            phi_max: phi_max_radians(phi_max_deg),
            flip: reverse_orientation ^ object_to_world.swaps_handedness(),
            object_to_world,
            reverse_orientation,
            world_area: 0.0,
        };
        let phi_max = c.phi_max;
        c.world_area = world_area(&object_to_world, c.object_area(), |u| {
            let phi = u.y * phi_max;
            Vec3::new(phi.cos(), phi.sin(), 0.0)
        });
        c
    }

    /// Object-space bounds.
    pub fn object_bound(&self) -> (Vec3, Vec3) {
        (
            Vec3::new(-self.radius, -self.radius, self.z_min),
            Vec3::new(self.radius, self.radius, self.z_max),
        )
    }

    /// World-space bounds (the object bounds' corners transformed).
    pub fn world_bound(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.object_bound();
        self.object_to_world.bounds(lo, hi)
    }

    /// The object-space hit point at `t` re-projected onto the cylinder, and its azimuth.
    #[inline]
    fn hit_at(&self, o: Vec3, d: Vec3, t: f32) -> (Vec3, f32) {
        let mut p = o + d * t;
        let hit_rad = (p.x * p.x + p.y * p.y).sqrt();
        p.x *= self.radius / hit_rad;
        p.y *= self.radius / hit_rad;
        (p, phi_of(p))
    }

    /// Whether the z range or phimax removes the point.
    #[inline]
    fn clipped(&self, p: Vec3, phi: f32) -> bool {
        p.z < self.z_min || p.z > self.z_max || phi > self.phi_max
    }

    /// The closest hit with t in (0, t_max]: the ray is taken to object space and the quadratic
    /// solved in double precision (in place of pbrt-v3's EFloat); when the nearer root is cut
    /// away the farther one is tried, as in pbrt-v3.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, CylinderHit)> {
        let o = self.object_to_world.inv_point(ray.o);
        let d = self.object_to_world.inv_vector(ray.d);
        let (ox, oy, dx, dy) = (o.x as f64, o.y as f64, d.x as f64, d.y as f64);
        let r = self.radius as f64;
        let a = dx * dx + dy * dy;
        if a == 0.0 {
            return None;
        }
        let b = 2.0 * (dx * ox + dy * oy);
        let c = ox * ox + oy * oy - r * r;
        // Discriminant without cancellation: 4 a (r^2 - |o_xy - (b / 2a) d_xy|^2).
        let f = b / (2.0 * a);
        let (vx, vy) = (ox - f * dx, oy - f * dy);
        let l = (vx * vx + vy * vy).sqrt();
        let discrim = 4.0 * a * (r + l) * (r - l);
        let roots = quadratic_roots(a, b, c, discrim)?;
        nearest_root(roots, t_max, |t| {
            let (p, phi) = self.hit_at(o, d, t);
            (!self.clipped(p, phi)).then_some(CylinderHit { p, phi })
        })
    }

    /// Any-hit variant of [`Cylinder::intersect`].
    #[inline]
    pub fn intersect_p(&self, ray: &Ray, t_max: f32) -> bool {
        self.intersect(ray, t_max).is_some()
    }

    /// The interaction at a hit: u = phi / phimax, v = (z - zmin) / (zmax - zmin), pbrt-v3's
    /// dp/du and dp/dv, n = normalize(dpdu x dpdv) (outward) flipped by ReverseOrientation xor
    /// handedness swap, carried to world space.
    pub fn interaction(&self, ray: &Ray, _t: f32, hit: &CylinderHit) -> SurfaceInteraction {
        let p = hit.p;
        let u = hit.phi / self.phi_max;
        let v = (p.z - self.z_min) / (self.z_max - self.z_min);
        let dpdu = Vec3::new(-self.phi_max * p.y, self.phi_max * p.x, 0.0);
        let dpdv = Vec3::new(0.0, 0.0, self.z_max - self.z_min);
        let pm = self.phi_max;
        let second = [-pm * pm * Vec3::new(p.x, p.y, 0.0), Vec3::ZERO, Vec3::ZERO];
        quadric_interaction(
            &self.object_to_world,
            self.flip,
            ray,
            p,
            Vec2::new(u, v),
            dpdu,
            dpdv,
            Some(second),
        )
    }

    /// pbrt-v3's `Area()`: the object-space area (zmax - zmin) phimax r.
    pub fn object_area(&self) -> f32 {
        (self.z_max - self.z_min) * self.phi_max * self.radius
    }

    /// World-space area: exact when the transform scales the plane perpendicular to the axis
    /// uniformly; otherwise the object area times the transform's mean area scale over the
    /// surface.
    pub fn area(&self) -> f32 {
        self.world_area
    }

    /// pbrt-v3's `Cylinder::Sample(u)`: z = lerp(u0, zmin, zmax), phi = u1 phimax; the point in
    /// world space and its world normal, oriented as in interactions.
    pub fn sample_area(&self, u: Vec2) -> (Vec3, Vec3) {
        let z = (1.0 - u.x) * self.z_min + u.x * self.z_max;
        let phi = u.y * self.phi_max;
        let p = Vec3::new(self.radius * phi.cos(), self.radius * phi.sin(), z);
        let n = self
            .object_to_world
            .normal(Vec3::new(p.x, p.y, 0.0))
            .normalize_or(Vec3::X);
        (
            self.object_to_world.point(p),
            if self.flip { -n } else { n },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::geometry::Mat4;
    use std::f32::consts::PI;

    fn hit(c: &Cylinder, o: Vec3, dir: Vec3) -> Option<SurfaceInteraction> {
        let ray = Ray::new(o, dir, 0.0);
        c.intersect(&ray, f32::INFINITY).map(|(t, h)| {
            let si = c.interaction(&ray, t, &h);
            close3(si.p, ray.at(t), 1e-5 * (1.0 + t));
            si
        })
    }

    fn unit() -> Cylinder {
        Cylinder::new(1.0, -1.0, 1.0, 360.0, Transform::IDENTITY, false)
    }

    #[test]
    fn cylinder_hit_matches_pbrt() {
        let c = unit();
        let ray = Ray::new(Vec3::new(-5.0, 0.0, 0.5), Vec3::X, 0.0);
        let (t, h) = c.intersect(&ray, f32::INFINITY).unwrap();
        close(t, 4.0, 1e-6);
        let si = c.interaction(&ray, t, &h);
        close3(si.p, Vec3::new(-1.0, 0.0, 0.5), 1e-6);
        close3(si.n, -Vec3::X, 1e-6);
        close(si.uv.x, 0.5, 1e-6);
        close(si.uv.y, 0.75, 1e-6);
        close3(si.dpdu, Vec3::new(0.0, -2.0 * PI, 0.0), 1e-5);
        close3(si.dpdv, Vec3::new(0.0, 0.0, 2.0), 0.0);
        // From inside: the far wall, normal outward.
        let si = hit(&c, Vec3::ZERO, Vec3::new(0.0, 2.0, 0.0)).unwrap();
        close3(si.p, Vec3::Y, 1e-6);
        close3(si.n, Vec3::Y, 1e-6);
        // Beyond the ends, parallel to the axis, behind, t_max.
        assert!(hit(&c, Vec3::new(-5.0, 0.0, 1.5), Vec3::X).is_none());
        assert!(hit(&c, Vec3::new(0.5, 0.0, -5.0), Vec3::Z).is_none());
        assert!(hit(&c, Vec3::new(-5.0, 0.0, 0.0), -Vec3::X).is_none());
        assert!(c.intersect(&ray, 3.99).is_none());
        assert!(c.intersect(&ray, 4.0).is_some());
        // Through an open end: hits the inside of the wall.
        let si = hit(&c, Vec3::new(0.0, 0.0, 1.5), Vec3::new(0.5, 0.0, -1.0)).unwrap();
        close3(si.p, Vec3::new(1.0, 0.0, -0.5), 1e-5);
        close3(si.n, Vec3::X, 1e-6);
        // Aimed at the wall above the top end: both roots are cut.
        assert!(hit(&c, Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.5, 0.0, -1.0)).is_none());
        close(c.area(), 4.0 * PI, 1e-5);
    }

    #[test]
    fn partial_cylinder_uses_the_second_root() {
        let c = Cylinder::new(1.0, 1.0, -1.0, 90.0, Transform::IDENTITY, false);
        assert_eq!((c.z_min, c.z_max), (-1.0, 1.0));
        // The near hit (phi = pi) is cut; the far one (phi = 0) is not.
        let si = hit(&c, Vec3::new(-5.0, 0.0, 0.5), Vec3::X).unwrap();
        close3(si.p, Vec3::new(1.0, 0.0, 0.5), 1e-6);
        close3(si.n, Vec3::X, 1e-6);
        close(si.uv.x, 0.0, 1e-6);
        // Both cut: miss.
        assert!(hit(&c, Vec3::new(-5.0, -0.5, 0.0), Vec3::X).is_none());
        // The second root beyond t_max: miss.
        let ray = Ray::new(Vec3::new(-5.0, 0.0, 0.5), Vec3::X, 0.0);
        assert!(c.intersect(&ray, 5.5).is_none());
        close(c.object_area(), PI, 1e-6);
    }

    #[test]
    fn transformed_cylinder_orientation() {
        // Axis along world x, stretched along it, translated.
        let m = Mat4::from_translation(Vec3::new(0.0, 0.0, 2.0))
            * Mat4::from_rotation_y(std::f32::consts::FRAC_PI_2)
            * Mat4::from_scale(Vec3::new(1.0, 1.0, 3.0));
        for (rev, mirror, sign) in [
            (false, false, 1.0),
            (true, false, -1.0),
            (false, true, -1.0),
            (true, true, 1.0),
        ] {
            let mm = if mirror {
                m * Mat4::from_scale(Vec3::new(1.0, 1.0, -1.0))
            } else {
                m
            };
            let c = Cylinder::new(0.5, -1.0, 1.0, 360.0, Transform::new(mm), rev);
            let si = hit(&c, Vec3::new(2.0, 0.0, 10.0), -Vec3::Z).unwrap();
            close3(si.p, Vec3::new(2.0, 0.0, 2.5), 1e-5);
            close3(si.n, Vec3::Z * sign, 1e-5);
            let (p, n) = c.sample_area(Vec2::new(0.3, 0.1));
            let radial = Vec3::new(0.0, p.y, p.z - 2.0).normalize();
            close3(n, radial * sign, 1e-5);
            // Length 6, radius 0.5.
            close(c.area(), 6.0 * PI, 1e-3);
            let (lo, hi) = c.world_bound();
            assert!(p.cmpge(lo - 1e-5).all() && p.cmple(hi + 1e-5).all());
        }
    }

    #[test]
    fn sample_area_is_uniform_on_the_surface() {
        let m = Mat4::from_rotation_x(0.5) * Mat4::from_scale(Vec3::splat(2.0));
        for c in [
            unit(),
            Cylinder::new(0.7, -0.2, 1.5, 250.0, Transform::new(m), false),
        ] {
            let (lo, hi) = c.world_bound();
            let s = c.object_to_world.similarity_scale().unwrap();
            let mut rng = Rng::new(8);
            let n = 40000;
            let mut z2 = 0.0f64;
            for _ in 0..n {
                let (p, nn) = c.sample_area(rng.v2());
                assert!(p.cmpge(lo - 1e-4).all() && p.cmple(hi + 1e-4).all());
                let po = c.object_to_world.inv_point(p);
                close(po.truncate().length(), c.radius, 1e-5);
                assert!(po.z >= c.z_min - 1e-5 && po.z <= c.z_max + 1e-5);
                let phi = phi_of(po);
                assert!(phi <= c.phi_max + 1e-4 || phi >= 2.0 * PI - 1e-4);
                let radial = c
                    .object_to_world
                    .vector(Vec3::new(po.x, po.y, 0.0))
                    .normalize();
                close3(nn, radial, 1e-5);
                z2 += (po.z * po.z) as f64;
            }
            // The integral of z^2 over the surface: phimax r (zmax^3 - zmin^3) / 3.
            let est = c.area() as f64 * z2 / n as f64;
            let exact = c.phi_max * c.radius * (c.z_max.powi(3) - c.z_min.powi(3)) / 3.0 * s * s;
            close(est as f32, exact, 0.02 * exact);
        }
    }
}
