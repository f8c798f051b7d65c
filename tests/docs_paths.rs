//! The documentation names only files that exist: every repository path that README.md and
//! `docs/**/*.md` name, inside backticks, fenced code blocks or markdown links, is looked up
//! relative to the repository root or to the document's own folder (a link relative to its own
//! file only, as a browser reads it),
//! and README.md stays short enough to read (docs/testing.md, "Documentation").
//!
//! What counts as a path is decided by rule, so prose stays free of false alarms:
//! - a token with a known file extension (`.rs`, `.md`, `.pbrt`, ...), or one with a `/`
//!   whose first component is a top-level entry of the repository (so `R/G/B` or `1/64` is
//!   not a path, while `src/gone.rs` is);
//! - not a URL, not absolute, not outside the repository (`../`), not a pattern or placeholder
//!   (`*`, `<`, `{`, `=`, `$`, `...`, or a component such as `SCENE`, `OUT`, `FILE`, `N`);
//! - not the argument of an output option (`-o`, `--out`, `--stats`, `>`): those are written;
//! - not under a folder that `.gitignore` ignores (generated outputs such as `bench/cache/`).

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

/// The extensions that make a token a file name.
const EXTENSIONS: &[&str] = &[
    "rs", "md", "toml", "pbrt", "py", "sh", "exr", "png", "csv", "json", "ply", "pfm", "yaml",
    "sbatch", "cpp", "dict", "txt", "hdr", "bsdf", "lock",
];

/// Upper-case words the docs use for a value the reader supplies, separated by spaces.
const PLACEHOLDERS: &str = "SCENE OUT FILE NAME DIR PATH TARGET IMAGE REFERENCE CROP RANGE \
    MANIFEST KIND PARAM VALUE LABEL HOST PORT TILES IN N S X T K A B PR OLD NEW MESH";

/// Options whose argument is a file the command writes.
const OUTPUT_OPTIONS: &[&str] = &["-o", "--out", "--stats", ">", "--output"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and every markdown file under docs/.
fn documents(root: &Path) -> Vec<PathBuf> {
    let mut out = vec![root.join("README.md")];
    let mut stack = vec![root.join("docs")];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let p = entry.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "md") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The `.gitignore` patterns, as lists of path segments (`*` matches one segment or a part).
fn ignored_patterns(root: &Path) -> Vec<(bool, Vec<String>)> {
    let text = fs::read_to_string(root.join(".gitignore")).unwrap_or_default();
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#') && !l.starts_with('!'))
        .map(|l| {
            let anchored = l.starts_with('/') || l.trim_end_matches('/').contains('/');
            let segs = l.trim_matches('/').split('/').map(str::to_string).collect();
            (anchored, segs)
        })
        .collect()
}

/// Whether one segment matches a gitignore segment with at most one `*`.
fn segment_matches(pattern: &str, seg: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == seg,
        Some((pre, post)) => {
            seg.len() >= pre.len() + post.len() && seg.starts_with(pre) && seg.ends_with(post)
        }
    }
}

fn is_ignored(path: &str, patterns: &[(bool, Vec<String>)]) -> bool {
    let segs: Vec<&str> = path.trim_end_matches('/').split('/').collect();
    patterns.iter().any(|(anchored, pat)| {
        let starts: Vec<usize> = if *anchored {
            vec![0]
        } else {
            (0..segs.len()).collect()
        };
        starts.into_iter().any(|s| {
            segs.len() >= s + pat.len()
                && pat
                    .iter()
                    .zip(&segs[s..])
                    .all(|(p, g)| segment_matches(p, g))
        })
    })
}

/// The token with quotes, brackets and trailing punctuation taken off, and a `:LINE` suffix.
fn clean(token: &str) -> &str {
    let t = token.trim_matches(|c: char| "\"'`()[],;".contains(c));
    let t = t.trim_end_matches(['.', ':']);
    // `src/cli/render.rs:455` names the file.
    match t.split_once(':') {
        Some((file, rest)) if rest.chars().all(|c| c.is_ascii_digit() || c == ':') => file,
        _ => t,
    }
}

fn is_placeholder(t: &str) -> bool {
    if ["*", "<", ">", "{", "}", "=", "$", "...", "|", "~", "%"]
        .iter()
        .any(|c| t.contains(c))
    {
        return true;
    }
    t.split(['/', '.', '-', '_'])
        .any(|part| PLACEHOLDERS.split_whitespace().any(|w| w == part))
}

fn has_known_extension(t: &str) -> bool {
    let name = t.rsplit('/').next().unwrap_or(t);
    name.rsplit_once('.')
        .is_some_and(|(stem, ext)| !stem.is_empty() && EXTENSIONS.contains(&ext))
}

