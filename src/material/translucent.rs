//! pbrt-v3's `translucent` material (materials/translucent.cpp): diffuse and glossy
//! reflection and transmission through a thin dielectric of index 1.5.

use super::shared::{clamp0, distribution, is_black, remap_roughness};
use crate::bsdf::{Bsdf, Bxdf, Fresnel};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{FloatTexture, SpectrumTexture, TextureBuilder};
use acr_parser::{ParamList, Result};

/// The index of refraction pbrt-v3's translucent material fixes.
const ETA: f32 = 1.5;

/// pbrt-v3's `translucent`: diffuse and glossy reflection weighted by `reflect`, diffuse
/// and glossy transmission weighted by `transmit` (index 1.5).
#[derive(Clone, Debug)]
pub struct Translucent {
    /// Diffuse reflectance and transmittance.
    pub kd: SpectrumTexture,
    /// Glossy reflectance and transmittance.
    pub ks: SpectrumTexture,
    /// Share reflected.
    pub reflect: SpectrumTexture,
    /// Share transmitted.
    pub transmit: SpectrumTexture,
    /// Microfacet roughness.
    pub roughness: FloatTexture,
    /// Whether roughness goes through `roughness_to_alpha`.
    pub remap_roughness: bool,
}

impl Translucent {
    /// The material from its parameters (`Kd` and `Ks` 0.25, `reflect` and `transmit` 0.5,
    /// `roughness` 0.1).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList) -> Result<Self> {
        Ok(Self {
            kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.25))?,
            ks: t.spectrum_param(p, "Ks", Spectrum::splat(0.25))?,
            reflect: t.spectrum_param(p, "reflect", Spectrum::splat(0.5))?,
            transmit: t.spectrum_param(p, "transmit", Spectrum::splat(0.5))?,
            roughness: t.float_param(p, "roughness", 0.1)?,
            remap_roughness: remap_roughness(p)?,
        })
    }

    /// Adds its lobes to `b`, weighted by `scale`, as pbrt-v3's
    /// `TranslucentMaterial::ComputeScatteringFunctions`; as the `first` material (the one that
    /// owns the BSDF) it sets the BSDF's relative index.
    #[inline]
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum, first: bool) {
        if first {
            b.set_eta(ETA);
        }
        let (r, t) = (
            clamp0(self.reflect.eval(si)),
            clamp0(self.transmit.eval(si)),
        );
        if is_black(r) && is_black(t) {
            return;
        }
        let kd = clamp0(self.kd.eval(si));
        if !is_black(kd) {
            if !is_black(r) {
                b.add_scaled(Bxdf::Lambertian { r: r * kd }, scale);
            }
            if !is_black(t) {
                b.add_scaled(Bxdf::LambertianTransmission { t: t * kd }, scale);
            }
        }
        let ks = clamp0(self.ks.eval(si));
        if !is_black(ks) {
            let rough = self.roughness.eval(si);
            let dist = distribution(rough, rough, self.remap_roughness);
            if !is_black(r) {
                let fresnel = Fresnel::Dielectric {
                    eta_i: 1.0,
                    eta_t: ETA,
                };
                b.add_scaled(
                    Bxdf::MicrofacetReflection {
                        r: r * ks,
                        distribution: dist,
                        fresnel,
                    },
                    scale,
                );
            }
            if !is_black(t) {
                b.add_scaled(
                    Bxdf::MicrofacetTransmission {
                        t: t * ks,
                        distribution: dist,
                        eta_a: 1.0,
                        eta_b: ETA,
                    },
                    scale,
                );
            }
        }
    }
}
