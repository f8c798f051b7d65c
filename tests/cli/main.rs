//! The `acr` command line, run as a process: `acr render` (outputs, stats file, determinism,
//! errors) and `acr diff`, as docs/cli.md specifies them.

mod aovs;
mod bands;
mod errors;
mod output;
mod pipeline;
mod plugins;
mod stopping;
mod tools;

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

/// Most memory a command run by [`output_within`] may hold: far above what the small scenes
/// the tests give need, and low enough that an unbounded read is stopped in a second or two
/// before it takes the machine.
const MEMORY_LIMIT_KB: u64 = 2 << 20;

/// The resident memory of process `pid` in kB, where the system tells it (Linux).
fn resident_kb(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Runs `cmd` and kills it if it has not finished within `limit`, or (on Linux) once it
/// holds more than [`MEMORY_LIMIT_KB`].
fn output_within(mut cmd: Command, limit: Duration) -> Output {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        let rss = resident_kb(child.id()).unwrap_or(0);
        if start.elapsed() > limit || rss > MEMORY_LIMIT_KB {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!(
                "still running after {:?} (limit {limit:?}), holding {rss} kB (limit \
                 {MEMORY_LIMIT_KB}): {}",
                start.elapsed(),
                stderr(&o)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}
