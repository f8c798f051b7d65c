//! The render loop (docs/architecture.md §3): batches of sample points, traced in parallel with
//! rayon, added to the film in a fixed order, so the image depends on the scene, seed and
//! budget only.

use crate::camera::CameraSample;
use crate::first_hit::{FeatureImage, FirstHit};
use crate::geometry::{is_valid_radiance, Spectrum, Vec2};
use crate::geometry::{Ray, RayDifferentials};
use crate::integrator::{Integrator, Radiance};
use crate::scene::Scene;
use crate::stream::SampleStream;
use acr_plugins::first_hit::{sanitized, Features};
use acr_plugins::sampler::{ErrorMap, IndexStream, SOBOL_DIMS_USED};
use acr_plugins::{Film, RenderingSpace, SamplePoint, Sampler};
use rayon::prelude::*;
use std::time::{Duration, Instant};

pub use acr_plugins::sampler::MAX_SPP;
pub use bands::{render_in_bands, Banded, Bands};
pub use stop::{Checkpoint, ErrorEstimate, Halt, RenderCounts, Stop};

pub mod bands;
pub mod stop;

/// The part of the rendering space a scene's render covers: its film's crop and its dims.
pub fn rendering_space(scene: &Scene) -> RenderingSpace {
    let [x0, x1, y0, y1] = scene.film.crop;
    RenderingSpace {
        x0,
        x1,
        y0,
        y1,
        dims: scene.dims,
    }
}

/// The pixels a render samples: the film's crop widened by the filter's radius, as pbrt-v3's
/// `Film::GetSampleBounds` widens it (floor(x0 + 0.5 - r) to ceil(x1 - 0.5 + r)), so that a
/// crop's edge pixels receive the same samples' splats as in a render of the whole frame and
/// crops tile the frame exactly. Kept within the image: acr samples no pixel outside it (a
/// whole-frame render samples exactly its pixels).
pub fn sample_space(scene: &Scene, radius: (f32, f32)) -> RenderingSpace {
    let crop = rendering_space(scene);
    let (w, h) = scene.film.resolution;
    let widen = |lo: u32, hi: u32, r: f32, size: u32| {
        let r = if r.is_finite() { r.max(0.0) } else { 0.0 };
        let a = (lo as f32 + 0.5 - r).floor().max(0.0) as u32;
        let b = (hi as f32 - 0.5 + r).ceil().min(size as f32) as u32;
        (a.min(lo), b.max(hi))
    };
    let (x0, x1) = widen(crop.x0, crop.x1, radius.0, w);
    let (y0, y1) = widen(crop.y0, crop.y1, radius.1, h);
    RenderingSpace {
        x0,
        x1,
        y0,
        y1,
        dims: crop.dims,
    }
}

/// The raster position of offset `u` in [0, 1)^2 within pixel (px, py). Rounding can carry
/// `py + u.y` to `py + 1` (from row 1024 on, say); the result is kept inside the pixel, so that
/// a sample always lands in the pixel it was drawn for and batches stay sorted by row.
#[inline]
pub fn in_pixel(px: u32, py: u32, u: Vec2) -> Vec2 {
    let below = |i: u32| f32::from_bits((i as f32).to_bits() - 1);
    let p = Vec2::new(px as f32, py as f32) + u;
    p.min(Vec2::new(below(px + 1), below(py + 1)))
}

/// Hands `sampler` the estimated error of each pixel when it asks, the film holding every
/// batch it gave (the render loop calls it only when no batch is in flight).
fn answer_guidance(
    sampler: &mut dyn Sampler,
    film: &Film,
    estimate: Option<&ErrorEstimate<'_>>,
    in_sampler: &mut Duration,
) {
    if sampler.wants_guidance() {
        let map = ErrorMap::of(film, estimate.and_then(|e| e(film)));
        timed(in_sampler, || sampler.guide(&map));
    }
}

/// The image's estimated relative error: the mean over pixels of the standard error of the
/// pixel's mean luminance over (that mean + 0.01), Cycles' and LuxCore's kind of measure. The
/// 0.01 keeps black pixels from dominating. Pixels with fewer than 2 samples count as 1 (no
/// estimate yet).
pub fn relative_error(stats: &[acr_plugins::PixelStats]) -> f64 {
    if stats.is_empty() {
        return 0.0;
    }
    let sum: f64 = stats
        .iter()
        .map(|s| {
            if s.count < 2 {
                return 1.0;
            }
            acr_plugins::film::relative_error_of(
                f64::from(crate::spectrum_luminance(s.mean())),
                f64::from(crate::spectrum_luminance(s.variance_of_mean())),
            )
        })
        .sum();
    sum / stats.len() as f64
}

