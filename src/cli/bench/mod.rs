//! `acr bench MANIFEST.toml`: time against error. Renders every scene of a manifest with every
//! method at every budget (and, in equal-time mode, with each method given the first method's
//! time), compares each image with the scene's reference, and writes a CSV, a log-log plot of
//! error against time per scene and a Markdown report. Each render is a separate `acr render`
//! process, so that its time and peak memory are its own and a crash is only a failed row.

use crate::cli::stats::median;
use crate::image_io::read_image;
use crate::metrics::{compare, Metrics};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

mod manifest;
mod report;

pub use manifest::*;
pub use report::*;

/// One row of the results.
#[derive(Clone, Debug)]
pub struct Row {
    /// Scene label.
    pub scene: String,
    /// Method label.
    pub method: String,
    /// How it was budgeted.
    pub mode: Mode,
    /// The budget (equal-time: the budget whose baseline time it was given).
    pub spp: u32,
    /// How many seeds its figures are the means over.
    pub seeds: usize,
    /// What the run measured (the means over its seeds), or why it (one of them) failed.
    pub outcome: Result<Measured, String>,
}

/// What a successful run measured.
#[derive(Clone, Debug)]
pub struct Measured {
    /// Render plus reconstruction time, from its stats file.
    pub seconds: f64,
    /// Samples taken.
    pub samples: u64,
    /// Samples per pixel reached.
    pub spp_reached: f64,
    /// Error against the reference.
    pub metrics: Metrics,
    /// Peak resident memory of the run's process.
    pub peak_rss_mb: f64,
}

/// The sampler's share of wall time of one method on one scene at one budget.
#[derive(Clone, Debug)]
pub struct CostRow {
    /// Scene label.
    pub scene: String,
    /// Method label.
    pub method: String,
    /// The budget.
    pub spp: u32,
    /// Each run's figures, or why a run failed.
    pub outcome: Result<Vec<SamplerCost>, String>,
}

/// What one `--sampler-cost` run reported.
#[derive(Clone, Copy, Debug)]
pub struct SamplerCost {
    /// Its `sampler_share`.
    pub share: f64,
    /// Its `seconds.rerender`: a render by a fresh sampler.
    pub rerender: f64,
    /// Its `seconds.replay`: the same points traced without the sampler.
    pub replay: f64,
}

/// A sampler-cost measure over its runs.
#[derive(Clone, Copy, Debug)]
struct CostSummary {
    runs: usize,
    /// The median share.
    share: f64,
    least: f64,
    largest: f64,
    /// The median seconds of a render by a fresh sampler.
    rerender: f64,
    /// The median seconds of a replay.
    replay: f64,
}

impl Measured {
    /// The means of `runs` (one per seed; the largest peak memory), or the first failure.
    fn mean_of(runs: Vec<Result<Measured, String>>) -> Result<Measured, String> {
        let runs = runs.into_iter().collect::<Result<Vec<_>, String>>()?;
        let n = runs.len().max(1) as f64;
        let mean = |f: fn(&Measured) -> f64| runs.iter().map(f).sum::<f64>() / n;
        Ok(Measured {
            seconds: mean(|r| r.seconds),
            samples: mean(|r| r.samples as f64).round() as u64,
            spp_reached: mean(|r| r.spp_reached),
            metrics: Metrics {
                mse: mean(|r| r.metrics.mse),
                relmse: mean(|r| r.metrics.relmse),
                psnr: mean(|r| r.metrics.psnr),
                mean: mean(|r| r.metrics.mean),
                reference_mean: mean(|r| r.metrics.reference_mean),
            },
            peak_rss_mb: runs.iter().map(|r| r.peak_rss_mb).fold(0.0, f64::max),
        })
    }
}

