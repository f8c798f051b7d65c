//! pbrt-v3's `plastic` material (materials/plastic.cpp): diffuse plus a glossy dielectric
//! coat.

use super::shared::{clamp0, distribution, is_black, remap_roughness};
use crate::bsdf::{Bsdf, Bxdf, Fresnel};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{FloatTexture, SpectrumTexture, TextureBuilder};
use acr_parser::{ParamList, Result};

/// Diffuse plus a glossy dielectric coat (pbrt-v3's Fresnel 1.5 -> 1 quirk included).
#[derive(Clone, Debug)]
pub struct Plastic {
    /// Diffuse reflectance.
    pub kd: SpectrumTexture,
    /// Glossy reflectance.
    pub ks: SpectrumTexture,
    /// Roughness of the coat.
    pub roughness: FloatTexture,
    /// Whether roughness goes through `roughness_to_alpha`.
    pub remap_roughness: bool,
}

impl Plastic {
    /// The material from its parameters (`Kd` and `Ks` 0.25, `roughness` 0.1).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList) -> Result<Self> {
        Ok(Self {
            kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.25))?,
            ks: t.spectrum_param(p, "Ks", Spectrum::splat(0.25))?,
            roughness: t.float_param(p, "roughness", 0.1)?,
            remap_roughness: remap_roughness(p)?,
        })
    }

    /// Adds its diffuse and glossy lobes to `b`, weighted by `scale` (each only where its
    /// reflectance is not black).
    #[inline]
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum) {
        let kd = clamp0(self.kd.eval(si));
        if !is_black(kd) {
            b.add_scaled(Bxdf::Lambertian { r: kd }, scale);
        }
        let ks = clamp0(self.ks.eval(si));
        if !is_black(ks) {
            let rough = self.roughness.eval(si);
            b.add_scaled(
                Bxdf::MicrofacetReflection {
                    r: ks,
                    distribution: distribution(rough, rough, self.remap_roughness),
                    // pbrt-v3 builds this Fresnel with the indices swapped.
                    fresnel: Fresnel::Dielectric {
                        eta_i: 1.5,
                        eta_t: 1.0,
                    },
                },
                scale,
            );
        }
    }
}
