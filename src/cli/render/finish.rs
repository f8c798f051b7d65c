//! The steps after the render: the image and the AOVs written, the stats, and the lines that
//! tell how the render ended.

use super::prepare::Job;
use super::run::Rendered;
use super::target::Target;
use super::{Clock, RenderArgs, SamplerCost};
use crate::cli::aov::write_aov;
use crate::cli::output::{reached_spp, End};
use crate::cli::stats::{peak_rss_mb, ByPhase, Rss, Seconds, Stats};
use crate::geometry::Spectrum;
use crate::render::Halt;

/// Shows the final `image`, then writes it and the AOVs that have files of their own.
pub(super) fn write_image_and_aovs(
    args: &RenderArgs,
    job: &Job,
    target: &Target,
    rendered: &mut Rendered,
    image: &[Spectrum],
    clock: &Clock,
) -> Result<(), String> {
    if let Some(d) = &rendered.display {
        d.show(image);
    }
    let fit_partition = job.plugins.filter.fit_partition();
    let out = &target.out;
    if !out.writes_sums(rendered.signalled()) {
        // The image is made; the sums would only raise the peak while the file is written.
        rendered.film.release_sums();
    }
    let end = End {
        spp: rendered.spp,
        halted: rendered.counts.halted,
        signalled: rendered.signalled(),
        seconds: clock.render_seconds(),
        features: rendered.features.as_ref(),
    };
    out.write_final(image, &rendered.film, &end)?;
    let (w, h) = job.size();
    for a in target.aovs.iter().filter(|a| !out.holds(a)) {
        let line = write_aov(
            a,
            w as usize,
            h as usize,
            &rendered.film.pixel_stats(),
            job.plugins.sampler.partition(),
            fit_partition.as_ref(),
            rendered.features.as_ref(),
        )?;
        if !args.quiet {
            eprintln!("{line}");
        }
    }
    Ok(())
}

/// The run's statistics (`--stats`).
pub(super) fn stats(
    args: &RenderArgs,
    job: &Job,
    rendered: &Rendered,
    cost: Option<SamplerCost>,
    clock: &Clock,
) -> Stats {
    let (w, h) = job.size();
    let counts = &rendered.counts;
    let plugins = &job.plugins;
    // A render by bands filtered as it went: that time is the reconstruction's.
    let banded_s = rendered.banded.as_ref().map_or(0.0, |b| b.seconds);
    let render_s = clock.render_seconds() - banded_s;
    let report = plugins.sampler.report();
    Stats {
        scene: args.scene.display().to_string(),
        width: w,
        height: h,
        spp: rendered.spp,
        samples: counts.samples,
        rays: counts.rays,
        threads: rayon::current_num_threads(),
        seed: args.seed,
        sampler: plugins.sampler.name().into(),
        filter: plugins.reconstruction().into(),
        integrator: plugins.integrator.name().into(),
        pipeline: super::pipeline::stats_name(job.pipeline),
        halted: counts.halted,
        halted_by: counts.halted_by.map(Halt::name),
        dims: job
            .scene
            .dims
            .names()
            .into_iter()
            .map(str::to_owned)
            .collect(),
        clusters: report.clusters,
        cells: report.cells,
        rounds: report.rounds,
        fitted_by_degree: plugins.filter.report().fitted_by_degree,
        bands: rendered.banded.as_ref().map(|b| b.bands),
        dropped_samples: counts.dropped,
        seconds: Seconds {
            parse: (clock.parsed - clock.start).as_secs_f64(),
            build: (clock.built - clock.parsed).as_secs_f64(),
            render: render_s,
            sampler: counts.sampler_seconds,
            replay: cost.map(|c| c.replay),
            rerender: cost.map(|c| c.render),
            reconstruct: (clock.reconstructed - clock.measured).as_secs_f64() + banded_s,
            write: (clock.written - clock.reconstructed).as_secs_f64(),
            total: clock.start.elapsed().as_secs_f64(),
        },
        mrays_per_s: if render_s > 0.0 {
            counts.rays as f64 / render_s / 1e6
        } else {
            0.0
        },
        sampler_share: cost.map(|c| c.share),
        sampler_cost_pairs: cost.map(|c| c.pairs),
        peak_rss_mb: peak_rss_mb(),
        peak_rss_mb_by_phase: by_phase(clock, |r| r.peak),
        rss_mb_by_phase: by_phase(clock, |r| r.held),
    }
}

