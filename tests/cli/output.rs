//! Outputs of `acr render`: the image formats, the stats file, the default file name and determinism.

use super::*;

fn dims(stats: &serde_json::Value) -> Vec<String> {
    stats["dims"]
        .as_array()
        .unwrap_or_else(|| panic!("dims: {}", stats["dims"]))
        .iter()
        .map(|d| d.as_str().unwrap().to_owned())
        .collect()
}

#[test]
fn render_writes_a_png_of_the_film_size_and_every_stats_key() {
    let dir = TempDir::new("png-stats");
    let scene = dir.write("small.pbrt", &small_scene(""));
    let (png, stats_path) = (dir.join("out.png"), dir.join("s.json"));
    let o = render_ok(
        &scene,
        &png,
        &[
            "--spp",
            "2",
            "--seed",
            "9",
            "--stats",
            stats_path.to_str().unwrap(),
        ],
    );
    // --quiet: no summary line (and no progress bar in a pipe).
    assert!(stderr(&o).trim().is_empty(), "{}", stderr(&o));

    assert_eq!(image::image_dimensions(&png).unwrap(), (24, 16));
    let img = read_image(&png, true).unwrap();
    assert!(
        img.pixels.iter().any(|p| p.max_element() > 0.0),
        "black image"
    );

    let s = read_stats(&stats_path);
    let keys = [
        "scene",
        "width",
        "height",
        "spp",
        "samples",
        "rays",
        "threads",
        "seed",
        "sampler",
        "filter",
        "integrator",
        "dims",
        "clusters",
        "dropped_samples",
        "halted",
        "halted_by",
        "seconds",
        "mrays_per_s",
        "peak_rss_mb",
    ];
    let obj = s.as_object().unwrap();
    for k in keys {
        assert!(obj.contains_key(k), "stats lack \"{k}\": {s}");
    }
    assert_eq!(s["scene"].as_str(), scene.to_str());
    let n = |k: &str| {
        s[k].as_u64()
            .unwrap_or_else(|| panic!("{k} is not a whole number: {}", s[k]))
    };
    let (w, h, spp) = (n("width"), n("height"), n("spp"));
    assert_eq!((w, h, spp), (24, 16, 2));
    assert_eq!(n("samples"), w * h * spp);
    assert!(n("rays") >= n("samples"), "{s}");
    assert!(n("threads") >= 1);
    assert_eq!(n("seed"), 9);
    assert_eq!(n("dropped_samples"), 0);
    for k in ["sampler", "filter", "integrator"] {
        assert!(
            s[k].as_str().is_some_and(|v| !v.is_empty()),
            "{k}: {}",
            s[k]
        );
    }
    assert_eq!(s["integrator"], "path");
    assert_eq!(dims(&s), ["x", "y"]);
    // Only the cluster sampler has clusters; a number otherwise would be made up.
    assert!(
        s["clusters"].is_null() || s["sampler"] == "cluster",
        "{}",
        s["clusters"]
    );
    let secs = s["seconds"].as_object().unwrap();
    let mut sum = 0.0;
    for k in ["parse", "build", "render", "reconstruct", "write", "total"] {
        let v = secs
            .get(k)
            .and_then(|v| v.as_f64())
            .unwrap_or_else(|| panic!("seconds.{k} missing: {}", s["seconds"]));
        assert!(v.is_finite() && v >= 0.0, "seconds.{k} = {v}");
        if k != "total" {
            sum += v;
        }
    }
    assert!(
        secs["total"].as_f64().unwrap() >= sum * 0.999,
        "total is less than its parts: {}",
        s["seconds"]
    );
    let mrays = s["mrays_per_s"].as_f64().unwrap();
    assert!(mrays.is_finite() && mrays >= 0.0, "{mrays}");
    let rss = s["peak_rss_mb"].as_f64().unwrap();
    assert!(rss.is_finite() && rss >= 0.0, "{rss}");
    if cfg!(target_os = "linux") {
        assert!(rss > 1.0, "peak RSS {rss} MiB");
    }
}

/// The rendering space's dimensions follow the scene: x y for a static pinhole scene, t with
/// motion, u v with a lens; width, height and samples follow the Film.
#[test]
fn stats_dims_follow_the_scene() {
    let dir = TempDir::new("dims");
    let cases: [(&str, &[&str]); 4] = [
        ("cornell-box.pbrt", &["x", "y"]),
        ("motion-blur.pbrt", &["x", "y", "t"]),
        ("depth-of-field.pbrt", &["x", "y", "u", "v"]),
        ("motion-dof.pbrt", &["x", "y", "t", "u", "v"]),
    ];
    for (i, (name, expected)) in cases.into_iter().enumerate() {
        let (w, h) = (20 + 2 * i as u32, 14 + i as u32);
        let scene = dir.write(name, &example_scene(name, w, h));
        let stats_path = dir.join(format!("{name}.json"));
        let out = dir.join(format!("{name}.exr"));
        render_ok(
            &scene,
            &out,
            &["--spp", "1", "--stats", stats_path.to_str().unwrap()],
        );
        let s = read_stats(&stats_path);
        assert_eq!(dims(&s), expected, "{name}");
        assert_eq!(s["width"].as_u64(), Some(w as u64), "{name}");
        assert_eq!(s["height"].as_u64(), Some(h as u64), "{name}");
        assert_eq!(s["spp"].as_u64(), Some(1), "{name}");
        assert_eq!(s["samples"].as_u64(), Some((w * h) as u64), "{name}");
        let img = read_image(&out, false).unwrap();
        assert_eq!((img.width, img.height), (w as usize, h as usize), "{name}");
    }
}

