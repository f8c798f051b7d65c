//! What the image-space adaptive samplers (`gem`, `awr`) share: rounds of samples allocated to
//! pixels from per-pixel statistics, each sample uniform in its pixel and the active dims.
//! A method supplies the per-pixel error that steers the next round and the reconstruction.

// Channel and dim loops index several small arrays at once, as the formulas do.
#![allow(clippy::needless_range_loop)]

use super::{pixel_key, IndexStream, PixelCursor, Sampler, SamplerSetup, BATCH_SAMPLES};
use crate::film::{luminance, Film, Spectrum};
use crate::registry::{int_in, ParamSpec};
use crate::space::{RenderingSpace, SamplePoint};
use acr_parser::{ParamList, ParamType, Result};

/// Per-pixel running statistics of the samples a sampler has seen (dropped ones excluded).
#[derive(Clone, Debug, Default)]
pub struct PixelMoments {
    /// Samples per pixel, row-major over the space.
    pub count: Vec<u32>,
    /// Sum of radiance per pixel.
    pub sum: Vec<[f64; 3]>,
    /// Sum of squared luminance per pixel.
    pub sum_sq: Vec<f64>,
}

impl PixelMoments {
    fn new(pixels: usize) -> Self {
        Self {
            count: vec![0; pixels],
            sum: vec![[0.0; 3]; pixels],
            sum_sq: vec![0.0; pixels],
        }
    }

    /// Mean radiance of pixel `i` (0 without samples).
    pub fn mean(&self, i: usize) -> [f64; 3] {
        let n = f64::from(self.count[i].max(1));
        self.sum[i].map(|s| s / n)
    }

    /// Variance of the mean luminance of pixel `i`: the sample variance over n, with fewer than
    /// two samples taken as the largest over the image (unknown, so assumed bad).
    pub fn var_of_mean(&self, i: usize, fallback: f64) -> f64 {
        let n = self.count[i];
        if n < 2 {
            return fallback;
        }
        let nf = f64::from(n);
        let m = (0.212671 * self.sum[i][0] + 0.715160 * self.sum[i][1] + 0.072169 * self.sum[i][2])
            / nf;
        let var = ((self.sum_sq[i] - nf * m * m) / (nf - 1.0)).max(0.0);
        var / nf
    }

    /// The variance of the mean of every pixel, with the fallback for pixels of < 2 samples.
    pub fn vars_of_mean(&self) -> Vec<f64> {
        let known: Vec<f64> = (0..self.count.len())
            .map(|i| self.var_of_mean(i, f64::NAN))
            .collect();
        let worst = known
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        known
            .into_iter()
            .map(|v| if v.is_finite() { v } else { worst })
            .collect()
    }
}

/// An image-space adaptive method: where the next samples go and how the image is made.
pub(crate) trait PixelMethod: Send {
    /// The plugin's name.
    const NAME: &'static str;

    /// Each pixel's estimated error (>= 0, finite), to which the next round's samples are
    /// allocated in proportion.
    fn error(&self, space: &RenderingSpace, m: &PixelMoments) -> Vec<f64>;

    /// The image from the statistics, row-major over the space.
    fn reconstruct(&self, space: &RenderingSpace, m: &PixelMoments) -> Vec<Spectrum>;
}

/// Rounds of samples over pixels, driven by a [`PixelMethod`].
pub(crate) struct PixelRounds<M> {
    method: M,
    space: RenderingSpace,
    spp: u32,
    seed: u64,
    salt: u64,
    /// Which interleaved stream of sample indices it gives.
    stream: IndexStream,
    /// The first, uniform round's walk: pass by pass over every pixel, so that a time limit
    /// ends it at a pass and [`Sampler::plan_for`] can shorten it.
    first: PixelCursor,
    /// Whether `initspp` was given (then a time plan keeps it).
    init_given: bool,
    /// Adaptive rounds after the first.
    adaptive_rounds: u32,
    /// Samples each pixel gets in the adaptive round under way.
    plan: Vec<u32>,
    /// The next pixel of the plan to emit.
    cursor: usize,
    /// Samples not yet planned.
    unplanned: u64,
    /// Samples of each adaptive round after the first.
    round_size: u64,
    /// Adaptive samples planned so far.
    adaptive_planned: u64,
    moments: PixelMoments,
    /// Sample indices given so far per pixel.
    given: Vec<u32>,
    rounds: u64,
    halted: bool,
    /// Each pixel's count decided from the other colour of a checkerboard, from the first
    /// round alone (`unbiased`).
    unbiased: bool,
}

