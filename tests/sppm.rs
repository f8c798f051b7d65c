//! The `sppm` integrator (pbrt-v3's stochastic progressive photon mapping,
//! docs/light-transport.md): agreement with pbrt-v3's own render of scenes/pbrt-v3/sppm.pbrt,
//! determinism whatever the thread count, `--spp` as its iterations, the samplers it refuses,
//! located errors for nonsense parameters, and the lights' emitted rays (`sample_le`).

use acr::geometry::{Spectrum, Vec2};
use acr::integrator::Integrator;
use acr::light::emission::sample_le;
use acr::parser::{parse_file, parse_str, SceneDescription};
use acr::registry::{choose_for_scene, Overrides};
use acr::scene::Scene;
use std::path::{Path, PathBuf};

mod common;
use common::in_process::render_in_process;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The image `desc` renders to with `spp` (sppm's iterations) and `seed`, with the samples
/// dropped.
fn render_desc(desc: &SceneDescription, spp: Option<u32>, seed: u64) -> (Vec<Spectrum>, u64) {
    let r = render_in_process(desc, &Overrides::default(), spp, seed);
    (r.pixels, r.counts.dropped)
}

fn mean_luminance(p: &[Spectrum]) -> f64 {
    let m = p.iter().copied().sum::<Spectrum>() / p.len() as f32;
    f64::from(acr::spectrum_luminance(m))
}

fn mse(a: &[Spectrum], b: &[Spectrum]) -> f64 {
    assert_eq!(a.len(), b.len());
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| f64::from((*x - *y).length_squared()) / 3.0)
        .sum();
    sum / a.len() as f64
}

fn read(name: &str) -> Vec<Spectrum> {
    let path = root().join("scenes/pbrt-v3/references").join(name);
    acr::image_io::read_image(&path, false).unwrap().pixels
}

/// At the scene's 64 iterations, acr's image mean is within 1% of pbrt-v3's converged render
/// (1024 iterations) and of pbrt-v3's own at 64 iterations, and its MSE against the converged
/// render (linear values) is within 1.25x pbrt-v3's at 64 (scenes/pbrt-v3/README.md).
#[test]
fn sppm_agrees_with_pbrt_v3() {
    let desc = parse_file(&root().join("scenes/pbrt-v3/sppm.pbrt")).unwrap();
    let (image, dropped) = render_desc(&desc, None, 11);
    assert_eq!(dropped, 0);
    let reference = read("sppm-ref1024.exr");
    let pbrt = read("sppm-pbrt64.exr");
    let ratio = mean_luminance(&image) / mean_luminance(&reference);
    let pbrt_ratio = mean_luminance(&image) / mean_luminance(&pbrt);
    let (ours, theirs) = (mse(&image, &reference), mse(&pbrt, &reference));
    eprintln!(
        "sppm: mean / reference {ratio:.4}, / pbrt-v3 at 64 {pbrt_ratio:.4}; MSE {ours:.3e}, \
         pbrt-v3's {theirs:.3e} (ratio {:.2})",
        ours / theirs
    );
    assert!((ratio - 1.0).abs() < 0.01, "mean ratio {ratio:.4}");
    assert!(
        (pbrt_ratio - 1.0).abs() < 0.01,
        "mean ratio {pbrt_ratio:.4}"
    );
    assert!(ours <= 1.25 * theirs, "MSE {ours:.3e} vs {theirs:.3e}");
}

/// A small sppm scene: a point light and an area light over a matte floor, behind a glass
/// sphere; `params` go on the Integrator line.
fn small_scene(params: &str) -> String {
    format!(
        "LookAt 0 1 4  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
         Film \"image\" \"integer xresolution\" 24 \"integer yresolution\" 20\n\
         Integrator \"sppm\" {params}\nWorldBegin\n\
         LightSource \"point\" \"point from\" [0.5 2.5 0.5] \"rgb I\" [4 4 4]\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [3 3 3]\n\
         Translate 0 3 0\nRotate 90 1 0 0\nShape \"disk\" \"float radius\" 0.5\nAttributeEnd\n\
         Material \"matte\" \"rgb Kd\" [0.6 0.5 0.4]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point P\" [-3 0 -3  -3 0 3  3 0 3  3 0 -3]\n\
         AttributeBegin\nMaterial \"glass\"\nTranslate 0 0.6 0\n\
         Shape \"sphere\" \"float radius\" 0.5\nAttributeEnd\nWorldEnd\n"
    )
}

