//! Colour as every plugin sees it: linear RGB and its luminance. At the bottom of the crate,
//! so that the cells, the film and the filters all read it without reading each other.

use glam::Vec3;

/// Linear RGB radiance.
pub type Spectrum = Vec3;

/// Luminance of linear RGB (pbrt's y(): Rec. 709 weights).
#[inline]
pub fn luminance(c: Spectrum) -> f32 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}
