//! Shapes as pbrt-v3 defines them: triangle meshes (stored in the space they are given, world
//! space for static meshes) and the quadrics sphere, disk, cylinder, cone, paraboloid and
//! hyperboloid (stored in object space
//! with their object-to-world transform). Parametrisations, normals and orientation rules follow
//! pbrt-v3 so that texture coordinates and shading agree with its images.

pub mod cone;
pub mod curve;
pub mod cylinder;
pub mod disk;
pub mod heightfield;
pub mod hyperboloid;
pub mod loopsubdiv;
pub mod nurbs;
pub mod paraboloid;
pub mod profile;
pub mod quadric;
pub mod revolved;
pub mod sphere;
pub mod triangle;

pub use curve::{Curve, CurveCommon, CurveHit};
pub use cylinder::{Cylinder, CylinderHit};
pub use disk::{Disk, DiskHit};
pub use revolved::{Revolved, RevolvedHit};
pub use sphere::{Sphere, SphereHit};
pub use triangle::{TriangleHit, TriangleMesh};

use crate::geometry::{Mat3, Mat4, Ray, Vec3};

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

    /// Asserts `a` is within `eps` of pbrt-v3's `b`, relative to 1 + |b|'s largest component;
    /// `line` (the reference data's line) goes in the message.
    #[track_caller]
    pub fn close_rel(a: Vec3, b: Vec3, eps: f32, what: &str, line: &str) {
        let scale = 1.0 + b.abs().max_element();
        assert!(
            (a - b).abs().max_element() <= eps * scale,
            "{what}: {a} != pbrt-v3's {b}\n{line}"
        );
    }

    /// The parameters and location of the one shape of `text`, parsed as file `file`.
    pub fn shape_params(text: &str, file: &str) -> (acr_parser::ParamList, acr_parser::Loc) {
        let full = format!("WorldBegin {text} WorldEnd");
        let d = acr_parser::parse_str(&full, std::path::Path::new(file)).unwrap();
        let s = &d.shapes[0];
        (s.plugin.params.clone(), s.plugin.loc.clone())
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
}
