//! The `acr` command line, run as a process: `acr render` (outputs, stats file, determinism,
//! errors) and `acr diff`, as ARCHITECTURE.md specifies them.

use acr::image_io::read_image;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh folder under the system's temporary folder, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let dir = std::env::temp_dir().join(format!(
            "acr-cli-{name}-{}-{nanos}-{}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }

    fn join(&self, p: impl AsRef<Path>) -> PathBuf {
        self.0.join(p)
    }

    /// Writes `text` to `name` in this folder and gives its path.
    fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.join(name);
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d).unwrap();
        }
        std::fs::write(&p, text).unwrap();
        p
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn acr_command<I, S>(args: I) -> Command
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    let mut c = Command::new(env!("CARGO_BIN_EXE_acr"));
    c.args(args);
    c
}

/// Runs `acr` with `args` and gives what it printed.
fn acr<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    acr_command(args).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Asserts a clean failure: exit status non-zero, a message, no panic.
fn assert_clean_failure(o: &Output, what: &str) {
    let err = stderr(o);
    assert!(!o.status.success(), "{what}: succeeded; stderr: {err}");
    assert!(o.status.code().is_some(), "{what}: killed by a signal");
    assert!(!err.contains("panicked"), "{what}: {err}");
    assert!(!err.trim().is_empty(), "{what}: no message");
}

/// A small scene: a matte sphere on a floor under a point light and a dim sky, path traced.
/// 24 x 16 (not square, so that swapped sizes show).
fn small_scene(extra_film: &str) -> String {
    format!(
        "LookAt 0 1 -4  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n\
         Film \"image\" \"integer xresolution\" 24 \"integer yresolution\" 16 {extra_film}\n\
         Integrator \"path\" \"integer maxdepth\" 3\nWorldBegin\n\
         LightSource \"point\" \"point3 from\" [1 3 -2] \"rgb I\" [10 10 10]\n\
         LightSource \"infinite\" \"rgb L\" [0.2 0.2 0.2]\n\
         Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
         AttributeBegin\nTranslate 0 0.5 0\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [-3 0 -3  -3 0 3  3 0 3  3 0 -3]\nWorldEnd\n"
    )
}

/// The text of scenes/NAME with the Film's resolution replaced by `w` x `h`.
fn example_scene(name: &str, w: u32, h: u32) -> String {
    let mut text = std::fs::read_to_string(root().join("scenes").join(name)).unwrap();
    for (key, value) in [("xresolution", w), ("yresolution", h)] {
        let pat = format!("\"integer {key}\" [");
        let start = text
            .find(&pat)
            .unwrap_or_else(|| panic!("{name}: no {key}"))
            + pat.len();
        let end = start + text[start..].find(']').unwrap();
        text.replace_range(start..end, &value.to_string());
    }
    text
}

fn read_stats(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}\n{text}", path.display()))
}

fn dims(stats: &serde_json::Value) -> Vec<String> {
    stats["dims"]
        .as_array()
        .unwrap_or_else(|| panic!("dims: {}", stats["dims"]))
        .iter()
        .map(|d| d.as_str().unwrap().to_owned())
        .collect()
}

/// `render SCENE -o OUTPUT`, the start of every render command line here.
fn render_args<'a>(scene: &'a Path, output: &'a Path) -> Vec<&'a OsStr> {
    vec![
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
    ]
}

/// Renders `scene` with `args` after the output and checks the run succeeded.
fn render_ok(scene: &Path, output: &Path, args: &[&str]) -> Output {
    let mut all = render_args(scene, output);
    all.push("--quiet".as_ref());
    all.extend(args.iter().map(OsStr::new));
    let o = acr(&all);
    assert!(o.status.success(), "acr {all:?}: {}", stderr(&o));
    o
}

/// Renders `scene` with `args` after the output and checks it fails cleanly saying `message`.
fn render_fails(scene: &Path, output: &Path, args: &[&str], message: &str) {
    let mut all = render_args(scene, output);
    all.extend(args.iter().map(OsStr::new));
    let o = acr(&all);
    assert_clean_failure(&o, &format!("acr {all:?}"));
    assert!(stderr(&o).contains(message), "{}", stderr(&o));
}

#[test]
fn render_writes_a_png_of_the_film_size_and_every_stats_key() {
    let dir = TempDir::new("png-stats");
    let scene = dir.write("small.pbrt", &small_scene(""));
    let (png, stats_path) = (dir.join("out.png"), dir.join("s.json"));
    let o = render_ok(
        &scene,
        &png,
        &[
            "--spp",
            "2",
            "--seed",
            "9",
            "--stats",
            stats_path.to_str().unwrap(),
        ],
    );
    // --quiet: no summary line (and no progress bar in a pipe).
    assert!(stderr(&o).trim().is_empty(), "{}", stderr(&o));

    assert_eq!(image::image_dimensions(&png).unwrap(), (24, 16));
    let img = read_image(&png, true).unwrap();
    assert!(
        img.pixels.iter().any(|p| p.max_element() > 0.0),
        "black image"
    );

    let s = read_stats(&stats_path);
    let keys = [
        "scene",
        "width",
        "height",
        "spp",
        "samples",
        "rays",
        "threads",
        "seed",
        "sampler",
        "filter",
        "integrator",
        "dims",
        "clusters",
        "dropped_samples",
        "halted",
        "halted_by",
        "seconds",
        "mrays_per_s",
        "peak_rss_mb",
    ];
    let obj = s.as_object().unwrap();
    for k in keys {
        assert!(obj.contains_key(k), "stats lack \"{k}\": {s}");
    }
    assert_eq!(s["scene"].as_str(), scene.to_str());
    let n = |k: &str| {
        s[k].as_u64()
            .unwrap_or_else(|| panic!("{k} is not a whole number: {}", s[k]))
    };
    let (w, h, spp) = (n("width"), n("height"), n("spp"));
    assert_eq!((w, h, spp), (24, 16, 2));
    assert_eq!(n("samples"), w * h * spp);
    assert!(n("rays") >= n("samples"), "{s}");
    assert!(n("threads") >= 1);
    assert_eq!(n("seed"), 9);
    assert_eq!(n("dropped_samples"), 0);
    for k in ["sampler", "filter", "integrator"] {
        assert!(
            s[k].as_str().is_some_and(|v| !v.is_empty()),
            "{k}: {}",
            s[k]
        );
    }
    assert_eq!(s["integrator"], "path");
    assert_eq!(dims(&s), ["x", "y"]);
    // Only the cluster sampler has clusters; a number otherwise would be made up.
    assert!(
        s["clusters"].is_null() || s["sampler"] == "cluster",
        "{}",
        s["clusters"]
    );
    let secs = s["seconds"].as_object().unwrap();
    let mut sum = 0.0;
    for k in ["parse", "build", "render", "reconstruct", "write", "total"] {
        let v = secs
            .get(k)
            .and_then(|v| v.as_f64())
            .unwrap_or_else(|| panic!("seconds.{k} missing: {}", s["seconds"]));
        assert!(v.is_finite() && v >= 0.0, "seconds.{k} = {v}");
        if k != "total" {
            sum += v;
        }
    }
    assert!(
        secs["total"].as_f64().unwrap() >= sum * 0.999,
        "total is less than its parts: {}",
        s["seconds"]
    );
    let mrays = s["mrays_per_s"].as_f64().unwrap();
    assert!(mrays.is_finite() && mrays >= 0.0, "{mrays}");
    let rss = s["peak_rss_mb"].as_f64().unwrap();
    assert!(rss.is_finite() && rss >= 0.0, "{rss}");
    if cfg!(target_os = "linux") {
        assert!(rss > 1.0, "peak RSS {rss} MiB");
    }
}

