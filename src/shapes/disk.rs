//! pbrt-v3's disk: an annulus in the plane z = height, between innerradius and radius, cut at
//! phi = phimax.

use super::quadric::{phi_max_radians, phi_of, quadric_interaction, world_area};
use super::Transform;
use crate::geometry::{Ray, SurfaceInteraction, Vec2, Vec3};
use crate::sampling::concentric_sample_disk;
use std::f32::consts::PI;

/// A disk shape (pbrt-v3 `disk`). Build it with [`Disk::new`].
#[derive(Clone, Debug)]
pub struct Disk {
    /// Height of its plane (object z).
    pub height: f32,
    /// Outer radius.
    pub radius: f32,
    /// Inner radius.
    pub inner_radius: f32,
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

/// What [`Disk::interaction`] needs from [`Disk::intersect`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiskHit {
    /// Object-space hit point (z = height).
    pub p: Vec3,
    /// Its azimuth in [0, 2 pi).
    pub phi: f32,
}

impl Disk {
    /// From the shape's parameters (`phi_max_deg` in degrees), as pbrt-v3's constructor.
    pub fn new(
        height: f32,
        radius: f32,
        inner_radius: f32,
        phi_max_deg: f32,
        object_to_world: Transform,
        reverse_orientation: bool,
    ) -> Self {
        let mut d = Self {
            height,
            radius,
            inner_radius,
            phi_max: phi_max_radians(phi_max_deg),
            flip: reverse_orientation ^ object_to_world.swaps_handedness(),
            object_to_world,
            reverse_orientation,
            world_area: 0.0,
        };
        // A plane's areas all scale by the same factor.
        d.world_area = world_area(&object_to_world, d.object_area(), |_| Vec3::Z);
        d
    }

    /// Object-space bounds.
    pub fn object_bound(&self) -> (Vec3, Vec3) {
        (
            Vec3::new(-self.radius, -self.radius, self.height),
            Vec3::new(self.radius, self.radius, self.height),
        )
    }

    /// World-space bounds (the object bounds' corners transformed).
    pub fn world_bound(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.object_bound();
        self.object_to_world.bounds(lo, hi)
    }

