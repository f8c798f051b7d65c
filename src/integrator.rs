//! Integrators: `path` (unidirectional path tracing with light and BSDF sampling combined by
//! multiple importance sampling, and Russian roulette as pbrt-v3) and `directlighting`.
//!
//! The path integrator follows pbrt-v3's PathIntegrator in what it estimates, with one change
//! in how: the BSDF sample that continues the path also serves as the BSDF half of the MIS pair
//! for emission it hits (as pbrt-v4 does), where pbrt-v3 traces a separate ray for it. Same
//! expectation, one ray fewer per bounce.

use crate::features::{FirstHit, FirstHitProbe};
use crate::geometry::{Ray, Spectrum, SurfaceInteraction};
use crate::lightbvh::LightContext;
use crate::lightdistrib::LightStrategy;
use crate::sampling::power_heuristic;
use crate::scene::Scene;
use crate::stream::SampleStream;
use acr_parser::{Error, ParamList, ParamType, Result};
use acr_plugins::{Choice, Entry, Kind, ParamSpec, PluginInfo};

/// Most consecutive pass-through surfaces (`Material ""`) a ray may cross before it is
/// abandoned: a guard against a ray trapped between coincident interfaces.
const MAX_PASS_THROUGH: u32 = 256;

/// How `directlighting` samples the lights (pbrt-v3's "strategy").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectStrategy {
    /// Every light at every shading point.
    All,
    /// One light, chosen uniformly (as pbrt-v3's UniformSampleOneLight without a distribution).
    One,
}

/// An integrator and its settings.
#[derive(Clone, Debug)]
pub enum Integrator {
    /// `path`.
    Path {
        /// Longest path, in bounces.
        max_depth: u32,
        /// Russian roulette starts when the throughput falls below this.
        rr_threshold: f32,
        /// How a light is chosen for next-event estimation.
        light_strategy: LightStrategy,
    },
    /// `directlighting`.
    Direct {
        /// Specular recursion depth.
        max_depth: u32,
        /// Light sampling strategy.
        strategy: DirectStrategy,
    },
}

/// What one camera sample's estimate produced.
#[derive(Clone, Copy, Debug, Default)]
pub struct Radiance {
    /// Incident radiance along the camera ray.
    pub l: Spectrum,
    /// Rays traced for it (camera, continuation and shadow rays).
    pub rays: u32,
    /// What the camera path saw first (`--aov albedo/normal/depth`).
    pub first_hit: FirstHit,
}

/// Builds an integrator from its checked parameters.
pub type IntegratorBuild = fn(&Choice) -> Result<Integrator>;

/// Every integrator, by name.
pub static INTEGRATORS: &[Entry<IntegratorBuild>] = &[
    Entry {
        info: PluginInfo {
            kind: Kind::Integrator,
            name: "path",
            doc: "path tracing: light and BSDF sampling with MIS, Russian roulette (pbrt-v3 path)",
            params: &[
                ParamSpec::new(
                    "maxdepth",
                    ParamType::Integer,
                    "5",
                    "longest path, in bounces",
                ),
                ParamSpec::new(
                    "rrthreshold",
                    ParamType::Float,
                    "1",
                    "Russian roulette once the throughput's largest channel is below this",
                ),
                ParamSpec::new(
                    "lightsamplestrategy",
                    ParamType::String,
                    "bvh",
                    "how a light is chosen: bvh (pbrt-v4's light BVH), spatial (pbrt-v3's default), power or uniform",
                ),
            ],
        },
        build: Integrator::path,
    },
    Entry {
        info: PluginInfo {
            kind: Kind::Integrator,
            name: "directlighting",
            doc: "direct lighting plus specular reflection and refraction (pbrt-v3 directlighting)",
            params: &[
                ParamSpec::new(
                    "maxdepth",
                    ParamType::Integer,
                    "5",
                    "specular recursion depth",
                ),
                ParamSpec::new(
                    "strategy",
                    ParamType::String,
                    "all",
                    "all: every light at each point; one: one light chosen uniformly",
                ),
            ],
        },
        build: Integrator::direct,
    },
];

/// `maxdepth`, which must not be negative.
fn max_depth(params: &ParamList) -> Result<u32> {
    let d = params.int_or("maxdepth", 5)?;
    u32::try_from(d).map_err(|_| match params.get("maxdepth") {
        Some(p) => Error::at(&p.loc, format!("maxdepth {d} is negative")),
        None => Error::file("maxdepth", "negative"),
    })
}

