//! The render itself: the progress bar, the signals that stop it, the partial images and the
//! display that look at it, and the render loop.

use super::prepare::Job;
use super::target::Target;
use super::{RenderArgs, TimePlan};
use crate::cli::aov::AovRequest;
use crate::cli::display::Display;
use crate::cli::output::Output;
use crate::cli::replay::Recording;
use crate::first_hit::FeatureImage;
use crate::integrator::Integrator;
use crate::render::{render_in_bands, render_with_features, Banded, Bands, Checkpoint, Halt};
use crate::render::{RenderCounts, Stop};
use acr_plugins::{Film, SamplePoint, Sampler};
use std::io::IsTerminal;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

/// What a render made.
pub(super) struct Rendered {
    /// The film, its samples added.
    pub(super) film: Film,
    /// What the render loop counted, and why it stopped.
    pub(super) counts: RenderCounts,
    /// The first-hit features, when an AOV needs them.
    pub(super) features: Option<FeatureImage>,
    /// The viewer the image is shown in (`--display-server`).
    pub(super) display: Option<Display>,
    /// The sampler's batches, recorded under `--sampler-cost`.
    pub(super) batches: Option<Vec<Vec<SamplePoint>>>,
    /// Samples per pixel planned.
    pub(super) spp: u32,
    /// A render by bands: the image its filter made band by band.
    pub(super) banded: Option<Banded>,
}

impl Rendered {
    /// Whether SIGINT or SIGTERM stopped the render.
    pub(super) fn signalled(&self) -> bool {
        self.counts.halted_by == Some(Halt::Signal)
    }
}

/// Renders `job` into a fresh film, with a progress bar on a terminal, stopped by the time
/// limit, the noise threshold or a signal, showing partial images as `args` ask.
pub(super) fn render_scene(
    args: &RenderArgs,
    job: &mut Job,
    target: &Target,
) -> Result<Rendered, String> {
    // The variance AOV reads every pixel's statistics (the spp AOV its count, kept anyway).
    let keep_stats = target.aovs.iter().any(|a| a.name == "variance");
    let window = job
        .by_bands
        .then(|| Bands::window(job.plugins.filter.as_ref(), job.size().1))
        .flatten();
    let mut film = job
        .plugins
        .film_by_rows(&job.scene, window.map(|w| (w, keep_stats)));
    if counts_suffice(args, job, target) {
        film.count_only();
    }
    let bar = progress_bar(args.quiet);
    let spp = match &job.plugins.integrator {
        // What mlt's --spp sets.
        Integrator::Mlt(m) => m.mutations_per_pixel,
        // sppm draws one camera sample per pixel per iteration, whatever the sampler's budget.
        Integrator::Sppm(s) => s.iterations,
        _ => job.plugins.sampler.spp(),
    };
    if matches!(job.plugins.integrator, Integrator::Mlt(_)) {
        refuse_with_mlt(args)?;
    }
    if let Some(t) = args.noise_threshold {
        // An adaptive sampler that can stops where it is settled; the render loop's global
        // check stops any sampler.
        job.plugins.sampler.stop_at_noise(t, args.min_spp);
    }
    let mut recording = Recording::new(job.plugins.sampler.as_mut());
    let sampler: &mut dyn Sampler = if args.sampler_cost {
        &mut recording
    } else {
        recording.inner()
    };
    let interrupted = watch_signals()?;
    let looks = Looks {
        out: &target.out,
        display: connect_display(args, target, job.scene.film.size()),
    };
    let write_partial = |film: &Film, seconds: f64| looks.write_partial(film, seconds);
    let show = |film: &Film, _: f64| looks.show(film);
    let filter = &job.plugins.filter;
    let estimate = |f: &Film| filter.estimated_error(f);
    let mut stop = stop_rules(args, &interrupted, &write_partial, &show, &looks);
    if let Some(limit) = stop.time_limit {
        // An auto pipeline's reconstruction comes out of the limit (docs/cli.md).
        stop.time_limit = Some(limit.saturating_sub(Duration::from_secs_f64(job.reserve)));
    }
    stop.estimated_error = Some(&estimate);
    let mut features = target.aovs.iter().any(AovRequest::is_feature).then(|| {
        let [x0, x1, y0, y1] = job.scene.film.crop;
        FeatureImage::new(x0, x1, y0, y1)
    });
    crate::integrator::bdpt::begin_render(&job.plugins.integrator, &job.scene);
    let bands = window.and_then(|_| Bands::new(&job.scene, filter.as_ref(), sampler, &film));
    let (counts, banded) = match bands {
        Some(mut bands) => {
            let counts = render_in_bands(
                &job.scene,
                &job.plugins.integrator,
                sampler,
                &mut film,
                args.seed,
                &stop,
                bar.as_ref(),
                features.as_mut(),
                &mut bands,
            );
            (counts, Some(bands.finish(&mut film)))
        }
        None => {
            let counts = render_with_features(
                &job.scene,
                &job.plugins.integrator,
                sampler,
                &mut film,
                args.seed,
                &stop,
                bar.as_ref(),
                features.as_mut(),
            );
            (counts, None)
        }
    };
    warn_of_non_finite_features(features.as_ref(), &counts);
    crate::integrator::bdpt::end_render(
        &job.plugins.integrator,
        &job.scene,
        &target.out.path,
        counts.samples,
    )?;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let batches = args.sampler_cost.then(|| recording.into_batches());
    Ok(Rendered {
        film,
        counts,
        features,
        display: looks.display,
        batches,
        spp,
        banded,
    })
}

