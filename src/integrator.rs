//! Integrators: `path` (unidirectional path tracing with light and BSDF sampling combined by
//! multiple importance sampling, and Russian roulette as pbrt-v3) and `directlighting`.
//!
//! The path integrator follows pbrt-v3's PathIntegrator in what it estimates, with one change
//! in how: the BSDF sample that continues the path also serves as the BSDF half of the MIS pair
//! for emission it hits (as pbrt-v4 does), where pbrt-v3 traces a separate ray for it. Same
//! expectation, one ray fewer per bounce.
//!
//! A path transmitted into a subsurface material leaves from an exit point that
//! the step in `src/integrator/subsurface.rs` finds (docs/subsurface.md).

use crate::first_hit::{FirstHit, FirstHitProbe};
use crate::geometry::{Ray, RayDifferentials, Spectrum, SurfaceInteraction, Vec3};
use crate::lightbvh::LightContext;
use crate::lightdistrib::LightStrategy;
use crate::sampling::power_heuristic;
use crate::scene::Scene;
use crate::stream::SampleStream;
use acr_parser::{Error, ParamList, ParamType, Result};
use acr_plugins::{Choice, Entry, Kind, ParamSpec, PluginInfo};

pub mod bdpt;
mod subsurface;
mod volpath;
pub use bdpt::BdptSettings;
pub use volpath::VolPathSettings;

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
    /// `volpath`: path tracing through participating media (docs/media.md).
    VolPath(VolPathSettings),
    /// `bdpt`: bidirectional path tracing (docs/light-transport.md).
    Bdpt(BdptSettings),
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

/// `path`'s and `volpath`'s Russian roulette threshold.
const RR_THRESHOLD: ParamSpec = ParamSpec::new(
    "rrthreshold",
    ParamType::Float,
    "1",
    "Russian roulette once the throughput's largest channel is below this",
);