impl Integrator {
    /// `path` from its parameters (pbrt-v3's defaults: maxdepth 5, rrthreshold 1).
    pub fn path(c: &Choice) -> Result<Self> {
        let params = &c.params;
        let name = params.string("lightsamplestrategy")?.unwrap_or("bvh");
        let Some(light_strategy) = LightStrategy::from_name(name) else {
            let p = params.get("lightsamplestrategy");
            let message =
                format!("lightsamplestrategy \"{name}\" is not bvh, spatial, power or uniform");
            return Err(match p {
                Some(p) => Error::at(&p.loc, message),
                None => Error::file("lightsamplestrategy", message),
            });
        };
        Ok(Integrator::Path {
            max_depth: max_depth(params)?,
            rr_threshold: params.float_or("rrthreshold", 1.0)? as f32,
            light_strategy,
        })
    }

    /// `directlighting` from its parameters (pbrt-v3's defaults: maxdepth 5, strategy all).
    pub fn direct(c: &Choice) -> Result<Self> {
        let params = &c.params;
        let strategy = match params.string("strategy")?.unwrap_or("all") {
            "all" => DirectStrategy::All,
            "one" => DirectStrategy::One,
            other => {
                let message = format!("strategy \"{other}\" is not \"all\" or \"one\"");
                return Err(match params.get("strategy") {
                    Some(p) => Error::at(&p.loc, message),
                    None => Error::file("strategy", message),
                });
            }
        };
        Ok(Integrator::Direct {
            max_depth: max_depth(params)?,
            strategy,
        })
    }

    /// The name, as the stats file reports it.
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Path { .. } => "path",
            Integrator::Direct { .. } => "directlighting",
        }
    }

    /// Radiance arriving along `ray`.
    pub fn li(&self, scene: &Scene, ray: Ray, stream: &mut SampleStream) -> Radiance {
        match *self {
            Integrator::Path {
                max_depth,
                rr_threshold,
                light_strategy,
            } => path_li(scene, ray, stream, max_depth, rr_threshold, light_strategy),
            Integrator::Direct {
                max_depth,
                strategy,
            } => {
                let mut tally = Tally::default();
                let l = direct_li(scene, ray, stream, max_depth, 0, strategy, &mut tally);
                Radiance {
                    l,
                    rays: tally.rays,
                    first_hit: tally.probe.features(),
                }
            }
        }
    }
}

/// One light sample at `si` with MIS against the BSDF (for non-delta lights): pbrt-v3's
/// EstimateDirect without its BSDF-sampling half, which the caller's next ray provides.
#[inline]
fn sample_light(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &crate::bsdf::Bsdf,
    light_index: u32,
    choice_pdf: f32,
    stream: &mut SampleStream,
    rays: &mut u32,
) -> Spectrum {
    let light = &scene.lights[light_index as usize];
    let u = stream.next_2d();
    let Some(ls) = light.sample_li(&scene.accel.world, si.p, u) else {
        return Spectrum::ZERO;
    };
    if ls.pdf <= 0.0 || ls.li == Spectrum::ZERO {
        return Spectrum::ZERO;
    }
    let f = bsdf.f(si.wo, ls.wi) * ls.wi.dot(si.shading_n).abs();
    if f == Spectrum::ZERO {
        return Spectrum::ZERO;
    }
    *rays += 1;
    if scene.occluded(si, ls.p) {
        return Spectrum::ZERO;
    }
    let light_pdf = ls.pdf * choice_pdf;
    if light.is_delta() {
        f * ls.li / light_pdf
    } else {
        let w = power_heuristic(1.0, light_pdf, 1.0, bsdf.pdf(si.wo, ls.wi));
        f * ls.li * w / light_pdf
    }
}

