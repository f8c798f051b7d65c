//! `acr bench MANIFEST.toml`: time against error. Renders every scene of a manifest with every
//! method at every budget (and, in equal-time mode, with each method given the first method's
//! time), compares each image with the scene's reference, and writes a CSV, a log-log plot of
//! error against time per scene and a Markdown report. Each render is a separate `acr render`
//! process, so that its time and peak memory are its own and a crash is only a failed row.
//!
//! One file per concept: the manifest (`manifest.rs`), the run loop (`run.rs`), the budgets
//! of compared runs (`budget.rs`), one render as a child process (`child.rs`), the references
//! (`reference.rs`), the sampler-cost measures (`costs.rs`), an external command as a method
//! (`external.rs`), what is measured (`results.rs`), what is written (`report.rs`) and the
//! images side by side (`gallery.rs`).

use std::path::{Path, PathBuf};
use std::process::Command;

mod budget;
mod child;
mod costs;
mod external;
mod gallery;
mod manifest;
mod reference;
mod report;
mod results;
mod run;

use costs::measure_costs;
pub use manifest::*;
pub use report::*;
pub use results::*;
pub use run::run_bench;

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
    let skipped = rows
        .iter()
        .filter(|r| r.outcome.as_ref().is_err_and(|e| e.starts_with("skipped:")))
        .count();
    let failed = rows.iter().filter(|r| r.outcome.is_err()).count() - skipped;
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
        "{} runs, {failed} failed, {skipped} skipped{cost_note} -> {}",
        rows.len(),
        out.join("report.md").display()
    );
    Ok(())
}
