//! Participating media and `volpath` (docs/media.md): analytic cases (an absorbing sphere's
//! transmittance, a white furnace of scattering medium), and bad input that must give located
//! errors or warnings, never a panic or a NaN image.

use acr::geometry::Spectrum;
use acr::parser::{parse_str, SceneDescription, Warning};
use acr::registry::{choose_for_scene, Overrides};
use acr::scene::Scene;
use std::path::Path;

mod common;
use common::in_process::render_in_process;

fn parse(text: &str) -> SceneDescription {
    parse_str(text, Path::new("media.pbrt")).unwrap_or_else(|e| panic!("{e}"))
}

/// The scene's warnings (parse, build and plugin choice) and its image at `spp`, with the
/// count of dropped samples.
fn render_text(text: &str, spp: u32) -> (Vec<Warning>, Vec<Spectrum>, u64) {
    render_desc(&parse(text), &Overrides::default(), spp, 3)
}

/// [`render_text`] of a parsed scene, with the command line's `overrides`, at `seed`.
fn render_desc(
    desc: &SceneDescription,
    overrides: &Overrides,
    spp: u32,
    seed: u64,
) -> (Vec<Warning>, Vec<Spectrum>, u64) {
    let r = render_in_process(desc, overrides, Some(spp), seed);
    (r.warnings, r.pixels, r.counts.dropped)
}

