//! pbrt-v3's cone: radius `radius` at z = 0 narrowing to its apex at z = `height`.

use super::profile::Profile;
use super::quadric::phi_of;
use crate::geometry::{Vec2, Vec3};
use glam::DVec3;

/// A cone's own parameters (pbrt-v3 `cone`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Radius of the base (z = 0).
    pub radius: f32,
    /// Height of the apex.
    pub height: f32,
}

impl Profile for Cone {
    fn coefficients(&self, o: DVec3, d: DVec3) -> (f64, f64, f64) {
        let k = (self.radius as f64 / self.height as f64).powi(2);
        let h = self.height as f64;
        (
            d.x * d.x + d.y * d.y - k * d.z * d.z,
            2.0 * (d.x * o.x + d.y * o.y - k * d.z * (o.z - h)),
            o.x * o.x + o.y * o.y - k * (o.z - h) * (o.z - h),
        )
    }

    fn phi(&self, p: Vec3) -> f32 {
        phi_of(p)
    }

    fn z_range(&self) -> (f32, f32) {
        (0.0, self.height)
    }

    fn geometry(&self, p: Vec3, phi: f32, phi_max: f32) -> (Vec2, Vec3, Vec3, [Vec3; 3]) {
        let v = p.z / self.height;
        // pbrt-v3 divides by 1 - v, infinite at the apex (a set of measure zero).
        let w = (1.0 - v).max(1e-6);
        let dpdu = Vec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
        let dpdv = Vec3::new(-p.x / w, -p.y / w, self.height);
        let second = [
            -phi_max * phi_max * Vec3::new(p.x, p.y, 0.0),
            phi_max / w * Vec3::new(p.y, -p.x, 0.0),
            Vec3::ZERO,
        ];
        (Vec2::new(phi / phi_max, v), dpdu, dpdv, second)
    }

    fn object_bound(&self) -> (Vec3, Vec3) {
        let r = self.radius;
        (Vec3::new(-r, -r, 0.0), Vec3::new(r, r, self.height))
    }

    fn object_area(&self, phi_max: f32) -> f32 {
        let (r, h) = (self.radius, self.height);
        r * (h * h + r * r).sqrt() * phi_max / 2.0
    }
}
