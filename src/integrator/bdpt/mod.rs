//! `bdpt`: pbrt-v3's bidirectional path tracer (docs/light-transport.md). Each camera sample
//! traces a camera subpath and a light subpath and evaluates every connection (s, t) with its
//! MIS weight; the strategies that reach the camera from the light side (t = 1) land on other
//! pixels and go to the film as unfiltered splats (see [`take_splats`]).
//!
//! The subpaths and the connection are generic over [`SampleSource`], so that mlt drives
//! them from its own primary sample space.

use crate::first_hit::FirstHitProbe;
use crate::geometry::{Ray, RayDifferentials, Spectrum, Vec2, Vec3};
use crate::integrator::{Integrator, Radiance};
use crate::lightbvh::LightContext;
use crate::lightdistrib::LightStrategy;
use crate::scene::Scene;
use crate::stream::SampleSource;
use acr_parser::Result;
use acr_plugins::Choice;
use std::cell::RefCell;

mod connect;
mod mis;
mod path_slots;
pub mod strategies;
mod subpath;
mod vertex;

pub use connect::{connect, Connection};
pub use path_slots::Subpath;
pub use subpath::{
    generate_camera_subpath, generate_camera_subpath_from, generate_camera_subpath_on_film,
    generate_light_subpath,
};
pub use vertex::{Mode, Vertex, VertexKind};

use super::MAX_PASS_THROUGH;

/// `bdpt`'s settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BdptSettings {
    /// Longest path, in bounces (pbrt-v3's `maxdepth`).
    pub max_depth: u32,
    /// How lights are chosen: with `bvh`, the s = 1 strategy's at the vertex it connects (as
    /// `path`) and light subpaths' by power; with the others, every choice of a sample by
    /// this strategy looked up at the camera (pbrt-v3's `lightsamplestrategy`).
    pub light_strategy: LightStrategy,
    /// Strategy images to write beside the output (pbrt-v3's `visualizestrategies` and
    /// `visualizeweights`), if asked.
    pub visualize: Option<strategies::Visualize>,
}

impl Integrator {
    /// `bdpt` from its parameters (pbrt-v3's defaults: maxdepth 5; the light strategy as
    /// `path`'s).
    pub fn bdpt(c: &Choice) -> Result<Self> {
        let s = super::path_settings(c)?;
        let params = &c.params;
        let weights = params.bool_or("visualizeweights", false)?;
        let visualize = if weights {
            Some(strategies::Visualize::Weights)
        } else if params.bool_or("visualizestrategies", false)? {
            Some(strategies::Visualize::Strategies)
        } else {
            None
        };
        Ok(Integrator::Bdpt(BdptSettings {
            // pbrt-v3 limits the depth to 5 when it writes the strategy images.
            max_depth: if visualize.is_some() {
                s.max_depth.min(5)
            } else {
                s.max_depth
            },
            light_strategy: s.light_strategy,
            visualize,
        }))
    }
}

/// Before a render with `integrator` of `scene`: starts bdpt's strategy images when asked.
pub fn begin_render(integrator: &Integrator, scene: &Scene) {
    if let Integrator::Bdpt(BdptSettings {
        visualize: Some(_), ..
    }) = integrator
    {
        strategies::start(scene.film.resolution);
    }
}

/// After it, `samples` traced: writes bdpt's strategy images beside `output`, if asked.
pub fn end_render(
    integrator: &Integrator,
    scene: &Scene,
    output: &std::path::Path,
    samples: u64,
) -> Result<(), String> {
    if let Integrator::Bdpt(BdptSettings {
        visualize: Some(_), ..
    }) = integrator
    {
        let (w, h) = scene.film.resolution;
        strategies::finish(
            output,
            (u64::from(w) * u64::from(h)) as f64 / samples.max(1) as f64,
        )?;
    }
    Ok(())
}

