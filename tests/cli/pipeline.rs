//! `--pipeline` (docs/cli.md): a render stopped by a time limit or a noise threshold that names
//! no sampler or filter, or one given `--pipeline auto`, renders with the table's pipeline for
//! the scene's dims and says so on stderr and in the stats.

use super::*;
use acr::cli::render::{row_for, Row, NFOR_ROW};
use acr_plugins::Dims;

/// The stats and stderr of rendering `scene` with `args`.
fn run(dir: &TempDir, scene: &Path, args: &[&str]) -> (serde_json::Value, String) {
    let (out, stats) = (dir.join("p.pfm"), dir.join("p.json"));
    let mut all = vec!["--seed", "1", "--stats", stats.to_str().unwrap()];
    all.extend_from_slice(args);
    let o = render_ok(scene, &out, &all);
    (read_stats(&stats), stderr(&o))
}

fn auto_name(row: &Row) -> String {
    format!("auto:{}+{}", row.sampler, row.filter)
}

#[test]
fn a_time_limit_or_noise_threshold_with_nothing_named_renders_the_auto_pipeline() {
    let dir = TempDir::new("pipeline-auto");
    // No Sampler, no PixelFilter, nothing moves, no lens.
    let scene = dir.write("s.pbrt", &small_scene(""));
    let dims_row = row_for(Dims::default());
    // A limit that leaves room for nfor's reconstruction takes the nfor row; a limit that
    // does not, and a noise threshold, the dims' row.
    let cases = [
        (["--time-limit", "30"], &NFOR_ROW),
        (["--time-limit", "0.0001"], dims_row),
        (["--noise-threshold", "0.5"], dims_row),
    ];
    for (stop, row) in cases {
        let (s, err) = run(&dir, &scene, &[stop[0], stop[1], "--spp", "4"]);
        assert_eq!(s["pipeline"], auto_name(row), "{stop:?}");
        assert_eq!(s["sampler"], row.sampler, "{stop:?}");
        assert_eq!(s["filter"], row.filter, "{stop:?}");
        let said = format!("pipeline auto: {} + {}", row.sampler, row.filter);
        assert!(err.contains(&said), "{stop:?}: {err}");
    }
    // Without --spp the row's cap is the budget, not pbrt-v3's default 16.
    let (s, _) = run(&dir, &scene, &["--noise-threshold", "1e-9"]);
    assert_eq!(s["spp"], 64);
}

#[test]
fn a_sampler_or_filter_named_anywhere_keeps_the_scenes_pipeline() {
    let dir = TempDir::new("pipeline-scene");
    let bare = dir.write("s.pbrt", &small_scene(""));
    let limit = ["--time-limit", "30", "--spp", "2"];
    let scene_pipeline = |s: &serde_json::Value, err: &str, what: &str| {
        assert_eq!(s["pipeline"], "scene", "{what}");
        assert!(!err.contains("pipeline auto"), "{what}: {err}");
    };
    for named in [["--sampler", "stratified"], ["--filter", "gaussian"]] {
        let (s, err) = run(&dir, &bare, &[&limit[..], &named[..]].concat());
        scene_pipeline(&s, &err, named[0]);
    }
    // Named in the scene.
    for directive in ["Sampler \"random\"", "PixelFilter \"triangle\""] {
        let text = small_scene("").replacen("WorldBegin", &format!("{directive}\nWorldBegin"), 1);
        let scene = dir.write("named.pbrt", &text);
        let (s, err) = run(&dir, &scene, &limit);
        scene_pipeline(&s, &err, directive);
    }
    // Neither a time limit nor a noise threshold: pbrt-v3's defaults, as before.
    let (s, err) = run(&dir, &bare, &["--spp", "2"]);
    scene_pipeline(&s, &err, "no stop");
    assert_eq!(s["sampler"], "halton");
    assert_eq!(s["filter"], "box");
    // `--pipeline scene` keeps today's behaviour under a time limit.
    let (s, err) = run(
        &dir,
        &bare,
        &[&limit[..], &["--pipeline", "scene"]].concat(),
    );
    scene_pipeline(&s, &err, "--pipeline scene");
    assert_eq!(s["sampler"], "halton");
    // Outputs only some pipelines give keep the scene's.
    let (out, stats) = (dir.join("m.exr"), dir.join("m.json"));
    let more = ["--mergeable", "--stats", stats.to_str().unwrap()];
    render_ok(&bare, &out, &[&limit[..], &more[..]].concat());
    assert_eq!(read_stats(&stats)["pipeline"], "scene");
}

#[test]
fn pipeline_auto_is_parsed_and_refuses_a_named_sampler() {
    let dir = TempDir::new("pipeline-parse");
    let bare = dir.write("s.pbrt", &small_scene(""));
    // `auto` without a stop, and on a scene whose Sampler it replaces, with a motion-blurred
    // and defocused scene's row.
    let (s, _) = run(&dir, &bare, &["--pipeline", "auto", "--spp", "2"]);
    assert_eq!(s["pipeline"], auto_name(row_for(Dims::default())));
    let moving = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 16, 12));
    let (s, _) = run(&dir, &moving, &["--pipeline", "auto", "--spp", "2"]);
    let row = row_for(Dims {
        time: true,
        lens: true,
    });
    assert_eq!(s["pipeline"], auto_name(row));
    assert_eq!(s["dims"], serde_json::json!(["x", "y", "t", "u", "v"]));
    let out = dir.join("x.pfm");
    render_fails(&bare, &out, &["--pipeline", "fastest"], "possible values");
    render_fails(
        &bare,
        &out,
        &["--pipeline", "auto", "--sampler", "sobol"],
        "--pipeline auto chooses the sampler and filter",
    );
}

#[test]
fn the_auto_pipeline_renders_what_naming_its_row_renders() {
    let dir = TempDir::new("pipeline-same");
    for (name, scene, dims) in [
        ("still", small_scene(""), Dims::default()),
        (
            "moving",
            example_scene("motion-blur.pbrt", 24, 16),
            Dims {
                time: true,
                lens: false,
            },
        ),
    ] {
        let scene = dir.write(&format!("{name}.pbrt"), &scene);
        let row = row_for(dims);
        let common = ["--seed", "3", "--spp", "4", "--threads", "2"];
        let auto = dir.join(format!("{name}-auto.pfm"));
        render_ok(
            &scene,
            &auto,
            &[&common[..], &["--pipeline", "auto"]].concat(),
        );
        let named = dir.join(format!("{name}-named.pfm"));
        let mut args = common.to_vec();
        args.extend(["--sampler", row.sampler, "--filter", row.filter]);
        for s in row.settings {
            args.extend(["--set", s]);
        }
        render_ok(&scene, &named, &args);
        let (a, b) = (
            std::fs::read(&auto).unwrap(),
            std::fs::read(&named).unwrap(),
        );
        assert!(
            a == b,
            "{name}: the auto pipeline's image differs from {args:?}'s"
        );
    }
}