/// Whether nothing in this render reads the means or deviations of the pixels' own samples,
/// so that the film may count them alone (4 bytes a pixel, not 28; docs/BENCHMARKS.md,
/// memory on the interiors): no AOV, noise threshold, mergeable or
/// partial file, sampler-cost measure, a sampler and a reconstruction that read none, and one
/// sample stream.
fn counts_suffice(args: &RenderArgs, job: &Job, target: &Target) -> bool {
    let plugins = &job.plugins;
    target.aovs.is_empty()
        && args.noise_threshold.is_none()
        && !args.mergeable
        && args.write_partial_images.is_none()
        && !args.sampler_cost
        && job.splats
        && plugins.sampler.streams() == 1
        && !plugins.sampler.reads_film()
        && !plugins.filter.reads_pixel_stats()
}

/// The options mlt cannot honour: it drives its own sampling (Markov chains), keeps no
/// per-pixel error estimate, and normalises its image by its own bootstrap.
fn refuse_with_mlt(args: &RenderArgs) -> Result<(), String> {
    if args.noise_threshold.is_some() {
        return Err(
            "--noise-threshold cannot be used with the mlt integrator: it drives its \
                    own sampling (Markov chains) and keeps no per-pixel error estimate; use \
                    --spp (its mutations per pixel) or --time-limit"
                .to_owned(),
        );
    }
    if args.mergeable || args.sample_offset > 0 {
        return Err(
            "--mergeable and --sample-offset cannot be used with the mlt integrator: \
                    it drives its own sampling (Markov chains) and normalises each render by \
                    its own bootstrap, so sample ranges do not add up"
                .to_owned(),
        );
    }
    Ok(())
}

/// What looks at the image as it renders: the partial images written to the output, the
/// viewer it is shown in.
struct Looks<'t> {
    /// The output the partial images go to.
    out: &'t Output,
    /// The viewer (`--display-server`), if it answered.
    display: Option<Display>,
}

impl Looks<'_> {
    /// Writes the image so far to the output (`--write-partial-images`); a failure is a
    /// warning.
    fn write_partial(&self, film: &Film, seconds: f64) {
        if let Err(e) = self.out.write_partial(film, seconds) {
            eprintln!("warning: partial image: {e}");
        }
    }

    /// Shows the film's image so far in the viewer, if there is one.
    fn show(&self, film: &Film) {
        if let Some(d) = &self.display {
            let scale = film.settings().scale;
            d.show(
                &film
                    .with_splats(film.pixels())
                    .into_iter()
                    .map(|c| c * scale)
                    .collect::<Vec<_>>(),
            );
        }
    }
}