/// How lights are chosen: once per sample for the light subpath's origin (at the camera, as
/// pbrt-v3), and, with the light BVH, at the connected vertex for the s = 1 strategy.
#[derive(Clone, Copy, Debug)]
pub struct LightChoice {
    /// The s = 1 strategy's.
    strategy: LightStrategy,
    /// The origin's (never the BVH: it bounds a shading point's light).
    origin: LightStrategy,
    /// Where the origin's choice is looked up (the camera, as pbrt-v3).
    at: LightContext,
    /// The scene has one light: every choice is that light, with probability 1 (the light
    /// BVH's importance is not asked; where it would say 0 the light sends nothing there).
    single: bool,
}

impl LightChoice {
    /// The choices of `strategy` in `scene` for a sample whose camera vertex is at `camera`.
    pub fn new(scene: &Scene, strategy: LightStrategy, camera: Vec3) -> Self {
        Self {
            single: scene.lights.len() == 1,
            strategy,
            origin: match strategy {
                LightStrategy::Bvh => LightStrategy::Power,
                s => s,
            },
            at: LightContext {
                p: camera,
                n: Vec3::ZERO,
            },
        }
    }

    /// Chooses a light subpath's light with `u`: its index and probability.
    pub fn sample_origin(&self, scene: &Scene, u: f32) -> Option<(usize, f32)> {
        if self.single {
            return Some((0, 1.0));
        }
        scene.choose_light(self.origin, self.at, u)
    }

    /// The probability that [`LightChoice::sample_origin`] chooses `light`.
    pub fn origin_pdf(&self, scene: &Scene, light: usize) -> f32 {
        if self.single {
            return 1.0;
        }
        scene.light_choice_pdf(self.origin, self.at, light)
    }

    /// Where the s = 1 strategy chooses at `v`.
    fn context(v: &Vertex) -> LightContext {
        LightContext { p: v.p, n: v.ns }
    }

    /// The s = 1 strategy's choice at `v` with `u`: a light and its probability.
    pub fn sample_at(&self, scene: &Scene, v: &Vertex, u: f32) -> Option<(usize, f32)> {
        if self.single {
            return Some((0, 1.0));
        }
        if self.strategy != LightStrategy::Bvh {
            return self.sample_origin(scene, u);
        }
        scene.choose_light(self.strategy, Self::context(v), u)
    }

    /// The density of the s = 1 strategy's choice of the path's light endpoint over the
    /// origin's choice of it (1 when both choose alike).
    fn s1_ratio(
        &self,
        scene: &Scene,
        light: &[Vertex],
        camera: &[Vertex],
        sampled: Option<&Vertex>,
        s: usize,
        t: usize,
    ) -> f32 {
        if self.single || self.strategy != LightStrategy::Bvh {
            return 1.0;
        }
        let ends = match s {
            0 if t >= 2 => Some((&camera[t - 1], &camera[t - 2])),
            1 => sampled.map(|v| (v, &camera[t - 1])),
            _ if light.len() >= 2 => Some((&light[0], &light[1])),
            _ => None,
        };
        let Some((x0, x1)) = ends else { return 1.0 };
        let at = Self::context(x1);
        let (num, den) = if x0.is_infinite_light(scene) {
            let w = (x1.p - x0.p).normalize_or_zero();
            (
                vertex::infinite_light_density(scene, w, |i| {
                    scene.light_choice_pdf(self.strategy, at, i)
                }),
                vertex::infinite_light_density(scene, w, |i| self.origin_pdf(scene, i)),
            )
        } else {
            let Some(l) = x0.light else { return 1.0 };
            (
                scene.light_choice_pdf(self.strategy, at, l as usize),
                self.origin_pdf(scene, l as usize),
            )
        };
        let r = num / den;
        if r.is_finite() {
            r
        } else if num > 0.0 {
            f32::MAX
        } else {
            1.0
        }
    }
}

thread_local! {
    /// The t = 1 strategies' splats of the sample this thread traced last.
    static SPLATS: RefCell<Vec<(Vec2, Spectrum)>> = const { RefCell::new(Vec::new()) };
    /// The subpaths' vertices, reused from sample to sample.
    static PATHS: RefCell<(Subpath, Subpath)> = const { RefCell::new((Subpath::new(), Subpath::new())) };
}