/// Renders `scene` with `sampler`'s points into `film`, until the sampler's budget is spent
/// or, with a `time_limit`, until the pass running when the limit passes is complete.
pub fn render(
    scene: &Scene,
    integrator: &Integrator,
    sampler: &mut dyn Sampler,
    film: &mut Film,
    seed: u64,
    time_limit: Option<Duration>,
    progress: Option<&indicatif::ProgressBar>,
) -> RenderCounts {
    let stop = Stop::time(time_limit);
    render_with_features(
        scene, integrator, sampler, film, seed, &stop, progress, None,
    )
}

/// [`render`] with any [`Stop`] rule, also adding each sample's first-hit features to
/// `features` when given.
#[allow(clippy::too_many_arguments)]
pub fn render_with_features(
    scene: &Scene,
    integrator: &Integrator,
    sampler: &mut dyn Sampler,
    film: &mut Film,
    seed: u64,
    stop: &Stop,
    progress: Option<&indicatif::ProgressBar>,
    features: Option<&mut FeatureImage>,
) -> RenderCounts {
    // mlt drives its own sampling (docs/light-transport.md).
    if let Integrator::Mlt(settings) = integrator {
        return crate::integrator::mlt::render(scene, settings, film, seed, stop, progress);
    }
    if let Integrator::Sppm(settings) = integrator {
        return crate::integrator::sppm::render(scene, settings, film, seed, stop, progress);
    }
    let li = |scene: &Scene,
              ray: Ray,
              diff: Option<&RayDifferentials>,
              stream: &mut SampleStream| { integrator.li(scene, ray, diff, stream) };
    render_with(scene, &li, sampler, film, seed, stop, progress, features)
}

/// The fewest samples a thread takes at once in [`Traced::take_plain`].
const TAKE_MIN_LEN: usize = 4096;

/// A traced batch and what became of its samples, waiting for the sampler and the film.
#[derive(Default)]
struct Traced {
    batch: Vec<SamplePoint>,
    /// Each point's radiance, clamped by the film's limits; NaN where it was dropped.
    radiance: Vec<[f32; 3]>,
    /// The film position and radiance of each sample kept, by stream (the index's parity)
    /// when the film keeps a paired sampler's two streams apart, else all in the first.
    valid: [Vec<(Vec2, Spectrum)>; 2],
    /// Each point's first-hit features, when the film's cells keep them (values that are not
    /// finite become 0 and are counted); empty otherwise.
    features: Vec<Features>,
    /// The batch's unfiltered splats (bdpt's light tracing), in the batch's order.
    splats: Vec<(Vec2, Spectrum)>,
    /// Samples handed to the film so far: each traced one light subpath, whose splats the
    /// film scales by full-film pixels over their number (docs/light-transport.md).
    handed: u64,
    /// The full film's pixels.
    full_pixels: u64,
    /// Walking by rows, the rows whose every sample the batches up to this one hold
    /// ([`Sampler::rows_given`]).
    rows_given: u32,
}

impl Traced {
    /// Takes `results` of `self.batch`: counts them, drops radiance that is NaN, infinite or
    /// negative, and clamps the rest by the film's limits.
    fn take(
        &mut self,
        results: &[SampleResult],
        film: &Film,
        counts: &mut RenderCounts,
        mut features: Option<&mut FeatureImage>,
    ) {
        self.valid.iter_mut().for_each(Vec::clear);
        let split = film.halves().is_some();
        self.radiance.clear();
        self.features.clear();
        self.splats.clear();
        let keep_features = film.collects_features();
        if !split && !keep_features && features.is_none() {
            return self.take_plain(results, film, counts);
        }
        for (q, (l, rays, first_hit, splats)) in self.batch.iter().zip(results) {
            let (l, rays, first_hit) = (*l, *rays, *first_hit);
            self.splats.extend_from_slice(splats);
            counts.rays += u64::from(rays);
            if keep_features {
                let (f, bad) = sanitized(first_hit.to_array());
                counts.non_finite_features += u64::from(bad);
                self.features.push(f);
            }
            if let Some(f) = features.as_deref_mut() {
                f.add(Vec2::from(q.film), &first_hit);
            }
            if is_valid_radiance(l) {
                let l = film.settings().clamp(l);
                let stream = if split { q.index as usize & 1 } else { 0 };
                self.valid[stream].push((Vec2::from(q.film), l));
                self.radiance.push(l.to_array());
            } else {
                counts.dropped += 1;
                // NaN marks a dropped sample for adaptive samplers, which must skip it.
                self.radiance.push([f32::NAN; 3]);
            }
        }
        counts.samples += self.batch.len() as u64;
    }

