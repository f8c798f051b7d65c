//! Samplers: batches of points in the rendering space (`space.rs`), whole pixels at a time in
//! row-major order. Every sampler is deterministic in (space, spp, seed) and keeps no global
//! state, so an image does not depend on the thread count. A new sampler is one file here.

mod awr;
mod cluster;
mod gem;
mod guide;
mod halton;
mod mdas;
mod paired;
mod pixel_pattern;
mod pixel_rounds;
mod random;
mod sobol;
mod stratified;

pub use cluster::{ClusterSampler, ClusterSettings, Priority};
pub use guide::ErrorMap;
pub use halton::HaltonSampler;
pub(crate) use pixel_pattern::{next_batch_where, PixelCursor, PixelPattern};
pub use pixel_rounds::PixelMoments;
pub use random::RandomSampler;
pub use sobol::{SobolSampler, SOBOL_DIMS_USED, SOBOL_SAMPLES};
pub use stratified::StratifiedSampler;

use crate::cells::CellView;
use crate::film::{Film, Spectrum};
use crate::partition::Partition;
use crate::registry::{Choice, Entry};
pub(crate) use crate::rng::{mix64, Pcg32};
use crate::space::{RenderingSpace, SamplePoint};
use acr_parser::{Error, ParamList, ParamType, Result};

/// Samples per batch: enough to keep every thread busy, few enough to report progress often.
pub const BATCH_SAMPLES: u64 = 1 << 15;

/// Largest accepted samples per pixel.
pub const MAX_SPP: u32 = 1 << 20;

/// An adaptive sampler's first, uniform stage out of `spp` samples per pixel, by default: a
/// quarter, at least `least`. One rule for the samplers' `initspp` defaults and for the
/// share a time plan ([`Sampler::plan_for`]) gives the first stage of what fits.
pub(crate) fn first_stage_spp(spp: u32, least: u32) -> u32 {
    (spp / 4).max(least)
}

/// A source of sample points over the rendering space.
pub trait Sampler: Send {
    /// The plugin's name (`random`, `stratified`, ...).
    fn name(&self) -> &'static str;

    /// The samples per pixel it will give unless halted.
    fn spp(&self) -> u32;

    /// Clears `out` and fills it with the next batch, row-major by pixel, each pixel's
    /// samples together. Returns false (with `out` empty) once the budget is spent.
    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool;

    /// The radiance of each point of `batch`, in order; adaptive samplers learn from it.
    fn observe(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        let _ = (batch, radiance);
    }

    /// Learns from points another sampler planned (the other stream of a [`paired`] sampler),
    /// as [`Sampler::observe`] learns from its own; by default, the same.
    fn observe_other(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        self.observe(batch, radiance);
    }

    /// Its own batch was traced, but its values went to the other stream: what `observe` does
    /// for the batch's bookkeeping, without learning from the values. By default, nothing.
    fn retire(&mut self, batch: &[SamplePoint]) {
        let _ = batch;
    }

    /// How many sample streams the points come in: 2 when each stream's points are decided from
    /// the other's values (a [`paired`] sampler). A point's stream is its index's parity; the
    /// film keeps the streams apart and the image is their mean.
    fn streams(&self) -> u32 {
        1
    }

    /// With two streams, the first stream's fixed weight in the image (the second's is 1
    /// minus it): a half for two equal streams, the pilot's share of the budget for a pilot.
    fn stream_weight(&self) -> f64 {
        0.5
    }

    /// Asks the sampler to stop early (a time limit): it ends its current pass, so that every
    /// pixel has as many samples as the others (at least one pass), then gives no more.
    fn halt(&mut self);

    /// Asks the sampler to stop sampling where its own estimate of the relative error is below
    /// `threshold` once every cell there has `min_spp` samples, and to end when that holds
    /// everywhere (`--noise-threshold`); says whether it does. By default it does not, and the
    /// render loop stops it as a whole.
    fn stop_at_noise(&mut self, threshold: f64, min_spp: u32) -> bool {
        let _ = (threshold, min_spp);
        false
    }

