//! What the tests that render in process share: the render itself, as `acr render` makes it
//! without its stop rules, and the measure agreement with pbrt-v3 is stated in.

use acr::geometry::Spectrum;
use acr::parser::{SceneDescription, Warning};
use acr::registry::{choose_for_scene, Overrides};
use acr::render::{render, RenderCounts};
use acr::scene::Scene;

/// What an in-process render made.
pub struct Rendered {
    /// The image, row-major over the crop, the film's scale applied.
    pub pixels: Vec<Spectrum>,
    /// Its width in pixels.
    pub width: usize,
    /// The warnings of the parse, the build and the plugins' choice.
    pub warnings: Vec<Warning>,
    /// What the render loop counted.
    pub counts: RenderCounts,
}

/// Renders `desc` with the command line's `overrides`, `spp` (the sampler's budget, or what
/// the integrator takes for it) and `seed`, as `acr render` does without its stop rules.
pub fn render_in_process(
    desc: &SceneDescription,
    overrides: &Overrides,
    spp: Option<u32>,
    seed: u64,
) -> Rendered {
    let mut warnings = desc.warnings.clone();
    let scene = Scene::build(desc, &mut warnings).unwrap_or_else(|e| panic!("{e}"));
    let mut plugins = choose_for_scene(desc, &scene, overrides, spp, seed, &mut warnings)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut film = plugins.film(&scene);
    let counts = render(
        &scene,
        &plugins.integrator,
        plugins.sampler.as_mut(),
        &mut film,
        seed,
        None,
        None,
    );
    Rendered {
        pixels: plugins.image(&film),
        width: scene.film.size().0 as usize,
        warnings,
        counts,
    }
}

/// MSE of two images after pbrt's 8-bit sRGB conversion (clamp, gamma, round), the measure
/// every agreement with pbrt-v3 is stated in.
pub fn srgb8_mse(a: &[Spectrum], b: &[Spectrum]) -> f64 {
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