impl<M: PixelMethod> PixelRounds<M> {
    /// `spp` samples per pixel on average: `init_spp` in every pixel first, then the rest in
    /// `rounds` rounds steered by the method.
    pub(crate) fn new(
        method: M,
        space: RenderingSpace,
        spp: u32,
        init_spp: u32,
        rounds: u32,
        seed: u64,
        salt: u64,
    ) -> Self {
        let pixels = space.pixels() as usize;
        let init = init_spp.clamp(1, spp);
        let budget = space.pixels() * u64::from(spp);
        let rest = budget - space.pixels() * u64::from(init);
        Self {
            method,
            space,
            spp,
            seed,
            salt,
            stream: IndexStream::ALL,
            first: PixelCursor::new(space, init),
            init_given: false,
            adaptive_rounds: rounds.max(1),
            plan: Vec::new(),
            cursor: 0,
            unplanned: rest,
            round_size: rest.div_ceil(u64::from(rounds.max(1))),
            adaptive_planned: 0,
            moments: PixelMoments::new(pixels),
            given: vec![0; pixels],
            rounds: 1,
            halted: false,
            unbiased: false,
        }
    }

    /// The same sampler deciding without selection bias (`unbiased`): the whole adaptive
    /// budget in one round after the first, each pixel's share from the other colour's
    /// first-round samples alone.
    pub(crate) fn unbiased(mut self, on: bool) -> Self {
        self.unbiased = on && self.space.pixels() > 1;
        if self.unbiased {
            self.round_size = self.unplanned;
        }
        self
    }

    /// Each pixel's error as the method estimates it from moments in which every pixel of
    /// its colour (parity of column + row) holds its four neighbours' pooled samples instead
    /// of its own: so a pixel's error reads only the other colour's samples.
    fn crossed_error(&self) -> Vec<f64> {
        let (w, h) = (self.space.width() as usize, self.space.height() as usize);
        let mut error = vec![0.0; w * h];
        for colour in 0..2 {
            let mut m = self.moments.clone();
            for y in 0..h {
                for x in (0..w).filter(|x| (x + y) & 1 == colour) {
                    let i = y * w + x;
                    let (mut count, mut sum, mut sum_sq) = (0, [0.0; 3], 0.0);
                    let near = [(x > 0, i.wrapping_sub(1)), (x + 1 < w, i + 1)];
                    let rows = [(y > 0, i.wrapping_sub(w)), (y + 1 < h, i + w)];
                    for (_, j) in near.into_iter().chain(rows).filter(|n| n.0) {
                        count += self.moments.count[j];
                        for c in 0..3 {
                            sum[c] += self.moments.sum[j][c];
                        }
                        sum_sq += self.moments.sum_sq[j];
                    }
                    (m.count[i], m.sum[i], m.sum_sq[i]) = (count, sum, sum_sq);
                }
            }
            let e = self.method.error(&self.space, &m);
            for y in 0..h {
                for x in (0..w).filter(|x| (x + y) & 1 == colour) {
                    error[y * w + x] = e[y * w + x];
                }
            }
        }
        error
    }

