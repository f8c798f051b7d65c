//! Two streams of an adaptive sampler whose decisions never read the values they decide
//! (docs/algorithm.md §8). An adaptive sampler that decides a pixel's count from the samples that
//! then estimate it biases the image: where the rare outcome is the bright one, a pixel whose
//! first samples agree looks settled and keeps its dark estimate. A point's stream is its
//! sample index's parity and the film keeps the streams apart ([`Film::split_streams`]); the
//! image is a blend of the two streams' images with fixed weights (weights from the counts
//! would bring the dependence back). Two layouts:
//! - `pilot` (a share a of the budget): a value-blind pilot stream, every pixel the same count,
//!   traced first; the adaptive stream decides from the pilot's values alone (its own are
//!   never read) and gives every pixel at least one sample; the image is a * pilot + (1 - a) *
//!   adaptive. No path leads from a value to its own pixel's weight: unbiased.
//! - `streams 2`: two half-budget instances, each learning only from the other's values, the
//!   image their mean. After the first adaptive round a stream's values still reach its own
//!   later rounds through where the other stream's points went (measured: docs/rivals.md).

use super::{
    alternate, pixel_samples, IndexStream, Sampler, SamplerBuild, SamplerReport, SamplerSetup,
};
use crate::cells::CellView;
use crate::film::{Film, Spectrum};
use crate::partition::Partition;
use crate::registry::{error_at_param, float_in, int_in, Choice, ParamSpec};
use crate::space::SamplePoint;
use acr_parser::{Param, ParamType, Result, Values};
use std::collections::VecDeque;

/// The `streams` parameter every adaptive sampler declares: kept as a measured comparison.
pub(crate) const STREAMS: ParamSpec = ParamSpec::new(
    "streams",
    ParamType::Integer,
    "1",
    "1: one stream, as the method was published; 2: two half-budget streams, each placed by \
     the other's values, their images averaged. A comparison: measured, the shift of the \
     image mean changes sign rather than vanishing and the MSE mostly grows (0.45x to 8.7x \
     one stream's); for an unbiased mean set unbiased (cluster, gem, awr) or pilot (mdas); \
     see docs/cluster-sampler.md",
);

/// The `pilot` parameter of the samplers that also have `unbiased` (cluster, gem, awr): kept
/// as a measured comparison.
pub(crate) const PILOT: ParamSpec = ParamSpec::new(
    "pilot",
    ParamType::Float,
    "0",
    "share of the budget traced first as a value-blind pilot stream that alone decides where \
     the rest goes; the image blends the two with fixed weights, so the mean is unbiased \
     (0: off). A comparison: unbiased does the same without splitting the budget, where the \
     pilot's points lose their stratification with the rest (measured: a higher MSE); see \
     docs/cluster-sampler.md",
);

/// The `pilot` parameter of mdas, which has no `unbiased`: its way out of selection bias.
pub(crate) const PILOT_ONLY: ParamSpec = ParamSpec::new(
    "pilot",
    ParamType::Float,
    "0",
    "share of the budget traced first as a value-blind pilot stream that alone decides where \
     the rest goes; the image blends the two with fixed weights, so no value decides its own \
     pixel's weight (0: off, decisions read every value, as the method was published). \
     mdas's way out of selection bias (pilot 0.25 measured 0.6x to 6x the published MSE); \
     its leaves' means still shift the image (-0.7% on the Cornell box); see docs/rivals.md",
);

/// Per-pixel count parameters that each stream takes half of.
const HALVED: [(&str, u32); 2] = [("initspp", 1), ("minspp", 0)];