/// The error building `text` gives.
fn build_error(text: &str) -> String {
    let desc = match parse_str(text, Path::new("media.pbrt")) {
        Ok(d) => d,
        Err(e) => return e.to_string(),
    };
    let mut warnings = Vec::new();
    match Scene::build(&desc, &mut warnings) {
        Ok(_) => panic!("no error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// An orthographic camera looking down -z at a sphere of radius 1 filled with `medium`,
/// under a uniform white sky, rendered by `integrator`.
fn sphere_scene(medium: &str, integrator: &str) -> String {
    format!(
        "LookAt 0 0 5  0 0 0  0 1 0\n\
         Camera \"orthographic\" \"float screenwindow\" [-0.05 0.05 -0.05 0.05]\n\
         Sampler \"random\" \"integer pixelsamples\" [16]\n\
         Integrator {integrator}\n\
         Film \"image\" \"integer xresolution\" [4] \"integer yresolution\" [4]\n\
         WorldBegin\n\
         LightSource \"infinite\" \"rgb L\" [1 1 1]\n\
         MakeNamedMedium \"m\" \"string type\" \"homogeneous\" {medium}\n\
         AttributeBegin\n\
           MediumInterface \"m\" \"\"\n\
           Material \"\"\n\
           Shape \"sphere\" \"float radius\" [1]\n\
         AttributeEnd\n\
         WorldEnd\n"
    )
}

fn mean(p: &[Spectrum]) -> Spectrum {
    p.iter().copied().sum::<Spectrum>() / p.len() as f32
}

/// Through the centre of an absorbing sphere (no scattering) the sky arrives attenuated by
/// exp(-sigma_a * 2): the ray crosses two interfaces and carries the medium between them
/// (volpath's camera path, and bdpt's camera subpath that escapes to the sky).
#[test]
fn an_absorbing_sphere_transmits_exp_minus_optical_depth() {
    for integrator in ["\"volpath\"", "\"bdpt\""] {
        absorbing_sphere(integrator);
    }
}

fn absorbing_sphere(integrator: &str) {
    let medium = "\"rgb sigma_a\" [0.25 0.5 1.5] \"rgb sigma_s\" [0 0 0]";
    let spp = 1024;
    let (warnings, image, dropped) = render_text(&sphere_scene(medium, integrator), spp);
    assert!(warnings.is_empty(), "{integrator}: {warnings:?}");
    assert_eq!(dropped, 0);
    let m = mean(&image);
    let expected = Spectrum::new(0.5f32.exp().recip(), 1f32.exp().recip(), 3f32.exp().recip());
    // Each sample passes with probability p = the channels' mean transmittance and then weighs
    // tr / p (pbrt-v3's spectral MIS); the mean of N such has a standard deviation of
    // tr * sqrt((1 / p - 1) / N). The pixels span |x| < 0.05: the chord is within 0.25% of 2.
    let p = (expected.x + expected.y + expected.z) / 3.0;
    let n = (16 * spp) as f32;
    for c in 0..3 {
        let std = expected[c] * ((1.0 / p - 1.0) / n).sqrt();
        assert!(
            (m[c] - expected[c]).abs() < 4.0 * std + 0.003 * expected[c],
            "{integrator}: {m} against {expected} (std {std})"
        );
    }
    if integrator != "\"volpath\"" {
        return;
    }
    // `path` ignores the medium (as pbrt-v3's), with one warning.
    let (warnings, image, _) = render_text(&sphere_scene(medium, "\"path\""), 4);
    assert!((mean(&image) - Spectrum::ONE).abs().max_element() < 1e-4);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].message.contains("volpath"),
        "{}",
        warnings[0].message
    );
}

/// `bdpt` and `mlt` (whose paths are bdpt's) render media themselves, as pbrt-v3's do:
/// without a warning, an image of their own (tests/bdpt.rs checks bdpt's images, and
/// `mlt_through_an_absorbing_sphere_keeps_the_transmittance` below mlt's mean); `sppm` renders
/// and warns that it ignores them, as pbrt-v3's does.
#[test]
fn bdpt_and_mlt_render_media_themselves_and_sppm_warns() {
    let medium = "\"rgb sigma_a\" [0.25 0.5 1.5] \"rgb sigma_s\" [0.5 0.5 0.5]";
    let (_, volpath, _) = render_text(&sphere_scene(medium, "\"volpath\""), 8);
    for integrator in ["\"bdpt\"", MLT_SMALL] {
        let (warnings, image, _) = render_text(&sphere_scene(medium, integrator), 8);
        assert!(warnings.is_empty(), "{integrator}: {warnings:?}");
        assert_ne!(image, volpath, "{integrator}");
    }
    let (warnings, _, _) = render_text(&sphere_scene(medium, "\"sppm\""), 2);
    assert!(
        warnings
            .iter()
            .any(|w| w.message.contains("\"sppm\" integrator ignores them")),
        "{warnings:?}"
    );
}

/// mlt with a bootstrap small enough for a debug build (its image's mean is the bootstrap's
/// estimate `b`).
const MLT_SMALL: &str =
    "\"mlt\" \"integer bootstrapsamples\" [20000] \"integer chains\" [64] \"integer maxdepth\" [2]";

/// Through an absorbing sphere mlt's image keeps the transmittance exp(-sigma_a * 2): every
/// path it can find crosses the medium, so its colour is the transmittance's and its
/// brightness the bootstrap's estimate, a mean of 20,000 paths a depth, each either 0 or the
/// transmittance over the chance of passing (relative standard deviation about 1.2%).
#[test]
fn mlt_through_an_absorbing_sphere_keeps_the_transmittance() {
    let medium = "\"rgb sigma_a\" [0.25 0.5 1.5] \"rgb sigma_s\" [0 0 0]";
    let (warnings, image, dropped) = render_text(&sphere_scene(medium, MLT_SMALL), 16);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(dropped, 0);
    let m = mean(&image);
    let expected = Spectrum::new(0.5f32.exp().recip(), 1f32.exp().recip(), 3f32.exp().recip());
    let ratio = m / expected;
    // The brightness: four standard deviations of the bootstrap's estimate.
    assert!((ratio.x - 1.0).abs() < 0.05, "{m} against {expected}");
    // The colour: every path has the transmittance's.
    assert!(
        (ratio.y / ratio.x - 1.0).abs() < 0.01 && (ratio.z / ratio.x - 1.0).abs() < 0.01,
        "{m} against {expected}"
    );
}

/// A white furnace: a medium that only scatters, in a sphere under a uniform sky of
/// radiance 1, sends back exactly 1 in every direction; the light samples, the phase samples
/// and their MIS weights, and the transmittance along shadow rays through the interface must
/// all be right for the mean to come out 1 (paths long enough: optical radius 1.5, depth 200).
#[test]
fn a_white_furnace_of_scattering_medium_stays_white() {
    let medium = "\"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [1.5 0.5 1] \"float g\" [0.6]";
    let integrator = "\"volpath\" \"integer maxdepth\" [200] \"float rrthreshold\" [0]";
    let (_, image, dropped) = render_text(&sphere_scene(medium, integrator), 256);
    assert_eq!(dropped, 0);
    let m = mean(&image);
    assert!((m - Spectrum::ONE).abs().max_element() < 0.02, "{m}");
}

/// Bad coefficients, grids and types are errors at the parameter that is wrong.
#[test]
fn bad_media_are_located_errors() {
    let scene = |medium: &str| {
        format!("Camera \"perspective\"\nWorldBegin\n{medium}\nShape \"sphere\"\nWorldEnd\n")
    };
    for (medium, says, line) in [
        (
            "MakeNamedMedium \"a\" \"string type\" \"homogeneous\"\n  \"rgb sigma_a\" [1 -1 1]",
            "sigma_a",
            4,
        ),
        (
            "MakeNamedMedium \"a\" \"string type\" \"homogeneous\" \"float scale\" [-2]",
            "scale -2",
            3,
        ),
        (
            "MakeNamedMedium \"a\" \"string type\" \"homogeneous\"\n  \"rgb sigma_s\" [1 1e39 1]",
            "sigma_s",
            4,
        ),
        (
            "MakeNamedMedium \"a\" \"string type\" \"homogeneous\"\n  \"float g\" [1]",
            "g 1",
            4,
        ),
        (
            "MakeNamedMedium \"a\" \"string type\" \"heterogeneous\" \"integer nx\" [2]\n  \"float density\" [1 2 3]",
            "3 density values, but nx * ny * nz = 2 * 1 * 1 = 2",
            4,
        ),
        (
            "MakeNamedMedium \"a\" \"string type\" \"heterogeneous\"\n  \"float density\" [-1]",
            "density value 0 is -1",
            4,
        ),
        (
            "MakeNamedMedium \"a\" \"string type\" \"heterogeneous\" \"float density\" [1]\n  \"point p1\" [1 0 1]",
            "p1 > p0",
            4,
        ),
        (
            "MakeNamedMedium \"a\" \"string type\" \"homogenous\"",
            "unknown medium type \"homogenous\" (did you mean \"homogeneous\"?)",
            3,
        ),
        (
            "MakeNamedMedium \"a\" \"float g\" [0]",
            "needs a \"string type\"",
            3,
        ),
    ] {
        let e = build_error(&scene(medium));
        assert!(e.contains(says), "{medium}: {e}");
        assert!(e.contains(&format!("media.pbrt:{line}:")), "{medium}: {e}");
    }
}

/// An unknown preset and an undefined medium name are located warnings, as pbrt-v3's; the
/// image renders, finite.
#[test]
fn unknown_presets_and_names_warn_and_render() {
    let text = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n\
        Integrator \"volpath\"\n\
        Film \"image\" \"integer xresolution\" [8] \"integer yresolution\" [8]\n\
        WorldBegin\nLightSource \"point\" \"point from\" [0 2 3] \"rgb I\" [5 5 5]\n\
        MakeNamedMedium \"milk\" \"string type\" \"homogeneous\" \"string preset\" \"Wholemlk\"\n\
        AttributeBegin\nMediumInterface \"milk\" \"\"\nMaterial \"\"\nShape \"sphere\"\nAttributeEnd\n\
        AttributeBegin\nMediumInterface \"mlik\" \"\"\nMaterial \"\"\nTranslate 1 0 0\nShape \"sphere\"\nAttributeEnd\n\
        WorldEnd\n";
    let (warnings, image, _) = render_text(text, 4);
    let said: Vec<String> = warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        said.iter().any(|w| w.contains("media.pbrt:7:")
            && w.contains("\"Wholemlk\"")
            && w.contains("did you mean \"Wholemilk\"")),
        "{said:#?}"
    );
    assert!(
        said.iter().any(|w| w.contains("media.pbrt:14:")
            && w.contains("\"mlik\" is not defined")
            && w.contains("did you mean \"milk\"")),
        "{said:#?}"
    );
    assert!(image.iter().all(|p| p.is_finite()));
    assert!(mean(&image).max_element() > 0.0);
}

