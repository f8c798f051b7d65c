//! Numerical stress tests, each asserting a measured outcome: degenerate shapes are skipped
//! with a warning, an extremely bright light leaves no NaN or infinity anywhere and the film's
//! `maxcomponentvalue` bounds its fireflies, and an estimator that returns NaN for half its
//! samples still gives the cluster sampler and the polynomial filter a finite image, with every
//! drop counted. (The scene moved 1e6 units from the origin is in tests/render.rs.)
//!
//! Figures are printed: `cargo test --test stress -- --nocapture`.

use acr::geometry::Spectrum;
use acr::parser::{parse_str, Warning};
use acr::registry::{choose_for_scene, Overrides, Plugins};
use acr::render::{render, render_with, RenderCounts};
use acr::scene::Scene;
use std::path::Path;

/// The scene `text` built, its plugins chosen with `overrides` at `spp`, and its warnings.
fn build(text: &str, overrides: &Overrides, spp: u32) -> (Scene, Plugins, Vec<Warning>) {
    let desc = parse_str(text, Path::new("stress.pbrt")).unwrap_or_else(|e| panic!("{e}"));
    let mut warnings = desc.warnings.clone();
    let scene = Scene::build(&desc, &mut warnings).unwrap_or_else(|e| panic!("{e}"));
    let plugins = choose_for_scene(&desc, &scene, overrides, Some(spp), 7, &mut warnings)
        .unwrap_or_else(|e| panic!("{e}"));
    (scene, plugins, warnings)
}

/// Renders with the scene's integrator; the image and the counts.
fn render_scene(text: &str, overrides: &Overrides, spp: u32) -> (Vec<Spectrum>, RenderCounts) {
    let (scene, mut plugins, _) = build(text, overrides, spp);
    let mut film = plugins.film(&scene);
    let counts = render(
        &scene,
        &plugins.integrator,
        plugins.sampler.as_mut(),
        &mut film,
        7,
        None,
        None,
    );
    (plugins.image(&film), counts)
}

fn overrides(sampler: &str, filter: &str) -> Overrides {
    Overrides {
        sampler: Some(sampler.into()),
        filter: Some(filter.into()),
        ..Default::default()
    }
}

/// A matte floor and sphere under a dim sky, seen from above at an angle, 32 x 24, path traced;
/// `film` is added to the Film directive and `world` to the world block.
fn dim_scene(film: &str, world: &str) -> String {
    format!(
        "LookAt 0 3 6  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n\
         Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 24 {film}\n\
         Integrator \"path\" \"integer maxdepth\" 4\nWorldBegin\n\
         AttributeBegin\nRotate -90 1 0 0\n\
         LightSource \"infinite\" \"rgb L\" [0.01 0.01 0.012]\nAttributeEnd\n\
         Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [-5 0 -5  -5 0 5  5 0 5  5 0 -5]\n\
         AttributeBegin\nTranslate 0 1 0\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\n\
         {world}\nWorldEnd\n"
    )
}

