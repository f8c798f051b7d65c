//! Integrators: the enum every render dispatches on, their registry entries and parameters.
//! `path` (`src/integrator/path.rs`: unidirectional path tracing with light and BSDF sampling
//! combined by multiple importance sampling, and Russian roulette as pbrt-v3),
//! `directlighting` (`src/integrator/direct.rs`; the light sampling both share in
//! `src/integrator/light_sample.rs`), `volpath` (docs/media.md), and pbrt-v3's
//! other integrators (docs/light-transport.md), one file or folder each.
//!
//! The path integrator follows pbrt-v3's PathIntegrator in what it estimates, with one change
//! in how: the BSDF sample that continues the path also serves as the BSDF half of the MIS pair
//! for emission it hits (as pbrt-v4 does), where pbrt-v3 traces a separate ray for it. Same
//! expectation, one ray fewer per bounce.
//!
//! A path transmitted into a subsurface material leaves from an exit point that
//! the step in `src/integrator/subsurface.rs` finds (docs/subsurface.md).

use crate::first_hit::FirstHit;
use crate::geometry::{Ray, RayDifferentials, Spectrum};
use crate::lightdistrib::LightStrategy;
use crate::scene::Scene;
use crate::stream::SampleStream;
use acr_parser::{Error, ParamList, ParamType, Result};
use acr_plugins::{Choice, Entry, Kind, ParamSpec, PluginInfo};

mod ao;
pub mod bdpt;
mod direct;
mod light_sample;
pub mod mlt;
mod path;
pub mod sppm;
mod subsurface;
mod volpath;
mod whitted;
pub use ao::AoSettings;
pub use bdpt::BdptSettings;
use direct::{direct_li, Tally};
pub use mlt::MltSettings;
use path::{path_li, PathRange};
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
    /// `mlt`: primary-sample-space Metropolis light transport (docs/light-transport.md).
    Mlt(MltSettings),
    /// `bdpt`: bidirectional path tracing (docs/light-transport.md).
    Bdpt(BdptSettings),
    /// `directlighting`.
    Direct {
        /// Specular recursion depth.
        max_depth: u32,
        /// Light sampling strategy.
        strategy: DirectStrategy,
    },
    /// `ambientocclusion` (pbrt-v3's AOIntegrator).
    AmbientOcclusion(AoSettings),
    /// `whitted` (pbrt-v3's WhittedIntegrator).
    Whitted {
        /// Specular recursion depth.
        max_depth: u32,
    },
    /// `sppm`: stochastic progressive photon mapping; it drives its own sampling
    /// ([`sppm::render`]).
    Sppm(sppm::SppmSettings),
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

/// `maxdepth` of the integrators that count a path's bounces (`path`, `bdpt`, `mlt`).
pub(super) const MAX_DEPTH_BOUNCES: ParamSpec = ParamSpec::new(
    "maxdepth",
    ParamType::Integer,
    "5",
    "longest path, in bounces",
);

/// `maxdepth` of the integrators that recurse only through specular lobes
/// (`directlighting`, `whitted`).
const MAX_DEPTH_SPECULAR: ParamSpec = ParamSpec::new(
    "maxdepth",
    ParamType::Integer,
    "5",
    "specular recursion depth",
);

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
                MAX_DEPTH_BOUNCES,
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
                MAX_DEPTH_BOUNCES,
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
                MAX_DEPTH_SPECULAR,
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
    mlt::ENTRY,
    Entry {
        info: PluginInfo {
            kind: Kind::Integrator,
            name: "ambientocclusion",
            doc: "ambient occlusion at the first hit: pi times the unoccluded fraction of the hemisphere (pbrt-v3 ambientocclusion)",
            params: &[
                ParamSpec::new(
                    "nsamples",
                    ParamType::Integer,
                    "64",
                    "hemisphere directions traced at each camera ray's hit",
                ),
                ParamSpec::new(
                    "cossample",
                    ParamType::Bool,
                    "true",
                    "cosine-weighted directions (else uniform over the hemisphere)",
                ),
            ],
        },
        build: Integrator::ambient_occlusion,
    },
    Entry {
        info: PluginInfo {
            kind: Kind::Integrator,
            name: "whitted",
            doc: "Whitted ray tracing: every light sampled once, specular reflection and refraction followed (pbrt-v3 whitted)",
            params: &[MAX_DEPTH_SPECULAR],
        },
        build: Integrator::whitted,
    },
    Entry {
        info: PluginInfo {
            kind: Kind::Integrator,
            name: "sppm",
            doc: "stochastic progressive photon mapping: visible points, photons from the lights, shrinking radii (pbrt-v3 sppm)",
            params: sppm::PARAMS,
        },
        build: |c| Ok(Integrator::Sppm(sppm::SppmSettings::from_choice(c)?)),
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

    /// `ambientocclusion` from its parameters (pbrt-v3's defaults: nsamples 64, cossample
    /// true); fewer than one sample is refused (pbrt-v3 renders black).
    pub fn ambient_occlusion(c: &Choice) -> Result<Self> {
        let params = &c.params;
        let n = params.int_or("nsamples", 64)?;
        let samples = u32::try_from(n).ok().filter(|&n| n > 0).ok_or_else(|| {
            let message = format!("nsamples {n} is not a positive count of directions");
            match params.get("nsamples") {
                Some(p) => Error::at(&p.loc, message),
                None => Error::file("nsamples", message),
            }
        })?;
        Ok(Integrator::AmbientOcclusion(AoSettings {
            samples,
            cos_sample: params.bool_or("cossample", true)?,
        }))
    }

    /// `whitted` from its parameters (pbrt-v3's default: maxdepth 5).
    pub fn whitted(c: &Choice) -> Result<Self> {
        Ok(Integrator::Whitted {
            max_depth: max_depth(&c.params)?,
        })
    }

    /// The name, as the stats file reports it.
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Path { .. } => "path",
            Integrator::VolPath(_) => "volpath",
            Integrator::Mlt(_) => "mlt",
            Integrator::Bdpt(_) => "bdpt",
            Integrator::Direct { .. } => "directlighting",
            Integrator::AmbientOcclusion(_) => "ambientocclusion",
            Integrator::Whitted { .. } => "whitted",
            Integrator::Sppm(_) => "sppm",
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
                PathRange {
                    max_depth,
                    rr_threshold,
                },
                light_strategy,
            ),
            // mlt renders through `mlt::render`; a caller tracing pixel samples with it gets
            // path's estimate of the same depth.
            Integrator::Mlt(ref m) => path_li(
                scene,
                ray,
                diff,
                stream,
                PathRange {
                    max_depth: m.max_depth,
                    rr_threshold: 1.0,
                },
                LightStrategy::Bvh,
            ),
            Integrator::VolPath(settings) => {
                volpath::volpath_li(scene, ray, diff, stream, settings)
            }
            // sppm renders whole images ([`sppm::render`]); a caller that asks it for one
            // camera sample's estimate gets the path integrator's.
            Integrator::Sppm(ref s) => path_li(
                scene,
                ray,
                diff,
                stream,
                PathRange {
                    max_depth: s.max_depth,
                    rr_threshold: 1.0,
                },
                LightStrategy::Power,
            ),
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
            Integrator::AmbientOcclusion(settings) => ao::ao_li(scene, ray, stream, settings),
            Integrator::Whitted { max_depth } => {
                let mut tally = Tally::default();
                let l = whitted::whitted_li(scene, ray, diff, stream, max_depth, 0, &mut tally);
                Radiance {
                    l,
                    rays: tally.rays,
                    first_hit: tally.probe.features(),
                }
            }
        }
    }
}
