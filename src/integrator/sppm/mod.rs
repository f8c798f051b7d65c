//! `sppm`: pbrt-v3's stochastic progressive photon mapping (`SPPMIntegrator`,
//! docs/light-transport.md). Each iteration traces one camera path per pixel to its first
//! diffuse (or last glossy) vertex, the visible point ([`visible`]); puts the visible points in
//! a hash grid ([`grid`]); shoots photons from the lights ([`photons`]) whose hits after the
//! first bounce add to the visible points within each pixel's radius; then shrinks the radii
//! and folds the photons into each pixel's flux. The image is direct light averaged over the
//! iterations plus the flux over the photons shot and each pixel's disc.
//!
//! It drives its own sampling: the render loop hands it the film, and the image goes to the
//! film's unfiltered splats, one value per pixel at its centre.

use crate::geometry::{Spectrum, Vec2};
use crate::render::stop::{Halt, RenderCounts, Stop};
use crate::scene::Scene;
use acr_parser::{Error, ParamList, ParamType, Result};
use acr_plugins::film::UnfilteredSplats;
use acr_plugins::{Choice, Film, ParamSpec};
use std::time::Instant;

mod grid;
mod photons;
mod visible;

/// `sppm`'s settings (pbrt-v3's parameters and defaults).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SppmSettings {
    /// Iterations (`iterations`, or pbrt-v3's older `numiterations`; `--spp` overrides it).
    pub iterations: u32,
    /// Photons shot per iteration; `None`: one per pixel of the crop (pbrt-v3's -1).
    pub photons_per_iteration: Option<u32>,
    /// Every pixel's initial search radius, in world units.
    pub radius: f32,
    /// Longest camera path and photon path, in bounces.
    pub max_depth: u32,
    /// pbrt-v3 writes the image every this many iterations; acr writes partial images by
    /// time instead (`--write-partial-images`), so it is read and checked but not used.
    pub image_write_frequency: Option<u32>,
}

/// `sppm`'s parameters, as `acr plugins` lists them.
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec::new(
        "iterations",
        ParamType::Integer,
        "64",
        "camera passes, each followed by a photon pass (--spp sets it)",
    ),
    ParamSpec::new(
        "numiterations",
        ParamType::Integer,
        "64",
        "older name of iterations (iterations wins when both are given)",
    ),
    ParamSpec::new(
        "photonsperiteration",
        ParamType::Integer,
        "-1",
        "photons per iteration; -1: one per pixel",
    ),
    ParamSpec::new(
        "radius",
        ParamType::Float,
        "1",
        "initial search radius of every pixel, world units",
    ),
    ParamSpec::new(
        "maxdepth",
        ParamType::Integer,
        "5",
        "longest camera and photon path, in bounces",
    ),
    ParamSpec::new(
        "imagewritefrequency",
        ParamType::Integer,
        "2147483647",
        "ignored: acr writes partial images by time (--write-partial-images)",
    ),
];

/// An error at parameter `name`'s place in the scene file (or naming it, from the command line).
fn param_error(params: &ParamList, name: &str, message: String) -> Error {
    match params.get(name) {
        Some(p) => Error::at(&p.loc, message),
        None => Error::file(name, message),
    }
}

/// An integer parameter that must be at least `least`.
fn at_least(params: &ParamList, name: &str, default: i32, least: i32) -> Result<i32> {
    let v = params.int_or(name, default)?;
    if v < least {
        return Err(param_error(
            params,
            name,
            format!("{name} {v} is less than {least}"),
        ));
    }
    Ok(v)
}

