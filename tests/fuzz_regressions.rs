//! Replays every input the fuzzers kept (fuzz/regressions/TARGET/, one file per crash found)
//! through the same check its target runs (fuzz/cases.rs), so that a fixed crash stays fixed
//! in the ordinary test run, without nightly or cargo-fuzz.

#[path = "../fuzz/cases.rs"]
mod cases;

use std::path::PathBuf;

/// The kept inputs of `target`, sorted.
fn inputs(target: &str) -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/regressions")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && p.file_name().is_some_and(|n| n != ".gitkeep"))
        .collect();
    files.sort();
    files
}

/// Runs `check` on each kept input of `target`, naming the input that fails.
fn replay(target: &str, check: fn(&[u8])) -> usize {
    let files = inputs(target);
    for f in &files {
        let data = std::fs::read(f).unwrap();
        if std::panic::catch_unwind(|| check(&data)).is_err() {
            panic!("{target}: {} fails again", f.display());
        }
    }
    files.len()
}

#[test]
fn kept_fuzz_inputs_pass_their_checks() {
    let counts = [
        ("parse", replay("parse", cases::parse)),
        ("ply", replay("ply", cases::ply)),
        ("scene", replay("scene", cases::scene)),
        ("render", replay("render", cases::render)),
    ];
    eprintln!("replayed {counts:?}");
}
