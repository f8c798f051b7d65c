//! `acr render`: a scene to an image, with AOVs, statistics and the sampler-cost measure.

use super::{parse_seconds, parse_threshold};
use crate::cli::aov::{parse_aovs, write_aov, AovRequest};
use crate::cli::display::Display;
use crate::cli::output::{reached_spp, End, Output};
use crate::cli::replay::{Recording, Replay};
use crate::cli::stats::{median, peak_rss_mb, Seconds, Stats};
use crate::features::FeatureImage;
use crate::image_io::Frame;
use crate::integrator::Integrator;
use crate::registry::{choose_for_scene, Overrides};
use crate::render::{render, render_with_features, Checkpoint, Halt, Stop, MAX_SPP};
use crate::scene::Scene;
use acr_parser::SceneDescription;
use acr_plugins::{Film, SamplePoint, Sampler, Setting};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

/// What an adaptive sampler plans for under `--time-limit`.
#[derive(clap::ValueEnum, serde::Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum TimePlan {
    /// The samples per pixel that fit in the time left, at the speed so far.
    Fit,
    /// Its budget (`--spp`), as without a limit.
    Budget,
}

/// Arguments of `acr render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The .pbrt scene file.
    pub scene: PathBuf,
    /// Output image; the format follows the extension (.exr, .png, .pfm). Default: the Film's
    /// "filename", else the scene's name with .exr.
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Samples per pixel (overrides the scene's Sampler).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: Option<u32>,
    /// Stop after this many seconds of rendering, at the end of the pass under way (every
    /// pixel keeps as many samples as the others); --spp or the scene's budget still caps it.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub time_limit: Option<f64>,
    /// With --time-limit, what an adaptive sampler plans its stages for: `fit`, the samples
    /// per pixel its speed so far says fit in the time left (measured again after every
    /// batch; --spp still caps it), or `budget`, --spp as without a limit (the limit only
    /// stops it, maybe inside its first stage).
    #[arg(long, value_enum, default_value_t = TimePlan::Fit, requires = "time_limit")]
    pub time_plan: TimePlan,
    /// Stop once the image's estimated relative error (the mean over pixels of the standard
    /// error of the pixel's luminance over its mean + 0.01) is below T, at the end of the pass
    /// under way; --spp or the scene's budget still caps it. Any sampler.
    #[arg(long, value_name = "T", value_parser = parse_threshold)]
    pub noise_threshold: Option<f64>,
    /// Samples per pixel before --noise-threshold may stop the render (at least 2).
    #[arg(long, value_name = "N", default_value_t = 4, requires = "noise_threshold",
          value_parser = clap::value_parser!(u32).range(2..=MAX_SPP as i64))]
    pub min_spp: u32,
    /// The sampler, by name (overrides the scene's Sampler; see `acr plugins`).
    #[arg(long)]
    pub sampler: Option<String>,
    /// The reconstruction filter, by name (overrides the scene's PixelFilter).
    #[arg(long)]
    pub filter: Option<String>,
    /// The integrator, by name (overrides the scene's Integrator).
    #[arg(long)]
    pub integrator: Option<String>,
    /// A plugin parameter, KIND.PARAM=VALUE (e.g. sampler.pixelsamples=64, filter.alpha=1);
    /// repeatable, overrides the scene's.
    #[arg(long = "set", value_name = "KIND.PARAM=VALUE")]
    pub set: Vec<String>,
    /// Extra per-pixel outputs, NAME=FILE[,NAME=FILE]: spp (samples per pixel), variance (of
    /// each pixel's mean), clusters (cluster sampler), fitclusters (the clusters the
    /// polynomial filter fitted), albedo, normal, depth (means of the first-hit features, .exr
    /// or .pfm). An .exr holds the values; a .png is false colour scaled by the largest value
    /// (the scale is printed and stored in the PNG). A NAME without a file (albedo, normal,
    /// depth, spp, variance) goes into the output EXR as channels, with pbrt-v4's GBuffer
    /// names (Albedo.R, Ns.X, Z, count, Variance.R...). Repeatable.
    #[arg(long, value_name = "NAME=FILE")]
    pub aov: Vec<String>,
    /// Worker threads (default: every core).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Seed of every random decision; the same seed gives the same image.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write run statistics as JSON to this file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Also measure what the sampler adds to the render's wall time: after the render, its
    /// batches are traced again by a sampler that only replays them, alternating with renders
    /// by a fresh sampler (same image, checked; three of each), and the stats give the median
    /// times and the sampler's share. Holds every point in memory (32 bytes each).
    #[arg(long, conflicts_with_all = ["time_limit", "noise_threshold"])]
    pub sampler_cost: bool,
    /// No progress bar and no summary line.
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// Render only this window of the image, in fractions of it, X0,X1,Y0,Y1 (pbrt-v4's
    /// --cropwindow; overrides the Film's cropwindow). An EXR output keeps the whole frame as
    /// its display window and the crop as its data window, so crops can be merged.
    #[arg(long, value_name = "X0,X1,Y0,Y1", value_parser = parse_window,
          conflicts_with = "pixelbounds")]
    pub cropwindow: Option<[f64; 4]>,
    /// Write the image so far to the output every SECONDS of rendering (default 10), atomically
    /// (a temporary file, then a rename), as pbrt-v4's --write-partial-images. With a
    /// splatting filter it is the image; a reconstruction's fit runs only at the end.
    #[arg(long, value_name = "SECONDS", num_args = 0..=1, default_missing_value = "10",
          value_parser = parse_seconds)]
    pub write_partial_images: Option<f64>,
    /// Render sample indices K to K + spp of each pixel instead of 0 to spp (Cycles' sample
    /// offset): ranges rendered apart with --mergeable merge (`acr merge`) into the render of
    /// them all. Samplers whose points depend on the index alone (random, sobol).
    #[arg(long, value_name = "K", default_value_t = 0)]
    pub sample_offset: u32,
    /// Write an EXR that `acr merge` can combine with renders of other sample ranges: beside
    /// R, G, B, each pixel's weighted radiance sums, filter-weight sum and sample count, and
    /// the header attributes samplesPerPixel and renderTimeSeconds (pbrt-v4's names).
    #[arg(long)]
    pub mergeable: bool,
    /// A quick look: a quarter of the resolution in each direction and 1 sample per pixel, as
    /// pbrt-v4's --quick (overrides --spp).
    #[arg(long, conflicts_with = "sampler_cost")]
    pub quick: bool,
    /// Render only the pixels [X0, X1) x [Y0, Y1) (pbrt-v4's --pixelbounds; overrides the
    /// Film's cropwindow).
    #[arg(long, value_name = "X0,X1,Y0,Y1", value_parser = parse_bounds)]
    pub pixelbounds: Option<[u32; 4]>,
    /// Show the image as it renders in the tev viewer listening at HOST:PORT (pbrt-v4's
    /// --display-server; tev listens on 127.0.0.1:14158 by default): every second, and the
    /// final image at the end.
    #[arg(long, value_name = "HOST:PORT")]
    pub display_server: Option<String>,
}

