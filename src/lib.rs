//! acr: adaptive cluster rendering of pbrt-v3 scenes. This crate holds the renderer core and, in
//! `cli/`, the command-line tools on top of it; the parser and the plugins live in their own
//! crates.

pub mod accel;
pub mod bsdf;
pub mod bssrdf;
pub mod bump;
pub mod camera;
pub mod cli;
pub mod exr_channels;
pub mod first_hit;
pub mod fourier;
pub use acr_plugins::film;
pub mod geometry;
pub mod image_io;
pub mod integrator;
pub mod interpolation;
pub mod light;
pub mod lightbvh;
pub mod lightdistrib;
pub mod material;
pub mod medium;
pub mod metrics;
pub mod microfacet;
pub mod mipmap;
pub mod noise;
pub mod procedural;
pub mod registry;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shapes;
pub mod spectrum;
pub mod stream;
pub mod texture;
pub mod transform;

pub use acr_parser as parser;

/// Luminance of linear RGB (pbrt's y(): Rec. 709 weights), one definition for the core and
/// the plugins.
pub use acr_plugins::color::luminance as spectrum_luminance;
