//! Plugins chosen by the scene and the command line, and what the adaptive samplers and the polynomial filter report.

use super::*;

/// The plugins a render used, from its stats file.
fn plugins_used(stats: &serde_json::Value) -> [String; 3] {
    ["sampler", "filter", "integrator"].map(|k| stats[k].as_str().unwrap_or("?").to_owned())
}

/// The rivals make the image themselves: the stats file names the sampler as the
/// reconstruction, a filter asked for is reported unused, the budget is spent exactly and the
/// file is the same with 1 and 2 threads.
#[test]
fn the_rivals_reconstruct_the_image_themselves() {
    let dir = TempDir::new("rivals");
    let scene = dir.write("s.pbrt", &small_scene(""));
    for name in ["mdas", "gem", "awr"] {
        let (a, b) = (
            dir.join(format!("{name}1.exr")),
            dir.join(format!("{name}2.exr")),
        );
        let stats = dir.join(format!("{name}.json"));
        let o = render_ok(
            &scene,
            &a,
            &[
                "--sampler",
                name,
                "--filter",
                "gaussian",
                "--spp",
                "6",
                "--threads",
                "1",
                "--stats",
                stats.to_str().unwrap(),
            ],
        );
        assert!(
            stderr(&o).contains(&format!(
                "the {name} sampler reconstructs the image itself; filter \"gaussian\" is not used"
            )),
            "{}",
            stderr(&o)
        );
        let s = read_stats(&stats);
        assert_eq!(plugins_used(&s)[..2], [name.to_owned(), name.to_owned()]);
        assert_eq!(s["samples"], 24 * 16 * 6, "{name}: budget");
        assert!(
            s["rounds"].as_u64().unwrap_or(0) >= 2,
            "{name}: adaptive rounds"
        );
        render_ok(
            &scene,
            &b,
            &["--sampler", name, "--spp", "6", "--threads", "2"],
        );
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{name}: 1 and 2 threads differ"
        );
    }
}

#[test]
fn plugins_come_from_the_scene_and_the_command_line_overrides_them() {
    let dir = TempDir::new("plugins");
    let scene = dir.write(
        "s.pbrt",
        &small_scene("")
            .replace(
                "WorldBegin",
                "Sampler \"stratified\" \"integer xsamples\" 2 \"integer ysamples\" 3\n\
                 PixelFilter \"mitchell\" \"float B\" 0.5\nWorldBegin",
            )
            .replace("\"path\"", "\"directlighting\""),
    );
    let (out, stats) = (dir.join("a.exr"), dir.join("a.json"));
    render_ok(&scene, &out, &["--stats", stats.to_str().unwrap()]);
    let s = read_stats(&stats);
    assert_eq!(
        plugins_used(&s),
        ["stratified", "mitchell", "directlighting"]
    );
    assert_eq!(s["spp"], 6, "xsamples x ysamples");
    render_ok(
        &scene,
        &out,
        &[
            "--stats",
            stats.to_str().unwrap(),
            "--sampler",
            "sobol",
            "--filter",
            "gaussian",
            "--integrator",
            "path",
            "--set",
            "sampler.pixelsamples=3",
            "--set",
            "filter.alpha=1.5",
        ],
    );
    let s = read_stats(&stats);
    assert_eq!(plugins_used(&s), ["sobol", "gaussian", "path"]);
    assert_eq!(s["spp"], 3);
    assert_eq!(s["samples"], 3 * 24 * 16);
    // pbrt-v3's names acr lacks map to the nearest, with a warning.
    let scene = dir.write(
        "alias.pbrt",
        &small_scene("").replace(
            "WorldBegin",
            "Sampler \"02sequence\" \"integer pixelsamples\" 2\nWorldBegin",
        ),
    );
    let o = render_ok(&scene, &out, &["--stats", stats.to_str().unwrap()]);
    assert!(stderr(&o).contains("\"02sequence\""), "{}", stderr(&o));
    assert_eq!(read_stats(&stats)["sampler"], "sobol");
    assert_eq!(read_stats(&stats)["spp"], 2);
}