impl CostRow {
    /// Its runs summed up, or why one failed.
    fn summary(&self) -> Result<CostSummary, &str> {
        let runs = self.outcome.as_deref().map_err(String::as_str)?;
        let of = |f: fn(&SamplerCost) -> f64| runs.iter().map(f).collect::<Vec<_>>();
        let mut shares = of(|r| r.share);
        let share = median(&mut shares);
        Ok(CostSummary {
            runs: runs.len(),
            share,
            // Sorted by the median.
            least: shares.first().copied().unwrap_or(f64::NAN),
            largest: shares.last().copied().unwrap_or(f64::NAN),
            rerender: median(&mut of(|r| r.rerender)),
            replay: median(&mut of(|r| r.replay)),
        })
    }
}

/// Everything a bench measured.
#[derive(Clone, Debug)]
pub struct BenchResults {
    /// The equal-spp and equal-time runs.
    pub rows: Vec<Row>,
    /// The sampler-cost measures.
    pub costs: Vec<CostRow>,
}

/// FNV-1a, 64 bits: a stable hash for cache keys (std's hasher may change between releases).
fn fnv1a(h: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *h ^= u64::from(b);
        *h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
}

/// The cache key of a reference: every file the scene reads, the method, budget and seed.
fn reference_key(scene: &Path, method: &Method, spp: u32, seed: u64) -> Result<u64, String> {
    let desc = acr_parser::parse_file(scene).map_err(|e| e.to_string())?;
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for f in &desc.files {
        fnv1a(&mut h, f.text.as_bytes());
        fnv1a(&mut h, &[0xff]);
    }
    // Meshes and images the scene loads are files too; their bytes count when present.
    let dir = scene.parent().unwrap_or(Path::new("."));
    for f in &desc.files {
        for word in f.text.split('"') {
            let lower = word.to_ascii_lowercase();
            if [".ply", ".exr", ".png", ".pfm", ".hdr"]
                .iter()
                .any(|e| lower.ends_with(e))
            {
                if let Ok(bytes) = std::fs::read(dir.join(word)) {
                    fnv1a(&mut h, &bytes);
                }
            }
        }
    }
    let m = format!(
        "{:?}|{:?}|{:?}|{:?}|{spp}|{seed}|{}",
        method.sampler,
        method.filter,
        method.integrator,
        method.set,
        env!("CARGO_PKG_VERSION")
    );
    fnv1a(&mut h, m.as_bytes());
    Ok(h)
}

/// What `acr render` reported of one run.
struct RunOutput {
    seconds: f64,
    samples: u64,
    pixels: u64,
    peak_rss_mb: f64,
    /// With `--sampler-cost`: what it measured.
    cost: Option<SamplerCost>,
}

