//! pbrt-v3's BxDFs, as one enum: each lobe's value, sampling and density in the local
//! shading frame.

use super::disney::DisneyBxdf;
use super::fresnel::{fr_dielectric, reflect, refract, Fresnel};
use super::hair::HairBsdf;
use super::lobe::{
    finite_pdf, sample_microfacet_reflection, BxdfType, LobeSample, MicrofacetTransmission,
    ONE_MINUS_EPSILON,
};
use crate::fourier::FourierBsdf;
use crate::geometry::{Spectrum, Vec2, Vec3};
use crate::microfacet::{abs_cos_theta, cos_theta, same_hemisphere, sin_theta, TrowbridgeReitz};
use crate::sampling::cosine_sample_hemisphere;
use std::f32::consts::FRAC_1_PI;

/// Perfect refraction of local `wo` through the boundary between `eta_a` (the normal's side)
/// and `eta_b`: the direction and (eta_i / eta_t)^2, the radiance scale across it. `None` on
/// total internal reflection or a grazing result.
fn specular_refraction(wo: Vec3, eta_a: f32, eta_b: f32) -> Option<(Vec3, f32)> {
    let (eta_i, eta_t) = if cos_theta(wo) > 0.0 {
        (eta_a, eta_b)
    } else {
        (eta_b, eta_a)
    };
    let n = if wo.z < 0.0 { -Vec3::Z } else { Vec3::Z };
    let wi = refract(wo, n, eta_i / eta_t)?;
    if wi.z == 0.0 {
        return None;
    }
    Some((wi, (eta_i * eta_i) / (eta_t * eta_t)))
}

/// One of pbrt-v3's BxDFs, for radiance transport.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bxdf {
    /// Lambertian reflection: R / π.
    Lambertian {
        /// Reflectance.
        r: Spectrum,
    },
    /// Lambertian transmission: T / π to the other side (pbrt-v3's, for `translucent`).
    LambertianTransmission {
        /// Transmittance.
        t: Spectrum,
    },
    /// Oren-Nayar rough diffuse reflection.
    OrenNayar {
        /// Reflectance.
        r: Spectrum,
        /// Precomputed A term.
        a: f32,
        /// Precomputed B term.
        b: f32,
    },
    /// Perfect mirror reflection weighted by a Fresnel term.
    SpecularReflection {
        /// Reflectance scale.
        r: Spectrum,
        /// Fresnel term.
        fresnel: Fresnel,
    },
    /// Perfect refraction between indices `eta_a` (outside) and `eta_b` (inside).
    SpecularTransmission {
        /// Transmittance scale.
        t: Spectrum,
        /// Index on the normal's side.
        eta_a: f32,
        /// Index on the other side.
        eta_b: f32,
    },
    /// Smooth dielectric: reflection and refraction chosen by their Fresnel probabilities.
    FresnelSpecular {
        /// Reflectance scale.
        r: Spectrum,
        /// Transmittance scale.
        t: Spectrum,
        /// Index on the normal's side.
        eta_a: f32,
        /// Index on the other side.
        eta_b: f32,
    },
    /// Torrance-Sparrow microfacet reflection.
    MicrofacetReflection {
        /// Reflectance scale.
        r: Spectrum,
        /// Microfacet distribution.
        distribution: TrowbridgeReitz,
        /// Fresnel term.
        fresnel: Fresnel,
    },
    /// Walter et al.'s microfacet refraction through a dielectric.
    MicrofacetTransmission {
        /// Transmittance scale.
        t: Spectrum,
        /// Microfacet distribution.
        distribution: TrowbridgeReitz,
        /// Index on the normal's side.
        eta_a: f32,
        /// Index on the other side.
        eta_b: f32,
    },
    /// Ashikhmin-Shirley glossy coating over a diffuse base (the substrate material).
    FresnelBlend {
        /// Diffuse reflectance.
        rd: Spectrum,
        /// Specular reflectance at normal incidence.
        rs: Spectrum,
        /// Microfacet distribution.
        distribution: TrowbridgeReitz,
    },
    /// pbrt-v3's `HairBSDF` (the hair material), in a frame whose x is along the hair.
    Hair(HairBsdf),
    /// A lobe of pbrt-v3's Disney BSDF (`src/bsdf/disney/mod.rs`).
    Disney(DisneyBxdf),
    /// pbrt-v3's tabulated `FourierBSDF` (the fourier material, `src/fourier.rs`).
    Fourier(FourierBsdf),
    /// pbrt-v3's `SeparableBSSRDFAdapter`: where a subsurface path leaves the surface, the
    /// BSSRDF's directional term `(1 - Fr(cos θi)) * scale` (scale = η² / (c π), made by
    /// `src/bssrdf/adapter.rs`), diffuse reflection.
    BssrdfAdapter {
        /// Relative index of refraction, inside over outside.
        eta: f32,
        /// η² / (c π), with c = 1 - 2 FresnelMoment1(1 / η).
        scale: f32,
    },
}

