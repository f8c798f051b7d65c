//! What a sampler adds to a render's wall time (`acr render --sampler-cost`): its batches are
//! recorded, then traced again in the same order by a sampler that only gives them back. The
//! image is the same; the difference in wall time from a render by the sampler itself is the
//! sampler's, whether or not its work overlapped tracing.

use acr_plugins::{SamplePoint, Sampler};

/// Records the batches of the sampler it wraps (every point of the render: 32 bytes each).
pub struct Recording<'a> {
    inner: &'a mut dyn Sampler,
    batches: Vec<Vec<SamplePoint>>,
}

impl<'a> Recording<'a> {
    /// Wraps `inner`.
    pub fn new(inner: &'a mut dyn Sampler) -> Self {
        Self {
            inner,
            batches: Vec::new(),
        }
    }

    /// The wrapped sampler, to render without recording.
    pub fn inner(&mut self) -> &mut dyn Sampler {
        &mut *self.inner
    }

    /// The recorded batches, in the order given.
    pub fn into_batches(self) -> Vec<Vec<SamplePoint>> {
        self.batches
    }
}

impl Sampler for Recording<'_> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn spp(&self) -> u32 {
        self.inner.spp()
    }

    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool {
        let more = self.inner.next_batch(out);
        if more {
            self.batches.push(out.clone());
        }
        more
    }

    fn observe(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        self.inner.observe(batch, radiance);
    }

    fn halt(&mut self) {
        self.inner.halt();
    }

    fn wants_guidance(&self) -> bool {
        self.inner.wants_guidance()
    }

    fn guide(&mut self, error: &acr_plugins::sampler::ErrorMap) {
        self.inner.guide(error);
    }

    fn plans_ahead(&self) -> bool {
        self.inner.plans_ahead()
    }

    fn whole_passes(&self) -> bool {
        self.inner.whole_passes()
    }

    fn streams(&self) -> u32 {
        self.inner.streams()
    }
}

/// Gives recorded batches again, in order, doing no work of its own but copying them out.
pub struct Replay<'a> {
    spp: u32,
    streams: u32,
    batches: &'a [Vec<SamplePoint>],
    next: usize,
}

impl<'a> Replay<'a> {
    /// Gives `batches` again, for a render of `spp` samples per pixel in `streams` streams.
    pub fn new(spp: u32, streams: u32, batches: &'a [Vec<SamplePoint>]) -> Self {
        Self {
            spp,
            streams,
            batches,
            next: 0,
        }
    }
}

impl Sampler for Replay<'_> {
    fn name(&self) -> &'static str {
        "replay"
    }

    fn spp(&self) -> u32 {
        self.spp
    }

    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool {
        out.clear();
        let Some(b) = self.batches.get(self.next) else {
            return false;
        };
        out.extend_from_slice(b);
        self.next += 1;
        true
    }

    fn halt(&mut self) {
        // The recording stopped where the time limit stopped it.
    }

    fn plans_ahead(&self) -> bool {
        true
    }

    fn streams(&self) -> u32 {
        self.streams
    }
}
