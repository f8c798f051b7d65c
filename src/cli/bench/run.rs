//! The bench's run loop: every scene, budget and method, at equal spp and, after the first
//! method, at equal time, each over the manifest's seeds.

use super::budget::{run_budget, Spent};
use super::child::{scored_path, RenderRun};
use super::external::skip_reason;
use super::gallery::write_gallery;
use super::reference::reference_image;
use super::report::write_results;
use super::{
    file_safe, measure_costs, read_manifest, BenchOptions, BenchResults, Manifest, Measured,
    Method, Mode, Row, SceneEntry,
};
use crate::image_io::RgbImage;
use std::path::{Path, PathBuf};

/// Runs the whole manifest; returns what it measured (failed runs included).
pub fn run_bench(manifest_path: &Path, opts: &BenchOptions) -> Result<BenchResults, String> {
    let m = read_manifest(manifest_path)?;
    let base = manifest_path.parent().unwrap_or(Path::new("."));
    let cache = base.join(m.cache.clone().unwrap_or_else(|| PathBuf::from("cache")));
    let runs_dir = opts.out.join("runs");
    for d in [&opts.out, &runs_dir, &cache] {
        std::fs::create_dir_all(d).map_err(|e| format!("{}: cannot create: {e}", d.display()))?;
    }
    let mut bench = Bench::new(&m, base, &runs_dir, opts);
    let mut rows = Vec::new();
    for scene in &m.scenes {
        bench.scene(scene, &cache, &mut rows);
    }
    let costs = measure_costs(&m, base, &runs_dir, opts);
    write_results(&m, manifest_path, opts, &rows, &costs)?;
    Ok(BenchResults { rows, costs })
}

/// A bench under way: what every run shares, and how many rows are done.
struct Bench<'a> {
    /// The manifest.
    m: &'a Manifest,
    /// The manifest's folder, which its paths are relative to.
    base: &'a Path,
    /// Where the runs' images and stats go.
    runs_dir: &'a Path,
    /// The executable and the output folder.
    opts: &'a BenchOptions,
    /// The seeds each row averages over.
    seeds: Vec<u64>,
    /// Rows in all, for the progress lines.
    total: usize,
    /// Rows done so far.
    done: usize,
    /// Per method, why its rows are skipped on this machine (an external program absent).
    skipped: Vec<Option<String>>,
}

/// One method on one scene at one budget: what its rows share.
struct Cell<'a> {
    /// The scene.
    scene: &'a SceneEntry,
    /// Its file.
    scene_path: &'a Path,
    /// The method.
    method: &'a Method,
    /// The budget.
    spp: u32,
    /// Whether it is the first method, whose times are the equal-time limits.
    first: bool,
}

/// Per seed, the seconds of the runs that budget an equal-time run.
struct Times {
    /// The first method's, at this budget.
    baseline: Vec<Option<f64>>,
    /// What the method's own equal-spp run spent.
    own: Vec<Option<Spent>>,
}

impl<'a> Bench<'a> {
    /// A bench of `m`, nothing done yet.
    fn new(m: &'a Manifest, base: &'a Path, runs_dir: &'a Path, opts: &'a BenchOptions) -> Self {
        let per_scene = m.budgets.spp.len()
            * (m.methods.len()
                + if m.budgets.equal_time {
                    m.methods.len() - 1
                } else {
                    0
                });
        let skipped: Vec<Option<String>> = m
            .methods
            .iter()
            .map(|meth| skip_reason(meth, base))
            .collect();
        for (meth, why) in m.methods.iter().zip(&skipped) {
            if let Some(why) = why {
                eprintln!(
                    "warning: method \"{}\" {why}: its rows are skipped",
                    meth.label
                );
            }
        }
        Bench {
            m,
            base,
            runs_dir,
            opts,
            seeds: m.run_seeds(),
            total: per_scene * m.scenes.len(),
            done: 0,
            skipped,
        }
    }

    /// Every row of `scene`, added to `rows`: each budget and method, at equal spp and, after
    /// the first method, at equal time.
    fn scene(&mut self, scene: &SceneEntry, cache: &Path, rows: &mut Vec<Row>) {
        let m = self.m;
        let scene_path = self.base.join(&scene.path);
        let reference = match reference_image(m, scene, &scene_path, self.base, cache, self.opts) {
            Ok(r) => Ok(r),
            Err(e) => {
                eprintln!("{}: reference failed: {e}", scene.name);
                Err(format!("no reference: {e}"))
            }
        };
        for &spp in &m.budgets.spp {
            let mut times = Times {
                baseline: vec![None; self.seeds.len()],
                own: Vec::new(),
            };
            for (k, method) in m.methods.iter().enumerate() {
                times.own = vec![None; self.seeds.len()];
                if let Some(why) = &self.skipped[k] {
                    let skip = |mode| Row {
                        scene: scene.name.clone(),
                        method: method.label.clone(),
                        mode,
                        spp,
                        seeds: self.seeds.len(),
                        outcome: Err(why.clone()),
                    };
                    rows.push(skip(Mode::EqualSpp));
                    if k > 0 && m.budgets.equal_time {
                        rows.push(skip(Mode::EqualTime));
                    }
                    self.done += if k > 0 && m.budgets.equal_time { 2 } else { 1 };
                    continue;
                }
                let modes: &[Mode] = if k > 0 && m.budgets.equal_time {
                    &[Mode::EqualSpp, Mode::EqualTime]
                } else {
                    &[Mode::EqualSpp]
                };
                let cell = Cell {
                    scene,
                    scene_path: &scene_path,
                    method,
                    spp,
                    first: k == 0,
                };
                for &mode in modes {
                    rows.push(self.row(&cell, mode, &reference, &mut times));
                }
            }
        }
        if let Ok(reference) = &reference {
            self.gallery(scene, reference);
        }
    }