/// The same seed gives the same image in a pool of 1 thread and of 3 (the photons' flux is
/// summed in photon order), and another seed another image.
#[test]
fn sppm_is_the_same_whatever_the_thread_count() {
    let desc = parse_str(
        &small_scene(
            "\"integer iterations\" 3 \"integer photonsperiteration\" 3000 \"float radius\" 0.2",
        ),
        Path::new("small.pbrt"),
    )
    .unwrap();
    let in_pool = |threads: usize, seed: u64| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render_desc(&desc, None, seed).0)
    };
    let one = in_pool(1, 5);
    assert!(mean_luminance(&one) > 0.01);
    assert_eq!(one, in_pool(3, 5));
    assert_ne!(one, in_pool(3, 6));
}

/// `--spp` (the render's spp) sets the iterations; without it, the scene's.
#[test]
fn spp_sets_the_iterations() {
    let desc = parse_str(
        &small_scene("\"integer iterations\" 7"),
        Path::new("small.pbrt"),
    )
    .unwrap();
    let iterations = |spp: Option<u32>| {
        let mut warnings = Vec::new();
        let scene = Scene::build(&desc, &mut warnings).unwrap();
        let p =
            choose_for_scene(&desc, &scene, &Overrides::default(), spp, 1, &mut warnings).unwrap();
        match p.integrator {
            Integrator::Sppm(s) => s.iterations,
            _ => panic!("not sppm"),
        }
    };
    assert_eq!(iterations(None), 7);
    assert_eq!(iterations(Some(3)), 3);
}

/// The error `choose_for_scene` gives for the scene `text`, with `overrides`.
fn choice_error(text: &str, overrides: &Overrides) -> String {
    let desc = parse_str(text, Path::new("bad.pbrt")).unwrap();
    let mut warnings = Vec::new();
    let scene = Scene::build(&desc, &mut warnings).unwrap();
    match choose_for_scene(&desc, &scene, overrides, None, 1, &mut warnings) {
        Ok(_) => panic!("accepted: {text}"),
        Err(e) => e.to_string(),
    }
}

/// Zero photons, a radius that is not positive, zero iterations, a negative depth: errors at
/// the parameter's line, never a panic.
#[test]
fn nonsense_parameters_are_located_errors() {
    for (params, says) in [
        ("\"integer photonsperiteration\" 0", "photonsperiteration"),
        ("\"float radius\" -1", "radius -1"),
        ("\"float radius\" 0", "radius 0"),
        ("\"integer iterations\" 0", "iterations 0"),
        ("\"integer numiterations\" -2", "numiterations -2"),
        ("\"integer maxdepth\" -1", "maxdepth -1"),
        ("\"integer imagewritefrequency\" 0", "imagewritefrequency 0"),
    ] {
        let e = choice_error(&small_scene(params), &Overrides::default());
        assert!(e.contains("bad.pbrt:4:"), "{params}: {e}");
        assert!(e.contains(says), "{params}: {e}");
    }
}

/// An adaptive sampler and a noise threshold are refused with a message that says sppm draws
/// its own samples.
#[test]
fn adaptive_samplers_are_refused() {
    let overrides = Overrides {
        sampler: Some("mdas".into()),
        ..Overrides::default()
    };
    let e = choice_error(&small_scene(""), &overrides);
    assert!(e.contains("mdas") && e.contains("sppm"), "{e}");
    // `--noise-threshold` too (`acr render` asks before it renders); a plain sampler is not.
    let desc = parse_str(&small_scene(""), Path::new("ok.pbrt")).unwrap();
    let mut warnings = Vec::new();
    let scene = Scene::build(&desc, &mut warnings).unwrap();
    let p = choose_for_scene(&desc, &scene, &Overrides::default(), None, 1, &mut warnings).unwrap();
    let e = acr::integrator::sppm::refuse(p.sampler.as_ref(), true).unwrap();
    assert!(e.contains("--noise-threshold") && e.contains("sppm"), "{e}");
    assert_eq!(
        acr::integrator::sppm::refuse(p.sampler.as_ref(), false),
        None
    );
}

