//! Shapes as pbrt-v3 defines them: triangle meshes (stored in the space they are given, world
//! space for static meshes) and the quadrics sphere, disk and cylinder (stored in object space
//! with their object-to-world transform). Parametrisations, normals and orientation rules follow
//! pbrt-v3 so that texture coordinates and shading agree with its images.

pub mod cylinder;
pub mod disk;
pub mod heightfield;
pub mod loopsubdiv;
pub mod sphere;
pub mod triangle;

pub use cylinder::{Cylinder, CylinderHit};
pub use disk::{Disk, DiskHit};
pub use sphere::{Sphere, SphereHit};
pub use triangle::{TriangleHit, TriangleMesh};

use crate::geometry::{Mat3, Mat4, Ray, SurfaceInteraction, Vec2, Vec3};

/// An affine transform and its inverse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// The matrix (column vectors, affine: last row 0 0 0 1).
    pub m: Mat4,
    /// Its inverse.
    pub inv: Mat4,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        m: Mat4::IDENTITY,
        inv: Mat4::IDENTITY,
    };

    /// From a matrix; the inverse is computed in double precision.
    pub fn new(m: Mat4) -> Self {
        Self {
            m,
            inv: m.as_dmat4().inverse().as_mat4(),
        }
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Self {
        Self {
            m: self.inv,
            inv: self.m,
        }
    }

    /// Determinant of the upper-left 3x3 (the linear part).
    #[inline]
    pub fn det3(&self) -> f32 {
        Mat3::from_mat4(self.m).determinant()
    }

    /// Whether the transform changes the handedness of coordinate systems (pbrt-v3's
    /// `SwapsHandedness`: the 3x3 determinant is negative).
    #[inline]
    pub fn swaps_handedness(&self) -> bool {
        self.det3() < 0.0
    }

    /// Applies the transform to a point.
    #[inline]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.m.transform_point3(p)
    }

    /// Applies the transform to a vector (no translation).
    #[inline]
    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.m.transform_vector3(v)
    }

    /// Applies the transform to a normal: multiplies by the inverse transpose (not normalised).
    #[inline]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        Vec3::new(
            self.inv.x_axis.truncate().dot(n),
            self.inv.y_axis.truncate().dot(n),
            self.inv.z_axis.truncate().dot(n),
        )
    }

    /// Applies the inverse to a point.
    #[inline]
    pub fn inv_point(&self, p: Vec3) -> Vec3 {
        self.inv.transform_point3(p)
    }

    /// Applies the inverse to a vector.
    #[inline]
    pub fn inv_vector(&self, v: Vec3) -> Vec3 {
        self.inv.transform_vector3(v)
    }

    /// Applies the transform to a ray (the direction is not normalised, so parameters `t` are
    /// the same in both spaces).
    #[inline]
    pub fn ray(&self, r: &Ray) -> Ray {
        Ray::new(self.point(r.o), self.vector(r.d), r.time)
    }

    /// Applies the inverse to a ray (world to object for an object-to-world transform).
    #[inline]
    pub fn inv_ray(&self, r: &Ray) -> Ray {
        Ray::new(self.inv_point(r.o), self.inv_vector(r.d), r.time)
    }

    /// Bounds of the transformed box (its 8 corners transformed, as pbrt-v3 does).
    pub fn bounds(&self, lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
        let mut blo = Vec3::splat(f32::INFINITY);
        let mut bhi = Vec3::splat(f32::NEG_INFINITY);
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let p = self.point(c);
            blo = blo.min(p);
            bhi = bhi.max(p);
        }
        (blo, bhi)
    }

    /// The uniform scale factor when the linear part is a similarity (rotation, possibly a
    /// mirror, times a uniform scale), else `None`.
    pub fn similarity_scale(&self) -> Option<f32> {
        let c = [
            self.m.x_axis.truncate(),
            self.m.y_axis.truncate(),
            self.m.z_axis.truncate(),
        ];
        let l = [c[0].length(), c[1].length(), c[2].length()];
        let s = (l[0] + l[1] + l[2]) / 3.0;
        if s.is_nan() || s <= 0.0 || s.is_infinite() {
            return None;
        }
        const TOL: f32 = 1e-4;
        let lengths_ok = l.iter().all(|&li| (li - s).abs() <= TOL * s);
        let orthogonal = c[0].dot(c[1]).abs() <= TOL * s * s
            && c[0].dot(c[2]).abs() <= TOL * s * s
            && c[1].dot(c[2]).abs() <= TOL * s * s;
        (lengths_ok && orthogonal).then_some(s)
    }

    /// How much the transform scales areas of a surface element with unit normal `n` (object
    /// space): |det M| |M^-T n|.
    #[inline]
    pub fn area_scale(&self, n: Vec3) -> f32 {
        self.det3().abs() * self.normal(n).length()
    }
}

