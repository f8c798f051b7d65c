//! The bench manifest (TOML): scenes, methods, budgets and references, read and checked.

use crate::cli::render::TimePlan;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The manifest: scenes, methods, budgets and references.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// A title for the report.
    #[serde(default)]
    pub title: Option<String>,
    /// Seed of every run (of the references and the sampler-cost runs, when `seeds` is given).
    #[serde(default)]
    pub seed: u64,
    /// Seeds of the compared runs: each run is made once per seed and its row holds the means
    /// over them, so that time-limited rows move less from one bench to the next (default:
    /// `seed` alone).
    #[serde(default)]
    pub seeds: Option<Vec<u64>>,
    /// Worker threads per run (default: every core).
    #[serde(default)]
    pub threads: Option<u32>,
    /// Folder of cached reference renders, relative to the manifest (default `cache`).
    #[serde(default)]
    pub cache: Option<PathBuf>,
    /// The budgets.
    pub budgets: Budgets,
    /// The reference of scenes that name none.
    #[serde(default)]
    pub reference: Option<Reference>,
    /// The scenes.
    #[serde(rename = "scene")]
    pub scenes: Vec<SceneEntry>,
    /// The methods; the first is the baseline of every ratio.
    #[serde(rename = "method")]
    pub methods: Vec<Method>,
    /// Runs that measure the sampler's share of wall time, if any.
    #[serde(default)]
    pub sampler_cost: Option<SamplerCostRuns>,
}

/// The sampler's share of wall time (`acr render --sampler-cost`) of every scene and method,
/// at some budgets: each run is its own process, and the report gives the median over them,
/// since one process's share moves with the machine's load.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SamplerCostRuns {
    /// Samples per pixel to measure at.
    pub spp: Vec<u32>,
    /// Processes per scene, method and budget.
    #[serde(default = "five")]
    pub runs: u32,
}

fn five() -> u32 {
    5
}

/// Most processes per scene, method and budget in a sampler-cost measure.
const MAX_COST_RUNS: u32 = 100;

/// Most seeds a compared run is averaged over.
const MAX_SEEDS: usize = 64;

impl Manifest {
    /// The seeds of the compared runs: `seeds`, or `seed` alone.
    pub fn run_seeds(&self) -> Vec<u64> {
        self.seeds.clone().unwrap_or_else(|| vec![self.seed])
    }
}

/// Samples per pixel to run at, and whether to run equal-time too.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Budgets {
    /// Samples per pixel (equal-spp runs).
    pub spp: Vec<u32>,
    /// Also run every method but the first with `--time-limit` set to the first method's
    /// render time at each budget.
    #[serde(default = "yes")]
    pub equal_time: bool,
    /// Equal-time runs take this `--spp` (a cap: an adaptive sampler plans for what fits in
    /// the time, `--time-plan fit`) instead of what the method's own equal-spp run says fits.
    #[serde(default)]
    pub time_limited_spp: Option<u32>,
}

fn yes() -> bool {
    true
}

/// One scene of the manifest.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneEntry {
    /// Its label in the report.
    pub name: String,
    /// The .pbrt file, relative to the manifest.
    pub path: PathBuf,
    /// Its reference (else the manifest's).
    #[serde(default)]
    pub reference: Option<Reference>,
    /// `--pixelbounds X0,X1,Y0,Y1` of every render of it, the reference's included: a crop
    /// of a large image that fits the bench's time.
    #[serde(default)]
    pub pixelbounds: Option<[u32; 4]>,
}

/// A scene's reference image: a file, or a render by one of the methods at a high budget.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged, deny_unknown_fields)]
pub enum Reference {
    /// A given image (EXR, PFM...), relative to the manifest.
    Image {
        /// The file.
        image: PathBuf,
    },
    /// Rendered at `spp` by the manifest's method labelled `method`, or by the sampler,
    /// filter, integrator and settings given here; cached.
    Render {
        /// A method's label.
        #[serde(default)]
        method: Option<String>,
        /// `--sampler`, when no method is named.
        #[serde(default)]
        sampler: Option<String>,
        /// `--filter`, when no method is named.
        #[serde(default)]
        filter: Option<String>,
        /// `--integrator`, when no method is named.
        #[serde(default)]
        integrator: Option<String>,
        /// `--set` settings, when no method is named.
        #[serde(default)]
        set: Vec<String>,
        /// Samples per pixel.
        spp: u32,
    },
}

