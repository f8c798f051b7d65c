//! Renders that stop early: the noise threshold and the time limit.

use super::*;

/// The image's estimated relative error as `--noise-threshold` measures it
/// (`acr::render::relative_error`: the mean over pixels of the standard error of the pixel's
/// mean luminance over that mean + 0.01, 1 for pixels of fewer than 2 samples), recomputed
/// from the per-pixel sample moments of the mergeable EXR at `path`.
fn relative_error_of_mergeable(path: &Path) -> f64 {
    use acr::geometry::Spectrum;
    let s = acr::cli::mergeable::Sums::read(path)
        .unwrap()
        .expect("a mergeable EXR");
    let moments = s.moments.as_ref().expect("sample moments");
    let luminance = |f: &dyn Fn(usize) -> f64| {
        f64::from(acr::spectrum_luminance(Spectrum::new(
            f(0) as f32,
            f(1) as f32,
            f(2) as f32,
        )))
    };
    let total: f64 = moments
        .iter()
        .zip(&s.counts)
        .map(|(m, &n)| {
            if n < 2.0 {
                return 1.0;
            }
            let mean = luminance(&|c| m[c] / n);
            let variance_of_mean =
                luminance(&|c| (m[3 + c] - m[c] * m[c] / n).max(0.0) / (n - 1.0) / n);
            acr_plugins::film::relative_error_of(mean, variance_of_mean)
        })
        .sum();
    total / moments.len() as f64
}

/// `--noise-threshold`: a loose threshold stops at `--min-spp` (plus the pass under way), with
/// every pixel at the same count, for every kind of sampler; a tighter one takes more samples
/// and ends with a lower error; the cluster sampler adapts before it stops; one that is never
/// met leaves the budget to `--spp`.
#[test]
fn a_noise_threshold_stops_early_keeps_min_spp_and_spp_caps_it() {
    let dir = TempDir::new("noise");
    // 40,000 pixels: more than a batch, so that a pass is one sample per pixel.
    let scene = dir.write("n.pbrt", &example_scene("cornell-box.pbrt", 200, 200));
    let pixels = 200 * 200;
    let run = |sampler: &str, args: &[&str]| {
        let (out, stats) = (dir.join(format!("{sampler}.exr")), dir.join("n.json"));
        let mut all = vec!["--sampler", sampler, "--seed", "1", "--stats"];
        all.push(stats.to_str().unwrap());
        all.extend_from_slice(args);
        render_ok(&scene, &out, &all);
        read_stats(&stats)
    };
    for sampler in ["stratified", "sobol", "random", "cluster"] {
        let s = run(
            sampler,
            &["--spp", "64", "--noise-threshold", "1e6", "--min-spp", "6"],
        );
        let spp = s["samples"].as_u64().unwrap() as f64 / pixels as f64;
        assert!((6.0..=7.0).contains(&spp), "{sampler}: {spp} spp");
        assert_eq!(s["halted"], true, "{sampler}");
        assert_eq!(s["halted_by"], "noise", "{sampler}");
    }
    // Tighter thresholds: more samples, and the error they stop at is below the threshold
    // (recomputed from the image's sample moments, which a mergeable EXR holds).
    let stop_at = |t: &str| {
        let (out, stats) = (dir.join(format!("t{t}.exr")), dir.join("t.json"));
        let args = ["--sampler", "stratified", "--seed", "1", "--spp", "1024"];
        let more = ["--noise-threshold", t, "--mergeable", "--stats"];
        let all = [&args[..], &more[..], &[stats.to_str().unwrap()]].concat();
        render_ok(&scene, &out, &all);
        let spp = read_stats(&stats)["samples"].as_u64().unwrap() / pixels;
        (spp, relative_error_of_mergeable(&out))
    };
    let ((loose, loose_error), (tight, tight_error)) = (stop_at("0.3"), stop_at("0.1"));
    eprintln!("stopped at {loose} spp, error {loose_error}; at {tight} spp, error {tight_error}");
    assert!(loose < tight && tight < 1024, "{loose} then {tight} spp");
    assert!(
        loose_error <= 0.3 && tight_error <= 0.1,
        "errors at the stop: {loose_error} (threshold 0.3), {tight_error} (0.1)"
    );
    // The loose one stopped early: its error is still above the tight threshold.
    assert!(loose_error > 0.1, "loose error {loose_error}");
    // The cluster sampler adapts toward the threshold: its first stage is --min-spp (not a
    // quarter of --spp), and it has planned rounds by the time the threshold stops it.
    let s = run(
        "cluster",
        &[
            "--spp",
            "1024",
            "--noise-threshold",
            "0.1",
            "--min-spp",
            "4",
        ],
    );
    assert_eq!(s["halted_by"], "noise");
    assert!(s["rounds"].as_u64().unwrap() > 0, "{}", s["rounds"]);
    assert!(s["samples"].as_u64().unwrap() < 1024 * pixels);
    // Never met: the budget caps it, and nothing says it halted.
    let s = run("stratified", &["--spp", "8", "--noise-threshold", "1e-9"]);
    assert_eq!(s["samples"].as_u64().unwrap(), 8 * pixels);
    assert_eq!(s["halted"], false);
    assert!(s["halted_by"].is_null());
}