/// The viewer at `--display-server`, shown the output's name and an image of `size`.
fn connect_display(args: &RenderArgs, target: &Target, size: (u32, u32)) -> Option<Display> {
    args.display_server.as_deref().and_then(|address| {
        let name = target
            .out
            .path
            .file_name()
            .map_or_else(|| "acr".to_owned(), |n| n.to_string_lossy().into_owned());
        Display::connect(address, &name, size.0 as usize, size.1 as usize)
    })
}

/// When the render stops early (`interrupted`, the time limit, the noise threshold) and what
/// looks at it on the way: `write_partial` under `--write-partial-images`, `show` every
/// second when `looks` has a viewer.
fn stop_rules<'a>(
    args: &RenderArgs,
    interrupted: &'a AtomicBool,
    write_partial: &'a (dyn Fn(&Film, f64) + Sync),
    show: &'a (dyn Fn(&Film, f64) + Sync),
    looks: &Looks,
) -> Stop<'a> {
    let mut checkpoints = Vec::new();
    if let Some(s) = args.write_partial_images {
        checkpoints.push(Checkpoint {
            every: Duration::from_secs_f64(s),
            whole_passes: true,
            look: write_partial,
        });
    }
    if looks.display.is_some() {
        checkpoints.push(Checkpoint {
            every: Duration::from_secs(1),
            whole_passes: false,
            look: show,
        });
    }
    Stop {
        time_limit: args.time_limit.map(Duration::from_secs_f64),
        noise_threshold: args.noise_threshold,
        min_spp: args.min_spp,
        plan_to_time: args.time_plan == TimePlan::Fit,
        interrupt: Some(interrupted),
        checkpoints,
        estimated_error: None,
    }
}

/// A progress bar of the samples traced, on a terminal and without `--quiet`.
fn progress_bar(quiet: bool) -> Option<indicatif::ProgressBar> {
    let show_progress = !quiet && std::io::stderr().is_terminal();
    show_progress.then(|| {
        let b = indicatif::ProgressBar::new(0);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{wide_bar}] {percent}% samples, eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    })
}

/// SIGINT and SIGTERM (what a scheduler sends before it kills) set the flag returned, which
/// ends the render at the end of the pass under way; a second one exits at once.
#[cfg(unix)]
fn watch_signals() -> Result<Arc<AtomicBool>, String> {
    let interrupted = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register_conditional_shutdown(signal, 1, Arc::clone(&interrupted))
            .and_then(|_| signal_hook::flag::register(signal, Arc::clone(&interrupted)))
            .map_err(|e| format!("cannot watch for signals: {e}"))?;
    }
    Ok(interrupted)
}

/// On systems other than Unix nothing watches for signals: the flag returned is never set,
/// and Ctrl-C ends the process at once, without writing the image so far.
#[cfg(not(unix))]
fn watch_signals() -> Result<Arc<AtomicBool>, String> {
    Ok(Arc::new(AtomicBool::new(false)))
}

/// Warns of samples whose first-hit features were not finite: left out of the feature AOVs,
/// taken as 0 by the polynomial fit's cells.
fn warn_of_non_finite_features(features: Option<&FeatureImage>, counts: &RenderCounts) {
    if let Some(f) = features.filter(|f| f.non_finite > 0) {
        eprintln!(
            "warning: {} samples had non-finite first-hit features; they are left out of the \
             feature AOVs",
            f.non_finite
        );
    }
    if counts.non_finite_features > 0 {
        eprintln!(
            "warning: {} samples had non-finite first-hit features; the polynomial fit's cells \
             took them as 0",
            counts.non_finite_features
        );
    }
}
