//! Bad input: located errors, clean failures before rendering, never a panic.

use super::*;

/// A scene that takes minutes to render (2000 x 2000 at 256 spp): a command that fails within
/// seconds on it failed before rendering.
fn slow_scene(dir: &TempDir) -> PathBuf {
    let text = small_scene("").replace(
        "\"integer xresolution\" 24 \"integer yresolution\" 16",
        "\"integer xresolution\" 2000 \"integer yresolution\" 2000",
    );
    assert!(text.contains("2000"));
    dir.write("slow.pbrt", &text)
}

/// Renders the slow scene to `out` (in `dir`), which must fail within 20 s, before rendering;
/// gives what it printed.
fn render_slow_scene_to(dir: &TempDir, out: &Path) -> Output {
    let scene = slow_scene(dir);
    output_within(
        acr_command([
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
            "--spp".as_ref(),
            "256".as_ref(),
        ]),
        Duration::from_secs(20),
    )
}

#[test]
fn an_unknown_output_format_fails_before_rendering() {
    let dir = TempDir::new("jpg");
    let out = dir.join("out.jpg");
    let o = render_slow_scene_to(&dir, &out);
    assert_clean_failure(&o, "-o out.jpg");
    let err = stderr(&o);
    assert!(err.contains("jpg"), "the message names the format: {err}");
    assert!(!out.exists());
}

#[test]
fn a_missing_output_folder_fails_cleanly_before_rendering() {
    let dir = TempDir::new("nofolder");
    let out = dir.join("missing/deeper/out.png");
    let o = render_slow_scene_to(&dir, &out);
    assert_clean_failure(&o, "-o missing/deeper/out.png");
    let err = stderr(&o);
    assert!(
        err.contains("missing"),
        "the message names the folder: {err}"
    );
    assert!(
        !dir.join("missing").exists(),
        "the folder was created behind the user's back"
    );
}

/// Scenes with an error at a known place: (text, line, column, a word of the message).
const BAD_SCENES: &[(&str, u32, u32, &str)] = &[
    // An unknown directive, indented.
    (
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n  Shpae \"sphere\"\nWorldEnd\n",
        4,
        3,
        "Shpae",
    ),
    // A parameter of the wrong type: the message points at the parameter.
    (
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\n\
         Shape \"sphere\" \"float radius\" \"one\"\nWorldEnd\n",
        5,
        16,
        "radius",
    ),
    // A bracket left open: the first token that cannot be a value is the error.
    (
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
         Shape \"sphere\" \"float radius\" [ 1\nWorldEnd\n",
        5,
        1,
        "WorldEnd",
    ),
    // Found when the scene is built, not parsed: an unknown light.
    (
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\nShape \"sphere\"\n\
         LightSource \"pointt\"\nWorldEnd\n",
        5,
        1,
        "pointt",
    ),
];

#[test]
fn scene_errors_are_located_and_never_panic() {
    let dir = TempDir::new("errors");
    for (i, &(text, line, col, word)) in BAD_SCENES.iter().enumerate() {
        let scene = dir.write(&format!("bad{i}.pbrt"), text);
        let out = dir.join(format!("bad{i}.png"));
        let o = acr([
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
            "--quiet".as_ref(),
        ]);
        assert_clean_failure(&o, &format!("bad scene {i}"));
        let err = stderr(&o);
        let prefix = format!("{}:{line}:{col}: ", scene.display());
        assert!(
            err.starts_with(&prefix),
            "bad scene {i}: expected {prefix:?} first, got:\n{err}"
        );
        assert!(err.contains(word), "bad scene {i}: {err}");
        assert!(!out.exists(), "bad scene {i}: an image was written");
    }
}