impl Bxdf {
    /// Oren-Nayar with reflectance `r` and roughness `sigma_degrees` (standard deviation of the
    /// facet angle, in degrees).
    pub fn oren_nayar(r: Spectrum, sigma_degrees: f32) -> Self {
        let sigma = sigma_degrees.to_radians();
        let sigma2 = sigma * sigma;
        Bxdf::OrenNayar {
            r,
            a: 1.0 - (sigma2 / (2.0 * (sigma2 + 0.33))),
            b: 0.45 * sigma2 / (sigma2 + 0.09),
        }
    }

    /// The lobe's kind.
    pub fn kind(&self) -> BxdfType {
        use BxdfType as T;
        match self {
            Bxdf::Lambertian { .. } | Bxdf::OrenNayar { .. } | Bxdf::BssrdfAdapter { .. } => {
                T::REFLECTION.or(T::DIFFUSE)
            }
            Bxdf::LambertianTransmission { .. } => T::TRANSMISSION.or(T::DIFFUSE),
            Bxdf::SpecularReflection { .. } => T::REFLECTION.or(T::SPECULAR),
            Bxdf::SpecularTransmission { .. } => T::TRANSMISSION.or(T::SPECULAR),
            Bxdf::FresnelSpecular { .. } => T::REFLECTION.or(T::TRANSMISSION).or(T::SPECULAR),
            Bxdf::MicrofacetReflection { .. } | Bxdf::FresnelBlend { .. } => {
                T::REFLECTION.or(T::GLOSSY)
            }
            Bxdf::MicrofacetTransmission { .. } => T::TRANSMISSION.or(T::GLOSSY),
            Bxdf::Hair(_) => T::REFLECTION.or(T::TRANSMISSION).or(T::GLOSSY),
            Bxdf::Disney(d) => d.kind(),
            Bxdf::Fourier(_) => T::REFLECTION.or(T::TRANSMISSION).or(T::GLOSSY),
        }
    }

    /// Whether [`Bxdf::sample_f`]'s value is [`Bxdf::f`] of the sampled direction, bit for bit
    /// (so [`super::Bsdf::sample_f`] need not evaluate it again).
    #[inline]
    pub(crate) fn sample_is_f(&self) -> bool {
        matches!(
            self,
            Bxdf::Lambertian { .. }
                | Bxdf::OrenNayar { .. }
                | Bxdf::BssrdfAdapter { .. }
                | Bxdf::LambertianTransmission { .. }
                | Bxdf::MicrofacetReflection { .. }
                | Bxdf::MicrofacetTransmission { .. }
                | Bxdf::FresnelBlend { .. }
        )
    }

    /// Whether the lobe is a delta distribution.
    #[inline]
    pub fn is_specular(&self) -> bool {
        self.kind().contains(BxdfType::SPECULAR)
    }

