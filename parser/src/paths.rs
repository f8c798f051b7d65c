//! Files a scene names: where a name points ([`resolve_path`]) and why reading failed, in
//! words ([`io_message`]).

use crate::source::SourceFile;
use std::path::{Path, PathBuf};

/// An I/O error in words, without Rust's "(os error 2)" suffix.
pub fn io_message(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".to_owned(),
        std::io::ErrorKind::PermissionDenied => "permission denied".to_owned(),
        _ => {
            let s = e.to_string();
            match s.find(" (os error") {
                Some(i) => s[..i].to_owned(),
                None => s,
            }
        }
    }
}

/// Resolves a file name written in a scene: relative to the file that names it, and failing
/// that relative to the main scene file's directory (pbrt-v3's rule), so both layouts work.
pub fn resolve_path(name: &str, including: &SourceFile, base_dir: &Path) -> PathBuf {
    let p = Path::new(name);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    let local = including.dir().join(p);
    if local.exists() {
        return local;
    }
    let from_base = base_dir.join(p);
    if from_base.exists() {
        from_base
    } else {
        local
    }
}