    /// [`Traced::take`] where neither the streams nor the features are kept (cleared
    /// already): each sample's radiance and film sample written in place, in parallel. Read on
    /// one thread between batches, half of them from the other core's cache, the results kept
    /// the other thread idle for 2% of the CPU time on small scenes (docs/BENCHMARKS.md, "The
    /// small rows again: the serial take and the instances' walk").
    fn take_plain(&mut self, results: &[SampleResult], film: &Film, counts: &mut RenderCounts) {
        let n = results.len();
        let settings = film.settings();
        let valid = &mut self.valid[0];
        self.radiance.resize(n, [0.0; 3]);
        valid.resize(n, (Vec2::ZERO, Spectrum::ZERO));
        let (rays, dropped, splats) = self
            .radiance
            .par_iter_mut()
            .zip(valid.par_iter_mut())
            .zip(results.par_iter().zip(self.batch.par_iter()))
            .with_min_len(TAKE_MIN_LEN)
            .map(|((r, v), ((l, rays, _, splats), q))| {
                let ok = is_valid_radiance(*l);
                if ok {
                    let l = settings.clamp(*l);
                    *r = l.to_array();
                    *v = (Vec2::from(q.film), l);
                } else {
                    // NaN marks a dropped sample for adaptive samplers, which must skip it,
                    // and here the film samples to leave out (a kept one is finite).
                    *r = [f32::NAN; 3];
                    *v = (Vec2::ZERO, Spectrum::NAN);
                }
                (u64::from(*rays), u64::from(!ok), splats.len())
            })
            .reduce(|| (0, 0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
        if dropped > 0 {
            valid.retain(|(_, l)| !l.x.is_nan());
        }
        if splats > 0 {
            for (.., s) in results {
                self.splats.extend_from_slice(s);
            }
        }
        counts.rays += rays;
        counts.dropped += dropped;
        counts.samples += n as u64;
    }

    /// Gives the batch to the sampler (its time added to `in_sampler`), then to the film, with
    /// its splats, scaled for the light subpaths traced so far.
    fn hand_over(&mut self, sampler: &mut dyn Sampler, film: &mut Film, in_sampler: &mut Duration) {
        self.handed += self.batch.len() as u64;
        if !self.splats.is_empty() {
            film.add_splats(&self.splats);
        }
        film.unfiltered_mut()
            .set_scale(self.full_pixels as f64 / self.handed.max(1) as f64);
        timed(in_sampler, || sampler.observe(&self.batch, &self.radiance));
        let features = film.collects_features().then_some(self.features.as_slice());
        film.add_points(&self.batch, &self.radiance, features);
        match film.halves() {
            Some(_) => {
                film.add_stream_samples(0, &self.valid[0]);
                film.add_stream_samples(1, &self.valid[1]);
            }
            None => film.add_samples(&self.valid[0]),
        }
    }
}

/// Runs `f`, adding its wall time to `total`.
fn timed<T>(total: &mut Duration, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let r = f();
    *total += t.elapsed();
    r
}

/// What a sample estimates: the radiance arriving along a camera ray.
/// The ray comes with its differentials, scaled to the sample spacing.
pub type Estimator<'a> =
    dyn Fn(&Scene, Ray, Option<&RayDifferentials>, &mut SampleStream) -> Radiance + Sync + 'a;

/// One traced sample: its radiance, rays, first-hit features and unfiltered splats (empty,
/// without allocation, for every integrator but bdpt).
type SampleResult = (Spectrum, u32, FirstHit, Vec<(Vec2, Spectrum)>);

/// [`render`] with any estimator in place of an integrator (tests give it one that misbehaves).
/// Radiance that is NaN, infinite or negative is dropped and counted where it arises; the rest
/// is clamped by the film's limits before the sampler, the cells and the film see it. With
/// `features`, each sample's first-hit features are added there. `stop` may end it early.
#[allow(clippy::too_many_arguments)]
pub fn render_with(
    scene: &Scene,
    li: &Estimator<'_>,
    sampler: &mut dyn Sampler,
    film: &mut Film,
    seed: u64,
    stop: &Stop,
    progress: Option<&indicatif::ProgressBar>,
    features: Option<&mut FeatureImage>,
) -> RenderCounts {
    render_loop(
        scene, li, sampler, film, seed, stop, progress, features, None,
    )
}

/// [`render_with`], and with `bands`, a render by bands: each band filtered once the film
/// holds its rows and halo ([`Bands::rows_in`]), between batches.
#[allow(clippy::too_many_arguments)]
fn render_loop(
    scene: &Scene,
    li: &Estimator<'_>,
    sampler: &mut dyn Sampler,
    film: &mut Film,
    seed: u64,
    stop: &Stop,
    progress: Option<&indicatif::ProgressBar>,
    mut features: Option<&mut FeatureImage>,
    mut bands: Option<&mut Bands<'_>>,
) -> RenderCounts {
    let space = rendering_space(scene);
    let mut watch = Watch::new(stop, space.pixels().max(1));
    let mut counts = RenderCounts::default();
    if sampler.streams() == 2 {
        film.split_streams(sampler.stream_weight());
    }
    if let Some(p) = progress {
        p.set_length(space.pixels() * u64::from(sampler.spp()));
    }
    let tracer = Tracer {
        scene,
        li,
        seed,
        // A paired sampler's streams draw the integrator's decisions from sequences of their
        // own: sharing one, a sample and its neighbour in the other stream would be a
        // stratified pair, and one stream's values would tell where the other's went.
        streams: sampler.streams().max(1),
    };
    // Reused from batch to batch: a fresh half-megabyte vector per batch costs page faults.
    let (mut batch, mut next) = (Vec::new(), Vec::new());
    let mut results: Vec<SampleResult> = Vec::new();
    // The last batch traced, when the sampler and the film have not yet seen it.
    let (w, h) = scene.film.resolution;
    let mut traced = Traced {
        full_pixels: u64::from(w) * u64::from(h),
        ..Traced::default()
    };
    let mut pending = false;
    let mut in_sampler = Duration::ZERO;
    let last_pixel = space.pixel(space.pixels().saturating_sub(1));
    let in_passes = sampler.whole_passes();
    let mut more = timed(&mut in_sampler, || sampler.next_batch(&mut batch));
    // The rows whose every sample the batches up to `batch` hold (walking by rows).
    let mut rows_given = sampler.rows_given();
    while more {
        // While `batch` is traced, the sampler and the film take the batch before and, when
        // the sampler plans ahead, it plans the next.
        let ahead = sampler.plans_ahead();
        let ((), planned) = rayon::join(
            || tracer.trace(&batch, &mut results),
            || {
                if pending {
                    traced.hand_over(sampler, film, &mut in_sampler);
                }
                ahead.then(|| {
                    let more = timed(&mut in_sampler, || sampler.next_batch(&mut next));
                    (more, sampler.rows_given())
                })
            },
        );
        if let (true, Some(b)) = (pending, bands.as_deref_mut()) {
            // Filtered between batches, not while one is traced: the filter's time is its own.
            b.rows_in(film, traced.rows_given);
        }
        std::mem::swap(&mut traced.batch, &mut batch);
        traced.rows_given = rows_given;
        traced.take(&results, film, &mut counts, features.as_deref_mut());
        pending = true;
        if let Some(p) = progress {
            p.set_position(counts.samples);
        }
        // The film holds what the sampler has handed over so far, `batch` the last of it: a
        // batch ending at the last pixel ends a pass.
        let pass_done = !in_passes || batch.last().is_some_and(|q| q.pixel == last_pixel);
        watch.look(film, pass_done);
        watch.check(film, sampler, &mut counts);
        watch.plan_to_time(sampler, &counts);
        match planned {
            Some((planned, rows)) => {
                std::mem::swap(&mut batch, &mut next);
                more = planned;
                rows_given = rows;
            }
            None => {
                traced.hand_over(sampler, film, &mut in_sampler);
                pending = false;
                if let Some(b) = bands.as_deref_mut() {
                    b.rows_in(film, traced.rows_given);
                }
                // A sampler that asks for guidance plans nothing ahead meanwhile: the film
                // now holds every batch it gave.
                answer_guidance(sampler, film, stop.estimated_error, &mut in_sampler);
                more = timed(&mut in_sampler, || sampler.next_batch(&mut batch));
                rows_given = sampler.rows_given();
            }
        }
    }
    if pending {
        traced.hand_over(sampler, film, &mut in_sampler);
        if let Some(b) = bands {
            b.rows_in(film, traced.rows_given);
        }
    }
    counts.halted = counts.samples < space.pixels() * u64::from(sampler.spp());
    watch.say_why_halted(&mut counts);
    counts.sampler_seconds = in_sampler.as_secs_f64();
    counts
}

/// Traces batches of sample points: camera rays and the estimator's radiance.
struct Tracer<'s, 'e> {
    /// The scene and its camera.
    scene: &'s Scene,
    /// What each sample estimates.
    li: &'s Estimator<'e>,
    /// The render's seed.
    seed: u64,
    /// The sampler's streams (at least 1), each drawing the integrator's decisions from
    /// sequences of its own.
    streams: u32,
}

impl Tracer<'_, '_> {
    /// Traces `batch` in parallel into `results`, one per point, in its order.
    fn trace(&self, batch: &[SamplePoint], results: &mut Vec<SampleResult>) {
        let scene = self.scene;
        let full_width = u64::from(scene.film.resolution.0);
        // pbrt-v3 scales the differentials to the spacing of a pixel's samples: 1 / sqrt(spp),
        // of the render's whole budget (see `Scene::set_footprint_spp`).
        let diff_scale = scene.differential_scale;
        batch
            .par_iter()
            .map(|q| {
                let key = u64::from(q.pixel[1]) * full_width + u64::from(q.pixel[0]);
                let own = IndexStream {
                    count: self.streams,
                    which: q.index % self.streams,
                };
                // The integrator's decisions come after the dims the sampler drew.
                let mut stream = SampleStream::new(
                    key,
                    q.index / self.streams,
                    own.seed(self.seed),
                    SOBOL_DIMS_USED,
                );
                let sample = CameraSample {
                    film: Vec2::from(q.film),
                    lens: Vec2::from(q.lens),
                    time: q.time,
                };
                let li = self.li;
                // A sample the realistic camera's lens vignettes counts, black (pbrt-v3).
                let Some((ray, diff, weight)) =
                    scene.camera.weighted_ray(&sample, scene.uses_differentials)
                else {
                    return (Spectrum::ZERO, 0, Default::default(), Vec::new());
                };
                let diff = diff.map(|d| d.scaled(&ray, diff_scale));
                let r = li(scene, ray, diff.as_ref(), &mut stream);
                // Every camera but the realistic one weighs 1: x * 1 is x, images unchanged.
                // bdpt's light-tracing splats are not the camera sample's: not weighted.
                (
                    r.l * weight,
                    r.rays,
                    r.first_hit,
                    crate::integrator::bdpt::take_splats(),
                )
            })
            .collect_into_vec(results);
    }
}

/// A render's [`Stop`] rules and what they keep between batches.
struct Watch<'s, 'a> {
    /// The rules.
    stop: &'s Stop<'a>,
    /// When the render started.
    start: Instant,
    /// The pixels rendered (at least 1).
    pixels: u64,
    /// The samples traced at which the noise threshold is next looked at: once per sample per
    /// pixel given (it reads every pixel), from `min_spp` on.
    next_check: u64,
    /// When each checkpoint last looked.
    last_look: Vec<Instant>,
    /// Set once the sampler planned for fewer samples than its budget to end in the time.
    planned_short: bool,
}

impl<'s, 'a> Watch<'s, 'a> {
    /// The rules of `stop` for a render of `pixels` pixels starting now.
    fn new(stop: &'s Stop<'a>, pixels: u64) -> Self {
        Self {
            stop,
            start: Instant::now(),
            pixels,
            next_check: pixels * u64::from(stop.min_spp.max(2)),
            last_look: vec![Instant::now(); stop.checkpoints.len()],
            planned_short: false,
        }
    }

    /// Lets the checkpoints that are due look at the film; one that waits for whole passes
    /// looks only when `pass_done`.
    fn look(&mut self, film: &Film, pass_done: bool) {
        for (c, last) in self.stop.checkpoints.iter().zip(&mut self.last_look) {
            if last.elapsed() >= c.every && (!c.whole_passes || pass_done) {
                (c.look)(film, self.start.elapsed().as_secs_f64());
                *last = Instant::now();
            }
        }
    }

    /// Halts the sampler, once, when a signal came, the time limit passed or the image is
    /// below the noise threshold, and records why in `counts`.
    fn check(&mut self, film: &Film, sampler: &mut dyn Sampler, counts: &mut RenderCounts) {
        if counts.halted_by.is_some() {
            return;
        }
        let stop = self.stop;
        if stop
            .interrupt
            .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed))
        {
            counts.halted_by = Some(Halt::Signal);
            sampler.halt();
        } else if stop.time_limit.is_some_and(|t| self.start.elapsed() >= t) {
            counts.halted_by = Some(Halt::Time);
            sampler.halt();
        } else if let Some(threshold) = stop.noise_threshold {
            if counts.samples >= self.next_check {
                self.next_check = counts.samples + self.pixels;
                if relative_error(&film.pixel_stats()) < threshold {
                    counts.halted_by = Some(Halt::Noise);
                    sampler.halt();
                }
            }
        }
    }