/// pbrt-v3's machine epsilon (half an ulp of 1).
const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// pbrt-v3's gamma(n): a bound on the relative error of n floating-point operations.
#[inline]
pub(crate) fn gamma(n: i32) -> f32 {
    let n = n as f32;
    (n * MACHINE_EPSILON) / (1.0 - n * MACHINE_EPSILON)
}

/// pbrt-v3's `CoordinateSystem`: two unit vectors completing unit `v1` to a right-handed
/// orthonormal basis (v1, v2, v3).
#[inline]
pub(crate) fn coordinate_system(v1: Vec3) -> (Vec3, Vec3) {
    let v2 = if v1.x.abs() > v1.y.abs() {
        Vec3::new(-v1.z, 0.0, v1.x) / (v1.x * v1.x + v1.z * v1.z).sqrt()
    } else {
        Vec3::new(0.0, v1.z, -v1.y) / (v1.y * v1.y + v1.z * v1.z).sqrt()
    };
    (v2, v1.cross(v2))
}

/// pbrt-v3's `Faceforward`: `n` flipped to the hemisphere of `v`.
#[inline]
pub(crate) fn faceforward(n: Vec3, v: Vec3) -> Vec3 {
    if n.dot(v) < 0.0 {
        -n
    } else {
        n
    }
}

/// pbrt-v3's `Radians` of `Clamp(deg, 0, 360)`.
#[inline]
pub(crate) fn phi_max_radians(deg: f32) -> f32 {
    deg.clamp(0.0, 360.0).to_radians()
}

/// The two roots t0 <= t1 of `a t^2 + b t + c` with the discriminant `discrim` (computed by
/// the caller in a cancellation-free form), using the numerically stable formulation pbrt-v3's
/// `Quadratic` uses. `None` when there is no real root or the roots are degenerate.
#[inline]
pub(crate) fn quadratic_roots(a: f64, b: f64, c: f64, discrim: f64) -> Option<(f64, f64)> {
    if discrim.is_nan() || discrim < 0.0 || a == 0.0 {
        return None;
    }
    let root = discrim.sqrt();
    let q = if b < 0.0 {
        -0.5 * (b - root)
    } else {
        -0.5 * (b + root)
    };
    if q == 0.0 {
        return None;
    }
    let (t0, t1) = (q / a, c / q);
    if t0 > t1 {
        Some((t1, t0))
    } else {
        Some((t0, t1))
    }
}

/// `atan2(y, x)` mapped to [0, 2 pi) as pbrt-v3's quadrics do.
#[inline]
pub(crate) fn phi_of(p: Vec3) -> f32 {
    let phi = p.y.atan2(p.x);
    if phi < 0.0 {
        phi + 2.0 * std::f32::consts::PI
    } else {
        phi
    }
}

/// A quadric's interaction from its object-space differential geometry, as pbrt-v3 builds it:
/// n = normalize(dpdu x dpdv), flipped when `flip` (reverse orientation xor handedness swap),
/// then everything is carried to world space (the normal by the inverse transpose). The shading
/// geometry is the geometric one.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn quadric_interaction(
    to_world: &Transform,
    flip: bool,
    ray: &Ray,
    p_obj: Vec3,
    uv: Vec2,
    dpdu: Vec3,
    dpdv: Vec3,
    second: Option<[Vec3; 3]>,
) -> SurfaceInteraction {
    let n_obj = dpdu.cross(dpdv).normalize_or(Vec3::Z);
    let (dndu, dndv) = second.map_or((Vec3::ZERO, Vec3::ZERO), |d2| weingarten(dpdu, dpdv, d2));
    let n_obj = if flip { -n_obj } else { n_obj };
    let n = to_world.normal(n_obj).normalize_or(n_obj);
    let dpdu_w = to_world.vector(dpdu);
    SurfaceInteraction {
        p: to_world.point(p_obj),
        n,
        uv,
        dpdu: dpdu_w,
        dpdv: to_world.vector(dpdv),
        shading_n: n,
        shading_dpdu: dpdu_w,
        shading_dpdv: to_world.vector(dpdv),
        dndu: to_world.normal(dndu),
        dndv: to_world.normal(dndv),
        wo: (-ray.d).normalize_or_zero(),
        time: ray.time,
    }
}

