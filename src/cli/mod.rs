//! The `acr` command line: the subcommands, one file each (`parse`, `render`, `bench`, `diff`, `merge`;
//! `plugins` is a one-liner here), and what they alone use (AOV files, run statistics, replays).

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

pub mod aov;
pub mod bench;
pub mod diff;
pub mod display;
pub mod merge;
pub mod mergeable;
pub mod output;
pub mod parse;
pub mod render;
pub mod replay;
pub mod stats;

pub use render::RenderArgs;

/// Adaptive cluster rendering for pbrt-v3 scenes.
#[derive(Parser, Debug)]
#[command(name = "acr", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Parse a scene and print its scene graph (as the snapshot tests see it).
    Parse {
        /// The .pbrt scene file.
        scene: PathBuf,
    },
    /// Render a scene to an image (.exr, .png or .pfm).
    Render(Box<RenderArgs>),
    /// List every plugin (samplers, filters, integrators) with its parameters and defaults.
    Plugins,
    /// Time against error: render a manifest's scenes with its methods at its budgets, and
    /// write a CSV, a plot per scene and a Markdown report.
    Bench {
        /// The manifest (TOML; see bench/ for examples).
        manifest: PathBuf,
        /// Output folder (default: bench-out/MANIFEST-NAME).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Assemble crops of one frame (EXRs from `acr render --cropwindow` or `--pixelbounds`),
    /// placed by their data windows, into the whole image.
    Merge {
        /// The merged image (.exr, .png or .pfm).
        output: PathBuf,
        /// The crops (.exr), which together cover the frame once.
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
    },
    /// Compare an image with a reference: MSE, relMSE and PSNR (linear radiance).
    Diff {
        /// The image to judge (.exr, .pfm, .hdr or .png).
        image: PathBuf,
        /// The reference image, of the same size.
        reference: PathBuf,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
}

/// Runs the command line; returns the process exit code.
pub fn run(cli: Cli) -> ExitCode {
    let result = match cli.command {
        Command::Parse { scene } => parse::command(&scene),
        Command::Render(args) => render::command(&args),
        Command::Bench { manifest, out } => bench::command(&manifest, out),
        Command::Merge { output, inputs } => merge::command(&output, &inputs),
        Command::Plugins => {
            print!("{}", crate::registry::describe());
            Ok(())
        }
        Command::Diff {
            image,
            reference,
            json,
        } => diff::command(&image, &reference, json),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => report(&e),
    }
}

/// A time limit in seconds: finite and positive.
pub(crate) fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v < 1e9 => Ok(v),
        _ => Err(format!("\"{s}\" is not a positive number of seconds")),
    }
}

pub(crate) fn parse_threshold(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("\"{s}\" is not a positive relative error")),
    }
}

/// Prints an error the way every acr command does, and gives the failure exit code.
pub fn report(e: &dyn std::fmt::Display) -> ExitCode {
    eprintln!("{e}");
    ExitCode::FAILURE
}
