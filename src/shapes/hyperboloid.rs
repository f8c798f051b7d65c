//! pbrt-v3's hyperboloid: the surface swept by the segment p1-p2 turning about the z axis,
//! a x^2 + a y^2 - c z^2 = 1.

use super::profile::Profile;
use crate::geometry::{Vec2, Vec3};
use glam::DVec3;
use std::f32::consts::PI;

/// A hyperboloid's own parameters (pbrt-v3 `hyperboloid`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hyperboloid {
    /// One end of the generating segment (after pbrt-v3's swap, p2.z is not 0).
    pub p1: Vec3,
    /// The other end.
    pub p2: Vec3,
    /// The larger of the ends' distances to the axis.
    pub r_max: f32,
    /// Lower z.
    pub z_min: f32,
    /// Upper z.
    pub z_max: f32,
    /// pbrt-v3's `ah`.
    pub ah: f32,
    /// pbrt-v3's `ch`.
    pub ch: f32,
}

impl Hyperboloid {
    /// pbrt-v3's constructor: swaps the ends when p2 lies at z = 0, then moves a point along
    /// the line until the implicit coefficients are finite. `None` where they never are (the
    /// segment lies in a plane z = constant, or on the axis): pbrt-v3 loops for ever there.
    pub fn new(p1: Vec3, p2: Vec3) -> Option<Self> {
        let (r1, r2) = (p1.truncate().length(), p2.truncate().length());
        let (z_min, z_max) = (p1.z.min(p2.z), p1.z.max(p2.z));
        let (p1, p2) = if p2.z == 0.0 { (p2, p1) } else { (p1, p2) };
        let mut pp = p1;
        for _ in 0..64 {
            pp += 2.0 * (p2 - p1);
            let xy1 = pp.x * pp.x + pp.y * pp.y;
            let xy2 = p2.x * p2.x + p2.y * p2.y;
            let z2 = p2.z * p2.z;
            let ah =
                (1.0 / xy1 - (pp.z * pp.z) / (xy1 * z2)) / (1.0 - (xy2 * pp.z * pp.z) / (xy1 * z2));
            let ch = (ah * xy2 - 1.0) / z2;
            if ah.is_finite() && ch.is_finite() && p1.z != p2.z {
                return Some(Self {
                    p1,
                    p2,
                    r_max: r1.max(r2),
                    z_min,
                    z_max,
                    ah,
                    ch,
                });
            }
        }
        None
    }
}

impl Profile for Hyperboloid {
    fn coefficients(&self, o: DVec3, d: DVec3) -> (f64, f64, f64) {
        let (ah, ch) = (self.ah as f64, self.ch as f64);
        (
            ah * d.x * d.x + ah * d.y * d.y - ch * d.z * d.z,
            2.0 * (ah * d.x * o.x + ah * d.y * o.y - ch * d.z * o.z),
            ah * o.x * o.x + ah * o.y * o.y - ch * o.z * o.z - 1.0,
        )
    }

    /// The angle from the generating segment's point at the same height, as pbrt-v3 measures it.
    fn phi(&self, p: Vec3) -> f32 {
        let v = (p.z - self.p1.z) / (self.p2.z - self.p1.z);
        let pr = (1.0 - v) * self.p1 + v * self.p2;
        let phi = (pr.x * p.y - p.x * pr.y).atan2(p.x * pr.x + p.y * pr.y);
        if phi < 0.0 {
            phi + 2.0 * PI
        } else {
            phi
        }
    }

    fn z_range(&self) -> (f32, f32) {
        (self.z_min, self.z_max)
    }

    fn geometry(&self, p: Vec3, phi: f32, phi_max: f32) -> (Vec2, Vec3, Vec3, [Vec3; 3]) {
        let (p1, p2) = (self.p1, self.p2);
        let v = (p.z - p1.z) / (p2.z - p1.z);
        let (sin_phi, cos_phi) = phi.sin_cos();
        let dpdu = Vec3::new(-phi_max * p.y, phi_max * p.x, 0.0);
        let dpdv = Vec3::new(
            (p2.x - p1.x) * cos_phi - (p2.y - p1.y) * sin_phi,
            (p2.x - p1.x) * sin_phi + (p2.y - p1.y) * cos_phi,
            p2.z - p1.z,
        );
        let second = [
            -phi_max * phi_max * Vec3::new(p.x, p.y, 0.0),
            phi_max * Vec3::new(-dpdv.y, dpdv.x, 0.0),
            Vec3::ZERO,
        ];
        (Vec2::new(phi / phi_max, v), dpdu, dpdv, second)
    }

    fn object_bound(&self) -> (Vec3, Vec3) {
        let r = self.r_max;
        (Vec3::new(-r, -r, self.z_min), Vec3::new(r, r, self.z_max))
    }

    /// pbrt-v3's closed form, kept as it is written there.
    fn object_area(&self, phi_max: f32) -> f32 {
        let (p1, p2) = (self.p1, self.p2);
        let sqr = |a: f32| a * a;
        let quad = |a: f32| sqr(a) * sqr(a);
        phi_max / 6.0
            * (2.0 * quad(p1.x) - 2.0 * p1.x * p1.x * p1.x * p2.x
                + 2.0 * quad(p2.x)
                + 2.0
                    * (p1.y * p1.y + p1.y * p2.y + p2.y * p2.y)
                    * (sqr(p1.y - p2.y) + sqr(p1.z - p2.z))
                + p2.x
                    * p2.x
                    * (5.0 * p1.y * p1.y + 2.0 * p1.y * p2.y - 4.0 * p2.y * p2.y
                        + 2.0 * sqr(p1.z - p2.z))
                + p1.x
                    * p1.x
                    * (-4.0 * p1.y * p1.y
                        + 2.0 * p1.y * p2.y
                        + 5.0 * p2.y * p2.y
                        + 2.0 * sqr(p1.z - p2.z))
                - 2.0
                    * p1.x
                    * p2.x
                    * (p2.x * p2.x - p1.y * p1.y + 5.0 * p1.y * p2.y - p2.y * p2.y - p1.z * p1.z
                        + 2.0 * p1.z * p2.z
                        - p2.z * p2.z))
    }
}
