//! Tests of the lights: the environment map's lookups, and the goniometric and projection
//! lights against pbrt-v3.

use super::light_image::HITHER;
use super::*;
use crate::accel::Geometry;
use std::path::Path;

fn infinite(width: usize, rgb: Spectrum) -> Light {
    let image = RgbImage {
        width,
        height: 1,
        pixels: vec![rgb; width],
    };
    let m = Mat4::from_rotation_x(0.7) * Mat4::from_rotation_z(-0.3);
    Light::Infinite {
        l: Spectrum::new(2.0, 1.0, 0.5),
        map: Some(EnvMap::new(&image)),
        light_from_world: m.inverse(),
        world_from_light: m,
        world_radius: 10.0,
    }
}

/// A one-pixel map (pbrt-v3's constant environment) answers without spherical
/// coordinates: the same radiance as a uniform map read through them. It is sampled
/// uniformly over the sphere, and `sample_li` gives the density and radiance that `pdf_le`
/// and `le` give for the direction it picks (what MIS weighs against BSDF sampling).
#[test]
fn a_constant_environment_matches_the_general_lookup() {
    let rgb = Spectrum::new(0.3, 0.6, 0.9);
    let (constant, general) = (infinite(1, rgb), infinite(2, rgb));
    let world = Geometry::default();
    for k in 0..1024 {
        let u = Vec2::new(
            ((k % 32) as f32 + 0.5) / 32.0,
            ((k / 32) as f32 + 0.5) / 32.0,
        );
        let d = crate::sampling::uniform_sample_sphere(u);
        let (a, b) = (constant.le(d), general.le(d));
        assert!((a - b).abs().max_element() <= 1e-6, "{d}: {a} against {b}");
        assert_eq!(constant.pdf_le(d), 1.0 / (4.0 * PI));
        let s = constant.sample_li(&world, Vec3::ZERO, u).unwrap();
        assert!((s.wi.length() - 1.0).abs() < 1e-5);
        assert_eq!(s.pdf, constant.pdf_le(s.wi));
        assert!((s.li - constant.le(s.wi)).abs().max_element() <= 1e-6);
    }
}

/// The light-to-world transforms of `tests/data/pbrt-v3/lightimagecheck.cpp`.
fn transforms() -> [DMat4; 2] {
    let rot = |deg: f64, axis: [f64; 3]| {
        DMat4::from_axis_angle(glam::DVec3::from(axis).normalize(), deg.to_radians())
    };
    let t = |x: f64, y: f64, z: f64| DMat4::from_translation(glam::DVec3::new(x, y, z));
    [
        t(0.3, -0.2, 0.5) * rot(35.0, [1.0, 2.0, 0.5]),
        t(-0.4, 0.6, 0.1)
            * rot(-70.0, [0.3, -1.0, 0.8])
            * DMat4::from_scale(glam::DVec3::new(1.5, 0.8, 1.2)),
    ]
}

fn image(name: &str) -> LightImage {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3");
    let img = crate::image_io::read_image(&dir.join(name), false).unwrap();
    LightImage::new(&img).unwrap()
}

/// The lights of `lightimagecheck.cpp`, in its order.
fn lights() -> Vec<Light> {
    let [a, b] = transforms();
    let i = Spectrum::new(1.5, 0.75, 2.0);
    let (wide, tall) = (image("lightimage-8x4.exr"), image("lightimage-4x8.exr"));
    vec![
        Light::goniometric(&a, i, Some(wide.clone())).unwrap(),
        Light::goniometric(&b, i, None).unwrap(),
        Light::projection(&a, i, Some(wide), 60.0).unwrap(),
        Light::projection(&b, i, Some(tall), 30.0).unwrap(),
        Light::projection(&a, i, None, 45.0).unwrap(),
    ]
}

/// How far the screen point of the direction from `light` to `p` lies from the screen
/// window's edges (infinite for other lights): where pbrt-v3's and acr's transforms, a few
/// ulps apart, may put it on either side.
fn edge_distance(light: &Light, p: Vec3) -> f32 {
    let Light::Projection {
        pos,
        light_from_world,
        projection,
        ..
    } = light
    else {
        return f32::INFINITY;
    };
    let wl = light_from_world.transform_vector3(-(*pos - p).normalize());
    let s = projection.screen_point(wl);
    let (lo, hi) = projection.screen_window();
    let d = (s.x - lo.x)
        .abs()
        .min((s.x - hi.x).abs())
        .min((s.y - lo.y).abs())
        .min((s.y - hi.y).abs());
    d.min((wl.z - HITHER).abs())
}

