//! `Include` as pbrt-v3's tokenizer reads it: a stack of tokenizers, so that when an included
//! file ends, the directive it ended with goes on with the tokens after the `Include` (the
//! pbrt-v3-scenes cloud scenes write a `MakeNamedMedium`'s last parameters after the `Include`
//! of the file that begins it). Errors keep the file, line and column of the token at fault.

use acr_parser::{parse_file, Error, SceneDescription};
use std::path::{Path, PathBuf};

/// A temporary folder, removed when dropped.
struct TempFolder(PathBuf);

impl std::ops::Deref for TempFolder {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempFolder {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fresh folder holding `files` (name, text).
fn folder(name: &str, files: &[(&str, &str)]) -> TempFolder {
    let dir = std::env::temp_dir().join(format!("acr-include-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    TempFolder(dir)
}

/// Parses `main` with `inc.pbrt` beside it.
fn parse(name: &str, main: &str, inc: &str) -> (Result<SceneDescription, Error>, TempFolder) {
    let dir = folder(name, &[("main.pbrt", main), ("inc.pbrt", inc)]);
    (parse_file(&dir.join("main.pbrt")), dir)
}

/// The error's message with the folder left out.
fn error_of(result: Result<SceneDescription, Error>, dir: &Path) -> String {
    match result {
        Ok(_) => panic!("parsed without error"),
        Err(e) => e.to_string().replace(&format!("{}/", dir.display()), ""),
    }
}

#[test]
fn a_shapes_parameters_continue_after_the_include_that_ends_with_it() {
    let (r, dir) = parse(
        "shape",
        "WorldBegin\nInclude \"inc.pbrt\" \"float radius\" [ 2.5 ]\nShape \"disk\"\nWorldEnd\n",
        "AttributeBegin\nShape \"sphere\" \"float zmin\" -1\nAttributeEnd\nShape \"sphere\"\n",
    );
    let d = r.unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(d.shapes.len(), 3);
    // The first sphere ended inside the included file's attribute block: nothing added.
    assert!(d.shapes[0].plugin.params.get("radius").is_none());
    let p = &d.shapes[1].plugin.params;
    assert_eq!(p.float("radius").unwrap(), Some(2.5));
    // The parameter is located where it is written: in the including file.
    let at = p.get("radius").unwrap().loc.to_string();
    assert_eq!(at, format!("{}:2:20", dir.join("main.pbrt").display()));
    assert_eq!(d.shapes[2].plugin.kind, "disk");
}

#[test]
fn a_parameter_list_spans_both_files_as_one_list() {
    // pbrt-v3's cloud scenes: the medium's density in the included file, its coefficients
    // after the Include. The duplicate "g" shows that both halves reach one list: the later
    // one (in main.pbrt) wins, with a warning at the earlier one (in inc.pbrt).
    let (r, dir) = parse(
        "medium",
        "Include \"inc.pbrt\"\n\"color sigma_a\" [10 10 10] \"float g\" 0.5\n\
         WorldBegin\nShape \"sphere\"\nWorldEnd\n",
        "MakeNamedMedium \"smoke\" \"string type\" \"heterogeneous\" \"float g\" 0.1\n\
         \"integer nx\" 1 \"integer ny\" 1 \"integer nz\" 1 \"float density\" [ 0.5 ]\n",
    );
    let d = r.unwrap_or_else(|e| panic!("{e}"));
    let inc = dir.join("inc.pbrt").display().to_string();
    let warned = d.warnings.iter().any(|w| {
        w.to_string().starts_with(&format!("{inc}:1:"))
            && w.message.contains("\"g\" is given again later")
    });
    assert!(warned, "{:?}", d.warnings);
    // The same list, cut short inside its last value: the error is at the parameter in the
    // including file.
    let (r, dir) = parse(
        "medium-bad",
        "Include \"inc.pbrt\"\n\"color sigma_a\" [10 10\n",
        "MakeNamedMedium \"smoke\" \"string type\" \"homogeneous\"\n",
    );
    let e = error_of(r, &dir);
    assert!(
        e.starts_with("main.pbrt:2:1: parameter \"sigma_a\": '[' is never closed"),
        "{e}"
    );
}

#[test]
fn a_directives_arguments_and_values_may_straddle_the_end_of_an_include() {
    // A bracket opened in an included file and closed after its Include, and a transform
    // whose numbers are split between two files, as pbrt-v3 reads them.
    let dir = folder(
        "straddle",
        &[
            (
                "main.pbrt",
                "WorldBegin\nInclude \"inc.pbrt\" 2 3 ]\nInclude \"t.pbrt\" 3\n\
                 Shape \"disk\"\nWorldEnd\n",
            ),
            ("inc.pbrt", "Shape \"sphere\" \"float radius\" [ 1\n"),
            ("t.pbrt", "Translate 0 0"),
        ],
    );
    let d = parse_file(&dir.join("main.pbrt")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        d.shapes[0].plugin.params.floats("radius").unwrap(),
        Some(&[1.0, 2.0, 3.0][..])
    );
    let moved = d.shapes[1]
        .world_from_object
        .start
        .transform_point3(glam::DVec3::ZERO);
    assert_eq!(moved, glam::DVec3::new(0.0, 0.0, 3.0));
}

#[test]
fn an_include_that_ends_mid_directive_gives_located_errors() {
    let inc_ending = [
        // (the included file, what follows the Include, the error expected)
        (
            "Shape",
            "\nWorldEnd\n",
            "main.pbrt:3:1: Shape expects a quoted string here, found 'WorldEnd'",
        ),
        (
            "Shape \"sphere\" \"float radius\"",
            " ]\nWorldEnd\n",
            "main.pbrt:2:20: expected a value for parameter \"radius\", found ']'",
        ),
        (
            "Shape \"sphere\" \"float radius\" [ 1",
            "\n",
            "inc.pbrt:1:16: parameter \"radius\": '[' is never closed",
        ),
        (
            "Shape \"sphere\" \"float radius\"",
            "",
            "inc.pbrt:1:16: parameter \"radius\" has no value: the file ends",
        ),
        (
            "Shape \"sphere\" \"float radius\" [",
            " \"x\" ]\n",
            "inc.pbrt:1:16: parameter \"radius\" is declared float but has string values",
        ),
        (
            "Translate 1 2",
            " Shape\n",
            "main.pbrt:2:20: Translate expects 3 numbers, found 'Shape' after 2",
        ),
        (
            "Shape \"sphere\" \"float radius\" [ 1",
            " WorldEnd ]\n",
            "main.pbrt:2:20: parameter \"radius\": unexpected 'WorldEnd' among its values",
        ),
        (
            "AttributeBegin",
            " \"float radius\" 1\n",
            "main.pbrt:2:20: expected a directive, found string \"float radius\"",
        ),
        (
            "",
            " 2 3\n",
            "main.pbrt:2:20: expected a directive, found number 2",
        ),
        (
            "Shape \"sphere\" \"float radius\" [ 1 \"",
            " ]\n",
            "inc.pbrt:1:35: unterminated string",
        ),
    ];
    for (i, (inc, after, want)) in inc_ending.into_iter().enumerate() {
        let main = format!("WorldBegin\nInclude \"inc.pbrt\"{after}");
        let (r, dir) = parse(&format!("bad-{i}"), &main, inc);
        let e = error_of(r, &dir);
        assert!(
            e.starts_with(want),
            "{inc:?} then {after:?}\n got: {e}\nwant: {want}"
        );
    }
}

#[test]
fn nested_includes_continue_outward_one_file_at_a_time() {
    let dir = folder(
        "nested",
        &[
            (
                "main.pbrt",
                "WorldBegin\nInclude \"a.pbrt\" \"float zmax\" 0.5\nWorldEnd\n",
            ),
            ("a.pbrt", "Include \"b.pbrt\" \"float zmin\" -0.5\n"),
            ("b.pbrt", "Shape \"sphere\" \"float radius\" 2\n"),
        ],
    );
    let d = parse_file(&dir.join("main.pbrt")).unwrap_or_else(|e| panic!("{e}"));
    let p = &d.shapes[0].plugin.params;
    assert_eq!(p.float("radius").unwrap(), Some(2.0));
    assert_eq!(p.float("zmin").unwrap(), Some(-0.5));
    assert_eq!(p.float("zmax").unwrap(), Some(0.5));
}

/// The starts of the tokens of `text` after its first, where a file may be cut.
fn token_starts(text: &str) -> Vec<usize> {
    let mut t = acr_parser::lexer::Tokenizer::new(acr_parser::SourceFile::new("t.pbrt", text));
    let mut out = Vec::new();
    while let Ok(Some(tok)) = t.next_token() {
        out.push(tok.offset);
    }
    out.split_off(1.min(out.len()))
}

/// Asserts that `r` parsed, or failed with an error at a line and column in one of the files
/// `dir` holds; gives whether it failed.
fn ok_or_located(r: &Result<SceneDescription, Error>, dir: &Path, texts: &[(&str, &str)]) -> bool {
    let Err(e) = r else { return false };
    let Error::At { loc, .. } = e else {
        panic!("an error with no place: {e}")
    };
    let (name, text) = texts
        .iter()
        .find(|(n, _)| loc.file.path == dir.join(n))
        .unwrap_or_else(|| panic!("{e}: not in {texts:?}"));
    let (line, col) = loc.line_col();
    assert!(
        (1..=text.split('\n').count()).contains(&line) && col >= 1,
        "{name}: {line}:{col} is not in the text: {e}"
    );
    true
}

/// A scene cut anywhere between its tokens into an included file (its start) and the file that
/// includes it first thing (its rest) is the same scene, as one token stream; and every prefix
/// of that rest gives the scene or a located error, never a panic.
#[test]
fn a_scene_cut_anywhere_into_an_include_and_its_rest_is_the_same_scene() {
    let scene = "LookAt 0 0 5 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" [45]\n\
                 WorldBegin AttributeBegin Material \"matte\" \"rgb Kd\" [.5 .5 .5]\n\
                 Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n\
                 AttributeEnd Shape \"sphere\" \"float radius\" 2 WorldEnd\n";
    let whole = acr_parser::parse_str(scene, Path::new("whole.pbrt")).unwrap();
    let dir = folder("cut", &[]);
    let mut errors = 0;
    for cut in token_starts(scene) {
        let (head, rest) = scene.split_at(cut);
        let main = format!("Include \"inc.pbrt\" {rest}");
        std::fs::write(dir.join("inc.pbrt"), head).unwrap();
        std::fs::write(dir.join("main.pbrt"), &main).unwrap();
        let d = parse_file(&dir.join("main.pbrt")).unwrap_or_else(|e| panic!("cut at {cut}: {e}"));
        assert_eq!(d.shapes.len(), whole.shapes.len(), "cut at {cut}");
        let params = |d: &SceneDescription| {
            d.shapes
                .iter()
                .map(|s| {
                    s.plugin
                        .params
                        .iter()
                        .map(|p| p.name.clone())
                        .collect::<Vec<_>>()
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(params(&d), params(&whole), "cut at {cut}");
        for end in token_starts(&main).into_iter().step_by(3) {
            std::fs::write(dir.join("main.pbrt"), &main[..end]).unwrap();
            let r = parse_file(&dir.join("main.pbrt"));
            let texts = [("main.pbrt", &main[..end]), ("inc.pbrt", head)];
            errors += usize::from(ok_or_located(&r, &dir, &texts));
        }
    }
    assert!(errors > 100, "only {errors} errors");
}
