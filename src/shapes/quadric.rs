//! What pbrt-v3's quadrics share: the stable quadratic, the choice between its two roots when
//! the nearer one is cut away, the azimuth, the differential geometry carried to world space
//! (with the Weingarten equations for dn/du and dn/dv) and the world-space area.

use super::Transform;
use crate::geometry::{Ray, SurfaceInteraction, Vec2, Vec3};

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

/// pbrt-v3's choice of hit among the roots `t0 <= t1` of a quadric: the nearer root in
/// (0, t_max], or the farther one when the nearer is behind the ray or cut away (`at` returns
/// `None` for a root whose point the shape's z range or azimuth removes). Every quadric runs
/// this same sequence of tests.
#[inline]
pub(crate) fn nearest_root<H>(
    (t0, t1): (f64, f64),
    t_max: f32,
    at: impl Fn(f32) -> Option<H>,
) -> Option<(f32, H)> {
    let t_max = t_max as f64;
    if t0 > t_max || t1 <= 0.0 {
        return None;
    }
    let first = if t0 > 0.0 { t0 } else { t1 };
    if first > t_max {
        return None;
    }
    let (t, hit) = match at(first as f32) {
        Some(h) => (first, h),
        None if first == t1 || t1 > t_max => return None,
        None => (t1, at(t1 as f32)?),
    };
    let t = t as f32;
    (t > 0.0).then_some((t, hit))
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
    let (dndu, dndv) = second.map_or((Vec3::ZERO, Vec3::ZERO), |d2| weingarten(dpdu, dpdv, d2));
    let n = quadric_normal(to_world, flip, dpdu, dpdv);
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
        p_error: 0.0,
        diff: Default::default(),
    }
}

/// A quadric's world-space unit normal, as [`quadric_interaction`] orients it: normalize(dpdu x
/// dpdv) flipped when `flip`, carried to world space by the inverse transpose.
#[inline]
pub(crate) fn quadric_normal(to_world: &Transform, flip: bool, dpdu: Vec3, dpdv: Vec3) -> Vec3 {
    let n_obj = dpdu.cross(dpdv).normalize_or(Vec3::Z);
    let n_obj = if flip { -n_obj } else { n_obj };
    to_world.normal(n_obj).normalize_or(n_obj)
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
mod tests {
    use super::*;

    #[test]
    fn nearest_root_falls_back_to_the_far_root() {
        let keep_all = |t: f32| Some(t);
        assert_eq!(nearest_root((1.0, 2.0), 10.0, keep_all), Some((1.0, 1.0)));
        // Behind the origin: the far root.
        assert_eq!(nearest_root((-1.0, 2.0), 10.0, keep_all), Some((2.0, 2.0)));
        // The near root cut: the far one; both cut: none.
        let cut_near = |t: f32| (t > 1.5).then_some(t);
        assert_eq!(nearest_root((1.0, 2.0), 10.0, cut_near), Some((2.0, 2.0)));
        assert_eq!(nearest_root((1.0, 2.0), 10.0, |_| None::<f32>), None);
        // Beyond t_max.
        assert_eq!(nearest_root((1.0, 2.0), 1.5, cut_near), None);
        assert_eq!(nearest_root((1.0, 2.0), 0.5, keep_all), None);
        assert_eq!(nearest_root((-2.0, -1.0), 10.0, keep_all), None);
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
