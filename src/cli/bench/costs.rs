//! The manifest's sampler-cost measures: `acr render --sampler-cost` processes, the sampler's
//! share of each render's wall time.

use super::child::RenderRun;
use super::{file_safe, BenchOptions, CostRow, Manifest};
use std::path::Path;

/// The manifest's sampler-cost measures: every scene, budget and method, `runs` processes
/// each with `--sampler-cost`; a measure with a failed run is a failed row.
pub(super) fn measure_costs(
    m: &Manifest,
    base: &Path,
    runs_dir: &Path,
    opts: &BenchOptions,
) -> Vec<CostRow> {
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
                let run = RenderRun {
                    exe: &opts.exe,
                    scene: &scene_path,
                    method,
                    seed: m.seed,
                    threads: m.threads,
                    pixelbounds: scene.pixelbounds,
                };
                let outcome = (0..spec.runs)
                    .map(|_| {
                        let r = run.run(&out, spp, None, true)?;
                        r.cost.ok_or_else(|| "no sampler cost".to_owned())
                    })
                    .collect::<Result<Vec<_>, String>>();
                let row = CostRow {
                    scene: scene.name.clone(),
                    method: method.label.clone(),
                    spp,
                    outcome,
                };
                print_cost(&row, costs.len() + 1, total);
                costs.push(row);
            }
        }
    }
    costs
}

/// The progress line of the `done`th of `total` measures.
fn print_cost(row: &CostRow, done: usize, total: usize) {
    let head = format!(
        "[{done}/{total}] {} {} {} spp sampler cost",
        row.scene, row.method, row.spp
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
}
