//! mlt's sampler: pbrt-v3's `MLTSampler`, a point of primary sample space that a Markov chain
//! mutates (docs/light-transport.md, `## mlt`). Its coordinates are created lazily as the path
//! asks for them; a large step draws them afresh, a small step moves each by a Gaussian of
//! width `sigma` (wrapped into [0, 1)), and a rejected proposal restores the ones it moved.

use super::gaussian::Ziggurat;
use crate::stream::{mix64, Pcg32, SampleSource};

/// The sample streams pbrt-v3's mlt interleaves: the camera subpath's, the light subpath's
/// and the connection's decisions, each in coordinates of its own.
pub const STREAM_COUNT: u32 = 3;
/// The camera subpath's stream.
pub const CAMERA_STREAM: u32 = 0;
/// The light subpath's stream.
pub const LIGHT_STREAM: u32 = 1;
/// The connection's stream.
pub const CONNECTION_STREAM: u32 = 2;

/// One coordinate of primary sample space (pbrt-v3's `PrimarySample`).
#[derive(Clone, Copy, Debug, Default)]
struct PrimarySample {
    /// Its value in [0, 1).
    value: f32,
    /// The iteration that last changed it.
    last_modified: u64,
    /// The value before the proposal under way, restored if it is rejected.
    value_backup: f32,
    /// `last_modified` before the proposal under way.
    modify_backup: u64,
}

impl PrimarySample {
    fn backup(&mut self) {
        self.value_backup = self.value;
        self.modify_backup = self.last_modified;
    }

    fn restore(&mut self) {
        self.value = self.value_backup;
        self.last_modified = self.modify_backup;
    }
}

/// A Markov chain's state in primary sample space and its mutations (pbrt-v3's `MLTSampler`).
#[derive(Clone, Debug)]
pub struct MltSampler {
    /// The coordinates asked for so far, interleaved by stream.
    x: Vec<PrimarySample>,
    /// Draws the mutations.
    rng: Pcg32,
    /// Turns the generator's draws into the small steps' Gaussian deviates.
    normal: &'static Ziggurat,
    /// The width of a small step.
    sigma: f32,
    /// The chance that a proposal is a large step.
    large_step_probability: f32,
    /// The iteration under way (0: the chain's first state).
    current_iteration: u64,
    /// Whether the proposal under way is a large step (the first state is one).
    large_step: bool,
    /// The iteration of the last accepted large step.
    last_large_step_iteration: u64,
    /// The stream the path draws from now.
    stream_index: u32,
    /// The next coordinate of that stream.
    sample_index: u32,
    /// Per stream, how many coordinates the proposal under way has drawn (noted at each
    /// change of stream): `reject` looks at those alone, not at every coordinate.
    used: [u32; STREAM_COUNT as usize],
}

impl MltSampler {
    /// The sampler of bootstrap path `index` under `seed`: a chain that starts from it draws the
    /// same first state (pbrt-v3 seeds its RNG by the index alone; acr adds the render's seed).
    pub fn new(seed: u64, index: u64, sigma: f32, large_step_probability: f32) -> Self {
        Self {
            x: Vec::new(),
            // The index is hashed into the seed: PCG streams whose seeds and increments
            // differ by small steps start out correlated.
            rng: {
                let key = mix64(seed ^ 0x6d6c_745f_7361_6d70);
                Pcg32::new(mix64(key ^ mix64(index)), mix64(key).wrapping_add(index))
            },
            normal: Ziggurat::get(),
            sigma,
            large_step_probability,
            current_iteration: 0,
            large_step: true,
            last_large_step_iteration: 0,
            stream_index: 0,
            sample_index: 0,
            used: [0; STREAM_COUNT as usize],
        }
    }

    /// Makes this sampler [`MltSampler::new`]'s for `seed` and `index`, keeping the allocation
    /// of its coordinates (the bootstrap makes one sampler per path: a fresh vector each time
    /// cost the reallocations of its growth).
    pub fn reset(&mut self, seed: u64, index: u64) {
        let mut x = std::mem::take(&mut self.x);
        x.clear();
        *self = Self {
            x,
            ..Self::new(seed, index, self.sigma, self.large_step_probability)
        };
    }

