//! pbrt-v3's sphere: a (possibly partial) sphere around the object-space origin, cut by
//! z in [zmin, zmax] and phi in [0, phimax].

use super::coordinate_system;
use super::quadric::{
    nearest_root, phi_max_radians, phi_of, quadratic_roots, quadric_interaction, quadric_normal,
    world_area,
};
use super::Transform;
use crate::geometry::{Crossing, Ray, SurfaceInteraction, Vec2, Vec3};
use crate::sampling::uniform_sample_sphere;
use std::f32::consts::PI;

/// A sphere shape (pbrt-v3 `sphere`). Build it with [`Sphere::new`].
#[derive(Clone, Debug)]
pub struct Sphere {
    /// Radius.
    pub radius: f32,
    /// Lower z cut, clamped to [-radius, radius].
    pub z_min: f32,
    /// Upper z cut, clamped to [-radius, radius].
    pub z_max: f32,
    /// pbrt-v3's thetaMin: acos(zmin / radius) (the larger polar angle).
    pub theta_min: f32,
    /// pbrt-v3's thetaMax: acos(zmax / radius).
    pub theta_max: f32,
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
    /// The transform's uniform scale when it is a similarity.
    similarity: Option<f32>,
    /// World centre and radius for cone sampling (full spheres under similarities), computed
    /// once: [`Sphere::cone`] runs for every light sample.
    cone_base: Option<(Vec3, f64)>,
}

/// What [`Sphere::interaction`] needs from [`Sphere::intersect`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereHit {
    /// Object-space hit point, re-projected onto the sphere.
    pub p: Vec3,
    /// Its azimuth in [0, 2 pi), or -1 where not computed yet (full spheres).
    pub phi: f32,
}

/// The sphere's tangents at a point and the angles they come from.
struct SphereTangents {
    theta: f32,
    /// thetaMax - thetaMin.
    dtheta: f32,
    cos_phi: f32,
    sin_phi: f32,
    dpdu: Vec3,
    dpdv: Vec3,
}

impl Sphere {
    /// From the shape's parameters (`phi_max_deg` in degrees) as pbrt-v3's constructor clamps
    /// them.
    pub fn new(
        radius: f32,
        z_min: f32,
        z_max: f32,
        phi_max_deg: f32,
        object_to_world: Transform,
        reverse_orientation: bool,
    ) -> Self {
        let (lo, hi) = (z_min.min(z_max), z_min.max(z_max));
        let mut s = Self {
            radius,
            z_min: lo.clamp(-radius, radius),
            z_max: hi.clamp(-radius, radius),
            theta_min: (lo / radius).clamp(-1.0, 1.0).acos(),
            theta_max: (hi / radius).clamp(-1.0, 1.0).acos(),
            phi_max: phi_max_radians(phi_max_deg),
            flip: reverse_orientation ^ object_to_world.swaps_handedness(),
            similarity: object_to_world.similarity_scale(),
            object_to_world,
            reverse_orientation,
            world_area: 0.0,
            cone_base: None,
        };
        let t = s.object_to_world;
        s.world_area = world_area(&t, s.object_area(), |u| s.sample_object(u).normalize());
        s.cone_base = s
            .similarity
            .filter(|_| s.is_full())
            .map(|scale| (t.point(Vec3::ZERO), (s.radius * scale).abs() as f64));
        s
    }