#[test]
fn degenerate_shapes_are_skipped_with_a_warning_and_render_cleanly() {
    // Every kind of degenerate shape, two of them emitting (an area light of zero area would
    // divide by its area when sampled).
    let world = "\
        Shape \"sphere\" \"float radius\" 0\n\
        Shape \"sphere\" \"float radius\" -2\n\
        Shape \"disk\" \"float radius\" 0.5 \"float innerradius\" 1\n\
        Shape \"cylinder\" \"float radius\" -1\n\
        Shape \"cylinder\" \"float zmin\" 0.5 \"float zmax\" 0.5\n\
        AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n\
        Shape \"sphere\" \"float radius\" 0\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2  0 1 3  2 2 2]\n\
        \"point3 P\" [-1 3 -1  1 3 -1  3 3 -1  -1 3 1]\nAttributeEnd\n\
        AttributeBegin\nScale 1e30 1e30 1e30\nShape \"sphere\" \"float radius\" 1e10\nAttributeEnd\n";
    let text = dim_scene("", world);
    let (_, _, warnings) = build(&text, &Overrides::default(), 4);
    let text_of: Vec<String> = warnings.iter().map(|w| w.to_string()).collect();
    let skipped = |what: &str| {
        text_of
            .iter()
            .filter(|w| w.contains(what) && (w.contains("skipped")))
            .count()
    };
    assert_eq!(skipped("sphere: radius is 0"), 2, "{text_of:#?}");
    assert_eq!(skipped("sphere: radius is -2"), 1, "{text_of:#?}");
    assert_eq!(
        skipped("disk: radius - innerradius is -0.5"),
        1,
        "{text_of:#?}"
    );
    assert_eq!(skipped("cylinder: radius is -1"), 1, "{text_of:#?}");
    assert_eq!(skipped("cylinder: |zmax - zmin| is 0"), 1, "{text_of:#?}");
    // (0 1 2) is collinear, (2 2 2) repeats a vertex; (0 1 3) is kept.
    assert_eq!(
        skipped("2 of 3 triangles are degenerate"),
        1,
        "{text_of:#?}"
    );
    // Each warning is located at the shape's line.
    assert!(
        text_of.iter().all(|w| w.starts_with("stress.pbrt:")),
        "{text_of:#?}"
    );

    let (image, counts) = render_scene(&text, &Overrides::default(), 8);
    let (clean, _) = render_scene(&dim_scene("", ""), &Overrides::default(), 8);
    assert_eq!(counts.dropped, 0);
    assert!(image.iter().all(|p| p.is_finite()));
    // The one kept emitting triangle lights the scene up.
    let lum = |img: &[Spectrum]| img.iter().map(|p| acr::spectrum_luminance(*p)).sum::<f32>();
    eprintln!(
        "mean luminance: with the kept light {:.4}, without {:.4}",
        lum(&image) / 768.0,
        lum(&clean) / 768.0
    );
    assert!(lum(&image) > 2.0 * lum(&clean));
}

/// Geometry whose coordinates are finite but huge (1e20: its box's area overflows f32) is
/// skipped with a located warning: the BVH builder's costs would be infinite and it would
/// pick no split (docs/architecture.md §5). The rest of the scene renders.
#[test]
fn geometry_beyond_the_bvh_range_is_skipped_with_a_warning() {
    let world = "\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2  1 2 3]\n\
        \"point3 P\" [1e20 0 0  -1 1 0  -1 0 0  0 0 1]\n\
        AttributeBegin\nTranslate 1e20 0 0\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\n\
        ObjectBegin \"far\"\nShape \"sphere\" \"float radius\" 1\nObjectEnd\n\
        AttributeBegin\nTranslate 0 0 -1e20\nObjectInstance \"far\"\nAttributeEnd\n";
    let text = dim_scene("", world);
    let (_, _, warnings) = build(&text, &Overrides::default(), 4);
    let text_of: Vec<String> = warnings.iter().map(|w| w.to_string()).collect();
    let far = |what: &str| {
        text_of
            .iter()
            .filter(|w| w.contains(what) && w.contains("(the BVH's range)"))
            .count()
    };
    assert_eq!(far("trianglemesh: 1 of 2 primitives"), 1, "{text_of:#?}");
    assert_eq!(far("sphere: 1 of 1 primitives"), 1, "{text_of:#?}");
    assert_eq!(far("1 object instances"), 1, "{text_of:#?}");
    let (image, counts) = render_scene(&text, &Overrides::default(), 4);
    assert_eq!(counts.dropped, 0);
    assert!(image.iter().all(|p| p.is_finite()));
}

/// A 1e8-radiance spherical light beside the dim scene.
fn bright_scene(film: &str) -> String {
    dim_scene(
        film,
        "AttributeBegin\nTranslate 2 0.3 1\nAreaLightSource \"diffuse\" \"rgb L\" [1e8 1e8 1e8]\n\
         Shape \"sphere\" \"float radius\" 0.05\nAttributeEnd\n",
    )
}