#[test]
fn the_cluster_sampler_reports_clusters_and_draws_them() {
    let dir = TempDir::new("cluster");
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 40, 30));
    let (out, stats, clusters, ids, spp) = (
        dir.join("c.exr"),
        dir.join("c.json"),
        dir.join("clusters.png"),
        dir.join("clusters.exr"),
        dir.join("spp.exr"),
    );
    let aov = format!("clusters={},spp={}", clusters.display(), spp.display());
    let o = render_ok(
        &scene,
        &out,
        &[
            "--spp",
            "8",
            "--sampler",
            "cluster",
            "--set",
            "sampler.bins=2",
            "--filter",
            "gaussian",
            "--stats",
            stats.to_str().unwrap(),
            "--aov",
            &aov,
            "--aov",
            &format!("clusters={}", ids.display()),
        ],
    );
    let _ = o;
    let s = read_stats(&stats);
    let n = |k: &str| s[k].as_u64().unwrap_or_else(|| panic!("{k}: {s}"));
    // 40 x 30 pixels, 8 cells each (t, u, v in two bins).
    assert_eq!(n("cells"), 40 * 30 * 8);
    assert!(n("clusters") > 1 && n("clusters") < n("cells"), "{s}");
    assert!(n("rounds") >= 1);
    assert_eq!(n("samples"), 40 * 30 * 8, "the budget, spent exactly");
    let sampler_s = s["seconds"]["sampler"].as_f64().unwrap();
    assert!(sampler_s > 0.0 && sampler_s <= s["seconds"]["render"].as_f64().unwrap());
    // The samples went unevenly, never below one per pixel, 8 on average.
    let counts = read_image(&spp, false).unwrap();
    let (lo, hi) = counts
        .pixels
        .iter()
        .fold((f32::MAX, 0.0f32), |(a, b), c| (a.min(c.x), b.max(c.x)));
    assert!(lo >= 1.0 && hi > 8.0, "spp from {lo} to {hi}");
    // The partition: cluster ids in the EXR, colours with dark borders in the PNG.
    let ids = read_image(&ids, false).unwrap();
    let distinct: std::collections::HashSet<u32> = ids.pixels.iter().map(|c| c.x as u32).collect();
    assert!(distinct.len() > 1);
    let png = image::open(&clusters).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (40, 30));
    let colours: std::collections::HashSet<[u8; 3]> = png.pixels().map(|p| p.0).collect();
    assert!(colours.len() > 2, "{} colours", colours.len());
    // Another sampler has no clusters to draw: refused before rendering.
    render_fails(
        &scene,
        &dir.join("x.exr"),
        &[
            "--sampler",
            "sobol",
            "--aov",
            &format!("clusters={}", clusters.display()),
        ],
        "makes no clusters",
    );
    // A knob out of range is a located error.
    render_fails(
        &scene,
        &dir.join("x.exr"),
        &["--sampler", "cluster", "--set", "sampler.omega=-1"],
        "omega -1 is out of range",
    );
}

#[test]
fn the_polynomial_filter_reconstructs_after_any_sampler_and_reports_its_fits() {
    let dir = TempDir::new("polynomial");
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 40, 30));
    for sampler in ["stratified", "cluster"] {
        let (out, stats) = (dir.join(format!("{sampler}.exr")), dir.join("p.json"));
        let args = [
            "--spp",
            "4",
            "--sampler",
            sampler,
            "--filter",
            "polynomial",
            "--stats",
            stats.to_str().unwrap(),
        ];
        render_ok(&scene, &out, &args);
        let s = read_stats(&stats);
        assert_eq!(s["filter"], "polynomial");
        let fitted: Vec<u64> = s["fitted_by_degree"]
            .as_array()
            .unwrap_or_else(|| panic!("fitted_by_degree: {s}"))
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        assert_eq!(fitted.len(), 3);
        // 5D: degree 1 by default, so no cluster at degree 2, and some fitted at all.
        assert!(
            fitted[0] + fitted[1] > 0 && fitted[2] == 0,
            "{sampler}: {fitted:?}"
        );
        let img = read_image(&out, false).unwrap();
        assert_eq!(img.pixels.len(), 40 * 30);
        assert!(img
            .pixels
            .iter()
            .all(|c| c.is_finite() && c.min_element() >= 0.0));
        assert!(
            img.pixels.iter().any(|c| c.max_element() > 0.0),
            "{sampler}: black image"
        );
    }
    // A bad knob is a located error.
    render_fails(
        &scene,
        &dir.join("bad.exr"),
        &["--filter", "polynomial", "--set", "filter.degree=5"],
        "degree 5 is out of range",
    );
}

