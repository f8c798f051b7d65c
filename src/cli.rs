//! The `acr` command line: subcommands and their arguments.

use clap::{Parser, Subcommand};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
}

/// Runs the command line; returns the process exit code.
pub fn run(cli: Cli) -> ExitCode {
    let result = match cli.command {
        Command::Parse { scene } => parse(&scene),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => report(&e),
    }
}

fn parse(scene: &Path) -> Result<(), String> {
    let desc = acr_parser::parse_file(scene).map_err(|e| e.to_string())?;
    let mut out = std::io::stdout().lock();
    // A closed pipe (acr parse x | head) is not an error worth reporting.
    let _ = out.write_all(desc.to_text().as_bytes());
    Ok(())
}

/// Prints an error the way every acr command does, and gives the failure exit code.
pub fn report(e: &dyn std::fmt::Display) -> ExitCode {
    eprintln!("{e}");
    ExitCode::FAILURE
}