/// Runs `acr render` as a child process.
#[allow(clippy::too_many_arguments)]
fn run_render(
    exe: &Path,
    scene: &Path,
    output: &Path,
    method: &Method,
    spp: u32,
    seed: u64,
    threads: Option<u32>,
    time_limit: Option<f64>,
    sampler_cost: bool,
) -> Result<RunOutput, String> {
    let stats = output.with_extension("json");
    let mut cmd = Command::new(exe);
    cmd.arg("render")
        .arg(scene)
        .arg("-o")
        .arg(output)
        .arg("--quiet")
        .arg("--stats")
        .arg(&stats)
        .arg("--spp")
        .arg(spp.to_string())
        .arg("--seed")
        .arg(seed.to_string());
    for (flag, v) in [
        ("--sampler", &method.sampler),
        ("--filter", &method.filter),
        ("--integrator", &method.integrator),
    ] {
        if let Some(v) = v {
            cmd.arg(flag).arg(v);
        }
    }
    for s in &method.set {
        cmd.arg("--set").arg(s);
    }
    if let Some(t) = threads {
        cmd.arg("--threads").arg(t.to_string());
    }
    if let Some(t) = time_limit {
        cmd.arg("--time-limit").arg(format!("{t:.6}"));
        if let Some(plan) = method.time_plan {
            let name = clap::ValueEnum::to_possible_value(&plan).expect("named");
            cmd.arg("--time-plan").arg(name.get_name());
        }
    }
    if sampler_cost {
        cmd.arg("--sampler-cost");
    }
    let out = cmd
        .output()
        .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let first = err.lines().next().unwrap_or("").trim();
        return Err(match out.status.code() {
            Some(c) => format!("exit {c}: {first}"),
            None => format!("killed by a signal: {first}"),
        });
    }
    let text = std::fs::read_to_string(&stats)
        .map_err(|e| format!("{}: cannot read: {e}", stats.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", stats.display()))?;
    let f = |k: &str| v["seconds"][k].as_f64().unwrap_or(0.0);
    let cost = if sampler_cost {
        let share = v["sampler_share"]
            .as_f64()
            .ok_or_else(|| format!("{}: no sampler_share", stats.display()))?;
        Some(SamplerCost {
            share,
            rerender: f("rerender"),
            replay: f("replay"),
        })
    } else {
        None
    };
    Ok(RunOutput {
        cost,
        seconds: f("render") + f("reconstruct"),
        samples: v["samples"].as_u64().unwrap_or(0),
        pixels: v["width"].as_u64().unwrap_or(0) * v["height"].as_u64().unwrap_or(0),
        peak_rss_mb: v["peak_rss_mb"].as_f64().unwrap_or(0.0),
    })
}

/// Options of a bench run.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// The `acr` executable to run renders with.
    pub exe: PathBuf,
    /// Where the CSV, plots and report go.
    pub out: PathBuf,
    /// The command line that started it, for the report.
    pub command: String,
    /// The git commit of the working tree when it started, for the report.
    pub commit: String,
}

/// Equal-time runs take the samples per pixel that the method's own equal-spp run says fit in
/// the first method's time, at most this many times the budget, with that time as a limit. A
/// sampler that plans from its budget (stratified's strata, the cluster sampler's stages)
/// then plans for what it will reach: given a larger budget and stopped by the clock, the
/// cluster sampler would spend the time in its first stage and never adapt.
const EQUAL_TIME_SPP_FACTOR: u32 = 4;

/// The equal-time budget: `spp` scaled by the first method's seconds over this method's own
/// at `spp`, within 1 and `EQUAL_TIME_SPP_FACTOR` x `spp`.
fn equal_time_spp(spp: u32, baseline: Option<f64>, own: Option<f64>) -> u32 {
    let cap = spp
        .saturating_mul(EQUAL_TIME_SPP_FACTOR)
        .min(crate::render::MAX_SPP);
    match (baseline, own) {
        (Some(base), Some(own)) if own > 0.0 && base > 0.0 => {
            ((f64::from(spp) * base / own).round() as u32).clamp(1, cap)
        }
        _ => cap,
    }
}

/// A compared run's spp and time limit: at equal spp the budget; at equal time the first
/// method's seconds at this budget as the limit (`seconds.0`, an error where it failed) with the
/// spp that `time_limited_spp` names or the method's own equal-spp seconds (`seconds.1`) say fit.
fn run_budget(
    mode: Mode,
    spp: u32,
    budgets: &Budgets,
    seconds: (Option<f64>, Option<f64>),
) -> Result<(u32, Option<f64>), String> {
    match (mode, seconds) {
        (Mode::EqualSpp, _) => Ok((spp, None)),
        (Mode::EqualTime, (None, _)) => Err("the first method failed at this budget".to_owned()),
        (Mode::EqualTime, (Some(baseline), own)) => Ok((
            budgets
                .time_limited_spp
                .unwrap_or_else(|| equal_time_spp(spp, Some(baseline), own)),
            Some(baseline),
        )),
    }
}