impl SppmSettings {
    /// The settings from `sppm`'s checked parameters: located errors for zero iterations, zero
    /// photons, a radius that is not positive, a negative depth.
    pub fn from_choice(c: &Choice) -> Result<Self> {
        let params = &c.params;
        let name = if params.get("iterations").is_some() {
            "iterations"
        } else {
            "numiterations"
        };
        let iterations = at_least(params, name, 64, 1)? as u32;
        let photons = params.int_or("photonsperiteration", -1)?;
        if photons == 0 {
            return Err(param_error(
                params,
                "photonsperiteration",
                "photonsperiteration is 0: no photon would be shot (-1 shoots one per pixel)"
                    .into(),
            ));
        }
        let radius = params.float_or("radius", 1.0)?;
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(param_error(
                params,
                "radius",
                format!("radius {radius} is not a positive finite distance"),
            ));
        }
        let frequency = at_least(params, "imagewritefrequency", i32::MAX, 1)?;
        Ok(Self {
            iterations,
            photons_per_iteration: u32::try_from(photons).ok(),
            radius: radius as f32,
            max_depth: at_least(params, "maxdepth", 5, 0)? as u32,
            image_write_frequency: (frequency != i32::MAX).then_some(frequency as u32),
        })
    }
}

/// What a pixel keeps from iteration to iteration (pbrt-v3's `SPPMPixel` less its visible
/// point, which lives for one iteration).
#[derive(Clone, Copy, Debug)]
struct PixelState {
    /// The search radius.
    radius: f32,
    /// Direct light (and emission seen) summed over the iterations.
    ld: Spectrum,
    /// The photon count the radius was shrunk by so far.
    n: f32,
    /// The flux gathered, scaled as the radius shrank.
    tau: Spectrum,
}

/// pbrt-v3's share of new photons kept when a radius shrinks.
const GAMMA: f32 = 2.0 / 3.0;

impl PixelState {
    /// pbrt-v3's per-pixel update after a photon pass: `m` photons found the visible point of
    /// throughput `beta`, bringing flux `phi`; the radius shrinks and `tau` follows it.
    fn update(&mut self, beta: Spectrum, phi: Spectrum, m: u32) {
        if m == 0 {
            return;
        }
        let m = m as f32;
        let n_new = self.n + GAMMA * m;
        let r_new = self.radius * (n_new / (self.n + m)).sqrt();
        self.tau = (self.tau + beta * phi) * (r_new * r_new) / (self.radius * self.radius);
        self.n = n_new;
        self.radius = r_new;
    }

    /// The pixel's value after `iterations` iterations of `photons` photons each.
    fn value(&self, iterations: u32, photons: u64) -> Spectrum {
        let np = (u64::from(iterations) * photons) as f32;
        let r2 = self.radius * self.radius;
        self.ld / iterations as f32 + self.tau / (np * std::f32::consts::PI * r2)
    }
}

/// The pixels of the film's crop, row-major.
#[derive(Clone, Copy, Debug)]
struct Crop {
    x0: u32,
    y0: u32,
    width: u32,
    height: u32,
}

impl Crop {
    fn of(scene: &Scene) -> Self {
        let [x0, x1, y0, y1] = scene.film.crop;
        Self {
            x0,
            y0,
            width: x1.saturating_sub(x0),
            height: y1.saturating_sub(y0),
        }
    }

    fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Raster coordinates of pixel `i`.
    fn pixel(&self, i: usize) -> (u32, u32) {
        let w = self.width.max(1) as usize;
        (self.x0 + (i % w) as u32, self.y0 + (i / w) as u32)
    }
}

/// Puts the image after `iterations` iterations on the film: its unfiltered splats replaced by
/// one value per pixel at the pixel's centre, scale 1.
fn to_film(film: &mut Film, crop: Crop, pixels: &[PixelState], iterations: u32, photons: u64) {
    let splats: Vec<(Vec2, Spectrum)> = pixels
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (x, y) = crop.pixel(i);
            let at = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            (at, p.value(iterations.max(1), photons))
        })
        .collect();
    *film.unfiltered_mut() = UnfilteredSplats::default();
    film.unfiltered_mut().set_scale(1.0);
    film.add_splats(&splats);
}

