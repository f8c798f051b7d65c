//! pbrt-v3's `mirror` material (materials/mirror.cpp): a perfect mirror.

use super::shared::{clamp0, is_black};
use crate::bsdf::{Bsdf, Bxdf, Fresnel};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{SpectrumTexture, TextureBuilder};
use acr_parser::{ParamList, Result};

/// A perfect mirror.
#[derive(Clone, Debug)]
pub struct Mirror {
    /// Reflectance.
    pub kr: SpectrumTexture,
}

impl Mirror {
    /// The material from its parameters (`Kr` 0.9).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList) -> Result<Self> {
        Ok(Self {
            kr: t.spectrum_param(p, "Kr", Spectrum::splat(0.9))?,
        })
    }

    /// Adds its specular reflection to `b`, weighted by `scale` (none where `Kr` is black).
    #[inline]
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum) {
        let r = clamp0(self.kr.eval(si));
        if !is_black(r) {
            b.add_scaled(
                Bxdf::SpecularReflection {
                    r,
                    fresnel: Fresnel::NoOp,
                },
                scale,
            );
        }
    }
}
