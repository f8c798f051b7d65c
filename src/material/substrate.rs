//! pbrt-v3's `substrate` material (materials/substrate.cpp): a glossy coat over a diffuse
//! base, one `FresnelBlend` lobe.

use super::shared::{clamp0, distribution, is_black, remap_roughness};
use crate::bsdf::{Bsdf, Bxdf};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{FloatTexture, SpectrumTexture, TextureBuilder};
use acr_parser::{ParamList, Result};

/// Glossy coat over a diffuse base (pbrt-v3's `FresnelBlend`).
#[derive(Clone, Debug)]
pub struct Substrate {
    /// Diffuse reflectance.
    pub kd: SpectrumTexture,
    /// Specular reflectance at normal incidence.
    pub ks: SpectrumTexture,
    /// Roughness along the tangent.
    pub u_roughness: FloatTexture,
    /// Roughness along the bitangent.
    pub v_roughness: FloatTexture,
    /// Whether roughness goes through `roughness_to_alpha`.
    pub remap_roughness: bool,
}

impl Substrate {
    /// The material from its parameters (`Kd` and `Ks` 0.5, roughnesses 0.1).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList) -> Result<Self> {
        Ok(Self {
            kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.5))?,
            ks: t.spectrum_param(p, "Ks", Spectrum::splat(0.5))?,
            u_roughness: t.float_param(p, "uroughness", 0.1)?,
            v_roughness: t.float_param(p, "vroughness", 0.1)?,
            remap_roughness: remap_roughness(p)?,
        })
    }

    /// Adds its lobe to `b`, weighted by `scale` (none where both reflectances are black).
    #[inline]
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum) {
        let d = clamp0(self.kd.eval(si));
        let s = clamp0(self.ks.eval(si));
        if !is_black(d) || !is_black(s) {
            let (u, v) = (self.u_roughness.eval(si), self.v_roughness.eval(si));
            b.add_scaled(
                Bxdf::FresnelBlend {
                    rd: d,
                    rs: s,
                    distribution: distribution(u, v, self.remap_roughness),
                },
                scale,
            );
        }
    }
}