/// `Sample_Li` and `Power` of pbrt-v3's goniometric and projection lights, printed by
/// `tests/data/pbrt-v3/lightimagecheck.cpp` (linked with pbrt-v3's libpbrt.a; it says
/// how) at 300 points around each light (the projections' half
/// behind or outside their frustum): acr's agree to 1e-5 (relative), power to 1e-4.
#[test]
fn samples_match_pbrt_v3() {
    let lights = lights();
    let world = Geometry::default();
    let data = include_str!("../../tests/data/pbrt-v3/lightimage.txt");
    let (mut lit, mut dark, mut edge, mut worst) = ([0; 5], [0; 5], 0, 0f32);
    for line in data.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        let f = |i: usize| -> f32 { w[i].parse().unwrap() };
        let v3 = |i: usize| Vec3::new(f(i), f(i + 1), f(i + 2));
        let l: usize = w[1].parse().unwrap();
        if w[0] == "power" {
            let got = lights[l].power();
            assert!(
                (got - v3(2)).abs().max_element() <= 1e-4 * v3(2).max_element(),
                "{got}\n{line}"
            );
            continue;
        }
        let (p, wi, li, pdf) = (v3(2), v3(5), v3(8), f(11));
        let got = lights[l].sample_li(&world, p, Vec2::new(0.5, 0.5));
        if li == Spectrum::ZERO {
            if let Some(s) = got {
                assert!(
                    edge_distance(&lights[l], p) < 1e-5,
                    "acr lights where pbrt-v3 does not: {s:?}\n{line}"
                );
                edge += 1;
            } else {
                dark[l] += 1;
            }
            continue;
        }
        let Some(s) = got else {
            assert!(
                edge_distance(&lights[l], p) < 1e-5,
                "acr is dark where pbrt-v3 lights:\n{line}"
            );
            edge += 1;
            continue;
        };
        lit[l] += 1;
        assert_eq!(pdf, 1.0);
        assert_eq!(s.pdf, 1.0);
        assert!(
            (s.wi - wi).abs().max_element() < 1e-5,
            "wi {}\n{line}",
            s.wi
        );
        let err = (s.li - li).abs().max_element() / li.max_element();
        assert!(err <= 1e-5, "li {}\n{line}", s.li);
        worst = worst.max(err);
    }
    // Every light was lit from some points, and the projections dark from others.
    assert!(lit.iter().all(|&n| n > 50), "{lit:?}");
    assert!(dark[2..].iter().all(|&n| n > 20), "{dark:?}");
    assert!(edge <= 2, "{edge} points on an edge");
    eprintln!("lit {lit:?}, dark {dark:?}, on an edge {edge}, largest relative error {worst:.2e}");
}

