#![allow(dead_code)] // each fuzz target uses one of these
//! What each fuzz target checks on one input, shared by the targets (fuzz_targets/) and by the
//! ordinary test run, which replays every input kept in fuzz/regressions/TARGET/
//! (tests/fuzz_regressions.rs). Each function panics exactly when the input exposes a bug.

use acr::integrator::Integrator;
use std::path::Path;

/// Where fuzzed scenes pretend to live: a folder that does not exist, so that `Include` and
/// file names fail cleanly instead of reading whatever the fuzzer names.
const SCENE_PATH: &str = "/nonexistent-acr-fuzz/scene.pbrt";

/// Tokenizer, parser and graphics state: a description or an error, never a panic.
pub fn parse(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = acr_parser::parse_str(text, Path::new(SCENE_PATH));
    }
}

/// The PLY reader: a mesh whose indices are all in range, or an error.
pub fn ply(data: &[u8]) {
    if let Ok(ply) = acr_parser::ply::parse_ply(data) {
        let n = ply.mesh.positions.len();
        assert!(ply.mesh.indices.iter().all(|&i| (i as usize) < n));
        assert_eq!(ply.mesh.indices.len() % 3, 0);
    }
}

/// A `.bsdf` table (the `fourier` material's `bsdffile`): a table or an error, never a panic;
/// a table of modest finite numbers evaluates, samples and gives densities without NaN.
pub fn fourier(data: &[u8]) {
    use acr::fourier::{FourierBsdf, FourierTable};
    use acr::geometry::Vec3;
    let Ok(table) = FourierTable::parse(data) else {
        return;
    };
    // Huge or non-finite coefficients overflow pbrt-v3's arithmetic as they would ours; the
    // check is for tables a layered-BSDF tool could write.
    let modest = data
        .get(64..)
        .unwrap_or_default()
        .chunks_exact(4)
        .all(|w| f32::from_le_bytes([w[0], w[1], w[2], w[3]]).abs() <= 1e4)
        && table.eta.is_finite();
    // The material keeps tables for the process's life; this one is reclaimed below so that
    // the fuzzer's leak check stays meaningful.
    let table: &'static FourierTable = Box::leak(Box::new(table));
    let bsdf = FourierBsdf { table };
    let dirs = [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.6, 0.0, 0.8),
        Vec3::new(0.0, -0.6, -0.8),
        Vec3::new(0.48, 0.6, 0.64),
        Vec3::new(1.0, 0.0, 0.0),
    ];
    for &wo in &dirs {
        for &wi in &dirs {
            let (f, pdf) = (bsdf.f(wo, wi), bsdf.pdf(wo, wi));
            assert!(!modest || !(f.x.is_nan() || f.y.is_nan() || f.z.is_nan() || pdf.is_nan()));
        }
        for u in [[0.1, 0.2], [0.5, 0.5], [0.99, 0.01]] {
            if let Some((wi, f, pdf)) = bsdf.sample_f(wo, u) {
                let nan = wi.x.is_nan() || f.x.is_nan() || f.y.is_nan() || f.z.is_nan();
                assert!(!modest || !(nan || pdf.is_nan()), "sampled NaN");
            }
        }
    }
    // SAFETY: `table` came from `Box::leak` above and `bsdf`, its only user, is not used again.
    drop(unsafe { Box::from_raw(table as *const FourierTable as *mut FourierTable) });
}

/// `acr merge`'s inputs: an EXR's bytes read as a crop placed in its frame and as a mergeable
/// EXR's sums, or an error, never a panic; a crop lies within its frame, and sums added to
/// themselves double.
pub fn merge(data: &[u8]) {
    if let Ok((crop, frame)) = acr::image_io::decode_image_with_frame(data, "exr") {
        assert!(frame.x0 + crop.width <= frame.width && frame.y0 + crop.height <= frame.height);
        assert!(frame.width.saturating_mul(frame.height) <= acr::image_io::MAX_IMAGE_PIXELS);
        assert_eq!(crop.pixels.len(), crop.width * crop.height);
    }
    let Ok(layer) = acr::exr_channels::Channels::decode(data) else {
        return;
    };
    let f = layer.frame;
    assert!(f.x0 + layer.width <= f.width && f.y0 + layer.height <= f.height);
    let Some(sums) = acr::cli::mergeable::Sums::from_channels(layer) else {
        return;
    };
    let n = sums.width * sums.height;
    assert_eq!(sums.sums.len(), n);
    let mut twice = sums.clone();
    twice.add(&sums).expect("a crop merges with itself");
    assert_eq!(twice.image().len(), n);
    let _ = twice.variance();
}

/// Parse, build the scene (shapes, BVH, materials, textures, lights) and choose its plugins.
pub fn scene(data: &[u8]) {
    let _ = built(data);
}

/// The scene and its plugins, if the input makes them.
fn built(data: &[u8]) -> Option<(acr::scene::Scene, acr::registry::Plugins)> {
    let text = std::str::from_utf8(data).ok()?;
    let desc = acr_parser::parse_str(text, Path::new(SCENE_PATH)).ok()?;
    let mut warnings = Vec::new();
    let mut scene = acr::scene::Scene::build(&desc, &mut warnings).ok()?;
    // A 4x3 film keeps every input quick; the film's limits and scale stay.
    let mut film = acr_plugins::FilmSettings::with_resolution(4, 3);
    film.scale = scene.film.scale;
    film.max_sample_luminance = scene.film.max_sample_luminance;
    film.max_component_value = scene.film.max_component_value;
    scene.film = film;
    let plugins = acr::registry::choose_for_scene(
        &desc,
        &scene,
        &Default::default(),
        Some(1),
        0,
        &mut warnings,
    )
    .ok()?;
    Some((scene, plugins))
}

/// Everything a scene drives: [`scene`], then 1 sample per pixel of the 4x3 film (paths at
/// most 8 bounces, so that a hall of mirrors cannot stall the fuzzer) and the reconstruction.
/// The image has no NaN (radiance near f32::MAX times the film's scale may overflow to
/// infinity; that is arithmetic, not a bug).
pub fn render(data: &[u8]) {
    let Some((scene, mut plugins)) = built(data) else {
        return;
    };
    match &mut plugins.integrator {
        Integrator::Path { max_depth, .. }
        | Integrator::Direct { max_depth, .. }
        | Integrator::Whitted { max_depth } => {
            *max_depth = (*max_depth).min(8);
        }
        Integrator::VolPath(settings) => settings.max_depth = settings.max_depth.min(8),
        // A small bootstrap and few chains, so that a scene's defaults cannot stall it.
        Integrator::Mlt(settings) => {
            settings.max_depth = settings.max_depth.min(8);
            settings.bootstrap_samples = settings.bootstrap_samples.min(64);
            settings.chains = settings.chains.min(16);
        }
        Integrator::AmbientOcclusion(settings) => settings.samples = settings.samples.min(8),
        Integrator::Sppm(s) => {
            s.max_depth = s.max_depth.min(8);
            s.iterations = s.iterations.min(2);
            s.photons_per_iteration = Some(s.photons_per_iteration.unwrap_or(64).min(64));
        }
        Integrator::Bdpt(settings) => settings.max_depth = settings.max_depth.min(8),
    }
    let mut film = plugins.film(&scene);
    acr::render::render(
        &scene,
        &plugins.integrator,
        plugins.sampler.as_mut(),
        &mut film,
        0,
        None,
        None,
    );
    let image = plugins.image(&film);
    assert!(image.iter().all(|p| !p.is_nan()), "a pixel is NaN");
}
