//! Rendering tests: every example scene renders; analytic cases converge to their known values;
//! acr agrees with pbrt-v3's own renders of the public scenes in ../shared.

use acr::film::Film;
use acr::geometry::Spectrum;
use acr::integrator::Integrator;
use acr::parser::{parse_file, parse_str, Param, ParamType, SceneDescription, Values};
use acr::render::{kernel_from_desc, render};
use acr::scene::Scene;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Sets the film resolution in the description (as if the scene file said so).
fn set_resolution(desc: &mut SceneDescription, w: u32, h: u32) {
    let film = desc.film.get_or_insert_with(|| acr::parser::PluginDesc {
        kind: "image".into(),
        params: Default::default(),
        loc: acr::parser::Loc::new(&desc.files[0], 0),
    });
    let loc = film.loc.clone();
    film.params.push(Param::new(
        ParamType::Integer,
        "xresolution",
        Values::Ints(vec![w as i32]),
        loc.clone(),
    ));
    film.params.push(Param::new(
        ParamType::Integer,
        "yresolution",
        Values::Ints(vec![h as i32]),
        loc,
    ));
}

struct Rendered {
    pixels: Vec<Spectrum>,
    width: usize,
    dropped: u64,
}

fn render_desc(desc: &SceneDescription, spp: u32, seed: u64) -> Rendered {
    let mut warnings = Vec::new();
    let scene = Scene::build(desc, &mut warnings).unwrap_or_else(|e| panic!("{e}"));
    let integrator = Integrator::new(desc.integrator.as_ref(), &mut warnings).unwrap();
    let kernel = kernel_from_desc(desc.filter.as_ref()).unwrap();
    let mut film = Film::new(scene.film.clone(), kernel);
    let counts = render(&scene, &integrator, &mut film, spp, seed, None);
    Rendered {
        pixels: film.pixels(),
        width: scene.film.size().0 as usize,
        dropped: counts.dropped,
    }
}

fn mean(p: &[Spectrum]) -> Spectrum {
    p.iter().copied().sum::<Spectrum>() / p.len() as f32
}

#[test]
fn every_example_scene_renders_at_low_resolution() {
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "pbrt"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 5);
    for s in scenes {
        let mut desc = parse_file(&s).unwrap();
        set_resolution(&mut desc, 48, 36);
        let r = render_desc(&desc, 4, 1);
        assert_eq!(r.pixels.len(), 48 * 36);
        assert_eq!(r.dropped, 0, "{}", s.display());
        let m = mean(&r.pixels);
        assert!(m.is_finite(), "{}", s.display());
        // Lit, not black, not blown out.
        let lum = acr::spectrum_luminance(m);
        assert!(lum > 0.01 && lum < 10.0, "{}: mean {m}", s.display());
    }
}

/// Inside a closed sphere that emits L = 1 and reflects with albedo 0.5, radiance is
/// L / (1 - albedo) = 2 everywhere (the white furnace, with emission).
#[test]
fn furnace_converges_to_the_known_value() {
    let desc = parse_str(
        "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 60\n\
         Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
         Integrator \"path\" \"integer maxdepth\" 100\nWorldBegin\n\
         ReverseOrientation\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n\
         Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\nShape \"sphere\" \"float radius\" 1\nWorldEnd",
        Path::new("furnace.pbrt"),
    )
    .unwrap();
    let r = render_desc(&desc, 64, 7);
    let m = mean(&r.pixels);
    for c in m.to_array() {
        assert!((c - 2.0).abs() < 0.02, "furnace mean {m}, expected 2");
    }
}

/// A diffuse sphere of albedo 0.6 under a constant environment of radiance 1, direct light
/// only: every visible point of a lone convex sphere sees the whole environment above it, so
/// its radiance is exactly the albedo; the background is the environment.
#[test]
fn diffuse_sphere_under_constant_environment() {
    let desc = parse_str(
        "LookAt 0 0 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
         Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 32\n\
         PixelFilter \"box\"\nIntegrator \"path\" \"integer maxdepth\" 1\nWorldBegin\n\
         LightSource \"infinite\" \"rgb L\" [1 1 1]\n\
         Material \"matte\" \"rgb Kd\" [0.6 0.6 0.6]\nShape \"sphere\" \"float radius\" 1\nWorldEnd",
        Path::new("envsphere.pbrt"),
    )
    .unwrap();
    let r = render_desc(&desc, 64, 3);
    // The sphere subtends 29 degrees of the 40-degree view: the centre is sphere, the
    // corners (27 degrees off axis) are background.
    let centre: Vec<Spectrum> = (12..20)
        .flat_map(|y| (12..20).map(move |x| (x, y)))
        .map(|(x, y)| r.pixels[y * r.width + x])
        .collect();
    let m = mean(&centre);
    assert!(
        (m.x - 0.6).abs() < 0.01,
        "sphere radiance {m}, expected 0.6"
    );
    let corner = r.pixels[0];
    assert!((corner.x - 1.0).abs() < 1e-4, "background {corner}");
}

