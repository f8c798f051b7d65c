//! The command line of `acr render`: its arguments and their parsers.

use crate::cli::{parse_seconds, parse_threshold};
use crate::render::MAX_SPP;
use std::path::PathBuf;

/// What an adaptive sampler plans for under `--time-limit`.
#[derive(clap::ValueEnum, serde::Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum TimePlan {
    /// The samples per pixel that fit in the time left, at the speed so far.
    Fit,
    /// Its budget (`--spp`), as without a limit.
    Budget,
}

/// `--pipeline`: whose sampler and filter render.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pipeline {
    /// The scene's Sampler and PixelFilter, as the command line overrides them.
    Scene,
    /// The pipeline measured best at equal time for the scene's dimensions (docs/cli.md).
    Auto,
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
    /// Whose sampler and filter render: `scene`, the scene's Sampler and PixelFilter as
    /// --sampler and --filter override them; `auto`, the pipeline measured best at equal time
    /// for the scene's dimensions (motion blur, lens), said on stderr and in the stats. Default:
    /// `auto` when --time-limit or --noise-threshold is given and neither the command line nor
    /// the scene names a sampler or filter (nor --mergeable or --sample-offset), else `scene`.
    #[arg(long, value_enum)]
    pub pipeline: Option<Pipeline>,
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
    /// The samples per pixel of the whole render this one is part of, which sets the texture
    /// footprint (camera-ray differentials scaled by 1 / sqrt(N), as pbrt-v3): give every
    /// sample range of one frame the same N, so that they merge into its render. Default:
    /// --sample-offset + the budget (--spp or the scene's; an adaptive sampler's or a time
    /// limit's most), which is the whole render for its first part or its only one.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub footprint_spp: Option<u32>,
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
