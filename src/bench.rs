//! `acr bench MANIFEST.toml`: time against error. Renders every scene of a manifest with every
//! method at every budget (and, in equal-time mode, with each method given the first method's
//! time), compares each image with the scene's reference, and writes a CSV, a log-log plot of
//! error against time per scene and a Markdown report. Each render is a separate `acr render`
//! process, so that its time and peak memory are its own and a crash is only a failed row.

use crate::image_io::read_image;
use crate::metrics::{compare, Metrics};
use crate::stats::median;
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The manifest: scenes, methods, budgets and references.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// A title for the report.
    #[serde(default)]
    pub title: Option<String>,
    /// Seed of every run.
    #[serde(default)]
    pub seed: u64,
    /// Worker threads per run (default: every core).
    #[serde(default)]
    pub threads: Option<u32>,
    /// Folder of cached reference renders, relative to the manifest (default `cache`).
    #[serde(default)]
    pub cache: Option<PathBuf>,
    /// The budgets.
    pub budgets: Budgets,
    /// The reference of scenes that name none.
    #[serde(default)]
    pub reference: Option<Reference>,
    /// The scenes.
    #[serde(rename = "scene")]
    pub scenes: Vec<SceneEntry>,
    /// The methods; the first is the baseline of every ratio.
    #[serde(rename = "method")]
    pub methods: Vec<Method>,
    /// Runs that measure the sampler's share of wall time, if any.
    #[serde(default)]
    pub sampler_cost: Option<SamplerCostRuns>,
}

/// The sampler's share of wall time (`acr render --sampler-cost`) of every scene and method,
/// at some budgets: each run is its own process, and the report gives the median over them,
/// since one process's share moves with the machine's load.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SamplerCostRuns {
    /// Samples per pixel to measure at.
    pub spp: Vec<u32>,
    /// Processes per scene, method and budget.
    #[serde(default = "five")]
    pub runs: u32,
}

fn five() -> u32 {
    5
}

/// Most processes per scene, method and budget in a sampler-cost measure.
const MAX_COST_RUNS: u32 = 100;

/// Samples per pixel to run at, and whether to run equal-time too.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Budgets {
    /// Samples per pixel (equal-spp runs).
    pub spp: Vec<u32>,
    /// Also run every method but the first with `--time-limit` set to the first method's
    /// render time at each budget.
    #[serde(default = "yes")]
    pub equal_time: bool,
}

fn yes() -> bool {
    true
}

/// One scene of the manifest.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneEntry {
    /// Its label in the report.
    pub name: String,
    /// The .pbrt file, relative to the manifest.
    pub path: PathBuf,
    /// Its reference (else the manifest's).
    #[serde(default)]
    pub reference: Option<Reference>,
}

/// A scene's reference image: a file, or a render by one of the methods at a high budget.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged, deny_unknown_fields)]
pub enum Reference {
    /// A given image (EXR, PFM...), relative to the manifest.
    Image {
        /// The file.
        image: PathBuf,
    },
    /// Rendered at `spp` by the manifest's method labelled `method`, or by the sampler,
    /// filter, integrator and settings given here; cached.
    Render {
        /// A method's label.
        #[serde(default)]
        method: Option<String>,
        /// `--sampler`, when no method is named.
        #[serde(default)]
        sampler: Option<String>,
        /// `--filter`, when no method is named.
        #[serde(default)]
        filter: Option<String>,
        /// `--integrator`, when no method is named.
        #[serde(default)]
        integrator: Option<String>,
        /// `--set` settings, when no method is named.
        #[serde(default)]
        set: Vec<String>,
        /// Samples per pixel.
        spp: u32,
    },
}

impl Reference {
    /// The method a rendered reference uses.
    fn method(&self, methods: &[Method]) -> Result<Option<Method>, String> {
        match self {
            Reference::Image { .. } => Ok(None),
            Reference::Render {
                method: Some(label),
                ..
            } => methods
                .iter()
                .find(|m| &m.label == label)
                .cloned()
                .map(Some)
                .ok_or_else(|| format!("names method \"{label}\", which is not listed")),
            Reference::Render {
                method: None,
                sampler,
                filter,
                integrator,
                set,
                ..
            } => Ok(Some(Method {
                label: "reference".to_owned(),
                sampler: sampler.clone(),
                filter: filter.clone(),
                integrator: integrator.clone(),
                set: set.clone(),
            })),
        }
    }
}