    /// The scene's images side by side, at the smallest budget, for each mode run.
    fn gallery(&self, scene: &SceneEntry, reference: &RgbImage) {
        let m = self.m;
        let Some(&spp) = m.budgets.spp.iter().min() else {
            return;
        };
        let modes: &[Mode] = if m.budgets.equal_time && m.methods.len() > 1 {
            &[Mode::EqualSpp, Mode::EqualTime]
        } else {
            &[Mode::EqualSpp]
        };
        for &mode in modes {
            let images: Vec<(String, PathBuf)> = m
                .methods
                .iter()
                .enumerate()
                .filter(|(k, _)| self.skipped[*k].is_none())
                .map(|(k, method)| {
                    // The first method's equal-spp run is its equal-time run too.
                    let mode = if k == 0 { Mode::EqualSpp } else { mode };
                    let run = self.run_path((scene, method, spp), mode, self.seeds[0]);
                    (method.label.clone(), scored_path(method, &run))
                })
                .collect();
            let name = format!("{}-images-{}-{spp}", file_safe(&scene.name), mode.name());
            let title = format!("{} at {spp} spp, {}", scene.name, mode.name());
            if let Err(e) = write_gallery(&self.opts.out, &name, &title, reference, &images) {
                eprintln!("{}: images side by side failed: {e}", scene.name);
            }
        }
    }

    /// The row of `cell` in `mode`: a run per seed, their means; records their seconds in
    /// `times` for the runs after it.
    fn row(
        &mut self,
        cell: &Cell,
        mode: Mode,
        reference: &Result<RgbImage, String>,
        times: &mut Times,
    ) -> Row {
        self.done += 1;
        let mut runs = Vec::with_capacity(self.seeds.len());
        for (i, &seed) in self.seeds.iter().enumerate() {
            let out = self.run_path((cell.scene, cell.method, cell.spp), mode, seed);
            let outcome = reference.as_ref().map_err(Clone::clone).and_then(|r| {
                let (run_spp, limit) = run_budget(
                    mode,
                    cell.spp,
                    &self.m.budgets,
                    times.baseline[i],
                    times.own[i],
                    cell.method.is_external(),
                )?;
                let run = RenderRun {
                    exe: &self.opts.exe,
                    scene: cell.scene_path,
                    method: cell.method,
                    seed,
                    threads: self.m.threads,
                    pixelbounds: cell.scene.pixelbounds,
                };
                run.measure(&out, run_spp, limit, r, self.base)
            });
            if cell.first {
                times.baseline[i] = outcome.as_ref().ok().map(|r| r.seconds);
            }
            if mode == Mode::EqualSpp {
                times.own[i] = outcome.as_ref().ok().map(|r| {
                    // What runs after the render's time limit: the reconstruction and a
                    // command (docs/BENCHMARKS.md, "Equal time").
                    let after = r.command_seconds.unwrap_or(0.0) + r.reconstruct_seconds;
                    Spent {
                        render: r.seconds - after,
                        after_limit: after,
                    }
                });
            }
            runs.push(outcome);
        }
        let outcome = Measured::mean_of(runs);
        self.print_progress(cell, mode, &outcome);
        Row {
            scene: cell.scene.name.clone(),
            method: cell.method.label.clone(),
            mode,
            spp: cell.spp,
            seeds: self.seeds.len(),
            outcome,
        }
    }

    /// The image of the run of a scene, method and budget in `mode` with `seed`.
    fn run_path(
        &self,
        (scene, method, spp): (&SceneEntry, &Method, u32),
        mode: Mode,
        seed: u64,
    ) -> PathBuf {
        // One seed keeps the file names of before.
        let tag = if self.seeds.len() > 1 {
            format!("-seed{seed}")
        } else {
            String::new()
        };
        self.runs_dir.join(format!(
            "{}-{}-{}-{}{tag}.exr",
            file_safe(&scene.name),
            file_safe(&method.label),
            spp,
            mode.name()
        ))
    }

    /// The progress line of a row done.
    fn print_progress(&self, cell: &Cell, mode: Mode, outcome: &Result<Measured, String>) {
        let (done, total, spp) = (self.done, self.total, cell.spp);
        let (scene, method) = (&cell.scene.name, &cell.method.label);
        match outcome {
            Ok(r) => eprintln!(
                "[{done}/{total}] {scene} {method} {spp} spp {}: {:.3} s, {:.1} spp, MSE {:.4e}, relMSE {:.4e}",
                mode.name(),
                r.seconds,
                r.spp_reached,
                r.metrics.mse,
                r.metrics.relmse
            ),
            Err(e) => eprintln!(
                "[{done}/{total}] {scene} {method} {spp} spp {}: FAILED: {e}",
                mode.name()
            ),
        }
    }
}
