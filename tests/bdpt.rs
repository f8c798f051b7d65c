//! `bdpt` (docs/light-transport.md): agreement with pbrt-v3's own renders of the scenes in
//! scenes/pbrt-v3 (a point light's caustic through glass, a room lit indirectly), the film's
//! splats whatever the thread count and crop, and located errors for bad parameters.

use acr::geometry::Spectrum;
use acr::parser::{parse_file, parse_str, SceneDescription};
use acr::registry::{choose_for_scene, Overrides};
use acr::scene::Scene;
use std::path::PathBuf;

mod common;
use common::in_process::{render_in_process, srgb8_mse};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The image of `desc` at `spp` and `seed`, and its width.
fn render_desc(desc: &SceneDescription, spp: u32, seed: u64) -> (Vec<Spectrum>, usize) {
    let r = render_in_process(desc, &Overrides::default(), Some(spp), seed);
    assert_eq!(r.counts.dropped, 0);
    (r.pixels, r.width)
}

fn scene(name: &str) -> SceneDescription {
    parse_file(&root().join("scenes/pbrt-v3").join(name)).unwrap()
}

fn read_reference(name: &str) -> Vec<Spectrum> {
    let path = root().join("scenes/pbrt-v3/references").join(name);
    acr::image_io::read_image(&path, false).unwrap().pixels
}

fn mean_lum(p: &[Spectrum]) -> f64 {
    p.iter()
        .map(|&c| f64::from(acr::spectrum_luminance(c)))
        .sum::<f64>()
        / p.len() as f64
}

/// The luminance summed over the window [x0, x1) x [y0, y1) of an image `width` wide.
fn window(p: &[Spectrum], width: usize, [x0, x1, y0, y1]: [usize; 4]) -> f64 {
    (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| y * width + x))
        .map(|i| f64::from(acr::spectrum_luminance(p[i])))
        .sum()
}

/// The caustic under the glass sphere of `caustic-point.pbrt`.
const CAUSTIC: [usize; 4] = [36, 54, 57, 67];

/// A point light through a glass sphere: the caustic only light tracing (t = 1) finds. Its
/// energy in a window over it is within 2% of pbrt-v3's converged render, the image mean
/// within 1%, the MSE within 1.3x pbrt-v3's own at 16 spp; `path` shows no caustic there.
#[test]
fn point_light_caustic_through_glass_agrees_with_pbrt_v3() {
    let desc = scene("caustic-point.pbrt");
    let reference = read_reference("caustic-point-ref1024.exr");
    let pbrt16 = read_reference("caustic-point-pbrt16.exr");
    let (img, width) = render_desc(&desc, 64, 11);
    let (ours, theirs) = (
        window(&img, width, CAUSTIC),
        window(&reference, width, CAUSTIC),
    );
    eprintln!("caustic window: acr {ours:.3}, pbrt-v3 {theirs:.3}");
    assert!((ours / theirs - 1.0).abs() < 0.02, "{ours} vs {theirs}");
    let m = mean_lum(&img) / mean_lum(&reference);
    assert!((m - 1.0).abs() < 0.01, "mean ratio {m}");
    let (img16, _) = render_desc(&desc, 16, 11);
    let (mse, pbrt_mse) = (
        srgb8_mse(&img16, &reference),
        srgb8_mse(&pbrt16, &reference),
    );
    eprintln!("caustic 16 spp: acr MSE {mse:.3e}, pbrt-v3 {pbrt_mse:.3e}");
    assert!(mse <= 1.3 * pbrt_mse, "{mse:.3e} vs {pbrt_mse:.3e}");
    let mut path = desc.clone();
    path.integrator.as_mut().unwrap().kind = "path".into();
    let (img, _) = render_desc(&path, 16, 11);
    let by_path = window(&img, width, CAUSTIC);
    assert!(by_path < 0.1 * theirs, "path finds {by_path} of {theirs}");
}