/// A sampler + filter (+ integrator) with parameters, under a label.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Method {
    /// Its name in the report (`stratified+box`).
    pub label: String,
    /// `--sampler` (default: the scene's).
    #[serde(default)]
    pub sampler: Option<String>,
    /// `--filter` (default: the scene's).
    #[serde(default)]
    pub filter: Option<String>,
    /// `--integrator` (default: the scene's).
    #[serde(default)]
    pub integrator: Option<String>,
    /// `--set KIND.PARAM=VALUE` settings.
    #[serde(default)]
    pub set: Vec<String>,
}

/// How a run was budgeted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// At a number of samples per pixel.
    EqualSpp,
    /// At the first method's time for that number of samples per pixel.
    EqualTime,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::EqualSpp => "equal-spp",
            Mode::EqualTime => "equal-time",
        }
    }
}

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
    /// What the run measured, or why it failed.
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

/// Reads and checks a manifest.
pub fn read_manifest(path: &Path) -> Result<Manifest, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let m: Manifest = toml::from_str(&text).map_err(|e| {
        let (line, col) = e.span().map_or((1, 1), |s| line_col(&text, s.start));
        format!("{}:{line}:{col}: {}", path.display(), e.message())
    })?;
    if m.methods.is_empty() || m.scenes.is_empty() || m.budgets.spp.is_empty() {
        return Err(format!(
            "{}: a manifest needs at least one [[scene]], one [[method]] and one budget",
            path.display()
        ));
    }
    if let Some(&bad) = m
        .budgets
        .spp
        .iter()
        .find(|&&s| s == 0 || s > crate::render::MAX_SPP)
    {
        return Err(format!(
            "{}: budget {bad} spp is out of range",
            path.display()
        ));
    }
    if let Some(c) = &m.sampler_cost {
        if let Some(&bad) = c
            .spp
            .iter()
            .find(|&&s| s == 0 || s > crate::render::MAX_SPP)
        {
            return Err(format!(
                "{}: sampler_cost budget {bad} spp is out of range",
                path.display()
            ));
        }
        if c.runs == 0 || c.runs > MAX_COST_RUNS {
            return Err(format!(
                "{}: sampler_cost runs {} is out of range (1 to {MAX_COST_RUNS})",
                path.display(),
                c.runs
            ));
        }
    }
    let mut labels = std::collections::HashSet::new();
    for meth in &m.methods {
        if !labels.insert(meth.label.as_str()) {
            return Err(format!(
                "{}: method \"{}\" is listed twice",
                path.display(),
                meth.label
            ));
        }
    }
    for s in &m.scenes {
        let Some(r) = s.reference.as_ref().or(m.reference.as_ref()) else {
            return Err(format!(
                "{}: scene \"{}\" has no reference (give it one, or a top-level one)",
                path.display(),
                s.name
            ));
        };
        r.method(&m.methods).map_err(|e| {
            format!(
                "{}: the reference of scene \"{}\" {e}",
                path.display(),
                s.name
            )
        })?;
    }
    Ok(m)
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, col)
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
            let mut baseline_seconds = None;
            for (k, method) in m.methods.iter().enumerate() {
                let mut own_seconds = None;
                let modes: &[Mode] = if k > 0 && m.budgets.equal_time {
                    &[Mode::EqualSpp, Mode::EqualTime]
                } else {
                    &[Mode::EqualSpp]
                };
                for &mode in modes {
                    done += 1;
                    let out = runs_dir.join(format!(
                        "{}-{}-{spp}-{}.exr",
                        file_safe(&scene.name),
                        file_safe(&method.label),
                        mode.name()
                    ));
                    let outcome = match (&reference, mode, baseline_seconds) {
                        (Err(e), _, _) => Err(e.clone()),
                        (Ok(_), Mode::EqualTime, None) => {
                            Err("the first method failed at this budget".to_owned())
                        }
                        (Ok(reference), _, _) => {
                            let (run_spp, limit) = match mode {
                                Mode::EqualSpp => (spp, None),
                                Mode::EqualTime => (
                                    equal_time_spp(spp, baseline_seconds, own_seconds),
                                    baseline_seconds,
                                ),
                            };
                            measure(
                                opts,
                                &scene_path,
                                &out,
                                method,
                                run_spp,
                                m.seed,
                                m.threads,
                                limit,
                                reference,
                            )
                        }
                    };
                    if k == 0 {
                        baseline_seconds = outcome.as_ref().ok().map(|r| r.seconds);
                    }
                    if mode == Mode::EqualSpp {
                        own_seconds = outcome.as_ref().ok().map(|r| r.seconds);
                    }
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

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// The image's mean over the reference's (1 when the reference is black): a filter or sampler
/// that moves the mean shows here whatever its MSE.
fn mean_ratio(m: &crate::metrics::Metrics) -> f64 {
    if m.reference_mean > 0.0 {
        m.mean / m.reference_mean
    } else {
        1.0
    }
}

/// The CSV: one row per run, failed runs with their reason.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<(), String> {
    let mut s = String::from(
        "scene,method,mode,spp,seconds,samples,spp_reached,mse,relmse,psnr,peak_rss_mb,status,\
         mean_ratio\n",
    );
    for r in rows {
        let head = format!(
            "{},{},{},{}",
            csv_field(&r.scene),
            csv_field(&r.method),
            r.mode.name(),
            r.spp
        );
        match &r.outcome {
            Ok(m) => {
                let _ = writeln!(
                    s,
                    "{head},{:.6},{},{:.3},{:.6e},{:.6e},{:.4},{:.1},ok,{:.5}",
                    m.seconds,
                    m.samples,
                    m.spp_reached,
                    m.metrics.mse,
                    m.metrics.relmse,
                    m.metrics.psnr,
                    m.peak_rss_mb,
                    mean_ratio(&m.metrics)
                );
            }
            Err(e) => {
                let _ = writeln!(s, "{head},,,,,,,,{},", csv_field(&format!("failed: {e}")));
            }
        }
    }
    std::fs::write(path, s).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// The sampler-cost CSV: one row per scene, method and budget, with the median share over
/// its runs, the least and the largest, and the median seconds of a render and of a replay.
pub fn write_cost_csv(path: &Path, costs: &[CostRow]) -> Result<(), String> {
    let mut s = String::from(
        "scene,method,spp,runs,sampler_share,share_min,share_max,rerender_seconds,replay_seconds,status\n",
    );
    for c in costs {
        let head = format!("{},{},{}", csv_field(&c.scene), csv_field(&c.method), c.spp);
        match c.summary() {
            Ok(c) => {
                let _ = writeln!(
                    s,
                    "{head},{},{:.4},{:.4},{:.4},{:.6},{:.6},ok",
                    c.runs, c.share, c.least, c.largest, c.rerender, c.replay
                );
            }
            Err(e) => {
                let _ = writeln!(s, "{head},,,,,,,{}", csv_field(&format!("failed: {e}")));
            }
        }
    }
    std::fs::write(path, s).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// The equal-spp and equal-time result of `method` on `scene` at `spp`.
fn find<'a>(rows: &'a [Row], scene: &str, method: &str, spp: u32, mode: Mode) -> Option<&'a Row> {
    rows.iter()
        .find(|r| r.scene == scene && r.method == method && r.spp == spp && r.mode == mode)
}

/// The Markdown report: the setting, then per scene a table of equal-spp and equal-time errors
/// with their ratios to the first method (below 1: better than the first method).
pub fn report_markdown(
    m: &Manifest,
    manifest: &Path,
    opts: &BenchOptions,
    rows: &[Row],
    costs: &[CostRow],
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# {}\n", m.title.as_deref().unwrap_or("acr bench"));
    let _ = writeln!(s, "- manifest: `{}`", manifest.display());
    let _ = writeln!(s, "- command: `{}`", opts.command);
    let _ = writeln!(s, "- machine: {}", machine());
    let _ = writeln!(
        s,
        "- threads: {}",
        m.threads.map_or_else(
            || format!("all ({})", available_threads()),
            |t| t.to_string()
        )
    );
    let _ = writeln!(s, "- commit: {}", opts.commit);
    let _ = writeln!(s, "- seed: {}", m.seed);
    let _ = writeln!(
        s,
        "- seconds: render + reconstruction of each run (its stats file); ratios are against `{}`, the first method (below 1 is better); equal time: each method given the spp its own equal-spp run says fits in the first method's seconds at that budget (at most 4x), and those seconds as `--time-limit` (it stops at the end of the pass under way, so its time can overshoot by up to one pass)\n",
        m.methods[0].label
    );
    let failed = rows.iter().filter(|r| r.outcome.is_err()).count();
    if failed > 0 {
        let _ = writeln!(s, "**{failed} runs failed**; see `results.csv`.\n");
    }
    for scene in &m.scenes {
        let _ = writeln!(s, "## {}\n", scene.name);
        let _ = writeln!(s, "![{0}]({0}.png)\n", file_safe(&scene.name));
        let _ = writeln!(
            s,
            "| spp | method | seconds | MSE | relMSE | MSE ratio | relMSE ratio | mean / reference | equal-time seconds | equal-time spp | equal-time MSE | MSE ratio | relMSE ratio |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for &spp in &m.budgets.spp {
            let base = find(rows, &scene.name, &m.methods[0].label, spp, Mode::EqualSpp)
                .and_then(|r| r.outcome.as_ref().ok());
            for meth in &m.methods {
                let eq = find(rows, &scene.name, &meth.label, spp, Mode::EqualSpp);
                let et = find(rows, &scene.name, &meth.label, spp, Mode::EqualTime);
                let mut line = format!("| {spp} | {} ", meth.label);
                match eq.map(|r| &r.outcome) {
                    Some(Ok(r)) => {
                        let _ = write!(
                            line,
                            "| {:.3} | {:.3e} | {:.3e} | {} | {} | {:.4} ",
                            r.seconds,
                            r.metrics.mse,
                            r.metrics.relmse,
                            ratio(r.metrics.mse, base.map(|b| b.metrics.mse)),
                            ratio(r.metrics.relmse, base.map(|b| b.metrics.relmse)),
                            mean_ratio(&r.metrics)
                        );
                    }
                    Some(Err(_)) => line.push_str("| failed | | | | | "),
                    None => line.push_str("| | | | | | "),
                }
                match et.map(|r| &r.outcome) {
                    Some(Ok(r)) => {
                        let _ = write!(
                            line,
                            "| {:.3} | {:.1} | {:.3e} | {} | {} |",
                            r.seconds,
                            r.spp_reached,
                            r.metrics.mse,
                            ratio(r.metrics.mse, base.map(|b| b.metrics.mse)),
                            ratio(r.metrics.relmse, base.map(|b| b.metrics.relmse))
                        );
                    }
                    Some(Err(_)) => line.push_str("| failed | | | | |"),
                    None => line.push_str("| | | | | |"),
                }
                let _ = writeln!(s, "{line}");
            }
        }
        s.push('\n');
    }
    if let Some(spec) = &m.sampler_cost {
        let _ = writeln!(s, "## The sampler's share of wall time\n");
        let _ = writeln!(
            s,
            "`acr render --sampler-cost`, {} processes each (`sampler_cost.csv`): a render by a fresh sampler against a replay of its points, share = (render - replay) / render; the median over the processes, then the least and the largest.\n",
            spec.runs
        );
        let _ = writeln!(
            s,
            "| scene | spp | method | share | least | largest | render s | replay s |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
        for c in costs {
            let figures = match c.summary() {
                Ok(c) => format!(
                    "{:.1}% | {:.1}% | {:.1}% | {:.3} | {:.3}",
                    100.0 * c.share,
                    100.0 * c.least,
                    100.0 * c.largest,
                    c.rerender,
                    c.replay
                ),
                Err(_) => "failed | | | |".to_owned(),
            };
            let _ = writeln!(s, "| {} | {} | {} | {figures} |", c.scene, c.spp, c.method);
        }
        s.push('\n');
    }
    s
}

fn ratio(x: f64, base: Option<f64>) -> String {
    match base {
        Some(b) if b > 0.0 => format!("{:.3}", x / b),
        _ => "-".to_owned(),
    }
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

/// Axis ticks at 1, 2 and 5 times the powers of ten within `lo..hi` (plotters' log axes label
/// only powers of ten, which a narrow range may not contain).
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut v = Vec::new();
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi {
        for m in [1.0, 2.0, 5.0] {
            let t = decade * m;
            if t >= lo && t <= hi {
                v.push(t);
            }
        }
        decade *= 10.0;
    }
    v
}

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Registers the embedded font with plotters once (its ab_glyph text needs one; no system
/// font library is used).
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ =
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT);
    });
}

