//! The other commands and scripts: `acr diff`, `acr plugins`, `acr bench`, `--sampler-cost` and `bench/versus.py`.

use super::*;

/// The number after `name ` in `acr diff`'s text output.
fn text_field(text: &str, name: &str) -> f64 {
    let mut words = text.split_whitespace();
    words
        .by_ref()
        .find(|w| *w == name)
        .unwrap_or_else(|| panic!("no {name} in {text:?}"));
    let v = words.next().unwrap();
    v.parse()
        .unwrap_or_else(|_| panic!("{name} is {v:?} in {text:?}"))
}

#[test]
fn diff_measures_the_error_between_two_images() {
    let dir = TempDir::new("diff");
    let scene = dir.write("small.pbrt", &small_scene(""));
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    render_ok(&scene, &a, &["--spp", "2", "--seed", "1"]);
    render_ok(&scene, &b, &["--spp", "2", "--seed", "2"]);

    // An image against itself.
    let o = acr([OsStr::new("diff"), a.as_os_str(), a.as_os_str()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(text_field(&stdout(&o), "mse"), 0.0, "{}", stdout(&o));
    assert_eq!(text_field(&stdout(&o), "relmse"), 0.0, "{}", stdout(&o));
    let o = acr([
        OsStr::new("diff"),
        a.as_os_str(),
        a.as_os_str(),
        OsStr::new("--json"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    for k in ["mse", "relmse", "psnr"] {
        assert!(v.get(k).is_some(), "--json lacks {k}: {v}");
    }
    assert_eq!(v["mse"].as_f64(), Some(0.0));
    assert_eq!(v["relmse"].as_f64(), Some(0.0));

    // Two renders with different seeds, against this test's own reckoning (docs/algorithm.md §7).
    let o = acr([
        OsStr::new("diff"),
        a.as_os_str(),
        b.as_os_str(),
        OsStr::new("--json"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let (ia, ib) = (
        read_image(&a, false).unwrap(),
        read_image(&b, false).unwrap(),
    );
    let n = (3 * ia.pixels.len()) as f64;
    let (mut se, mut rel, mut clamped) = (0.0, 0.0, 0.0);
    for (x, r) in ia.pixels.iter().zip(&ib.pixels) {
        for c in 0..3 {
            let (x, r) = (x[c] as f64, r[c] as f64);
            se += (x - r).powi(2);
            rel += (x - r).powi(2) / (r * r + 0.01);
            clamped += (x.clamp(0.0, 1.0) - r.clamp(0.0, 1.0)).powi(2);
        }
    }
    let (mse, relmse, psnr) = (se / n, rel / n, 10.0 * (n / clamped).log10());
    assert!(mse > 0.0);
    let near = |k: &str, want: f64| {
        let got = v[k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k} is not a number: {v}"));
        assert!(
            (got - want).abs() <= 1e-9 * want.abs(),
            "{k}: acr diff says {got}, expected {want}"
        );
    };
    near("mse", mse);
    near("relmse", relmse);
    near("psnr", psnr);
    // The text output agrees (it prints 7 significant digits).
    let o = acr([OsStr::new("diff"), a.as_os_str(), b.as_os_str()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text_mse = text_field(&stdout(&o), "mse");
    assert!((text_mse - mse).abs() <= 1e-6 * mse, "{text_mse} vs {mse}");

    // Images of different sizes cannot be compared.
    let small = dir.write(
        "smaller.pbrt",
        &small_scene("").replace("yresolution\" 16", "yresolution\" 12"),
    );
    let c = dir.join("c.exr");
    render_ok(&small, &c, &["--spp", "1"]);
    assert_eq!(read_image(&c, false).unwrap().height, 12);
    let o = acr([OsStr::new("diff"), a.as_os_str(), c.as_os_str()]);
    assert_clean_failure(&o, "diff of 24x16 and 24x12");
    let err = stderr(&o);
    assert!(
        err.contains("24x16") && err.contains("24x12"),
        "the message gives both sizes: {err}"
    );
    assert!(stdout(&o).trim().is_empty(), "{}", stdout(&o));
}

#[test]
fn plugins_lists_every_plugin_with_its_parameters() {
    let o = acr(["plugins"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for name in [
        "random",
        "stratified",
        "halton",
        "sobol",
        "box",
        "triangle",
        "gaussian",
        "mitchell",
        "sinc",
        "path",
        "directlighting",
    ] {
        assert!(
            text.lines().any(|l| l.trim_start().starts_with(name)),
            "{name} missing from:\n{text}"
        );
    }
    for param in [
        "integer pixelsamples",
        "integer xsamples",
        "bool jitter",
        "float alpha",
        "float B",
        "float tau",
        "integer maxdepth",
    ] {
        assert!(text.contains(param), "{param} missing");
    }
}

#[test]
fn sampler_cost_replays_the_render_and_reports_the_sampler_s_share() {
    let dir = TempDir::new("cost");
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 64, 48));
    for sampler in ["cluster", "stratified"] {
        let (plain, measured, stats) = (
            dir.join(format!("{sampler}.exr")),
            dir.join(format!("{sampler}-cost.exr")),
            dir.join(format!("{sampler}.json")),
        );
        let args = ["--spp", "8", "--sampler", sampler];
        render_ok(&scene, &plain, &args);
        let cost = ["--sampler-cost", "--stats", stats.to_str().unwrap()];
        render_ok(&scene, &measured, &[&args[..], &cost[..]].concat());
        // Recording the batches changes nothing; the replays and the renders again were
        // checked to give this image.
        assert!(std::fs::read(&plain).unwrap() == std::fs::read(&measured).unwrap());
        let s = read_stats(&stats);
        let replay = s["seconds"]["replay"].as_f64().unwrap();
        let rerender = s["seconds"]["rerender"].as_f64().unwrap();
        let share = s["sampler_share"].as_f64().unwrap();
        assert!(
            replay > 0.0 && rerender > 0.0,
            "{sampler}: {replay} {rerender}"
        );
        // The measure's six renders are not counted as reconstruction (a 64x48 image's
        // reconstruction takes microseconds, a render milliseconds).
        let reconstruct = s["seconds"]["reconstruct"].as_f64().unwrap();
        assert!(
            reconstruct < rerender,
            "{sampler}: reconstruct {reconstruct}"
        );
        // The figures are what they are documented to be: the medians over the three
        // back-to-back pairs of the rerender, the replay and (rerender - replay) / rerender
        // (0 if negative).
        let pairs: Vec<[f64; 2]> = serde_json::from_value(s["sampler_cost_pairs"].clone())
            .unwrap_or_else(|e| panic!("{sampler}: {e}"));
        assert_eq!(pairs.len(), 3, "{sampler}");
        assert!(pairs.iter().flatten().all(|&t| t > 0.0), "{pairs:?}");
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[1]
        };
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-9);
        assert!(close(
            rerender,
            median(pairs.iter().map(|p| p[0]).collect())
        ));
        assert!(close(replay, median(pairs.iter().map(|p| p[1]).collect())));
        let ratios = pairs.iter().map(|[r, p]| (r - p) / r).collect();
        let want = median(ratios).max(0.0);
        assert!(
            close(share, want),
            "{sampler}: share {share}, pairs give {want}"
        );
    }
    // Without the flag, neither is reported.
    let stats = dir.join("none.json");
    render_ok(
        &scene,
        &dir.join("none.exr"),
        &["--spp", "1", "--stats", stats.to_str().unwrap()],
    );
    let s = read_stats(&stats);
    for key in ["replay", "rerender"] {
        assert!(s["seconds"][key].is_null(), "{key}");
    }
    assert!(s["sampler_share"].is_null());
    assert!(s["sampler_cost_pairs"].is_null());
}

/// Runs `acr bench MANIFEST --out OUT`, which must succeed; its stderr.
fn bench_ok(manifest: &Path, out: &Path) -> String {
    let o = acr([
        "bench",
        manifest.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    stderr(&o)
}

#[test]
fn bench_writes_csv_plot_and_report_and_survives_a_failing_method() {
    let dir = TempDir::new("bench");
    dir.write("s.pbrt", &small_scene(""));
    let manifest = dir.write(
        "m.toml",
        "title = \"tiny\"\nseed = 3\nthreads = 2\n[budgets]\nspp = [1, 4]\nequal_time = true\n\
         [reference]\nsampler = \"sobol\"\nfilter = \"box\"\nspp = 64\n\
         [[scene]]\nname = \"small\"\npath = \"s.pbrt\"\n\
         [[method]]\nlabel = \"random+box\"\nsampler = \"random\"\nfilter = \"box\"\n\
         [[method]]\nlabel = \"sobol+gaussian\"\nsampler = \"sobol\"\nfilter = \"gaussian\"\n\
         set = [\"filter.alpha=3\"]\n\
         [[method]]\nlabel = \"broken\"\nsampler = \"nosuch\"\n",
    );
    let out = dir.join("out");
    let run = || bench_ok(&manifest, &out);
    let err = run();
    assert!(err.contains("rendering the reference"), "{err}");
    // A progress line per run: 2 budgets x (3 equal-spp + 2 equal-time).
    assert_eq!(err.matches("] small ").count(), 10, "{err}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "scene,method,mode,spp,seconds,samples,spp_reached,mse,relmse,psnr,peak_rss_mb,status,\
         mean_ratio,seeds,command_seconds,command_time"
    );
    assert_eq!(lines.len(), 11);
    let ok: Vec<&str> = lines[1..]
        .iter()
        .copied()
        .filter(|l| l.contains(",ok,"))
        .collect();
    assert_eq!(ok.len(), 6, "{csv}");
    assert!(lines
        .iter()
        .filter(|l| l.contains("broken"))
        .all(|l| l.contains("failed:") && l.contains("nosuch")));
    // Equal-spp rows took their budget exactly; errors are finite and fall with samples.
    let field = |l: &str, i: usize| l.split(',').nth(i).unwrap().parse::<f64>().unwrap();
    let eq = |m: &str, spp: &str| {
        *lines
            .iter()
            .find(|l| l.starts_with(&format!("small,{m},equal-spp,{spp},")))
            .unwrap()
    };
    for m in ["random+box", "sobol+gaussian"] {
        assert_eq!(field(eq(m, "1"), 6), 1.0);
        assert_eq!(field(eq(m, "4"), 6), 4.0);
        assert!(
            field(eq(m, "4"), 7) < field(eq(m, "1"), 7),
            "{m}: MSE falls"
        );
        // The image mean over the reference's: near 1 for an unbiased method.
        let mean = field(eq(m, "4"), 12);
        assert!((mean - 1.0).abs() < 0.05, "{m}: mean ratio {mean}");
    }
    let plot = std::fs::read(out.join("small.png")).unwrap();
    assert!(plot.len() > 1000 && plot.starts_with(b"\x89PNG"));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("# tiny"));
    assert!(report.contains("**4 runs failed**"), "{report}");
    assert!(report.contains("| 4 | sobol+gaussian |"), "{report}");
    // The reference is cached: a second run does not render it again.
    let err = run();
    assert!(!err.contains("rendering the reference"), "{err}");
}

#[test]
fn bench_runs_an_external_command_as_a_method_and_skips_one_whose_program_is_absent() {
    let dir = TempDir::new("bench-external");
    dir.write("s.pbrt", &small_scene(""));
    // `cp` through sh: the command's image is the render itself, so its MSE is the plain
    // method's; it prints 1 µs as its seconds (less than any render here, so that its equal-time render has time left).
    let copy = "command = [\"sh\", \"-c\", \"cp \\\"$0\\\" \\\"$1\\\" && echo 0.000001\", \"{in}\", \"{out}\"]";
    let manifest = dir.write(
        "m.toml",
        &format!(
            "seed = 5\nthreads = 2\n[budgets]\nspp = [2]\nequal_time = true\n\
             [reference]\nsampler = \"sobol\"\nfilter = \"box\"\nspp = 16\n\
             [[scene]]\nname = \"small\"\npath = \"s.pbrt\"\npixelbounds = [4, 20, 2, 14]\n\
             [[method]]\nlabel = \"random+box\"\nsampler = \"random\"\nfilter = \"box\"\n\
             [[method]]\nlabel = \"stratified+box\"\nsampler = \"stratified\"\nfilter = \"box\"\n\
             [[method]]\nlabel = \"copy\"\nsampler = \"stratified\"\nfilter = \"box\"\n\
             aov = \"albedo,normal\"\noutput = \"exr\"\ntime = \"printed\"\n{copy}\n\
             [[method]]\nlabel = \"absent\"\ncommand = [\"./no-such-denoiser\", \"{{in}}\", \"{{out}}\"]\n\
             [[method]]\nlabel = \"broken\"\ncommand = [\"sh\", \"-c\", \"exit 4\", \"{{in}}\", \"{{out}}\"]\n"
        ),
    );
    let out = dir.join("out");
    let err = bench_ok(&manifest, &out);
    assert!(
        err.contains(
            "warning: method \"absent\" skipped: program \"./no-such-denoiser\" not found"
        ),
        "{err}"
    );
    assert!(err.contains("failed, 2 skipped"), "{err}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let row = |m: &str, mode: &str| -> Vec<String> {
        let l = csv
            .lines()
            .find(|l| l.starts_with(&format!("small,{m},{mode},2,")))
            .unwrap_or_else(|| panic!("{m} {mode}: {csv}"));
        l.split(',').map(str::to_owned).collect()
    };
    let plain = row("stratified+box", "equal-spp");
    let copied = row("copy", "equal-spp");
    // The same image, scored alike; the command's printed seconds added and recorded.
    assert_eq!(copied[11], "ok", "{csv}");
    assert_eq!(copied[7], plain[7], "MSE: {csv}");
    assert_eq!(
        (copied[14].as_str(), copied[15].as_str()),
        ("0.000001", "printed")
    );
    assert!(plain[14].is_empty() && plain[15].is_empty(), "{csv}");
    // The crop: 16 x 12 pixels.
    assert_eq!(copied[5], (2 * 16 * 12).to_string(), "{csv}");
    let timed = row("copy", "equal-time");
    assert_eq!(timed[11], "ok", "{csv}");
    assert_eq!(timed[14], "0.000001", "{csv}");
    for mode in ["equal-spp", "equal-time"] {
        let absent = row("absent", mode);
        assert!(absent[11].starts_with("\"skipped: program"), "{csv}");
        let broken = row("broken", mode);
        assert!(broken[11].starts_with("\"failed:"), "{csv}");
    }
    assert!(
        csv.contains("method \"\"broken\"\": \"\"sh\"\" exit 4"),
        "{csv}"
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("**2 runs failed**"), "{report}");
    assert!(
        report.contains("**`absent` was skipped: program"),
        "{report}"
    );
    assert!(report.contains("- `copy`: `sh -c"), "{report}");
    assert!(report.contains("| 2 | absent | skipped |"), "{report}");
    // The images side by side, and their crop, at the budget.
    for name in ["small-images-equal-spp-2", "small-images-equal-time-2"] {
        for file in [format!("{name}.png"), format!("{name}-crop.png")] {
            let png = std::fs::read(out.join(&file)).unwrap_or_else(|e| panic!("{file}: {e}"));
            assert!(png.starts_with(b"\x89PNG"), "{file}");
            assert!(report.contains(&file), "{report}");
        }
    }
}

#[test]
fn bench_rows_over_seeds_are_the_means_of_each_seed_s_rows() {
    let dir = TempDir::new("bench-seeds");
    dir.write("s.pbrt", &small_scene(""));
    let manifest = |seeds: &str| {
        format!(
            "{seeds}\nthreads = 2\n[budgets]\nspp = [2]\nequal_time = true\n\
             [reference]\nsampler = \"sobol\"\nfilter = \"box\"\nspp = 32\n\
             [[scene]]\nname = \"small\"\npath = \"s.pbrt\"\n\
             [[method]]\nlabel = \"random+box\"\nsampler = \"random\"\nfilter = \"box\"\n\
             [[method]]\nlabel = \"stratified+box\"\nsampler = \"stratified\"\nfilter = \"box\"\n"
        )
    };
    // The equal-spp rows: MSE and the seeds column, by method.
    let rows = |name: &str, seeds: &str| {
        let out = dir.join(name);
        bench_ok(&dir.write(&format!("{name}.toml"), &manifest(seeds)), &out);
        let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
        let rows: Vec<(String, f64, String)> = csv
            .lines()
            .filter(|l| l.contains(",equal-spp,"))
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                (f[1].to_owned(), f[7].parse().unwrap(), f[13].to_owned())
            })
            .collect();
        (rows, out)
    };
    // `seed` keeps the reference the same for all three.
    let (one, _) = rows("one", "seed = 7\nseeds = [1]");
    let (two, _) = rows("two", "seed = 7\nseeds = [2]");
    let (both, out) = rows("both", "seed = 7\nseeds = [1, 2]");
    assert_eq!(both.len(), 2);
    for ((a, b), c) in one.iter().zip(&two).zip(&both) {
        assert_eq!((&a.0, &a.2, &c.2), (&c.0, &"1".to_owned(), &"2".to_owned()));
        let mean = (a.1 + b.1) / 2.0;
        assert!(
            (c.1 - mean).abs() <= 1e-5 * mean,
            "{}: {} against {mean}",
            c.0,
            c.1
        );
    }
    // Each seed's run keeps its image; the report names the seeds.
    for seed in [1, 2] {
        let run = format!("small-stratified_box-2-equal-time-seed{seed}.exr");
        assert!(out.join("runs").join(&run).is_file(), "{run}");
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("- seeds: 1, 2 (each row the means"),
        "{report}"
    );
}

#[test]
fn bench_measures_the_sampler_s_share_of_wall_time_when_asked() {
    let dir = TempDir::new("bench-cost");
    dir.write("s.pbrt", &small_scene(""));
    let manifest = dir.write(
        "m.toml",
        "seed = 2\nthreads = 2\n[budgets]\nspp = [2]\nequal_time = false\n\
         [sampler_cost]\nspp = [2]\nruns = 2\n\
         [reference]\nsampler = \"sobol\"\nfilter = \"box\"\nspp = 16\n\
         [[scene]]\nname = \"small\"\npath = \"s.pbrt\"\n\
         [[method]]\nlabel = \"random+box\"\nsampler = \"random\"\nfilter = \"box\"\n\
         [[method]]\nlabel = \"cluster+gaussian\"\nsampler = \"cluster\"\nfilter = \"gaussian\"\n\
         [[method]]\nlabel = \"broken\"\nsampler = \"nosuch\"\n",
    );
    let out = dir.join("out");
    let err = bench_ok(&manifest, &out);
    assert_eq!(err.matches("spp sampler cost: ").count(), 3, "{err}");
    assert!(err.contains("3 sampler-cost measures, 1 failed"), "{err}");
    let csv = std::fs::read_to_string(out.join("sampler_cost.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "scene,method,spp,runs,sampler_share,share_min,share_max,rerender_seconds,replay_seconds,status"
    );
    assert_eq!(lines.len(), 4, "{csv}");
    for m in ["random+box", "cluster+gaussian"] {
        let l = lines
            .iter()
            .find(|l| l.starts_with(&format!("small,{m},2,")))
            .unwrap_or_else(|| panic!("{m}: {csv}"));
        assert!(l.ends_with(",ok"), "{l}");
        let f = |i: usize| l.split(',').nth(i).unwrap().parse::<f64>().unwrap();
        assert_eq!(f(3), 2.0, "{l}");
        let (share, lo, hi) = (f(4), f(5), f(6));
        assert!(
            (0.0..1.0).contains(&share) && lo <= share && share <= hi,
            "{l}"
        );
        assert!(f(7) > 0.0 && f(8) > 0.0, "{l}");
    }
    let broken = lines.iter().find(|l| l.contains("broken")).unwrap();
    assert!(
        broken.contains("failed:") && broken.contains("nosuch"),
        "{broken}"
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("## The sampler's share of wall time"),
        "{report}"
    );
    assert!(
        report.contains("| small | 2 | cluster+gaussian | "),
        "{report}"
    );
    assert!(
        report.contains("| small | 2 | broken | failed |"),
        "{report}"
    );
}

/// bench/versus.py (acr alone, as without pbrt binaries): it renders the given scene and puts
/// its table between the markers of the output file, keeping the text around them. Needs
/// python3 on the PATH (and fails, rather than passes, without it).
#[test]
fn the_comparison_script_writes_its_table_between_the_markers() {
    assert!(
        Command::new("python3").arg("--version").output().is_ok(),
        "this test runs bench/versus.py: it needs python3 on the PATH"
    );
    let dir = TempDir::new("versus");
    let scene = dir.write(
        "tiny.pbrt",
        "LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\"\n\
         Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
         Sampler \"random\" \"integer pixelsamples\" 2\nWorldBegin\n\
         LightSource \"point\" \"point from\" [0 0 -2]\nShape \"sphere\"\nWorldEnd\n",
    );
    let out = dir.write(
        "report.md",
        "# before\n<!-- versus:begin -->\nold table\n<!-- versus:end -->\nafter\n",
    );
    // bench/versus.py with this acr on `scene`, and `args`.
    let versus = |args: &[&OsStr]| {
        Command::new("python3")
            .arg(root().join("bench/versus.py"))
            .args(["--acr", env!("CARGO_BIN_EXE_acr"), "--scene"])
            .arg(&scene)
            .args(args)
            .output()
            .unwrap()
    };
    let run = versus(&[
        "--threads".as_ref(),
        "1".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.starts_with("# before\n<!-- versus:begin -->\n"),
        "{text}"
    );
    assert!(text.ends_with("<!-- versus:end -->\nafter\n"), "{text}");
    assert!(!text.contains("old table"), "{text}");
    let row = text
        .lines()
        .find(|l| l.starts_with("| tiny |"))
        .unwrap_or_else(|| panic!("no row for the scene: {text}"));
    // | tiny | seconds | peak MiB |: both numbers, the time positive.
    let cells: Vec<&str> = row.trim_matches('|').split('|').map(str::trim).collect();
    assert_eq!(cells.len(), 3, "{row}");
    assert!(cells[1].parse::<f64>().unwrap() > 0.0, "{row}");
    assert!(cells[2].parse::<f64>().unwrap() > 0.0, "{row}");
    // A binary that is not there is a clear error, not a table.
    let bad = versus(&["--pbrt-v4".as_ref(), "/nonexistent/pbrt".as_ref()]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("pbrt-v4 binary /nonexistent/pbrt is not an executable file"),
        "{err}"
    );
}