/// The camera's medium is the interface's outside medium in effect at the end of the world
/// block; shapes inside an object definition keep the interface they were defined with.
#[test]
fn the_camera_and_instances_get_their_media() {
    let desc = parse(
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
         MediumInterface \"\" \"fog\"\nCamera \"perspective\"\nWorldBegin\n\
         ObjectBegin \"o\"\nAttributeBegin\nMediumInterface \"fog\" \"\"\nShape \"sphere\"\n\
         AttributeEnd\nObjectEnd\nObjectInstance \"o\"\nShape \"sphere\"\nWorldEnd\n",
    );
    assert_eq!(desc.camera_medium, Some(0));
    let object = &desc.objects["o"].shapes[0];
    assert_eq!((object.media.inside, object.media.outside), (Some(0), None));
    assert_eq!(
        (desc.shapes[0].media.inside, desc.shapes[0].media.outside),
        (None, Some(0))
    );
    let mut warnings = Vec::new();
    let scene = Scene::build(&desc, &mut warnings).unwrap();
    assert_eq!(scene.camera_medium, Some(0));
    assert!(scene.surfaces.iter().all(|s| s.media.is_some()));
}

/// The adaptive samplers (cluster; mdas, gem and awr of docs/rivals.md in their unbiased
/// modes) keep the image mean of a medium scene within 0.5% of a stratified render at 4x the
/// samples.
#[test]
fn adaptive_samplers_keep_the_mean_of_a_medium_scene() {
    use acr_plugins::Setting;
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/pbrt-v3/media-homogeneous.pbrt");
    let desc = acr::parser::parse_file(&path).unwrap_or_else(|e| panic!("{e}"));
    let image_mean = |sampler: &str, settings: &[&str], spp: u32| {
        let overrides = Overrides {
            sampler: Some(sampler.into()),
            filter: None,
            integrator: None,
            settings: settings
                .iter()
                .map(|s| Setting::parse(s).unwrap())
                .collect(),
        };
        let (_, image, _) = render_desc(&desc, &overrides, spp, 1);
        let m = mean(&image);
        f64::from(m.x + m.y + m.z) / 3.0
    };
    let reference = image_mean("stratified", &[], 64);
    for (sampler, settings) in [
        ("cluster", &[][..]),
        ("mdas", &["sampler.pilot=0.25"][..]),
        ("gem", &["sampler.unbiased=true"][..]),
        ("awr", &["sampler.unbiased=true"][..]),
    ] {
        let ratio = image_mean(sampler, settings, 16) / reference;
        println!("{sampler}: {ratio:.4} of stratified's mean");
        assert!(
            (ratio - 1.0).abs() < 0.005,
            "{sampler}: mean {ratio:.4} of stratified's"
        );
    }
}

