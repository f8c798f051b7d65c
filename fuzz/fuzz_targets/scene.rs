//! The whole path from text to a renderable scene: parse, build the scene (shapes, BVH,
//! materials, textures, lights) and choose its plugins. Any input gives a scene or an error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("/nonexistent-acr-fuzz/scene.pbrt");
    let Ok(desc) = acr_parser::parse_str(text, path) else {
        return;
    };
    let mut warnings = Vec::new();
    let Ok(scene) = acr::scene::Scene::build(&desc, &mut warnings) else {
        return;
    };
    let setup = || acr_plugins::SamplerSetup {
        space: acr::render::rendering_space(&scene),
        spp: None,
        seed: 0,
    };
    let _ = acr::registry::choose(&desc, &Default::default(), setup, &mut warnings);
});
