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
fn replay(target: &str, check: Check) -> usize {
    let files = inputs(target);
    for f in &files {
        let data = std::fs::read(f).unwrap();
        if std::panic::catch_unwind(|| check(&data)).is_err() {
            panic!("{target}: {} fails again", f.display());
        }
    }
    files.len()
}

/// What a target checks on one input (panicking on a bug).
type Check = fn(&[u8]);

/// Every target and how many inputs its folder keeps. A replay that finds another count
/// fails: an emptied or deleted folder must not pass as "nothing failed", and a new kept
/// input is counted here when it is added.
const KEPT: &[(&str, Check, usize)] = &[
    ("parse", cases::parse, 0),
    ("ply", cases::ply, 0),
    ("scene", cases::scene, 1),
    ("render", cases::render, 2),
    ("fourier", cases::fourier, 1),
    ("merge", cases::merge, 2),
];

#[test]
fn kept_fuzz_inputs_pass_their_checks() {
    for &(target, check, kept) in KEPT {
        let n = replay(target, check);
        assert_eq!(
            n, kept,
            "fuzz/regressions/{target}/ holds {n} inputs, {kept} were kept"
        );
    }
    // Every target's folder is listed above (a new target's crashes are replayed too).
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions");
    let mut folders: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    folders.sort();
    let mut listed: Vec<String> = KEPT.iter().map(|k| k.0.to_owned()).collect();
    listed.sort();
    assert_eq!(folders, listed);
}