/// A room lit indirectly by a shaded light: acr's MSE against pbrt-v3's converged render is
/// within 1.3x pbrt-v3's own at 16 spp, and the means agree within 1% (at 64 spp: at 16 the
/// glass sphere's caustic paths move the mean by about 1% from seed to seed).
#[test]
fn bdpt_room_agrees_with_pbrt_v3() {
    let desc = scene("bdpt-room.pbrt");
    let reference = read_reference("bdpt-room-ref1024.exr");
    let pbrt16 = read_reference("bdpt-room-pbrt16.exr");
    let (img, _) = render_desc(&desc, 16, 11);
    let (mse, pbrt_mse) = (srgb8_mse(&img, &reference), srgb8_mse(&pbrt16, &reference));
    let m = mean_lum(&render_desc(&desc, 64, 11).0) / mean_lum(&reference);
    eprintln!("room: acr MSE {mse:.3e}, pbrt-v3 {pbrt_mse:.3e}; mean ratio {m:.4}");
    assert!(mse <= 1.3 * pbrt_mse, "{mse:.3e} vs {pbrt_mse:.3e}");
    assert!((m - 1.0).abs() < 0.01, "mean ratio {m}");
}

/// The film's splats are added in each batch's order: the image is the same whatever the
/// thread count.
#[test]
fn bdpt_image_does_not_depend_on_the_thread_count() {
    let desc = scene("caustic-point.pbrt");
    let with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render_desc(&desc, 4, 3).0)
    };
    let one = with(1);
    assert!(one == with(3), "the image depends on the thread count");
}

/// Crops share one estimator: the splats of a crop are scaled by full-film pixels over the
/// light subpaths its samples traced, so two crops that tile the frame show the caustic with
/// the energy of the whole frame's render.
#[test]
fn crops_tile_the_frame_with_their_splats() {
    let text = std::fs::read_to_string(root().join("scenes/pbrt-v3/caustic-point.pbrt")).unwrap();
    let crop = |window: &str| {
        let t = text.replace(
            "\"string filename\"",
            &format!("\"float cropwindow\" [ {window} ] \"string filename\""),
        );
        let desc = parse_str(&t, &root().join("scenes/pbrt-v3/caustic-point.pbrt")).unwrap();
        render_desc(&desc, 64, 5).0
    };
    // Top and bottom halves: the caustic (rows 57-67 of 96) lies in the bottom one.
    let (top, bottom) = (crop("0 1 0 0.5"), crop("0 1 0.5 1"));
    assert_eq!(top.len() + bottom.len(), 96 * 96);
    let whole: Vec<Spectrum> = top.into_iter().chain(bottom).collect();
    let reference = read_reference("caustic-point-ref1024.exr");
    let (ours, theirs) = (window(&whole, 96, CAUSTIC), window(&reference, 96, CAUSTIC));
    eprintln!("cropped caustic window: {ours:.3} vs {theirs:.3}");
    assert!((ours / theirs - 1.0).abs() < 0.03, "{ours} vs {theirs}");
    let m = mean_lum(&whole) / mean_lum(&reference);
    assert!((m - 1.0).abs() < 0.01, "mean ratio {m}");
}

/// Nonsense parameters are errors at their place in the file, as for the other integrators.
#[test]
fn bad_bdpt_parameters_are_located_errors() {
    for (param, says) in [
        ("\"integer maxdepth\" [ -2 ]", "maxdepth -2 is negative"),
        (
            "\"string lightsamplestrategy\" [ \"nearest\" ]",
            "lightsamplestrategy \"nearest\"",
        ),
    ] {
        let text = format!(
            "Integrator \"bdpt\"\n  {param}\nCamera \"perspective\"\nWorldBegin\n\
             LightSource \"point\"\nWorldEnd\n"
        );
        let desc = parse_str(&text, &root().join("bad.pbrt")).unwrap();
        let mut warnings = Vec::new();
        let scene = Scene::build(&desc, &mut warnings).unwrap();
        let err = choose_for_scene(&desc, &scene, &Overrides::default(), None, 0, &mut warnings)
            .err()
            .expect("refused")
            .to_string();
        assert!(err.contains(says) && err.contains("bad.pbrt:2"), "{err}");
    }
}