/// Runs the whole manifest; returns what it measured (failed runs included).
pub fn run_bench(manifest_path: &Path, opts: &BenchOptions) -> Result<BenchResults, String> {
    let m = read_manifest(manifest_path)?;
    let base = manifest_path.parent().unwrap_or(Path::new("."));
    let cache = base.join(m.cache.clone().unwrap_or_else(|| PathBuf::from("cache")));
    let runs_dir = opts.out.join("runs");
    for d in [&opts.out, &runs_dir, &cache] {
        std::fs::create_dir_all(d).map_err(|e| format!("{}: cannot create: {e}", d.display()))?;
    }
    let per_scene = m.budgets.spp.len()
        * (m.methods.len()
            + if m.budgets.equal_time {
                m.methods.len() - 1
            } else {
                0
            });
    let total = per_scene * m.scenes.len();
    let seeds = m.run_seeds();
    let mut done = 0;
    let mut rows = Vec::new();
    for scene in &m.scenes {
        let scene_path = base.join(&scene.path);
        let reference = match reference_image(&m, scene, &scene_path, base, &cache, opts) {
            Ok(r) => Ok(r),
            Err(e) => {
                eprintln!("{}: reference failed: {e}", scene.name);
                Err(format!("no reference: {e}"))
            }
        };
        for &spp in &m.budgets.spp {
            // Per seed: the first method's seconds, the time limit of that seed's runs.
            let mut baseline_seconds: Vec<Option<f64>> = vec![None; seeds.len()];
            for (k, method) in m.methods.iter().enumerate() {
                let mut own_seconds: Vec<Option<f64>> = vec![None; seeds.len()];
                let modes: &[Mode] = if k > 0 && m.budgets.equal_time {
                    &[Mode::EqualSpp, Mode::EqualTime]
                } else {
                    &[Mode::EqualSpp]
                };
                for &mode in modes {
                    done += 1;
                    let mut runs = Vec::with_capacity(seeds.len());
                    for (i, &seed) in seeds.iter().enumerate() {
                        // One seed keeps the file names of before.
                        let tag = if seeds.len() > 1 {
                            format!("-seed{seed}")
                        } else {
                            String::new()
                        };
                        let out = runs_dir.join(format!(
                            "{}-{}-{spp}-{}{tag}.exr",
                            file_safe(&scene.name),
                            file_safe(&method.label),
                            mode.name()
                        ));
                        let outcome = reference.as_ref().map_err(Clone::clone).and_then(|r| {
                            let budget = (baseline_seconds[i], own_seconds[i]);
                            let (run_spp, limit) = run_budget(mode, spp, &m.budgets, budget)?;
                            measure(
                                opts,
                                &scene_path,
                                &out,
                                method,
                                run_spp,
                                seed,
                                m.threads,
                                limit,
                                r,
                            )
                        });
                        if k == 0 {
                            baseline_seconds[i] = outcome.as_ref().ok().map(|r| r.seconds);
                        }
                        if mode == Mode::EqualSpp {
                            own_seconds[i] = outcome.as_ref().ok().map(|r| r.seconds);
                        }
                        runs.push(outcome);
                    }
                    let outcome = Measured::mean_of(runs);
                    match &outcome {
                        Ok(r) => eprintln!(
                            "[{done}/{total}] {} {} {spp} spp {}: {:.3} s, {:.1} spp, MSE {:.4e}, relMSE {:.4e}",
                            scene.name,
                            method.label,
                            mode.name(),
                            r.seconds,
                            r.spp_reached,
                            r.metrics.mse,
                            r.metrics.relmse
                        ),
                        Err(e) => eprintln!(
                            "[{done}/{total}] {} {} {spp} spp {}: FAILED: {e}",
                            scene.name,
                            method.label,
                            mode.name()
                        ),
                    }
                    rows.push(Row {
                        scene: scene.name.clone(),
                        method: method.label.clone(),
                        mode,
                        spp,
                        seeds: seeds.len(),
                        outcome,
                    });
                }
            }
        }
    }
    let costs = measure_costs(&m, base, &runs_dir, opts);
    write_csv(&opts.out.join("results.csv"), &rows)?;
    if m.sampler_cost.is_some() {
        write_cost_csv(&opts.out.join("sampler_cost.csv"), &costs)?;
    }
    for scene in &m.scenes {
        let path = opts.out.join(format!("{}.png", file_safe(&scene.name)));
        if let Err(e) = plot_scene(&path, &scene.name, &m.methods, &rows) {
            eprintln!("{}: plot failed: {e}", path.display());
        }
    }
    let report = report_markdown(&m, manifest_path, opts, &rows, &costs);
    let path = opts.out.join("report.md");
    std::fs::write(&path, report).map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    Ok(BenchResults { rows, costs })
}

