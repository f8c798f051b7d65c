//! One render of a bench: `acr render` as a child process, so that its time and peak memory
//! are its own and a crash is only a failed row; what its stats file reports, and its image
//! measured against the reference.

use super::external::run_command;
use super::{Measured, Method, SamplerCost};
use crate::image_io::{read_image, RgbImage};
use crate::metrics::compare;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The image a run of `method` into `output` is scored on: the render, or for an external
/// method its command's `{out}` (the render then goes to [`command_input`]).
pub(super) fn scored_path(method: &Method, output: &Path) -> PathBuf {
    if method.is_external() {
        output.with_extension(method.output.unwrap_or_default().extension())
    } else {
        output.to_owned()
    }
}

/// Where an external method's render of a run into `output` goes: its command's `{in}`.
pub(super) fn command_input(output: &Path) -> PathBuf {
    output.with_extension("input.exr")
}

/// What `acr render` reported of one run.
pub(super) struct RunOutput {
    /// Render plus reconstruction seconds.
    pub(super) seconds: f64,
    /// The reconstruction's share of `seconds`.
    pub(super) reconstruct_seconds: f64,
    /// Samples traced.
    pub(super) samples: u64,
    /// Pixels of the image.
    pub(super) pixels: u64,
    /// Peak resident memory.
    pub(super) peak_rss_mb: f64,
    /// With `--sampler-cost`: what it measured.
    pub(super) cost: Option<SamplerCost>,
}

/// What the runs of one method on one scene share: the executable, the scene, the method,
/// the seed and the worker threads.
pub(super) struct RenderRun<'a> {
    /// The `acr` executable.
    pub(super) exe: &'a Path,
    /// The scene file.
    pub(super) scene: &'a Path,
    /// The sampler, filter, integrator and settings.
    pub(super) method: &'a Method,
    /// The seed.
    pub(super) seed: u64,
    /// Worker threads (default: every core).
    pub(super) threads: Option<u32>,
    /// The scene's `--pixelbounds`, if it is cropped.
    pub(super) pixelbounds: Option<[u32; 4]>,
}

impl RenderRun<'_> {
    /// Runs `acr render` into `output` at `spp`, stopped by `time_limit`, with
    /// `--sampler-cost` when `sampler_cost`; reads its stats file (`output` as `.json`).
    pub(super) fn run(
        &self,
        output: &Path,
        spp: u32,
        time_limit: Option<f64>,
        sampler_cost: bool,
    ) -> Result<RunOutput, String> {
        let stats = output.with_extension("json");
        let mut cmd = self.command(output, &stats, spp);
        if let Some(t) = time_limit {
            cmd.arg("--time-limit").arg(format!("{t:.6}"));
            if let Some(plan) = self.method.time_plan {
                let name = clap::ValueEnum::to_possible_value(&plan).expect("named");
                cmd.arg("--time-plan").arg(name.get_name());
            }
        }
        if sampler_cost {
            cmd.arg("--sampler-cost");
        }
        let out = cmd
            .output()
            .map_err(|e| format!("cannot run {}: {e}", self.exe.display()))?;
        if !out.status.success() {
            let err = String::from_utf8_lossy(&out.stderr);
            let first = err.lines().next().unwrap_or("").trim();
            return Err(match out.status.code() {
                Some(c) => format!("exit {c}: {first}"),
                None => format!("killed by a signal: {first}"),
            });
        }
        read_stats(&stats, sampler_cost)
    }

    /// The command line of a run into `output` at `spp`, its stats into `stats`.
    fn command(&self, output: &Path, stats: &Path, spp: u32) -> Command {
        let mut cmd = Command::new(self.exe);
        cmd.arg("render")
            .arg(self.scene)
            .arg("-o")
            .arg(output)
            .arg("--quiet")
            .arg("--stats")
            .arg(stats)
            .arg("--spp")
            .arg(spp.to_string())
            .arg("--seed")
            .arg(self.seed.to_string());
        let method = self.method;
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
        if let Some(aov) = &method.aov {
            cmd.arg("--aov").arg(aov);
        }
        if let Some([x0, x1, y0, y1]) = self.pixelbounds {
            cmd.arg("--pixelbounds").arg(format!("{x0},{x1},{y0},{y1}"));
        }
        if let Some(t) = self.threads {
            cmd.arg("--threads").arg(t.to_string());
        }
        cmd
    }

    /// One run into `output`, measured against `reference`; an external method's command
    /// runs in `base` (the manifest's folder) on the render, and its seconds are added.
    pub(super) fn measure(
        &self,
        output: &Path,
        spp: u32,
        time_limit: Option<f64>,
        reference: &RgbImage,
        base: &Path,
    ) -> Result<Measured, String> {
        let scored = scored_path(self.method, output);
        let (r, command) = if self.method.is_external() {
            let input = command_input(output);
            let r = self.run(&input, spp, time_limit, false)?;
            (r, Some(run_command(self.method, base, &input, &scored)?))
        } else {
            (self.run(output, spp, time_limit, false)?, None)
        };
        let img = read_image(&scored, false).map_err(|e| format!("{}: {e}", scored.display()))?;
        let metrics = compare(&img, reference)?;
        let command_seconds = command.map(|c| c.seconds);
        Ok(Measured {
            seconds: r.seconds + command_seconds.unwrap_or(0.0),
            command_seconds,
            command_time: command.map(|_| self.method.time.unwrap_or_default()),
            reconstruct_seconds: r.reconstruct_seconds,
            samples: r.samples,
            spp_reached: r.samples as f64 / r.pixels.max(1) as f64,
            metrics,
            peak_rss_mb: r.peak_rss_mb,
        })
    }
}

/// What a run's stats file says; with `sampler_cost`, its sampler share must be there.
fn read_stats(stats: &Path, sampler_cost: bool) -> Result<RunOutput, String> {
    let text = std::fs::read_to_string(stats)
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
        reconstruct_seconds: f("reconstruct"),
        samples: v["samples"].as_u64().unwrap_or(0),
        pixels: v["width"].as_u64().unwrap_or(0) * v["height"].as_u64().unwrap_or(0),
        peak_rss_mb: v["peak_rss_mb"].as_f64().unwrap_or(0.0),
    })
}
