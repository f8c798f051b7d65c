//! Rendering by bands of rows (docs/reconstruction.md, "Rendering by bands"): for a filter that
//! makes the image band by band from each band's rows and a halo around them
//! ([`Filter::bands`], nfor) and a sampler whose points depend on the pixel and index alone
//! ([`Sampler::walk_by_rows`]), the sampler walks the image a few rows at a time, each band is
//! filtered as soon as the film holds every sample of its rows and halo, and the half buffers'
//! rows no later band reads are freed. The film then holds a band and its two halos, not the
//! image; the image is the same, byte for byte, as the whole image's filtered at the end.

use super::{render_loop, sample_space, RenderCounts, Stop};
use crate::camera::CameraSample;
use crate::first_hit::FeatureImage;
use crate::geometry::{Spectrum, Vec2};
use crate::integrator::Integrator;
use crate::scene::Scene;
use acr_plugins::filters::BandPlan;
use acr_plugins::{Film, Filter, Sampler};
use rayon::prelude::*;
use std::collections::VecDeque;
use std::ops::Range;
use std::time::Instant;

/// Rows the sampler walks at a time: the filter's tile side, so that the rows of a band and
/// its halo (whole tiles) are in as soon as their last chunk is.
pub const CHUNK_ROWS: u32 = 32;

/// The bands of a render by bands: those left to filter and the image's rows made so far.
pub struct Bands<'f> {
    filter: &'f dyn Filter,
    plan: BandPlan,
    /// The bands not yet filtered, top first (crop rows).
    left: VecDeque<Range<usize>>,
    /// The crop's rows.
    height: usize,
    /// Sampled rows above the crop's first row (the sampler's space is the crop widened by
    /// the filter's radius).
    rows_above: usize,
    /// Crop rows whose every sample the film holds.
    rows_in: usize,
    /// The image's rows made so far, row-major.
    image: Vec<Spectrum>,
    /// Seconds spent filtering.
    seconds: f64,
    /// Bands filtered.
    made: u64,
}

/// What a render by bands made.
#[derive(Clone, Debug, Default)]
pub struct Banded {
    /// The image, row-major over the crop (before the film's unfiltered splats and scale).
    pub image: Vec<Spectrum>,
    /// Seconds spent filtering.
    pub seconds: f64,
    /// Bands filtered.
    pub bands: u64,
}

impl<'f> Bands<'f> {
    /// The rows a film's half buffers need room for in a render by bands with `filter`
    /// ([`Film::keep_pixel_buffers_by_rows`]) for an image of `height` rows: a band, its halo
    /// above and below, and a chunk under way. None for a filter that needs the whole film.
    pub fn window(filter: &dyn Filter, height: u32) -> Option<usize> {
        let plan = filter.bands(height as usize)?;
        Some(plan.rows.max(1) + 2 * plan.halo + CHUNK_ROWS as usize)
    }

    /// A render by bands of `scene` into `film` with `filter`, when the filter makes the image
    /// band by band, the film's half buffers hold rows only
    /// ([`Film::keep_pixel_buffers_by_rows`]) and `sampler` can walk by rows: the sampler is
    /// then set to walk [`CHUNK_ROWS`] rows at a time. None otherwise.
    pub fn new(
        scene: &Scene,
        filter: &'f dyn Filter,
        sampler: &mut dyn Sampler,
        film: &Film,
    ) -> Option<Self> {
        let (w, h) = film.settings().size();
        let plan = filter.bands(h as usize)?;
        let by_rows = film.pixel_buffers().is_some_and(|b| b.by_rows());
        if !by_rows || sampler.streams() != 1 || !sampler.walk_by_rows(CHUNK_ROWS) {
            return None;
        }
        let space = sample_space(scene, filter.kernel().radius());
        let rows_above = scene.film.crop[2].saturating_sub(space.y0) as usize;
        Some(Self {
            filter,
            plan,
            left: plan.layout(h as usize).into(),
            height: h as usize,
            rows_above,
            rows_in: 0,
            image: Vec::with_capacity(w as usize * h as usize),
            seconds: 0.0,
            made: 0,
        })
    }