/// Renders `scene` with sppm into `film` (its unfiltered splats): `settings.iterations`
/// iterations, fewer when `stop`'s time limit passes or a signal comes (checked after each
/// iteration; the image is that of the iterations done). `stop`'s checkpoints look at the
/// image after the iterations during which they fell due. Deterministic per `seed` whatever
/// the thread count.
pub fn render(
    scene: &Scene,
    settings: &SppmSettings,
    film: &mut Film,
    seed: u64,
    stop: &Stop,
    progress: Option<&indicatif::ProgressBar>,
) -> RenderCounts {
    let start = Instant::now();
    let crop = Crop::of(scene);
    let photons = settings
        .photons_per_iteration
        .map_or(crop.pixels() as u64, u64::from);
    let mut pixels = vec![
        PixelState {
            radius: settings.radius,
            ld: Spectrum::ZERO,
            n: 0.0,
            tau: Spectrum::ZERO,
        };
        crop.pixels()
    ];
    let mut counts = RenderCounts::default();
    if let Some(p) = progress {
        p.set_length(u64::from(settings.iterations));
    }
    let mut shooter = photons::Shooter::new(scene, settings.max_depth, seed);
    let mut last_look = vec![Instant::now(); stop.checkpoints.len()];
    let mut visible = Vec::new();
    let (mut radii, mut grid) = (Vec::new(), None);
    let mut done = 0u32;
    while done < settings.iterations {
        let iter = done;
        let pass = visible::CameraPass {
            scene,
            crop,
            iteration: iter,
            iterations: settings.iterations,
            max_depth: settings.max_depth,
            seed,
        };
        counts.rays += pass.run(&mut pixels, &mut visible);
        counts.samples += crop.pixels() as u64;
        radii.clear();
        radii.extend(pixels.iter().map(|p| p.radius));
        // The grid is rebuilt in the last one's buffers.
        grid = grid::Grid::rebuild(&visible, &radii, grid.take());
        if let Some(grid) = &grid {
            let gathered = shooter.shoot(grid, &visible, &radii, iter, photons);
            counts.rays += gathered.rays;
            counts.dropped += gathered.dropped;
            for (i, p) in pixels.iter_mut().enumerate() {
                if let Some(vp) = &visible[i] {
                    let phi = gathered.phi[i];
                    let phi = Spectrum::new(phi[0] as f32, phi[1] as f32, phi[2] as f32);
                    p.update(vp.beta, phi, gathered.m[i]);
                }
            }
        }
        done += 1;
        if let Some(p) = progress {
            p.set_position(u64::from(done));
        }
        for (c, last) in stop.checkpoints.iter().zip(&mut last_look) {
            if last.elapsed() >= c.every {
                to_film(film, crop, &pixels, done, photons);
                (c.look)(film, start.elapsed().as_secs_f64());
                *last = Instant::now();
            }
        }
        if let Some(why) = halt(stop, start) {
            counts.halted_by = Some(why);
            break;
        }
    }
    to_film(film, crop, &pixels, done, photons);
    counts.dropped += film.unfiltered().dropped;
    counts.halted = done < settings.iterations;
    if !counts.halted {
        counts.halted_by = None;
    }
    counts
}

/// Why the render should stop after the iteration just done, if it should.
fn halt(stop: &Stop, start: Instant) -> Option<Halt> {
    let signalled = stop
        .interrupt
        .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed));
    if signalled {
        Some(Halt::Signal)
    } else if stop.time_limit.is_some_and(|t| start.elapsed() >= t) {
        Some(Halt::Time)
    } else {
        None
    }
}

/// Why `sppm` cannot run with these choices: an adaptive sampler (one whose batches do not
/// come in whole passes) or a noise threshold; sppm draws its own camera samples.
pub fn refuse(sampler: &dyn acr_plugins::Sampler, noise_threshold: bool) -> Option<String> {
    if noise_threshold {
        return Some(
            "--noise-threshold does not apply to the sppm integrator: it draws its own samples, \
             one camera path per pixel per iteration (use --spp for the iterations or \
             --time-limit)"
                .into(),
        );
    }
    (!sampler.whole_passes()).then(|| {
        format!(
            "the {} sampler places samples adaptively, but the sppm integrator draws its own \
             (one camera path per pixel per iteration): use random, stratified, halton or sobol",
            sampler.name()
        )
    })
}

#[cfg(test)]
mod tests;
