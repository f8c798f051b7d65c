//! Property tests (proptest) of the transforms: inverses round-trip, pbrt's constructors undo
//! one another, and a motion interpolated between two transforms meets them at the shutter's
//! ends (its decomposition into translation, rotation and scale recomposes to each end).

use acr::parser::transform::{look_at, rotate, scale, translate};
use acr::parser::AnimatedTransform;
use acr::shapes::Transform;
use acr::transform::MotionTransform;
use glam::{DMat4, DVec3, Mat4, Vec3};
use proptest::prelude::*;

/// Largest entry-wise difference of `a` and `b`, relative to `size`.
fn rel_diff(a: &Mat4, b: &Mat4, size: f32) -> f32 {
    let (a, b) = (a.to_cols_array(), b.to_cols_array());
    let diff = a
        .iter()
        .zip(&b)
        .fold(0.0f32, |m, (x, y)| m.max((x - y).abs()));
    diff / size.max(1e-30)
}

/// The largest entry of either matrix.
fn largest(a: &DMat4, b: &DMat4) -> f32 {
    a.to_cols_array()
        .iter()
        .chain(&b.to_cols_array())
        .fold(0.0f64, |m, x| m.max(x.abs())) as f32
}

/// A unit axis from three numbers (z when they are all near zero).
fn axis(v: [f64; 3]) -> DVec3 {
    DVec3::from_array(v).try_normalize().unwrap_or(DVec3::Z)
}

/// Any affine transform pbrt scenes make: translate, rotate, scale (each axis 0.01 to 100,
/// either sign, so reflections too), rotate again.
fn affine() -> impl Strategy<Value = DMat4> {
    (
        proptest::array::uniform3(-1e3f64..1e3),
        proptest::array::uniform3(-1.0f64..1.0),
        -360.0f64..360.0,
        proptest::array::uniform3(-2.0f64..2.0),
        proptest::array::uniform3(any::<bool>()),
        proptest::array::uniform3(-1.0f64..1.0),
        -360.0f64..360.0,
    )
        .prop_map(|(t, a1, r1, log_s, neg, a2, r2)| {
            let s = DVec3::from_array(std::array::from_fn(|i| {
                10f64.powf(log_s[i]) * if neg[i] { -1.0 } else { 1.0 }
            }));
            translate(DVec3::from_array(t))
                * rotate(r1, axis(a1)).unwrap_or(DMat4::IDENTITY)
                * scale(s)
                * rotate(r2, axis(a2)).unwrap_or(DMat4::IDENTITY)
        })
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 512,
        // Fixed: CI runs the same cases every time (a failure reproduces); change the seed
        // to explore further.
        rng_seed: proptest::test_runner::RngSeed::Fixed(0xacc0_5eed),
        ..ProptestConfig::default()
    })]

    /// A point, a vector and a normal taken through a transform and its inverse come back.
    #[test]
    fn transforms_round_trip_through_their_inverse(
        m in affine(),
        p in proptest::array::uniform3(-100.0f32..100.0),
    ) {
        let t = Transform::new(m.as_mat4());
        let p = Vec3::from_array(p);
        let back = t.inverse().point(t.point(p));
        // f32 rounding of values up to |m| (|p| + 1), amplified by up to |m^-1|.
        let largest = |m: &Mat4| m.to_cols_array().iter().fold(0.0f32, |a, x| a.max(x.abs()));
        let tol = 1e-5 * largest(&t.inv) * largest(&t.m) * (1.0 + p.abs().max_element());
        prop_assert!((back - p).abs().max_element() <= tol, "{} -> {}", p, back);
        let v = t.inverse().vector(t.vector(p));
        prop_assert!((v - p).abs().max_element() <= tol, "vector {} -> {}", p, v);
        // Products with the inverse are the identity (in f64, as the scene builder keeps them).
        let inv = m.inverse();
        let big = |m: &DMat4| m.to_cols_array().iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let id = m * inv;
        prop_assert!(id.abs_diff_eq(DMat4::IDENTITY, 1e-13 * big(&m) * big(&inv)), "{:?}", id);
    }

    /// Rotations undo one another, and LookAt's inverse puts the camera at `pos` looking at
    /// `look`.
    #[test]
    fn pbrt_constructors_undo_one_another(
        a in proptest::array::uniform3(-1.0f64..1.0),
        degrees in -720.0f64..720.0,
        pos in proptest::array::uniform3(-1e4f64..1e4),
        dir in proptest::array::uniform3(-1.0f64..1.0),
        up in proptest::array::uniform3(-1.0f64..1.0),
    ) {
        let ax = axis(a);
        let r = rotate(degrees, ax).unwrap() * rotate(-degrees, ax).unwrap();
        prop_assert!(r.abs_diff_eq(DMat4::IDENTITY, 1e-12));
        let (pos, dir) = (DVec3::from_array(pos), DVec3::from_array(dir));
        let up = DVec3::from_array(up);
        prop_assume!(dir.length() > 1e-3 && up.length() > 1e-3);
        prop_assume!(dir.normalize().cross(up.normalize()).length() > 1e-3);
        let camera_from_world = look_at(pos, pos + dir, up).unwrap();
        let world_from_camera = camera_from_world.inverse();
        let eye = world_from_camera.transform_point3(DVec3::ZERO);
        prop_assert!((eye - pos).length() <= 1e-9 * (1.0 + pos.length()), "eye {}", eye);
        let forward = world_from_camera.transform_vector3(DVec3::Z);
        prop_assert!((forward - dir.normalize()).length() < 1e-9, "forward {}", forward);
    }

    /// A moving transform equals its ends at the shutter's ends and is continuous there:
    /// the decomposition recomposes each end, for any pair of affine transforms.
    #[test]
    fn motion_meets_its_ends_at_the_shutters_ends(
        start in affine(),
        end in affine(),
        t0 in -1.0f64..1.0,
        length in 0.01f64..2.0,
    ) {
        let t1 = t0 + length;
        let motion = MotionTransform::new(&AnimatedTransform {
            start,
            end,
            start_time: t0,
            end_time: t1,
        });
        prop_assert!(motion.is_moving());
        prop_assert_eq!(motion.at(t0 as f32), start.as_mat4());
        prop_assert_eq!(motion.at(t1 as f32), end.as_mat4());
        prop_assert_eq!(motion.at(t0 as f32 - 1.0), start.as_mat4());
        prop_assert_eq!(motion.at(t1 as f32 + 1.0), end.as_mat4());
        // Just inside the shutter the interpolation's own recomposition is used; it may move
        // by up to 1e-4 of the motion (the largest entry of either end) from the end.
        let size = largest(&start, &end);
        let eps = (length * 1e-4) as f32;
        let near_start = motion.at(t0 as f32 + eps);
        let near_end = motion.at(t1 as f32 - eps);
        prop_assert!(
            rel_diff(&near_start, &start.as_mat4(), size) < 2e-3,
            "start {:?} vs {:?}", near_start, start.as_mat4()
        );
        prop_assert!(
            rel_diff(&near_end, &end.as_mat4(), size) < 2e-3,
            "end {:?} vs {:?}", near_end, end.as_mat4()
        );
        // In between it stays finite.
        prop_assert!(motion.at((t0 + 0.5 * length) as f32).is_finite());
    }
}