    /// Plans for `spp` samples per pixel in all, at most its own budget: a time limit's
    /// estimate of what fits in the time left, made again after every batch
    /// (`--time-limit`, docs/algorithm.md §9), so that an adaptive sampler reaches its adaptive
    /// stage in the time rather than spending it on a first stage planned for its budget.
    /// Says whether it plans by it; by default it does not, and the time limit just stops it.
    fn plan_for(&mut self, spp: u32) -> bool {
        let _ = spp;
        false
    }

    /// Whether it asks, before its next batch, for the reconstruction's estimate of each
    /// pixel's error ([`Sampler::guide`]): the render loop asks before every batch and answers
    /// once every batch given is in the film. A sampler that asks does not plan ahead
    /// ([`Sampler::plans_ahead`]) meanwhile. By default, never.
    fn wants_guidance(&self) -> bool {
        false
    }

    /// Whether it reads the film, or makes or hands over anything that does (an error map, a
    /// partition, cells, its own image): a sampler that does not lets the film count the
    /// pixels' samples alone ([`crate::Film::count_only`]). By default, it may.
    fn reads_film(&self) -> bool {
        true
    }

    /// The reconstruction's estimated squared error of each pixel from the film as it stands
    /// (or the variance of each pixel's mean where the filter makes no estimate), which it
    /// asked for ([`Sampler::wants_guidance`]). By default, ignored.
    fn guide(&mut self, error: &ErrorMap) {
        let _ = error;
    }

    /// Whether the next batch may be asked for before the last one is observed (so that it is
    /// planned while that one is traced); the order of calls is the same whatever the timing.
    fn plans_ahead(&self) -> bool {
        false
    }

    /// Whether its batches come in passes over every pixel of the space, row-major, each
    /// pass's last batch ending at the last pixel (so that the film holds whole passes when
    /// the last batch handed over ends there). By default, no.
    fn whole_passes(&self) -> bool {
        false
    }

    /// Walks the space `rows` rows at a time from the top, every sample of those rows given
    /// before any of the next rows' (a render by bands, docs/reconstruction.md), each pixel's
    /// samples in the order and with the values of the usual walk; says whether it does. Only
    /// a sampler whose points depend on the pixel and index alone can; by default it does not.
    /// Called before the first batch.
    fn walk_by_rows(&mut self, rows: u32) -> bool {
        let _ = rows;
        false
    }

    /// Walking by rows, the rows from the space's top whose every sample the batches given so
    /// far hold (0 otherwise).
    fn rows_given(&self) -> u32 {
        0
    }

    /// Gives sample indices `offset` to `offset + spp` of each pixel instead of 0 to `spp`
    /// (Cycles' sample offset), so that renders of consecutive ranges add up to one of them
    /// all. Only a sampler whose points depend on the index alone can; it says whether it did.
    fn set_sample_offset(&mut self, offset: u32) -> bool {
        offset == 0
    }

    /// The sampler's clusters, for the reconstruction, when it has any.
    fn partition(&self) -> Option<&Partition> {
        None
    }

    /// The sampler's cells and clusters, for the reconstruction, when it keeps them.
    fn cells(&self) -> Option<CellView<'_>> {
        None
    }

    /// Whether [`Sampler::cells`] will give the cells at the end of the render (then the film
    /// need not collect its own).
    fn keeps_cells(&self) -> bool {
        false
    }

    /// What the sampler reports for the stats file (nothing, for a non-adaptive sampler).
    fn report(&self) -> SamplerReport {
        SamplerReport::default()
    }

    /// Whether the sampler makes the image itself ([`Sampler::reconstruct`]), as the methods
    /// whose reconstruction is part of them do (mdas, gem, awr); the filter is then unused.
    fn reconstructs(&self) -> bool {
        false
    }

    /// The image, row-major over the space's pixels, when the sampler [reconstructs]
    /// (`film` holds the splats and per-pixel statistics of every sample).
    ///
    /// [reconstructs]: Sampler::reconstructs
    fn reconstruct(&self, film: &Film) -> Option<Vec<Spectrum>> {
        let _ = film;
        None
    }
}