/// A camera ray whose first event is scattering in a medium gets the medium's
/// single-scattering albedo, a zero normal and the distance as its first-hit features.
#[test]
fn first_hit_features_of_a_medium() {
    use acr::geometry::{Ray, Vec3};
    let desc = parse(
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
           \"rgb sigma_a\" [1 2 3] \"rgb sigma_s\" [3 2 1]\n\
         MediumInterface \"\" \"fog\"\nCamera \"perspective\"\nIntegrator \"volpath\"\n\
         WorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1]\nWorldEnd\n",
    );
    let mut warnings = Vec::new();
    let scene = Scene::build(&desc, &mut warnings).unwrap();
    let plugins = choose_for_scene(
        &desc,
        &scene,
        &Overrides::default(),
        Some(1),
        1,
        &mut warnings,
    )
    .unwrap();
    let ray = Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), 0.0);
    let mut stream = acr::stream::SampleStream::new(0, 0, 1, 0);
    let r = plugins.integrator.li(&scene, ray, None, &mut stream);
    let f = r.first_hit;
    assert_eq!(f.albedo, Spectrum::new(0.75, 0.5, 0.25));
    assert_eq!(f.normal, Vec3::ZERO);
    assert!(f.depth > 0.0 && f.depth.is_finite(), "{}", f.depth);
    assert!(r.l.is_finite());
}