fn path_li(
    scene: &Scene,
    mut ray: Ray,
    stream: &mut SampleStream,
    max_depth: u32,
    rr_threshold: f32,
    light_strategy: LightStrategy,
) -> Radiance {
    let mut l = Spectrum::ZERO;
    let mut beta = Spectrum::ONE;
    let mut rays = 0u32;
    let mut depth = 0u32;
    let mut specular_bounce = false;
    let mut eta_scale = 1.0f32;
    // The previous scattering point and the BSDF density of the direction taken from it.
    let mut prev_p = ray.o;
    let mut prev_bsdf_pdf = 0.0f32;
    // Where the light for next-event estimation was chosen at the previous scattering point,
    // for the MIS weight of emission that the BSDF sample finds (`None`: none was chosen).
    let mut prev_ctx: Option<LightContext> = None;
    let mut pass_through = 0u32;
    let have_lights = !scene.lights.is_empty();
    let mut probe = FirstHitProbe::default();
    loop {
        rays += 1;
        let Some(hit) = scene.intersect(&ray) else {
            for &i in &scene.infinite_lights {
                let light = &scene.lights[i as usize];
                let le = light.le(ray.d.normalize());
                if depth == 0 || specular_bounce {
                    l += beta * le;
                } else {
                    let choice = prev_ctx.map_or(0.0, |ctx| {
                        scene.light_choice_pdf(light_strategy, ctx, i as usize)
                    });
                    let light_pdf = choice * light.pdf_le(ray.d.normalize());
                    l += beta * le * power_heuristic(1.0, prev_bsdf_pdf, 1.0, light_pdf);
                }
            }
            break;
        };
        let si = hit.si;
        probe.travel(ray.o, si.p);
        if let Some(li) = hit.surface.area_light {
            let light = &scene.lights[li as usize];
            let le = light.l(&si, si.wo);
            if le != Spectrum::ZERO {
                if depth == 0 || specular_bounce {
                    l += beta * le;
                } else {
                    let choice = prev_ctx.map_or(0.0, |ctx| {
                        scene.light_choice_pdf(light_strategy, ctx, li as usize)
                    });
                    let light_pdf =
                        choice * light.pdf_area_hit(&scene.accel.world, prev_p, si.p, si.n);
                    l += beta * le * power_heuristic(1.0, prev_bsdf_pdf, 1.0, light_pdf);
                }
            }
        }
        let Some(material) = hit.surface.material else {
            // An interface between media: continue in the same direction, same depth.
            pass_through += 1;
            if pass_through > MAX_PASS_THROUGH {
                break;
            }
            ray = si.spawn_ray(ray.d);
            continue;
        };
        if depth >= max_depth {
            break;
        }
        let material = &scene.materials[material as usize];
        let si = material.shading(&si);
        let bsdf = material.bsdf(&si);
        probe.surface(&si, &bsdf);
        prev_ctx = None;
        if have_lights && bsdf.has_non_specular() {
            let ctx = LightContext {
                p: si.p,
                n: si.shading_n,
            };
            prev_ctx = Some(ctx);
            match scene.choose_light(light_strategy, ctx, stream.next_1d()) {
                Some((light_index, choice_pdf)) => {
                    l += beta
                        * sample_light(
                            scene,
                            &si,
                            &bsdf,
                            light_index as u32,
                            choice_pdf,
                            stream,
                            &mut rays,
                        );
                }
                // No light can reach the point: the light sample's dimensions are spent all
                // the same, so that later decisions keep their place in the stream.
                None => {
                    stream.next_2d();
                }
            }
        }
        let u_lobe = stream.next_1d();
        let u = stream.next_2d();
        let Some(s) = bsdf.sample_f(si.wo, u, u_lobe) else {
            break;
        };
        if s.pdf <= 0.0 || s.f == Spectrum::ZERO {
            break;
        }
        beta *= s.f * s.wi.dot(si.shading_n).abs() / s.pdf;
        if !crate::geometry::is_valid_radiance(beta) {
            break;
        }
        specular_bounce = s.specular;
        let transmitted = s.wi.dot(si.n) * si.wo.dot(si.n) < 0.0;
        if s.specular && transmitted {
            let eta = bsdf.eta();
            eta_scale *= if si.wo.dot(si.n) > 0.0 {
                eta * eta
            } else {
                1.0 / (eta * eta)
            };
        }
        prev_p = si.p;
        prev_bsdf_pdf = if s.specular { 0.0 } else { s.pdf };
        ray = si.spawn_ray(s.wi);
        depth += 1;
        let rr_beta = beta * eta_scale;
        let m = rr_beta.max_element();
        if m < rr_threshold && depth > 3 {
            let q = (1.0 - m).max(0.05);
            if stream.next_1d() < q {
                break;
            }
            beta /= 1.0 - q;
        }
    }
    Radiance {
        l,
        rays,
        first_hit: probe.features(),
    }
}

/// What a recursive estimate counts on its way: rays traced and the first-hit features.
#[derive(Default)]
struct Tally {
    rays: u32,
    probe: FirstHitProbe,
}