#[test]
fn a_1e8_light_leaves_no_nan_or_infinity_and_maxcomponentvalue_bounds_fireflies() {
    for (sampler, filter) in [
        ("stratified", "box"),
        ("stratified", "gaussian"),
        ("stratified", "mitchell"),
        ("halton", "polynomial"),
        ("cluster", "gaussian"),
        ("cluster", "polynomial"),
    ] {
        let o = overrides(sampler, filter);
        let (image, counts) = render_scene(&bright_scene(""), &o, 8);
        assert_eq!(counts.dropped, 0, "{sampler}+{filter}");
        assert!(
            image
                .iter()
                .all(|p| p.is_finite() && p.min_element() >= 0.0),
            "{sampler}+{filter}: a pixel is NaN, infinite or negative"
        );
        let brightest = image.iter().map(|p| p.max_element()).fold(0.0, f32::max);
        let (bounded, _) = render_scene(&bright_scene("\"float maxcomponentvalue\" [10]"), &o, 8);
        let bounded_max = bounded.iter().map(|p| p.max_element()).fold(0.0, f32::max);
        eprintln!(
            "{sampler}+{filter}: brightest pixel {brightest:.3e}; with maxcomponentvalue 10: \
             {bounded_max:.3}"
        );
        // Without the bound the light and its fireflies reach far beyond it.
        assert!(brightest > 1e3, "{sampler}+{filter}: {brightest}");
        assert!(bounded.iter().all(|p| p.is_finite()));
        // Filters with positive weights (and the polynomial fit, clamped to its cells' means)
        // average samples that are each at most 10; Mitchell's negative lobes may overshoot.
        let limit = if filter == "mitchell" {
            15.0
        } else {
            10.0 * (1.0 + 1e-5)
        };
        assert!(bounded_max <= limit, "{sampler}+{filter}: {bounded_max}");
    }
}

#[test]
fn maxcomponentvalue_must_be_positive() {
    let text = bright_scene("\"float maxcomponentvalue\" [0]");
    let desc = parse_str(&text, Path::new("stress.pbrt")).unwrap();
    let err = match Scene::build(&desc, &mut Vec::new()) {
        Ok(_) => panic!("a zero maxcomponentvalue was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(err.starts_with("stress.pbrt:3:"), "{err}");
    assert!(err.contains("maxcomponentvalue must be positive"), "{err}");
}

#[test]
fn an_estimator_returning_nan_for_half_its_samples_leaves_a_finite_image_and_counts_drops() {
    let text = dim_scene(
        "",
        "LightSource \"point\" \"point3 from\" [1 4 2] \"rgb I\" [10 10 10]\n",
    );
    let o = overrides("cluster", "polynomial");
    let spp = 8;
    let (scene, mut plugins, _) = build(&text, &o, spp);
    let mut film = plugins.film(&scene);
    let integrator = &plugins.integrator;
    // The decision comes from the sample's own random stream, so it is the same for a seed.
    let li = |s: &Scene,
              ray,
              diff: Option<&acr::geometry::RayDifferentials>,
              stream: &mut acr::stream::SampleStream| {
        let nan = stream.next_1d() < 0.5;
        let mut r = integrator.li(s, ray, diff, stream);
        if nan {
            r.l = Spectrum::splat(f32::NAN);
        }
        r
    };
    let counts = render_with(
        &scene,
        &li,
        plugins.sampler.as_mut(),
        &mut film,
        7,
        &acr::render::Stop::default(),
        None,
        None,
    );
    let image = plugins.image(&film);
    let (w, h) = scene.film.size();
    let budget = u64::from(w * h) * u64::from(spp);
    let share = counts.dropped as f64 / counts.samples as f64;
    let (reference, ref_counts) = render_scene(&text, &o, spp);
    let lum = |img: &[Spectrum]| {
        img.iter()
            .map(|p| acr::spectrum_luminance(*p) as f64)
            .sum::<f64>()
            / img.len() as f64
    };
    eprintln!(
        "{} of {} samples dropped ({:.1}%); mean luminance {:.4} against {:.4} with none dropped",
        counts.dropped,
        counts.samples,
        100.0 * share,
        lum(&image),
        lum(&reference)
    );
    assert_eq!(counts.samples, budget, "the budget is spent exactly");
    assert_eq!(ref_counts.dropped, 0);
    assert!((0.45..0.55).contains(&share), "dropped share {share}");
    assert!(
        image
            .iter()
            .all(|p| p.is_finite() && p.min_element() >= 0.0),
        "a pixel is NaN, infinite or negative"
    );
    // The surviving half estimates the same image.
    let rel = lum(&image) / lum(&reference) - 1.0;
    assert!(
        rel.abs() < 0.05,
        "mean luminance differs by {:+.1}%",
        100.0 * rel
    );
}