/// Whether a cleaned token is a repository path by the rules above.
fn is_repo_path(t: &str, top: &BTreeSet<String>) -> bool {
    if t.is_empty() || t.contains("://") || t.starts_with('/') || t.starts_with("../") {
        return false;
    }
    if is_placeholder(t) || t.contains("::") || t.starts_with('-') {
        return false;
    }
    if !t
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || "/._-+".contains(c))
    {
        return false;
    }
    let first = t.trim_start_matches("./").split('/').next().unwrap_or("");
    has_known_extension(t) || (t.contains('/') && top.contains(first))
}

/// Every path named in backticks or fenced blocks of one document, with its line number.
fn code_paths(text: &str, top: &BTreeSet<String>) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_fence = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        let spans: Vec<&str> = if in_fence {
            vec![line]
        } else {
            line.split('`').skip(1).step_by(2).collect()
        };
        for span in spans {
            let mut after_output = false;
            for raw in span.split_whitespace() {
                let t = clean(raw);
                let skip = after_output;
                after_output = OUTPUT_OPTIONS.contains(&raw);
                if !skip && is_repo_path(t, top) {
                    out.push((i + 1, t.trim_start_matches("./").to_string()));
                }
            }
        }
    }
    out
}

/// Every markdown link target of one document (`[text](target)`), outside code.
fn link_targets(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_fence = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        let mut rest = line;
        while let Some(pos) = rest.find("](") {
            rest = &rest[pos + 2..];
            let Some(end) = rest.find(')') else { break };
            let target = rest[..end].split('#').next().unwrap_or("");
            let target = target.split_whitespace().next().unwrap_or("");
            if !target.is_empty() && !target.contains("://") && !target.starts_with("mailto:") {
                out.push((i + 1, target.to_string()));
            }
            rest = &rest[end..];
        }
    }
    out
}

#[test]
fn every_path_the_docs_name_exists() {
    let root = root();
    let top: BTreeSet<String> = fs::read_dir(&root)
        .expect("the repository root")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "target")
        .collect();
    let ignored = ignored_patterns(&root);
    let mut missing = Vec::new();
    let mut checked = 0;
    for doc in documents(&root) {
        let text = fs::read_to_string(&doc).expect("a readable document");
        let name = doc
            .strip_prefix(&root)
            .unwrap_or(&doc)
            .display()
            .to_string();
        for (line, path) in code_paths(&text, &top) {
            if is_ignored(&path, &ignored) {
                continue;
            }
            checked += 1;
            // A path is read from the root; a report may name a file beside itself.
            let dir = doc.parent().unwrap_or(&root);
            if !root.join(&path).exists() && !dir.join(&path).exists() {
                missing.push(format!("{name}:{line}: `{path}`"));
            }
        }
        let dir = doc.parent().unwrap_or(&root);
        for (line, target) in link_targets(&text) {
            let resolved = dir.join(&target);
            let Ok(rel) = resolved
                .canonicalize()
                .or_else(|_| Ok::<_, ()>(resolved.clone()))
            else {
                continue;
            };
            let rel = rel
                .strip_prefix(&root)
                .unwrap_or(&rel)
                .display()
                .to_string();
            if target.starts_with('/') || is_ignored(&rel, &ignored) {
                continue;
            }
            checked += 1;
            if !resolved.exists() {
                missing.push(format!("{name}:{line}: link ({target})"));
            }
        }
    }
    assert!(
        checked > 50,
        "only {checked} paths found: is the extraction broken?"
    );
    assert!(
        missing.is_empty(),
        "{} of {checked} paths named in the docs do not exist:\n{}",
        missing.len(),
        missing.join("\n")
    );
}

#[test]
fn the_readme_stays_short() {
    let text = fs::read_to_string(root().join("README.md")).expect("README.md");
    let lines = text.lines().count();
    assert!(
        lines <= 220,
        "README.md has {lines} lines; keep it at most 220 (docs/ holds the rest)"
    );
}

#[test]
fn the_rules_tell_paths_from_prose() {
    let top: BTreeSet<String> = ["src", "docs", "tests", "scenes"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let found: Vec<String> = code_paths(
        "`src/render.rs:455` `R/G/B` `1/64` `acr render SCENE.pbrt -o out.png` \
         `docs/bench/*/runs/` `https://a.b/c.rs` `../shared/x.pbrt` `mod.rs`, `sampler::x`",
        &top,
    )
    .into_iter()
    .map(|(_, p)| p)
    .collect();
    assert_eq!(found, ["src/render.rs", "mod.rs"]);
    let ignored = vec![
        (
            true,
            vec!["docs".into(), "bench".into(), "*".into(), "runs".into()],
        ),
        (false, vec!["bench-out".into()]),
    ];
    assert!(is_ignored("docs/bench/paper/runs/x.exr", &ignored));
    assert!(is_ignored("x/bench-out/y", &ignored));
    assert!(!is_ignored("docs/bench/paper/report.md", &ignored));
}