/// Four comma-separated numbers.
fn four<T: std::str::FromStr>(s: &str) -> Result<[T; 4], String> {
    let parts: Vec<T> = s
        .split(',')
        .map(|v| v.trim().parse::<T>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("\"{s}\" is not four comma-separated numbers X0,X1,Y0,Y1"))?;
    <[T; 4]>::try_from(parts)
        .map_err(|_| format!("\"{s}\" is not four comma-separated numbers X0,X1,Y0,Y1"))
}

/// A crop window: four fractions in [0, 1].
fn parse_window(s: &str) -> Result<[f64; 4], String> {
    let w: [f64; 4] = four(s)?;
    if w.iter().any(|v| !(0.0..=1.0).contains(v)) {
        return Err(format!(
            "\"{s}\": the window's fractions must lie in [0, 1]"
        ));
    }
    Ok(w)
}

/// Pixel bounds: four whole numbers.
fn parse_bounds(s: &str) -> Result<[u32; 4], String> {
    four(s)
}

/// The output path: the command line's, else the Film's filename (relative to the working
/// directory, as pbrt-v3 writes it), else the scene's path with `.exr`.
fn output_path(args: &RenderArgs, film_filename: Option<&str>) -> PathBuf {
    if let Some(o) = &args.output {
        return o.clone();
    }
    match film_filename {
        Some(name) if !name.is_empty() => PathBuf::from(name),
        _ => args.scene.with_extension("exr"),
    }
}

