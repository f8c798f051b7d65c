//! The lobes of pbrt-v3's Disney BSDF (materials/disney.cpp): Burley's 2015 BSDF as pbrt-v3
//! builds it, lobe for lobe, quirks included (each noted where it is). The material that adds
//! them at a hit is [`crate::material::disney`]; the lobes pbrt-v3 defines in disney.cpp are
//! [`DisneyBxdf`] (one `Bxdf::Disney` variant), and the two it borrows unchanged from
//! core/reflection.cpp are the plain `Bxdf::MicrofacetTransmission` (the thin surface's) and
//! `Bxdf::LambertianTransmission`.

use super::fresnel::{fr_dielectric, reflect};
use super::lobe::{
    finite_pdf, sample_microfacet_reflection, BxdfType, LobeSample, MicrofacetTransmission,
};
use crate::geometry::{Spectrum, Vec2, Vec3};
use crate::microfacet::{abs_cos_theta, same_hemisphere, TrowbridgeReitz};
use crate::sampling::cosine_sample_hemisphere;
use std::f32::consts::{FRAC_1_PI, PI};

/// pbrt-v3's `SchlickWeight`: (1 - cos θ)⁵, with 1 - cos θ clamped to [0, 1].
#[inline]
fn schlick_weight(cos_theta: f32) -> f32 {
    let m = (1.0 - cos_theta).clamp(0.0, 1.0);
    (m * m) * (m * m) * m
}

/// pbrt-v3's `Lerp(t, a, b)` = (1 - t) a + t b, for floats.
#[inline]
pub(crate) fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// pbrt-v3's `Lerp` for spectra.
#[inline]
pub(crate) fn lerp_s(t: f32, a: Spectrum, b: Spectrum) -> Spectrum {
    (1.0 - t) * a + t * b
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
    /// `MicrofacetTransmission`, which acr's `Bxdf::MicrofacetTransmission` is.
    #[inline]
    fn smith_transmission(
        t: Spectrum,
        distribution: TrowbridgeReitz,
        eta: f32,
    ) -> MicrofacetTransmission {
        MicrofacetTransmission {
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
        finite_pdf(p)
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

#[cfg(test)]
mod tests;
