//! acr: adaptive cluster rendering of pbrt-v3 scenes. This crate holds the renderer core and the
//! command line; the parser and the plugins live in their own crates.

pub mod camera;
pub mod cli;
pub mod film;
pub mod geometry;
pub mod sampling;
pub mod stats;
pub mod stream;
pub mod transform;

pub use acr_parser as parser;

/// Luminance of linear RGB (pbrt's y(): Rec. 709 weights).
#[inline]
pub fn spectrum_luminance(c: geometry::Spectrum) -> f32 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}