    /// Starts a proposal: a large step with the sampler's chance, else a small one.
    pub fn start_iteration(&mut self) {
        self.current_iteration += 1;
        self.large_step = self.rng.next_f32() < self.large_step_probability;
        self.used = [0; STREAM_COUNT as usize];
        self.sample_index = 0;
    }

    /// Notes how many coordinates the current stream has drawn in this proposal.
    fn note_stream(&mut self) {
        let used = &mut self.used[self.stream_index as usize];
        *used = (*used).max(self.sample_index);
    }

    /// Makes the path draw from stream `index` ([`CAMERA_STREAM`], ...), from its start.
    pub fn start_stream(&mut self, index: u32) {
        debug_assert!(index < STREAM_COUNT);
        self.note_stream();
        self.stream_index = index;
        self.sample_index = 0;
    }

    /// The proposal was accepted.
    pub fn accept(&mut self) {
        if self.large_step {
            self.last_large_step_iteration = self.current_iteration;
        }
    }

    /// The proposal was rejected: the coordinates it moved get their values back. Only
    /// coordinates it drew can have moved (each stream's first `used`); pbrt-v3 looks at every
    /// coordinate.
    pub fn reject(&mut self) {
        self.note_stream();
        for (k, &used) in self.used.iter().enumerate() {
            let stream = self.x.iter_mut().skip(k).step_by(STREAM_COUNT as usize);
            for xi in stream.take(used as usize) {
                if xi.last_modified == self.current_iteration {
                    xi.restore();
                }
            }
        }
        self.current_iteration -= 1;
    }

    /// Whether the proposal under way is a large step.
    pub fn is_large_step(&self) -> bool {
        self.large_step
    }

    /// The index in `x` of the current stream's next coordinate.
    fn next_index(&mut self) -> usize {
        let i = self.stream_index + STREAM_COUNT * self.sample_index;
        self.sample_index += 1;
        i as usize
    }

    /// Brings coordinate `index` up to the iteration under way (pbrt-v3's `EnsureReady`): the
    /// small steps it missed since it was last used are applied as one of their summed width.
    /// Out of line: [`MltSampler::next_1d`] does the common case itself.
    #[inline(never)]
    fn ensure_ready(&mut self, index: usize) {
        if index >= self.x.len() {
            self.grow(index + 1);
        }
        let xi = &mut self.x[index];
        // Reset a coordinate not used since the last accepted large step.
        if xi.last_modified < self.last_large_step_iteration {
            xi.value = self.rng.next_f32();
            xi.last_modified = self.last_large_step_iteration;
        }
        xi.backup();
        if self.large_step {
            xi.value = self.rng.next_f32();
        } else {
            let n_small = self.current_iteration - xi.last_modified;
            // pbrt-v3 draws sqrt(2) erfinv(2u - 1), one logarithm and a long polynomial a
            // deviate; the ziggurat's deviates are exactly normal and mostly a table look-up.
            let normal = self.normal.sample(&mut self.rng);
            // A coordinate moved at every iteration (most of them) needs no square root:
            // sqrt(1) is 1 exactly, so the value is the same.
            let eff_sigma = if n_small == 1 {
                self.sigma
            } else {
                self.sigma * (n_small as f32).sqrt()
            };
            xi.value += normal * eff_sigma;
            xi.value -= xi.value.floor();
            // `v - floor(v)` of a tiny negative v rounds to 1.
            if xi.value >= 1.0 {
                xi.value = 0.0;
            }
        }
        xi.last_modified = self.current_iteration;
    }
}