/// One figure of the resident memory at the end of each phase.
fn by_phase(clock: &Clock, figure: fn(&Rss) -> f64) -> ByPhase {
    let [parse, build, render, reconstruct, write] = clock.rss.each_ref().map(figure);
    ByPhase {
        parse,
        build,
        render,
        reconstruct,
        write,
    }
}

/// Writes `stats` as JSON to the `--stats` file, if one is named.
pub(super) fn write_stats(args: &RenderArgs, stats: &Stats) -> Result<(), String> {
    if let Some(path) = &args.stats {
        let json = serde_json::to_string_pretty(stats).map_err(|e| e.to_string())?;
        std::fs::write(path, json + "\n")
            .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    }
    Ok(())
}

/// Tells how the render ended: the samples dropped, an interruption (an error, with how to
/// resume), an early stop and the summary line (without `--quiet`).
pub(super) fn report_end(
    args: &RenderArgs,
    target: &Target,
    rendered: &Rendered,
    stats: &Stats,
) -> Result<(), String> {
    let counts = &rendered.counts;
    let output = &target.out.path;
    let spp = rendered.spp;
    if counts.dropped > 0 {
        eprintln!(
            "warning: {} of {} samples had NaN, infinite or negative radiance and were dropped",
            counts.dropped, counts.samples
        );
    }
    if rendered.signalled() {
        return Err(interrupted(args, target, rendered));
    }
    if counts.halted && !args.quiet {
        let why = match counts.halted_by {
            Some(Halt::Noise) => "noise threshold",
            _ => "time limit",
        };
        eprintln!(
            "{why}: stopped after {} of {} samples per pixel",
            counts.samples / (u64::from(stats.width) * u64::from(stats.height)).max(1),
            spp
        );
    }
    if !args.quiet {
        eprintln!(
            "{}: {}x{}, {spp} spp, {:.2} s render, {:.2} Mrays/s, {} threads -> {}",
            args.scene.display(),
            stats.width,
            stats.height,
            stats.seconds.render,
            stats.mrays_per_s,
            stats.threads,
            output.display()
        );
    }
    Ok(())
}

/// The mutations per pixel an mlt render made (its film holds splats, no samples); `None`
/// for a render whose film holds its samples.
fn mutations_made(rendered: &Rendered, pixels: usize) -> Option<u32> {
    let splats_only = rendered.film.pixel_counts().iter().all(|&n| n == 0);
    (splats_only && rendered.counts.samples > 0)
        .then(|| (rendered.counts.samples / pixels.max(1) as u64).min(u64::from(u32::MAX)) as u32)
}

/// The error of a render a signal stopped: how far it got, where the image so far is, and
/// how to finish it.
fn interrupted(args: &RenderArgs, target: &Target, rendered: &Rendered) -> String {
    let spp = rendered.spp;
    let counts = rendered.film.pixel_counts();
    // sppm's image is not made of filtered samples: its camera samples count its iterations.
    let pixels = counts.len().max(1) as u64;
    let sppm_iterations = (rendered.counts.samples / pixels).min(u64::from(u32::MAX)) as u32;
    let reached = match mutations_made(rendered, counts.len()) {
        Some(m) => m,
        None => reached_spp(&counts).max(sppm_iterations),
    };
    let resume = if target.out.can_merge {
        // The rest's default footprint is this render's unless the command line chose one.
        let footprint = args
            .footprint_spp
            .map_or(String::new(), |n| format!(" --footprint-spp {n}"));
        format!(
            "a mergeable EXR of sample indices {}..{}: render the rest with --sample-offset {} \
             --spp {}{footprint} --mergeable and `acr merge` the two",
            args.sample_offset,
            args.sample_offset + reached,
            args.sample_offset + reached,
            spp.saturating_sub(reached)
        )
    } else {
        "render again to finish it".to_owned()
    };
    format!(
        "interrupted by a signal after {reached} of {spp} samples per pixel; the image so far \
         is in {} ({resume})",
        target.out.path.display()
    )
}
