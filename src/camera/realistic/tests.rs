use super::*;
use crate::lightdistrib::radical_inverse;

const DGAUSS: &str = include_str!("../../../scenes/pbrt-v3/lenses/dgauss.50mm.dat");

/// The double-Gauss focused at `focus` metres on a 35 mm film, the pupil bounded with
/// `samples` points a ring.
fn dgauss(focus: f32, aperture: f32, simple: bool, samples: u32) -> LensSystem {
    let rows = parse_lens_file(DGAUSS).unwrap();
    let mut clamped = None;
    LensSystem::new(&rows, aperture, focus, 0.035, simple, samples, &mut clamped).unwrap()
}

#[test]
fn the_lens_file_is_read_as_pbrt_v3_reads_it() {
    let rows = parse_lens_file(DGAUSS).unwrap();
    assert_eq!(rows.len(), 11);
    assert_eq!(rows[0].values, [29.475, 3.76, 1.67, 25.2]);
    assert_eq!(rows[0].line, 8);
    assert_eq!(rows[5].values, [0.0, 4.5, 0.0, 17.1]);
    assert_eq!(rows[10].line, 18);
    // Numbers may run across lines and share them: pbrt-v3 reads a stream of floats.
    let rows = parse_lens_file("1 2\n 3 4 # comment 5 6\n5 6 7 8").unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[1].values, [5.0, 6.0, 7.0, 8.0]);
    assert_eq!(rows[1].line, 3);
}

#[test]
fn malformed_lens_files_are_refused_with_their_line() {
    for (text, says) in [
        ("", "no lens element"),
        ("# only a comment\n", "no lens element"),
        ("1 2 3 4\n5 6 7", "7 values is not a multiple of four"),
        ("1 2 3 4\n5 nan 7 8", "line 2: NaN is not a finite number"),
        ("1 2 3 4\n\n5 6 inf 8", "line 3: inf is not a finite number"),
        ("1 -2 3 4", "line 1: thickness -2 is negative"),
        ("1 2 -3 4", "line 1: index of refraction -3 is negative"),
        ("1 2 3 0", "line 1: aperture diameter 0 is not positive"),
        ("1 2 3 4\n5 6 seven 8", "line 2: \"seven\" is not a number"),
    ] {
        let e = parse_lens_file(text).unwrap_err();
        assert!(e.contains(says), "{text:?}: {e}");
    }
}

#[test]
fn rays_from_the_film_centre_meet_at_the_focus_distance() {
    for focus in [0.5f32, 2.0, 10.0] {
        let lens = dgauss(focus, 4.0, true, 4096);
        // Near-axis rays through the stopped-down lens: the thick-lens focus holds, up to the
        // lens's spherical aberration (3% at 10 m for the outer ray).
        let pupil = lens.exit_pupil_bounds[0];
        for x in [0.1f32, 0.2, 0.4] {
            let rear = Vec3::new(x * pupil.max.x, 0.0, lens.rear_z());
            let out = lens
                .trace_from_film(LensRay {
                    o: Vec3::ZERO,
                    d: rear,
                })
                .expect("a near-axis ray passes");
            let t = -out.o.x / out.d.x;
            let z = out.o.z + out.d.z * t;
            assert!((z / focus - 1.0).abs() < 0.05, "focus {focus}, x {x}: {z}");
        }
    }
    // Focusing closer moves the lens away from the film.
    assert!(dgauss(0.5, 4.0, true, 1024).rear_z() > dgauss(10.0, 4.0, true, 1024).rear_z());
}

#[test]
fn every_ray_through_the_lens_leaves_within_the_exit_pupil_bounds() {
    let lens = dgauss(5.0, 17.1, true, 256 * 256);
    let n = lens.exit_pupil_bounds.len();
    assert_eq!(n, 64);
    let rear = lens.rear_radius();
    let mut passed = 0;
    for k in 0..40u32 {
        let r_film = (k as f32 + 0.37) / 40.0 * lens.film_diagonal / 2.0;
        let i = ((r_film / (lens.film_diagonal / 2.0) * n as f32) as usize).min(n - 1);
        let b = lens.exit_pupil_bounds[i];
        for j in 0..400u32 {
            let u = Vec2::new(radical_inverse(2, j), radical_inverse(3, j));
            let p = crate::sampling::concentric_sample_disk(u) * rear;
            let film = Vec3::new(r_film, 0.0, 0.0);
            let ray = LensRay {
                o: film,
                d: Vec3::new(p.x, p.y, lens.rear_z()) - film,
            };
            if lens.trace_from_film(ray).is_some() {
                passed += 1;
                assert!(b.inside(p), "ring {i}: {p} outside {b:?}");
            }
        }
    }
    assert!(passed > 1000, "{passed}");
    // The pupil shrinks towards the film's corner (vignetting).
    assert!(lens.exit_pupil_bounds[63].area() < lens.exit_pupil_bounds[0].area());
}