/// The manifest's sampler-cost measures: every scene, budget and method, `runs` processes
/// each with `--sampler-cost`; a measure with a failed run is a failed row.
fn measure_costs(m: &Manifest, base: &Path, runs_dir: &Path, opts: &BenchOptions) -> Vec<CostRow> {
    let Some(spec) = &m.sampler_cost else {
        return Vec::new();
    };
    let total = m.scenes.len() * spec.spp.len() * m.methods.len();
    let mut costs = Vec::with_capacity(total);
    for scene in &m.scenes {
        let scene_path = base.join(&scene.path);
        for &spp in &spec.spp {
            for method in &m.methods {
                let out = runs_dir.join(format!(
                    "{}-{}-{spp}-sampler-cost.exr",
                    file_safe(&scene.name),
                    file_safe(&method.label)
                ));
                let outcome = (0..spec.runs)
                    .map(|_| {
                        let r = run_render(
                            &opts.exe,
                            &scene_path,
                            &out,
                            method,
                            spp,
                            m.seed,
                            m.threads,
                            None,
                            true,
                        )?;
                        r.cost.ok_or_else(|| "no sampler cost".to_owned())
                    })
                    .collect::<Result<Vec<_>, String>>();
                let row = CostRow {
                    scene: scene.name.clone(),
                    method: method.label.clone(),
                    spp,
                    outcome,
                };
                let head = format!(
                    "[{}/{total}] {} {} {spp} spp sampler cost",
                    costs.len() + 1,
                    scene.name,
                    method.label
                );
                match row.summary() {
                    Ok(c) => eprintln!(
                        "{head}: {:.1}% (median of {}; {:.1} to {:.1}%)",
                        100.0 * c.share,
                        c.runs,
                        100.0 * c.least,
                        100.0 * c.largest
                    ),
                    Err(e) => eprintln!("{head}: FAILED: {e}"),
                }
                costs.push(row);
            }
        }
    }
    costs
}

/// One run, measured against the reference.
#[allow(clippy::too_many_arguments)]
fn measure(
    opts: &BenchOptions,
    scene: &Path,
    out: &Path,
    method: &Method,
    spp: u32,
    seed: u64,
    threads: Option<u32>,
    time_limit: Option<f64>,
    reference: &crate::image_io::RgbImage,
) -> Result<Measured, String> {
    let r = run_render(
        &opts.exe, scene, out, method, spp, seed, threads, time_limit, false,
    )?;
    let img = read_image(out, false).map_err(|e| format!("{}: {e}", out.display()))?;
    let metrics = compare(&img, reference)?;
    Ok(Measured {
        seconds: r.seconds,
        samples: r.samples,
        spp_reached: r.samples as f64 / r.pixels.max(1) as f64,
        metrics,
        peak_rss_mb: r.peak_rss_mb,
    })
}