    /// Whether no part is cut away (z range and azimuth complete).
    pub fn is_full(&self) -> bool {
        self.z_min <= -self.radius && self.z_max >= self.radius && self.phi_max >= 2.0 * PI
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

    /// The object-space hit point at `t` re-projected onto the sphere, and its azimuth.
    #[inline]
    fn hit_at(&self, o: Vec3, d: Vec3, t: f32) -> (Vec3, f32) {
        let mut p = o + d * t;
        p *= self.radius / p.length();
        if p.x == 0.0 && p.y == 0.0 {
            p.x = 1e-5 * self.radius;
        }
        // Only a partial sphere needs phi to clip; a full one computes it in `interaction`,
        // for the one hit that is kept (atan2 per candidate hit is measurable).
        let phi = if self.is_full() { -1.0 } else { phi_of(p) };
        (p, phi)
    }

    /// Whether the partial-shape cuts remove the point.
    #[inline]
    fn clipped(&self, p: Vec3, phi: f32) -> bool {
        (self.z_min > -self.radius && p.z < self.z_min)
            || (self.z_max < self.radius && p.z > self.z_max)
            || phi > self.phi_max
    }

    /// The closest hit with t in (0, t_max]: the ray is taken to object space and the quadratic
    /// solved in double precision (in place of pbrt-v3's EFloat); when the nearer root is cut
    /// away by zmin/zmax/phimax the farther one is tried, as in pbrt-v3.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, SphereHit)> {
        let o = self.object_to_world.inv_point(ray.o);
        let d = self.object_to_world.inv_vector(ray.d);
        if self.clearly_missed(o, d) {
            return None;
        }
        self.intersect_object(o, d, t_max)
    }

    /// [`Sphere::intersect`] for the object-space ray `o + t d`, without the early miss test.
    #[inline]
    fn intersect_object(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, SphereHit)> {
        let (od, dd) = (o.as_dvec3(), d.as_dvec3());
        let r = self.radius as f64;
        let a = dd.length_squared();
        if a == 0.0 {
            return None;
        }
        let b = 2.0 * dd.dot(od);
        let c = od.length_squared() - r * r;
        // Discriminant without cancellation (pbrt-v4): 4 a (r^2 - |o - (b / 2a) d|^2).
        let l = (od - dd * (b / (2.0 * a))).length();
        let discrim = 4.0 * a * (r + l) * (r - l);
        let roots = quadratic_roots(a, b, c, discrim)?;
        nearest_root(roots, t_max, |t| {
            let (p, phi) = self.hit_at(o, d, t);
            (!self.clipped(p, phi)).then_some(SphereHit { p, phi })
        })
    }

    /// Whether the line through object-space `o` along `d` passes so far from the sphere that
    /// the exact test below must find no root: a test in f32 without division or square root,
    /// which most rays that reach a sphere's box and miss it take. Its margin, 10^-5 of
    /// |o|^2 |d|^2, is 16 times the rounding error of the f32 expression (a few ulps of that
    /// product), so it rejects only lines whose squared distance from the centre exceeds r^2
    /// by more than both tests' errors: the same result as the f64 test, never a lost hit.
    #[inline]
    fn clearly_missed(&self, o: Vec3, d: Vec3) -> bool {
        let (oo, dd, od) = (o.dot(o), d.dot(d), o.dot(d));
        let r2 = self.radius * self.radius;
        // |d|^2 times the squared distance from the centre to the line, minus r^2 |d|^2.
        let excess = (oo * dd - od * od) - r2 * dd;
        excess > 1e-5 * (oo * dd) && (oo * dd).is_finite()
    }

    /// Any-hit variant of [`Sphere::intersect`].
    #[inline]
    pub fn intersect_p(&self, ray: &Ray, t_max: f32) -> bool {
        self.intersect(ray, t_max).is_some()
    }

    /// The interaction at a hit: u = phi / phimax, v = (theta - thetaMin) / (thetaMax -
    /// thetaMin), pbrt-v3's dp/du and dp/dv, n = normalize(dpdu x dpdv) (outward) flipped by
    /// ReverseOrientation xor handedness swap, then carried to world space.
    pub fn interaction(&self, ray: &Ray, _t: f32, hit: &SphereHit) -> SurfaceInteraction {
        let p = hit.p;
        let phi = if hit.phi < 0.0 { phi_of(p) } else { hit.phi };
        let u = phi / self.phi_max;
        let t = self.tangents(p);
        let v = (t.theta - self.theta_min) / t.dtheta;
        let (pm, dtheta) = (self.phi_max, t.dtheta);
        let second = [
            -pm * pm * Vec3::new(p.x, p.y, 0.0),
            dtheta * p.z * pm * Vec3::new(-t.sin_phi, t.cos_phi, 0.0),
            -dtheta * dtheta * p,
        ];
        quadric_interaction(
            &self.object_to_world,
            self.flip,
            ray,
            p,
            Vec2::new(u, v),
            t.dpdu,
            t.dpdv,
            Some(second),
        )
    }

