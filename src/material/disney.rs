//! pbrt-v3's `disney` material (materials/disney.{h,cpp}): its parameters and
//! `DisneyMaterial::ComputeScatteringFunctions`, which weighs and adds the lobes of
//! [`crate::bsdf::disney`], lobe for lobe and weight for weight, quirks included.
//!
//! Not supported: `scatterdistance` (pbrt-v3's `DisneyBSSRDF` subsurface scattering, which
//! replaces the diffuse lobe by a smooth refraction into the object): acr has no BSSRDF, so a
//! non-zero `scatterdistance` warns and the surface keeps pbrt-v3's diffuse lobe instead.

use crate::bsdf::disney::{lerp, lerp_s, DisneyBxdf};
use crate::bsdf::{Bsdf, Bxdf};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::microfacet::TrowbridgeReitz;
use crate::texture::{FloatTexture, SpectrumTexture, TextureBuilder};
use acr_parser::{Loc, ParamList, Result};

/// `std::max(a, b)` as C++ has it: `a` unless `a < b`, so a NaN `b` gives `a` (pbrt-v3's
/// alphas of a NaN roughness become 0.001).
#[inline]
fn cpp_max(a: f32, b: f32) -> f32 {
    if a < b {
        b
    } else {
        a
    }
}

/// pbrt-v3's `SchlickR0FromEta`: normal-incidence reflectance of a dielectric seen from air.
#[inline]
fn schlick_r0_from_eta(eta: f32) -> f32 {
    let (a, b) = (eta - 1.0, eta + 1.0);
    (a * a) / (b * b)
}

/// pbrt-v3's `disney` material's parameters, possibly textured (defaults as its
/// `CreateDisneyMaterial`).
#[derive(Clone, Debug)]
pub struct DisneyMaterial {
    /// Base colour (0.5).
    pub color: SpectrumTexture,
    /// Metallic weight (0).
    pub metallic: FloatTexture,
    /// Index of refraction (1.5).
    pub eta: FloatTexture,
    /// Roughness, squared into the alphas (0.5).
    pub roughness: FloatTexture,
    /// Tint of the specular reflectance toward the colour's hue (0).
    pub specular_tint: FloatTexture,
    /// Anisotropy: alphas r² / aspect and r² aspect with aspect = sqrt(1 - 0.9 a) (0).
    pub anisotropic: FloatTexture,
    /// Sheen weight (0).
    pub sheen: FloatTexture,
    /// Tint of the sheen toward the colour's hue (0.5).
    pub sheen_tint: FloatTexture,
    /// Clearcoat weight (0).
    pub clearcoat: FloatTexture,
    /// Clearcoat glossiness (1).
    pub clearcoat_gloss: FloatTexture,
    /// Specular transmission weight (0).
    pub spec_trans: FloatTexture,
    /// A thin surface: diffuse and fake-subsurface blend, diffuse transmission (false).
    pub thin: bool,
    /// Thin surfaces: share of the diffuse given to the fake subsurface lobe (0).
    pub flatness: FloatTexture,
    /// Thin surfaces: diffuse transmission, halved by pbrt-v3 (1).
    pub diff_trans: FloatTexture,
}