impl MltSampler {
    /// [`SampleSource::next_1d`]'s small step of coordinate `index` (moved at the last
    /// iteration) whose draw `bits` fell outside its layer's box.
    #[inline(never)]
    fn small_step_finish(&mut self, index: usize, bits: u32) -> f32 {
        let normal = self.normal.finish(bits, &mut self.rng);
        let xi = &mut self.x[index];
        xi.backup();
        xi.value += normal * self.sigma;
        xi.value -= xi.value.floor();
        if xi.value >= 1.0 {
            xi.value = 0.0;
        }
        xi.last_modified = self.current_iteration;
        xi.value
    }

    /// Makes room for `len` coordinates.
    #[cold]
    fn grow(&mut self, len: usize) {
        self.x.resize(len, PrimarySample::default());
    }
}

impl SampleSource for MltSampler {
    /// The common case inline (a small step of a coordinate moved at the last iteration, its
    /// deviate in its layer's box), the same values as [`MltSampler::ensure_ready`]'s: the
    /// path asks for a coordinate a few dozen times a mutation, and a call each cost more
    /// than the step.
    #[inline(always)]
    fn next_1d(&mut self) -> f32 {
        let i = self.next_index();
        if !self.large_step {
            if let Some(xi) = self.x.get_mut(i) {
                // Neither reset (moved since the last accepted large step) nor behind.
                if xi.last_modified + 1 == self.current_iteration
                    && xi.last_modified >= self.last_large_step_iteration
                {
                    let bits = self.rng.next_u32();
                    if let Some(normal) = self.normal.in_box(bits) {
                        xi.backup();
                        let mut v = xi.value + normal * self.sigma;
                        v -= v.floor();
                        // `v - floor(v)` of a tiny negative v rounds to 1.
                        if v >= 1.0 {
                            v = 0.0;
                        }
                        xi.value = v;
                        xi.last_modified = self.current_iteration;
                        return v;
                    }
                    return self.small_step_finish(i, bits);
                }
            }
        }
        self.ensure_ready(i);
        self.x[i].value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rejected_proposal_restores_the_state_and_an_accepted_one_keeps_it() {
        let mut s = MltSampler::new(7, 3, 0.01, 0.3);
        let draw = |s: &mut MltSampler| -> Vec<f32> {
            (0..STREAM_COUNT)
                .flat_map(|k| {
                    s.start_stream(k);
                    [s.next_1d(), s.next_1d()]
                })
                .collect()
        };
        let values = |s: &MltSampler| s.x.iter().map(|p| p.value).collect::<Vec<_>>();
        let first = draw(&mut s);
        let first_state = values(&s);
        assert!(first.iter().all(|v| (0.0..1.0).contains(v)));
        // The same index and seed give the same first state (how a chain starts from its
        // bootstrap path).
        assert_eq!(draw(&mut MltSampler::new(7, 3, 0.01, 0.3)), first);
        assert_ne!(draw(&mut MltSampler::new(8, 3, 0.01, 0.3)), first);
        for _ in 0..50 {
            s.start_iteration();
            let large = s.is_large_step();
            let proposed = draw(&mut s);
            assert!(proposed.iter().all(|v| (0.0..1.0).contains(v)));
            if !large {
                // A small step moves each coordinate by about sigma (wrapped around).
                for (a, b) in first.iter().zip(&proposed) {
                    let d = (a - b).abs();
                    assert!(d.min(1.0 - d) < 0.1, "{a} {b}");
                }
            }
            s.reject();
            assert_eq!(values(&s), first_state);
        }
        // A proposal that draws fewer coordinates than the state holds (a shorter path)
        // restores what it drew and leaves the rest.
        for _ in 0..20 {
            s.start_iteration();
            s.start_stream(CAMERA_STREAM);
            s.next_1d();
            s.start_stream(CONNECTION_STREAM);
            s.next_2d();
            s.reject();
            assert_eq!(values(&s), first_state);
        }
        s.start_iteration();
        draw(&mut s);
        let proposed_state = values(&s);
        assert_ne!(proposed_state, first_state);
        s.accept();
        s.start_iteration();
        draw(&mut s);
        s.reject();
        assert_eq!(values(&s), proposed_state);
    }
}