    /// The point and normal of a hit without the (u, v) (an atan2), tangents (an acos and a
    /// sine) or normal derivatives of [`Sphere::interaction`]: dp/du x dp/dv is -phimax
    /// (thetaMax - thetaMin) r sin(theta) p, outward wherever the sphere is not degenerate
    /// (thetaMin > thetaMax, phimax > 0), so the object-space normal is p / r, oriented and
    /// carried to world space as the interaction's. It equals the interaction's normal to a
    /// few ulps, not bit for bit (docs/media.md).
    #[inline]
    pub fn crossing(&self, ray: &Ray, hit: &SphereHit) -> Crossing {
        let n = if self.phi_max > 0.0 && self.theta_min > self.theta_max {
            let n_obj = hit.p.normalize_or(Vec3::Z);
            let n_obj = if self.flip { -n_obj } else { n_obj };
            self.object_to_world.normal(n_obj).normalize_or(n_obj)
        } else {
            let t = self.tangents(hit.p);
            quadric_normal(&self.object_to_world, self.flip, t.dpdu, t.dpdv)
        };
        Crossing {
            p: self.object_to_world.point(hit.p),
            n,
            p_error: 0.0,
            time: ray.time,
        }
    }

    /// pbrt-v3's dp/du and dp/dv at object-space point `p` and the angles they come from.
    #[inline]
    fn tangents(&self, p: Vec3) -> SphereTangents {
        let theta = (p.z / self.radius).clamp(-1.0, 1.0).acos();
        let dtheta = self.theta_max - self.theta_min;
        let z_radius = (p.x * p.x + p.y * p.y).sqrt();
        let cos_phi = p.x / z_radius;
        let sin_phi = p.y / z_radius;
        SphereTangents {
            theta,
            dtheta,
            cos_phi,
            sin_phi,
            dpdu: Vec3::new(-self.phi_max * p.y, self.phi_max * p.x, 0.0),
            dpdv: dtheta * Vec3::new(p.z * cos_phi, p.z * sin_phi, -self.radius * theta.sin()),
        }
    }

    /// pbrt-v3's `Area()`: the object-space area phimax r (zmax - zmin).
    pub fn object_area(&self) -> f32 {
        self.phi_max * self.radius * (self.z_max - self.z_min)
    }

    /// World-space area: exact for similarity transforms; for others, the object area times the
    /// mean area scale of the transform over the surface.
    pub fn area(&self) -> f32 {
        self.world_area
    }

    /// An object-space point, uniform by area on the (partial) sphere.
    #[inline]
    fn sample_object(&self, u: Vec2) -> Vec3 {
        let p = if self.is_full() {
            // pbrt-v3's Sphere::Sample(u).
            self.radius * uniform_sample_sphere(u)
        } else {
            // Uniform in z and phi is uniform by area (Archimedes).
            let z = self.z_max + u.x * (self.z_min - self.z_max);
            let phi = u.y * self.phi_max;
            let rxy = (self.radius * self.radius - z * z).max(0.0).sqrt();
            Vec3::new(rxy * phi.cos(), rxy * phi.sin(), z)
        };
        p * (self.radius / p.length())
    }

    /// A point uniform by object-space area on the sphere (pbrt-v3's `Sample(u)`, restricted to
    /// the partial sphere when cut) and its world normal, oriented as in interactions.
    pub fn sample_area(&self, u: Vec2) -> (Vec3, Vec3) {
        let p = self.sample_object(u);
        let n = self.object_to_world.normal(p).normalize_or(Vec3::Z);
        (
            self.object_to_world.point(p),
            if self.flip { -n } else { n },
        )
    }

