//! Rays, frames, surface interactions and robust ray spawning.

pub use glam::{Mat3, Mat4, Quat, Vec2, Vec3};

/// Linear RGB radiance or reflectance.
pub type Spectrum = Vec3;

/// A ray with a time (for motion blur). Its extent is kept by the caller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub o: Vec3,
    /// Direction (not necessarily normalised).
    pub d: Vec3,
    /// Time within the shutter interval, in scene time units.
    pub time: f32,
}

impl Ray {
    /// A ray from `o` along `d` at `time`.
    pub fn new(o: Vec3, d: Vec3, time: f32) -> Self {
        Self { o, d, time }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// An orthonormal frame: local z is `n`.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// Local x.
    pub s: Vec3,
    /// Local y.
    pub t: Vec3,
    /// Local z.
    pub n: Vec3,
}

impl Frame {
    /// A frame around unit `n` (Duff et al. 2017, branchless and continuous almost everywhere).
    pub fn from_z(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// A frame with z = unit `n` and x as close as possible to `s` (Gram-Schmidt); falls back to
    /// [`Frame::from_z`] when `s` is parallel to `n` or degenerate.
    #[inline]
    pub fn from_xz(s: Vec3, n: Vec3) -> Self {
        let s = (s - n * n.dot(s)).normalize_or_zero();
        if s == Vec3::ZERO || !s.is_finite() {
            return Self::from_z(n);
        }
        Self {
            s,
            t: n.cross(s),
            n,
        }
    }

    /// World to local.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local to world.
    #[inline]
    pub fn from_local(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Where a ray meets a surface, with pbrt's differential geometry.
#[derive(Clone, Copy, Debug, Default)]
pub struct SurfaceInteraction {
    /// The hit point.
    pub p: Vec3,
    /// Unit geometric normal, on the side pbrt orients it (flipped by ReverseOrientation and by
    /// handedness-changing transforms).
    pub n: Vec3,
    /// Surface parameters.
    pub uv: Vec2,
    /// dp/du.
    pub dpdu: Vec3,
    /// dp/dv.
    pub dpdv: Vec3,
    /// Unit shading normal (interpolated vertex normals), on the same side as `n`.
    pub shading_n: Vec3,
    /// Shading dp/du (the tangent the BSDF frame is aligned with).
    pub shading_dpdu: Vec3,
    /// Shading dp/dv (pbrt-v3's `shading.dpdv`: dpdv, or for a mesh with vertex normals the
    /// unit tangent `ns x ss`), which bump mapping perturbs with `shading_dpdu`.
    pub shading_dpdv: Vec3,
    /// dn/du, the normal's derivative (pbrt-v3's Weingarten equations on the quadrics; zero on
    /// triangles, where pbrt-v3 differentiates the vertex normals), which bump mapping adds
    /// times the displacement; the same for the shading normal.
    pub dndu: Vec3,
    /// dn/dv.
    pub dndv: Vec3,
    /// Unit direction towards where the ray came from (-ray.d normalised).
    pub wo: Vec3,
    /// The ray's time.
    pub time: f32,
    /// How far off the surface spawned rays start, beyond the rounding offset: pbrt-v3's error
    /// bound where it is large (two widths on curves, which face every ray); 0 elsewhere.
    pub p_error: f32,
    /// How the point and (u, v) change from pixel to pixel (zero unless the ray came from the
    /// camera with differentials).
    pub diff: SurfaceDifferentials,
}

/// The rays through the next pixel right and the next pixel down (pbrt-v3's
/// `RayDifferential`), scaled to the sample spacing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayDifferentials {
    /// Origin of the ray one pixel right.
    pub rx_o: Vec3,
    /// Its direction.
    pub rx_d: Vec3,
    /// Origin of the ray one pixel down.
    pub ry_o: Vec3,
    /// Its direction.
    pub ry_d: Vec3,
}

impl RayDifferentials {
    /// Scales the offsets from `ray` by `s` (pbrt-v3's `ScaleDifferentials`: 1 / sqrt(spp)).
    pub fn scaled(self, ray: &Ray, s: f32) -> Self {
        Self {
            rx_o: ray.o + (self.rx_o - ray.o) * s,
            ry_o: ray.o + (self.ry_o - ray.o) * s,
            rx_d: ray.d + (self.rx_d - ray.d) * s,
            ry_d: ray.d + (self.ry_d - ray.d) * s,
        }
    }
}

/// The screen-space derivatives of a hit's position and (u, v) (pbrt-v3's `dpdx`, `dpdy`,
/// `dudx`, `dvdx`, `dudy`, `dvdy`), from its ray's differentials.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceDifferentials {
    /// dp/dx.
    pub dpdx: Vec3,
    /// dp/dy.
    pub dpdy: Vec3,
    /// du/dx.
    pub dudx: f32,
    /// dv/dx.
    pub dvdx: f32,
    /// du/dy.
    pub dudy: f32,
    /// dv/dy.
    pub dvdy: f32,
}

/// Offsets a point off a surface so that a ray leaving it does not hit that surface again.
/// Wächter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection" (Ray Tracing
/// Gems, ch. 6): an offset of a fixed number of ulps along the normal, which scales with the
/// point's magnitude and so stays safe far from the origin; near the origin, a small absolute
/// offset instead.
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let of_i = (n * INT_SCALE).as_ivec3();
    let bump = |p: f32, o: i32| -> f32 {
        let bits = p.to_bits() as i32;
        f32::from_bits((bits + if p < 0.0 { -o } else { o }) as u32)
    };
    let p_i = Vec3::new(bump(p.x, of_i.x), bump(p.y, of_i.y), bump(p.z, of_i.z));
    Vec3::new(
        if p.x.abs() < ORIGIN {
            p.x + FLOAT_SCALE * n.x
        } else {
            p_i.x
        },
        if p.y.abs() < ORIGIN {
            p.y + FLOAT_SCALE * n.y
        } else {
            p_i.y
        },
        if p.z.abs() < ORIGIN {
            p.z + FLOAT_SCALE * n.z
        } else {
            p_i.z
        },
    )
}

impl SurfaceInteraction {
    /// For tests: a point `p` with coordinates `uv` on the plane z = const facing +z, its
    /// tangents x and y, seen from +z.
    #[cfg(test)]
    pub(crate) fn flat(p: Vec3, uv: Vec2) -> Self {
        Self {
            p,
            n: Vec3::Z,
            uv,
            dpdu: Vec3::X,
            dpdv: Vec3::Y,
            shading_n: Vec3::Z,
            shading_dpdu: Vec3::X,
            shading_dpdv: Vec3::Y,
            dndu: Vec3::ZERO,
            dndv: Vec3::ZERO,
            wo: Vec3::Z,
            time: 0.0,
            p_error: 0.0,
            diff: SurfaceDifferentials::default(),
        }
    }