impl DisneyMaterial {
    /// The material from its parameters, as pbrt-v3's `CreateDisneyMaterial` (`bumpmap` is the
    /// material builder's); a non-zero `scatterdistance` warns (no subsurface scattering).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList, loc: &Loc) -> Result<Self> {
        let sd = t.spectrum_param_opt(p, "scatterdistance")?;
        if sd.is_some_and(|sd| sd.as_constant() != Some(Spectrum::ZERO)) {
            t.warn_once(
                "disney scatterdistance",
                loc,
                "disney \"scatterdistance\" (subsurface scattering) is not supported; \
                 the diffuse lobe is used",
            );
        }
        Ok(Self {
            color: t.spectrum_param(p, "color", Spectrum::splat(0.5))?,
            metallic: t.float_param(p, "metallic", 0.0)?,
            eta: t.float_param(p, "eta", 1.5)?,
            roughness: t.float_param(p, "roughness", 0.5)?,
            specular_tint: t.float_param(p, "speculartint", 0.0)?,
            anisotropic: t.float_param(p, "anisotropic", 0.0)?,
            sheen: t.float_param(p, "sheen", 0.0)?,
            sheen_tint: t.float_param(p, "sheentint", 0.5)?,
            clearcoat: t.float_param(p, "clearcoat", 0.0)?,
            clearcoat_gloss: t.float_param(p, "clearcoatgloss", 1.0)?,
            spec_trans: t.float_param(p, "spectrans", 0.0)?,
            thin: p.bool_or("thin", false)?,
            flatness: t.float_param(p, "flatness", 0.0)?,
            diff_trans: t.float_param(p, "difftrans", 1.0)?,
        })
    }

    /// Adds the lobes pbrt-v3's `DisneyMaterial::ComputeScatteringFunctions` adds, each weighted
    /// by `scale`. Lobes of zero weight are added too, as pbrt-v3 does: the lobe count decides
    /// the sampling probabilities. pbrt-v3's Disney BSDF keeps the relative index 1 (its
    /// transmission is rough, and only a specular one scales Russian roulette by it).
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum) {
        let mut add = |x: Bxdf| {
            b.add_scaled(x, scale);
        };
        let c = self.color.eval(si).max(Spectrum::ZERO);
        let metallic = self.metallic.eval(si);
        let e = self.eta.eval(si);
        let strans = self.spec_trans.eval(si);
        let diffuse_weight = (1.0 - metallic) * (1.0 - strans);
        // 0: all the diffuse is reflected; 1: half of it transmitted (pbrt-v3 halves it).
        let dt = self.diff_trans.eval(si) / 2.0;
        let rough = self.roughness.eval(si);
        let lum = crate::spectrum_luminance(c);
        // The colour's hue and saturation.
        let c_tint = if lum > 0.0 { c / lum } else { Spectrum::ONE };
        let sheen = self.sheen.eval(si);
        let c_sheen = if sheen > 0.0 {
            lerp_s(self.sheen_tint.eval(si), Spectrum::ONE, c_tint)
        } else {
            Spectrum::ZERO
        };

        if diffuse_weight > 0.0 {
            if self.thin {
                // Diffuse and fake subsurface blended by flatness, both weighted by 1 - dt.
                let flat = self.flatness.eval(si);
                add(Bxdf::Disney(DisneyBxdf::Diffuse {
                    r: diffuse_weight * (1.0 - flat) * (1.0 - dt) * c,
                }));
                add(Bxdf::Disney(DisneyBxdf::FakeSs {
                    r: diffuse_weight * flat * (1.0 - dt) * c,
                    roughness: rough,
                }));
            } else {
                // pbrt-v3 swaps this for a refraction and its BSSRDF when scatterdistance is
                // not black: not supported (a warning at build time).
                add(Bxdf::Disney(DisneyBxdf::Diffuse {
                    r: diffuse_weight * c,
                }));
            }
            // A pbrt-v3 quirk: the retro-reflection is not weighted by 1 - dt on thin surfaces.
            add(Bxdf::Disney(DisneyBxdf::Retro {
                r: diffuse_weight * c,
                roughness: rough,
            }));
            if sheen > 0.0 {
                add(Bxdf::Disney(DisneyBxdf::Sheen {
                    r: diffuse_weight * sheen * c_sheen,
                }));
            }
        }

        // Roughness is squared, not remapped, into the alphas.
        let aspect = (1.0 - self.anisotropic.eval(si) * 0.9).sqrt();
        let alphas = |r: f32| {
            TrowbridgeReitz::new(
                cpp_max(0.001, r * r / aspect),
                cpp_max(0.001, r * r * aspect),
            )
        };
        let distribution = alphas(rough);
        let spec_tint = self.specular_tint.eval(si);
        let r0 = lerp_s(
            metallic,
            schlick_r0_from_eta(e) * lerp_s(spec_tint, Spectrum::ONE, c_tint),
            c,
        );
        add(Bxdf::Disney(DisneyBxdf::Specular {
            distribution,
            r0,
            metallic,
            eta: e,
        }));

        let cc = self.clearcoat.eval(si);
        if cc > 0.0 {
            add(Bxdf::Disney(DisneyBxdf::Clearcoat {
                weight: cc,
                gloss: lerp(self.clearcoat_gloss.eval(si), 0.1, 0.001),
            }));
        }

        if strans > 0.0 {
            // Scaled by sqrt(colour), so that two refractions give the colour back.
            let t = strans * c.map(f32::sqrt);
            if self.thin {
                // Roughness scaled by the index (Burley 2015, figure 15), and, unlike the
                // reflection, Trowbridge-Reitz's own masking-shadowing. A thin surface still
                // refracts with `eta` in pbrt-v3.
                let rscaled = (0.65 * e - 0.35) * rough;
                add(Bxdf::MicrofacetTransmission {
                    t,
                    distribution: alphas(rscaled),
                    eta_a: 1.0,
                    eta_b: e,
                });
            } else {
                add(Bxdf::Disney(DisneyBxdf::Transmission {
                    t,
                    distribution,
                    eta: e,
                }));
            }
        }
        if self.thin {
            // pbrt-v3's comment says "weighted by (1 - diffTrans)"; it is weighted by dt, and
            // added even where the diffuse weight is zero (a thin metal transmits diffusely).
            add(Bxdf::LambertianTransmission { t: dt * c });
        }
    }
}