#[test]
fn nfor_reconstructs_after_any_sampler_the_same_on_any_thread_count() {
    let dir = TempDir::new("nfor");
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 40, 30));
    let mean = |img: &[acr::geometry::Spectrum]| {
        img.iter().map(|c| f64::from(c.x + c.y + c.z)).sum::<f64>()
    };
    let render = |name: &str, extra: &[&str]| {
        let out = dir.join(format!("{name}.exr"));
        let mut args = vec!["--spp", "8"];
        args.extend_from_slice(extra);
        render_ok(&scene, &out, &args);
        read_image(&out, false).unwrap().pixels
    };
    let plain = mean(&render(
        "box",
        &["--sampler", "stratified", "--filter", "box"],
    ));
    for (name, sampler) in [
        ("stratified", &["--sampler", "stratified"][..]),
        ("sobol", &["--sampler", "sobol"][..]),
        ("cluster", &["--sampler", "cluster"][..]),
        (
            "streams",
            &["--sampler", "cluster", "--set", "sampler.streams=2"][..],
        ),
    ] {
        let mut args = sampler.to_vec();
        args.extend(["--filter", "nfor"]);
        let img = render(name, &args);
        assert_eq!(img.len(), 40 * 30);
        assert!(img.iter().all(|c| c.is_finite() && c.min_element() >= 0.0));
        // The filter moves the image mean by little: within the noise of 8 spp on 1200 pixels.
        let m = mean(&img);
        assert!(
            (m / plain - 1.0).abs() < 0.03,
            "{name}: mean {m} against box's {plain}"
        );
    }
    let one = render(
        "one",
        &[
            "--sampler",
            "stratified",
            "--filter",
            "nfor",
            "--threads",
            "1",
        ],
    );
    let two = render(
        "two",
        &[
            "--sampler",
            "stratified",
            "--filter",
            "nfor",
            "--threads",
            "2",
        ],
    );
    assert_eq!(one, two);
    render_fails(
        &scene,
        &dir.join("bad.exr"),
        &["--filter", "nfor", "--set", "filter.radius=40"],
        "radius 40 is out of range",
    );
}

/// `--aov fitclusters`: the polynomial filter's fitted clusters, as ids per pixel. With the
/// first-hit features, no cluster straddles the edge between two albedos; a filter that fits
/// nothing is told so.
#[test]
fn the_fit_clusters_follow_an_albedo_edge() {
    let dir = TempDir::new("fitclusters");
    let scene = dir.write(
        "halves.pbrt",
        "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
         Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
         Sampler \"random\" \"integer pixelsamples\" 16\nWorldBegin\n\
         LightSource \"distant\" \"point from\" [0 0 0] \"point to\" [0 0 1] \"rgb L\" [3 3 3]\n\
         AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.2 0.2 0.2]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [-9 -9 4  0 -9 4  0 9 4  -9 9 4]\nAttributeEnd\n\
         Material \"matte\" \"rgb Kd\" [0.8 0.8 0.8]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [0 -9 4  9 -9 4  9 9 4  0 9 4]\nWorldEnd\n",
    );
    let ids = dir.join("ids.exr");
    let aov = format!("fitclusters={}", ids.display());
    let out = dir.join("o.exr");
    let args = [
        "--filter",
        "polynomial",
        "--set",
        "filter.features=true",
        "--aov",
        &aov,
    ];
    render_ok(&scene, &out, &args);
    let ids = read_image(&ids, false).unwrap();
    let image = read_image(&out, false).unwrap();
    let id = |x: usize, y: usize| ids.pixels[y * 16 + x].x;
    let mut found = std::collections::BTreeSet::new();
    for y in 0..16 {
        for x in 0..16 {
            let v = id(x, y);
            assert!(v >= 0.0 && v.fract() == 0.0, "id {v}");
            found.insert(v as u32);
        }
    }
    // The two albedos' sides, told apart by the image (which side is brighter).
    let left = image.pixels[8 * 16 + 2].x < image.pixels[8 * 16 + 13].x;
    let dark = |x: usize| (x < 8) == left;
    let side = |want: bool| -> std::collections::BTreeSet<u32> {
        (0..256)
            .filter(|i| dark(i % 16) == want)
            .map(|i| id(i % 16, i / 16) as u32)
            .collect()
    };
    let (d, b) = (side(true), side(false));
    assert!(
        d.is_disjoint(&b),
        "a cluster straddles the edge: {d:?} {b:?}"
    );
    // Noise merges: far fewer clusters than pixels.
    assert!(
        found.len() >= 2 && found.len() <= 32,
        "{} clusters",
        found.len()
    );
    render_fails(
        &scene,
        &out,
        &["--filter", "box", "--aov", &aov],
        "the filter fitted no clusters",
    );
}