    /// The cone that the sphere subtends from `ref_p`: (world centre, world radius, distance
    /// to the centre, 1 - cos(thetaMax)). `None` when `ref_p` is inside the sphere, the sphere
    /// is partial, or the transform is not a similarity (where cone sampling does not apply).
    #[inline]
    fn cone(&self, ref_p: Vec3) -> Option<(Vec3, f64, f64, f64)> {
        let (center, r) = self.cone_base?;
        let dc2 = (center - ref_p).as_dvec3().length_squared();
        // A point on the sphere itself (rounding puts half of them just outside) must take the
        // inside branch: from the surface the cone is a whole hemisphere whose sampled points
        // collapse onto ref_p. pbrt-v3 offsets ref_p towards the centre for this; a relative
        // margin does the same, and both branches are unbiased wherever they are used.
        if dc2 <= r * r * (1.0 + 1e-3) {
            return None;
        }
        let sin2_max = r * r / dc2;
        // 1 - sqrt(1 - x) without cancellation for small spheres far away.
        let one_minus_cos_max = sin2_max / (1.0 + (1.0 - sin2_max).sqrt());
        Some((center, r, dc2.sqrt(), one_minus_cos_max))
    }

    /// pbrt-v3's `Sphere::Sample(ref, u)` when `ref_p` is outside: a point uniform in the cone
    /// of directions the sphere subtends, its world normal (oriented as in interactions) and
    /// its solid-angle density. Returns `None` when `ref_p` is inside the sphere (and for
    /// partial spheres and non-similarity transforms): the caller then samples by area
    /// ([`Sphere::sample_area`]) and converts to solid angle itself, as pbrt-v3 does inside.
    pub fn sample_solid_angle(&self, ref_p: Vec3, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        let (center, r, dc, omc_max) = self.cone(ref_p)?;
        let wc = (center - ref_p).normalize();
        let (wc_x, wc_y) = coordinate_system(wc);
        // The sampled direction's angle theta from the centre direction.
        let omc = u.x as f64 * omc_max;
        let cos_t = 1.0 - omc;
        let sin2_t = omc * (2.0 - omc);
        let phi = u.y * 2.0 * PI;
        // Angle alpha at the centre between -wc and the point where the direction meets the
        // sphere first.
        let ds = dc * cos_t - (r * r - dc * dc * sin2_t).max(0.0).sqrt();
        let cos_a = ((dc * dc + r * r - ds * ds) / (2.0 * dc * r)).clamp(-1.0, 1.0);
        let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt() as f32;
        let cos_a = cos_a as f32;
        let n_out = -(wc_x * (sin_a * phi.cos()) + wc_y * (sin_a * phi.sin()) + wc * cos_a);
        let n_out = n_out.normalize();
        let p = center + n_out * r as f32;
        let n = if self.flip { -n_out } else { n_out };
        let pdf = (1.0 / (2.0 * std::f64::consts::PI * omc_max)) as f32;
        Some((p, n, pdf))
    }