/// `path`'s and `volpath`'s light choice.
const LIGHT_SAMPLE_STRATEGY: ParamSpec = ParamSpec::new(
    "lightsamplestrategy",
    ParamType::String,
    "bvh",
    "how a light is chosen: bvh (pbrt-v4's light BVH), spatial (pbrt-v3's default), power or uniform",
);

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
                RR_THRESHOLD,
                LIGHT_SAMPLE_STRATEGY,
            ],
        },
        build: Integrator::path,
    },
    Entry {
        info: PluginInfo {
            kind: Kind::Integrator,
            name: "volpath",
            doc: "path tracing through participating media: medium and phase sampling, MIS with lights through media (pbrt-v3 volpath)",
            params: &[
                ParamSpec::new(
                    "maxdepth",
                    ParamType::Integer,
                    "5",
                    "longest path, in scattering events (surface or medium)",
                ),
                RR_THRESHOLD,
                LIGHT_SAMPLE_STRATEGY,
            ],
        },
        build: Integrator::volpath,
    },
    Entry {
        info: PluginInfo {
            kind: Kind::Integrator,
            name: "bdpt",
            doc: "bidirectional path tracing: every connection of a camera and a light subpath, MIS-weighted; light tracing splatted (pbrt-v3 bdpt)",
            params: &[
                ParamSpec::new(
                    "maxdepth",
                    ParamType::Integer,
                    "5",
                    "longest path, in bounces",
                ),
                ParamSpec::new(
                    "lightsamplestrategy",
                    ParamType::String,
                    "bvh",
                    "bvh: the s = 1 strategy chooses at its vertex (as path), light subpaths by power; spatial, power, uniform: every choice at the camera (pbrt-v3)",
                ),
                ParamSpec::new(
                    "visualizestrategies",
                    ParamType::Bool,
                    "false",
                    "also write each strategy's unweighted image, bdpt_dDD_sSS_tTT.exr beside the output (maxdepth at most 5)",
                ),
                ParamSpec::new(
                    "visualizeweights",
                    ParamType::Bool,
                    "false",
                    "also write each strategy's weighted image, as visualizestrategies",
                ),
            ],
        },
        build: Integrator::bdpt,
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

/// `path`'s and `volpath`'s parameters (pbrt-v3's defaults: maxdepth 5, rrthreshold 1).
fn path_settings(c: &Choice) -> Result<VolPathSettings> {
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
    Ok(VolPathSettings {
        max_depth: max_depth(params)?,
        rr_threshold: params.float_or("rrthreshold", 1.0)? as f32,
        light_strategy,
    })
}

impl Integrator {
    /// `path` from its parameters (pbrt-v3's defaults: maxdepth 5, rrthreshold 1).
    pub fn path(c: &Choice) -> Result<Self> {
        let s = path_settings(c)?;
        Ok(Integrator::Path {
            max_depth: s.max_depth,
            rr_threshold: s.rr_threshold,
            light_strategy: s.light_strategy,
        })
    }

    /// `volpath` from its parameters (those of `path`, the same defaults).
    pub fn volpath(c: &Choice) -> Result<Self> {
        Ok(Integrator::VolPath(path_settings(c)?))
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
            Integrator::VolPath(_) => "volpath",
            Integrator::Bdpt(_) => "bdpt",
            Integrator::Direct { .. } => "directlighting",
        }
    }

    /// Radiance arriving along `ray`; `diff`, a camera ray's differentials, give the first hit
    /// its screen-space derivatives (for texture filtering and bump mapping, as pbrt-v3).
    pub fn li(
        &self,
        scene: &Scene,
        ray: Ray,
        diff: Option<&RayDifferentials>,
        stream: &mut SampleStream,
    ) -> Radiance {
        match *self {
            Integrator::Path {
                max_depth,
                rr_threshold,
                light_strategy,
            } => path_li(
                scene,
                ray,
                diff,
                stream,
                max_depth,
                rr_threshold,
                light_strategy,
            ),
            Integrator::VolPath(settings) => {
                volpath::volpath_li(scene, ray, diff, stream, settings)
            }
            Integrator::Bdpt(settings) => bdpt::bdpt_li(scene, ray, diff, stream, settings),
            Integrator::Direct {
                max_depth,
                strategy,
            } => {
                let mut tally = Tally::default();
                let l = direct_li(scene, ray, diff, stream, max_depth, 0, strategy, &mut tally);
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

/// The path's last scattering, as the MIS weight of the emission its next ray finds needs it.
#[derive(Clone, Copy)]
struct LastScatter {
    /// Whether the next ray is the camera ray or leaves a specular bounce: no light sample
    /// could have found what it finds, so its emission counts whole.
    whole: bool,
    /// The scattering point.
    p: Vec3,
    /// The BSDF density of the direction taken from it.
    bsdf_pdf: f32,
    /// Where the light for next-event estimation was chosen there (`None`: none was).
    ctx: Option<LightContext>,
}

impl LastScatter {
    /// Emission `le` of light `light` found by the path of throughput `beta`, weighted against
    /// the light sample at the last scattering, whose density of it `pdf_of_light` gives
    /// (times the chance of choosing the light).
    fn weigh(
        &self,
        scene: &Scene,
        strategy: LightStrategy,
        light: usize,
        beta: Spectrum,
        le: Spectrum,
        pdf_of_light: impl FnOnce() -> f32,
    ) -> Spectrum {
        if self.whole {
            return beta * le;
        }
        let choice = self
            .ctx
            .map_or(0.0, |ctx| scene.light_choice_pdf(strategy, ctx, light));
        let light_pdf = choice * pdf_of_light();
        beta * le * power_heuristic(1.0, self.bsdf_pdf, 1.0, light_pdf)
    }
}

/// Next-event estimation at `si` for the lights chosen at `ctx`: a light's sampled direct
/// radiance; `None` when no light can reach the point (its sample's dimensions are spent all
/// the same, so that later decisions keep their place in the stream).
fn next_event(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &crate::bsdf::Bsdf,
    ctx: LightContext,
    strategy: LightStrategy,
    stream: &mut SampleStream,
    rays: &mut u32,
) -> Option<Spectrum> {
    match scene.choose_light(strategy, ctx, stream.next_1d()) {
        Some((light_index, choice_pdf)) => Some(sample_light(
            scene,
            si,
            bsdf,
            light_index as u32,
            choice_pdf,
            stream,
            rays,
        )),
        None => {
            stream.next_2d();
            None
        }
    }
}

/// The path integrator's estimate of the radiance along `ray`: at each scattering a light
/// sample and a BSDF sample, emission found weighted by MIS, Russian roulette after depth 3.
fn path_li(
    scene: &Scene,
    mut ray: Ray,
    mut diff: Option<&RayDifferentials>,
    stream: &mut SampleStream,
    max_depth: u32,
    rr_threshold: f32,
    light_strategy: LightStrategy,
) -> Radiance {
    let mut l = Spectrum::ZERO;
    let mut beta = Spectrum::ONE;
    let mut rays = 0u32;
    let mut depth = 0u32;
    let mut eta_scale = 1.0f32;
    let mut last = LastScatter {
        whole: true,
        p: ray.o,
        bsdf_pdf: 0.0,
        ctx: None,
    };
    let mut pass_through = 0u32;
    let have_lights = !scene.lights.is_empty();
    let mut probe = FirstHitProbe::default();
    loop {
        rays += 1;
        let Some(hit) = scene.intersect(&ray) else {
            for &i in &scene.infinite_lights {
                let light = &scene.lights[i as usize];
                let le = light.le(ray.d.normalize());
                l += last.weigh(scene, light_strategy, i as usize, beta, le, || {
                    light.pdf_le(ray.d.normalize())
                });
            }
            break;
        };
        let mut si = hit.si;
        // Only the camera ray has differentials (pbrt-v3's path integrator spawns every later
        // ray, and the one through an interface, without them).
        if let Some(d) = diff.take() {
            si.compute_differentials(d);
        }
        probe.travel(ray.o, si.p);
        if let Some(li) = hit.surface.area_light {
            let light = &scene.lights[li as usize];
            let le = light.l(&si, si.wo);
            if le != Spectrum::ZERO {
                l += last.weigh(scene, light_strategy, li as usize, beta, le, || {
                    light.pdf_area_hit(&scene.accel.world, last.p, si.p, si.n)
                });
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
        let material_index = material;
        let material = &scene.materials[material as usize];
        let si = material.shading(&si);
        let bsdf = material.bsdf(&si);
        probe.surface(&si, &bsdf);
        last.ctx = None;
        if have_lights && bsdf.has_non_specular() {
            let ctx = LightContext {
                p: si.p,
                n: si.shading_n,
            };
            last.ctx = Some(ctx);
            let direct = next_event(scene, &si, &bsdf, ctx, light_strategy, stream, &mut rays);
            if let Some(direct) = direct {
                l += beta * direct;
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
        let transmitted = s.wi.dot(si.n) * si.wo.dot(si.n) < 0.0;
        if s.specular && transmitted {
            let eta = bsdf.eta();
            eta_scale *= if si.wo.dot(si.n) > 0.0 {
                eta * eta
            } else {
                1.0 / (eta * eta)
            };
        }
        last.whole = s.specular;
        last.p = si.p;
        last.bsdf_pdf = if s.specular { 0.0 } else { s.pdf };
        ray = si.spawn_ray(s.wi);
        // Transmitted into a subsurface material: the path leaves from an exit point instead.
        if let Some(bssrdf) = transmitted.then(|| material.bssrdf(&si)).flatten() {
            let exit = subsurface::scatter(
                scene,
                &bssrdf,
                material_index,
                si.time,
                light_strategy,
                stream,
                &mut beta,
                &mut l,
                &mut last,
                &mut rays,
            );
            let Some(next) = exit else { break };
            ray = next;
        }
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
/// (MIS of light and BSDF sampling), and specular reflection and transmission recursively,
/// every specular lobe followed as pbrt-v3 does, the camera ray's differentials carried
/// through them.
#[allow(clippy::too_many_arguments)]
fn direct_li(
    scene: &Scene,
    ray: Ray,
    diff: Option<&RayDifferentials>,
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
    let mut si = hit.si;
    // The differentials hold for the ray as it left the camera (or a specular bounce), not
    // through an interface.
    let camera_diff = diff.filter(|_| pass_through == 0);
    if let Some(d) = camera_diff {
        si.compute_differentials(d);
    }
    let mut l = Spectrum::ZERO;
    if let Some(li) = hit.surface.area_light {
        l += scene.lights[li as usize].l(&si, si.wo);
    }
    let Some(material) = hit.surface.material else {
        return l;
    };
    let material = &scene.materials[material as usize];
    let si = material.shading(&si);
    // pbrt-v3's DirectLightingIntegrator asks for separate lobes (a glass's reflection and
    // transmission apart), and follows each.
    let bsdf = material.bsdf_with(&si, false);
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
    // pbrt-v3's SpecularReflect and SpecularTransmit: every specular lobe is followed (a
    // glass's reflection and its transmission both), each with its own sample.
    if depth + 1 < max_depth {
        for index in 0..bsdf.num_lobes() {
            let u = stream.next_2d();
            let Some(s) = bsdf.sample_specular_lobe(si.wo, u, index) else {
                continue;
            };
            let cos = s.wi.dot(si.shading_n).abs();
            let weight = s.f * cos / s.pdf;
            if cos == 0.0 || weight == Spectrum::ZERO || !crate::geometry::is_valid_radiance(weight)
            {
                continue;
            }
            let next = si.spawn_ray(s.wi);
            let transmitted = s.wi.dot(si.n) * si.wo.dot(si.n) < 0.0;
            let next_diff =
                camera_diff.map(|d| specular_differentials(d, &si, s.wi, transmitted, bsdf.eta()));
            l += weight
                * direct_li(
                    scene,
                    next,
                    next_diff.as_ref(),
                    stream,
                    max_depth,
                    depth + 1,
                    strategy,
                    tally,
                );
        }
    }
    l
}

/// The differentials of the ray leaving `si` along `wi` by specular reflection or transmission,
/// from those of the ray that arrived (`d`): pbrt-v3's `SpecularReflect` and
/// `SpecularTransmit`, which follow the footprint through mirrors and glass (with the normal's
/// change across it, from dn/du and dn/dv).
fn specular_differentials(
    d: &RayDifferentials,
    si: &SurfaceInteraction,
    wi: crate::geometry::Vec3,
    transmitted: bool,
    bsdf_eta: f32,
) -> RayDifferentials {
    let wo = si.wo;
    let mut ns = si.shading_n;
    let f = &si.diff;
    let mut dndx = si.dndu * f.dudx + si.dndv * f.dvdx;
    let mut dndy = si.dndu * f.dudy + si.dndv * f.dvdy;
    let (rx_o, ry_o) = (si.p + f.dpdx, si.p + f.dpdy);
    let (dwodx, dwody) = (-d.rx_d - wo, -d.ry_d - wo);
    if !transmitted {
        let ddndx = dwodx.dot(ns) + wo.dot(dndx);
        let ddndy = dwody.dot(ns) + wo.dot(dndy);
        return RayDifferentials {
            rx_o,
            ry_o,
            rx_d: wi - dwodx + 2.0 * (wo.dot(ns) * dndx + ddndx * ns),
            ry_d: wi - dwody + 2.0 * (wo.dot(ns) * dndy + ddndy * ns),
        };
    }
    let mut eta = 1.0 / bsdf_eta;
    if wo.dot(ns) < 0.0 {
        eta = 1.0 / eta;
        ns = -ns;
        dndx = -dndx;
        dndy = -dndy;
    }
    let ddndx = dwodx.dot(ns) + wo.dot(dndx);
    let ddndy = dwody.dot(ns) + wo.dot(dndy);
    let mu = eta * wo.dot(ns) - wi.dot(ns).abs();
    let k = eta - (eta * eta * wo.dot(ns)) / wi.dot(ns).abs();
    RayDifferentials {
        rx_o,
        ry_o,
        rx_d: wi - eta * dwodx + (mu * dndx + k * ddndx * ns),
        ry_d: wi - eta * dwody + (mu * dndy + k * ddndy * ns),
    }
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