    /// `n` samples over the pixels by `error`, each colour taking its share of pixels' worth
    /// and allocating it among its own pixels (so that neither colour's total reads the
    /// other's errors).
    fn allocate_by_colour(&self, error: &[f64], n: u64) -> Vec<u32> {
        let w = self.space.width() as usize;
        let colour_of = |i: usize| (i % w + i / w) & 1;
        let pixels = error.len() as u64;
        let zeros = pixels.div_ceil(2);
        let share = [n * zeros / pixels, n - n * zeros / pixels];
        let mut plan = vec![0; error.len()];
        for (colour, &n) in share.iter().enumerate() {
            let own: Vec<usize> = (0..error.len())
                .filter(|&i| colour_of(i) == colour)
                .collect();
            let weights: Vec<f64> = own.iter().map(|&i| error[i]).collect();
            for (&i, k) in own.iter().zip(allocate(&weights, n)) {
                plan[i] = k;
            }
        }
        plan
    }

    /// The same sampler, keeping its first round's count under a time plan when it was given.
    pub(crate) fn init_given(mut self, given: bool) -> Self {
        self.init_given = given;
        self
    }

    /// The same sampler giving stream `stream`'s sample indices.
    pub(crate) fn with_stream(mut self, stream: IndexStream) -> Self {
        self.stream = stream;
        self
    }

    /// Plans the next round from the method's error map; false when nothing is left.
    fn plan_round(&mut self) -> bool {
        if self.halted || self.unplanned == 0 {
            return false;
        }
        let n = self.round_size.min(self.unplanned);
        self.plan = if self.unbiased {
            let error = self.crossed_error();
            self.allocate_by_colour(&error, n)
        } else {
            let error = self.method.error(&self.space, &self.moments);
            allocate(&error, n)
        };
        self.cursor = 0;
        self.unplanned -= n;
        self.adaptive_planned += n;
        self.rounds += 1;
        true
    }

    /// A uniform point in pixel `i` (row-major index) with sample index `index`.
    fn point(&self, i: usize, index: u32) -> SamplePoint {
        let p = self.space.pixel(i as u64);
        let key = pixel_key(p, self.seed, self.salt);
        super::random::uniform_point(p, index, key, self.space.dims)
    }
}

/// The parameters every image-space adaptive method declares first.
pub(crate) const ROUND_PARAMS: [ParamSpec; 4] = [
    super::PIXELSAMPLES_ON_AVERAGE,
    ParamSpec::new(
        "initspp",
        ParamType::Integer,
        "spp/4, from 2 up to spp",
        "samples per pixel of the first, uniform round",
    ),
    ParamSpec::new(
        "rounds",
        ParamType::Integer,
        "4",
        "adaptive rounds after it",
    ),
    ParamSpec::new(
        "unbiased",
        ParamType::Bool,
        "false",
        "decide each pixel's count from the other colour of a checkerboard, from the first \
         round alone (one adaptive round), so that no pixel's count reads its own values, and \
         reconstruct so that the image sums to the sum of the pixel means (gem: symmetric \
         weights from the chosen scales; awr: blocks across the image's edge kept whole): an \
         unbiased image mean (docs/rivals.md)",
    ),
];

/// The first round's samples per pixel out of `spp`, by default: the samplers' first-stage
/// rule with at least 2 (a pixel's first variance) and at most `spp`.
fn first_round_spp(spp: u32) -> u32 {
    super::first_stage_spp(spp, 2).min(spp)
}

/// The sampler of `method`, its budget, first round and rounds read from `params` (the
/// [`ROUND_PARAMS`]).
pub(crate) fn build<M: PixelMethod + 'static>(
    method: M,
    params: &ParamList,
    setup: &SamplerSetup,
    salt: u64,
) -> Result<Box<dyn Sampler>> {
    let spp = super::pixel_samples(params, setup)?;
    let init = int_in(
        params,
        "initspp",
        first_round_spp(spp) as i32,
        1..=i64::from(spp),
    )?;
    let rounds = int_in(params, "rounds", 4, 1..=64)?;
    let unbiased = params.bool_or("unbiased", false)?;
    Ok(Box::new(
        PixelRounds::new(method, setup.space, spp, init, rounds, setup.seed, salt)
            .init_given(params.get("initspp").is_some())
            .with_stream(setup.stream)
            .unbiased(unbiased),
    ))
}