#[test]
fn a_time_limit_stops_at_a_whole_pass_and_the_image_stays_complete() {
    let dir = TempDir::new("timelimit");
    let scene = dir.write("slow.pbrt", &example_scene("cornell-box.pbrt", 200, 200));
    let (out, stats, spp_aov) = (dir.join("t.exr"), dir.join("t.json"), dir.join("spp.exr"));
    let mut cmd = acr_command([
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
        "--spp",
        "100000",
        "--time-limit",
        "0.5",
        "--stats",
        stats.to_str().unwrap(),
        "--aov",
        &format!("spp={}", spp_aov.display()),
    ]);
    cmd.stderr(Stdio::piped()).stdout(Stdio::piped());
    let o = output_within(cmd, Duration::from_secs(60));
    assert!(o.status.success(), "{}", stderr(&o));
    let s = read_stats(&stats);
    assert_eq!(s["halted"], true);
    assert_eq!(s["halted_by"], "time");
    let samples = s["samples"].as_u64().unwrap();
    assert!(samples > 0 && samples < 100_000 * 200 * 200);
    // Whole passes: every pixel has the same count, and the image has no hole.
    let counts = read_image(&spp_aov, false).unwrap();
    let first = counts.pixels[0].x;
    assert!(first >= 1.0);
    assert!(counts.pixels.iter().all(|c| c.x == first));
    assert_eq!(first as u64 * 200 * 200, samples);
    let img = read_image(&out, false).unwrap();
    let lit = img.pixels.iter().filter(|c| c.max_element() > 0.0).count();
    assert!(lit > 200 * 200 * 9 / 10, "{lit} lit pixels");
}

/// A time limit that adapts (docs/algorithm.md §9): with `--spp 1024` the cluster sampler's first
/// stage would be 256 spp, longer than the limit, so planned for its budget it never adapts;
/// planned for what its speed says fits (`--time-plan fit`, the default) it ends its first
/// stage early, adapts in rounds, and stops in the time with every pixel sampled twice or more.
#[test]
fn a_time_limit_plans_the_adaptive_sampler_for_what_fits() {
    let dir = TempDir::new("timeplan");
    let scene = dir.write("t.pbrt", &example_scene("cornell-box.pbrt", 200, 200));
    let run = |plan: &str| {
        let (out, stats, spp) = (dir.join("t.exr"), dir.join("t.json"), dir.join("spp.exr"));
        let spp_aov = format!("spp={}", spp.display());
        let args = [
            "--sampler",
            "cluster",
            "--spp",
            "1024",
            "--time-limit",
            "3",
            "--time-plan",
            plan,
            "--aov",
            &spp_aov,
            "--stats",
            stats.to_str().unwrap(),
        ];
        render_ok(&scene, &out, &args);
        let least = read_image(&spp, false)
            .unwrap()
            .pixels
            .iter()
            .map(|c| c.x)
            .fold(f32::INFINITY, f32::min);
        (read_stats(&stats), least)
    };
    let (fit, least) = run("fit");
    assert_eq!(fit["halted_by"], "time");
    assert!(fit["rounds"].as_u64().unwrap() > 0, "{}", fit["rounds"]);
    assert!(least >= 2.0, "{least} spp");
    let (budget, _) = run("budget");
    assert_eq!(budget["halted_by"], "time");
    assert_eq!(budget["rounds"], 0);
}