    /// The hit with t in (0, t_max) (pbrt-v3 rejects t >= tMax for disks), in object space.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, DiskHit)> {
        let o = self.object_to_world.inv_point(ray.o);
        let d = self.object_to_world.inv_vector(ray.d);
        // Reject rays parallel to the disk's plane.
        if d.z == 0.0 {
            return None;
        }
        let t = (self.height - o.z) / d.z;
        if t.is_nan() || t <= 0.0 || t >= t_max {
            return None;
        }
        let mut p = o + d * t;
        let dist2 = p.x * p.x + p.y * p.y;
        if dist2 > self.radius * self.radius || dist2 < self.inner_radius * self.inner_radius {
            return None;
        }
        let phi = phi_of(p);
        if phi > self.phi_max {
            return None;
        }
        // Refine the hit point onto the plane.
        p.z = self.height;
        Some((t, DiskHit { p, phi }))
    }

    /// Any-hit variant of [`Disk::intersect`].
    #[inline]
    pub fn intersect_p(&self, ray: &Ray, t_max: f32) -> bool {
        self.intersect(ray, t_max).is_some()
    }

    /// The interaction at a hit: u = phi / phimax, v = 1 - (r - ri) / (radius - ri), pbrt-v3's
    /// dp/du and dp/dv, n = normalize(dpdu x dpdv) (+z) flipped by ReverseOrientation xor
    /// handedness swap, carried to world space.
    pub fn interaction(&self, ray: &Ray, _t: f32, hit: &DiskHit) -> SurfaceInteraction {
        let p = hit.p;
        let u = hit.phi / self.phi_max;
        let r_hit = (p.x * p.x + p.y * p.y).sqrt();
        let v = 1.0 - (r_hit - self.inner_radius) / (self.radius - self.inner_radius);
        // At the exact centre the derivatives are taken just beside it (pbrt-v3 divides by 0).
        let (px, py, r_d) = if r_hit > 0.0 {
            (p.x, p.y, r_hit)
        } else {
            (1e-5 * self.radius, 0.0, 1e-5 * self.radius)
        };
        let dpdu = Vec3::new(-self.phi_max * py, self.phi_max * px, 0.0);
        let dpdv = Vec3::new(px, py, 0.0) * (self.inner_radius - self.radius) / r_d;
        quadric_interaction(
            &self.object_to_world,
            self.flip,
            ray,
            p,
            Vec2::new(u, v),
            dpdu,
            dpdv,
            // A plane: pbrt-v3's dn/du = dn/dv = 0.
            None,
        )
    }

    /// pbrt-v3's `Area()`: the object-space area phimax (r^2 - ri^2) / 2.
    pub fn object_area(&self) -> f32 {
        self.phi_max * 0.5 * (self.radius * self.radius - self.inner_radius * self.inner_radius)
    }

    /// World-space area (exact for any affine transform).
    pub fn area(&self) -> f32 {
        self.world_area
    }

    /// A point uniform by area on the disk and its world normal, oriented as in interactions.
    /// A full disk uses pbrt-v3's concentric mapping; an annulus or a partial disk is sampled
    /// over its actual extent.
    pub fn sample_area(&self, u: Vec2) -> (Vec3, Vec3) {
        let p = if self.inner_radius == 0.0 && self.phi_max >= 2.0 * PI {
            let pd = concentric_sample_disk(u);
            Vec3::new(pd.x * self.radius, pd.y * self.radius, self.height)
        } else {
            let (ri2, r2) = (
                self.inner_radius * self.inner_radius,
                self.radius * self.radius,
            );
            let r = (ri2 + u.x * (r2 - ri2)).max(0.0).sqrt();
            let phi = u.y * self.phi_max;
            Vec3::new(r * phi.cos(), r * phi.sin(), self.height)
        };
        let n = self.object_to_world.normal(Vec3::Z).normalize_or(Vec3::Z);
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

    fn hit(d: &Disk, o: Vec3, dir: Vec3) -> Option<SurfaceInteraction> {
        let ray = Ray::new(o, dir, 0.0);
        d.intersect(&ray, f32::INFINITY).map(|(t, h)| {
            let si = d.interaction(&ray, t, &h);
            close3(si.p, ray.at(t), 1e-5 * (1.0 + t));
            si
        })
    }

    #[test]
    fn annulus_hit_matches_pbrt() {
        let d = Disk::new(1.0, 2.0, 0.5, 360.0, Transform::IDENTITY, false);
        let ray = Ray::new(Vec3::new(1.0, 0.0, 5.0), -Vec3::Z, 0.0);
        let (t, h) = d.intersect(&ray, f32::INFINITY).unwrap();
        close(t, 4.0, 1e-6);
        let si = d.interaction(&ray, t, &h);
        close3(si.p, Vec3::new(1.0, 0.0, 1.0), 1e-6);
        close3(si.n, Vec3::Z, 1e-6);
        close(si.uv.x, 0.0, 1e-6);
        close(si.uv.y, 1.0 - 0.5 / 1.5, 1e-6);
        close3(si.dpdu, Vec3::new(0.0, 2.0 * PI, 0.0), 1e-5);
        close3(si.dpdv, Vec3::new(-1.5, 0.0, 0.0), 1e-6);
        // From below the normal stays +z.
        let si = hit(&d, Vec3::new(0.0, -1.0, -3.0), Vec3::Z).unwrap();
        close3(si.n, Vec3::Z, 1e-6);
        close(si.uv.x, 0.75, 1e-6);
        // The hole, outside, parallel, behind, t_max (strict, as pbrt-v3 for disks).
        assert!(hit(&d, Vec3::new(0.2, 0.0, 5.0), -Vec3::Z).is_none());
        assert!(hit(&d, Vec3::new(2.1, 0.0, 5.0), -Vec3::Z).is_none());
        assert!(hit(&d, Vec3::new(1.0, 0.0, 1.0), Vec3::X).is_none());
        assert!(hit(&d, Vec3::new(1.0, 0.0, 5.0), Vec3::Z).is_none());
        assert!(d.intersect(&ray, 4.0).is_none());
        assert!(d.intersect(&ray, 4.001).is_some());
        close(d.area(), PI * (4.0 - 0.25), 1e-5);
    }

    #[test]
    fn partial_disk_and_centre() {
        let d = Disk::new(0.0, 1.0, 0.0, 90.0, Transform::IDENTITY, false);
        assert!(hit(&d, Vec3::new(0.5, 0.5, 1.0), -Vec3::Z).is_some());
        assert!(hit(&d, Vec3::new(-0.5, 0.5, 1.0), -Vec3::Z).is_none());
        assert!(hit(&d, Vec3::new(0.5, -0.5, 1.0), -Vec3::Z).is_none());
        let si = hit(&d, Vec3::new(1e-3, 0.5, 1.0), -Vec3::Z).unwrap();
        close(si.uv.x, 1.0, 3e-3);
        // The exact centre gives finite derivatives.
        let full = Disk::new(0.0, 1.0, 0.0, 360.0, Transform::IDENTITY, false);
        let si = hit(&full, Vec3::new(0.0, 0.0, 1.0), -Vec3::Z).unwrap();
        assert!(si.dpdu.is_finite() && si.dpdv.is_finite() && si.dpdu.length() > 0.0);
        close3(si.n, Vec3::Z, 0.0);
        close(si.uv.y, 1.0, 0.0);
    }

    #[test]
    fn transformed_disk_orientation() {
        // Rotated so that its normal is +y, translated, scaled non-uniformly.
        let m = Mat4::from_translation(Vec3::new(0.0, 3.0, 0.0))
            * Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2)
            * Mat4::from_scale(Vec3::new(2.0, 1.0, 5.0));
        for (rev, mirror, sign) in [
            (false, false, 1.0),
            (true, false, -1.0),
            (false, true, -1.0),
            (true, true, 1.0),
        ] {
            let mm = if mirror {
                m * Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0))
            } else {
                m
            };
            let d = Disk::new(0.0, 1.0, 0.0, 360.0, Transform::new(mm), rev);
            let si = hit(&d, Vec3::new(0.5, 10.0, 0.2), -Vec3::Y).unwrap();
            close3(si.p, Vec3::new(0.5, 3.0, 0.2), 1e-5);
            close3(si.n, Vec3::Y * sign, 1e-5);
            let (p, n) = d.sample_area(Vec2::new(0.2, 0.9));
            close(p.y, 3.0, 1e-5);
            close3(n, si.n, 1e-6);
            // An ellipse with semi-axes 2 and 1.
            close(d.area(), 2.0 * PI, 1e-4);
        }
    }

    #[test]
    fn sample_area_is_uniform_on_the_surface() {
        let m =
            Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)) * Mat4::from_scale(Vec3::splat(2.0));
        for d in [
            Disk::new(0.5, 1.0, 0.0, 360.0, Transform::IDENTITY, false),
            Disk::new(-1.0, 2.0, 0.5, 200.0, Transform::new(m), false),
        ] {
            let (lo, hi) = d.world_bound();
            let s = d.object_to_world.similarity_scale().unwrap();
            let mut rng = Rng::new(4);
            let n = 40000;
            let mut r2 = 0.0f64;
            for _ in 0..n {
                let (p, nn) = d.sample_area(rng.v2());
                assert!(p.cmpge(lo - 1e-4).all() && p.cmple(hi + 1e-4).all());
                close3(nn, Vec3::Z, 1e-6);
                let po = d.object_to_world.inv_point(p);
                close(po.z, d.height, 1e-5);
                let rr = po.truncate().length();
                assert!(rr >= d.inner_radius - 1e-5 && rr <= d.radius + 1e-5);
                let phi = phi_of(po);
                assert!(phi <= d.phi_max + 1e-4 || phi >= 2.0 * PI - 1e-4);
                r2 += (rr * rr) as f64;
            }
            // The integral of r^2 over the surface: phimax (r^4 - ri^4) / 4.
            let est = d.area() as f64 * r2 / n as f64;
            let exact = d.phi_max * (d.radius.powi(4) - d.inner_radius.powi(4)) / 4.0 * s * s;
            close(est as f32, exact, 0.02 * exact);
            // Solid angle seen from a point on the axis, estimated by area sampling.
            if d.inner_radius == 0.0 {
                let h = 1.5;
                let q = Vec3::new(0.0, 0.0, d.height + h);
                let mut sum = 0.0f64;
                for _ in 0..n {
                    let (p, nn) = d.sample_area(rng.v2());
                    let w = q - p;
                    sum += (nn.dot(w.normalize()) / w.length_squared()) as f64;
                }
                let est = sum * d.area() as f64 / n as f64;
                let exact = 2.0 * PI * (1.0 - h / (h * h + d.radius * d.radius).sqrt());
                close(est as f32, exact, 0.01 * exact);
            }
        }
    }
}