/// Every file in tests/data/bad (parse errors) and tests/data/bad-render (scenes that parse
/// but cannot be built: absurd sizes, missing or hostile files, bad values), and each of their
/// PLY and image files given as a scene: `acr render` exits with status 1 within seconds,
/// prints `FILE:LINE:COL: message` first (the empty file has no place to point to: `FILE:
/// message`), never panics and writes no image. A folder and a missing file fail the same way.
#[test]
fn every_bad_input_fails_cleanly_with_its_location() {
    let dir = TempDir::new("bad-inputs");
    let out = dir.join("out.png");
    let mut files: Vec<PathBuf> = ["tests/data/bad", "tests/data/bad-render"]
        .iter()
        .flat_map(|d| std::fs::read_dir(root().join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(files.len() >= 40, "{} files", files.len());
    let unlocated = |p: &Path| p.file_name().is_some_and(|n| n == "empty.pbrt");
    let mut extra = vec![root().join("tests/data"), dir.join("no-such-scene.pbrt")];
    files.append(&mut extra);
    for f in &files {
        let o = output_within(acr_command(render_args(f, &out)), Duration::from_secs(60));
        let what = f.display().to_string();
        assert_clean_failure(&o, &what);
        assert_eq!(o.status.code(), Some(1), "{what}");
        let err = stderr(&o);
        let first = err.lines().next().unwrap_or("");
        let rest = first
            .strip_prefix(&format!("{}:", f.display()))
            .unwrap_or_else(|| panic!("{what}: not prefixed by the file: {first}"));
        let mut fields = rest.splitn(3, ':');
        let located = matches!(
            (fields.next(), fields.next(), fields.next()),
            (Some(l), Some(c), Some(m)) if l.parse::<u32>().is_ok()
                && c.parse::<u32>().is_ok() && m.starts_with(' ')
        );
        let expect_location = f.is_file() && !unlocated(f);
        assert_eq!(located, expect_location, "{what}: {first}");
        assert!(!out.exists(), "{what}: an image was written");
    }
}

/// Every kind of file a scene names, named as a device: refused at once with a located error
/// that says why, without reading (the `fourier` material's table once read `/dev/zero`
/// until the machine ran out of memory; the memory and time guard of [`output_within`]
/// stops such a run within a second or two).
#[cfg(unix)]
#[test]
fn a_device_named_as_any_scene_file_is_refused_at_once() {
    let dir = TempDir::new("devices");
    let out = dir.join("out.png");
    // Images are read by their extension: a device under an image's name.
    for name in ["zero.png", "zero.exr"] {
        std::os::unix::fs::symlink("/dev/zero", dir.join(name)).unwrap();
    }
    let world = "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\" Film \"image\" \
                 \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n";
    for (what, line) in [
        ("Include", "Include \"/dev/zero\""),
        ("PLY", "Shape \"plymesh\" \"string filename\" \"/dev/zero\""),
        (
            "image texture",
            "Texture \"t\" \"color\" \"imagemap\" \"string filename\" \"zero.png\"\n\
             Material \"matte\" \"texture Kd\" \"t\"\nShape \"sphere\"",
        ),
        (
            "image light",
            "LightSource \"infinite\" \"string mapname\" \"zero.exr\"",
        ),
        (
            "fourier table",
            "Material \"fourier\" \"string bsdffile\" \"/dev/zero\"\nShape \"sphere\"",
        ),
        (
            "spectrum file",
            "Material \"matte\" \"spectrum Kd\" \"/dev/zero\"\nShape \"sphere\"",
        ),
    ] {
        let scene = dir.write("d.pbrt", &format!("{world}{line}\nWorldEnd\n"));
        let started = Instant::now();
        let o = output_within(
            acr_command(render_args(&scene, &out)),
            Duration::from_secs(20),
        );
        assert_clean_failure(&o, what);
        let err = stderr(&o);
        assert!(
            err.starts_with(&format!("{}:4:", scene.display())),
            "{what}: not located: {err}"
        );
        assert!(err.contains("device, pipe or socket"), "{what}: {err}");
        // Refused before reading: as fast as any error (a build of this tiny scene).
        assert!(started.elapsed() < Duration::from_secs(10), "{what}");
    }
}

#[test]
fn unknown_plugins_and_parameters_are_located_errors_with_the_closest_name() {
    let dir = TempDir::new("badplugins");
    let out = dir.join("x.png");
    let scene = dir.write("ok.pbrt", &small_scene(""));
    let run = |args: &[&str]| {
        let mut all = vec![
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        all.extend_from_slice(args);
        acr(&all)
    };
    let cases: &[(&[&str], &[&str])] = &[
        (
            &["--sampler", "sobl"],
            &["unknown sampler \"sobl\"", "\"sobol\"", "known: random"],
        ),
        (
            &["--filter", "gausian"],
            &["unknown filter", "\"gaussian\""],
        ),
        (
            &["--integrator", "pth"],
            &["unknown integrator", "\"path\""],
        ),
        (
            &["--set", "sampler.pixelsampels=4"],
            &["--set:1:9:", "\"pixelsamples\""],
        ),
        (
            &["--filter", "gaussian", "--set", "filter.alpha=wide"],
            &["--set:1:14:", "not a number"],
        ),
        (
            &["--set", "filter.alpha=1"],
            &["--set:1:8:", "filter \"box\" has no parameter \"alpha\""],
        ),
        (&["--set", "camera.fov=3"], &["unknown plugin kind"]),
        (&["--aov", "sp=a.png"], &["unknown AOV", "\"spp\""]),
        (&["--time-limit", "0"], &["positive number of seconds"]),
        (&["--time-limit", "nan"], &["positive number of seconds"]),
        (&["--time-plan", "budget"], &["--time-limit"]),
        (
            &["--time-limit", "1", "--time-plan", "soon"],
            &["possible values: fit, budget"],
        ),
        // The renders that measure the sampler's cost cannot stop where the first one did.
        (
            &["--time-limit", "1", "--sampler-cost"],
            &["--sampler-cost", "--time-limit"],
        ),
    ];
    for (args, words) in cases {
        let o = run(args);
        assert_clean_failure(&o, &format!("{args:?}"));
        let err = stderr(&o);
        for w in *words {
            assert!(err.contains(w), "{args:?}: no {w} in {err}");
        }
        assert!(!out.exists(), "{args:?}: wrote an image");
    }
    // In the scene: the directive's location.
    let bad = dir.write(
        "bad.pbrt",
        &small_scene("").replace("WorldBegin", "Sampler \"haltn\"\nWorldBegin"),
    );
    let o = acr(["render", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_clean_failure(&o, "haltn");
    let err = stderr(&o);
    assert!(err.contains("bad.pbrt:5:1:"), "{err}");
    assert!(err.contains("\"halton\""), "{err}");
    // A parameter of the wrong type, in the scene: located at the parameter.
    let bad = dir.write(
        "badtype.pbrt",
        &small_scene("").replace(
            "WorldBegin",
            "Sampler \"sobol\" \"float pixelsamples\" 4\nWorldBegin",
        ),
    );
    let o = acr(["render", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_clean_failure(&o, "float pixelsamples");
    let err = stderr(&o);
    assert!(err.contains("badtype.pbrt:5:17:"), "{err}");
    assert!(err.contains("is integer, not float"), "{err}");
    // A misspelled parameter in the scene: a located warning, and the render goes on.
    let typo = dir.write(
        "typo.pbrt",
        &small_scene("").replace(
            "WorldBegin",
            "Sampler \"sobol\" \"integer pixelsampels\" 4\nWorldBegin",
        ),
    );
    let o = render_ok(&typo, &out, &[]);
    let err = stderr(&o);
    assert!(err.contains("typo.pbrt:5:17:"), "{err}");
    assert!(err.contains("did you mean \"pixelsamples\""), "{err}");
}