/// The rendering space's dimensions follow the scene: x y for a static pinhole scene, t with
/// motion, u v with a lens; width, height and samples follow the Film.
#[test]
fn stats_dims_follow_the_scene() {
    let dir = TempDir::new("dims");
    let cases: [(&str, &[&str]); 4] = [
        ("cornell-box.pbrt", &["x", "y"]),
        ("motion-blur.pbrt", &["x", "y", "t"]),
        ("depth-of-field.pbrt", &["x", "y", "u", "v"]),
        ("motion-dof.pbrt", &["x", "y", "t", "u", "v"]),
    ];
    for (i, (name, expected)) in cases.into_iter().enumerate() {
        let (w, h) = (20 + 2 * i as u32, 14 + i as u32);
        let scene = dir.write(name, &example_scene(name, w, h));
        let stats_path = dir.join(format!("{name}.json"));
        let out = dir.join(format!("{name}.exr"));
        render_ok(
            &scene,
            &out,
            &["--spp", "1", "--stats", stats_path.to_str().unwrap()],
        );
        let s = read_stats(&stats_path);
        assert_eq!(dims(&s), expected, "{name}");
        assert_eq!(s["width"].as_u64(), Some(w as u64), "{name}");
        assert_eq!(s["height"].as_u64(), Some(h as u64), "{name}");
        assert_eq!(s["spp"].as_u64(), Some(1), "{name}");
        assert_eq!(s["samples"].as_u64(), Some((w * h) as u64), "{name}");
        let img = read_image(&out, false).unwrap();
        assert_eq!((img.width, img.height), (w as usize, h as usize), "{name}");
    }
}

#[test]
fn exr_and_pfm_outputs_read_back_with_the_film_size() {
    let dir = TempDir::new("formats");
    let scene = dir.write("small.pbrt", &small_scene(""));
    let mut images = Vec::new();
    for ext in ["exr", "pfm", "png"] {
        let out = dir.join(format!("out.{ext}"));
        render_ok(&scene, &out, &["--spp", "2", "--seed", "3"]);
        let img = read_image(&out, false).unwrap_or_else(|e| panic!("{ext}: {e}"));
        assert_eq!((img.width, img.height), (24, 16), "{ext}");
        assert_eq!(img.pixels.len(), 24 * 16, "{ext}");
        images.push(img);
    }
    let (exr, pfm, png) = (&images[0], &images[1], &images[2]);
    assert!(exr.pixels.iter().any(|p| p.max_element() > 0.0));
    // Both hold 32-bit floats, top row first: the same seed gives the same pixels.
    assert_eq!(exr, pfm, "EXR and PFM of the same render differ");
    // The PNG holds the same image in 8-bit sRGB.
    for (i, (f, q)) in exr.pixels.iter().zip(&png.pixels).enumerate() {
        for c in 0..3 {
            let expected = acr::image_io::to_srgb8(f[c]) as f32 / 255.0;
            assert!(
                (q[c] - expected).abs() < 1e-6,
                "pixel {i} channel {c}: PNG {} vs EXR {} ({expected})",
                q[c],
                f[c]
            );
        }
    }
}