#[test]
fn weights_are_pbrt_v3s() {
    let res = (64.0, 64.0);
    let centre = Vec2::new(32.0, 32.0);
    let simple = dgauss(2.0, 8.0, true, 4096);
    let (ray, w) = simple
        .camera_ray(centre, res, Vec2::splat(0.5), 1.0)
        .unwrap();
    // cos^4 = 1 at the centre, and the centre ring's area over itself.
    assert!((w - 1.0).abs() < 1e-4, "{w}");
    // Out of the lens, towards the scene (+z in camera space).
    assert!(ray.d.z > 0.0 && ray.o.z > 0.0, "{ray:?}");
    let full = dgauss(2.0, 8.0, false, 4096);
    let (_, w) = full.camera_ray(centre, res, Vec2::splat(0.5), 0.5).unwrap();
    let expected = 0.5 * full.exit_pupil_bounds[0].area() / (full.rear_z() * full.rear_z());
    assert!((w / expected - 1.0).abs() < 1e-5, "{w} {expected}");
    // A corner gets less light on average than the centre.
    let mean = |raster: Vec2| {
        let mut sum = 0.0;
        for j in 0..1024u32 {
            let u = Vec2::new(radical_inverse(2, j), radical_inverse(3, j));
            sum += simple
                .camera_ray(raster, res, u, 1.0)
                .map_or(0.0, |(_, w)| w);
        }
        sum / 1024.0
    };
    assert!(mean(Vec2::new(0.5, 0.5)) < 0.9 * mean(centre));
}

#[test]
fn the_aperture_is_clamped_to_the_stops() {
    let rows = parse_lens_file(DGAUSS).unwrap();
    let mut clamped = None;
    let lens = LensSystem::new(&rows, 30.0, 2.0, 0.035, true, 1024, &mut clamped).unwrap();
    assert_eq!(clamped, Some(17.1));
    assert!((lens.elements[5].aperture_radius - 0.00855).abs() < 1e-7);
    let mut clamped = None;
    let lens = LensSystem::new(&rows, 4.0, 2.0, 0.035, true, 1024, &mut clamped).unwrap();
    assert_eq!(clamped, None);
    assert!((lens.elements[5].aperture_radius - 0.002).abs() < 1e-7);
}

#[test]
fn degenerate_lenses_are_errors_not_panics() {
    let mut clamped = None;
    // A focus closer than the lens can reach.
    let rows = parse_lens_file(DGAUSS).unwrap();
    let e = LensSystem::new(&rows, 4.0, 0.01, 0.035, true, 1024, &mut clamped).unwrap_err();
    assert!(matches!(e, LensError::TooClose(_)), "{e:?}");
    // A stop no paraxial ray passes (its aperture far below the film-diagonal offset).
    let rows = parse_lens_file("50 5 1.5 20\n0 5 0 0.00001\n-50 40 1 20").unwrap();
    let e = LensSystem::new(&rows, 1.0, 2.0, 0.035, true, 1024, &mut clamped).unwrap_err();
    assert!(matches!(e, LensError::NoParaxialRay), "{e:?}");
    // Zero thicknesses between elements: a lens all the same.
    let rows = parse_lens_file("50 0 1.5 20\n0 0 0 10\n-50 0 1 20").unwrap();
    if let Ok(lens) = LensSystem::new(&rows, 8.0, 2.0, 0.035, true, 1024, &mut clamped) {
        for j in 0..64 {
            let u = Vec2::new(radical_inverse(2, j), radical_inverse(3, j));
            if let Some((r, w)) = lens.camera_ray(Vec2::new(3.0, 50.0), (64.0, 64.0), u, 1.0) {
                assert!(w.is_finite() && r.d.is_finite());
            }
        }
    }
}