    /// pbrt-v3's `ComputeDifferentials`: where the offset rays meet the tangent plane, and the
    /// (u, v) steps that reach those points, by least squares over the two coordinates the
    /// normal leaves best conditioned. Zero when an offset ray runs parallel to the plane.
    pub fn compute_differentials(&mut self, rd: &RayDifferentials) {
        let n = self.n;
        let d = n.dot(self.p);
        let tx = -(n.dot(rd.rx_o) - d) / n.dot(rd.rx_d);
        let ty = -(n.dot(rd.ry_o) - d) / n.dot(rd.ry_d);
        if !tx.is_finite() || !ty.is_finite() {
            self.diff = SurfaceDifferentials::default();
            return;
        }
        let px = rd.rx_o + tx * rd.rx_d;
        let py = rd.ry_o + ty * rd.ry_d;
        let (dpdx, dpdy) = (px - self.p, py - self.p);
        let dim = if n.x.abs() > n.y.abs() && n.x.abs() > n.z.abs() {
            [1, 2]
        } else if n.y.abs() > n.z.abs() {
            [0, 2]
        } else {
            [0, 1]
        };
        let a = [
            [self.dpdu[dim[0]], self.dpdv[dim[0]]],
            [self.dpdu[dim[1]], self.dpdv[dim[1]]],
        ];
        let bx = [dpdx[dim[0]], dpdx[dim[1]]];
        let by = [dpdy[dim[0]], dpdy[dim[1]]];
        let solve = |b: [f32; 2]| -> (f32, f32) {
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            if det.abs() < 1e-10 {
                return (0.0, 0.0);
            }
            let x0 = (a[1][1] * b[0] - a[0][1] * b[1]) / det;
            let x1 = (a[0][0] * b[1] - a[1][0] * b[0]) / det;
            if !x0.is_nan() && !x1.is_nan() {
                (x0, x1)
            } else {
                (0.0, 0.0)
            }
        };
        let (dudx, dvdx) = solve(bx);
        let (dudy, dvdy) = solve(by);
        self.diff = SurfaceDifferentials {
            dpdx,
            dpdy,
            dudx,
            dvdx,
            dudy,
            dvdy,
        };
    }