/// pbrt-v3's DirectLightingIntegrator: emission, direct light at the first non-specular hit
/// (MIS of light and BSDF sampling), and specular reflection and transmission recursively.
/// Specular recursion follows one sampled specular lobe per level (pbrt-v3 traces reflection
/// and transmission separately); same expectation.
fn direct_li(
    scene: &Scene,
    ray: Ray,
    stream: &mut SampleStream,
    max_depth: u32,
    depth: u32,
    strategy: DirectStrategy,
    tally: &mut Tally,
) -> Spectrum {
    let mut ray = ray;
    let mut pass_through = 0;
    let hit = loop {
        tally.rays += 1;
        let hit = scene.intersect(&ray);
        if let Some(h) = &hit {
            tally.probe.travel(ray.o, h.si.p);
        }
        match hit {
            None => {
                return scene
                    .infinite_lights
                    .iter()
                    .map(|&i| scene.lights[i as usize].le(ray.d.normalize()))
                    .sum();
            }
            Some(h) if h.surface.material.is_none() && pass_through < MAX_PASS_THROUGH => {
                pass_through += 1;
                ray = h.si.spawn_ray(ray.d);
            }
            Some(h) => break h,
        }
    };
    let si = hit.si;
    let mut l = Spectrum::ZERO;
    if let Some(li) = hit.surface.area_light {
        l += scene.lights[li as usize].l(&si, si.wo);
    }
    let Some(material) = hit.surface.material else {
        return l;
    };
    let material = &scene.materials[material as usize];
    let si = material.shading(&si);
    let bsdf = material.bsdf(&si);
    tally.probe.surface(&si, &bsdf);
    if bsdf.has_non_specular() && !scene.lights.is_empty() {
        match strategy {
            DirectStrategy::All => {
                // pbrt-v3's UniformSampleAllLights: each light's `nsamples`, averaged.
                for (i, &n) in scene.light_samples.iter().enumerate() {
                    let mut sum = Spectrum::ZERO;
                    for _ in 0..n {
                        sum += estimate_direct(
                            scene,
                            &si,
                            &bsdf,
                            i as u32,
                            1.0,
                            stream,
                            &mut tally.rays,
                        );
                    }
                    l += sum / n as f32;
                }
            }
            DirectStrategy::One => {
                let ctx = LightContext {
                    p: si.p,
                    n: si.shading_n,
                };
                if let Some((i, pdf)) =
                    scene.choose_light(LightStrategy::Uniform, ctx, stream.next_1d())
                {
                    l += estimate_direct(scene, &si, &bsdf, i as u32, pdf, stream, &mut tally.rays);
                }
            }
        }
    }
    if depth + 1 < max_depth {
        let u_lobe = stream.next_1d();
        let u = stream.next_2d();
        if let Some(s) = bsdf.sample_f(si.wo, u, u_lobe) {
            if s.specular && s.pdf > 0.0 {
                let weight = s.f * s.wi.dot(si.shading_n).abs() / s.pdf;
                if weight != Spectrum::ZERO && crate::geometry::is_valid_radiance(weight) {
                    let next = si.spawn_ray(s.wi);
                    l += weight
                        * direct_li(scene, next, stream, max_depth, depth + 1, strategy, tally);
                }
            }
        }
    }
    l
}

/// pbrt-v3's EstimateDirect: a light sample and a BSDF sample, combined by MIS.
fn estimate_direct(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &crate::bsdf::Bsdf,
    light_index: u32,
    choice_pdf: f32,
    stream: &mut SampleStream,
    rays: &mut u32,
) -> Spectrum {
    let light = &scene.lights[light_index as usize];
    let mut ld = sample_light(scene, si, bsdf, light_index, choice_pdf, stream, rays);
    if light.is_delta() {
        return ld;
    }
    let u_lobe = stream.next_1d();
    let u = stream.next_2d();
    let Some(s) = bsdf.sample_f(si.wo, u, u_lobe) else {
        return ld;
    };
    if s.specular || s.pdf <= 0.0 {
        return ld;
    }
    let f = s.f * s.wi.dot(si.shading_n).abs();
    if f == Spectrum::ZERO {
        return ld;
    }
    let ray = si.spawn_ray(s.wi);
    *rays += 1;
    let (li, light_pdf) = match scene.intersect(&ray) {
        Some(h) if h.surface.area_light == Some(light_index) => (
            light.l(&h.si, -s.wi),
            light.pdf_area_hit(&scene.accel.world, si.p, h.si.p, h.si.n),
        ),
        Some(_) => return ld,
        None => (light.le(s.wi), light.pdf_le(s.wi)),
    };
    if light_pdf <= 0.0 || li == Spectrum::ZERO {
        return ld;
    }
    let w = power_heuristic(1.0, s.pdf, 1.0, light_pdf * choice_pdf);
    ld += f * li * w / (s.pdf * choice_pdf);
    ld
}