    /// pbrt-v3's `Sphere::Pdf(ref, wi)` for a direction `wi` that hits the sphere: the cone's
    /// uniform solid-angle density when `ref_p` is outside, and 0 where
    /// [`Sphere::sample_solid_angle`] returns `None` (inside: the caller uses the area density
    /// converted to solid angle).
    pub fn pdf_solid_angle(&self, ref_p: Vec3) -> f32 {
        match self.cone(ref_p) {
            Some((_, _, _, omc_max)) => (1.0 / (2.0 * std::f64::consts::PI * omc_max)) as f32,
            None => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::geometry::Mat4;

    fn unit() -> Sphere {
        Sphere::new(1.0, -1.0, 1.0, 360.0, Transform::IDENTITY, false)
    }

    fn hit(s: &Sphere, o: Vec3, d: Vec3) -> Option<SurfaceInteraction> {
        let ray = Ray::new(o, d, 0.0);
        s.intersect(&ray, f32::INFINITY).map(|(t, h)| {
            let si = s.interaction(&ray, t, &h);
            close3(si.p, ray.at(t), 1e-4 * (1.0 + t));
            si
        })
    }

    #[test]
    fn full_sphere_hit_matches_pbrt() {
        let s = unit();
        let ray = Ray::new(Vec3::new(-10.0, 0.0, 0.0), Vec3::X, 0.0);
        let (t, h) = s.intersect(&ray, f32::INFINITY).unwrap();
        close(t, 9.0, 1e-5);
        let si = s.interaction(&ray, t, &h);
        close3(si.p, -Vec3::X, 1e-6);
        close3(si.n, -Vec3::X, 1e-6);
        close3(si.shading_n, si.n, 0.0);
        close(si.uv.x, 0.5, 1e-6);
        close(si.uv.y, 0.5, 1e-6);
        close3(si.dpdu, Vec3::new(0.0, -2.0 * PI, 0.0), 1e-5);
        close3(si.dpdv, Vec3::new(0.0, 0.0, PI), 1e-5);
        // v runs from 0 at the bottom (z = -r) to 1 at the top.
        let top = hit(&s, Vec3::new(0.1, 0.0, 5.0), -Vec3::Z).unwrap();
        assert!(top.uv.y > 0.95 && top.n.z > 0.99);
        // u = phi / 2pi.
        let si = hit(&s, Vec3::new(0.0, 5.0, 0.0), -Vec3::Y).unwrap();
        close(si.uv.x, 0.25, 1e-6);
        // From inside: the far side, normal still outward.
        let si = hit(&s, Vec3::ZERO, Vec3::new(0.0, 0.0, 3.0)).unwrap();
        // (At the pole pbrt-v3 nudges x to 1e-5 r so that phi and dp/du stay defined.)
        close3(si.p, Vec3::Z, 2e-5);
        assert!(si.dpdu.length() > 0.0 && si.dpdv.is_finite());
        assert!(si.n.z > 0.999);
        // t_max, behind, miss.
        assert!(s.intersect(&ray, 8.99).is_none());
        assert!(s.intersect(&ray, 9.0).is_some());
        assert!(s
            .intersect(&Ray::new(ray.o, -Vec3::X, 0.0), f32::INFINITY)
            .is_none());
        assert!(s
            .intersect(&Ray::new(Vec3::new(-10.0, 1.01, 0.0), Vec3::X, 0.0), 1e9)
            .is_none());
        close(s.area(), 4.0 * PI, 1e-5);
    }

    #[test]
    fn crossing_matches_the_interaction() {
        // Full, cut, reversed and transformed (handedness-swapping) spheres: the crossing's
        // point is the interaction's bit for bit, its normal the same to a few ulps.
        let m = Mat4::from_translation(Vec3::new(0.3, -1.0, 2.0))
            * Mat4::from_rotation_y(0.4)
            * Mat4::from_scale(Vec3::new(1.5, -0.8, 1.1));
        let spheres = [
            unit(),
            Sphere::new(1.0, -0.4, 0.9, 250.0, Transform::IDENTITY, true),
            Sphere::new(0.6, -0.6, 0.6, 360.0, Transform::new(m), false),
        ];
        let mut checked = 0;
        for s in &spheres {
            for i in 0..300 {
                let f = i as f32;
                let o = Vec3::new((f * 0.3).sin(), (f * 0.7).cos(), (f * 0.11).sin()) * 6.0;
                let target = Vec3::new(0.3, -1.0, 2.0) * (i % 3) as f32 * 0.5;
                let ray = Ray::new(o, target - o + Vec3::splat((f * 0.9).sin() * 0.3), 0.0);
                let Some((t, h)) = s.intersect(&ray, f32::INFINITY) else {
                    continue;
                };
                let (si, c) = (s.interaction(&ray, t, &h), s.crossing(&ray, &h));
                assert_eq!(c.p, si.p);
                close3(c.n, si.n, 1e-5);
                checked += 1;
            }
        }
        assert!(checked > 100, "{checked}");
    }

    #[test]
    fn early_miss_test_never_loses_a_hit() {
        // Lines at distances from the centre around r, from near and far origins, in many
        // directions: where the f32 test says "missed", the exact test finds no root; and it
        // does reject clear misses (else it would save nothing).
        let s = Sphere::new(0.7, -0.7, 0.7, 360.0, Transform::IDENTITY, false);
        let (mut rejected, mut kept_hits) = (0, 0);
        for i in 0..4000 {
            let f = i as f32;
            let d = Vec3::new((f * 0.37).sin(), (f * 0.61).cos(), (f * 0.13).sin() + 0.1)
                .normalize()
                * (0.5 + (f * 0.07).sin().abs() * 3.0);
            let (a, _) = crate::shapes::coordinate_system(d.normalize());
            // Distance from the centre: 0.7 (1 + e), e from -1e-3 to 1e-3 and a few clear ones.
            let e = ((i % 41) as f32 - 20.0) * 5e-5 + if i % 7 == 0 { 0.5 } else { 0.0 };
            let back = [1.0, 30.0, 1e3, 1e5][i % 4];
            let o = a * 0.7 * (1.0 + e) - d.normalize() * back;
            let exact = s.intersect_object(o, d, f32::INFINITY);
            if s.clearly_missed(o, d) {
                assert!(exact.is_none(), "lost a hit: o {o} d {d}");
                rejected += 1;
            } else if exact.is_some() {
                kept_hits += 1;
            }
        }
        assert!(rejected > 500 && kept_hits > 500, "{rejected} {kept_hits}");
    }

    #[test]
    fn partial_sphere_cuts_and_second_root() {
        // zmax = 0.5: the top cap is cut away; a ray from above goes through the hole and hits
        // the inside of the far (bottom) side.
        let s = Sphere::new(1.0, -1.0, 0.5, 360.0, Transform::IDENTITY, false);
        let ray = Ray::new(Vec3::new(0.3, 0.0, 10.0), -Vec3::Z, 0.0);
        let (t, h) = s.intersect(&ray, f32::INFINITY).unwrap();
        let zb = (1.0f32 - 0.09).sqrt();
        close(t, 10.0 + zb, 1e-5);
        let si = s.interaction(&ray, t, &h);
        close3(si.n, Vec3::new(0.3, 0.0, -zb), 1e-5);
        // v with thetaMin = pi, thetaMax = acos(0.5).
        let theta = (-zb).acos();
        close(si.uv.y, (theta - PI) / ((0.5f32).acos() - PI), 1e-5);
        // A ray that would hit only the cut cap misses.
        let s2 = Sphere::new(1.0, 0.6, -0.5, 360.0, Transform::IDENTITY, false);
        assert_eq!((s2.z_min, s2.z_max), (-0.5, 0.6));
        assert!(hit(&s2, Vec3::new(5.0, 0.0, 0.8), -Vec3::X).is_none());
        assert!(hit(&s2, Vec3::new(5.0, 0.0, 0.55), -Vec3::X).is_some());
        // phimax = 180: y < 0 is cut; from -y the ray passes the open half and hits the inside
        // of the y > 0 half.
        let s3 = Sphere::new(1.0, -1.0, 1.0, 180.0, Transform::IDENTITY, false);
        let si = hit(&s3, Vec3::new(0.0, -5.0, 0.0), Vec3::Y).unwrap();
        close3(si.p, Vec3::Y, 1e-6);
        close3(si.n, Vec3::Y, 1e-6);
        close(si.uv.x, 0.5, 1e-6);
        assert!(hit(&s3, Vec3::new(0.0, -5.0, 0.0), Vec3::new(0.0, 1.0, 0.0)).is_some());
        assert!(hit(&s3, Vec3::new(0.5, -5.0, 0.0), Vec3::new(0.0, 1.0, 0.0)).is_some());
        // Both roots cut: miss. (Both hits at y < 0.)
        assert!(hit(&s3, Vec3::new(-5.0, -0.5, 0.0), Vec3::X).is_none());
        close(s3.object_area(), 2.0 * PI, 1e-5);
    }

    #[test]
    fn transformed_sphere_orientation_and_reprojection() {
        let m = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
            * Mat4::from_rotation_x(0.7)
            * Mat4::from_scale(Vec3::splat(2.0));
        let s = Sphere::new(1.5, -1.5, 1.5, 360.0, Transform::new(m), false);
        let c = Vec3::new(1.0, 2.0, 3.0);
        close(s.area(), 4.0 * PI * 9.0, 1e-3);
        let mut rng = Rng::new(1);
        for _ in 0..500 {
            let o = c + rng.v3().normalize() * 20.0;
            let target = c + rng.v3();
            let ray = Ray::new(o, target - o, 0.0);
            let (t, h) = s.intersect(&ray, f32::INFINITY).unwrap();
            // Re-projection: the object-space point is on the sphere to float precision.
            close(h.p.length(), 1.5, 1e-6);
            let si = s.interaction(&ray, t, &h);
            close((si.p - c).length(), 3.0, 1e-4);
            close3(si.n, (si.p - c).normalize(), 1e-4);
            assert!(si.n.dot(ray.d) < 0.0);
        }
        // ReverseOrientation flips; a mirror also flips (pbrt-v3 flips the object-space normal
        // by the handedness swap before transforming it as a normal).
        let rev = Sphere::new(1.0, -1.0, 1.0, 360.0, Transform::IDENTITY, true);
        let mirror = Sphere::new(
            1.0,
            -1.0,
            1.0,
            360.0,
            Transform::new(Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))),
            false,
        );
        let both = Sphere::new(1.0, -1.0, 1.0, 360.0, mirror.object_to_world, true);
        for (sphere, sign) in [(&rev, -1.0), (&mirror, -1.0), (&both, 1.0)] {
            let si = hit(sphere, Vec3::new(-10.0, 0.0, 0.0), Vec3::X).unwrap();
            close3(si.p, -Vec3::X, 1e-6);
            close3(si.n, -Vec3::X * sign, 1e-6);
            let (p, n) = sphere.sample_area(Vec2::new(0.3, 0.7));
            close3(n, p * sign, 1e-5);
        }
    }

