//! pbrt-v3's `uber` material (materials/uber.cpp): diffuse, glossy, specular reflection and
//! transmission, and opacity, each weighted by its own texture.

use super::shared::{clamp0, distribution, is_black, remap_roughness};
use crate::bsdf::{Bsdf, Bxdf, Fresnel};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{FloatTexture, SpectrumTexture, TextureBuilder};
use acr_parser::{ParamList, Result};

/// pbrt-v3's uber material: diffuse, glossy, specular reflection and transmission, opacity.
#[derive(Clone, Debug)]
pub struct Uber {
    /// Diffuse reflectance.
    pub kd: SpectrumTexture,
    /// Glossy reflectance.
    pub ks: SpectrumTexture,
    /// Specular reflectance.
    pub kr: SpectrumTexture,
    /// Specular transmittance.
    pub kt: SpectrumTexture,
    /// Roughness (both directions unless overridden).
    pub roughness: FloatTexture,
    /// Roughness along the tangent, overriding `roughness`.
    pub u_roughness: Option<FloatTexture>,
    /// Roughness along the bitangent (defaults to the tangent's).
    pub v_roughness: Option<FloatTexture>,
    /// Index of refraction.
    pub eta: FloatTexture,
    /// Opacity: below 1, a straight-through transmission lobe of 1 - opacity.
    pub opacity: SpectrumTexture,
    /// Whether roughness goes through `roughness_to_alpha`.
    pub remap_roughness: bool,
}

impl Uber {
    /// The material from its parameters (`eta`, or `index`, 1.5; `Kd` and `Ks` 0.25, `Kr` and
    /// `Kt` 0, `roughness` 0.1, opaque).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList) -> Result<Self> {
        let eta = match t.float_param_opt(p, "eta")? {
            Some(e) => e,
            None => t.float_param(p, "index", 1.5)?,
        };
        Ok(Self {
            kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.25))?,
            ks: t.spectrum_param(p, "Ks", Spectrum::splat(0.25))?,
            kr: t.spectrum_param(p, "Kr", Spectrum::ZERO)?,
            kt: t.spectrum_param(p, "Kt", Spectrum::ZERO)?,
            roughness: t.float_param(p, "roughness", 0.1)?,
            u_roughness: t.float_param_opt(p, "uroughness")?,
            v_roughness: t.float_param_opt(p, "vroughness")?,
            eta,
            opacity: t.spectrum_param(p, "opacity", Spectrum::ONE)?,
            remap_roughness: remap_roughness(p)?,
        })
    }

    /// Adds its lobes to `b`, weighted by `scale` (each only where its weight is not black);
    /// as the `first` material (the one that owns the BSDF) of an opaque surface, it sets the
    /// BSDF's relative index.
    #[inline]
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum, first: bool) {
        let e = self.eta.eval(si);
        let op = clamp0(self.opacity.eval(si));
        let t = clamp0(Spectrum::ONE - op);
        if !is_black(t) {
            b.add_scaled(
                Bxdf::SpecularTransmission {
                    t,
                    eta_a: 1.0,
                    eta_b: 1.0,
                },
                scale,
            );
        } else if first {
            b.set_eta(e);
        }
        let dielectric = Fresnel::Dielectric {
            eta_i: 1.0,
            eta_t: e,
        };
        let kd = op * clamp0(self.kd.eval(si));
        if !is_black(kd) {
            b.add_scaled(Bxdf::Lambertian { r: kd }, scale);
        }
        let ks = op * clamp0(self.ks.eval(si));
        if !is_black(ks) {
            let u = self
                .u_roughness
                .as_ref()
                .map_or_else(|| self.roughness.eval(si), |t| t.eval(si));
            let v = self.v_roughness.as_ref().map_or(u, |t| t.eval(si));
            b.add_scaled(
                Bxdf::MicrofacetReflection {
                    r: ks,
                    distribution: distribution(u, v, self.remap_roughness),
                    fresnel: dielectric,
                },
                scale,
            );
        }
        let kr = op * clamp0(self.kr.eval(si));
        if !is_black(kr) {
            b.add_scaled(
                Bxdf::SpecularReflection {
                    r: kr,
                    fresnel: dielectric,
                },
                scale,
            );
        }
        let kt = op * clamp0(self.kt.eval(si));
        if !is_black(kt) {
            b.add_scaled(
                Bxdf::SpecularTransmission {
                    t: kt,
                    eta_a: 1.0,
                    eta_b: e,
                },
                scale,
            );
        }
    }
}