/// The splats (raster position, value) of the sample this thread traced last, taken: the
/// render loop adds them to the film after each batch, in the batch's order. Empty (and
/// allocation-free) after any other integrator's sample.
pub fn take_splats() -> Vec<(Vec2, Spectrum)> {
    SPLATS.with(|s| {
        let mut s = s.borrow_mut();
        if s.is_empty() {
            Vec::new()
        } else {
            std::mem::take(&mut *s)
        }
    })
}

/// One camera sample of bdpt: the radiance of the strategies with t >= 2, the t = 1 ones
/// left for [`take_splats`].
pub fn bdpt_li<S: SampleSource + ?Sized>(
    scene: &Scene,
    ray: Ray,
    diff: Option<&RayDifferentials>,
    sampler: &mut S,
    settings: BdptSettings,
) -> Radiance {
    PATHS.with(|paths| {
        let (camera, light) = &mut *paths.borrow_mut();
        let max_depth = settings.max_depth as usize;
        let n_camera =
            generate_camera_subpath_from(scene, ray, diff, sampler, max_depth + 2, camera);
        let choice = LightChoice::new(scene, settings.light_strategy, ray.o);
        let n_light =
            generate_light_subpath(scene, sampler, max_depth + 1, ray.time, &choice, light);
        let mut rays = (n_camera + n_light) as u32;
        let mut l = Spectrum::ZERO;
        let mut probe = FirstHitProbe::default();
        for w in camera.windows(2) {
            probe.travel(w[0].p, w[1].p);
            match (&w[1].surface, w[1].media.inside) {
                (Some(s), _) => probe.surface(&s.si, &s.bsdf),
                // A medium vertex: the medium's albedo, as volpath's first hit.
                (None, Some(m)) if w[1].kind == VertexKind::Medium => {
                    probe.medium(scene.media[m as usize].albedo());
                    break;
                }
                _ => break,
            }
        }
        let mut shown = Vec::new();
        SPLATS.with(|splats| {
            let mut splats = splats.borrow_mut();
            for t in 1..=n_camera {
                // s = 1 samples its own light vertex: it runs even when the light subpath made
                // none (pbrt-v3 skips it then, which loses light where a light's emission
                // sample can come out black: a projection's or a goniometric map's zeros).
                for s in 0..=n_light.max(1) {
                    let depth = (t + s) as i64 - 2;
                    if (s == 1 && t == 1) || depth < 0 || depth > max_depth as i64 {
                        continue;
                    }
                    let c = connect(scene, light, camera, s, t, &choice, sampler);
                    rays += u32::from(c.traced);
                    if settings.visualize.is_some() && c.l != Spectrum::ZERO {
                        shown.push((s, t, c));
                    }
                    if t != 1 {
                        l += c.l;
                    } else if let (Some(r), true) = (c.raster, c.l != Spectrum::ZERO) {
                        splats.push((r, c.l));
                    }
                }
            }
        });
        if let Some(v) = settings.visualize {
            show_strategies(scene, &ray, v, &shown);
        }
        Radiance {
            l,
            rays,
            first_hit: probe.features(),
        }
    })
}

/// Adds one sample's strategies to the strategy images: t >= 2 at the camera sample's raster
/// position (found from the camera ray; perspective cameras only), t = 1 where it landed.
fn show_strategies(
    scene: &Scene,
    ray: &Ray,
    v: strategies::Visualize,
    shown: &[(usize, usize, Connection)],
) {
    let here = scene
        .camera
        .we(ray.o, ray.d.normalize(), ray.time)
        .map(|(_, r)| r);
    let list: Vec<_> = shown
        .iter()
        .filter_map(|&(s, t, c)| {
            let p = if t == 1 { c.raster } else { here }?;
            let value = match v {
                strategies::Visualize::Weights => c.l,
                strategies::Visualize::Strategies if c.mis_weight > 0.0 => c.l / c.mis_weight,
                strategies::Visualize::Strategies => Spectrum::ZERO,
            };
            Some((s, t, p, value))
        })
        .collect();
    strategies::add(&list);
}