/// dn/du and dn/dv of the unit normal normalize(dpdu x dpdv) from the surface's first and
/// second derivatives (`second` = d2p/du2, d2p/dudv, d2p/dv2): pbrt-v3's Weingarten equations,
/// shared by the quadrics. Zero where the first fundamental form is singular.
pub(crate) fn weingarten(dpdu: Vec3, dpdv: Vec3, second: [Vec3; 3]) -> (Vec3, Vec3) {
    let (e1, f1, g1) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
    let n = dpdu.cross(dpdv).normalize_or_zero();
    let [duu, duv, dvv] = second;
    let (e2, f2, g2) = (n.dot(duu), n.dot(duv), n.dot(dvv));
    let det = e1 * g1 - f1 * f1;
    if det.abs() < f32::MIN_POSITIVE || !det.is_finite() {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let inv = 1.0 / det;
    let dndu = (f2 * f1 - e2 * g1) * inv * dpdu + (e2 * f1 - f2 * e1) * inv * dpdv;
    let dndv = (g2 * f1 - f2 * g1) * inv * dpdu + (f2 * f1 - g2 * e1) * inv * dpdv;
    (dndu, dndv)
}

/// The world-space area of a quadric of object-space area `object_area` placed by `t`: exact
/// for similarity transforms; otherwise the mean area scale over a grid of points given by
/// `normal_at` (the object-space unit normal at the point that a sample `u` maps to).
pub(crate) fn world_area(t: &Transform, object_area: f32, normal_at: impl Fn(Vec2) -> Vec3) -> f32 {
    if let Some(s) = t.similarity_scale() {
        return object_area * s * s;
    }
    const N: usize = 32;
    let mut sum = 0.0f64;
    for j in 0..N {
        for i in 0..N {
            let u = Vec2::new((i as f32 + 0.5) / N as f32, (j as f32 + 0.5) / N as f32);
            sum += t.area_scale(normal_at(u)) as f64;
        }
    }
    object_area * (sum / (N * N) as f64) as f32
}

#[cfg(test)]
pub(crate) mod test_util {
    //! Deterministic random numbers and small helpers for the shape tests.

    use crate::geometry::{Vec2, Vec3};

    /// A tiny xorshift generator.
    pub struct Rng(u64);

    impl Rng {
        /// Seeded.
        pub fn new(seed: u64) -> Self {
            Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
        }

        /// Uniform in [0, 1).
        pub fn f(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }

        /// Uniform in [0, 1)^2.
        pub fn v2(&mut self) -> Vec2 {
            Vec2::new(self.f(), self.f())
        }

        /// Uniform in [-1, 1)^3.
        pub fn v3(&mut self) -> Vec3 {
            Vec3::new(self.f(), self.f(), self.f()) * 2.0 - Vec3::ONE
        }
    }

    /// Asserts `a` and `b` are within `eps` (component-wise).
    #[track_caller]
    pub fn close3(a: Vec3, b: Vec3, eps: f32) {
        assert!((a - b).abs().max_element() <= eps, "{a} != {b} (eps {eps})");
    }

    /// Asserts `a` and `b` are within `eps`.
    #[track_caller]
    pub fn close(a: f32, b: f32, eps: f32) {
        assert!((a - b).abs() <= eps, "{a} != {b} (eps {eps})");
    }
}

#[cfg(test)]
mod tests {
    use super::test_util::*;
    use super::*;

    #[test]
    fn transform_applies_to_points_vectors_normals() {
        let m = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
            * Mat4::from_rotation_z(0.3)
            * Mat4::from_scale(Vec3::new(2.0, 1.0, 0.5));
        let t = Transform::new(m);
        close3(
            t.inv_point(t.point(Vec3::new(0.3, -0.2, 0.7))),
            Vec3::new(0.3, -0.2, 0.7),
            1e-5,
        );
        // A normal stays perpendicular to transformed tangents.
        let n = Vec3::new(1.0, 1.0, 1.0);
        let tangent = Vec3::new(1.0, -1.0, 0.0);
        close(t.normal(n).dot(t.vector(tangent)), 0.0, 1e-5);
        assert!(!t.swaps_handedness());
        assert!(t.similarity_scale().is_none());
        let mirror = Transform::new(Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)));
        assert!(mirror.swaps_handedness());
        assert_eq!(mirror.similarity_scale(), Some(1.0));
        let sim = Transform::new(Mat4::from_rotation_x(0.7) * Mat4::from_scale(Vec3::splat(3.0)));
        close(sim.similarity_scale().unwrap(), 3.0, 1e-5);
        close(sim.area_scale(Vec3::Z), 9.0, 1e-4);
        let (lo, hi) = t.bounds(Vec3::splat(-1.0), Vec3::splat(1.0));
        for i in 0..8 {
            let c = Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
            let p = t.point(c * 2.0 - Vec3::ONE);
            assert!(p.cmpge(lo).all() && p.cmple(hi).all());
        }
    }

    #[test]
    fn coordinate_system_is_right_handed_orthonormal() {
        let mut rng = Rng::new(3);
        for _ in 0..100 {
            let v = rng.v3().normalize();
            let (a, b) = coordinate_system(v);
            close(a.length(), 1.0, 1e-5);
            close(b.length(), 1.0, 1e-5);
            close(a.dot(v), 0.0, 1e-5);
            close3(a.cross(b), v, 1e-5);
        }
    }

    #[test]
    fn quadratic_roots_are_ordered_and_stable() {
        let (t0, t1) = quadratic_roots(1.0, -3.0, 2.0, 1.0).unwrap();
        assert_eq!((t0, t1), (1.0, 2.0));
        // Large b: the small root keeps its precision.
        let (a, b, c) = (1.0, 1e8, 1.0);
        let (t0, t1) = quadratic_roots(a, b, c, b * b - 4.0 * a * c).unwrap();
        assert!((t1 + 1e-8).abs() < 1e-20 && (t0 + 1e8).abs() < 1.0);
        assert!(quadratic_roots(1.0, 0.0, 1.0, -4.0).is_none());
    }
}