    /// The lobe's value for local directions `wo` and `wi` (zero for specular lobes).
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Spectrum {
        match *self {
            Bxdf::Lambertian { r } => r * FRAC_1_PI,
            Bxdf::BssrdfAdapter { eta, scale } => {
                Spectrum::splat((1.0 - fr_dielectric(cos_theta(wi), 1.0, eta)) * scale)
            }
            // As pbrt-v3, whatever the sides: the BSDF's geometric test keeps transmission.
            Bxdf::LambertianTransmission { t } => t * FRAC_1_PI,
            Bxdf::OrenNayar { r, a, b } => {
                let sin_i = sin_theta(wi);
                let sin_o = sin_theta(wo);
                let mut max_cos = 0.0;
                if sin_i > 1e-4 && sin_o > 1e-4 {
                    let (cos_phi_i, sin_phi_i) = (wi.x / sin_i, wi.y / sin_i);
                    let (cos_phi_o, sin_phi_o) = (wo.x / sin_o, wo.y / sin_o);
                    let d_cos = cos_phi_i.clamp(-1.0, 1.0) * cos_phi_o.clamp(-1.0, 1.0)
                        + sin_phi_i.clamp(-1.0, 1.0) * sin_phi_o.clamp(-1.0, 1.0);
                    max_cos = d_cos.max(0.0);
                }
                let (sin_alpha, tan_beta) = if abs_cos_theta(wi) > abs_cos_theta(wo) {
                    (sin_o, sin_i / abs_cos_theta(wi))
                } else {
                    (sin_i, sin_o / abs_cos_theta(wo))
                };
                let v = r * FRAC_1_PI * (a + b * max_cos * sin_alpha * tan_beta);
                if v.is_finite() {
                    v
                } else {
                    r * FRAC_1_PI * a
                }
            }
            Bxdf::SpecularReflection { .. }
            | Bxdf::SpecularTransmission { .. }
            | Bxdf::FresnelSpecular { .. } => Spectrum::ZERO,
            Bxdf::MicrofacetReflection {
                r,
                distribution,
                fresnel,
            } => {
                let cos_o = abs_cos_theta(wo);
                let cos_i = abs_cos_theta(wi);
                let wh = wi + wo;
                if cos_i == 0.0 || cos_o == 0.0 || wh == Vec3::ZERO {
                    return Spectrum::ZERO;
                }
                let wh = wh.normalize();
                // The half vector faced forward, as pbrt-v3 has done since its issue #254: with
                // a shading normal facing away from the viewer, Dot(wi, wh) is negative and a
                // dielectric Fresnel term would swap its indices.
                let wh_forward = if wh.z < 0.0 { -wh } else { wh };
                let fr = fresnel.evaluate(wi.dot(wh_forward));
                r * distribution.d(wh) * distribution.g(wo, wi) * fr / (4.0 * cos_i * cos_o)
            }
            Bxdf::MicrofacetTransmission {
                t,
                distribution,
                eta_a,
                eta_b,
            } => MicrofacetTransmission {
                t,
                distribution,
                eta_a,
                eta_b,
            }
            .f(wo, wi),
            Bxdf::FresnelBlend {
                rd,
                rs,
                distribution,
            } => {
                let pow5 = |v: f32| (v * v) * (v * v) * v;
                let diffuse = (28.0 / (23.0 * std::f32::consts::PI))
                    * rd
                    * (Spectrum::ONE - rs)
                    * (1.0 - pow5(1.0 - 0.5 * abs_cos_theta(wi)))
                    * (1.0 - pow5(1.0 - 0.5 * abs_cos_theta(wo)));
                let wh = wi + wo;
                if wh == Vec3::ZERO {
                    return Spectrum::ZERO;
                }
                let wh = wh.normalize();
                let denom = 4.0 * wi.dot(wh).abs() * abs_cos_theta(wi).max(abs_cos_theta(wo));
                if denom == 0.0 {
                    return diffuse;
                }
                let schlick = rs + pow5(1.0 - wi.dot(wh)) * (Spectrum::ONE - rs);
                diffuse + distribution.d(wh) / denom * schlick
            }
            Bxdf::Hair(h) => h.f(wo, wi),
            Bxdf::Disney(d) => d.f(wo, wi),
            Bxdf::Fourier(t) => t.f(wo, wi),
        }
    }

