//! pbrt-v3's `disney` material (materials/disney.{h,cpp}): Burley's 2015 Disney BSDF as pbrt-v3
//! builds it, lobe for lobe and weight for weight, quirks included (each noted where it is).
//!
//! [`DisneyMaterial::add_lobes`] is pbrt-v3's `DisneyMaterial::ComputeScatteringFunctions`; the
//! lobes pbrt-v3 defines in disney.cpp are [`DisneyBxdf`] (one [`Bxdf::Disney`] variant), and
//! the two it borrows unchanged from core/reflection.cpp are the existing
//! [`Bxdf::MicrofacetTransmission`] (the thin surface's) and [`Bxdf::LambertianTransmission`].
//!
//! Not supported: `scatterdistance` (pbrt-v3's `DisneyBSSRDF` subsurface scattering, which
//! replaces the diffuse lobe by a smooth refraction into the object): acr has no BSSRDF, so a
//! non-zero `scatterdistance` warns and the surface keeps pbrt-v3's diffuse lobe instead.

use crate::bsdf::{
    fr_dielectric, reflect, sample_microfacet_reflection, Bsdf, Bxdf, BxdfType, LobeSample,
};
use crate::geometry::{Spectrum, SurfaceInteraction, Vec2, Vec3};
use crate::microfacet::{abs_cos_theta, same_hemisphere, TrowbridgeReitz};
use crate::sampling::cosine_sample_hemisphere;
use crate::texture::{FloatTexture, SpectrumTexture, TextureBuilder};
use acr_parser::{Loc, ParamList, Result};
use std::f32::consts::{FRAC_1_PI, PI};

/// pbrt-v3's `SchlickWeight`: (1 - cos θ)⁵, with 1 - cos θ clamped to [0, 1].
#[inline]
fn schlick_weight(cos_theta: f32) -> f32 {
    let m = (1.0 - cos_theta).clamp(0.0, 1.0);
    (m * m) * (m * m) * m
}

/// pbrt-v3's `Lerp(t, a, b)` = (1 - t) a + t b, for floats.
#[inline]
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// pbrt-v3's `Lerp` for spectra.
#[inline]
fn lerp_s(t: f32, a: Spectrum, b: Spectrum) -> Spectrum {
    (1.0 - t) * a + t * b
}

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

/// pbrt-v3's `GTR1`, the clearcoat's distribution of normals (fatter tails than GGX).
#[inline]
fn gtr1(cos_theta: f32, alpha: f32) -> f32 {
    let alpha2 = alpha * alpha;
    (alpha2 - 1.0) / (PI * alpha2.ln() * (1.0 + (alpha2 - 1.0) * cos_theta * cos_theta))
}

/// pbrt-v3's `smithG_GGX`: the clearcoat's masking term with the 1 / (2 cos θ) of the microfacet
/// denominator folded in.
#[inline]
fn smith_g_ggx(cos_theta: f32, alpha: f32) -> f32 {
    let alpha2 = alpha * alpha;
    let cos2 = cos_theta * cos_theta;
    1.0 / (cos_theta + (alpha2 + cos2 - alpha2 * cos2).sqrt())
}

/// The normalised half vector of `wo` and `wi`; `None` when they are opposite (pbrt-v3's lobes
/// return zero there).
#[inline]
fn half_vector(wo: Vec3, wi: Vec3) -> Option<Vec3> {
    let wh = wi + wo;
    if wh == Vec3::ZERO {
        return None;
    }
    wh.try_normalize()
}

/// The ratio of the Disney masking-shadowing (pbrt-v3's `DisneyMicrofacetDistribution::G`, the
/// separable G1(wo) G1(wi)) to Trowbridge-Reitz's height-correlated 1 / (1 + Λ(wo) + Λ(wi)).
#[inline]
fn separable_over_correlated(d: &TrowbridgeReitz, wo: Vec3, wi: Vec3) -> f32 {
    let (lo, li) = (d.lambda(wo), d.lambda(wi));
    (1.0 + lo + li) / ((1.0 + lo) * (1.0 + li))
}