impl Reference {
    /// The method a rendered reference uses.
    pub(super) fn method(&self, methods: &[Method]) -> Result<Option<Method>, String> {
        match self {
            Reference::Image { .. } => Ok(None),
            Reference::Render {
                method: Some(label),
                ..
            } => match methods.iter().find(|m| &m.label == label) {
                None => Err(format!("names method \"{label}\", which is not listed")),
                Some(m) if m.is_external() => Err(format!(
                    "names method \"{label}\", which runs a command: a reference is acr's render"
                )),
                Some(m) => Ok(Some(m.clone())),
            },
            Reference::Render {
                method: None,
                sampler,
                filter,
                integrator,
                set,
                ..
            } => Ok(Some(Method {
                label: "reference".to_owned(),
                sampler: sampler.clone(),
                filter: filter.clone(),
                integrator: integrator.clone(),
                set: set.clone(),
                ..Method::default()
            })),
        }
    }
}

/// A sampler + filter (+ integrator) with parameters, under a label; with `command`, an
/// external program run on its render (docs/BENCHMARKS.md, "External methods").
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Method {
    /// Its name in the report (`stratified+box`).
    pub label: String,
    /// `--sampler` (default: the scene's).
    #[serde(default)]
    pub sampler: Option<String>,
    /// `--filter` (default: the scene's).
    #[serde(default)]
    pub filter: Option<String>,
    /// `--integrator` (default: the scene's).
    #[serde(default)]
    pub integrator: Option<String>,
    /// `--set KIND.PARAM=VALUE` settings.
    #[serde(default)]
    pub set: Vec<String>,
    /// `--time-plan` of its time-limited runs (default: `acr render`'s, `fit`).
    #[serde(default)]
    pub time_plan: Option<TimePlan>,
    /// `--aov` channels its render writes into its EXR (what a command reads).
    #[serde(default)]
    pub aov: Option<String>,
    /// A program and its arguments, run in the manifest's folder on the render: `{in}` is
    /// replaced by the rendered EXR, `{out}` by the image it must write, which is scored.
    #[serde(default)]
    pub command: Option<Vec<String>>,
    /// How the command's seconds are counted (default: its whole process's wall time).
    #[serde(default)]
    pub time: Option<CommandTime>,
    /// The format of the command's `{out}`: `pfm` (default) or `exr`.
    #[serde(default)]
    pub output: Option<CommandOutput>,
}

/// How an external command's seconds are counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CommandTime {
    /// The wall time of its whole process, start-up included.
    #[default]
    Wall,
    /// The seconds it prints on its last line of standard output (its own measure, without
    /// an interpreter's start-up).
    Printed,
}

impl CommandTime {
    /// Its name in the manifest and the CSV.
    pub fn name(self) -> &'static str {
        match self {
            CommandTime::Wall => "wall",
            CommandTime::Printed => "printed",
        }
    }
}

/// The format of an external command's `{out}` image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CommandOutput {
    /// Portable float map.
    #[default]
    Pfm,
    /// OpenEXR.
    Exr,
}

impl CommandOutput {
    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            CommandOutput::Pfm => "pfm",
            CommandOutput::Exr => "exr",
        }
    }
}

impl Method {
    /// Whether it runs an external command on its render.
    pub fn is_external(&self) -> bool {
        self.command.is_some()
    }
}

/// A method's command-related keys, checked: a program, `{in}` and `{out}` each named, and
/// `time`/`output` only with a command.
fn check_command(meth: &Method) -> Result<(), String> {
    let label = &meth.label;
    match &meth.command {
        None if meth.time.is_some() || meth.output.is_some() => Err(format!(
            "method \"{label}\": `time` and `output` need a `command`"
        )),
        None => Ok(()),
        Some(argv) if argv.first().is_none_or(|p| p.trim().is_empty()) => {
            Err(format!("method \"{label}\": `command` must name a program"))
        }
        Some(argv) => {
            for slot in ["{in}", "{out}"] {
                if !argv.iter().skip(1).any(|a| a.contains(slot)) {
                    return Err(format!(
                        "method \"{label}\": `command` must pass {slot} to its program"
                    ));
                }
            }
            Ok(())
        }
    }
}

