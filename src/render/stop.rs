//! When a render stops and what it reports (docs/architecture.md §3): the stop rules, the
//! checkpoints that look at the image on the way, and the counts a render returns. Apart from
//! the render loop so that renderers of their own (sppm) use them without importing it.

use acr_plugins::Film;
use std::time::Duration;

/// A look at the image so far, every `every` of render time (`--write-partial-images`, the
/// display).
pub struct Checkpoint<'a> {
    /// How often.
    pub every: Duration,
    /// Waits, once due, for the film to hold whole passes (every pixel as many samples as the
    /// others, so that a partial image is a sample range that resumes exactly), when the
    /// sampler's batches come in passes ([`Sampler::whole_passes`]; an adaptive one's do not).
    pub whole_passes: bool,
    /// Takes the film, with the render seconds so far.
    pub look: &'a (dyn Fn(&Film, f64) + Sync),
}

/// When a render stops before its sampler's budget is spent.
#[derive(Default)]
pub struct Stop<'a> {
    /// Stop (at the end of the pass under way) once this is set: the signal handler of
    /// SIGINT and SIGTERM sets it.
    pub interrupt: Option<&'a std::sync::atomic::AtomicBool>,
    /// Look at the image so far now and then.
    pub checkpoints: Vec<Checkpoint<'a>>,
    /// Stop once this much render time has passed (at the end of the pass under way).
    pub time_limit: Option<Duration>,
    /// Stop once the image's estimated relative error ([`relative_error`]) is below this (at
    /// the end of the pass under way).
    pub noise_threshold: Option<f64>,
    /// Samples per pixel before the noise threshold is looked at (at least 2: the error
    /// estimate needs a variance).
    pub min_spp: u32,
    /// With a time limit, tell the sampler after every batch how many samples per pixel fit
    /// in the time left at the speed so far ([`Sampler::plan_for`]), so that an adaptive
    /// sampler plans its stages for the time rather than for its budget.
    pub plan_to_time: bool,
    /// The reconstruction's estimate of each pixel's squared error from the film as it
    /// stands ([`acr_plugins::Filter::estimated_error`]), for a sampler that asks for one
    /// ([`Sampler::wants_guidance`]); without it, or where it gives none, the sampler gets
    /// each pixel's variance of the mean.
    pub estimated_error: Option<&'a ErrorEstimate<'a>>,
}

/// A reconstruction's per-pixel estimate of its squared error from a film, if it makes one.
pub type ErrorEstimate<'a> = dyn Fn(&Film) -> Option<Vec<f32>> + Sync + 'a;

impl Stop<'_> {
    /// A time limit alone.
    pub fn time(limit: Option<Duration>) -> Self {
        Self {
            time_limit: limit,
            ..Self::default()
        }
    }
}

/// Why a render stopped before its budget was spent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Halt {
    /// The time limit passed.
    Time,
    /// The image's estimated relative error fell below the noise threshold.
    Noise,
    /// SIGINT or SIGTERM arrived.
    Signal,
}

impl Halt {
    /// The name the stats file gives it.
    pub fn name(self) -> &'static str {
        match self {
            Halt::Time => "time",
            Halt::Noise => "noise",
            Halt::Signal => "signal",
        }
    }
}

/// What a render produced besides the image.
#[derive(Clone, Debug, Default)]
pub struct RenderCounts {
    /// Samples traced.
    pub samples: u64,
    /// Rays traced (camera, continuation and shadow).
    pub rays: u64,
    /// Samples whose radiance was NaN, infinite or negative, dropped before the film.
    pub dropped: u64,
    /// The time limit or the noise threshold stopped the render before the sampler's budget
    /// was spent.
    pub halted: bool,
    /// Which of them did.
    pub halted_by: Option<Halt>,
    /// Wall seconds spent in the sampler (its batches and what it learns from them).
    pub sampler_seconds: f64,
    /// Samples whose first-hit features were not finite, counted when the film's cells keep
    /// features (they take them as 0).
    pub non_finite_features: u64,
}