/// An adaptive sampler's figures for the stats file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SamplerReport {
    /// Clusters at the end.
    pub clusters: Option<u64>,
    /// Cells of its grid.
    pub cells: Option<u64>,
    /// Adaptive rounds run.
    pub rounds: Option<u64>,
}

impl SamplerReport {
    /// The report of a sampler made of two (a pair of streams or of halves): their clusters
    /// and rounds summed over one grid.
    pub fn combined(a: Self, b: Self) -> Self {
        let sum = |x: Option<u64>, y: Option<u64>| x.map(|x| x + y.unwrap_or(0));
        Self {
            clusters: sum(a.clusters, b.clusters),
            cells: a.cells,
            rounds: sum(a.rounds, b.rounds),
        }
    }
}

/// What every sampler is built for: the space, the command line's `--spp` and the seed.
#[derive(Clone, Copy, Debug)]
pub struct SamplerSetup {
    /// The part of the rendering space to sample.
    pub space: RenderingSpace,
    /// Samples per pixel from the command line, overriding the sampler's own parameter.
    pub spp: Option<u32>,
    /// Seed of every random decision.
    pub seed: u64,
    /// Whether the reconstruction reads the sampler's cells (the polynomial filter): a sampler
    /// that keeps cells sums their radiance and sample positions only then.
    pub reconstruction_reads_cells: bool,
    /// Which of interleaved streams of sample indices the sampler gives (all of them, unless it
    /// is one stream of a [`paired`] sampler).
    pub stream: IndexStream,
}

/// One of `count` interleaved streams of sample indices: a sampler's `i`th sample of a pixel
/// has index `i * count + which`, so that no two streams' samples share an index (which keys
/// the integrator's per-sample random stream) and the film tells the streams apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IndexStream {
    /// How many streams.
    pub count: u32,
    /// Which one, below `count`.
    pub which: u32,
}

impl IndexStream {
    /// The only stream: every index.
    pub const ALL: Self = Self { count: 1, which: 0 };

    /// The seed of this stream's own random decisions: `seed` for the first stream, another
    /// for each further one (the streams' points are not to repeat each other's choices).
    pub fn seed(self, seed: u64) -> u64 {
        if self.which == 0 {
            seed
        } else {
            mix64(seed ^ mix64(u64::from(self.which)))
        }
    }

    /// The index of a pixel's `i`th sample of this stream.
    #[inline]
    pub fn index(self, i: u32) -> u32 {
        i * self.count + self.which
    }
}

impl Default for IndexStream {
    fn default() -> Self {
        Self::ALL
    }
}

/// Builds a sampler from its checked parameters.
pub type SamplerBuild = fn(&Choice, &SamplerSetup) -> Result<Box<dyn Sampler>>;

/// Every sampler, by name: a new sampler is one file and one line here.
pub static SAMPLERS: &[Entry<SamplerBuild>] = &[
    random::ENTRY,
    stratified::ENTRY,
    halton::ENTRY,
    sobol::ENTRY,
    cluster::ENTRY,
    mdas::ENTRY,
    gem::ENTRY,
    awr::ENTRY,
];

/// The `pixelsamples` parameter, or the command line's `--spp`, checked to lie in 1..=MAX_SPP.
pub(crate) fn pixel_samples(params: &ParamList, setup: &SamplerSetup) -> Result<u32> {
    let v = params.int_or("pixelsamples", 16)?;
    if let Some(spp) = setup.spp {
        return Ok(spp.clamp(1, MAX_SPP));
    }
    check_count(params, "pixelsamples", i64::from(v))
}

/// A positive count parameter within 1..=MAX_SPP, or an error at its location.
pub(crate) fn check_count(params: &ParamList, name: &str, v: i64) -> Result<u32> {
    if v < 1 || v > i64::from(MAX_SPP) {
        if let Some(p) = params.get(name) {
            return Err(Error::at(
                &p.loc,
                format!("{name} {v} is out of range (1 to {MAX_SPP})"),
            ));
        }
    }
    Ok(v.clamp(1, i64::from(MAX_SPP)) as u32)
}

/// Doc of `pixelsamples`.
pub(crate) const PIXELSAMPLES: &str = "samples per pixel (--spp overrides)";