#[test]
fn same_seed_same_image_whatever_the_thread_count() {
    let mut desc = parse_file(&root().join("scenes/motion-dof.pbrt")).unwrap();
    set_resolution(&mut desc, 40, 30);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let a = one.install(|| render_desc(&desc, 8, 5).pixels);
    let b = two.install(|| render_desc(&desc, 8, 5).pixels);
    assert_eq!(a, b);
    let c = two.install(|| render_desc(&desc, 8, 6).pixels);
    assert_ne!(a, c, "a different seed must give a different image");
}

/// pbrt-v3's README figures: MSE at 8 spp (veach-mis 4 spp) against its own 64-spp reference,
/// on 8-bit sRGB values in [0, 1].
const PBRT_V3_MSE: &[(&str, &str, u32, f64)] = &[
    (
        "killeroo-simple/killeroo-simple.pbrt",
        "killeroo-simple-ref64.exr",
        8,
        5.5e-4,
    ),
    (
        "cornell-box/cornell_box.pbrt",
        "cornell_box-ref64.exr",
        8,
        4.1e-3,
    ),
    (
        "spheres-motion/spheres-motion.pbrt",
        "spheres-motion-ref64.exr",
        8,
        6.0e-4,
    ),
    ("veach-mis/mis.pbrt", "mis-ref64.exr", 4, 1.9e-2),
];

/// MSE of two images after pbrt's 8-bit sRGB conversion (clamp, gamma, round).
fn srgb8_mse(a: &[Spectrum], b: &[Spectrum]) -> f64 {
    let q = |v: f32| -> f64 {
        let v = v.clamp(0.0, 1.0);
        let s = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round() as f64 / 255.0
    };
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (0..3).map(|c| (q(x[c]) - q(y[c])).powi(2)).sum::<f64>())
        .sum();
    sum / (3 * a.len()) as f64
}

/// At the scene's spp, acr's MSE against pbrt-v3's 64-spp reference is within 1.25x pbrt-v3's
/// own figure (so there is no bias beyond noise), at the scene's full resolution.
#[test]
fn agrees_with_pbrt_v3_references() {
    let dir = root().join("../shared/scenes/pbrt-v3");
    if !dir.is_dir() {
        eprintln!("skipped: {} is absent", dir.display());
        return;
    }
    let mut failures = Vec::new();
    for &(scene, reference, spp, pbrt_mse) in PBRT_V3_MSE {
        let desc = parse_file(&dir.join(scene)).unwrap();
        let r = render_desc(&desc, spp, 11);
        let reference =
            acr::image_io::read_image(&dir.join("references").join(reference), false).unwrap();
        assert_eq!(reference.pixels.len(), r.pixels.len(), "{scene}");
        let mse = srgb8_mse(&r.pixels, &reference.pixels);
        eprintln!(
            "{scene}: acr MSE {mse:.3e} vs pbrt-v3 {pbrt_mse:.1e} (ratio {:.2})",
            mse / pbrt_mse
        );
        if mse > 1.25 * pbrt_mse {
            failures.push(format!(
                "{scene}: MSE {mse:.3e} > 1.25 x pbrt-v3's {pbrt_mse:.1e}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The public pbrt-v3 scenes without a reference render: at reduced resolution and 2 spp they
/// build and render with no sample dropped and a lit, finite image.
#[test]
fn public_pbrt_v3_scenes_without_references_render() {
    let dir = root().join("../shared/scenes/pbrt-v3");
    if !dir.is_dir() {
        eprintln!("skipped: {} is absent", dir.display());
        return;
    }
    for scene in [
        "anim-bluespheres.pbrt",
        "caustic.pbrt",
        "spheres-differentials-texfilt.pbrt",
    ] {
        let mut desc = parse_file(&dir.join(scene)).unwrap();
        set_resolution(&mut desc, 80, 40);
        let r = render_desc(&desc, 2, 1);
        assert_eq!(r.dropped, 0, "{scene}");
        let m = mean(&r.pixels);
        let lum = acr::spectrum_luminance(m);
        assert!(m.is_finite() && lum > 0.01, "{scene}: mean {m}");
    }
}
