//! The `acr` binary.

use clap::Parser;

fn main() -> std::process::ExitCode {
    acr::cli::run(acr::cli::Cli::parse())
}