/// The log-log plot of MSE against seconds for one scene: a line per method through its
/// equal-spp runs, and its equal-time runs as hollow circles.
pub fn plot_scene(
    path: &Path,
    scene: &str,
    methods: &[Method],
    rows: &[Row],
) -> Result<(), String> {
    use plotters::prelude::*;
    register_font();
    let ok: Vec<(&Row, &Measured)> = rows
        .iter()
        .filter(|r| r.scene == scene)
        .filter_map(|r| r.outcome.as_ref().ok().map(|m| (r, m)))
        .filter(|(_, m)| m.seconds > 0.0 && m.metrics.mse > 0.0)
        .collect();
    if ok.is_empty() {
        return Err("no successful run to plot".to_owned());
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (_, m) in &ok {
        x0 = x0.min(m.seconds);
        x1 = x1.max(m.seconds);
        y0 = y0.min(m.metrics.mse);
        y1 = y1.max(m.metrics.mse);
    }
    let pad = |lo: f64, hi: f64| (lo / 1.3, (hi * 1.3).max(lo * 1.5));
    let ((x0, x1), (y0, y1)) = (pad(x0, x1), pad(y0, y1));
    let root = BitMapBackend::new(path, (720, 480)).into_drawing_area();
    let e = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{scene}: MSE against time (dots: equal spp, rings: equal time)"),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x0..x1).log_scale().with_key_points(ticks(x0, x1)),
            (y0..y1).log_scale().with_key_points(ticks(y0, y1)),
        )
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_labels(8)
        .y_labels(8)
        .light_line_style(WHITE)
        .x_desc("seconds (render + reconstruction)")
        .y_desc("MSE")
        .y_label_formatter(&|v| format!("{v:.1e}"))
        .x_label_formatter(&|v| format!("{v:.2}"))
        .draw()
        .map_err(|x| e(&x))?;
    for (k, meth) in methods.iter().enumerate() {
        let colour = Palette99::pick(k).to_rgba();
        let mut line: Vec<(f64, f64)> = ok
            .iter()
            .filter(|(r, _)| r.method == meth.label && r.mode == Mode::EqualSpp)
            .map(|(_, m)| (m.seconds, m.metrics.mse))
            .collect();
        line.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(meth.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(line.iter().map(|&p| Circle::new(p, 3, colour.filled())))
            .map_err(|x| e(&x))?;
        let timed: Vec<(f64, f64)> = ok
            .iter()
            .filter(|(r, _)| r.method == meth.label && r.mode == Mode::EqualTime)
            .map(|(_, m)| (m.seconds, m.metrics.mse))
            .collect();
        chart
            .draw_series(
                timed
                    .iter()
                    .map(|&p| Circle::new(p, 6, colour.stroke_width(1))),
            )
            .map_err(|x| e(&x))?;
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
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
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn fnv_is_stable() {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        fnv1a(&mut h, b"a");
        assert_eq!(h, 0xaf63_dc4c_8601_ec8c);
    }
}
