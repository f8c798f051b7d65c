//! The profile of a surface of revolution: what each of cone, paraboloid and hyperboloid
//! tells the intersection code they share ([`super::revolved`]).

use crate::geometry::{Vec2, Vec3};
use glam::DVec3;

/// What a surface of revolution tells the shared intersection code.
pub trait Profile {
    /// The coefficients (a, b, c) of the implicit equation along the object-space ray o + t d.
    fn coefficients(&self, o: DVec3, d: DVec3) -> (f64, f64, f64);
    /// The azimuth of an object-space point on the surface, in [0, 2 pi).
    fn phi(&self, p: Vec3) -> f32;
    /// The z range the surface keeps.
    fn z_range(&self) -> (f32, f32);
    /// (u, v), dp/du, dp/dv and the second derivatives (uu, uv, vv) at a point of azimuth phi.
    fn geometry(&self, p: Vec3, phi: f32, phi_max: f32) -> (Vec2, Vec3, Vec3, [Vec3; 3]);
    /// Object-space bounds.
    fn object_bound(&self) -> (Vec3, Vec3);
    /// pbrt-v3's `Area()` for the azimuth range phi_max.
    fn object_area(&self, phi_max: f32) -> f32;
}