/// A lobe of pbrt-v3's Disney BSDF, in the local shading frame (z = shading normal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DisneyBxdf {
    /// `DisneyDiffuse`: R / π times Burley's diffuse Fresnel factors.
    Diffuse {
        /// Reflectance.
        r: Spectrum,
    },
    /// `DisneyFakeSS`: the Hanrahan-Krueger-like "fake subsurface" lobe of thin surfaces.
    FakeSs {
        /// Reflectance.
        r: Spectrum,
        /// Roughness (not remapped).
        roughness: f32,
    },
    /// `DisneyRetro`: the roughness-driven retro-reflection added to the diffuse lobe.
    Retro {
        /// Reflectance.
        r: Spectrum,
        /// Roughness (not remapped).
        roughness: f32,
    },
    /// `DisneySheen`: R times the Schlick weight of the half angle.
    Sheen {
        /// Sheen colour times its weights.
        r: Spectrum,
    },
    /// `DisneyClearcoat`: a GTR1 coat with a fixed 0.04 Schlick Fresnel.
    Clearcoat {
        /// The `clearcoat` weight.
        weight: f32,
        /// The GTR1 alpha (pbrt-v3 calls it gloss): lerp(clearcoatgloss, 0.1, 0.001).
        gloss: f32,
    },
    /// `MicrofacetReflection` with R = 1, `DisneyMicrofacetDistribution` (Trowbridge-Reitz with
    /// separable masking-shadowing) and `DisneyFresnel`.
    Specular {
        /// Trowbridge-Reitz alphas.
        distribution: TrowbridgeReitz,
        /// `Cspec0`, the Schlick reflectance at normal incidence of the metallic part.
        r0: Spectrum,
        /// Blend between dielectric Fresnel (0) and Schlick from `r0` (1).
        metallic: f32,
        /// Index of refraction of the dielectric Fresnel.
        eta: f32,
    },
    /// `MicrofacetTransmission` (from index 1 to `eta`) with `DisneyMicrofacetDistribution`:
    /// pbrt-v3's non-thin transmission shares the specular lobe's distribution, so its
    /// masking-shadowing is the separable one too.
    Transmission {
        /// Transmittance scale.
        t: Spectrum,
        /// Trowbridge-Reitz alphas.
        distribution: TrowbridgeReitz,
        /// Index of refraction inside.
        eta: f32,
    },
}

impl DisneyBxdf {
    /// The lobe's kind, as pbrt-v3's `BxDFType`.
    pub fn kind(&self) -> BxdfType {
        use BxdfType as T;
        match self {
            DisneyBxdf::Diffuse { .. }
            | DisneyBxdf::FakeSs { .. }
            | DisneyBxdf::Retro { .. }
            | DisneyBxdf::Sheen { .. } => T::REFLECTION.or(T::DIFFUSE),
            DisneyBxdf::Clearcoat { .. } | DisneyBxdf::Specular { .. } => {
                T::REFLECTION.or(T::GLOSSY)
            }
            DisneyBxdf::Transmission { .. } => T::TRANSMISSION.or(T::GLOSSY),
        }
    }

    /// The same transmission with Trowbridge-Reitz's own masking-shadowing: pbrt-v3's
    /// `MicrofacetTransmission`, which acr's [`Bxdf::MicrofacetTransmission`] is.
    #[inline]
    fn smith_transmission(t: Spectrum, distribution: TrowbridgeReitz, eta: f32) -> Bxdf {
        Bxdf::MicrofacetTransmission {
            t,
            distribution,
            eta_a: 1.0,
            eta_b: eta,
        }
    }