/// What `--sampler-cost` measured: times of the render loop alone, medians over
/// [`SamplerCostRun::PAIRS`] runs each.
#[derive(Clone, Copy, Debug)]
struct SamplerCost {
    /// The render again, by a fresh sampler of the same choice.
    render: f64,
    /// The recorded batches replayed by a sampler doing no work.
    replay: f64,
    /// The median over pairs of (render - replay) / render, each pair run back to back: the
    /// machine's drift cancels within a pair.
    share: f64,
    /// Each pair's [render, replay], in the order run.
    pairs: [[f64; 2]; SamplerCostRun::PAIRS],
}

/// What `--sampler-cost` needs to render the scene again, and the first render's film.
struct SamplerCostRun<'a> {
    desc: &'a SceneDescription,
    scene: &'a Scene,
    overrides: &'a Overrides,
    args: &'a RenderArgs,
    film: &'a Film,
}

impl SamplerCostRun<'_> {
    /// Replays and fresh renders, alternating: single runs on this noisy a machine differ by
    /// tens of percent.
    const PAIRS: usize = 3;

    /// Times replays of `batches` and fresh renders alike, after the first render (which
    /// recorded them) warmed what any render warms: lazily built light distributions, the
    /// thread pool, the caches (against that first render, a replay ran 10% faster with the
    /// random sampler, which does next to nothing). Every sampler and film is kept to the end,
    /// so that each fresh sampler's memory comes fresh from the system, its page faults paid
    /// as in the first render. Every image is checked to be the first's.
    fn measure(&self, batches: Vec<Vec<SamplePoint>>) -> Result<SamplerCost, String> {
        let mut scratch = Vec::new();
        let (mut renders, mut replays, mut kept) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..Self::PAIRS {
            let mut plugins = choose_for_scene(
                self.desc,
                self.scene,
                self.overrides,
                self.args.spp,
                self.args.seed,
                &mut scratch,
            )
            .map_err(|e| e.to_string())?;
            let mut replay =
                Replay::new(plugins.sampler.spp(), plugins.sampler.streams(), &batches);
            let mut films = [plugins.film(self.scene), plugins.film(self.scene)];
            let [replayed, rendered] = &mut films;
            let integrator = &plugins.integrator;
            replays.push(self.time(integrator, replayed, &mut replay, "the replayed batches")?);
            let sampler = plugins.sampler.as_mut();
            renders.push(self.time(integrator, rendered, sampler, "a second render")?);
            kept.push((plugins, films));
        }
        let mut shares: Vec<f64> = renders
            .iter()
            .zip(&replays)
            .map(|(r, p)| (r - p) / r.max(1e-9))
            .collect();
        let pairs = std::array::from_fn(|i| [renders[i], replays[i]]);
        Ok(SamplerCost {
            pairs,
            render: median(&mut renders),
            replay: median(&mut replays),
            share: median(&mut shares).max(0.0),
        })
    }

    /// The render loop's wall time with `sampler`, its image checked.
    fn time(
        &self,
        integrator: &Integrator,
        film: &mut Film,
        sampler: &mut dyn Sampler,
        what: &str,
    ) -> Result<f64, String> {
        let t = Instant::now();
        render(
            self.scene,
            integrator,
            sampler,
            film,
            self.args.seed,
            None,
            None,
        );
        let s = t.elapsed().as_secs_f64();
        if film.pixels() != self.film.pixels() {
            return Err(format!("--sampler-cost: {what} gave another image"));
        }
        Ok(s)
    }
}