/// The scene's reference image: read, or rendered (and cached) by the named method.
fn reference_image(
    m: &Manifest,
    scene: &SceneEntry,
    scene_path: &Path,
    base: &Path,
    cache: &Path,
    opts: &BenchOptions,
) -> Result<crate::image_io::RgbImage, String> {
    let spec = scene
        .reference
        .as_ref()
        .or(m.reference.as_ref())
        .ok_or("no reference")?;
    let path = match spec {
        Reference::Image { image } => base.join(image),
        Reference::Render { spp, .. } => {
            let meth = spec.method(&m.methods)?.ok_or("no method")?;
            let meth = &meth;
            let key = reference_key(scene_path, meth, *spp, m.seed)?;
            let path = cache.join(format!("{}-{key:016x}.exr", file_safe(&scene.name)));
            if !path.is_file() {
                eprintln!(
                    "{}: rendering the reference ({:?} {:?}, {spp} spp) -> {}",
                    scene.name,
                    meth.sampler,
                    meth.filter,
                    path.display()
                );
                let t = Instant::now();
                let tmp = path.with_extension("partial.exr");
                run_render(
                    &opts.exe, scene_path, &tmp, meth, *spp, m.seed, m.threads, None, false,
                )?;
                std::fs::rename(&tmp, &path).map_err(|e| format!("{}: {e}", path.display()))?;
                let _ = std::fs::remove_file(tmp.with_extension("json"));
                eprintln!(
                    "{}: reference took {:.1} s",
                    scene.name,
                    t.elapsed().as_secs_f64()
                );
            }
            path
        }
    };
    read_image(&path, false).map_err(|e| format!("{}: {e}", path.display()))
}

/// `name` with everything but letters, digits, `-` and `_` replaced by `_`.
fn file_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn available_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The CPU model and core count, from /proc/cpuinfo where there is one.
fn machine() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    format!(
        "{model}, {} hardware threads, {}",
        available_threads(),
        std::env::consts::OS
    )
}