/// Every light choice handles the image lights: finite, positive power; bounds whose cone
/// holds every direction a projection light sends (under a scale and a rotation); each
/// strategy can choose each light where it shines, with a finite probability.
#[test]
fn light_choice_handles_image_lights() {
    use crate::lightbvh::{LightBounds, LightContext};
    use crate::lightdistrib::LightStrategy;
    let text = "Camera \"perspective\"\nWorldBegin\n\
        AttributeBegin\nTranslate 0 3 0\nRotate 90 1 0 0\nScale 1 2 0.5\n\
        LightSource \"projection\" \"string mapname\" \"lightimage-8x4.exr\" \"float fov\" 50\n\
        AttributeEnd\n\
        AttributeBegin\nTranslate 2 1 0\nRotate 30 0 0 1\n\
        LightSource \"goniometric\" \"string mapname\" \"lightimage-4x8.exr\" \"rgb I\" [2 1 1]\n\
        AttributeEnd\n\
        AttributeBegin\nTranslate -2 2 0\nRotate 120 1 0 0\n\
        LightSource \"projection\" \"rgb I\" [1 2 3] \"float fov\" 20\n\
        AttributeEnd\n\
        AttributeBegin\nTranslate 0 1 -4\n\
        LightSource \"goniometric\" \"point3 from\" [0 0 0]\nAttributeEnd\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" \
        [-5 0 -5 5 0 -5 5 0 5 -5 0 5]\nWorldEnd\n";
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3");
    let desc = acr_parser::parse_str(text, &dir.join("image-lights.pbrt")).unwrap();
    let mut warnings = Vec::new();
    let scene = crate::scene::Scene::build(&desc, &mut warnings).unwrap();
    assert_eq!(scene.lights.len(), 4);
    // pbrt-v3's lights take no "from": reported unused, as pbrt-v3 does.
    assert_eq!(desc.unused_parameter_warnings().len(), 1);
    for light in &scene.lights {
        let power = light.power();
        assert!(power.is_finite() && power.min_element() > 0.0, "{power}");
        let b = LightBounds::of(light, &scene.accel.world).unwrap();
        assert!(format!("{b:?}").find("NaN").is_none(), "{b:?}");
        let Light::Projection {
            pos,
            light_from_world,
            projection,
            ..
        } = light
        else {
            continue;
        };
        let (axis, cos) = projection.world_cone(&light_from_world.inverse());
        assert!(cos > 0.0 && cos < 1.0, "{cos}");
        // Directions it lights lie in the cone; the cone is not much wider than they are.
        let mut widest = 1.0f32;
        for i in 0..20000 {
            let u = Vec2::new((i as f32 + 0.5) / 20000.0, (i as f32 * 0.618_034).fract());
            let w = crate::sampling::uniform_sample_sphere(u);
            if projection.eval(light_from_world.transform_vector3(w)) != Spectrum::ZERO {
                assert!(w.dot(axis) >= cos, "{w} outside the cone of {pos}");
                widest = widest.min(w.dot(axis));
            }
        }
        assert!(widest - cos < 0.05, "{widest} {cos}");
    }
    // From under each light, every strategy can pick it.
    let points = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.3)];
    for strategy in [
        LightStrategy::Uniform,
        LightStrategy::Power,
        LightStrategy::Spatial,
        LightStrategy::Bvh,
    ] {
        for p in points {
            let ctx = LightContext { p, n: Vec3::Y };
            let mut seen = [false; 4];
            for i in 0..64 {
                let (l, pdf) = scene
                    .choose_light(strategy, ctx, (i as f32 + 0.5) / 64.0)
                    .unwrap();
                assert!(pdf > 0.0 && pdf.is_finite(), "{strategy:?} {l} {pdf}");
                assert_eq!(pdf, scene.light_choice_pdf(strategy, ctx, l));
                seen[l] = true;
            }
            // The first projection light shines on the origin, the first goniometric
            // light everywhere.
            assert!(seen[1], "{strategy:?} at {p}: {seen:?}");
            if p == Vec3::ZERO {
                assert!(seen[0], "{strategy:?} at {p}: {seen:?}");
            }
        }
    }
}

/// An image that cannot be read and a field of view outside (0, 180) are errors at their
/// place in the file (pbrt-v3 goes on without the image, or with a degenerate frustum).
#[test]
fn bad_maps_and_fov_are_located_errors() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3");
    for (light, want) in [
        (
            "\"goniometric\"\n  \"string mapname\" \"missing.exr\"",
            "lights.pbrt:4:3: cannot read \"missing.exr\"",
        ),
        (
            "\"projection\"\n  \"string mapname\" \"lightimagecheck.cpp\"",
            "lights.pbrt:4:3: cannot read \"lightimagecheck.cpp\": unsupported image format",
        ),
        (
            "\"projection\" \"float fov\" 180",
            "lights.pbrt:3:1: projection light: fov 180 is not between 0 and 180",
        ),
    ] {
        let text = format!("Camera \"perspective\"\nWorldBegin\nLightSource {light}\nWorldEnd\n");
        let desc = acr_parser::parse_str(&text, &dir.join("lights.pbrt")).unwrap();
        let err = crate::scene::Scene::build(&desc, &mut Vec::new())
            .err()
            .unwrap();
        let msg = err.to_string();
        assert!(msg.contains(want), "{msg}");
    }
}