/// Builds the sampler of `build` as a pilot and an adaptive stream when its `pilot` share is
/// above 0, as two streams when its `streams` parameter is 2, and as one otherwise (the
/// default); a budget under two samples per pixel is always one stream.
pub(crate) fn wrap(
    c: &Choice,
    setup: &SamplerSetup,
    build: SamplerBuild,
) -> Result<Box<dyn Sampler>> {
    let streams = int_in(&c.params, "streams", 1, 1..=2)?;
    let pilot = float_in(&c.params, "pilot", 0.0, 0.0..=0.9)?;
    let spp = pixel_samples(&c.params, setup)?;
    if pilot > 0.0 && streams == 2 {
        let message = "a sampler takes a pilot stream or two streams, not both";
        return Err(error_at_param(
            &c.params,
            &["pilot", "streams"],
            "sampler",
            message,
        ));
    }
    if spp < 2 || (streams == 1 && pilot == 0.0) {
        return build(c, setup);
    }
    if pilot > 0.0 {
        return with_pilot(c, setup, build, pilot, spp);
    }
    let shares = [spp.div_ceil(2), spp / 2];
    let mut built = Vec::with_capacity(2);
    for (s, &share) in shares.iter().enumerate() {
        let mut choice = c.clone();
        for (name, least) in HALVED {
            if let Some(v) = given_count(c, name, least..=spp) {
                let half = ((v + 1 - s as u32) / 2).clamp(least, share);
                choice = with_int(&choice, name, half);
            }
        }
        built.push(build(&choice, &stream_setup(setup, s as u32, share))?);
    }
    let second = built.pop().expect("two");
    let first = built.pop().expect("two");
    Ok(Box::new(Paired::new([first, second], spp)))
}

/// The setup of stream `which` of two, `spp` samples per pixel: its own seed (independent
/// points: a stream's values must say nothing of where the other's points lie, as one
/// scrambled sequence shared would pair them by strata) and its own sample indices.
fn stream_setup(setup: &SamplerSetup, which: u32, spp: u32) -> SamplerSetup {
    let stream = IndexStream { count: 2, which };
    SamplerSetup {
        spp: Some(spp),
        seed: stream.seed(setup.seed),
        stream,
        // The film collects each stream's cells: the sampler's hold the other stream's values.
        reconstruction_reads_cells: false,
        ..*setup
    }
}

/// The one integer value of parameter `name` of `c` when given and within `range`; values out
/// of range are left for the sampler to report.
fn given_count(c: &Choice, name: &str, range: std::ops::RangeInclusive<u32>) -> Option<u32> {
    match c.params.get(name).map(|p| &p.values) {
        Some(Values::Ints(v)) => match v[..] {
            [v] => u32::try_from(v).ok().filter(|v| range.contains(v)),
            _ => None,
        },
        _ => None,
    }
}

/// `c` with the integer parameter `name` set to `v` (a later parameter overrides).
fn with_int(c: &Choice, name: &str, v: u32) -> Choice {
    let mut choice = c.clone();
    // Where the value came from, for an error that names it: the parameter, the directive,
    // or else the pilot's own setting.
    let loc = c
        .params
        .get(name)
        .map(|p| p.loc.clone())
        .or_else(|| c.loc.clone())
        .unwrap_or_else(|| acr_parser::Loc::new(&acr_parser::SourceFile::new("sampler", ""), 0));
    choice.params.push(Param::new(
        ParamType::Integer,
        name,
        Values::Ints(vec![v as i32]),
        loc,
    ));
    choice
}

/// A pilot stream of `pilot` of the budget (at least one sample per pixel, at most all but
/// one), every pixel alike, and the adaptive stream placed from the pilot's values alone.
fn with_pilot(
    c: &Choice,
    setup: &SamplerSetup,
    build: SamplerBuild,
    pilot: f64,
    spp: u32,
) -> Result<Box<dyn Sampler>> {
    let first = ((f64::from(spp) * pilot).round() as u32).clamp(1, spp - 1);
    // The pilot is the first stage's whole budget: it never adapts.
    let mut pilot_choice = with_int(c, "initspp", first);
    // The adaptive stream's own first stage is one sample per pixel: every pixel needs one for
    // its fixed-weight mean, and the pilot already did what a first stage is for. A minimum
    // count the user asked for is met by both streams together.
    let rest = spp - first;
    let mut adaptive_choice = with_int(c, "initspp", 1);
    if let Some(least) = given_count(c, "minspp", 0..=spp) {
        pilot_choice = with_int(&pilot_choice, "minspp", least.min(first));
        let left = least.saturating_sub(first);
        adaptive_choice = with_int(&adaptive_choice, "minspp", left);
    }
    let pilot_stream = build(&pilot_choice, &stream_setup(setup, 0, first))?;
    let adaptive = build(&adaptive_choice, &stream_setup(setup, 1, rest))?;
    let mut paired = Paired::new([pilot_stream, adaptive], spp);
    paired.pilot = Some(f64::from(first) / f64::from(spp));
    Ok(Box::new(paired))
}