/// Runs `cmd` and kills it if it has not finished within `limit`.
fn output_within(mut cmd: Command, limit: Duration) -> Output {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!("still running after {limit:?} (rendering?): {}", stderr(&o));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

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

#[test]
fn an_unknown_output_format_fails_before_rendering() {
    let dir = TempDir::new("jpg");
    let scene = slow_scene(&dir);
    let out = dir.join("out.jpg");
    let o = output_within(
        acr_command([
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
            "--spp".as_ref(),
            "256".as_ref(),
        ]),
        Duration::from_secs(20),
    );
    assert_clean_failure(&o, "-o out.jpg");
    let err = stderr(&o);
    assert!(err.contains("jpg"), "the message names the format: {err}");
    assert!(!out.exists());
}

#[test]
fn a_missing_output_folder_fails_cleanly_before_rendering() {
    let dir = TempDir::new("nofolder");
    let scene = slow_scene(&dir);
    let out = dir.join("missing/deeper/out.png");
    let o = output_within(
        acr_command([
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
            "--spp".as_ref(),
            "256".as_ref(),
        ]),
        Duration::from_secs(20),
    );
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

#[test]
fn the_same_seed_gives_the_same_file_whatever_the_thread_count() {
    let dir = TempDir::new("threads");
    let scene = dir.write("motion-dof.pbrt", &example_scene("motion-dof.pbrt", 40, 30));
    let run = |threads: &str, seed: &str, name: &str| {
        let (out, stats) = (dir.join(name), dir.join(format!("{name}.json")));
        render_ok(
            &scene,
            &out,
            &[
                "--spp",
                "4",
                "--threads",
                threads,
                "--seed",
                seed,
                "--stats",
                stats.to_str().unwrap(),
            ],
        );
        assert_eq!(
            read_stats(&stats)["threads"].as_u64(),
            Some(threads.parse().unwrap()),
            "threads in the stats"
        );
        std::fs::read(&out).unwrap()
    };
    let one = run("1", "5", "one.exr");
    let two = run("2", "5", "two.exr");
    assert!(
        one == two,
        "--threads 1 and 2 with --seed 5 give different files"
    );
    let other = run("2", "6", "other.exr");
    assert!(one != other, "--seed 6 gives the same file as --seed 5");
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

/// The number after `name ` in `acr diff`'s text output.
fn text_field(text: &str, name: &str) -> f64 {
    let mut words = text.split_whitespace();
    words
        .by_ref()
        .find(|w| *w == name)
        .unwrap_or_else(|| panic!("no {name} in {text:?}"));
    let v = words.next().unwrap();
    v.parse()
        .unwrap_or_else(|_| panic!("{name} is {v:?} in {text:?}"))
}

#[test]
fn diff_measures_the_error_between_two_images() {
    let dir = TempDir::new("diff");
    let scene = dir.write("small.pbrt", &small_scene(""));
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    render_ok(&scene, &a, &["--spp", "2", "--seed", "1"]);
    render_ok(&scene, &b, &["--spp", "2", "--seed", "2"]);

    // An image against itself.
    let o = acr([OsStr::new("diff"), a.as_os_str(), a.as_os_str()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(text_field(&stdout(&o), "mse"), 0.0, "{}", stdout(&o));
    assert_eq!(text_field(&stdout(&o), "relmse"), 0.0, "{}", stdout(&o));
    let o = acr([
        OsStr::new("diff"),
        a.as_os_str(),
        a.as_os_str(),
        OsStr::new("--json"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    for k in ["mse", "relmse", "psnr"] {
        assert!(v.get(k).is_some(), "--json lacks {k}: {v}");
    }
    assert_eq!(v["mse"].as_f64(), Some(0.0));
    assert_eq!(v["relmse"].as_f64(), Some(0.0));

    // Two renders with different seeds, against this test's own reckoning (ALGORITHM.md 7).
    let o = acr([
        OsStr::new("diff"),
        a.as_os_str(),
        b.as_os_str(),
        OsStr::new("--json"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let (ia, ib) = (
        read_image(&a, false).unwrap(),
        read_image(&b, false).unwrap(),
    );
    let n = (3 * ia.pixels.len()) as f64;
    let (mut se, mut rel, mut clamped) = (0.0, 0.0, 0.0);
    for (x, r) in ia.pixels.iter().zip(&ib.pixels) {
        for c in 0..3 {
            let (x, r) = (x[c] as f64, r[c] as f64);
            se += (x - r).powi(2);
            rel += (x - r).powi(2) / (r * r + 0.01);
            clamped += (x.clamp(0.0, 1.0) - r.clamp(0.0, 1.0)).powi(2);
        }
    }
    let (mse, relmse, psnr) = (se / n, rel / n, 10.0 * (n / clamped).log10());
    assert!(mse > 0.0);
    let near = |k: &str, want: f64| {
        let got = v[k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k} is not a number: {v}"));
        assert!(
            (got - want).abs() <= 1e-9 * want.abs(),
            "{k}: acr diff says {got}, expected {want}"
        );
    };
    near("mse", mse);
    near("relmse", relmse);
    near("psnr", psnr);
    // The text output agrees (it prints 7 significant digits).
    let o = acr([OsStr::new("diff"), a.as_os_str(), b.as_os_str()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text_mse = text_field(&stdout(&o), "mse");
    assert!((text_mse - mse).abs() <= 1e-6 * mse, "{text_mse} vs {mse}");

    // Images of different sizes cannot be compared.
    let small = dir.write(
        "smaller.pbrt",
        &small_scene("").replace("yresolution\" 16", "yresolution\" 12"),
    );
    let c = dir.join("c.exr");
    render_ok(&small, &c, &["--spp", "1"]);
    assert_eq!(read_image(&c, false).unwrap().height, 12);
    let o = acr([OsStr::new("diff"), a.as_os_str(), c.as_os_str()]);
    assert_clean_failure(&o, "diff of 24x16 and 24x12");
    let err = stderr(&o);
    assert!(
        err.contains("24x16") && err.contains("24x12"),
        "the message gives both sizes: {err}"
    );
    assert!(stdout(&o).trim().is_empty(), "{}", stdout(&o));
}

/// Without -o the Film's "filename" is used, relative to the working directory (as pbrt-v3
/// does), not to the scene's folder; without either, the scene's path with .exr.
#[test]
fn without_an_output_the_films_filename_is_used() {
    let dir = TempDir::new("filmname");
    dir.write(
        "sub/named.pbrt",
        &small_scene("\"string filename\" \"film-name.png\""),
    );
    dir.write("sub/unnamed.pbrt", &small_scene(""));
    let run = |scene: &str| {
        let o = acr_command(["render", scene, "--spp", "1", "--quiet"])
            .current_dir(&dir.0)
            .output()
            .unwrap();
        assert!(o.status.success(), "{scene}: {}", stderr(&o));
    };
    run("sub/named.pbrt");
    let written = dir.join("film-name.png");
    assert!(
        written.is_file(),
        "film-name.png is not in the working directory"
    );
    assert!(!dir.join("sub/film-name.png").exists());
    assert_eq!(image::image_dimensions(&written).unwrap(), (24, 16));

    run("sub/unnamed.pbrt");
    let exr = dir.join("sub/unnamed.exr");
    assert!(exr.is_file(), "no sub/unnamed.exr");
    let img = read_image(&exr, false).unwrap();
    assert_eq!((img.width, img.height), (24, 16));
}

#[test]
fn plugins_lists_every_plugin_with_its_parameters() {
    let o = acr(["plugins"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for name in [
        "random",
        "stratified",
        "halton",
        "sobol",
        "box",
        "triangle",
        "gaussian",
        "mitchell",
        "sinc",
        "path",
        "directlighting",
    ] {
        assert!(
            text.lines().any(|l| l.trim_start().starts_with(name)),
            "{name} missing from:\n{text}"
        );
    }
    for param in [
        "integer pixelsamples",
        "integer xsamples",
        "bool jitter",
        "float alpha",
        "float B",
        "float tau",
        "integer maxdepth",
    ] {
        assert!(text.contains(param), "{param} missing");
    }
}

/// The plugins a render used, from its stats file.
fn plugins_used(stats: &serde_json::Value) -> [String; 3] {
    ["sampler", "filter", "integrator"].map(|k| stats[k].as_str().unwrap_or("?").to_owned())
}

/// The rivals make the image themselves: the stats file names the sampler as the
/// reconstruction, a filter asked for is reported unused, the budget is spent exactly and the
/// file is the same with 1 and 2 threads.
#[test]
fn the_rivals_reconstruct_the_image_themselves() {
    let dir = TempDir::new("rivals");
    let scene = dir.write("s.pbrt", &small_scene(""));
    for name in ["mdas", "gem", "awr"] {
        let (a, b) = (
            dir.join(format!("{name}1.exr")),
            dir.join(format!("{name}2.exr")),
        );
        let stats = dir.join(format!("{name}.json"));
        let o = render_ok(
            &scene,
            &a,
            &[
                "--sampler",
                name,
                "--filter",
                "gaussian",
                "--spp",
                "6",
                "--threads",
                "1",
                "--stats",
                stats.to_str().unwrap(),
            ],
        );
        assert!(
            stderr(&o).contains(&format!(
                "the {name} sampler reconstructs the image itself; filter \"gaussian\" is not used"
            )),
            "{}",
            stderr(&o)
        );
        let s = read_stats(&stats);
        assert_eq!(plugins_used(&s)[..2], [name.to_owned(), name.to_owned()]);
        assert_eq!(s["samples"], 24 * 16 * 6, "{name}: budget");
        assert!(
            s["rounds"].as_u64().unwrap_or(0) >= 2,
            "{name}: adaptive rounds"
        );
        render_ok(
            &scene,
            &b,
            &["--sampler", name, "--spp", "6", "--threads", "2"],
        );
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{name}: 1 and 2 threads differ"
        );
    }
}

#[test]
fn plugins_come_from_the_scene_and_the_command_line_overrides_them() {
    let dir = TempDir::new("plugins");
    let scene = dir.write(
        "s.pbrt",
        &small_scene("")
            .replace(
                "WorldBegin",
                "Sampler \"stratified\" \"integer xsamples\" 2 \"integer ysamples\" 3\n\
                 PixelFilter \"mitchell\" \"float B\" 0.5\nWorldBegin",
            )
            .replace("\"path\"", "\"directlighting\""),
    );
    let (out, stats) = (dir.join("a.exr"), dir.join("a.json"));
    render_ok(&scene, &out, &["--stats", stats.to_str().unwrap()]);
    let s = read_stats(&stats);
    assert_eq!(
        plugins_used(&s),
        ["stratified", "mitchell", "directlighting"]
    );
    assert_eq!(s["spp"], 6, "xsamples x ysamples");
    render_ok(
        &scene,
        &out,
        &[
            "--stats",
            stats.to_str().unwrap(),
            "--sampler",
            "sobol",
            "--filter",
            "gaussian",
            "--integrator",
            "path",
            "--set",
            "sampler.pixelsamples=3",
            "--set",
            "filter.alpha=1.5",
        ],
    );
    let s = read_stats(&stats);
    assert_eq!(plugins_used(&s), ["sobol", "gaussian", "path"]);
    assert_eq!(s["spp"], 3);
    assert_eq!(s["samples"], 3 * 24 * 16);
    // pbrt-v3's names acr lacks map to the nearest, with a warning.
    let scene = dir.write(
        "alias.pbrt",
        &small_scene("").replace(
            "WorldBegin",
            "Sampler \"02sequence\" \"integer pixelsamples\" 2\nWorldBegin",
        ),
    );
    let o = render_ok(&scene, &out, &["--stats", stats.to_str().unwrap()]);
    assert!(stderr(&o).contains("\"02sequence\""), "{}", stderr(&o));
    assert_eq!(read_stats(&stats)["sampler"], "sobol");
    assert_eq!(read_stats(&stats)["spp"], 2);
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

#[test]
fn aovs_write_samples_per_pixel_and_variance() {
    let dir = TempDir::new("aov");
    let scene = dir.write("s.pbrt", &small_scene(""));
    let (spp_exr, spp_png, var_exr) = (
        dir.join("spp.exr"),
        dir.join("spp.png"),
        dir.join("var.exr"),
    );
    let arg = format!("spp={},variance={}", spp_exr.display(), var_exr.display());
    let o = render_ok(
        &scene,
        &dir.join("img.exr"),
        &[
            "--spp",
            "5",
            "--aov",
            &arg,
            "--aov",
            &format!("spp={}", spp_png.display()),
        ],
    );
    let _ = o;
    let counts = read_image(&spp_exr, false).unwrap();
    assert_eq!((counts.width, counts.height), (24, 16));
    assert!(counts.pixels.iter().all(|c| c.x == 5.0), "5 samples each");
    let var = read_image(&var_exr, false).unwrap();
    assert!(var
        .pixels
        .iter()
        .all(|c| c.is_finite() && c.min_element() >= 0.0));
    // The sphere's noisy pixels have some variance; a pixel seeing only the sky has none.
    assert!(var.pixels.iter().any(|c| c.max_element() > 0.0));
    let png = read_image(&spp_png, true).unwrap();
    assert_eq!((png.width, png.height), (24, 16));
    // Every pixel has the highest count: white, the top of the scale.
    assert!(png.pixels.iter().all(|c| c.min_element() > 0.99));
    let bytes = std::fs::read(&spp_png).unwrap();
    let needle = b"5 samples per pixel";
    assert!(
        bytes.windows(needle.len()).any(|w| w == needle),
        "the scale is written into the PNG"
    );
}

/// `--noise-threshold`: a loose threshold stops at `--min-spp` (plus the pass under way), with
/// every pixel at the same count, for every kind of sampler; a tighter one takes more samples
/// and ends with a lower error; one that is never met leaves the budget to `--spp`.
#[test]
fn a_noise_threshold_stops_early_keeps_min_spp_and_spp_caps_it() {
    let dir = TempDir::new("noise");
    // 40,000 pixels: more than a batch, so that a pass is one sample per pixel.
    let scene = dir.write("n.pbrt", &example_scene("cornell-box.pbrt", 200, 200));
    let pixels = 200 * 200;
    let run = |sampler: &str, args: &[&str]| {
        let (out, stats) = (dir.join(format!("{sampler}.exr")), dir.join("n.json"));
        let mut all = vec!["--sampler", sampler, "--seed", "1", "--stats"];
        all.push(stats.to_str().unwrap());
        all.extend_from_slice(args);
        render_ok(&scene, &out, &all);
        read_stats(&stats)
    };
    for sampler in ["stratified", "sobol", "random", "cluster"] {
        let s = run(
            sampler,
            &["--spp", "64", "--noise-threshold", "1e6", "--min-spp", "6"],
        );
        let spp = s["samples"].as_u64().unwrap() as f64 / pixels as f64;
        assert!((6.0..=7.0).contains(&spp), "{sampler}: {spp} spp");
        assert_eq!(s["halted"], true, "{sampler}");
        assert_eq!(s["halted_by"], "noise", "{sampler}");
    }
    // Tighter thresholds: more samples, and the error they stop at is below the threshold.
    let spp_at = |t: &str| {
        let s = run("stratified", &["--spp", "1024", "--noise-threshold", t]);
        s["samples"].as_u64().unwrap() / pixels
    };
    let (loose, tight) = (spp_at("0.3"), spp_at("0.1"));
    assert!(loose < tight && tight < 1024, "{loose} then {tight} spp");
    // Never met: the budget caps it, and nothing says it halted.
    let s = run("stratified", &["--spp", "8", "--noise-threshold", "1e-9"]);
    assert_eq!(s["samples"].as_u64().unwrap(), 8 * pixels);
    assert_eq!(s["halted"], false);
    assert!(s["halted_by"].is_null());
}

#[test]
fn a_time_limit_stops_at_a_whole_pass_and_the_image_stays_complete() {
    let dir = TempDir::new("timelimit");
    let scene = dir.write("slow.pbrt", &example_scene("cornell-box.pbrt", 200, 200));
    let (out, stats, spp_aov) = (dir.join("t.exr"), dir.join("t.json"), dir.join("spp.exr"));
    let mut cmd = acr_command([
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
        "--spp",
        "100000",
        "--time-limit",
        "0.5",
        "--stats",
        stats.to_str().unwrap(),
        "--aov",
        &format!("spp={}", spp_aov.display()),
    ]);
    cmd.stderr(Stdio::piped()).stdout(Stdio::piped());
    let o = output_within(cmd, Duration::from_secs(60));
    assert!(o.status.success(), "{}", stderr(&o));
    let s = read_stats(&stats);
    assert_eq!(s["halted"], true);
    assert_eq!(s["halted_by"], "time");
    let samples = s["samples"].as_u64().unwrap();
    assert!(samples > 0 && samples < 100_000 * 200 * 200);
    // Whole passes: every pixel has the same count, and the image has no hole.
    let counts = read_image(&spp_aov, false).unwrap();
    let first = counts.pixels[0].x;
    assert!(first >= 1.0);
    assert!(counts.pixels.iter().all(|c| c.x == first));
    assert_eq!(first as u64 * 200 * 200, samples);
    let img = read_image(&out, false).unwrap();
    let lit = img.pixels.iter().filter(|c| c.max_element() > 0.0).count();
    assert!(lit > 200 * 200 * 9 / 10, "{lit} lit pixels");
}

#[test]
fn every_sampler_gives_the_same_file_with_one_and_two_threads() {
    // Large enough for several cluster rounds, each planned while the one before is traced.
    let dir = TempDir::new("samplers");
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 64, 48));
    for sampler in ["random", "stratified", "halton", "sobol", "cluster"] {
        let run = |threads: &str| {
            let (out, stats) = (
                dir.join(format!("{sampler}{threads}.exr")),
                dir.join(format!("{sampler}{threads}.json")),
            );
            let args = ["--spp", "8", "--sampler", sampler, "--threads", threads];
            let stats_arg = ["--stats", stats.to_str().unwrap()];
            render_ok(&scene, &out, &[&args[..], &stats_arg[..]].concat());
            if sampler == "cluster" {
                let rounds = read_stats(&stats)["rounds"].as_u64().unwrap();
                assert!(rounds > 2, "{rounds} rounds");
            }
            std::fs::read(&out).unwrap()
        };
        assert!(run("1") == run("2"), "{sampler}: 1 and 2 threads differ");
    }
}

#[test]
fn sampler_cost_replays_the_render_and_reports_the_sampler_s_share() {
    let dir = TempDir::new("cost");
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 64, 48));
    for sampler in ["cluster", "stratified"] {
        let (plain, measured, stats) = (
            dir.join(format!("{sampler}.exr")),
            dir.join(format!("{sampler}-cost.exr")),
            dir.join(format!("{sampler}.json")),
        );
        let args = ["--spp", "8", "--sampler", sampler];
        render_ok(&scene, &plain, &args);
        let cost = ["--sampler-cost", "--stats", stats.to_str().unwrap()];
        render_ok(&scene, &measured, &[&args[..], &cost[..]].concat());
        // Recording the batches changes nothing; the replays and the renders again were
        // checked to give this image.
        assert!(std::fs::read(&plain).unwrap() == std::fs::read(&measured).unwrap());
        let s = read_stats(&stats);
        let replay = s["seconds"]["replay"].as_f64().unwrap();
        let rerender = s["seconds"]["rerender"].as_f64().unwrap();
        let share = s["sampler_share"].as_f64().unwrap();
        assert!(
            replay > 0.0 && rerender > 0.0,
            "{sampler}: {replay} {rerender}"
        );
        // The measure's six renders are not counted as reconstruction (a 64x48 image's
        // reconstruction takes microseconds, a render milliseconds).
        let reconstruct = s["seconds"]["reconstruct"].as_f64().unwrap();
        assert!(
            reconstruct < rerender,
            "{sampler}: reconstruct {reconstruct}"
        );
        assert!((0.0..1.0).contains(&share), "{sampler}: share {share}");
    }
    // Without the flag, neither is reported.
    let stats = dir.join("none.json");
    render_ok(
        &scene,
        &dir.join("none.exr"),
        &["--spp", "1", "--stats", stats.to_str().unwrap()],
    );
    let s = read_stats(&stats);
    for key in ["replay", "rerender"] {
        assert!(s["seconds"][key].is_null(), "{key}");
    }
    assert!(s["sampler_share"].is_null());
}

#[test]
fn the_cluster_sampler_reports_clusters_and_draws_them() {
    let dir = TempDir::new("cluster");
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 40, 30));
    let (out, stats, clusters, ids, spp) = (
        dir.join("c.exr"),
        dir.join("c.json"),
        dir.join("clusters.png"),
        dir.join("clusters.exr"),
        dir.join("spp.exr"),
    );
    let aov = format!("clusters={},spp={}", clusters.display(), spp.display());
    let o = render_ok(
        &scene,
        &out,
        &[
            "--spp",
            "8",
            "--sampler",
            "cluster",
            "--set",
            "sampler.bins=2",
            "--filter",
            "gaussian",
            "--stats",
            stats.to_str().unwrap(),
            "--aov",
            &aov,
            "--aov",
            &format!("clusters={}", ids.display()),
        ],
    );
    let _ = o;
    let s = read_stats(&stats);
    let n = |k: &str| s[k].as_u64().unwrap_or_else(|| panic!("{k}: {s}"));
    // 40 x 30 pixels, 8 cells each (t, u, v in two bins).
    assert_eq!(n("cells"), 40 * 30 * 8);
    assert!(n("clusters") > 1 && n("clusters") < n("cells"), "{s}");
    assert!(n("rounds") >= 1);
    assert_eq!(n("samples"), 40 * 30 * 8, "the budget, spent exactly");
    let sampler_s = s["seconds"]["sampler"].as_f64().unwrap();
    assert!(sampler_s > 0.0 && sampler_s <= s["seconds"]["render"].as_f64().unwrap());
    // The samples went unevenly, never below one per pixel, 8 on average.
    let counts = read_image(&spp, false).unwrap();
    let (lo, hi) = counts
        .pixels
        .iter()
        .fold((f32::MAX, 0.0f32), |(a, b), c| (a.min(c.x), b.max(c.x)));
    assert!(lo >= 1.0 && hi > 8.0, "spp from {lo} to {hi}");
    // The partition: cluster ids in the EXR, colours with dark borders in the PNG.
    let ids = read_image(&ids, false).unwrap();
    let distinct: std::collections::HashSet<u32> = ids.pixels.iter().map(|c| c.x as u32).collect();
    assert!(distinct.len() > 1);
    let png = image::open(&clusters).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (40, 30));
    let colours: std::collections::HashSet<[u8; 3]> = png.pixels().map(|p| p.0).collect();
    assert!(colours.len() > 2, "{} colours", colours.len());
    // Another sampler has no clusters to draw: refused before rendering.
    render_fails(
        &scene,
        &dir.join("x.exr"),
        &[
            "--sampler",
            "sobol",
            "--aov",
            &format!("clusters={}", clusters.display()),
        ],
        "makes no clusters",
    );
    // A knob out of range is a located error.
    render_fails(
        &scene,
        &dir.join("x.exr"),
        &["--sampler", "cluster", "--set", "sampler.omega=-1"],
        "omega -1 is out of range",
    );
}

/// Runs `acr bench MANIFEST --out OUT`, which must succeed; its stderr.
fn bench_ok(manifest: &Path, out: &Path) -> String {
    let o = acr([
        "bench",
        manifest.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    stderr(&o)
}

#[test]
fn bench_writes_csv_plot_and_report_and_survives_a_failing_method() {
    let dir = TempDir::new("bench");
    dir.write("s.pbrt", &small_scene(""));
    let manifest = dir.write(
        "m.toml",
        "title = \"tiny\"\nseed = 3\nthreads = 2\n[budgets]\nspp = [1, 4]\nequal_time = true\n\
         [reference]\nsampler = \"sobol\"\nfilter = \"box\"\nspp = 64\n\
         [[scene]]\nname = \"small\"\npath = \"s.pbrt\"\n\
         [[method]]\nlabel = \"random+box\"\nsampler = \"random\"\nfilter = \"box\"\n\
         [[method]]\nlabel = \"sobol+gaussian\"\nsampler = \"sobol\"\nfilter = \"gaussian\"\n\
         set = [\"filter.alpha=3\"]\n\
         [[method]]\nlabel = \"broken\"\nsampler = \"nosuch\"\n",
    );
    let out = dir.join("out");
    let run = || bench_ok(&manifest, &out);
    let err = run();
    assert!(err.contains("rendering the reference"), "{err}");
    // A progress line per run: 2 budgets x (3 equal-spp + 2 equal-time).
    assert_eq!(err.matches("] small ").count(), 10, "{err}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "scene,method,mode,spp,seconds,samples,spp_reached,mse,relmse,psnr,peak_rss_mb,status,\
         mean_ratio"
    );
    assert_eq!(lines.len(), 11);
    let ok: Vec<&str> = lines[1..]
        .iter()
        .copied()
        .filter(|l| l.contains(",ok,"))
        .collect();
    assert_eq!(ok.len(), 6, "{csv}");
    assert!(lines
        .iter()
        .filter(|l| l.contains("broken"))
        .all(|l| l.contains("failed:") && l.contains("nosuch")));
    // Equal-spp rows took their budget exactly; errors are finite and fall with samples.
    let field = |l: &str, i: usize| l.split(',').nth(i).unwrap().parse::<f64>().unwrap();
    let eq = |m: &str, spp: &str| {
        *lines
            .iter()
            .find(|l| l.starts_with(&format!("small,{m},equal-spp,{spp},")))
            .unwrap()
    };
    for m in ["random+box", "sobol+gaussian"] {
        assert_eq!(field(eq(m, "1"), 6), 1.0);
        assert_eq!(field(eq(m, "4"), 6), 4.0);
        assert!(
            field(eq(m, "4"), 7) < field(eq(m, "1"), 7),
            "{m}: MSE falls"
        );
        // The image mean over the reference's: near 1 for an unbiased method.
        let mean = field(eq(m, "4"), 12);
        assert!((mean - 1.0).abs() < 0.05, "{m}: mean ratio {mean}");
    }
    let plot = std::fs::read(out.join("small.png")).unwrap();
    assert!(plot.len() > 1000 && plot.starts_with(b"\x89PNG"));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("# tiny"));
    assert!(report.contains("**4 runs failed**"), "{report}");
    assert!(report.contains("| 4 | sobol+gaussian |"), "{report}");
    // The reference is cached: a second run does not render it again.
    let err = run();
    assert!(!err.contains("rendering the reference"), "{err}");
}

#[test]
fn bench_measures_the_sampler_s_share_of_wall_time_when_asked() {
    let dir = TempDir::new("bench-cost");
    dir.write("s.pbrt", &small_scene(""));
    let manifest = dir.write(
        "m.toml",
        "seed = 2\nthreads = 2\n[budgets]\nspp = [2]\nequal_time = false\n\
         [sampler_cost]\nspp = [2]\nruns = 2\n\
         [reference]\nsampler = \"sobol\"\nfilter = \"box\"\nspp = 16\n\
         [[scene]]\nname = \"small\"\npath = \"s.pbrt\"\n\
         [[method]]\nlabel = \"random+box\"\nsampler = \"random\"\nfilter = \"box\"\n\
         [[method]]\nlabel = \"cluster+gaussian\"\nsampler = \"cluster\"\nfilter = \"gaussian\"\n\
         [[method]]\nlabel = \"broken\"\nsampler = \"nosuch\"\n",
    );
    let out = dir.join("out");
    let err = bench_ok(&manifest, &out);
    assert_eq!(err.matches("spp sampler cost: ").count(), 3, "{err}");
    assert!(err.contains("3 sampler-cost measures, 1 failed"), "{err}");
    let csv = std::fs::read_to_string(out.join("sampler_cost.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "scene,method,spp,runs,sampler_share,share_min,share_max,rerender_seconds,replay_seconds,status"
    );
    assert_eq!(lines.len(), 4, "{csv}");
    for m in ["random+box", "cluster+gaussian"] {
        let l = lines
            .iter()
            .find(|l| l.starts_with(&format!("small,{m},2,")))
            .unwrap_or_else(|| panic!("{m}: {csv}"));
        assert!(l.ends_with(",ok"), "{l}");
        let f = |i: usize| l.split(',').nth(i).unwrap().parse::<f64>().unwrap();
        assert_eq!(f(3), 2.0, "{l}");
        let (share, lo, hi) = (f(4), f(5), f(6));
        assert!(
            (0.0..1.0).contains(&share) && lo <= share && share <= hi,
            "{l}"
        );
        assert!(f(7) > 0.0 && f(8) > 0.0, "{l}");
    }
    let broken = lines.iter().find(|l| l.contains("broken")).unwrap();
    assert!(
        broken.contains("failed:") && broken.contains("nosuch"),
        "{broken}"
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("## The sampler's share of wall time"),
        "{report}"
    );
    assert!(
        report.contains("| small | 2 | cluster+gaussian | "),
        "{report}"
    );
    assert!(
        report.contains("| small | 2 | broken | failed |"),
        "{report}"
    );
}

#[test]
fn the_polynomial_filter_reconstructs_after_any_sampler_and_reports_its_fits() {
    let dir = TempDir::new("polynomial");
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 40, 30));
    for sampler in ["stratified", "cluster"] {
        let (out, stats) = (dir.join(format!("{sampler}.exr")), dir.join("p.json"));
        let args = [
            "--spp",
            "4",
            "--sampler",
            sampler,
            "--filter",
            "polynomial",
            "--stats",
            stats.to_str().unwrap(),
        ];
        render_ok(&scene, &out, &args);
        let s = read_stats(&stats);
        assert_eq!(s["filter"], "polynomial");
        let fitted: Vec<u64> = s["fitted_by_degree"]
            .as_array()
            .unwrap_or_else(|| panic!("fitted_by_degree: {s}"))
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        assert_eq!(fitted.len(), 3);
        // 5D: degree 1 by default, so no cluster at degree 2, and some fitted at all.
        assert!(
            fitted[0] + fitted[1] > 0 && fitted[2] == 0,
            "{sampler}: {fitted:?}"
        );
        let img = read_image(&out, false).unwrap();
        assert_eq!(img.pixels.len(), 40 * 30);
        assert!(img
            .pixels
            .iter()
            .all(|c| c.is_finite() && c.min_element() >= 0.0));
        assert!(
            img.pixels.iter().any(|c| c.max_element() > 0.0),
            "{sampler}: black image"
        );
    }
    // A bad knob is a located error.
    render_fails(
        &scene,
        &dir.join("bad.exr"),
        &["--filter", "polynomial", "--set", "filter.degree=5"],
        "degree 5 is out of range",
    );
}

/// bench/versus.py (acr alone, as without pbrt binaries): it renders the given scene and puts
/// its table between the markers of the output file, keeping the text around them. Skipped
/// where there is no python3.
#[test]
fn the_comparison_script_writes_its_table_between_the_markers() {
    if Command::new("python3").arg("--version").output().is_err() {
        eprintln!("skipped: no python3");
        return;
    }
    let dir = TempDir::new("versus");
    let scene = dir.write(
        "tiny.pbrt",
        "LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\"\n\
         Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n\
         Sampler \"random\" \"integer pixelsamples\" 2\nWorldBegin\n\
         LightSource \"point\" \"point from\" [0 0 -2]\nShape \"sphere\"\nWorldEnd\n",
    );
    let out = dir.write(
        "report.md",
        "# before\n<!-- versus:begin -->\nold table\n<!-- versus:end -->\nafter\n",
    );
    // bench/versus.py with this acr on `scene`, and `args`.
    let versus = |args: &[&OsStr]| {
        Command::new("python3")
            .arg(root().join("bench/versus.py"))
            .args(["--acr", env!("CARGO_BIN_EXE_acr"), "--scene"])
            .arg(&scene)
            .args(args)
            .output()
            .unwrap()
    };
    let run = versus(&[
        "--threads".as_ref(),
        "1".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.starts_with("# before\n<!-- versus:begin -->\n"),
        "{text}"
    );
    assert!(text.ends_with("<!-- versus:end -->\nafter\n"), "{text}");
    assert!(!text.contains("old table"), "{text}");
    let row = text
        .lines()
        .find(|l| l.starts_with("| tiny |"))
        .unwrap_or_else(|| panic!("no row for the scene: {text}"));
    // | tiny | seconds | peak MiB |: both numbers, the time positive.
    let cells: Vec<&str> = row.trim_matches('|').split('|').map(str::trim).collect();
    assert_eq!(cells.len(), 3, "{row}");
    assert!(cells[1].parse::<f64>().unwrap() > 0.0, "{row}");
    assert!(cells[2].parse::<f64>().unwrap() > 0.0, "{row}");
    // A binary that is not there is a clear error, not a table.
    let bad = versus(&["--pbrt-v4".as_ref(), "/nonexistent/pbrt".as_ref()]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("pbrt-v4 binary /nonexistent/pbrt is not an executable file"),
        "{err}"
    );
}

/// A camera at the origin looking down +z (16 x 16, fov 30) at a matte wall at z = 4 with
/// Kd (0.2, 0.4, 0.6); with `mirror`, a mirror at z = 2 faces the camera and a second matte
/// wall, Kd (0.5, 0.25, 0.1), stands behind it at z = -3, facing +z.
fn feature_scene(mirror: bool) -> String {
    let mut s = String::from(
        "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
         Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
         Sampler \"random\" \"integer pixelsamples\" 8\nWorldBegin\n\
         LightSource \"point\" \"point from\" [0 0 1] \"rgb I\" [5 5 5]\n\
         Material \"matte\" \"rgb Kd\" [0.2 0.4 0.6]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [-9 -9 4  9 -9 4  9 9 4  -9 9 4]\n",
    );
    if mirror {
        s += "AttributeBegin\nMaterial \"mirror\"\n\
              Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
              \"point3 P\" [-9 -9 2  9 -9 2  9 9 2  -9 9 2]\nAttributeEnd\n\
              Material \"matte\" \"rgb Kd\" [0.5 0.25 0.1]\n\
              Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
              \"point3 P\" [-9 -9 -3  9 -9 -3  9 9 -3  -9 9 -3]\n";
    }
    s + "WorldEnd\n"
}

/// `--aov fitclusters`: the polynomial filter's fitted clusters, as ids per pixel. With the
/// first-hit features, no cluster straddles the edge between two albedos; a filter that fits
/// nothing is told so.
#[test]
fn the_fit_clusters_follow_an_albedo_edge() {
    let dir = TempDir::new("fitclusters");
    let scene = dir.write(
        "halves.pbrt",
        "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
         Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
         Sampler \"random\" \"integer pixelsamples\" 16\nWorldBegin\n\
         LightSource \"distant\" \"point from\" [0 0 0] \"point to\" [0 0 1] \"rgb L\" [3 3 3]\n\
         AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.2 0.2 0.2]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [-9 -9 4  0 -9 4  0 9 4  -9 9 4]\nAttributeEnd\n\
         Material \"matte\" \"rgb Kd\" [0.8 0.8 0.8]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [0 -9 4  9 -9 4  9 9 4  0 9 4]\nWorldEnd\n",
    );
    let ids = dir.join("ids.exr");
    let aov = format!("fitclusters={}", ids.display());
    let out = dir.join("o.exr");
    let args = [
        "--filter",
        "polynomial",
        "--set",
        "filter.features=true",
        "--aov",
        &aov,
    ];
    render_ok(&scene, &out, &args);
    let ids = read_image(&ids, false).unwrap();
    let image = read_image(&out, false).unwrap();
    let id = |x: usize, y: usize| ids.pixels[y * 16 + x].x;
    let mut found = std::collections::BTreeSet::new();
    for y in 0..16 {
        for x in 0..16 {
            let v = id(x, y);
            assert!(v >= 0.0 && v.fract() == 0.0, "id {v}");
            found.insert(v as u32);
        }
    }
    // The two albedos' sides, told apart by the image (which side is brighter).
    let left = image.pixels[8 * 16 + 2].x < image.pixels[8 * 16 + 13].x;
    let dark = |x: usize| (x < 8) == left;
    let side = |want: bool| -> std::collections::BTreeSet<u32> {
        (0..256)
            .filter(|i| dark(i % 16) == want)
            .map(|i| id(i % 16, i / 16) as u32)
            .collect()
    };
    let (d, b) = (side(true), side(false));
    assert!(
        d.is_disjoint(&b),
        "a cluster straddles the edge: {d:?} {b:?}"
    );
    // Noise merges: far fewer clusters than pixels.
    assert!(
        found.len() >= 2 && found.len() <= 32,
        "{} clusters",
        found.len()
    );
    render_fails(
        &scene,
        &out,
        &["--filter", "box", "--aov", &aov],
        "the filter fitted no clusters",
    );
}

/// `--aov albedo,normal,depth`: the first non-specular surface's albedo, normal (facing the
/// path) and path length, per pixel, through a mirror too, with either integrator; asking for
/// them leaves the image as it was; a PNG is refused before rendering.
#[test]
fn feature_aovs_hold_the_first_non_specular_surface() {
    let dir = TempDir::new("features");
    let cases = [
        (false, "path", [0.2, 0.4, 0.6], -1.0, 4.0),
        (true, "path", [0.5, 0.25, 0.1], 1.0, 7.0),
        (true, "directlighting", [0.5, 0.25, 0.1], 1.0, 7.0),
    ];
    for (mirror, integrator, albedo, nz, depth) in cases {
        let what = format!("mirror {mirror}, {integrator}");
        let scene = dir.write("f.pbrt", &feature_scene(mirror));
        let (a, n, d) = (dir.join("a.exr"), dir.join("n.pfm"), dir.join("d.exr"));
        let aov = format!(
            "albedo={},normal={},depth={}",
            a.display(),
            n.display(),
            d.display()
        );
        let with = dir.join("with.exr");
        render_ok(&scene, &with, &["--integrator", integrator, "--aov", &aov]);
        let read = |p: &Path| read_image(p, false).unwrap_or_else(|e| panic!("{what}: {e}"));
        let (a, n, d) = (read(&a), read(&n), read(&d));
        assert_eq!(
            (a.width, a.height, n.width, d.height),
            (16, 16, 16, 16),
            "{what}"
        );
        for i in 0..256 {
            let got = a.pixels[i].to_array();
            for c in 0..3 {
                assert!(
                    (got[c] - albedo[c]).abs() < 1e-5,
                    "{what}: albedo {got:?} at {i}"
                );
            }
            let normal = n.pixels[i];
            assert!(
                (normal.z - nz).abs() < 1e-5 && normal.x.abs() < 1e-5,
                "{what}: {normal}"
            );
            // From straight ahead to the corner rays, 20.7 degrees off the axis.
            let t = d.pixels[i].x;
            assert!(
                t >= depth - 1e-3 && t <= depth * 1.071,
                "{what}: depth {t} at {i}"
            );
        }
        // The features do not disturb the render.
        let without = dir.join("without.exr");
        render_ok(&scene, &without, &["--integrator", integrator]);
        assert_eq!(read(&with).pixels, read(&without).pixels, "{what}");
    }
    let scene = dir.write("f.pbrt", &feature_scene(false));
    let png = format!("albedo={}", dir.join("a.png").display());
    render_fails(
        &scene,
        &dir.join("x.exr"),
        &["--aov", &png],
        "must be an .exr or .pfm",
    );
}