    #[test]
    fn sample_area_is_uniform_on_the_surface() {
        let m =
            Mat4::from_translation(Vec3::new(0.0, -1.0, 2.0)) * Mat4::from_scale(Vec3::splat(2.0));
        for s in [
            Sphere::new(1.0, -1.0, 1.0, 360.0, Transform::IDENTITY, false),
            Sphere::new(1.0, -0.5, 0.8, 270.0, Transform::new(m), false),
        ] {
            let (lo, hi) = s.world_bound();
            let c = s.object_to_world.point(Vec3::ZERO);
            let scale = s.object_to_world.similarity_scale().unwrap();
            let mut rng = Rng::new(2);
            let n = 40000;
            let mut z2 = 0.0f64;
            for _ in 0..n {
                let (p, nn) = s.sample_area(rng.v2());
                close((p - c).length(), scale * s.radius, 1e-4);
                close3(nn, (p - c).normalize(), 1e-4);
                assert!(p.cmpge(lo - 1e-4).all() && p.cmple(hi + 1e-4).all());
                let po = s.object_to_world.inv_point(p);
                assert!(po.z >= s.z_min - 1e-4 && po.z <= s.z_max + 1e-4);
                let phi = phi_of(po);
                assert!(phi <= s.phi_max + 1e-4 || phi >= 2.0 * PI - 1e-4);
                z2 += (po.z * po.z) as f64;
            }
            // Area times the mean of z^2 (object space) is the integral of z^2 over the
            // surface: phimax r (zmax^3 - zmin^3) / 3, times the world area scale.
            let est = s.area() as f64 * z2 / n as f64;
            let exact =
                s.phi_max * s.radius * (s.z_max.powi(3) - s.z_min.powi(3)) / 3.0 * scale * scale;
            close(est as f32, exact, 0.02 * exact);
        }
    }