/// Two streams of one adaptive sampler, each fed the other's values.
pub(crate) struct Paired {
    streams: [Box<dyn Sampler>; 2],
    spp: u32,
    /// The stream of each batch given and not yet observed, oldest first.
    given: VecDeque<usize>,
    /// The stream asked next.
    turn: usize,
    /// Streams whose budget is spent.
    done: [bool; 2],
    /// With a pilot (stream 0), its share of the budget: its weight in the image. The pilot is
    /// traced first, and only the adaptive stream learns.
    pilot: Option<f64>,
}

impl Paired {
    /// The streams `streams`, `spp` samples per pixel between them.
    pub(crate) fn new(streams: [Box<dyn Sampler>; 2], spp: u32) -> Self {
        Self {
            streams,
            spp,
            given: VecDeque::new(),
            turn: 0,
            done: [false; 2],
            pilot: None,
        }
    }
}

impl Sampler for Paired {
    fn name(&self) -> &'static str {
        self.streams[0].name()
    }

    fn spp(&self) -> u32 {
        self.spp
    }

    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool {
        out.clear();
        // A pilot goes first, whole: the adaptive stream decides from all of it.
        if self.pilot.is_some() && !self.done[0] {
            self.turn = 0;
        }
        // Otherwise batches alternate between the streams while both have some.
        let streams = &mut self.streams;
        let given = alternate(&mut self.turn, &mut self.done, |s| {
            streams[s].next_batch(out)
        });
        let Some(s) = given else {
            return false;
        };
        self.given.push_back(s);
        true
    }

    fn observe(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        let Some(s) = self.given.pop_front() else {
            return;
        };
        // The pilot learns the adaptive stream's values only to make that stream's image
        // (mdas, gem, awr); its own points never depend on them.
        if self.pilot.is_none() || s == 0 || self.streams[0].reconstructs() {
            self.streams[1 - s].observe_other(batch, radiance);
        }
        self.streams[s].retire(batch);
    }

    fn halt(&mut self) {
        for s in &mut self.streams {
            s.halt();
        }
    }

    fn plans_ahead(&self) -> bool {
        // Either stream may be asked next (one may turn out spent): both must allow it.
        (0..2)
            .filter(|&s| !self.done[s])
            .all(|s| self.streams[s].plans_ahead())
    }

    fn streams(&self) -> u32 {
        2
    }

    fn stream_weight(&self) -> f64 {
        self.pilot.unwrap_or(0.5)
    }

    fn partition(&self) -> Option<&Partition> {
        // With a pilot, the clusters are the adaptive stream's.
        self.streams[usize::from(self.pilot.is_some())].partition()
    }

    fn cells(&self) -> Option<CellView<'_>> {
        None
    }

    fn report(&self) -> SamplerReport {
        SamplerReport::combined(self.streams[0].report(), self.streams[1].report())
    }

    fn reconstructs(&self) -> bool {
        self.streams[0].reconstructs()
    }

    fn reconstruct(&self, film: &Film) -> Option<Vec<Spectrum>> {
        if !self.reconstructs() {
            return None;
        }
        // Each stream's state holds the other stream's values: it makes that stream's image.
        Some(film.per_stream(|f, s| {
            self.streams[1 - s]
                .reconstruct(f)
                .unwrap_or_else(|| f.pixels())
        }))
    }
}
