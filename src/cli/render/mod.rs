//! `acr render`: a scene to an image, with AOVs, statistics and the sampler-cost measure. The
//! command is a sequence of named steps, one file each: prepare the scene and its plugins
//! (`prepare.rs`, with `--pipeline`'s choice in `pipeline.rs`), plan the output files (`target.rs`), render (`run.rs`), measure the
//! sampler's cost (`sampler_cost.rs`), write the image, the AOVs and the stats (`finish.rs`).

use crate::cli::stats::Rss;
use acr_parser::SceneDescription;
use std::time::Instant;

mod args;
mod finish;
mod pipeline;
mod prepare;
mod run;
mod sampler_cost;
mod target;

pub use args::{Pipeline, RenderArgs, TimePlan};
pub use pipeline::{row_for, Row, NFOR_ROW, TABLE};

use prepare::Job;
use run::Rendered;
use sampler_cost::{SamplerCost, SamplerCostRun};
use target::Target;

/// When each step of a render ended, for the stats' seconds.
struct Clock {
    /// The command began.
    start: Instant,
    /// The scene files parsed.
    parsed: Instant,
    /// The scene built, its plugins chosen, its outputs planned.
    built: Instant,
    /// The render loop done.
    rendered: Instant,
    /// `--sampler-cost` measured.
    measured: Instant,
    /// The image reconstructed from the film.
    reconstructed: Instant,
    /// The image and AOVs written.
    written: Instant,
    /// The resident memory at the end of the parse, the build, the render (with
    /// `--sampler-cost`'s measure), the reconstruction and the writing.
    rss: [Rss; 5],
}

impl Clock {
    /// Every step at the start, now.
    fn start() -> Self {
        let now = Instant::now();
        Self {
            start: now,
            parsed: now,
            built: now,
            rendered: now,
            measured: now,
            reconstructed: now,
            written: now,
            rss: [Rss::default(); 5],
        }
    }

    /// Seconds of the render itself (the film made, the samples traced).
    fn render_seconds(&self) -> f64 {
        (self.rendered - self.built).as_secs_f64()
    }
}

/// Renders as `args` say.
pub fn command(args: &RenderArgs) -> Result<(), String> {
    let mut clock = Clock::start();
    prepare::start_threads(args.threads)?;
    let desc = prepare::read_scene(args)?;
    let scene_hash = target::scene_hash_of(args, &desc);
    // Nothing reads the text again but a diagnostic, which reads the file again: freed before
    // the build, it is no part of the peak (docs/BENCHMARKS.md, memory on the interiors).
    for f in &desc.files {
        f.release_text();
    }
    clock.parsed = Instant::now();
    clock.rss[0] = Rss::now();

    let mut job = Job::prepare(args, &desc)?;
    let target = Target::plan(args, &job, scene_hash)?;
    // The render needs the built scene alone (`--sampler-cost` chooses its plugins again from
    // the description): freed before the film is made, the description and the scene text
    // are no part of the peak (docs/BENCHMARKS.md, memory on the interiors).
    let desc = args.sampler_cost.then_some(desc);
    prepare::return_freed_memory();
    clock.built = Instant::now();
    clock.rss[1] = Rss::now();

    let mut rendered = run::render_scene(args, &mut job, &target)?;
    clock.rendered = Instant::now();
    let cost = measure_sampler_cost(args, &job, desc.as_ref(), &mut rendered)?;
    // The measure's renders are no part of the reconstruction.
    clock.measured = Instant::now();
    clock.rss[2] = Rss::now();

    let image = match rendered.banded.as_mut() {
        // A render by bands made its image as it went.
        Some(b) => job
            .plugins
            .finish_image(&rendered.film, std::mem::take(&mut b.image)),
        None => job.plugins.image(&rendered.film),
    };
    clock.reconstructed = Instant::now();
    clock.rss[3] = Rss::now();
    finish::write_image_and_aovs(args, &job, &target, &mut rendered, &image, &clock)?;
    clock.written = Instant::now();
    clock.rss[4] = Rss::now();

    let stats = finish::stats(args, &job, &rendered, cost, &clock);
    finish::write_stats(args, &stats)?;
    finish::report_end(args, &target, &rendered, &stats)
}

/// With `--sampler-cost`: the render's recorded batches replayed, alternating with fresh
/// renders.
fn measure_sampler_cost(
    args: &RenderArgs,
    job: &Job,
    desc: Option<&SceneDescription>,
    rendered: &mut Rendered,
) -> Result<Option<SamplerCost>, String> {
    let (Some(batches), Some(desc)) = (rendered.batches.take(), desc) else {
        return Ok(None);
    };
    let run = SamplerCostRun {
        desc,
        scene: &job.scene,
        overrides: &job.overrides,
        args,
        film: &rendered.film,
    };
    run.measure(batches).map(Some)
}