#[cfg(test)]
mod weingarten_tests {
    use super::*;

    #[test]
    fn a_sphere_s_normal_turns_as_its_point_over_the_radius() {
        // pbrt-v3's full sphere of radius r at phi, theta (theta runs from thetaZMin = pi at
        // z = -r to thetaZMax = 0: dtheta = -pi): dn/du = dp/du / r, the outward normal's.
        let (r, phi, theta) = (0.9f32, 0.7f32, 1.1f32);
        let pm = std::f32::consts::TAU;
        let dt = -std::f32::consts::PI;
        let p = r * Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        );
        let dpdu = Vec3::new(-pm * p.y, pm * p.x, 0.0);
        let dpdv = dt * Vec3::new(p.z * phi.cos(), p.z * phi.sin(), -r * theta.sin());
        let second = [
            -pm * pm * Vec3::new(p.x, p.y, 0.0),
            dt * p.z * pm * Vec3::new(-phi.sin(), phi.cos(), 0.0),
            -dt * dt * p,
        ];
        let (dndu, dndv) = weingarten(dpdu, dpdv, second);
        assert!((dndu - dpdu / r).length() < 1e-4, "{dndu} {}", dpdu / r);
        assert!((dndv - dpdv / r).length() < 1e-4, "{dndv} {}", dpdv / r);
        // A plane's normal does not turn.
        let flat = weingarten(Vec3::X, Vec3::Y, [Vec3::ZERO; 3]);
        assert_eq!(flat, (Vec3::ZERO, Vec3::ZERO));
    }
}