/// Sample ranges of a bdpt render merge into the render of all their samples: `acr merge`
/// adds the splat sums and their light subpaths per pixel (`splatSpp`) as it adds the
/// filtered sums (docs/farm.md).
#[test]
fn sample_ranges_merge_their_splats() {
    use acr::cli::mergeable::Sums;
    use common::{ok, s, temp_dir};
    let dir = temp_dir("bdpt-ranges");
    let scene = root().join("scenes/pbrt-v3/caustic-point.pbrt");
    let path = |name: &str| dir.join(format!("{name}.exr"));
    let (full, a, b, m) = (path("full"), path("a"), path("b"), path("m"));
    let common = ["--sampler", "sobol", "-q", "--mergeable", "--threads", "2"];
    for (out, spp, offset) in [(&full, "16", "0"), (&a, "8", "0"), (&b, "8", "8")] {
        let mut args = vec!["render", s(&scene), "-o", s(out), "--spp", spp];
        args.extend(["--sample-offset", offset]);
        args.extend(common);
        ok(&args);
    }
    ok(&["merge", s(&m), s(&a), s(&b)]);
    let merged = Sums::read(&m).unwrap().unwrap();
    let whole = Sums::read(&full).unwrap().unwrap();
    assert_eq!(merged.splat_spp, Some(16.0));
    assert_eq!(whole.splat_spp, Some(16.0));
    assert!(merged.splats.is_some());
    let (mi, wi) = (merged.image(), whole.image());
    let worst = mi
        .iter()
        .zip(&wi)
        .flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs() / y[c].abs().max(1e-3)))
        .fold(0.0f32, f32::max);
    eprintln!("largest relative difference {worst:.1e}");
    assert!(worst < 1e-5, "relative difference {worst}");
    // The plain image of the whole render is the one its sums make.
    let plain = acr::image_io::read_image(&full, false).unwrap().pixels;
    let caustic: f32 = plain.iter().map(|p| p.x).sum();
    let from_sums: f32 = wi.iter().map(|p| p[0]).sum();
    assert!((caustic / from_sums - 1.0).abs() < 1e-5);
}

/// `visualizeweights` writes one image per strategy beside the output (pbrt-v3's names); the
/// weighted strategies add up to the image (their means: the strategy images are unfiltered).
#[test]
fn strategy_images_add_up_to_the_image() {
    use common::{ok, s, temp_dir};
    let dir = temp_dir("bdpt-strategies");
    let scene = root().join("scenes/pbrt-v3/caustic-point.pbrt");
    let out = dir.join("out.exr");
    ok(&[
        "render",
        s(&scene),
        "-o",
        s(&out),
        "-q",
        "--spp",
        "16",
        "--set",
        "integrator.visualizeweights=true",
    ]);
    let image = acr::image_io::read_image(&out, false).unwrap().pixels;
    let mut total = 0.0;
    let mut files = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name.starts_with("bdpt_d") {
            files += 1;
            total += mean_lum(&read_image(&dir.join(&name)));
        }
    }
    assert!(
        dir.join("bdpt_d03_s04_t01.exr").exists(),
        "the caustic's strategy"
    );
    assert!(files >= 10, "{files} strategy images");
    let m = total / mean_lum(&image);
    assert!(
        (m - 1.0).abs() < 0.005,
        "strategies sum to {m} of the image"
    );
}

fn read_image(path: &std::path::Path) -> Vec<Spectrum> {
    acr::image_io::read_image(path, false).unwrap().pixels
}

/// The luminance mean of an image file over the caustic reference's, and the caustic window's.
fn caustic_ratios(path: &std::path::Path) -> (f64, f64) {
    let img = read_image(path);
    let reference = read_reference("caustic-point-ref1024.exr");
    (
        mean_lum(&img) / mean_lum(&reference),
        window(&img, 96, CAUSTIC) / window(&reference, 96, CAUSTIC),
    )
}