    /// The lobe's value for local `wo` and `wi`. Like pbrt-v3's, the diffuse-like lobes do not
    /// look at the sides: the BSDF's geometric test keeps reflection.
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Spectrum {
        let v = match *self {
            DisneyBxdf::Diffuse { r } => {
                let fo = schlick_weight(abs_cos_theta(wo));
                let fi = schlick_weight(abs_cos_theta(wi));
                // Diffuse Fresnel: 1 at normal incidence to 0.5 at grazing (Burley 2015, eq. 4).
                r * FRAC_1_PI * (1.0 - fo / 2.0) * (1.0 - fi / 2.0)
            }
            DisneyBxdf::FakeSs { r, roughness } => {
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                let cos_d = wi.dot(wh);
                // Fss90 "flattens" the retro-reflection by roughness.
                let fss90 = cos_d * cos_d * roughness;
                let fo = schlick_weight(abs_cos_theta(wo));
                let fi = schlick_weight(abs_cos_theta(wi));
                let fss = lerp(fo, 1.0, fss90) * lerp(fi, 1.0, fss90);
                // pbrt-v3's 1.25 roughly preserves the albedo (it is not energy conserving).
                let ss = 1.25 * (fss * (1.0 / (abs_cos_theta(wo) + abs_cos_theta(wi)) - 0.5) + 0.5);
                r * FRAC_1_PI * ss
            }
            DisneyBxdf::Retro { r, roughness } => {
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                let cos_d = wi.dot(wh);
                let fo = schlick_weight(abs_cos_theta(wo));
                let fi = schlick_weight(abs_cos_theta(wi));
                let rr = 2.0 * roughness * cos_d * cos_d;
                // Burley 2015, eq. 4.
                r * FRAC_1_PI * rr * (fo + fi + fo * fi * (rr - 1.0))
            }
            DisneyBxdf::Sheen { r } => {
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                r * schlick_weight(wi.dot(wh))
            }
            DisneyBxdf::Clearcoat { weight, gloss } => {
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                // Index 1.5 (F0 = 0.04) is fixed; the geometric term always takes alpha 0.25.
                let dr = gtr1(abs_cos_theta(wh), gloss);
                let fr = lerp(schlick_weight(wo.dot(wh)), 0.04, 1.0);
                let gr =
                    smith_g_ggx(abs_cos_theta(wo), 0.25) * smith_g_ggx(abs_cos_theta(wi), 0.25);
                Spectrum::splat(weight * gr * fr * dr / 4.0)
            }
            DisneyBxdf::Specular {
                distribution,
                r0,
                metallic,
                eta,
            } => {
                let (cos_o, cos_i) = (abs_cos_theta(wo), abs_cos_theta(wi));
                if cos_i == 0.0 || cos_o == 0.0 {
                    return Spectrum::ZERO;
                }
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                // Fresnel of the half vector faced forward, as pbrt-v3's MicrofacetReflection.
                let wh_f = if wh.z < 0.0 { -wh } else { wh };
                let fr = disney_fresnel(r0, metallic, eta, wi.dot(wh_f));
                let g = distribution.g1(wo) * distribution.g1(wi);
                fr * (distribution.d(wh) * g) / (4.0 * cos_i * cos_o)
            }
            DisneyBxdf::Transmission {
                t,
                distribution,
                eta,
            } => {
                let f = Self::smith_transmission(t, distribution, eta).f(wo, wi);
                if f == Spectrum::ZERO {
                    return f;
                }
                f * separable_over_correlated(&distribution, wo, wi)
            }
        };
        if v.is_finite() {
            v
        } else {
            Spectrum::ZERO
        }
    }

