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
        Integrator::Path { max_depth, .. } | Integrator::Direct { max_depth, .. } => {
            *max_depth = (*max_depth).min(8);
        }
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