/// Renders as `args` say.
pub fn command(args: &RenderArgs) -> Result<(), String> {
    let t_start = Instant::now();
    if let Some(n) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .map_err(|e| format!("cannot start {n} threads: {e}"))?;
    }
    let mut desc = acr_parser::parse_file(&args.scene).map_err(|e| e.to_string())?;
    if args.quick {
        quarter_resolution(&mut desc).map_err(|e| e.to_string())?;
    }
    let spp = if args.quick { Some(1) } else { args.spp };
    let t_parsed = Instant::now();

    let mut warnings = desc.warnings.clone();
    let mut scene = Scene::build(&desc, &mut warnings).map_err(|e| e.to_string())?;
    if let Some(w) = args.cropwindow {
        scene
            .film
            .set_crop_window(w)
            .map_err(|e| format!("--cropwindow {e}"))?;
    }
    if let Some(b) = args.pixelbounds {
        scene
            .film
            .set_pixel_bounds(b)
            .map_err(|e| format!("--pixelbounds {e}"))?;
    }
    let overrides = Overrides {
        sampler: args.sampler.clone(),
        filter: args.filter.clone(),
        integrator: args.integrator.clone(),
        settings: args
            .set
            .iter()
            .map(|s| Setting::parse(s))
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?,
    };
    let mut plugins = choose_for_scene(&desc, &scene, &overrides, spp, args.seed, &mut warnings)
        .map_err(|e| e.to_string())?;
    if args.sample_offset > 0 {
        let fits = plugins
            .sampler
            .spp()
            .checked_add(args.sample_offset)
            .is_some();
        if !fits || !plugins.sampler.set_sample_offset(args.sample_offset) {
            return Err(format!(
                "--sample-offset {}: the {} sampler cannot start its samples there (sample \
                 ranges need a sampler whose points depend on the index alone: random or sobol)",
                args.sample_offset,
                plugins.sampler.name()
            ));
        }
    }
    let splats = plugins.filter.cell_layout().is_none() && !plugins.sampler.reconstructs();
    if args.mergeable && (!splats || plugins.sampler.streams() > 1) {
        return Err(format!(
            "--mergeable needs a splatting filter (box, gaussian, mitchell, sinc, triangle) and \
             a sampler that does not reconstruct the image itself, not {} + {}",
            plugins.sampler.name(),
            plugins.filter.name()
        ));
    }
    if let Some(a) = &desc.accelerator {
        // acr has one acceleration structure; pbrt-v3's choice of its own is moot.
        for p in a.params.iter() {
            p.mark_used();
        }
    }
    warnings.extend(desc.unused_parameter_warnings());
    // A file included twice repeats its warnings word for word: print each once.
    let mut printed = std::collections::HashSet::new();
    for w in &warnings {
        let text = w.to_string();
        if printed.insert(text.clone()) {
            eprintln!("{text}");
        }
    }
    let output = output_path(args, scene.film.filename.as_deref());
    let is_exr = crate::image_io::is_exr(&output);
    if args.mergeable && !is_exr {
        return Err(format!(
            "--mergeable writes an EXR, not {}",
            output.display()
        ));
    }
    check_writable(&output)?;
    let aovs: Vec<AovRequest> = args
        .aov
        .iter()
        .map(|a| parse_aovs(a))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .flatten()
        .collect();
    let frame = Frame {
        width: scene.film.resolution.0 as usize,
        height: scene.film.resolution.1 as usize,
        x0: scene.film.crop[0] as usize,
        y0: scene.film.crop[2] as usize,
    };
    let (w, h) = scene.film.size();
    let mut out = Output {
        path: output.clone(),
        frame,
        size: (w as usize, h as usize),
        scale: scene.film.scale,
        mergeable: args.mergeable,
        can_merge: is_exr && splats && plugins.sampler.streams() == 1,
        offset: args.sample_offset,
        channel_aovs: Vec::new(),
        // Only an EXR carries the hash: a PNG or PFM render does not read the scene again.
        scene: if is_exr {
            crate::cli::output::scene_hash(&desc)
        } else {
            0
        },
    };
    for a in &aovs {
        if out.holds(a) {
            if !is_exr {
                return Err(format!(
                    "--aov {}: AOVs go into the output as channels only when it is an .exr, not \
                     {}",
                    a.name,
                    output.display()
                ));
            }
            if !crate::cli::output::CHANNEL_AOVS
                .iter()
                .any(|(n, _)| *n == a.name)
            {
                return Err(format!(
                    "--aov {}: cannot be a channel of the output (give it a file of its own)",
                    a.name
                ));
            }
            out.channel_aovs.push(a.name.clone());
            continue;
        }
        check_writable(&a.path)?;
        if a.name == "clusters" && plugins.sampler.report().cells.is_none() {
            return Err(format!(
                "--aov clusters: the {} sampler makes no clusters (use --sampler cluster)",
                plugins.sampler.name()
            ));
        }
    }
    let t_built = Instant::now();

    let mut film = plugins.film(&scene);
    let show_progress = !args.quiet && std::io::stderr().is_terminal();
    let bar = show_progress.then(|| {
        let b = indicatif::ProgressBar::new(0);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{wide_bar}] {percent}% samples, eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let spp = plugins.sampler.spp();
    if let Some(t) = args.noise_threshold {
        // An adaptive sampler that can stops where it is settled; the render loop's global
        // check stops any sampler.
        plugins.sampler.stop_at_noise(t, args.min_spp);
    }
    let mut recording = Recording::new(plugins.sampler.as_mut());
    let sampler: &mut dyn Sampler = if args.sampler_cost {
        &mut recording
    } else {
        recording.inner()
    };
    // SIGINT and SIGTERM (what a scheduler sends before it kills) end the render at the end
    // of the pass under way; a second one exits at once.
    let interrupted = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register_conditional_shutdown(signal, 1, Arc::clone(&interrupted))
            .and_then(|_| signal_hook::flag::register(signal, Arc::clone(&interrupted)))
            .map_err(|e| format!("cannot watch for signals: {e}"))?;
    }
    let write_partial = |film: &Film, seconds: f64| {
        if let Err(e) = out.write_partial(film, seconds) {
            eprintln!("warning: partial image: {e}");
        }
    };
    let display = args.display_server.as_deref().and_then(|address| {
        let name = output
            .file_name()
            .map_or_else(|| "acr".to_owned(), |n| n.to_string_lossy().into_owned());
        Display::connect(address, &name, w as usize, h as usize)
    });
    let show = |film: &Film, _: f64| {
        if let Some(d) = &display {
            let scale = film.settings().scale;
            d.show(
                &film
                    .pixels()
                    .into_iter()
                    .map(|c| c * scale)
                    .collect::<Vec<_>>(),
            );
        }
    };
    let mut checkpoints = Vec::new();
    if let Some(s) = args.write_partial_images {
        checkpoints.push(Checkpoint {
            every: std::time::Duration::from_secs_f64(s),
            whole_passes: true,
            look: &write_partial,
        });
    }
    if display.is_some() {
        checkpoints.push(Checkpoint {
            every: std::time::Duration::from_secs(1),
            whole_passes: false,
            look: &show,
        });
    }
    let stop = Stop {
        time_limit: args.time_limit.map(std::time::Duration::from_secs_f64),
        noise_threshold: args.noise_threshold,
        min_spp: args.min_spp,
        plan_to_time: args.time_plan == TimePlan::Fit,
        interrupt: Some(&interrupted),
        checkpoints,
    };
    let mut features = aovs.iter().any(AovRequest::is_feature).then(|| {
        let [x0, x1, y0, y1] = scene.film.crop;
        FeatureImage::new(x0, x1, y0, y1)
    });
    let counts = render_with_features(
        &scene,
        &plugins.integrator,
        sampler,
        &mut film,
        args.seed,
        &stop,
        bar.as_ref(),
        features.as_mut(),
    );
    if let Some(f) = features.as_ref().filter(|f| f.non_finite > 0) {
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
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let t_rendered = Instant::now();
    let cost = if args.sampler_cost {
        let run = SamplerCostRun {
            desc: &desc,
            scene: &scene,
            overrides: &overrides,
            args,
            film: &film,
        };
        Some(run.measure(recording.into_batches())?)
    } else {
        None
    };
    // The measure's renders are no part of the reconstruction.
    let t_measured = Instant::now();

    let image = plugins.image(&film);
    let t_reconstructed = Instant::now();
    if let Some(d) = &display {
        d.show(&image);
    }
    let fit_partition = plugins.filter.fit_partition();
    let signalled = counts.halted_by == Some(Halt::Signal);
    if !out.writes_sums(signalled) {
        // The image is made; the sums would only raise the peak while the file is written.
        film.release_sums();
    }
    let end = End {
        spp,
        halted: counts.halted,
        signalled,
        seconds: (t_rendered - t_built).as_secs_f64(),
        features: features.as_ref(),
    };
    out.write_final(&image, &film, &end)?;
    for a in aovs.iter().filter(|a| !out.holds(a)) {
        let line = write_aov(
            a,
            w as usize,
            h as usize,
            film.pixel_stats(),
            plugins.sampler.partition(),
            fit_partition.as_ref(),
            features.as_ref(),
        )?;
        if !args.quiet {
            eprintln!("{line}");
        }
    }
    let t_written = Instant::now();

    let render_s = (t_rendered - t_built).as_secs_f64();
    let report = plugins.sampler.report();
    let stats = Stats {
        scene: args.scene.display().to_string(),
        width: w,
        height: h,
        spp,
        samples: counts.samples,
        rays: counts.rays,
        threads: rayon::current_num_threads(),
        seed: args.seed,
        sampler: plugins.sampler.name().into(),
        filter: plugins.reconstruction().into(),
        integrator: plugins.integrator.name().into(),
        halted: counts.halted,
        halted_by: counts.halted_by.map(Halt::name),
        dims: scene.dims.names().into_iter().map(str::to_owned).collect(),
        clusters: report.clusters,
        cells: report.cells,
        rounds: report.rounds,
        fitted_by_degree: plugins.filter.report().fitted_by_degree,
        dropped_samples: counts.dropped,
        seconds: Seconds {
            parse: (t_parsed - t_start).as_secs_f64(),
            build: (t_built - t_parsed).as_secs_f64(),
            render: render_s,
            sampler: counts.sampler_seconds,
            replay: cost.map(|c| c.replay),
            rerender: cost.map(|c| c.render),
            reconstruct: (t_reconstructed - t_measured).as_secs_f64(),
            write: (t_written - t_reconstructed).as_secs_f64(),
            total: t_start.elapsed().as_secs_f64(),
        },
        mrays_per_s: if render_s > 0.0 {
            counts.rays as f64 / render_s / 1e6
        } else {
            0.0
        },
        sampler_share: cost.map(|c| c.share),
        sampler_cost_pairs: cost.map(|c| c.pairs),
        peak_rss_mb: peak_rss_mb(),
    };
    if let Some(path) = &args.stats {
        let json = serde_json::to_string_pretty(&stats).map_err(|e| e.to_string())?;
        std::fs::write(path, json + "\n")
            .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    }
    if counts.dropped > 0 {
        eprintln!(
            "warning: {} of {} samples had NaN, infinite or negative radiance and were dropped",
            counts.dropped, counts.samples
        );
    }
    if signalled {
        let reached = reached_spp(film.pixel_stats());
        let resume = if out.can_merge {
            format!(
                "a mergeable EXR of sample indices {}..{}: render the rest with --sample-offset \
                 {} --spp {} --mergeable and `acr merge` the two",
                args.sample_offset,
                args.sample_offset + reached,
                args.sample_offset + reached,
                spp.saturating_sub(reached)
            )
        } else {
            "render again to finish it".to_owned()
        };
        return Err(format!(
            "interrupted by a signal after {reached} of {spp} samples per pixel; the image so \
             far is in {} ({resume})",
            output.display()
        ));
    }
    if counts.halted && !args.quiet {
        let why = match counts.halted_by {
            Some(Halt::Noise) => "noise threshold",
            _ => "time limit",
        };
        eprintln!(
            "{why}: stopped after {} of {} samples per pixel",
            counts.samples / (u64::from(w) * u64::from(h)).max(1),
            spp
        );
    }
    if !args.quiet {
        eprintln!(
            "{}: {w}x{h}, {spp} spp, {:.2} s render, {:.2} Mrays/s, {} threads -> {}",
            args.scene.display(),
            render_s,
            stats.mrays_per_s,
            stats.threads,
            output.display()
        );
    }
    Ok(())
}