    /// Samples an incident direction for local `wo` with `u` in [0, 1)²; `None` when the lobe
    /// gives nothing (below the horizon, total internal reflection, degenerate directions).
    pub fn sample_f(&self, wo: Vec3, u: Vec2) -> Option<LobeSample> {
        use BxdfType as T;
        let kind = self.kind();
        let s = match *self {
            Bxdf::Lambertian { .. } | Bxdf::OrenNayar { .. } | Bxdf::BssrdfAdapter { .. } => {
                let mut wi = cosine_sample_hemisphere(u);
                if wo.z < 0.0 {
                    wi.z = -wi.z;
                }
                LobeSample {
                    wi,
                    f: self.f(wo, wi),
                    pdf: self.pdf(wo, wi),
                    kind,
                }
            }
            Bxdf::LambertianTransmission { .. } => {
                let mut wi = cosine_sample_hemisphere(u);
                if wo.z > 0.0 {
                    wi.z = -wi.z;
                }
                LobeSample {
                    wi,
                    f: self.f(wo, wi),
                    pdf: self.pdf(wo, wi),
                    kind,
                }
            }
            Bxdf::SpecularReflection { r, fresnel } => {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                if wi.z == 0.0 {
                    return None;
                }
                LobeSample {
                    wi,
                    f: fresnel.evaluate(cos_theta(wi)) * r / abs_cos_theta(wi),
                    pdf: 1.0,
                    kind,
                }
            }
            Bxdf::SpecularTransmission { t, eta_a, eta_b } => {
                let (wi, eta2) = specular_refraction(wo, eta_a, eta_b)?;
                let ft = t * (1.0 - fr_dielectric(cos_theta(wi), eta_a, eta_b)) * eta2;
                LobeSample {
                    wi,
                    f: ft / abs_cos_theta(wi),
                    pdf: 1.0,
                    kind,
                }
            }
            Bxdf::FresnelSpecular { r, t, eta_a, eta_b } => {
                let fr = fr_dielectric(cos_theta(wo), eta_a, eta_b);
                if u.x < fr {
                    let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                    if wi.z == 0.0 {
                        return None;
                    }
                    LobeSample {
                        wi,
                        f: fr * r / abs_cos_theta(wi),
                        pdf: fr,
                        kind: T::SPECULAR.or(T::REFLECTION),
                    }
                } else {
                    let (wi, eta2) = specular_refraction(wo, eta_a, eta_b)?;
                    let ft = t * (1.0 - fr) * eta2;
                    LobeSample {
                        wi,
                        f: ft / abs_cos_theta(wi),
                        pdf: 1.0 - fr,
                        kind: T::SPECULAR.or(T::TRANSMISSION),
                    }
                }
            }
            Bxdf::MicrofacetReflection { distribution, .. } => {
                let (wi, pdf) = sample_microfacet_reflection(&distribution, wo, u)?;
                LobeSample {
                    wi,
                    f: self.f(wo, wi),
                    pdf,
                    kind,
                }
            }
            Bxdf::MicrofacetTransmission {
                t,
                distribution,
                eta_a,
                eta_b,
            } => MicrofacetTransmission {
                t,
                distribution,
                eta_a,
                eta_b,
            }
            .sample_f(wo, u)?,
            Bxdf::FresnelBlend { distribution, .. } => {
                let wi = if u.x < 0.5 {
                    let u = Vec2::new((2.0 * u.x).min(ONE_MINUS_EPSILON), u.y);
                    let mut wi = cosine_sample_hemisphere(u);
                    if wo.z < 0.0 {
                        wi.z = -wi.z;
                    }
                    wi
                } else {
                    let u = Vec2::new((2.0 * (u.x - 0.5)).min(ONE_MINUS_EPSILON), u.y);
                    let wh = distribution.sample_wh(wo, u);
                    let wi = reflect(wo, wh);
                    if !same_hemisphere(wo, wi) {
                        return None;
                    }
                    wi
                };
                LobeSample {
                    wi,
                    f: self.f(wo, wi),
                    pdf: self.pdf(wo, wi),
                    kind,
                }
            }
            Bxdf::Hair(h) => {
                let (wi, f, pdf) = h.sample_f(wo, u);
                LobeSample { wi, f, pdf, kind }
            }
            Bxdf::Disney(d) => d.sample_f(wo, u)?,
            Bxdf::Fourier(t) => {
                let (wi, f, pdf) = t.sample_f(wo, [u.x, u.y])?;
                LobeSample { wi, f, pdf, kind }
            }
        };
        s.valid()
    }

    /// Density with which [`Bxdf::sample_f`] picks local `wi` given `wo` (zero for specular
    /// lobes).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let p = match *self {
            Bxdf::Lambertian { .. } | Bxdf::OrenNayar { .. } | Bxdf::BssrdfAdapter { .. } => {
                if same_hemisphere(wo, wi) {
                    abs_cos_theta(wi) * FRAC_1_PI
                } else {
                    0.0
                }
            }
            Bxdf::LambertianTransmission { .. } => {
                if same_hemisphere(wo, wi) {
                    0.0
                } else {
                    abs_cos_theta(wi) * FRAC_1_PI
                }
            }
            Bxdf::SpecularReflection { .. }
            | Bxdf::SpecularTransmission { .. }
            | Bxdf::FresnelSpecular { .. } => 0.0,
            Bxdf::MicrofacetReflection { distribution, .. } => {
                if !same_hemisphere(wo, wi) {
                    return 0.0;
                }
                let Some(wh) = (wo + wi).try_normalize() else {
                    return 0.0;
                };
                distribution.pdf(wo, wh) / (4.0 * wo.dot(wh))
            }
            Bxdf::MicrofacetTransmission {
                t,
                distribution,
                eta_a,
                eta_b,
            } => MicrofacetTransmission {
                t,
                distribution,
                eta_a,
                eta_b,
            }
            .pdf(wo, wi),
            Bxdf::FresnelBlend { distribution, .. } => {
                if !same_hemisphere(wo, wi) {
                    return 0.0;
                }
                let Some(wh) = (wo + wi).try_normalize() else {
                    return 0.0;
                };
                let pdf_wh = distribution.pdf(wo, wh);
                0.5 * (abs_cos_theta(wi) * FRAC_1_PI + pdf_wh / (4.0 * wo.dot(wh)))
            }
            Bxdf::Hair(h) => h.pdf(wo, wi),
            Bxdf::Disney(d) => d.pdf(wo, wi),
            Bxdf::Fourier(t) => t.pdf(wo, wi),
        };
        finite_pdf(p)
    }
}