/// Every light's `sample_le` rays carry its power: the mean of Le |cos| / (pdf_pos pdf_dir)
/// over many rays is the light's `power()` (pbrt-v3's `Power` is exact for these lights; an
/// infinite light's is taken over the directions too).
#[test]
fn emitted_rays_carry_the_lights_power() {
    let text = "LookAt 0 1 4  0 0.5 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
        LightSource \"point\" \"point from\" [0.5 2.5 0.5] \"rgb I\" [4 3 2]\n\
        LightSource \"distant\" \"point from\" [1 2 3] \"point to\" [0 0 0] \"rgb L\" [1 2 3]\n\
        LightSource \"infinite\" \"rgb L\" [0.5 0.25 1]\n\
        LightSource \"goniometric\" \"rgb I\" [2 2 2]\n\
        AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [3 2 1]\n\
        Translate 0 3 0\nRotate 90 1 0 0\nShape \"disk\" \"float radius\" 0.5\nAttributeEnd\n\
        AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 2] \"bool twosided\" true\n\
        Translate 1 1 0\nShape \"sphere\" \"float radius\" 0.25\nAttributeEnd\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [-3 0 -3  -3 0 3  3 0 3]\n\
        WorldEnd\n";
    let desc = parse_str(text, Path::new("lights.pbrt")).unwrap();
    let scene = Scene::build(&desc, &mut Vec::new()).unwrap();
    assert_eq!(scene.lights.len(), 6);
    let n = 64 * 64;
    for (i, light) in scene.lights.iter().enumerate() {
        let mut sum = Spectrum::ZERO;
        for k in 0..n {
            // A stratified grid over u1 and, shuffled against it, over u2.
            let (a, b) = (k % 64, k / 64);
            let u1 = Vec2::new((a as f32 + 0.5) / 64.0, (b as f32 + 0.5) / 64.0);
            let c = (k * 37 + 11) % n;
            let u2 = Vec2::new(
                ((c % 64) as f32 + 0.5) / 64.0,
                ((c / 64) as f32 + 0.5) / 64.0,
            );
            if let Some(s) = sample_le(&scene, light, u1, u2, 0.0) {
                assert!((s.ray.d.length() - 1.0).abs() < 1e-4);
                sum += s.le * (s.n.dot(s.ray.d).abs() / (s.pdf_pos * s.pdf_dir));
            }
        }
        let mean = sum / n as f32;
        // pbrt-v3's `Power` of an infinite light is its radiance over the scene's disc (pi r^2
        // L); its rays come from every direction, 4 pi times as much.
        let power = match light {
            acr::light::Light::Infinite { .. } => light.power() * 4.0 * std::f32::consts::PI,
            _ => light.power(),
        };
        for c in 0..3 {
            let rel = (mean[c] / power[c] - 1.0).abs();
            assert!(rel < 0.01, "light {i}: mean {mean} vs power {power}");
        }
    }
}

/// A spot light's rays carry I times its falloff integrated over the cone:
/// 2 pi I ((1 - cos_start) + (cos_start - cos_total) / 5) for pbrt-v3's quartic smoothstep
/// (pbrt-v3's `Power` is an approximation of it, so the exact integral is the yardstick).
#[test]
fn spot_rays_carry_the_falloff_integral() {
    let text = "LookAt 0 1 4  0 0.5 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
        LightSource \"spot\" \"point from\" [0 2 0] \"point to\" [1 0 0.5] \"rgb I\" [3 2 1]\n\
        \"float coneangle\" 40 \"float conedeltaangle\" 15\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [-3 0 -3  -3 0 3  3 0 3]\n\
        WorldEnd\n";
    let desc = parse_str(text, Path::new("spot.pbrt")).unwrap();
    let scene = Scene::build(&desc, &mut Vec::new()).unwrap();
    let light = &scene.lights[0];
    let (n, mut sum) = (256 * 256, Spectrum::ZERO);
    for k in 0..n {
        let u1 = Vec2::new(
            ((k % 256) as f32 + 0.5) / 256.0,
            ((k / 256) as f32 + 0.5) / 256.0,
        );
        if let Some(s) = sample_le(&scene, light, u1, Vec2::splat(0.5), 0.0) {
            // Inside the cone around the axis from (0 2 0) to (1 0 0.5).
            let axis = acr::geometry::Vec3::new(1.0, -2.0, 0.5).normalize();
            assert!(s.ray.d.dot(axis) >= 40f32.to_radians().cos() - 1e-4);
            sum += s.le * (s.n.dot(s.ray.d).abs() / (s.pdf_pos * s.pdf_dir));
        }
    }
    let (ct, cs) = (40f32.to_radians().cos(), 25f32.to_radians().cos());
    let want =
        Spectrum::new(3.0, 2.0, 1.0) * 2.0 * std::f32::consts::PI * ((1.0 - cs) + (cs - ct) / 5.0);
    let mean = sum / n as f32;
    assert!(
        (mean - want).abs().max_element() < 0.005 * want.max_element(),
        "{mean} vs {want}"
    );
}
