//! pbrt-v3's `metal` material (materials/metal.cpp): a rough conductor, copper unless told.

use super::shared::{distribution, remap_roughness};
use crate::bsdf::{Bsdf, Bxdf, Fresnel};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{FloatTexture, SpectrumTexture, TextureBuilder};
use acr_parser::{ParamList, Result};

/// pbrt-v3's copper (metal.cpp's tables through `RGBSpectrum::FromSampled`): the metal
/// material's default `eta`.
pub const COPPER_ETA: Spectrum = Spectrum::new(0.200438, 0.924033, 1.10221);
/// pbrt-v3's copper absorption: the metal material's default `k`.
pub const COPPER_K: Spectrum = Spectrum::new(3.91295, 2.45285, 2.14219);

/// A rough conductor.
#[derive(Clone, Debug)]
pub struct Metal {
    /// Real part of the index of refraction.
    pub eta: SpectrumTexture,
    /// Absorption coefficient.
    pub k: SpectrumTexture,
    /// Roughness (both directions unless overridden).
    pub roughness: FloatTexture,
    /// Roughness along the tangent, overriding `roughness`.
    pub u_roughness: Option<FloatTexture>,
    /// Roughness along the bitangent, overriding `roughness`.
    pub v_roughness: Option<FloatTexture>,
    /// Whether roughness goes through `roughness_to_alpha`.
    pub remap_roughness: bool,
}

impl Metal {
    /// The material from its parameters (copper, `roughness` 0.01).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList) -> Result<Self> {
        Ok(Self {
            eta: t.spectrum_param(p, "eta", COPPER_ETA)?,
            k: t.spectrum_param(p, "k", COPPER_K)?,
            roughness: t.float_param(p, "roughness", 0.01)?,
            u_roughness: t.float_param_opt(p, "uroughness")?,
            v_roughness: t.float_param_opt(p, "vroughness")?,
            remap_roughness: remap_roughness(p)?,
        })
    }

    /// Adds its microfacet reflection to `b`, weighted by `scale`.
    #[inline]
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum) {
        let u = self
            .u_roughness
            .as_ref()
            .map_or_else(|| self.roughness.eval(si), |t| t.eval(si));
        let v = self
            .v_roughness
            .as_ref()
            .map_or_else(|| self.roughness.eval(si), |t| t.eval(si));
        b.add_scaled(
            Bxdf::MicrofacetReflection {
                r: Spectrum::ONE,
                distribution: distribution(u, v, self.remap_roughness),
                fresnel: Fresnel::Conductor {
                    eta_i: Spectrum::ONE,
                    eta_t: self.eta.eval(si),
                    k: self.k.eval(si),
                },
            },
            scale,
        );
    }
}