/// How a run was budgeted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// At a number of samples per pixel.
    EqualSpp,
    /// At the first method's time for that number of samples per pixel.
    EqualTime,
}

impl Mode {
    pub(super) fn name(self) -> &'static str {
        match self {
            Mode::EqualSpp => "equal-spp",
            Mode::EqualTime => "equal-time",
        }
    }
}

/// Reads and checks a manifest.
pub fn read_manifest(path: &Path) -> Result<Manifest, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let m: Manifest = toml::from_str(&text).map_err(|e| {
        let (line, col) = e.span().map_or((1, 1), |s| line_col(&text, s.start));
        format!("{}:{line}:{col}: {}", path.display(), e.message())
    })?;
    if m.methods.is_empty() || m.scenes.is_empty() || m.budgets.spp.is_empty() {
        return Err(format!(
            "{}: a manifest needs at least one [[scene]], one [[method]] and one budget",
            path.display()
        ));
    }
    if let Some(&bad) = m
        .budgets
        .spp
        .iter()
        .find(|&&s| s == 0 || s > crate::render::MAX_SPP)
    {
        return Err(format!(
            "{}: budget {bad} spp is out of range",
            path.display()
        ));
    }
    if m.budgets
        .time_limited_spp
        .is_some_and(|s| s == 0 || s > crate::render::MAX_SPP)
    {
        return Err(format!(
            "{}: time_limited_spp is out of range",
            path.display()
        ));
    }
    if let Some(c) = &m.sampler_cost {
        if let Some(&bad) = c
            .spp
            .iter()
            .find(|&&s| s == 0 || s > crate::render::MAX_SPP)
        {
            return Err(format!(
                "{}: sampler_cost budget {bad} spp is out of range",
                path.display()
            ));
        }
        if c.runs == 0 || c.runs > MAX_COST_RUNS {
            return Err(format!(
                "{}: sampler_cost runs {} is out of range (1 to {MAX_COST_RUNS})",
                path.display(),
                c.runs
            ));
        }
    }
    if let Some(seeds) = &m.seeds {
        let distinct: std::collections::HashSet<_> = seeds.iter().collect();
        if seeds.is_empty() || seeds.len() > MAX_SEEDS || distinct.len() < seeds.len() {
            return Err(format!(
                "{}: seeds must list 1 to {MAX_SEEDS} different seeds",
                path.display()
            ));
        }
    }
    let mut labels = std::collections::HashSet::new();
    for meth in &m.methods {
        if !labels.insert(meth.label.as_str()) {
            return Err(format!(
                "{}: method \"{}\" is listed twice",
                path.display(),
                meth.label
            ));
        }
        check_command(meth).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    for s in &m.scenes {
        let Some(r) = s.reference.as_ref().or(m.reference.as_ref()) else {
            return Err(format!(
                "{}: scene \"{}\" has no reference (give it one, or a top-level one)",
                path.display(),
                s.name
            ));
        };
        r.method(&m.methods).map_err(|e| {
            format!(
                "{}: the reference of scene \"{}\" {e}",
                path.display(),
                s.name
            )
        })?;
    }
    Ok(m)
}

fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manifest_errors_are_located() {
        let dir = std::env::temp_dir().join(format!("acr-bench-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("m.toml");
        std::fs::write(&p, "[budgets]\nspp = [1]\nbogus = 3\n").unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("m.toml:3:1:"), "{e}");
        std::fs::write(
            &p,
            "[budgets]\nspp = [1]\n[[scene]]\nname = \"a\"\npath = \"a.pbrt\"\n\
             reference = { method = \"nope\", spp = 4 }\n[[method]]\nlabel = \"x\"\n",
        )
        .unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("names method \"nope\""), "{e}");
        for (section, message) in [
            ("spp = [8]\nruns = 0", "sampler_cost runs 0 is out of range"),
            ("spp = [0]", "sampler_cost budget 0 spp is out of range"),
        ] {
            std::fs::write(
                &p,
                format!(
                    "[budgets]\nspp = [1]\n[sampler_cost]\n{section}\n[reference]\n\
                     sampler = \"sobol\"\nspp = 4\n[[scene]]\nname = \"a\"\npath = \"a.pbrt\"\n\
                     [[method]]\nlabel = \"x\"\n"
                ),
            )
            .unwrap();
            let e = read_manifest(&p).unwrap_err();
            assert!(e.contains(message), "{e}");
        }
        // The time-limited runs' spp and a method's time plan: read, and checked.
        let with = |budgets: &str, method: &str| {
            format!(
                "[budgets]\nspp = [1]\n{budgets}\n[reference]\nsampler = \"sobol\"\nspp = 4\n\
                 [[scene]]\nname = \"a\"\npath = \"a.pbrt\"\n[[method]]\nlabel = \"x\"\n{method}\n"
            )
        };
        std::fs::write(&p, with("time_limited_spp = 64", "time_plan = \"budget\"")).unwrap();
        let m = read_manifest(&p).unwrap();
        assert_eq!(m.budgets.time_limited_spp, Some(64));
        assert_eq!(
            m.methods[0].time_plan,
            Some(crate::cli::render::TimePlan::Budget)
        );
        // Seeds to average over: listed once each.
        for seeds in ["seeds = []", "seeds = [1, 2, 1]"] {
            std::fs::write(&p, format!("{seeds}\n{}", with("", ""))).unwrap();
            let e = read_manifest(&p).unwrap_err();
            assert!(e.contains("seeds must list 1 to 64 different seeds"), "{e}");
        }
        std::fs::write(&p, format!("seeds = [4, 2]\n{}", with("", ""))).unwrap();
        assert_eq!(read_manifest(&p).unwrap().run_seeds(), [4, 2]);
        std::fs::write(&p, format!("seed = 5\n{}", with("", ""))).unwrap();
        assert_eq!(read_manifest(&p).unwrap().run_seeds(), [5]);
        std::fs::write(&p, with("time_limited_spp = 0", "")).unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("time_limited_spp is out of range"), "{e}");
        // External methods: the command must name a program, {in} and {out}; `time` and
        // `output` need a command; a reference cannot be one.
        std::fs::write(
            &p,
            with(
                "",
                "aov = \"albedo,normal\"\ncommand = [\"sh\", \"-c\", \"cp $0 $1\", \"{in}\", \"{out}\"]\n\
                 time = \"printed\"\noutput = \"exr\"",
            ),
        )
        .unwrap();
        let meth = &read_manifest(&p).unwrap().methods[0];
        assert!(meth.is_external());
        assert_eq!(meth.command.as_ref().map(Vec::len), Some(5));
        assert_eq!(meth.aov.as_deref(), Some("albedo,normal"));
        assert_eq!(meth.time, Some(CommandTime::Printed));
        assert_eq!(meth.output.map(CommandOutput::extension), Some("exr"));
        for (method, message) in [
            (
                "command = []",
                "method \"x\": `command` must name a program",
            ),
            (
                "command = [\" \", \"{in}\", \"{out}\"]",
                "must name a program",
            ),
            (
                "command = [\"cp\", \"{in}\"]",
                "`command` must pass {out} to its program",
            ),
            (
                "command = [\"{in}\", \"{out}\"]",
                "`command` must pass {in} to its program",
            ),
            ("time = \"wall\"", "`time` and `output` need a `command`"),
            ("output = \"pfm\"", "`time` and `output` need a `command`"),
        ] {
            std::fs::write(&p, with("", method)).unwrap();
            let e = read_manifest(&p).unwrap_err();
            assert!(e.contains(message), "{method}: {e}");
        }
        std::fs::write(
            &p,
            with(
                "",
                "command = [\"cp\", \"{in}\", \"{out}\"]\ntime = \"cpu\"",
            ),
        )
        .unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("m.toml:13:8:") && e.contains("printed"), "{e}");
        std::fs::write(
            &p,
            "[budgets]\nspp = [1]\n[[scene]]\nname = \"a\"\npath = \"a.pbrt\"\n\
             reference = { method = \"x\", spp = 4 }\npixelbounds = [0, 4, 0, 2]\n\
             [[method]]\nlabel = \"x\"\ncommand = [\"cp\", \"{in}\", \"{out}\"]\n",
        )
        .unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("which runs a command"), "{e}");
        std::fs::write(&p, with("", "time_plan = \"soon\"")).unwrap();
        let e = read_manifest(&p).unwrap_err();
        assert!(e.contains("m.toml:12:13:") && e.contains("fit"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