    /// With a time limit and [`Stop::plan_to_time`], tells the sampler how many samples per
    /// pixel fit in the time left at the speed so far.
    fn plan_to_time(&mut self, sampler: &mut dyn Sampler, counts: &RenderCounts) {
        let stop = self.stop;
        let (Some(limit), true, None) = (stop.time_limit, stop.plan_to_time, counts.halted_by)
        else {
            return;
        };
        // From one sample per pixel on, the speed so far is a fair guess of the rest.
        if counts.samples >= self.pixels {
            let spp = spp_in_time(counts.samples, self.pixels, self.start.elapsed(), limit);
            // Once planned short, a later estimate may raise the plan again (to the cap).
            if (spp < sampler.spp() || self.planned_short)
                && sampler.plan_for(spp.min(sampler.spp()))
            {
                self.planned_short = true;
            }
        }
    }

    /// Once the render ended, why it halted (`counts.halted` set): none when it did not.
    fn say_why_halted(&self, counts: &mut RenderCounts) {
        if !counts.halted {
            counts.halted_by = None;
        } else if counts.halted_by.is_none() && self.planned_short {
            // It ended as planned, the time spent.
            counts.halted_by = Some(Halt::Time);
        } else if counts.halted_by.is_none() && self.stop.noise_threshold.is_some() {
            // A sampler that stops where it is settled ended by itself, everywhere settled.
            counts.halted_by = Some(Halt::Noise);
        }
    }
}