/// The time limit, the noise threshold and SIGTERM stop bdpt cleanly, the splats of the
/// samples traced at the right scale (the mean within 3% of pbrt-v3's, the caustic, which only
/// splats make, within 6%: a few dozen spp), with the partial image written under
/// `--write-partial-images` right as well.
#[cfg(unix)]
#[test]
fn time_limit_noise_threshold_and_sigterm_stop_bdpt_with_its_splats() {
    use common::{ok, s, temp_dir};
    let dir = temp_dir("bdpt-stops");
    let scene = root().join("scenes/pbrt-v3/caustic-point.pbrt");
    let check = |out: &std::path::Path, what: &str| {
        let (m, w) = caustic_ratios(out);
        eprintln!("{what}: mean {m:.4}, caustic {w:.4}");
        assert!(
            (m - 1.0).abs() < 0.03 && (w - 1.0).abs() < 0.05,
            "{what}: {m} {w}"
        );
    };
    for (what, flag, value) in [
        ("time limit", "--time-limit", "2"),
        ("noise threshold", "--noise-threshold", "0.2"),
    ] {
        let out = dir.join(format!("{}.exr", what.replace(' ', "-")));
        let stats = dir.join("stats.json");
        ok(&[
            "render",
            s(&scene),
            "-o",
            s(&out),
            "-q",
            "--spp",
            "100000",
            flag,
            value,
            "--stats",
            s(&stats),
        ]);
        let text = std::fs::read_to_string(&stats).unwrap();
        let halted = if flag == "--time-limit" {
            "time"
        } else {
            "noise"
        };
        assert!(
            text.contains(&format!("\"halted_by\": \"{halted}\"")),
            "{text}"
        );
        check(&out, what);
    }
    let out = dir.join("signal.exr");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_acr"))
        .args([
            "render",
            s(&scene),
            "-o",
            s(&out),
            "--spp",
            "100000",
            "--quiet",
        ])
        .args(["--write-partial-images", "0.3"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !out.exists() {
        assert!(start.elapsed().as_secs() < 120, "no partial image");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    std::thread::sleep(std::time::Duration::from_millis(1500));
    check(&out, "partial image");
    // SAFETY: kill(2) on our own child's pid, with a valid signal number.
    let rc = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    assert_eq!(rc, 0);
    let output = child.wait_with_output().unwrap();
    assert!(String::from_utf8_lossy(&output.stderr).contains("interrupted by a signal"));
    check(&out, "after SIGTERM");
}

/// bdpt converges to the image of `path` where their estimators differ most: a translucent
/// surface (Lambertian and microfacet transmission side by side: importance transport leaves
/// out radiance's eta^2 on the dielectric lobe only), and projection and goniometric lights
/// (whose emission samples can be black: the s = 1 strategy still runs). Means within 1% at
/// 64 spp, of pbrt-v3's converged `path` render and of acr's `path` at 256 spp.
#[test]
fn bdpt_converges_to_paths_image_through_translucency_and_image_lights() {
    let mut desc = scene("translucent.pbrt");
    desc.integrator.as_mut().unwrap().kind = "bdpt".into();
    let m = mean_lum(&render_desc(&desc, 64, 2).0)
        / mean_lum(&read_reference("translucent-ref1024.exr"));
    eprintln!("translucent: bdpt mean over pbrt-v3's path {m:.4}");
    assert!((m - 1.0).abs() < 0.01, "translucent: {m}");
    let mut desc = scene("image-lights.pbrt");
    desc.integrator.as_mut().unwrap().kind = "path".into();
    let path = mean_lum(&render_desc(&desc, 256, 2).0);
    desc.integrator.as_mut().unwrap().kind = "bdpt".into();
    let m = mean_lum(&render_desc(&desc, 64, 2).0) / path;
    eprintln!("image lights: bdpt mean over path's {m:.4}");
    assert!((m - 1.0).abs() < 0.01, "image lights: {m}");
}

/// With many lights and the light BVH, the s = 1 strategy chooses at the vertex it connects
/// and the light subpaths by power: the MIS weights take each strategy's own choice, and the
/// image is `path`'s (means within 1%); as with `spatial`, looked up at the camera (pbrt-v3).
#[test]
fn bdpt_with_many_lights_weighs_each_strategys_light_choice() {
    let path = root().join("scenes/many-lights.pbrt");
    let reference = mean_lum(&render_desc(&parse_file(&path).unwrap(), 64, 4).0);
    for strategy in ["bvh", "spatial"] {
        let text = std::fs::read_to_string(&path).unwrap();
        let text = text.replace(
            "Integrator \"path\"",
            &format!("Integrator \"bdpt\" \"string lightsamplestrategy\" \"{strategy}\""),
        );
        let desc = parse_str(&text, &path).unwrap();
        assert_eq!(desc.integrator.as_ref().unwrap().kind, "bdpt");
        let m = mean_lum(&render_desc(&desc, 16, 4).0) / reference;
        eprintln!("many lights, {strategy}: bdpt mean over path's {m:.4}");
        assert!((m - 1.0).abs() < 0.01, "{strategy}: {m}");
    }
}

/// A scene of scenes/pbrt-v3 written for `volpath`, rendered by `bdpt` with the parameters
/// `extra`, after `edit` (pairs of text to replace) and at `resolution` (the same view).
fn as_bdpt(name: &str, extra: &str, edit: &[(&str, &str)], resolution: u32) -> SceneDescription {
    let path = root().join("scenes/pbrt-v3").join(name);
    let mut text = std::fs::read_to_string(&path).unwrap();
    let bdpt = format!("Integrator \"bdpt\" {extra}");
    let film =
        format!("\"integer xresolution\" [{resolution}] \"integer yresolution\" [{resolution}]");
    for (from, to) in [
        ("Integrator \"volpath\"", bdpt.as_str()),
        (
            "\"integer xresolution\" [96] \"integer yresolution\" [96]",
            &film,
        ),
    ]
    .iter()
    .chain(edit)
    {
        assert!(text.contains(from), "{name}: no {from}");
        text = text.replace(from, to);
    }
    parse_str(&text, &path).unwrap_or_else(|e| panic!("{e}"))
}

/// Participating media (docs/media.md): a sphere of scattering medium behind an interface
/// and a sphere of milk under an area light. bdpt's image mean is within 1% of pbrt-v3's
/// converged volpath render, its MSE within 1.3x pbrt-v3's bdpt at 16 spp.
#[test]
fn bdpt_renders_homogeneous_media_as_pbrt_v3() {
    let desc = as_bdpt("media-homogeneous.pbrt", "", &[], 96);
    let reference = read_reference("media-homogeneous-ref1024.exr");
    let pbrt16 = read_reference("media-homogeneous-bdpt-pbrt16.exr");
    let (img, _) = render_desc(&desc, 16, 11);
    let m = mean_lum(&img) / mean_lum(&reference);
    let (mse, pbrt_mse) = (srgb8_mse(&img, &reference), srgb8_mse(&pbrt16, &reference));
    eprintln!(
        "homogeneous media: mean ratio {m:.4}; acr MSE {mse:.3e}, pbrt-v3 bdpt {pbrt_mse:.3e}"
    );
    assert!((m - 1.0).abs() < 0.01, "mean ratio {m}");
    assert!(mse <= 1.3 * pbrt_mse, "{mse:.3e} vs {pbrt_mse:.3e}");
}

/// A spot light's cone in fog, the camera in the fog. The scene declares its lights in the
/// fog although they hang above it (pbrt-v3 gives a light the outside medium in effect): light
/// subpaths start in the fog, shadow rays from below reach them through vacuum, so pbrt-v3's
/// bdpt and volpath disagree (by 1.5% in the mean) and bdpt's image depends on how its
/// strategies are weighed. With pbrt-v3's light choice (power) acr's bdpt is within 1% of
/// pbrt-v3's bdpt (256 spp), its MSE within 1.3x pbrt-v3's at 16 spp; with the lights put in
/// vacuum, where they are, within 1% of pbrt-v3's volpath (at half the resolution, the same
/// view).
#[test]
fn bdpt_renders_a_spot_light_in_fog_as_pbrt_v3() {
    let power = "\"string lightsamplestrategy\" \"power\"";
    let desc = as_bdpt("media-fog-spot.pbrt", power, &[], 96);
    let reference = read_reference("media-fog-spot-bdpt-pbrt256.exr");
    let pbrt16 = read_reference("media-fog-spot-bdpt-pbrt16.exr");
    let (img, _) = render_desc(&desc, 16, 11);
    let (mse, pbrt_mse) = (srgb8_mse(&img, &reference), srgb8_mse(&pbrt16, &reference));
    let (img, _) = render_desc(&desc, 64, 12);
    let m = mean_lum(&img) / mean_lum(&reference);
    eprintln!(
        "fog, lights in fog: mean ratio {m:.4}; acr MSE {mse:.3e}, pbrt-v3 bdpt {pbrt_mse:.3e}"
    );
    assert!((m - 1.0).abs() < 0.01, "mean ratio {m}");
    assert!(mse <= 1.3 * pbrt_mse, "{mse:.3e} vs {pbrt_mse:.3e}");
    let lights_in_vacuum = [
        (
            "LightSource \"spot\"",
            "MediumInterface \"\" \"\"\nLightSource \"spot\"",
        ),
        (
            "AttributeBegin\n  MediumInterface \"fog\" \"\"",
            "MediumInterface \"\" \"fog\"\nAttributeBegin\n  MediumInterface \"fog\" \"\"",
        ),
    ];
    let desc = as_bdpt("media-fog-spot.pbrt", "", &lights_in_vacuum, 48);
    let reference = read_reference("media-fog-spot-ref1024.exr");
    let m = mean_lum(&render_desc(&desc, 64, 13).0) / mean_lum(&reference);
    eprintln!("fog, lights in vacuum: mean ratio {m:.4} of volpath's");
    assert!((m - 1.0).abs() < 0.01, "mean ratio {m}");
}