    /// The geometric normal flipped to the side of `w`.
    #[inline]
    pub fn n_towards(&self, w: Vec3) -> Vec3 {
        if self.n.dot(w) < 0.0 {
            -self.n
        } else {
            self.n
        }
    }

    /// What spawning a ray from the point needs (its point, normal, error bound and time).
    #[inline]
    pub fn crossing(&self) -> Crossing {
        Crossing {
            p: self.p,
            n: self.n,
            p_error: self.p_error,
            time: self.time,
        }
    }

    /// A ray leaving the surface along `d`, its origin offset to the side `d` points to.
    #[inline]
    pub fn spawn_ray(&self, d: Vec3) -> Ray {
        self.crossing().spawn_ray(d)
    }

    /// A shadow ray towards `target` and the parameter just short of it (for t in (0, tmax)).
    #[inline]
    pub fn spawn_ray_to(&self, target: Vec3) -> (Ray, f32) {
        self.crossing().spawn_ray_to(target)
    }
}

/// Where a ray meets a surface, with only what spawning the ray that goes on needs: a ray
/// crossing an interface surface (`Material ""`) or a probe ray passing other surfaces needs
/// no (u, v), tangents or shading frame (docs/media.md). The full [`SurfaceInteraction`]'s
/// values (on spheres the normal to a few ulps).
#[derive(Clone, Copy, Debug)]
pub struct Crossing {
    /// The hit point.
    pub p: Vec3,
    /// Unit geometric normal, oriented as [`SurfaceInteraction::n`].
    pub n: Vec3,
    /// The point's error bound ([`SurfaceInteraction::p_error`]).
    pub p_error: f32,
    /// The ray's time.
    pub time: f32,
}

impl Crossing {
    /// The geometric normal flipped to the side of `w`.
    #[inline]
    fn n_towards(&self, w: Vec3) -> Vec3 {
        if self.n.dot(w) < 0.0 {
            -self.n
        } else {
            self.n
        }
    }

    /// A ray leaving the surface along `d`, its origin offset to the side `d` points to.
    #[inline]
    pub fn spawn_ray(&self, d: Vec3) -> Ray {
        let n = self.n_towards(d);
        Ray::new(
            offset_ray_origin(self.p + n * self.p_error, n),
            d,
            self.time,
        )
    }

    /// A shadow ray towards `target` and the parameter just short of it (for t in (0, tmax)).
    #[inline]
    pub fn spawn_ray_to(&self, target: Vec3) -> (Ray, f32) {
        let n = self.n_towards(target - self.p);
        let o = offset_ray_origin(self.p + n * self.p_error, n);
        (Ray::new(o, target - o, self.time), 1.0 - SHADOW_EPSILON)
    }
}

/// How far short of a light's surface a shadow ray stops (relative to its length).
pub const SHADOW_EPSILON: f32 = 1e-4;

/// Whether `a` is finite and non-negative in every channel.
#[inline]
pub fn is_valid_radiance(a: Spectrum) -> bool {
    a.is_finite() && a.min_element() >= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::X,
        ] {
            let f = Frame::from_z(n);
            assert!((f.s.dot(f.t)).abs() < 1e-6 && (f.s.dot(f.n)).abs() < 1e-6);
            assert!((f.s.cross(f.t) - f.n).length() < 1e-5);
            let v = Vec3::new(0.2, 0.4, -0.7);
            assert!((f.from_local(f.to_local(v)) - v).length() < 1e-6);
        }
    }

    #[test]
    fn offset_moves_off_the_surface_far_from_origin() {
        for scale in [1e-3f32, 1.0, 1e3, 1e6] {
            let p = Vec3::new(scale, -scale, 0.5 * scale);
            let n = Vec3::new(0.0, 0.0, 1.0);
            let q = offset_ray_origin(p, n);
            assert!(q.z > p.z, "{scale}: {q} {p}");
            assert!(q.x == p.x || (q.x - p.x).abs() < 1e-6 * scale.max(1.0));
        }
    }
}
