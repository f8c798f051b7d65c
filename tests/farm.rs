//! What a render farm needs (docs/farm.md): crops that tile a frame (`acr render --cropwindow` /
//! `--pixelbounds`) and `acr merge` (the EXR's display and data windows, merges equal to the
//! whole-frame render byte for byte), sample ranges (`--sample-offset`, `--mergeable`) merged
//! by their weights, clean stops on SIGTERM with partial writes, `--quick`.

mod common;

use acr::image_io::read_image_with_frame;
use common::{fails, ok, s, scene, temp_dir};
use std::path::PathBuf;
use std::process::Command;

/// The largest difference between two images' channels, relative to the second's (at least
/// 1e-3).
fn worst_relative(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs() / y[c].abs().max(1e-3)))
        .fold(0.0f32, f32::max)
}

/// For every non-adaptive sampler and every splatting filter, three uneven crops of a 240x160
/// frame, merged, equal the whole-frame render exactly: the crops sample the pixels within the
/// filter's radius around them (pbrt-v3's sample bounds), and each pixel's sample streams are
/// keyed by the pixel and the sample index, not by the crop.
#[test]
fn crops_merge_to_the_whole_frame_byte_for_byte() {
    let dir = temp_dir("tiles");
    let scene = scene();
    let tiles = ["0,97,0,61", "97,240,0,61", "0,240,61,160"];
    for sampler in ["stratified", "halton", "sobol", "random"] {
        for filter in ["box", "gaussian", "mitchell", "triangle", "sinc"] {
            let full = dir.join("full.exr");
            let common = ["--spp", "2", "--sampler", sampler, "--filter", filter, "-q"];
            let mut args = vec!["render", s(&scene), "-o", s(&full)];
            args.extend(common);
            ok(&args);
            let mut parts = Vec::new();
            for (k, b) in tiles.iter().enumerate() {
                let part = dir.join(format!("part{k}.exr"));
                let mut args = vec!["render", s(&scene), "-o", s(&part), "--pixelbounds", b];
                args.extend(common);
                ok(&args);
                parts.push(part);
            }
            let (img, frame) = read_image_with_frame(&parts[1]).unwrap();
            assert_eq!(
                (frame.width, frame.height, frame.x0, frame.y0),
                (240, 160, 97, 0)
            );
            assert_eq!((img.width, img.height), (143, 61));
            let merged = dir.join("merged.exr");
            let mut args = vec!["merge", s(&merged)];
            args.extend(parts.iter().map(|p| s(p)));
            ok(&args);
            let (a, _) = read_image_with_frame(&merged).unwrap();
            let (b, _) = read_image_with_frame(&full).unwrap();
            assert!(
                a.pixels == b.pixels,
                "{sampler} + {filter}: the merge differs"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A crop window in fractions is pbrt-v3's: the ceiling of each edge in raster space.
#[test]
fn cropwindow_places_the_crop_and_bad_crops_fail_cleanly() {
    let dir = temp_dir("window");
    let scene = scene();
    let out = dir.join("crop.exr");
    let (o, sc) = (s(&out), s(&scene));
    ok(&[
        "render",
        sc,
        "-o",
        o,
        "--spp",
        "1",
        "-q",
        "--cropwindow",
        "0.25,0.6,0.1,0.5",
    ]);
    let (img, f) = read_image_with_frame(&out).unwrap();
    assert_eq!((f.x0, f.y0, img.width, img.height), (60, 16, 84, 64));
    fails(
        &["render", sc, "-o", o, "--cropwindow", "0.5,0.5,0,1"],
        "no pixel",
    );
    fails(
        &["render", sc, "-o", o, "--cropwindow", "0,1.5,0,1"],
        "[0, 1]",
    );
    fails(&["render", sc, "-o", o, "--cropwindow", "0,1,0"], "four");
    fails(
        &["render", sc, "-o", o, "--pixelbounds", "0,300,0,10"],
        "beyond",
    );
    fails(
        &[
            "render",
            sc,
            "-o",
            o,
            "--pixelbounds",
            "0,1,0,1",
            "--cropwindow",
            "0,1,0,1",
        ],
        "cannot be used with",
    );
    // Merging: overlaps, holes and crops of different frames are errors.
    let part = |name: &str, bounds: &str| {
        let p = dir.join(name);
        ok(&[
            "render",
            sc,
            "-o",
            s(&p),
            "--spp",
            "1",
            "-q",
            "--pixelbounds",
            bounds,
        ]);
        p
    };
    let a = part("a.exr", "0,120,0,160");
    let b = part("b.exr", "100,240,0,160");
    let c = part("c.exr", "120,240,0,100");
    let m = dir.join("m.exr");
    fails(&["merge", s(&m), s(&a), s(&b)], "must not overlap");
    fails(&["merge", s(&m), s(&a), s(&c)], "in no input");
    fails(&["merge", s(&m)], "required");
    let other = dir.join("other.pbrt");
    let text = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("[240]", "[200]");
    std::fs::write(&other, text).unwrap();
    let d = dir.join("d.exr");
    ok(&[
        "render",
        s(&other),
        "-o",
        s(&d),
        "--spp",
        "1",
        "-q",
        "--pixelbounds",
        "120,200,0,160",
    ]);
    fails(&["merge", s(&m), s(&a), s(&d)], "frame");
    // A crop of another scene of the same size: told apart by the scene's hash.
    let lit = dir.join("lit.pbrt");
    let text = std::fs::read_to_string(&scene).unwrap() + "\n# another scene\n";
    std::fs::write(&lit, text).unwrap();
    let e = dir.join("e.exr");
    let mut args = vec!["render", s(&lit), "-o", s(&e), "--spp", "1", "-q"];
    args.extend(["--pixelbounds", "120,240,0,160"]);
    ok(&args);
    fails(&["merge", s(&m), s(&a), s(&e)], "another scene");
    // A file cut short (a crop being written when its node died) is refused.
    let cut = dir.join("cut.exr");
    let bytes = std::fs::read(&c).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let a2 = part("a2.exr", "0,120,100,160");
    fails(&["merge", s(&m), s(&a), s(&cut), s(&a2)], "cut.exr");
    assert!(!m.exists(), "no image written from bad input");
    let _ = std::fs::remove_dir_all(&dir);
}

/// SIGTERM (what a scheduler sends before it kills) ends the render at the end of the pass
/// under way: the image so far is written, the exit status is non-zero with a message. With
/// `--write-partial-images` the output appears while the render runs (written atomically).
// Signals, and `libc::kill` to send one, are Unix only.
#[cfg(unix)]
#[test]
fn sigterm_writes_the_image_so_far_and_fails() {
    let dir = temp_dir("signal");
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.pbrt");
    let out = dir.join("partial.exr");
    let child = Command::new(env!("CARGO_BIN_EXE_acr"))
        .args([
            "render",
            s(&scene),
            "-o",
            s(&out),
            "--spp",
            "65536",
            "--quiet",
        ])
        .args(["--threads", "1", "--write-partial-images", "0.2"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !out.exists() {
        assert!(
            start.elapsed().as_secs() < 120,
            "no partial image after two minutes"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let (img, _) = read_image_with_frame(&out).unwrap();
    assert_eq!((img.width, img.height), (256, 256));
    // SAFETY: kill(2) on our own child's pid, with a valid signal number.
    let rc = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    assert_eq!(rc, 0);
    let output = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success() && output.status.code().is_some(),
        "{err}"
    );
    assert!(err.contains("interrupted by a signal"), "{err}");
    let (img, _) = read_image_with_frame(&out).unwrap();
    let mean: f32 =
        img.pixels.iter().map(|c| c.x + c.y + c.z).sum::<f32>() / img.pixels.len() as f32;
    assert!(mean > 0.01 && mean.is_finite(), "mean {mean}");
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(leftovers.len(), 1, "{leftovers:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--quick`: a quarter of the resolution in each direction and 1 sample per pixel.
#[test]
fn quick_renders_a_quarter_resolution_at_one_sample() {
    let dir = temp_dir("quick");
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.pbrt");
    let (out, stats) = (dir.join("quick.exr"), dir.join("quick.json"));
    ok(&[
        "render",
        s(&scene),
        "-o",
        s(&out),
        "--quick",
        "-q",
        "--stats",
        s(&stats),
    ]);
    let (img, frame) = read_image_with_frame(&out).unwrap();
    assert_eq!((img.width, img.height, frame.width), (64, 64, 64));
    let stats: String = std::fs::read_to_string(&stats).unwrap();
    assert!(
        stats.contains("\"spp\":1,") || stats.contains("\"spp\": 1,"),
        "{stats}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A filter that reads half buffers (nfor) keeps no splats nor pixel statistics: its mergeable
/// file, its spp and variance AOVs come from the halves and equal the box filter's (one pixel
/// wide) to f32 rounding, and its sample ranges merge into the render of all their samples.
#[test]
fn nfor_writes_the_box_filters_sums_and_aovs_from_its_halves() {
    use acr::cli::mergeable::Sums;
    use acr::image_io::read_image;
    let dir = temp_dir("nfor-sums");
    let scene = scene();
    let sc = s(&scene);
    let path = |name: &str| dir.join(format!("{name}.exr"));
    let render = |filter: &str, out: &PathBuf, more: &[&str]| {
        let mut args = vec!["render", sc, "-o", s(out), "--sampler", "sobol", "--filter"];
        args.extend([filter, "-q", "--pixelbounds", "100,180,40,100"]);
        args.extend(more);
        ok(&args);
    };
    let mut read = Vec::new();
    for filter in ["box", "nfor"] {
        let (img, spp, var) = (path(filter), path("spp"), path("var"));
        let aov = format!("spp={},variance={}", s(&spp), s(&var));
        render(filter, &img, &["--spp", "8", "--aov", &aov]);
        let spp = read_image(&spp, false).unwrap().pixels;
        let var = read_image(&var, false).unwrap().pixels;
        render(filter, &img, &["--spp", "8", "--mergeable"]);
        read.push((spp, var, Sums::read(&img).unwrap().unwrap()));
    }
    let ((bspp, bvar, bsums), (nspp, nvar, nsums)) = (&read[0], &read[1]);
    assert_eq!(bspp, nspp);
    assert!(nspp.iter().all(|c| c.x == 8.0));
    let rows = |v: &[acr::geometry::Spectrum]| v.iter().map(|c| c.to_array()).collect::<Vec<_>>();
    let worst_var = worst_relative(&rows(nvar), &rows(bvar));
    assert!(worst_var < 1e-4, "variance {worst_var}");
    assert!(nvar.iter().any(|c| c.max_element() > 0.0));
    assert_eq!(bsums.counts, nsums.counts);
    assert_eq!(nsums.spp, 8);
    let worst = worst_relative(&nsums.image(), &bsums.image());
    assert!(worst < 1e-5, "image {worst}");
    let (mv, bv) = (nsums.variance().unwrap(), bsums.variance().unwrap());
    let worst = worst_relative(&mv, &bv);
    assert!(worst < 1e-4, "moments {worst}");
    // Ranges 0..4 and 4..8, each with the whole render's texture footprint, merge into the
    // 8-spp file.
    let (a, b, m) = (path("a"), path("b"), path("m"));
    let range = ["--spp", "4", "--footprint-spp", "8", "--mergeable"];
    render("nfor", &a, &range);
    render(
        "nfor",
        &b,
        &[&range[..], &["--sample-offset", "4"]].concat(),
    );
    ok(&["merge", s(&m), s(&a), s(&b)]);
    let merged = Sums::read(&m).unwrap().unwrap();
    assert_eq!(merged.counts, nsums.counts);
    let worst = worst_relative(&merged.image(), &nsums.image());
    assert!(worst < 1e-5, "merged {worst}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Sample ranges: for every sampler whose points depend on the index alone and every
/// splatting filter, the renders of indices 0..8 and 8..16 (`--sample-offset 8`, mergeable
/// EXRs, `--footprint-spp 16`) merge into the 16-spp render, to within the f32 storage of the weighted sums (measured
/// relative differences 1.2e-7 to 3.6e-7; asserted below 1e-5), with every pixel's count 16 and
/// samplesPerPixel 16.
#[test]
fn sample_ranges_merge_into_the_render_of_all_their_samples() {
    use acr::cli::mergeable::Sums;
    let dir = temp_dir("ranges");
    let scene = scene();
    let sc = s(&scene);
    for sampler in ["random", "sobol"] {
        for filter in ["box", "gaussian", "mitchell", "triangle", "sinc"] {
            // The scene's checkerboard is filtered over the whole render's footprint: every
            // range names it.
            let common = [
                "--sampler",
                sampler,
                "--filter",
                filter,
                "-q",
                "--mergeable",
                "--footprint-spp",
                "16",
            ];
            let path = |name: &str| dir.join(format!("{name}.exr"));
            let (full, a, b, m) = (path("full"), path("a"), path("b"), path("m"));
            let mut args = vec!["render", sc, "-o", s(&full), "--spp", "16"];
            args.extend(common);
            ok(&args);
            let mut args = vec!["render", sc, "-o", s(&a), "--spp", "8"];
            args.extend(common);
            ok(&args);
            let mut args = vec![
                "render",
                sc,
                "-o",
                s(&b),
                "--spp",
                "8",
                "--sample-offset",
                "8",
            ];
            args.extend(common);
            ok(&args);
            ok(&["merge", s(&m), s(&a), s(&b)]);
            let merged = Sums::read(&m).unwrap().unwrap();
            let whole = Sums::read(&full).unwrap().unwrap();
            assert_eq!(merged.spp, 16);
            assert!(
                merged.counts.iter().all(|&c| c == 16.0),
                "{sampler} + {filter}"
            );
            let worst = worst_relative(&merged.image(), &whole.image());
            eprintln!("{sampler} + {filter}: largest relative difference {worst:.1e}");
            assert!(
                worst < 1e-5,
                "{sampler} + {filter}: relative difference {worst}"
            );
            // The variance moments add up too: the merge's per-pixel sample variance is the
            // whole render's.
            let (mv, wv) = (merged.variance().unwrap(), whole.variance().unwrap());
            let worst_var = worst_relative(&mv, &wv);
            assert!(
                worst_var < 1e-4,
                "{sampler} + {filter}: variance {worst_var}"
            );
            // The plain image of the merge reads back as the mean.
            let (img, _) = read_image_with_frame(&m).unwrap();
            assert_eq!(img.pixels.len(), merged.sums.len());
        }
    }
    // Ranges that overlap would count samples twice: refused, naming both.
    let (full, b) = (dir.join("full.exr"), dir.join("b.exr"));
    fails(
        &["merge", s(&dir.join("bad.exr")), s(&full), s(&b)],
        "must not overlap",
    );
    assert!(!dir.join("bad.exr").exists());
    let o = dir.join("x.exr");
    let png = dir.join("x.png");
    fails(
        &[
            "render",
            sc,
            "-o",
            s(&o),
            "--sampler",
            "stratified",
            "--sample-offset",
            "4",
        ],
        "random or sobol",
    );
    fails(
        &[
            "render",
            sc,
            "-o",
            s(&o),
            "--sampler",
            "halton",
            "--sample-offset",
            "4",
        ],
        "random or sobol",
    );
    fails(
        &["render", sc, "-o", s(&png), "--mergeable"],
        "writes an EXR",
    );
    fails(
        &[
            "render",
            sc,
            "-o",
            s(&o),
            "--mergeable",
            "--filter",
            "polynomial",
        ],
        "splatting filter",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A render stopped by SIGTERM leaves a mergeable EXR of whole passes (its partial writes too:
/// every pixel as many samples as the header says), and rendering the missing range and
/// merging gives the render that was never stopped.
// Signals, and `libc::kill` to send one, are Unix only.
#[cfg(unix)]
#[test]
fn a_stopped_render_resumes_by_rendering_the_rest_and_merging() {
    use acr::cli::mergeable::Sums;
    let dir = temp_dir("resume");
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.pbrt");
    let sc = s(&scene);
    let (part, rest, merged, full) = (
        dir.join("part.exr"),
        dir.join("rest.exr"),
        dir.join("merged.exr"),
        dir.join("full.exr"),
    );
    const SPP: u32 = 64;
    let spp = SPP.to_string();
    let common = ["--sampler", "random", "--quiet"];
    let child = Command::new(env!("CARGO_BIN_EXE_acr"))
        .args(["render", sc, "-o", s(&part), "--spp", &spp])
        .args(common)
        .args(["--threads", "1", "--write-partial-images", "0.05"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !part.exists() {
        assert!(start.elapsed().as_secs() < 120, "no partial image");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // A partial write holds whole passes.
    let early = Sums::read(&part)
        .unwrap()
        .expect("a mergeable partial image");
    assert!(early.spp >= 1 && early.spp < SPP, "{}", early.spp);
    assert!(early.counts.iter().all(|&c| c == f64::from(early.spp)));
    // SAFETY: kill(2) on our own child's pid, with a valid signal number.
    assert_eq!(
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) },
        0
    );
    let output = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{err}");
    let stopped = Sums::read(&part)
        .unwrap()
        .expect("a mergeable image at the stop");
    let k = stopped.spp;
    assert!(k >= early.spp && k < SPP, "{k}");
    assert_eq!(stopped.offset, Some(0));
    assert!(stopped.counts.iter().all(|&c| c == f64::from(k)));
    assert!(
        err.contains(&format!("--sample-offset {k} --spp {}", SPP - k)),
        "{err}"
    );
    let (k_s, left) = (k.to_string(), (SPP - k).to_string());
    let mut args = vec!["render", sc, "-o", s(&rest), "--spp", &left];
    args.extend(["--sample-offset", &k_s, "--mergeable"]);
    args.extend(common);
    ok(&args);
    ok(&["merge", s(&merged), s(&part), s(&rest)]);
    let mut args = vec!["render", sc, "-o", s(&full), "--spp", &spp, "--mergeable"];
    args.extend(common);
    ok(&args);
    let (m, f) = (
        Sums::read(&merged).unwrap().unwrap(),
        Sums::read(&full).unwrap().unwrap(),
    );
    assert_eq!((m.spp, m.offset), (SPP, Some(0)));
    let worst = worst_relative(&m.image(), &f.image());
    eprintln!("stopped at {k} of {SPP} spp; resumed: largest relative difference {worst:.1e}");
    assert!(worst < 1e-5, "{worst}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The texture footprint follows the whole render's budget (pbrt-v3's camera-ray differentials
/// scaled by 1 / sqrt(spp)): `--spp 16` on a scene written for 4 filters its textures as a
/// 16-spp render, not as the scene's 4 (`--footprint-spp 4` gives that image, which differs);
/// sample ranges 0..8 and 8..16 rendered with `--footprint-spp 16` merge into the 16-spp
/// render, and ranges with different footprints are refused by `acr merge`.
#[test]
fn the_texture_footprint_follows_the_whole_budget_and_sample_ranges_still_merge() {
    use acr::cli::mergeable::Sums;
    let dir = temp_dir("footprint");
    let scene =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/pbrt-v3/texture-filtering.pbrt");
    let sc = s(&scene);
    let path = |name: &str| dir.join(format!("{name}.exr"));
    let render = |name: &str, extra: &[&str]| {
        let out = path(name);
        let mut args = vec!["render", sc, "-o", s(&out), "--sampler", "sobol", "-q"];
        args.extend(["--pixelbounds", "100,260,60,140", "--mergeable"]);
        args.extend(extra);
        ok(&args);
        Sums::read(&out).unwrap().unwrap()
    };
    let full = render("full", &["--spp", "16"]);
    assert_eq!(full.footprint, Some(16));
    let said = render("said", &["--spp", "16", "--footprint-spp", "16"]);
    assert_eq!(full.image(), said.image());
    let scenes_own = render("own", &["--spp", "16", "--footprint-spp", "4"]);
    assert_eq!(scenes_own.footprint, Some(4));
    let moved = worst_relative(&scenes_own.image(), &full.image());
    assert!(moved > 1e-2, "the footprint changed nothing: {moved}");

    let a = render("a", &["--spp", "8", "--footprint-spp", "16"]);
    assert_eq!(a.footprint, Some(16));
    render(
        "b",
        &[
            "--spp",
            "8",
            "--sample-offset",
            "8",
            "--footprint-spp",
            "16",
        ],
    );
    ok(&["merge", s(&path("m")), s(&path("a")), s(&path("b"))]);
    let merged = Sums::read(&path("m")).unwrap().unwrap();
    assert_eq!((merged.spp, merged.footprint), (16, Some(16)));
    let worst = worst_relative(&merged.image(), &full.image());
    assert!(worst < 1e-5, "relative difference {worst}");
    // Without --footprint-spp, the first range is an 8-spp render's: refused with the remedy.
    render("a8", &["--spp", "8"]);
    fails(
        &["merge", s(&path("bad")), s(&path("a8")), s(&path("b"))],
        "--footprint-spp",
    );
    assert!(!path("bad").exists());
}
