//! pbrt-v3's `glass` material (materials/glass.cpp): a dielectric, smooth or rough.

use super::shared::{clamp0, distribution, is_black, remap_roughness};
use crate::bsdf::{Bsdf, Bxdf, Fresnel};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{FloatTexture, SpectrumTexture, TextureBuilder};
use acr_parser::{ParamList, Result};

/// A dielectric, smooth or rough.
#[derive(Clone, Debug)]
pub struct Glass {
    /// Reflectance scale.
    pub kr: SpectrumTexture,
    /// Transmittance scale.
    pub kt: SpectrumTexture,
    /// Index of refraction inside.
    pub eta: FloatTexture,
    /// Roughness along the tangent.
    pub u_roughness: FloatTexture,
    /// Roughness along the bitangent.
    pub v_roughness: FloatTexture,
    /// Whether roughness goes through `roughness_to_alpha`.
    pub remap_roughness: bool,
}

impl Glass {
    /// The material from its parameters (`eta`, or pbrt-v3's older `index`, 1.5; `Kr` and `Kt`
    /// 1; smooth).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList) -> Result<Self> {
        let eta = match t.float_param_opt(p, "eta")? {
            Some(e) => e,
            None => t.float_param(p, "index", 1.5)?,
        };
        Ok(Self {
            kr: t.spectrum_param(p, "Kr", Spectrum::ONE)?,
            kt: t.spectrum_param(p, "Kt", Spectrum::ONE)?,
            eta,
            u_roughness: t.float_param(p, "uroughness", 0.0)?,
            v_roughness: t.float_param(p, "vroughness", 0.0)?,
            remap_roughness: remap_roughness(p)?,
        })
    }

    /// Adds its lobes to `b`, weighted by `scale`, and sets the BSDF's relative index when it
    /// is the `first` material (the one that owns the BSDF). Smooth glass is one
    /// `FresnelSpecular` lobe where `allow_multiple_lobes` (pbrt-v3's path integrators), else
    /// separate specular reflection and transmission.
    #[inline]
    pub fn add_lobes(
        &self,
        si: &SurfaceInteraction,
        allow_multiple_lobes: bool,
        b: &mut Bsdf,
        scale: Spectrum,
        first: bool,
    ) {
        let eta = self.eta.eval(si);
        let (urough, vrough) = (self.u_roughness.eval(si), self.v_roughness.eval(si));
        let r = clamp0(self.kr.eval(si));
        let t = clamp0(self.kt.eval(si));
        if first {
            b.set_eta(eta);
        }
        if is_black(r) && is_black(t) {
            return;
        }
        let specular = urough == 0.0 && vrough == 0.0;
        if specular && allow_multiple_lobes {
            b.add_scaled(
                Bxdf::FresnelSpecular {
                    r,
                    t,
                    eta_a: 1.0,
                    eta_b: eta,
                },
                scale,
            );
            return;
        }
        let dist = distribution(urough, vrough, self.remap_roughness);
        if !is_black(r) {
            let fresnel = Fresnel::Dielectric {
                eta_i: 1.0,
                eta_t: eta,
            };
            b.add_scaled(
                if specular {
                    Bxdf::SpecularReflection { r, fresnel }
                } else {
                    Bxdf::MicrofacetReflection {
                        r,
                        distribution: dist,
                        fresnel,
                    }
                },
                scale,
            );
        }
        if !is_black(t) {
            b.add_scaled(
                if specular {
                    Bxdf::SpecularTransmission {
                        t,
                        eta_a: 1.0,
                        eta_b: eta,
                    }
                } else {
                    Bxdf::MicrofacetTransmission {
                        t,
                        distribution: dist,
                        eta_a: 1.0,
                        eta_b: eta,
                    }
                },
                scale,
            );
        }
    }
}
