//! `mlt`: pbrt-v3's MLTIntegrator, primary-sample-space Metropolis light transport
//! (docs/light-transport.md, `## mlt`). A bootstrap of independent paths estimates the image's
//! total luminance `b` and seeds `chains` Markov chains; each chain mutates its path in
//! primary sample space ([`sampler::MltSampler`]: large steps and Gaussian small steps) and
//! splats the proposed and the current state, weighted by the acceptance, onto the film's
//! unfiltered splats, scaled in the end by `b / mutationsperpixel`.
//!
//! The path function the chains sample is [`contribution::PathContribution`]: bdpt's paths,
//! one connection strategy at a time ([`bdpt_path::BdptContribution`], pbrt-v3's
//! `MLTIntegrator::L`).

pub mod bdpt_path;
pub mod chain;
pub mod contribution;
pub mod gaussian;
pub mod sampler;

use super::IntegratorBuild;
use acr_parser::{Error, ParamList, ParamType, Result};
use acr_plugins::{Choice, Entry, Kind, ParamSpec, PluginInfo};

pub use chain::render;

/// mlt's parameters (pbrt-v3's names and defaults).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MltSettings {
    /// Longest path, in bounces (`maxdepth`, 5).
    pub max_depth: u32,
    /// Independent paths per depth for the normalisation (`bootstrapsamples`, 100000).
    pub bootstrap_samples: u32,
    /// Markov chains run (`chains`, 1000).
    pub chains: u32,
    /// Mutations per pixel in all (`mutationsperpixel`, 100; `--spp` sets it).
    pub mutations_per_pixel: u32,
    /// The chance a mutation is a large step (`largestepprobability`, 0.3).
    pub large_step_probability: f32,
    /// The width of a small step in primary sample space (`sigma`, 0.01).
    pub sigma: f32,
}

/// mlt in the registry of integrators.
pub const ENTRY: Entry<IntegratorBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Integrator,
        name: "mlt",
        doc: "Metropolis light transport in primary sample space (pbrt-v3 mlt, over bdpt's paths)",
        params: &[
            super::MAX_DEPTH_BOUNCES,
            ParamSpec::new(
                "bootstrapsamples",
                ParamType::Integer,
                "100000",
                "independent paths per depth that estimate the normalisation and seed the chains",
            ),
            ParamSpec::new("chains", ParamType::Integer, "1000", "Markov chains run"),
            ParamSpec::new(
                "mutationsperpixel",
                ParamType::Integer,
                "100",
                "mutations per pixel in all (--spp sets it)",
            ),
            ParamSpec::new(
                "largestepprobability",
                ParamType::Float,
                "0.3",
                "the chance a mutation draws a fresh path, in [0, 1]",
            ),
            ParamSpec::new(
                "sigma",
                ParamType::Float,
                "0.01",
                "the standard deviation of a small step in primary sample space, above 0",
            ),
        ],
    },
    build,
};

/// An error at parameter `name`'s location (or naming it, when it has none).
fn bad(params: &ParamList, name: &str, message: String) -> Error {
    match params.get(name) {
        Some(p) => Error::at(&p.loc, message),
        None => Error::file(name, message),
    }
}

/// A count parameter that must be at least 1.
fn count(params: &ParamList, name: &str, default: i32) -> Result<u32> {
    let v = params.int_or(name, default)?;
    u32::try_from(v)
        .ok()
        .filter(|&v| v >= 1)
        .ok_or_else(|| bad(params, name, format!("{name} {v} must be at least 1")))
}

impl MltSettings {
    /// mlt's settings from its parameters, each checked (a located error when out of range).
    pub fn from_params(params: &ParamList) -> Result<Self> {
        let large = params.float_or("largestepprobability", 0.3)?;
        if !(0.0..=1.0).contains(&large) {
            let message = format!("largestepprobability {large} is not in [0, 1]");
            return Err(bad(params, "largestepprobability", message));
        }
        let sigma = params.float_or("sigma", 0.01)?;
        if !(sigma > 0.0 && sigma.is_finite()) {
            let message = format!("sigma {sigma} must be above 0");
            return Err(bad(params, "sigma", message));
        }
        Ok(Self {
            max_depth: super::max_depth(params)?,
            bootstrap_samples: count(params, "bootstrapsamples", 100_000)?,
            chains: count(params, "chains", 1000)?,
            mutations_per_pixel: count(params, "mutationsperpixel", 100)?,
            large_step_probability: large as f32,
            sigma: sigma as f32,
        })
    }
}

/// Builds `mlt` from its checked parameters.
fn build(c: &Choice) -> Result<super::Integrator> {
    Ok(super::Integrator::Mlt(MltSettings::from_params(&c.params)?))
}
