//! pbrt-v3's paraboloid: z = zmax (x^2 + y^2) / radius^2, kept for z in [zmin, zmax].

use super::profile::Profile;
use super::quadric::phi_of;
use crate::geometry::{Vec2, Vec3};
use glam::DVec3;

/// A paraboloid's own parameters (pbrt-v3 `paraboloid`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Paraboloid {
    /// Radius at z = zmax.
    pub radius: f32,
    /// Lower cut.
    pub z_min: f32,
    /// Upper cut (and the height at which the radius is `radius`).
    pub z_max: f32,
}

impl Paraboloid {
    /// From pbrt-v3's parameters; z0 and z1 in either order.
    pub fn new(radius: f32, z0: f32, z1: f32) -> Self {
        Self {
            radius,
            z_min: z0.min(z1),
            z_max: z0.max(z1),
        }
    }
}

impl Profile for Paraboloid {
    fn coefficients(&self, o: DVec3, d: DVec3) -> (f64, f64, f64) {
        let k = self.z_max as f64 / (self.radius as f64 * self.radius as f64);
        (
            k * (d.x * d.x + d.y * d.y),
            2.0 * k * (d.x * o.x + d.y * o.y) - d.z,
            k * (o.x * o.x + o.y * o.y) - o.z,
        )
    }

    fn phi(&self, p: Vec3) -> f32 {
        phi_of(p)
    }

    fn z_range(&self) -> (f32, f32) {
        (self.z_min, self.z_max)
    }

    fn geometry(&self, p: Vec3, phi: f32, phi_max: f32) -> (Vec2, Vec3, Vec3, [Vec3; 3]) {
        let dz = self.z_max - self.z_min;
        // pbrt-v3 divides by z, zero at the vertex (a set of measure zero).
        let z = if p.z.abs() > 1e-7 * self.z_max.abs() {
            p.z
        } else {
            1e-7 * self.z_max.abs().max(1e-30)
        };
        let dpdu = Vec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
        let dpdv = dz * Vec3::new(p.x / (2.0 * z), p.y / (2.0 * z), 1.0);
        let second = [
            -phi_max * phi_max * Vec3::new(p.x, p.y, 0.0),
            dz * phi_max * Vec3::new(-p.y / (2.0 * z), p.x / (2.0 * z), 0.0),
            -dz * dz * Vec3::new(p.x / (4.0 * z * z), p.y / (4.0 * z * z), 0.0),
        ];
        let v = (p.z - self.z_min) / dz;
        (Vec2::new(phi / phi_max, v), dpdu, dpdv, second)
    }

    fn object_bound(&self) -> (Vec3, Vec3) {
        let r = self.radius;
        (Vec3::new(-r, -r, self.z_min), Vec3::new(r, r, self.z_max))
    }

    fn object_area(&self, phi_max: f32) -> f32 {
        let r2 = self.radius * self.radius;
        let k = 4.0 * self.z_max / r2;
        (r2 * r2 * phi_max / (12.0 * self.z_max * self.z_max))
            * ((k * self.z_max + 1.0).powf(1.5) - (k * self.z_min + 1.0).powf(1.5))
    }
}