/// `pixelsamples` of an adaptive sampler, whose pixels get unequal shares of the budget.
pub(crate) const PIXELSAMPLES_ON_AVERAGE: crate::registry::ParamSpec =
    crate::registry::ParamSpec::new(
        "pixelsamples",
        ParamType::Integer,
        "16",
        "samples per pixel on average (--spp overrides)",
    );

/// The next of two samplers taking turns that gives a batch (`give` asks one): from `turn` on,
/// skipping those marked `done` and marking those whose budget is spent; which one gave.
pub(crate) fn alternate(
    turn: &mut usize,
    done: &mut [bool; 2],
    mut give: impl FnMut(usize) -> bool,
) -> Option<usize> {
    for _ in 0..2 {
        let h = *turn;
        *turn = 1 - h;
        if done[h] {
            continue;
        }
        if give(h) {
            return Some(h);
        }
        done[h] = true;
    }
    None
}

/// Runs `sampler` to the end in the render loop's order of calls (a sampler that plans ahead
/// is asked for the next batch before it observes the last), with `radiance` of each batch,
/// halting after `halt_after` batches if given; every point given, in order.
pub fn drive(
    sampler: &mut dyn Sampler,
    radiance: impl FnMut(&[SamplePoint]) -> Vec<[f32; 3]>,
    halt_after: Option<usize>,
) -> Vec<SamplePoint> {
    drive_with(sampler, radiance, |s, batches| {
        if halt_after == Some(batches) {
            s.halt();
        }
    })
}

/// [`drive`], calling `after_batch` with the sampler and the count of batches given after each
/// one, where the render loop halts or re-plans it.
pub fn drive_with(
    sampler: &mut dyn Sampler,
    mut radiance: impl FnMut(&[SamplePoint]) -> Vec<[f32; 3]>,
    mut after_batch: impl FnMut(&mut dyn Sampler, usize),
) -> Vec<SamplePoint> {
    let (mut all, mut batch, mut next) = (Vec::new(), Vec::new(), Vec::new());
    let mut pending: Option<(Vec<SamplePoint>, Vec<[f32; 3]>)> = None;
    let mut batches = 0;
    let mut more = sampler.next_batch(&mut batch);
    while more {
        let ahead = sampler.plans_ahead();
        // What the render loop does while `batch` is traced.
        let r = radiance(&batch);
        if let Some((b, r)) = pending.take() {
            sampler.observe(&b, &r);
        }
        let planned = ahead.then(|| sampler.next_batch(&mut next));
        all.extend_from_slice(&batch);
        batches += 1;
        after_batch(&mut *sampler, batches);
        match planned {
            Some(planned) => {
                pending = Some((std::mem::replace(&mut batch, std::mem::take(&mut next)), r));
                more = planned;
            }
            None => {
                sampler.observe(&batch, &r);
                more = sampler.next_batch(&mut batch);
            }
        }
    }
    if let Some((b, r)) = pending {
        sampler.observe(&b, &r);
    }
    all
}

/// An estimate in f64, as a pixel's radiance: never negative (the image-space samplers'
/// reconstructions can undershoot).
pub(crate) fn nonnegative_spectrum(c: [f64; 3]) -> Spectrum {
    Spectrum::new(c[0] as f32, c[1] as f32, c[2] as f32).max(Spectrum::ZERO)
}