    #[test]
    fn solid_angle_sampling_is_consistent() {
        let m = Mat4::from_translation(Vec3::new(2.0, 1.0, -3.0))
            * Mat4::from_rotation_z(1.1)
            * Mat4::from_scale(Vec3::splat(0.5));
        let s = Sphere::new(2.0, -2.0, 2.0, 360.0, Transform::new(m), false);
        let c = Vec3::new(2.0, 1.0, -3.0);
        let r = 1.0;
        let mut rng = Rng::new(9);
        for ref_p in [
            Vec3::new(5.0, 1.0, -3.0),
            Vec3::new(2.0, 1.2, -1.5),
            Vec3::new(-20.0, 3.0, 4.0),
        ] {
            let pdf = s.pdf_solid_angle(ref_p);
            let dc = (c - ref_p).length();
            let cone = 2.0 * PI * (1.0 - (1.0 - r * r / (dc * dc)).sqrt());
            close(pdf * cone, 1.0, 1e-3);
            // Sampled points are on the visible side, first along their direction.
            for _ in 0..2000 {
                let (p, n, spdf) = s.sample_solid_angle(ref_p, rng.v2()).unwrap();
                assert_eq!(spdf, pdf);
                close((p - c).length(), r, 1e-4);
                close3(n, (p - c).normalize(), 1e-4);
                let facing = n.dot((ref_p - p).normalize());
                assert!(facing >= -1e-4);
                // (Rays grazing the silhouette may miss in floating point.)
                if facing > 1e-3 {
                    let ray = Ray::new(ref_p, p - ref_p, 0.0);
                    let (t, _) = s.intersect(&ray, 2.0).unwrap();
                    close(t, 1.0, 1e-3);
                }
            }
            // The pdf integrates to 1 over the directions that hit the sphere: estimate with
            // directions uniform in a cone of twice the solid angle around the centre.
            let wc = (c - ref_p).normalize();
            let frame = crate::geometry::Frame::from_z(wc);
            let cos_max = (1.0 - r * r / (dc * dc)).sqrt();
            let cos_big = 1.0 - 2.0 * (1.0 - cos_max);
            let n = 100_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                let w = frame.from_local(crate::sampling::uniform_sample_cone(rng.v2(), cos_big));
                if s.intersect_p(&Ray::new(ref_p, w, 0.0), f32::INFINITY) {
                    sum += pdf as f64;
                }
            }
            let big = 2.0 * std::f64::consts::PI * (1.0 - cos_big as f64);
            let integral = sum * big / n as f64;
            assert!((integral - 1.0).abs() < 0.02, "{integral}");
            // The sampled directions cover the cone uniformly: the mean direction's angle.
            let mut mean = Vec3::ZERO;
            for _ in 0..4000 {
                let (p, _, _) = s.sample_solid_angle(ref_p, rng.v2()).unwrap();
                mean += (p - ref_p).normalize();
            }
            // E[cos theta] for a uniform cone is (1 + cos_max) / 2.
            close(
                (mean / 4000.0).dot((c - ref_p).normalize()),
                0.5 * (1.0 + cos_max),
                0.01,
            );
        }
        // Inside: the caller falls back to area sampling.
        assert!(s
            .sample_solid_angle(c + Vec3::splat(0.1), Vec2::splat(0.5))
            .is_none());
        assert_eq!(s.pdf_solid_angle(c), 0.0);
        // Partial spheres and non-uniform scales too.
        let partial = Sphere::new(1.0, -1.0, 0.0, 360.0, Transform::IDENTITY, false);
        assert!(partial
            .sample_solid_angle(Vec3::splat(5.0), Vec2::splat(0.5))
            .is_none());
        let squashed = Sphere::new(
            1.0,
            -1.0,
            1.0,
            360.0,
            Transform::new(Mat4::from_scale(Vec3::new(1.0, 2.0, 1.0))),
            false,
        );
        assert_eq!(squashed.pdf_solid_angle(Vec3::splat(5.0)), 0.0);
        // A tiny sphere far away keeps a finite density.
        let tiny = Sphere::new(1e-3, -1e-3, 1e-3, 360.0, Transform::IDENTITY, false);
        let pdf = tiny.pdf_solid_angle(Vec3::new(1e3, 0.0, 0.0));
        assert!(pdf.is_finite() && pdf > 0.0);
        let (p, _, _) = tiny
            .sample_solid_angle(Vec3::new(1e3, 0.0, 0.0), Vec2::new(0.5, 0.5))
            .unwrap();
        close(p.length(), 1e-3, 1e-6);
    }
}
