//! Two streams of an adaptive sampler, each deciding where the *other* stream's samples go
//! (issue 26, item 3). An adaptive sampler that decides a pixel's count from the samples that
//! then estimate it biases the image: where the rare outcome is the bright one, a pixel whose
//! first samples agree looks settled and keeps its dark estimate. Here two instances of the
//! sampler, each with half the budget, learn only from each other's values; a point's stream is
//! its sample index's parity, the film keeps the streams apart ([`Film::split_streams`]) and
//! the image is the mean of the two streams' images, with equal weights (weights from the
//! counts would bring the dependence back). A stream's first adaptive round is decided from
//! the other's first stage alone; after that, a stream's values still reach its own later
//! rounds through where the other stream's points went (measured in the README: on the
//! cluster sampler that path shifts the mean about as much as the one it replaces, the other
//! way, so one stream stays the default).

use super::{pixel_samples, IndexStream, Sampler, SamplerBuild, SamplerReport, SamplerSetup};
use crate::cluster::CellView;
use crate::film::{Film, Spectrum};
use crate::partition::Partition;
use crate::registry::{int_in, Choice, ParamSpec};
use crate::space::SamplePoint;
use acr_parser::{Param, ParamType, Result, Values};
use std::collections::VecDeque;

/// The `streams` parameter every adaptive sampler declares.
pub(crate) const STREAMS: ParamSpec = ParamSpec::new(
    "streams",
    ParamType::Integer,
    "1",
    "1: one stream, as the method was published; 2: two half-budget streams, each placed by \
     the other's values, their images averaged (measured: the shift of the image mean changes \
     sign and the MSE grows; see the README)",
);

/// Per-pixel count parameters that each stream takes half of.
const HALVED: [(&str, i32); 2] = [("initspp", 1), ("minspp", 0)];

/// Builds the sampler of `build` as two streams when its `streams` parameter is 2 and the
/// budget has at least two samples per pixel; else as one (the default).
pub(crate) fn wrap(
    c: &Choice,
    setup: &SamplerSetup,
    build: SamplerBuild,
) -> Result<Box<dyn Sampler>> {
    let streams = int_in(&c.params, "streams", 1, 1..=2)?;
    let spp = pixel_samples(&c.params, setup)?;
    if streams == 1 || spp < 2 {
        return build(c, setup);
    }
    let shares = [spp.div_ceil(2), spp / 2];
    let mut built = Vec::with_capacity(2);
    for (s, &share) in shares.iter().enumerate() {
        let mut choice = c.clone();
        for (name, least) in HALVED {
            let Some(p) = c.params.get(name) else {
                continue;
            };
            // Out-of-range values are left for the sampler to report.
            if let Values::Ints(v) = &p.values {
                if let [v] = v[..] {
                    if (least..=spp as i32).contains(&v) {
                        let half = ((v + 1 - s as i32) / 2).clamp(least, share as i32);
                        let q = Param::new(p.ty, name, Values::Ints(vec![half]), p.loc.clone());
                        choice.params.push(q);
                    }
                }
            }
        }
        let stream = IndexStream {
            count: 2,
            which: s as u32,
        };
        let setup = SamplerSetup {
            spp: Some(share),
            // Independent points: a stream's values must say nothing of where the other's
            // points lie (one scrambled sequence shared would pair them by strata).
            seed: stream.seed(setup.seed),
            stream,
            // The film collects each stream's cells: the sampler's hold both streams' values.
            reconstruction_reads_cells: false,
            ..*setup
        };
        built.push(build(&choice, &setup)?);
    }
    let second = built.pop().expect("two");
    let first = built.pop().expect("two");
    Ok(Box::new(Paired::new([first, second], spp)))
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
        // Batches alternate between the streams while both have some.
        for _ in 0..2 {
            let s = self.turn;
            self.turn = 1 - s;
            if self.done[s] {
                continue;
            }
            if self.streams[s].next_batch(out) {
                self.given.push_back(s);
                return true;
            }
            self.done[s] = true;
        }
        false
    }

    fn observe(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        let Some(s) = self.given.pop_front() else {
            return;
        };
        self.streams[1 - s].observe_other(batch, radiance);
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

    fn partition(&self) -> Option<&Partition> {
        self.streams[0].partition()
    }

    fn cells(&self) -> Option<CellView<'_>> {
        None
    }

    fn report(&self) -> SamplerReport {
        let [a, b] = [self.streams[0].report(), self.streams[1].report()];
        let sum = |x: Option<u64>, y: Option<u64>| x.map(|x| x + y.unwrap_or(0));
        SamplerReport {
            clusters: sum(a.clusters, b.clusters),
            cells: a.cells,
            rounds: sum(a.rounds, b.rounds),
        }
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