/// The git commit of the working tree, if git can tell.
pub fn commit() -> String {
    Command::new("git")
        .args(["describe", "--always", "--dirty"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .unwrap_or_else(|| "unknown".to_owned())
}

/// `acr bench`: runs a manifest and writes its CSV, plots and report.
pub fn command(manifest: &Path, out: Option<PathBuf>) -> Result<(), String> {
    let out = out.unwrap_or_else(|| {
        let stem = manifest
            .file_stem()
            .map_or_else(|| "bench".to_owned(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("bench-out").join(stem)
    });
    let exe = std::env::current_exe().map_err(|e| format!("cannot find acr itself: {e}"))?;
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let opts = BenchOptions {
        exe,
        out: out.clone(),
        command,
        commit: commit(),
    };
    let results = run_bench(manifest, &opts)?;
    let rows = &results.rows;
    let failed = rows.iter().filter(|r| r.outcome.is_err()).count();
    let costs = &results.costs;
    let costs_failed = costs.iter().filter(|c| c.outcome.is_err()).count();
    let cost_note = if costs.is_empty() {
        String::new()
    } else {
        format!(
            ", {} sampler-cost measures, {costs_failed} failed",
            costs.len()
        )
    };
    eprintln!(
        "{} runs, {failed} failed{cost_note} -> {}",
        rows.len(),
        out.join("report.md").display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {

    #[test]
    fn equal_time_budgets_scale_with_the_method_s_own_speed() {
        // Twice as fast as the first method: twice the spp; half as fast: half.
        assert_eq!(equal_time_spp(8, Some(2.0), Some(1.0)), 16);
        assert_eq!(equal_time_spp(8, Some(1.0), Some(2.0)), 4);
        // Within 1 and 4x the budget.
        assert_eq!(equal_time_spp(8, Some(100.0), Some(1.0)), 32);
        assert_eq!(equal_time_spp(8, Some(0.01), Some(1.0)), 1);
        // No timing to go by: the cap, and the time limit decides.
        assert_eq!(equal_time_spp(8, Some(1.0), None), 32);
    }

    use super::*;

    #[test]
    fn a_compared_run_takes_its_budget_or_the_first_method_s_time() {
        let mut budgets = Budgets {
            spp: vec![8],
            equal_time: true,
            time_limited_spp: None,
        };
        let run = |mode, seconds, b: &Budgets| run_budget(mode, 8, b, seconds);
        assert_eq!(
            run(Mode::EqualSpp, (Some(1.0), None), &budgets),
            Ok((8, None))
        );
        // Twice as slow as the first method: half the spp, in its time.
        let half = (Some(1.0), Some(2.0));
        assert_eq!(run(Mode::EqualTime, half, &budgets), Ok((4, Some(1.0))));
        assert!(run(Mode::EqualTime, (None, Some(2.0)), &budgets)
            .is_err_and(|e| e.contains("first method failed")));
        budgets.time_limited_spp = Some(64);
        assert_eq!(run(Mode::EqualTime, half, &budgets), Ok((64, Some(1.0))));
    }

    #[test]
    fn manifest_errors_are_located() {
        let dir = std::env::temp_dir().join(format!("acr-bench-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("m.toml");
        std::fs::write(&p, "[budgets]\nspp = [1]\nbogus = 3\n").unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("m.toml:3:1:"), "{e}");
        std::fs::write(
            &p,
            "[budgets]\nspp = [1]\n[[scene]]\nname = \"a\"\npath = \"a.pbrt\"\n\
             reference = { method = \"nope\", spp = 4 }\n[[method]]\nlabel = \"x\"\n",
        )
        .unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("names method \"nope\""), "{e}");
        for (section, message) in [
            ("spp = [8]\nruns = 0", "sampler_cost runs 0 is out of range"),
            ("spp = [0]", "sampler_cost budget 0 spp is out of range"),
        ] {
            std::fs::write(
                &p,
                format!(
                    "[budgets]\nspp = [1]\n[sampler_cost]\n{section}\n[reference]\n\
                     sampler = \"sobol\"\nspp = 4\n[[scene]]\nname = \"a\"\npath = \"a.pbrt\"\n\
                     [[method]]\nlabel = \"x\"\n"
                ),
            )
            .unwrap();
            let e = read_manifest(&p).unwrap_err();
            assert!(e.contains(message), "{e}");
        }
        // The time-limited runs' spp and a method's time plan: read, and checked.
        let with = |budgets: &str, method: &str| {
            format!(
                "[budgets]\nspp = [1]\n{budgets}\n[reference]\nsampler = \"sobol\"\nspp = 4\n\
                 [[scene]]\nname = \"a\"\npath = \"a.pbrt\"\n[[method]]\nlabel = \"x\"\n{method}\n"
            )
        };
        std::fs::write(&p, with("time_limited_spp = 64", "time_plan = \"budget\"")).unwrap();
        let m = read_manifest(&p).unwrap();
        assert_eq!(m.budgets.time_limited_spp, Some(64));
        assert_eq!(
            m.methods[0].time_plan,
            Some(crate::cli::render::TimePlan::Budget)
        );
        // Seeds to average over: listed once each.
        for seeds in ["seeds = []", "seeds = [1, 2, 1]"] {
            std::fs::write(&p, format!("{seeds}\n{}", with("", ""))).unwrap();
            let e = read_manifest(&p).unwrap_err();
            assert!(e.contains("seeds must list 1 to 64 different seeds"), "{e}");
        }
        std::fs::write(&p, format!("seeds = [4, 2]\n{}", with("", ""))).unwrap();
        assert_eq!(read_manifest(&p).unwrap().run_seeds(), [4, 2]);
        std::fs::write(&p, format!("seed = 5\n{}", with("", ""))).unwrap();
        assert_eq!(read_manifest(&p).unwrap().run_seeds(), [5]);
        std::fs::write(&p, with("time_limited_spp = 0", "")).unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("time_limited_spp is out of range"), "{e}");
        std::fs::write(&p, with("", "time_plan = \"soon\"")).unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("m.toml:12:13:") && e.contains("fit"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn fnv_is_stable() {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        fnv1a(&mut h, b"a");
        assert_eq!(h, 0xaf63_dc4c_8601_ec8c);
    }
}
