//! What a texture produces: `f32` or [`Spectrum`], and how each is made from a texel or (s, t).

use crate::geometry::Spectrum;
use crate::spectrum::{luminance, srgb_to_linear};
use std::fmt::Debug;
use std::ops::{Add, Mul};

/// A value a texture can produce: `f32` or [`Spectrum`].
pub trait TexValue:
    Copy
    + Debug
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Mul<Output = Self>
    + Mul<f32, Output = Self>
{
    /// Zero.
    const ZERO: Self;
    /// One.
    const ONE: Self;
    /// pbrt-v3's `uv` texture value at (s, t): (s - ⌊s⌋, t - ⌊t⌋, 0) as a colour; for floats,
    /// s - ⌊s⌋.
    fn from_uv(s: f32, t: f32) -> Self;
    /// A texel of an image file as pbrt-v3's image texture stores it: sRGB-decoded when `gamma`
    /// (for floats, the luminance is decoded), times `scale`; with `invert`, 1 - v, at least 0.
    fn from_texel(rgb: Spectrum, scale: f32, gamma: bool, invert: bool) -> Self;
    /// The value with negative parts set to 0.
    fn clamp_nonneg(self) -> Self;
    /// A texel stored as bytes (1, or 3 for a colour), each byte's value being `lut[byte]`.
    fn from_bytes(bytes: &[u8], lut: &[f32; 256]) -> Self;
    /// Channel `c` (0 for a float; 0, 1, 2 for a colour's).
    fn channel(self, c: usize) -> f32;
}

impl TexValue for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;

    fn from_uv(s: f32, _t: f32) -> Self {
        s - s.floor()
    }

    fn clamp_nonneg(self) -> Self {
        self.max(0.0)
    }

    #[inline]
    fn from_bytes(bytes: &[u8], lut: &[f32; 256]) -> Self {
        lut[bytes[0] as usize]
    }

    fn channel(self, _c: usize) -> f32 {
        self
    }

    fn from_texel(rgb: Spectrum, scale: f32, gamma: bool, invert: bool) -> Self {
        let y = luminance(rgb);
        let v = scale * if gamma { srgb_to_linear(y) } else { y };
        if invert {
            (1.0 - v).max(0.0)
        } else {
            v
        }
    }
}

impl TexValue for Spectrum {
    const ZERO: Self = Spectrum::ZERO;
    const ONE: Self = Spectrum::ONE;

    fn from_uv(s: f32, t: f32) -> Self {
        Spectrum::new(s - s.floor(), t - t.floor(), 0.0)
    }

    fn clamp_nonneg(self) -> Self {
        self.max(Spectrum::ZERO)
    }

    #[inline]
    fn from_bytes(bytes: &[u8], lut: &[f32; 256]) -> Self {
        match bytes {
            [r, g, b] => Spectrum::new(lut[*r as usize], lut[*g as usize], lut[*b as usize]),
            _ => Spectrum::splat(lut[bytes[0] as usize]),
        }
    }

    fn channel(self, c: usize) -> f32 {
        self[c]
    }

    fn from_texel(rgb: Spectrum, scale: f32, gamma: bool, invert: bool) -> Self {
        let c = if gamma {
            Spectrum::new(
                srgb_to_linear(rgb.x),
                srgb_to_linear(rgb.y),
                srgb_to_linear(rgb.z),
            )
        } else {
            rgb
        };
        let v = c * scale;
        if invert {
            (Spectrum::ONE - v).max(Spectrum::ZERO)
        } else {
            v
        }
    }
}