    /// Samples an incident direction for local `wo`: cosine-weighted for the diffuse-like lobes
    /// (pbrt-v3's default `BxDF::Sample_f`), the GTR1 normals for the clearcoat, the visible
    /// Trowbridge-Reitz normals for the specular lobes.
    pub fn sample_f(&self, wo: Vec3, u: Vec2) -> Option<LobeSample> {
        let wi = match *self {
            DisneyBxdf::Diffuse { .. }
            | DisneyBxdf::FakeSs { .. }
            | DisneyBxdf::Retro { .. }
            | DisneyBxdf::Sheen { .. } => {
                let mut wi = cosine_sample_hemisphere(u);
                if wo.z < 0.0 {
                    wi.z = -wi.z;
                }
                wi
            }
            DisneyBxdf::Clearcoat { gloss, .. } => {
                if wo.z == 0.0 {
                    return None;
                }
                let alpha2 = gloss * gloss;
                let cos_theta = ((1.0 - alpha2.powf(1.0 - u.x)) / (1.0 - alpha2))
                    .max(0.0)
                    .sqrt();
                let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                let mut wh = Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta);
                if !same_hemisphere(wo, wh) {
                    wh = -wh;
                }
                let wi = reflect(wo, wh);
                if !same_hemisphere(wo, wi) {
                    return None;
                }
                wi
            }
            DisneyBxdf::Specular { distribution, .. } => {
                let (wi, pdf) = sample_microfacet_reflection(&distribution, wo, u)?;
                return Some(LobeSample {
                    wi,
                    f: self.f(wo, wi),
                    pdf,
                    kind: self.kind(),
                });
            }
            DisneyBxdf::Transmission {
                t,
                distribution,
                eta,
            } => {
                // The same directions and density as the Trowbridge-Reitz transmission (its
                // sampling and pdf use G1(wo) only); the value is this lobe's.
                let s = Self::smith_transmission(t, distribution, eta).sample_f(wo, u)?;
                return Some(LobeSample {
                    f: s.f * separable_over_correlated(&distribution, wo, s.wi),
                    ..s
                });
            }
        };
        Some(LobeSample {
            wi,
            f: self.f(wo, wi),
            pdf: self.pdf(wo, wi),
            kind: self.kind(),
        })
    }

    /// Density with which [`DisneyBxdf::sample_f`] picks local `wi` given `wo`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let p = match *self {
            DisneyBxdf::Diffuse { .. }
            | DisneyBxdf::FakeSs { .. }
            | DisneyBxdf::Retro { .. }
            | DisneyBxdf::Sheen { .. } => {
                if same_hemisphere(wo, wi) {
                    abs_cos_theta(wi) * FRAC_1_PI
                } else {
                    0.0
                }
            }
            DisneyBxdf::Clearcoat { gloss, .. } => {
                if !same_hemisphere(wo, wi) {
                    return 0.0;
                }
                let Some(wh) = half_vector(wo, wi) else {
                    return 0.0;
                };
                // The sampler draws wh from GTR1 exactly: D cos θh, to the reflected direction.
                let dr = gtr1(abs_cos_theta(wh), gloss);
                dr * abs_cos_theta(wh) / (4.0 * wo.dot(wh))
            }
            DisneyBxdf::Specular { distribution, .. } => {
                if !same_hemisphere(wo, wi) {
                    return 0.0;
                }
                let Some(wh) = half_vector(wo, wi) else {
                    return 0.0;
                };
                distribution.pdf(wo, wh) / (4.0 * wo.dot(wh))
            }
            DisneyBxdf::Transmission {
                t,
                distribution,
                eta,
            } => Self::smith_transmission(t, distribution, eta).pdf(wo, wi),
        };
        if p.is_finite() && p > 0.0 {
            p
        } else {
            0.0
        }
    }

    /// The lobe's nominal reflectance or transmittance for first-hit features: R for the
    /// diffuse-like lobes (none for the retro-reflection, a correction of the diffuse lobe's),
    /// the normal-incidence Fresnel for the specular lobe and the clearcoat, T for transmission.
    pub fn albedo(&self) -> Spectrum {
        match *self {
            DisneyBxdf::Diffuse { r } | DisneyBxdf::FakeSs { r, .. } | DisneyBxdf::Sheen { r } => r,
            DisneyBxdf::Retro { .. } => Spectrum::ZERO,
            DisneyBxdf::Clearcoat { weight, .. } => Spectrum::splat(0.04 * weight),
            DisneyBxdf::Specular {
                r0, metallic, eta, ..
            } => disney_fresnel(r0, metallic, eta, 1.0),
            DisneyBxdf::Transmission { t, .. } => t,
        }
    }
}

/// pbrt-v3's `DisneyFresnel`: lerp(metallic, dielectric Fresnel of `eta`, Schlick from `r0`).
/// A pbrt-v3 quirk: the dielectric part ignores `r0`, so `speculartint` only shows where
/// `metallic` is strictly between 0 and 1.
#[inline]
fn disney_fresnel(r0: Spectrum, metallic: f32, eta: f32, cos_i: f32) -> Spectrum {
    let dielectric = Spectrum::splat(fr_dielectric(cos_i, 1.0, eta));
    let schlick = lerp_s(schlick_weight(cos_i), r0, Spectrum::ONE);
    lerp_s(metallic, dielectric, schlick)
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
    /// the sampling probabilities.
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

#[cfg(test)]
mod tests;