    /// The film holds every sample of the sampler's first `rows_given` rows: filters each band
    /// whose rows and halo are all in, and frees the rows no later band reads.
    pub fn rows_in(&mut self, film: &mut Film, rows_given: u32) {
        let rows = (rows_given as usize).saturating_sub(self.rows_above);
        self.rows_in = self.rows_in.max(rows.min(self.height));
        while let Some(band) = self.left.front() {
            if self.plan.read(band, self.height).end > self.rows_in {
                break;
            }
            let band = band.clone();
            self.left.pop_front();
            self.make(film, band);
        }
    }

    /// Filters `band` from the film, then frees the rows above the next band's halo.
    fn make(&mut self, film: &mut Film, band: Range<usize>) {
        let start = Instant::now();
        film.hold_through(self.plan.read(&band, self.height).end);
        self.image
            .extend(self.filter.reconstruct_rows(film, band.clone()));
        film.release_rows(band.end.saturating_sub(self.plan.halo));
        self.seconds += start.elapsed().as_secs_f64();
        self.made += 1;
    }

    /// Filters the bands left (after a halt, from the samples they have: rows never sampled
    /// come out black) and frees the half buffers.
    pub fn finish(mut self, film: &mut Film) -> Banded {
        while let Some(band) = self.left.pop_front() {
            self.make(film, band);
        }
        film.release_rows(self.height);
        Banded {
            image: self.image,
            seconds: self.seconds,
            bands: self.made,
        }
    }
}

/// [`super::render_with_features`] by bands: `bands` filters each band as soon as the film
/// holds it (and, once the loop ends, those left). Not for mlt or sppm, which drive their own
/// sampling.
#[allow(clippy::too_many_arguments)]
pub fn render_in_bands(
    scene: &Scene,
    integrator: &Integrator,
    sampler: &mut dyn Sampler,
    film: &mut Film,
    seed: u64,
    stop: &Stop,
    progress: Option<&indicatif::ProgressBar>,
    features: Option<&mut FeatureImage>,
    bands: &mut Bands<'_>,
) -> RenderCounts {
    let li = |scene: &Scene, ray, diff: Option<&_>, stream: &mut _| {
        integrator.li(scene, ray, diff, stream)
    };
    render_loop(
        scene,
        &li,
        sampler,
        film,
        seed,
        stop,
        progress,
        features,
        Some(bands),
    )
}

/// The factor that brings the first-hit depth to a common scale for a reconstruction that
/// regresses on it (nfor's ridge suits every scene then): the inverse of the mean distance to
/// the first surface of camera rays through a grid of the crop's pixel centres (about 65,536
/// of them; the lens centre, mid-shutter; interfaces between media passed through), 1 when
/// none meets a surface. Known before any sample, it is the same whether the image is
/// filtered whole or by bands.
pub fn depth_scale(scene: &Scene) -> f32 {
    let [x0, x1, y0, y1] = scene.film.crop;
    let pixels = u64::from(x1 - x0) * u64::from(y1 - y0);
    let step = ((pixels as f64 / 65_536.0).sqrt().ceil() as usize).max(1);
    let rows: Vec<u32> = (y0..y1).step_by(step).collect();
    // Summed by row, the rows in order: the same whatever the thread count.
    let sums: Vec<(f64, u64)> = rows
        .par_iter()
        .map(|&y| {
            (x0..x1)
                .step_by(step)
                .filter_map(|x| first_surface_distance(scene, x, y))
                .fold((0.0, 0), |(s, n), d| (s + d, n + 1))
        })
        .collect();
    let (sum, n) = sums
        .iter()
        .fold((0.0, 0u64), |(s, n), &(a, b)| (s + a, n + b));
    if sum > 0.0 {
        (n as f64 / sum) as f32
    } else {
        1.0
    }
}

/// The distance from the camera to the first surface along the ray through pixel (x, y)'s
/// centre, if it meets one.
fn first_surface_distance(scene: &Scene, x: u32, y: u32) -> Option<f64> {
    // Interfaces between media (surfaces without a material) passed at most this often.
    const PASSES: u32 = 64;
    let sample = CameraSample {
        film: Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
        lens: Vec2::splat(0.5),
        time: 0.5,
    };
    let (mut ray, _, _) = scene.camera.weighted_ray(&sample, false)?;
    let mut travelled = 0.0f64;
    for _ in 0..PASSES {
        let hit = scene.intersect(&ray)?;
        travelled += f64::from(ray.o.distance(hit.si.p));
        if hit.surface.material.is_some() {
            return (travelled > 0.0).then_some(travelled);
        }
        ray = hit.si.spawn_ray(ray.d);
    }
    None
}
