//! What several materials share when they weigh their lobes: pbrt-v3's clamp of a textured
//! spectrum, its test for black, and the roughness-to-distribution step. A leaf below every
//! material's file.

use crate::geometry::Spectrum;
use crate::microfacet::{roughness_to_alpha, TrowbridgeReitz};
use acr_parser::{ParamList, Result};

/// pbrt-v3's `Spectrum::Clamp()`: negative channels to zero.
#[inline]
pub(super) fn clamp0(s: Spectrum) -> Spectrum {
    s.max(Spectrum::ZERO)
}

/// pbrt-v3's `IsBlack()`: every channel zero.
#[inline]
pub(super) fn is_black(s: Spectrum) -> bool {
    s == Spectrum::ZERO
}

/// A Trowbridge-Reitz distribution from roughnesses, remapped or not.
#[inline]
pub(super) fn distribution(u: f32, v: f32, remap: bool) -> TrowbridgeReitz {
    if remap {
        TrowbridgeReitz::new(roughness_to_alpha(u), roughness_to_alpha(v))
    } else {
        TrowbridgeReitz::new(u, v)
    }
}

/// The `remaproughness` parameter (true unless given): whether roughnesses go through
/// `roughness_to_alpha`.
pub(super) fn remap_roughness(p: &ParamList) -> Result<bool> {
    p.bool_or("remaproughness", true)
}
