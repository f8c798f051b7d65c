//! What the integration tests share: for the farm tests a scratch folder per test, running
//! the `acr` binary and the scene they render; for the agreement tests the render and the
//! image measure (`in_process`).

#![allow(dead_code)]

pub mod in_process;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A test's scratch folder, removed when the test ends (passed or failed).
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fresh folder for one test's files.
pub fn temp_dir(name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("acr-farm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

/// Runs `acr ARGS`.
pub fn acr(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_acr"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs `acr ARGS`, which must succeed; returns its stderr.
pub fn ok(args: &[&str]) -> String {
    let o = acr(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "acr {args:?}: {err}");
    err
}

/// Runs `acr ARGS`, which must fail cleanly (non-zero, a message, no panic) saying `says`.
pub fn fails(args: &[&str], says: &str) {
    let o = acr(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && o.status.code().is_some(),
        "acr {args:?}: {err}"
    );
    assert!(
        !err.contains("panicked") && err.contains(says),
        "acr {args:?}: {err}"
    );
}

/// The quadrics feature scene, small and quick.
pub fn scene() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/pbrt-v3/quadrics.pbrt")
}

/// A path as the command line takes it.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