/// A key for `pixel` under `seed`, salted per sampler so that samplers do not share streams
/// with each other or with the integrator's per-sample stream.
#[inline]
pub(crate) fn pixel_key(pixel: [u32; 2], seed: u64, salt: u64) -> u64 {
    let p = (u64::from(pixel[1]) << 32) | u64::from(pixel[0]);
    mix64(p ^ mix64(seed ^ mix64(salt)))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::space::Dims;

    /// Every combination of active dims.
    pub(crate) const ALL_DIMS: [Dims; 4] = [
        Dims {
            time: false,
            lens: false,
        },
        Dims {
            time: true,
            lens: false,
        },
        Dims {
            time: false,
            lens: true,
        },
        Dims {
            time: true,
            lens: true,
        },
    ];

    /// A space of `w` x `h` pixels from (x0, y0).
    pub(crate) fn space(x0: u32, y0: u32, w: u32, h: u32, dims: Dims) -> RenderingSpace {
        RenderingSpace {
            x0,
            x1: x0 + w,
            y0,
            y1: y0 + h,
            dims,
        }
    }

    /// Every sampler at `spp` (stratified as sqrt x sqrt when spp is a square, else spp x 1).
    pub(crate) fn all(s: RenderingSpace, spp: u32, seed: u64) -> Vec<Box<dyn Sampler>> {
        let r = (spp as f64).sqrt() as u32;
        let (xs, ys) = if r * r == spp { (r, r) } else { (spp, 1) };
        vec![
            Box::new(RandomSampler::new(s, spp, seed)) as Box<dyn Sampler>,
            Box::new(StratifiedSampler::new(s, xs, ys, true, seed)),
            Box::new(StratifiedSampler::new(s, xs, ys, false, seed)),
            Box::new(HaltonSampler::new(s, spp, seed)),
            Box::new(SobolSampler::new(s, spp, seed)),
        ]
    }

    /// Every batch a sampler gives, in order.
    pub(crate) fn batches(s: &mut dyn Sampler) -> Vec<Vec<SamplePoint>> {
        let mut v = Vec::new();
        let mut b = vec![SamplePoint {
            pixel: [9, 9],
            index: 9,
            film: [0.0; 2],
            time: 0.0,
            lens: [0.0; 2],
        }];
        while s.next_batch(&mut b) {
            v.push(b.clone());
        }
        assert!(b.is_empty(), "{}: the last call leaves out empty", s.name());
        // Once spent, a sampler stays spent.
        assert!(!s.next_batch(&mut b));
        v
    }

    /// The points of `batches` grouped by pixel (row-major) and sorted by index.
    pub(crate) fn by_pixel(sp: &RenderingSpace, bs: &[Vec<SamplePoint>]) -> Vec<SamplePoint> {
        let mut all: Vec<SamplePoint> = bs.iter().flatten().copied().collect();
        let key = |q: &SamplePoint| {
            (
                u64::from(q.pixel[1] - sp.y0) * u64::from(sp.width())
                    + u64::from(q.pixel[0] - sp.x0),
                q.index,
            )
        };
        all.sort_by_key(key);
        all
    }

    /// Asserts the contract every sampler keeps on `sp` at `spp`.
    fn check_contract(s: &mut dyn Sampler, sp: &RenderingSpace, spp: u32) {
        let name = s.name();
        assert_eq!(s.spp(), spp, "{name}");
        let bs = batches(s);
        for b in &bs {
            assert!(!b.is_empty());
            assert!(
                b.len() as u64 <= BATCH_SAMPLES.max(u64::from(spp)),
                "{name}"
            );
            // Row-major pixels, each with one run of consecutive indices, the same for all.
            let run = b.iter().take_while(|q| q.pixel == b[0].pixel).count();
            assert_eq!(b.len() % run, 0, "{name}");
            for (k, chunk) in b.chunks(run).enumerate() {
                assert!(chunk.iter().all(|q| q.pixel == chunk[0].pixel), "{name}");
                for (i, q) in chunk.iter().enumerate() {
                    assert_eq!(q.index, b[i].index, "{name}");
                    assert_eq!(q.index, chunk[0].index + i as u32, "{name}");
                }
                if k > 0 {
                    let prev = b[(k - 1) * run].pixel;
                    assert!((prev[1], prev[0]) < (chunk[0].pixel[1], chunk[0].pixel[0]));
                }
            }
        }
        let all = by_pixel(sp, &bs);
        assert_eq!(all.len() as u64, sp.pixels() * u64::from(spp), "{name}");
        // Each pixel's indices 0..spp exactly once.
        for (k, chunk) in all.chunks(spp as usize).enumerate() {
            let p = sp.pixel(k as u64);
            for (i, q) in chunk.iter().enumerate() {
                assert_eq!(q.pixel, p, "{name}");
                assert_eq!(q.index, i as u32, "{name}");
            }
        }
        for q in &all {
            for a in 0..2 {
                let f = f64::from(q.film[a]);
                let p = f64::from(q.pixel[a]);
                assert!(
                    f >= p && f < p + 1.0,
                    "{name}: film {:?} in {:?}",
                    q.film,
                    q.pixel
                );
            }
            if sp.dims.time {
                assert!((0.0..1.0).contains(&q.time), "{name}: t {}", q.time);
            } else {
                assert_eq!(q.time, 0.5, "{name}");
            }
            if sp.dims.lens {
                assert!(q.lens.iter().all(|l| (0.0..1.0).contains(l)), "{name}");
            } else {
                assert_eq!(q.lens, [0.5, 0.5], "{name}");
            }
        }
    }

    #[test]
    fn every_sampler_keeps_the_contract() {
        for dims in ALL_DIMS {
            // Odd sizes, a far-off origin (rounding), a budget spanning several batches.
            for (sp, spp) in [
                (space(0, 0, 7, 5, dims), 4),
                (space(4090, 1020, 9, 6, dims), 9),
                (space(2, 3, 64, 40, dims), 16),
            ] {
                for mut s in all(sp, spp, 7) {
                    check_contract(s.as_mut(), &sp, spp);
                }
            }
        }
    }

    #[test]
    fn batches_are_about_batch_samples() {
        let sp = space(0, 0, 100, 30, ALL_DIMS[3]);
        let mut s = RandomSampler::new(sp, 16, 1);
        // Passes of 10 and 6 samples per pixel over all 3000 pixels.
        let bs = batches(&mut s);
        assert_eq!(
            bs.iter().map(Vec::len).collect::<Vec<_>>(),
            [30_000, 18_000]
        );
        // More samples per pixel than a batch holds: passes of half a batch per pixel.
        let sp = space(0, 0, 2, 1, ALL_DIMS[0]);
        let mut s = RandomSampler::new(sp, 40_000, 1);
        assert_eq!(
            batches(&mut s).iter().map(Vec::len).collect::<Vec<_>>(),
            [32_768, 32_768, 14_464]
        );
        // A pixel alone over a batch: one pixel per batch.
        let sp = space(0, 0, 1, 1, ALL_DIMS[0]);
        let mut s = RandomSampler::new(sp, 40_000, 1);
        assert_eq!(
            batches(&mut s).iter().map(Vec::len).collect::<Vec<_>>(),
            [32_768, 7_232]
        );
        // No pixels, no batch.
        let mut s = SobolSampler::new(space(0, 0, 0, 4, ALL_DIMS[0]), 4, 1);
        assert!(batches(&mut s).is_empty());
    }

    #[test]
    fn halting_ends_the_pass_so_every_pixel_has_as_many_samples() {
        let sp = space(0, 0, 400, 100, ALL_DIMS[3]);
        for mut s in all(sp, 16, 2) {
            let mut b = Vec::new();
            // Halt during the first pass: that pass completes and nothing follows.
            assert!(s.next_batch(&mut b));
            let mut got = b.clone();
            s.halt();
            while s.next_batch(&mut b) {
                got.extend_from_slice(&b);
            }
            assert_eq!(got.len(), 40_000, "{}", s.name());
            let mut count = vec![0u32; 40_000];
            for q in &got {
                count[(q.pixel[1] * 400 + q.pixel[0]) as usize] += 1;
            }
            assert!(count.iter().all(|&c| c == 1), "{}", s.name());
        }
        // Halted between passes: stops at once.
        let mut s = SobolSampler::new(space(0, 0, 300, 100, ALL_DIMS[0]), 16, 2);
        let mut b = Vec::new();
        assert!(s.next_batch(&mut b));
        s.halt();
        assert!(!s.next_batch(&mut b));
    }

    #[test]
    fn walking_by_rows_gives_each_pixel_the_same_points_band_after_band() {
        // 3 rows at a time over 7 rows (the last chunk short), a crop not at the origin.
        let sp = space(5, 6, 300, 7, ALL_DIMS[3]);
        for (mut whole, mut banded) in all(sp, 9, 4).into_iter().zip(all(sp, 9, 4)) {
            let name = whole.name();
            assert!(banded.walk_by_rows(3), "{name}");
            let a = by_pixel(&sp, &batches(whole.as_mut()));
            let mut rows = Vec::new();
            let mut got = Vec::new();
            let mut b = Vec::new();
            while banded.next_batch(&mut b) {
                // Every point lies below the rows given before it.
                let given = rows.last().copied().unwrap_or(0);
                assert!(b.iter().all(|q| q.pixel[1] - sp.y0 >= given), "{name}");
                rows.push(banded.rows_given());
                got.extend_from_slice(&b);
            }
            rows.dedup();
            assert_eq!(
                rows.iter().filter(|&&r| r > 0).count(),
                3,
                "{name}: {rows:?}"
            );
            assert_eq!(rows.last(), Some(&7), "{name}");
            // Each pixel's points in the same order, with the same values.
            let mut per_pixel: Vec<SamplePoint> = got.clone();
            per_pixel.sort_by_key(|q| (q.pixel[1], q.pixel[0]));
            assert_eq!(per_pixel, a, "{name}");
        }
        // Halted in the second chunk: its pass completes, the third chunk is never given.
        let mut s = StratifiedSampler::new(space(0, 0, 4000, 30, ALL_DIMS[0]), 4, 4, true, 1);
        assert!(s.walk_by_rows(10));
        let mut b = Vec::new();
        while s.rows_given() < 10 {
            assert!(s.next_batch(&mut b));
        }
        assert!(s.next_batch(&mut b));
        s.halt();
        while s.next_batch(&mut b) {
            assert!(b.iter().all(|q| q.pixel[1] < 20));
        }
        assert_eq!(s.rows_given(), 10);
    }

    #[test]
    fn same_seed_same_points_other_seed_other_points() {
        for dims in ALL_DIMS {
            let sp = space(5, 6, 11, 7, dims);
            let a: Vec<_> = all(sp, 16, 3)
                .iter_mut()
                .map(|s| batches(s.as_mut()))
                .collect();
            let b: Vec<_> = all(sp, 16, 3)
                .iter_mut()
                .map(|s| batches(s.as_mut()))
                .collect();
            let c: Vec<_> = all(sp, 16, 4)
                .iter_mut()
                .map(|s| batches(s.as_mut()))
                .collect();
            assert_eq!(a, b);
            for k in 0..a.len() {
                let (x, y): (Vec<_>, Vec<_>) = (a[k].concat(), c[k].concat());
                // The unjittered stratified sampler differs only in its shuffles.
                let differ = x.iter().zip(&y).filter(|(p, q)| p != q).count();
                assert!(differ * 2 > x.len(), "sampler {k}: {differ} of {}", x.len());
            }
        }
    }

    /// The exact star discrepancy of points in [0, 1): sup over x of |#{v < x} / n - x|.
    pub(crate) fn star_discrepancy(vals: &[f64]) -> f64 {
        let mut v = vals.to_vec();
        v.sort_by(f64::total_cmp);
        let n = v.len() as f64;
        v.iter()
            .enumerate()
            .map(|(i, &x)| (x - i as f64 / n).max((i + 1) as f64 / n - x))
            .fold(0.0, f64::max)
    }

    #[test]
    fn star_discrepancy_is_exact_on_known_sets() {
        assert_eq!(star_discrepancy(&[0.5]), 0.5);
        // Centred strata: 1 / (2n).
        let c: Vec<f64> = (0..8).map(|i| (i as f64 + 0.5) / 8.0).collect();
        assert!((star_discrepancy(&c) - 1.0 / 16.0).abs() < 1e-12);
    }

    #[test]
    fn pixels_differ() {
        // Neighbouring pixels do not repeat each other's offsets (per-pixel scrambling).
        let sp = space(0, 0, 2, 1, ALL_DIMS[3]);
        for mut s in all(sp, 16, 5) {
            let b = &batches(s.as_mut())[0];
            let off = |q: &SamplePoint| [q.film[0].fract(), q.film[1].fract(), q.time, q.lens[0]];
            let same = (0..16).filter(|&i| off(&b[i]) == off(&b[16 + i])).count();
            assert!(same < 4, "{}: {same}", s.name());
        }
    }
}