/// `--quick`: the Film's resolution divided by 4 in each direction (at least 1 pixel), as
/// pbrt-v4 does; a scene without a Film gets pbrt-v3's default 1280x720, quartered.
fn quarter_resolution(desc: &mut SceneDescription) -> acr_parser::Result<()> {
    use acr_parser::{Param, ParamList, ParamType, PluginDesc, Values};
    let loc = match (&desc.film, &desc.camera) {
        (Some(f), _) => f.loc.clone(),
        (None, Some(c)) => c.plugin.loc.clone(),
        (None, None) => return Ok(()),
    };
    let film = desc.film.get_or_insert_with(|| PluginDesc {
        kind: "image".to_owned(),
        params: ParamList::new(),
        loc: loc.clone(),
    });
    for (name, default) in [("xresolution", 1280), ("yresolution", 720)] {
        let v = film.params.int_or(name, default)?;
        let quarter = Values::Ints(vec![(v / 4).max(1)]);
        film.params
            .push(Param::new(ParamType::Integer, name, quarter, loc.clone()));
    }
    Ok(())
}

/// Fails early, before the render, when the output cannot be written (unknown format or a
/// folder that does not exist), so that no render time is lost.
fn check_writable(output: &Path) -> Result<(), String> {
    let ext = output
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if !matches!(ext.as_str(), "exr" | "png" | "pfm") {
        return Err(format!(
            "{}: cannot write image format \"{ext}\" (acr writes .exr, .png and .pfm)",
            output.display()
        ));
    }
    let dir = output.parent().filter(|d| !d.as_os_str().is_empty());
    if let Some(d) = dir {
        if !d.is_dir() {
            return Err(format!(
                "{}: folder {} does not exist",
                output.display(),
                d.display()
            ));
        }
    }
    Ok(())
}