#[test]
fn exr_and_pfm_outputs_read_back_with_the_film_size() {
    let dir = TempDir::new("formats");
    let scene = dir.write("small.pbrt", &small_scene(""));
    let mut images = Vec::new();
    for ext in ["exr", "pfm", "png"] {
        let out = dir.join(format!("out.{ext}"));
        render_ok(&scene, &out, &["--spp", "2", "--seed", "3"]);
        let img = read_image(&out, false).unwrap_or_else(|e| panic!("{ext}: {e}"));
        assert_eq!((img.width, img.height), (24, 16), "{ext}");
        assert_eq!(img.pixels.len(), 24 * 16, "{ext}");
        images.push(img);
    }
    let (exr, pfm, png) = (&images[0], &images[1], &images[2]);
    assert!(exr.pixels.iter().any(|p| p.max_element() > 0.0));
    // Both hold 32-bit floats, top row first: the same seed gives the same pixels.
    assert_eq!(exr, pfm, "EXR and PFM of the same render differ");
    // The PNG holds the same image in 8-bit sRGB.
    for (i, (f, q)) in exr.pixels.iter().zip(&png.pixels).enumerate() {
        for c in 0..3 {
            let expected = acr::image_io::to_srgb8(f[c]) as f32 / 255.0;
            assert!(
                (q[c] - expected).abs() < 1e-6,
                "pixel {i} channel {c}: PNG {} vs EXR {} ({expected})",
                q[c],
                f[c]
            );
        }
    }
}

#[test]
fn the_same_seed_gives_the_same_file_whatever_the_thread_count() {
    let dir = TempDir::new("threads");
    let scene = dir.write("motion-dof.pbrt", &example_scene("motion-dof.pbrt", 40, 30));
    let run = |threads: &str, seed: &str, name: &str| {
        let (out, stats) = (dir.join(name), dir.join(format!("{name}.json")));
        render_ok(
            &scene,
            &out,
            &[
                "--spp",
                "4",
                "--threads",
                threads,
                "--seed",
                seed,
                "--stats",
                stats.to_str().unwrap(),
            ],
        );
        assert_eq!(
            read_stats(&stats)["threads"].as_u64(),
            Some(threads.parse().unwrap()),
            "threads in the stats"
        );
        std::fs::read(&out).unwrap()
    };
    let one = run("1", "5", "one.exr");
    let two = run("2", "5", "two.exr");
    assert!(
        one == two,
        "--threads 1 and 2 with --seed 5 give different files"
    );
    let other = run("2", "6", "other.exr");
    assert!(one != other, "--seed 6 gives the same file as --seed 5");
}

/// Without -o the Film's "filename" is used, relative to the working directory (as pbrt-v3
/// does), not to the scene's folder; without either, the scene's path with .exr.
#[test]
fn without_an_output_the_films_filename_is_used() {
    let dir = TempDir::new("filmname");
    dir.write(
        "sub/named.pbrt",
        &small_scene("\"string filename\" \"film-name.png\""),
    );
    dir.write("sub/unnamed.pbrt", &small_scene(""));
    let run = |scene: &str| {
        let o = acr_command(["render", scene, "--spp", "1", "--quiet"])
            .current_dir(&dir.0)
            .output()
            .unwrap();
        assert!(o.status.success(), "{scene}: {}", stderr(&o));
    };
    run("sub/named.pbrt");
    let written = dir.join("film-name.png");
    assert!(
        written.is_file(),
        "film-name.png is not in the working directory"
    );
    assert!(!dir.join("sub/film-name.png").exists());
    assert_eq!(image::image_dimensions(&written).unwrap(), (24, 16));

    run("sub/unnamed.pbrt");
    let exr = dir.join("sub/unnamed.exr");
    assert!(exr.is_file(), "no sub/unnamed.exr");
    let img = read_image(&exr, false).unwrap();
    assert_eq!((img.width, img.height), (24, 16));
}

#[test]
fn every_sampler_gives_the_same_file_with_one_and_two_threads() {
    // Large enough for several cluster rounds, each planned while the one before is traced.
    let dir = TempDir::new("samplers");
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 64, 48));
    // The cluster sampler twice: unbiased (its default) and as published.
    let published = ["--set", "sampler.unbiased=false"];
    let runs: [(&str, &[&str]); 6] = [
        ("random", &[]),
        ("stratified", &[]),
        ("halton", &[]),
        ("sobol", &[]),
        ("cluster", &[]),
        ("cluster", &published),
    ];
    for (k, (sampler, extra)) in runs.into_iter().enumerate() {
        let run = |threads: &str| {
            let (out, stats) = (
                dir.join(format!("{sampler}{k}-{threads}.exr")),
                dir.join(format!("{sampler}{k}-{threads}.json")),
            );
            let args = ["--spp", "8", "--sampler", sampler, "--threads", threads];
            let stats_arg = ["--stats", stats.to_str().unwrap()];
            render_ok(&scene, &out, &[&args[..], &stats_arg[..], extra].concat());
            if sampler == "cluster" {
                let rounds = read_stats(&stats)["rounds"].as_u64().unwrap();
                assert!(rounds > 2, "{rounds} rounds");
            }
            std::fs::read(&out).unwrap()
        };
        assert!(run("1") == run("2"), "{sampler}: 1 and 2 threads differ");
    }
}