/// `n` samples allocated in proportion to `weights` (largest remainders get the rest; ties to
/// the lower index), so the total is exactly `n`. Uniform when every weight is 0.
pub(crate) fn allocate(weights: &[f64], n: u64) -> Vec<u32> {
    let total: f64 = weights.iter().filter(|w| w.is_finite()).sum();
    let uniform = total.is_nan() || total <= 0.0;
    let share = |w: f64| {
        if uniform {
            1.0 / weights.len() as f64
        } else if w.is_finite() {
            w.max(0.0) / total
        } else {
            0.0
        }
    };
    let mut out = Vec::with_capacity(weights.len());
    let mut frac = Vec::with_capacity(weights.len());
    let mut given = 0u64;
    for (i, &w) in weights.iter().enumerate() {
        let exact = share(w) * n as f64;
        let whole = exact.floor().min(n as f64) as u64;
        given += whole;
        out.push(whole as u32);
        frac.push((exact - whole as f64, i));
    }
    let mut left = n.saturating_sub(given) as usize;
    if left > 0 {
        frac.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        // More left than pixels only through rounding of huge totals: go round again.
        while left > 0 {
            for &(_, i) in frac.iter().take(left) {
                out[i] += 1;
            }
            left = left.saturating_sub(frac.len());
        }
    }
    out
}

impl<M: PixelMethod> Sampler for PixelRounds<M> {
    fn name(&self) -> &'static str {
        M::NAME
    }

    fn spp(&self) -> u32 {
        self.spp
    }

    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool {
        out.clear();
        if let Some((pixels, indices)) = self.first.next() {
            for i in pixels {
                let i = i as usize;
                for k in indices.clone() {
                    out.push(self.point(i, self.stream.index(k)));
                }
                self.given[i] = indices.end;
            }
            return true;
        }
        if self.cursor >= self.plan.len() && !self.plan_round() {
            return false;
        }
        // Whole pixels in row-major order, about a batch's worth.
        while self.cursor < self.plan.len() && (out.len() as u64) < BATCH_SAMPLES {
            let i = self.cursor;
            for _ in 0..self.plan[i] {
                out.push(self.point(i, self.stream.index(self.given[i])));
                self.given[i] += 1;
            }
            self.cursor += 1;
        }
        if out.is_empty() {
            // A round that planned nothing for the rest of the image.
            return self.next_batch(out);
        }
        true
    }

    fn observe(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        for (q, l) in batch.iter().zip(radiance) {
            if !l.iter().all(|v| v.is_finite()) {
                continue;
            }
            let i = self.space.index_of(q.pixel);
            let m = &mut self.moments;
            m.count[i] += 1;
            for c in 0..3 {
                m.sum[i][c] += f64::from(l[c]);
            }
            let y = f64::from(luminance(Spectrum::from_array(*l)));
            m.sum_sq[i] += y * y;
        }
    }

    fn halt(&mut self) {
        // The first round ends at the pass under way; after it, no more rounds.
        self.halted = true;
        self.first.halt();
    }

    fn plan_for(&mut self, spp: u32) -> bool {
        let spp = spp.clamp(1, self.spp);
        // The first round, while under way, shrinks to its share (not inside a pass).
        if !self.init_given {
            self.first.shorten(first_round_spp(spp));
        }
        let adaptive = self.space.pixels() * u64::from(spp.saturating_sub(self.first.spp()));
        // Unbiased, the one adaptive round reads the first round alone: none after it.
        let one_round_done = self.unbiased && self.rounds > 1;
        self.unplanned = if one_round_done {
            0
        } else {
            adaptive.saturating_sub(self.adaptive_planned)
        };
        self.round_size = if self.unbiased {
            self.unplanned
        } else {
            adaptive.div_ceil(u64::from(self.adaptive_rounds))
        };
        true
    }

    fn report(&self) -> super::SamplerReport {
        super::SamplerReport {
            rounds: Some(self.rounds),
            ..Default::default()
        }
    }

    fn reconstructs(&self) -> bool {
        true
    }

    fn reconstruct(&self, _film: &Film) -> Option<Vec<Spectrum>> {
        Some(self.method.reconstruct(&self.space, &self.moments))
    }
}