/// The samples per pixel that fit in `limit` when `samples` over `pixels` took `elapsed`:
/// those given and, at the same speed, those of the time left.
fn spp_in_time(samples: u64, pixels: u64, elapsed: Duration, limit: Duration) -> u32 {
    let spent = elapsed.as_secs_f64().max(1e-6);
    let left = limit.saturating_sub(elapsed).as_secs_f64();
    let total = samples as f64 * (1.0 + left / spent);
    (total / pixels.max(1) as f64)
        .ceil()
        .min(f64::from(u32::MAX)) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use acr_plugins::PixelStats;

    #[test]
    fn the_samples_that_fit_follow_the_speed_so_far() {
        let s = Duration::from_secs_f64;
        // 1,000 samples over 100 pixels in 1 s: 20 spp more fit in 2 s more.
        assert_eq!(spp_in_time(1000, 100, s(1.0), s(3.0)), 30);
        // Past the limit, only what was given.
        assert_eq!(spp_in_time(1000, 100, s(4.0), s(3.0)), 10);
        assert_eq!(spp_in_time(0, 100, s(0.0), s(3.0)), 0);
    }

    #[test]
    fn relative_error_is_the_mean_standard_error_over_the_mean() {
        // A pixel of samples 0.5 and 1.5: mean 1, sample variance 0.5, variance of the mean
        // 0.25, standard error 0.5; over 1 + 0.01.
        let mut noisy = PixelStats::default();
        noisy.add(Spectrum::splat(0.5));
        noisy.add(Spectrum::splat(1.5));
        let mut flat = PixelStats::default();
        flat.add(Spectrum::splat(2.0));
        flat.add(Spectrum::splat(2.0));
        let e = relative_error(&[noisy, flat]);
        assert!((e - 0.5 * (0.5 / 1.01)).abs() < 1e-6, "{e}");
        // A pixel with one sample has no estimate yet: it counts as 1.
        let mut one = PixelStats::default();
        one.add(Spectrum::splat(1.0));
        assert_eq!(relative_error(&[one]), 1.0);
        assert_eq!(relative_error(&[]), 0.0);
    }
}
