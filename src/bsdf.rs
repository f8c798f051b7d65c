//! pbrt-v3's BxDFs and BSDF (core/reflection.{h,cpp}), for radiance transport, without heap
//! allocation: a [`Bsdf`] holds up to [`MAX_LOBES`] lobes by value, each a [`Bxdf`] enum with an
//! RGB scale (pbrt-v3's `ScaledBxDF`, used by the mix material).
//!
//! Lobes work in the local shading frame (z = shading normal); [`Bsdf`] converts from world
//! space and decides reflection against transmission with the geometric normal, as pbrt-v3 does.
//! Where pbrt-v3 would produce NaN or infinity (grazing or degenerate directions), these return
//! zero, or no sample.

use crate::geometry::{Frame, Spectrum, SurfaceInteraction, Vec2, Vec3};
use crate::microfacet::{abs_cos_theta, cos_theta, same_hemisphere, sin_theta, TrowbridgeReitz};
use crate::sampling::cosine_sample_hemisphere;
use std::f32::consts::FRAC_1_PI;

/// The largest u < 1 in f32 (pbrt-v3's `OneMinusEpsilon`).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Fresnel reflectance of a dielectric interface for unpolarised light (pbrt-v3's
/// `FrDielectric`). `cos_theta_i` is signed: negative means arriving from the `eta_t` side.
/// Total internal reflection gives 1.
pub fn fr_dielectric(cos_theta_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    let mut cos_i = cos_theta_i.clamp(-1.0, 1.0);
    let (mut eta_i, mut eta_t) = (eta_i, eta_t);
    if cos_i <= 0.0 {
        std::mem::swap(&mut eta_i, &mut eta_t);
        cos_i = cos_i.abs();
    }
    let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
    let sin_t = eta_i / eta_t * sin_i;
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let r_parl = ((eta_t * cos_i) - (eta_i * cos_t)) / ((eta_t * cos_i) + (eta_i * cos_t));
    let r_perp = ((eta_i * cos_i) - (eta_t * cos_t)) / ((eta_i * cos_i) + (eta_t * cos_t));
    let r = (r_parl * r_parl + r_perp * r_perp) / 2.0;
    if r.is_finite() {
        r
    } else {
        1.0
    }
}

/// Fresnel reflectance of a conductor with complex index `eta_t + i k` seen from a medium of
/// index `eta_i`, per channel (pbrt-v3's `FrConductor`).
pub fn fr_conductor(cos_theta_i: f32, eta_i: Spectrum, eta_t: Spectrum, k: Spectrum) -> Spectrum {
    let cos_i = cos_theta_i.clamp(-1.0, 1.0);
    let eta = eta_t / eta_i;
    let etak = k / eta_i;
    let cos2 = cos_i * cos_i;
    let sin2 = 1.0 - cos2;
    let eta2 = eta * eta;
    let etak2 = etak * etak;
    let t0 = eta2 - etak2 - Spectrum::splat(sin2);
    let a2plusb2 = (t0 * t0 + 4.0 * eta2 * etak2).max(Spectrum::ZERO).powf(0.5);
    let t1 = a2plusb2 + Spectrum::splat(cos2);
    let a = (0.5 * (a2plusb2 + t0)).max(Spectrum::ZERO).powf(0.5);
    let t2 = 2.0 * cos_i * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = cos2 * a2plusb2 + Spectrum::splat(sin2 * sin2);
    let t4 = t2 * sin2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    let r = 0.5 * (rp + rs);
    if r.is_finite() {
        r
    } else {
        Spectrum::ONE
    }
}

/// A Fresnel term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fresnel {
    /// Reflects everything (pbrt-v3's `FresnelNoOp`, for mirrors).
    NoOp,
    /// A dielectric interface from index `eta_i` to `eta_t`.
    Dielectric {
        /// Index on the side the normal points to.
        eta_i: f32,
        /// Index on the other side.
        eta_t: f32,
    },
    /// A conductor.
    Conductor {
        /// Index of the outside medium.
        eta_i: Spectrum,
        /// Real part of the conductor's index.
        eta_t: Spectrum,
        /// Absorption coefficient (imaginary part).
        k: Spectrum,
    },
}

impl Fresnel {
    /// Reflectance for incident cosine `cos_i` (signed for dielectrics; conductors use |cos|).
    #[inline]
    pub fn evaluate(&self, cos_i: f32) -> Spectrum {
        match *self {
            Fresnel::NoOp => Spectrum::ONE,
            Fresnel::Dielectric { eta_i, eta_t } => {
                Spectrum::splat(fr_dielectric(cos_i, eta_i, eta_t))
            }
            Fresnel::Conductor { eta_i, eta_t, k } => fr_conductor(cos_i.abs(), eta_i, eta_t, k),
        }
    }
}

/// Mirror `wo` about `n`.
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Refracts `wi` (pointing away from the surface, on `n`'s side) through the interface with
/// relative index `eta` = eta_i / eta_t; `None` on total internal reflection.
#[inline]
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = n.dot(wi);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = eta * eta * sin2_i;
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * -wi + (eta * cos_i - cos_t) * n)
}

/// The kind of a lobe, as pbrt-v3's `BxDFType` bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BxdfType(u8);

impl BxdfType {
    /// Scatters to the side it came from.
    pub const REFLECTION: Self = Self(1);
    /// Scatters through the surface.
    pub const TRANSMISSION: Self = Self(2);
    /// Diffuse.
    pub const DIFFUSE: Self = Self(4);
    /// Glossy.
    pub const GLOSSY: Self = Self(8);
    /// A delta distribution.
    pub const SPECULAR: Self = Self(16);

    /// The union of two sets of bits.
    #[inline]
    pub const fn or(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// Whether every bit of `other` is set.
    #[inline]
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }
}

/// A sample of one lobe, in local coordinates.
#[derive(Clone, Copy, Debug)]
pub struct LobeSample {
    /// Sampled incident direction (local).
    pub wi: Vec3,
    /// Lobe value for (wo, wi).
    pub f: Spectrum,
    /// Density of `wi` (for specular lobes, the discrete probability of the chosen event).
    pub pdf: f32,
    /// What was sampled (for `FresnelSpecular`: its reflection or its transmission).
    pub kind: BxdfType,
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
    Hair(crate::hair::HairBsdf),
    /// A lobe of pbrt-v3's Disney BSDF (`src/disney.rs`).
    Disney(crate::disney::DisneyBxdf),
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
            Bxdf::Lambertian { .. } | Bxdf::OrenNayar { .. } => T::REFLECTION.or(T::DIFFUSE),
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
        }
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
            } => {
                if same_hemisphere(wo, wi) {
                    return Spectrum::ZERO;
                }
                let (cos_o, cos_i) = (cos_theta(wo), cos_theta(wi));
                if cos_i == 0.0 || cos_o == 0.0 {
                    return Spectrum::ZERO;
                }
                let eta = if cos_o > 0.0 {
                    eta_b / eta_a
                } else {
                    eta_a / eta_b
                };
                let Some(mut wh) = (wo + wi * eta).try_normalize() else {
                    return Spectrum::ZERO;
                };
                if wh.z < 0.0 {
                    wh = -wh;
                }
                // Same side of the microfacet: not a refraction.
                if wo.dot(wh) * wi.dot(wh) > 0.0 {
                    return Spectrum::ZERO;
                }
                let fr = fr_dielectric(wo.dot(wh), eta_a, eta_b);
                let sqrt_denom = wo.dot(wh) + eta * wi.dot(wh);
                if sqrt_denom == 0.0 {
                    return Spectrum::ZERO;
                }
                let factor = 1.0 / eta;
                (1.0 - fr)
                    * t
                    * (distribution.d(wh)
                        * distribution.g(wo, wi)
                        * eta
                        * eta
                        * wi.dot(wh).abs()
                        * wo.dot(wh).abs()
                        * factor
                        * factor
                        / (cos_i * cos_o * sqrt_denom * sqrt_denom))
                        .abs()
            }
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
        }
    }

    /// Samples an incident direction for local `wo` with `u` in [0, 1)²; `None` when the lobe
    /// gives nothing (below the horizon, total internal reflection, degenerate directions).
    pub fn sample_f(&self, wo: Vec3, u: Vec2) -> Option<LobeSample> {
        use BxdfType as T;
        let kind = self.kind();
        let s = match *self {
            Bxdf::Lambertian { .. } | Bxdf::OrenNayar { .. } => {
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
                let entering = cos_theta(wo) > 0.0;
                let (eta_i, eta_t) = if entering {
                    (eta_a, eta_b)
                } else {
                    (eta_b, eta_a)
                };
                let n = if wo.z < 0.0 { -Vec3::Z } else { Vec3::Z };
                let wi = refract(wo, n, eta_i / eta_t)?;
                if wi.z == 0.0 {
                    return None;
                }
                let ft = t
                    * (1.0 - fr_dielectric(cos_theta(wi), eta_a, eta_b))
                    * ((eta_i * eta_i) / (eta_t * eta_t));
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
                    let entering = cos_theta(wo) > 0.0;
                    let (eta_i, eta_t) = if entering {
                        (eta_a, eta_b)
                    } else {
                        (eta_b, eta_a)
                    };
                    let n = if wo.z < 0.0 { -Vec3::Z } else { Vec3::Z };
                    let wi = refract(wo, n, eta_i / eta_t)?;
                    if wi.z == 0.0 {
                        return None;
                    }
                    let ft = t * (1.0 - fr) * ((eta_i * eta_i) / (eta_t * eta_t));
                    LobeSample {
                        wi,
                        f: ft / abs_cos_theta(wi),
                        pdf: 1.0 - fr,
                        kind: T::SPECULAR.or(T::TRANSMISSION),
                    }
                }
            }
            Bxdf::MicrofacetReflection { distribution, .. } => {
                if wo.z == 0.0 {
                    return None;
                }
                let wh = distribution.sample_wh(wo, u);
                if wo.dot(wh).is_nan() || wo.dot(wh) <= 0.0 {
                    return None;
                }
                let wi = reflect(wo, wh);
                if !same_hemisphere(wo, wi) {
                    return None;
                }
                LobeSample {
                    wi,
                    f: self.f(wo, wi),
                    pdf: distribution.pdf(wo, wh) / (4.0 * wo.dot(wh)),
                    kind,
                }
            }
            Bxdf::MicrofacetTransmission {
                distribution,
                eta_a,
                eta_b,
                ..
            } => {
                if wo.z == 0.0 {
                    return None;
                }
                let wh = distribution.sample_wh(wo, u);
                if wo.dot(wh).is_nan() || wo.dot(wh) <= 0.0 {
                    return None;
                }
                let eta = if cos_theta(wo) > 0.0 {
                    eta_a / eta_b
                } else {
                    eta_b / eta_a
                };
                let wi = refract(wo, wh, eta)?;
                LobeSample {
                    wi,
                    f: self.f(wo, wi),
                    pdf: self.pdf(wo, wi),
                    kind,
                }
            }
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
        };
        if s.pdf > 0.0 && s.pdf.is_finite() && s.f.is_finite() && s.wi.is_finite() {
            Some(s)
        } else {
            None
        }
    }

    /// Density with which [`Bxdf::sample_f`] picks local `wi` given `wo` (zero for specular
    /// lobes).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let p = match *self {
            Bxdf::Lambertian { .. } | Bxdf::OrenNayar { .. } => {
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
                distribution,
                eta_a,
                eta_b,
                ..
            } => {
                if same_hemisphere(wo, wi) {
                    return 0.0;
                }
                let eta = if cos_theta(wo) > 0.0 {
                    eta_b / eta_a
                } else {
                    eta_a / eta_b
                };
                let Some(wh) = (wo + wi * eta).try_normalize() else {
                    return 0.0;
                };
                if wo.dot(wh) * wi.dot(wh) > 0.0 {
                    return 0.0;
                }
                let sqrt_denom = wo.dot(wh) + eta * wi.dot(wh);
                let dwh_dwi = ((eta * eta * wi.dot(wh)) / (sqrt_denom * sqrt_denom)).abs();
                distribution.pdf(wo, wh) * dwh_dwi
            }
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
        };
        if p.is_finite() && p > 0.0 {
            p
        } else {
            0.0
        }
    }
}

/// The most lobes a BSDF holds (pbrt-v3's `MaxBxDFs`).
pub const MAX_LOBES: usize = 8;

/// A lobe with its RGB weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lobe {
    /// The BxDF.
    pub bxdf: Bxdf,
    /// Its weight (1 unless mixed).
    pub scale: Spectrum,
}

const EMPTY_LOBE: Lobe = Lobe {
    bxdf: Bxdf::Lambertian { r: Spectrum::ZERO },
    scale: Spectrum::ZERO,
};

/// A sampled direction from a [`Bsdf`], in world space.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Unit incident direction (world space), pointing away from the surface.
    pub wi: Vec3,
    /// BSDF value for (wo, wi).
    pub f: Spectrum,
    /// Density of `wi` (solid angle; for specular lobes, the discrete probability).
    pub pdf: f32,
    /// Whether a specular (delta) lobe was sampled.
    pub specular: bool,
}

/// pbrt-v3's BSDF: lobes in a shading frame, with the geometric normal and the relative index
/// of refraction (for Russian roulette's radiance scaling through refraction).
#[derive(Clone, Debug)]
pub struct Bsdf {
    frame: Frame,
    ng: Vec3,
    eta: f32,
    len: usize,
    lobes: [Lobe; MAX_LOBES],
}

impl Bsdf {
    /// An empty BSDF at `si`: shading frame from `si.shading_n` and `si.shading_dpdu`, geometric
    /// normal `si.n`, relative index `eta` (1 for surfaces that do not refract).
    // Inlined so that the (large) BSDF is built in place rather than copied out.
    #[inline]
    pub fn new(si: &SurfaceInteraction, eta: f32) -> Self {
        Self::from_frame(Frame::from_xz(si.shading_dpdu, si.shading_n), si.n, eta)
    }

    /// An empty BSDF with the given shading frame and geometric normal.
    #[inline]
    pub fn from_frame(frame: Frame, ng: Vec3, eta: f32) -> Self {
        Self {
            frame,
            ng,
            eta,
            len: 0,
            lobes: [EMPTY_LOBE; MAX_LOBES],
        }
    }

    /// Adds a lobe with weight 1; returns false (and adds nothing) when full.
    #[inline]
    pub fn add(&mut self, bxdf: Bxdf) -> bool {
        self.add_scaled(bxdf, Spectrum::ONE)
    }

    /// Adds a lobe with an RGB weight; returns false (and adds nothing) when full.
    #[inline]
    pub fn add_scaled(&mut self, bxdf: Bxdf, scale: Spectrum) -> bool {
        if self.len == MAX_LOBES {
            return false;
        }
        self.lobes[self.len] = Lobe { bxdf, scale };
        self.len += 1;
        true
    }

    /// Sets the relative index of refraction (inside over outside).
    #[inline]
    pub fn set_eta(&mut self, eta: f32) {
        self.eta = eta;
    }

    /// Multiplies every lobe's weight by `s`.
    pub fn scale_lobes(&mut self, s: Spectrum) {
        for l in &mut self.lobes[..self.len] {
            l.scale *= s;
        }
    }

    /// The lobes.
    pub fn lobes(&self) -> &[Lobe] {
        &self.lobes[..self.len]
    }

    /// Number of lobes.
    pub fn num_lobes(&self) -> usize {
        self.len
    }

    /// The relative index of refraction (inside over outside) of a refracting surface, else 1.
    pub fn eta(&self) -> f32 {
        self.eta
    }

    /// The shading frame.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The geometric normal.
    pub fn ng(&self) -> Vec3 {
        self.ng
    }

    /// The albedo for first-hit features: each lobe's nominal reflectance or transmittance
    /// (its `r`, `t`, or `rd + rs`) times its weight, summed and kept in [0, 1].
    pub fn albedo(&self) -> Spectrum {
        let sum: Spectrum = self
            .lobes()
            .iter()
            .map(|l| {
                let nominal = match l.bxdf {
                    Bxdf::Lambertian { r }
                    | Bxdf::OrenNayar { r, .. }
                    | Bxdf::SpecularReflection { r, .. }
                    | Bxdf::MicrofacetReflection { r, .. } => r,
                    Bxdf::SpecularTransmission { t, .. }
                    | Bxdf::LambertianTransmission { t }
                    | Bxdf::MicrofacetTransmission { t, .. } => t,
                    Bxdf::FresnelSpecular { r, t, .. } => r.max(t),
                    Bxdf::FresnelBlend { rd, rs, .. } => rd + rs,
                    Bxdf::Hair(h) => h.albedo(),
                    Bxdf::Disney(d) => d.albedo(),
                };
                nominal * l.scale
            })
            .sum();
        sum.clamp(Spectrum::ZERO, Spectrum::ONE)
    }

    /// Whether any lobe is not a delta distribution (so light sampling can help).
    pub fn has_non_specular(&self) -> bool {
        self.lobes().iter().any(|l| !l.bxdf.is_specular())
    }

    /// The BSDF for world directions `wo` and `wi` (both pointing away from the surface):
    /// reflection lobes when both are on the same side of the geometric normal, transmission
    /// lobes otherwise.
    pub fn f(&self, wo_world: Vec3, wi_world: Vec3) -> Spectrum {
        let wo = self.frame.to_local(wo_world);
        let wi = self.frame.to_local(wi_world);
        if wo.z == 0.0 {
            return Spectrum::ZERO;
        }
        let reflect = wi_world.dot(self.ng) * wo_world.dot(self.ng) > 0.0;
        let f = self.sum_f(wo, wi, reflect);
        if f.is_finite() {
            f
        } else {
            Spectrum::ZERO
        }
    }

    fn sum_f(&self, wo: Vec3, wi: Vec3, reflect: bool) -> Spectrum {
        let wanted = if reflect {
            BxdfType::REFLECTION
        } else {
            BxdfType::TRANSMISSION
        };
        self.lobes()
            .iter()
            .filter(|l| l.bxdf.kind().contains(wanted))
            .map(|l| l.scale * l.bxdf.f(wo, wi))
            .sum()
    }

    /// Samples an incident direction: a lobe chosen uniformly with `u_lobe`, then sampled with
    /// `u`. For a non-specular lobe, the value and density are those of the whole BSDF (the
    /// other lobes' values added, the densities averaged), as in pbrt-v3's `BSDF::Sample_f`.
    /// `None` when nothing can be sampled.
    pub fn sample_f(&self, wo_world: Vec3, u: Vec2, u_lobe: f32) -> Option<BsdfSample> {
        let n = self.len;
        if n == 0 {
            return None;
        }
        let comp = ((u_lobe * n as f32) as usize).min(n - 1);
        let wo = self.frame.to_local(wo_world);
        if wo.z == 0.0 {
            return None;
        }
        let lobe = &self.lobes[comp];
        let s = lobe.bxdf.sample_f(wo, u)?;
        let wi_world = self.frame.from_local(s.wi);
        let specular = s.kind.contains(BxdfType::SPECULAR);
        let mut pdf = s.pdf;
        let mut f = lobe.scale * s.f;
        if !specular {
            for (i, other) in self.lobes().iter().enumerate() {
                if i != comp {
                    pdf += other.bxdf.pdf(wo, s.wi);
                }
            }
            // As pbrt-v3, with one lobe too: a direction on the other side of the geometric
            // surface than a reflection lobe allows gives nothing (it applied only with several
            // lobes, so a bumped or smooth-shaded matte lit the sky below its surface: +0.45%
            // on scenes/pbrt-v3/bump-map.pbrt's floor under the sky alone).
            let reflect = wi_world.dot(self.ng) * wo_world.dot(self.ng) > 0.0;
            f = self.sum_f(wo, s.wi, reflect);
        }
        if n > 1 {
            pdf /= n as f32;
        }
        if !pdf.is_finite() || pdf <= 0.0 || !f.is_finite() || !wi_world.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi: wi_world,
            f,
            pdf,
            specular,
        })
    }

    /// Density with which [`Bsdf::sample_f`] picks world direction `wi` given `wo` (specular
    /// lobes count as zero).
    pub fn pdf(&self, wo_world: Vec3, wi_world: Vec3) -> f32 {
        let n = self.len;
        if n == 0 {
            return 0.0;
        }
        let wo = self.frame.to_local(wo_world);
        let wi = self.frame.to_local(wi_world);
        if wo.z == 0.0 {
            return 0.0;
        }
        let sum: f32 = self.lobes().iter().map(|l| l.bxdf.pdf(wo, wi)).sum();
        let p = sum / n as f32;
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }
}

/// Test helpers shared with the material tests: a deterministic generator and Monte Carlo
/// checks of a BSDF's sampling against its evaluation.
#[cfg(test)]
pub(crate) mod check {
    use super::*;
    use crate::sampling::uniform_sample_sphere;

    /// A small deterministic generator (PCG32).
    pub struct Rng(u64);

    impl Rng {
        pub fn new(seed: u64) -> Self {
            let mut r = Self(
                seed.wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407),
            );
            r.next_u32();
            r
        }

        pub fn next_u32(&mut self) -> u32 {
            let old = self.0;
            self.0 = old
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
            let rot = (old >> 59) as u32;
            xorshifted.rotate_right(rot)
        }

        pub fn next_f32(&mut self) -> f32 {
            (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
        }

        pub fn next_2d(&mut self) -> Vec2 {
            Vec2::new(self.next_f32(), self.next_f32())
        }
    }

    fn close(a: f32, b: f32, rel: f32) -> bool {
        (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-6
    }

    /// Sampled pdf equals `pdf()`, sampled f equals `f()`.
    pub fn sample_matches_eval(bsdf: &Bsdf, wo: Vec3, n: usize, seed: u64) {
        let mut rng = Rng::new(seed);
        let mut checked = 0;
        for _ in 0..n {
            let (u, ul) = (rng.next_2d(), rng.next_f32());
            let Some(s) = bsdf.sample_f(wo, u, ul) else {
                continue;
            };
            assert!(s.pdf > 0.0 && s.f.is_finite() && s.f.min_element() >= 0.0);
            assert!((s.wi.length() - 1.0).abs() < 1e-3, "{}", s.wi);
            if s.specular {
                continue;
            }
            let p = bsdf.pdf(wo, s.wi);
            assert!(
                close(s.pdf, p, 2e-3),
                "wo {wo} wi {}: sampled pdf {} vs pdf {p}",
                s.wi,
                s.pdf
            );
            let f = bsdf.f(wo, s.wi);
            for c in 0..3 {
                assert!(
                    close(s.f[c], f[c], 2e-3),
                    "wo {wo} wi {}: sampled f {} vs f {f}",
                    s.wi,
                    s.f
                );
            }
            checked += 1;
        }
        assert!(checked > 0 || !bsdf.has_non_specular());
    }

    /// ∫ pdf over the sphere (jittered uniform directions) with its standard error (that of
    /// independent samples: an overestimate for stratified ones), and the fraction of sampling
    /// attempts that succeed (which the integral should equal).
    pub fn pdf_integral(bsdf: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (f64, f64, f64) {
        let mut rng = Rng::new(seed);
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        let four_pi = 4.0 * std::f64::consts::PI;
        for j in 0..n {
            for i in 0..n {
                let u = Vec2::new(
                    (i as f32 + rng.next_f32()) / n as f32,
                    (j as f32 + rng.next_f32()) / n as f32,
                );
                let v = bsdf.pdf(wo, uniform_sample_sphere(u)) as f64 * four_pi;
                sum += v;
                sum2 += v * v;
            }
        }
        let trials = (n * n) as f64;
        let integral = sum / trials;
        let se = ((sum2 / trials - integral * integral).max(0.0) / trials).sqrt();
        let ok = (0..n * n)
            .filter(|_| {
                let (u, ul) = (rng.next_2d(), rng.next_f32());
                bsdf.sample_f(wo, u, ul).is_some_and(|s| !s.specular)
            })
            .count();
        (integral, se, ok as f64 / trials)
    }

    /// Directional albedo E[f |cos| / pdf] per channel and its standard error (max channel).
    pub fn albedo(bsdf: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (Spectrum, f32) {
        let mut rng = Rng::new(seed);
        let ns = bsdf.frame().n;
        let mut sum = [0.0f64; 3];
        let mut sum2 = [0.0f64; 3];
        for _ in 0..n {
            let (u, ul) = (rng.next_2d(), rng.next_f32());
            if let Some(s) = bsdf.sample_f(wo, u, ul) {
                let w = s.f * s.wi.dot(ns).abs() / s.pdf;
                for c in 0..3 {
                    sum[c] += w[c] as f64;
                    sum2[c] += (w[c] as f64) * (w[c] as f64);
                }
            }
        }
        let mean = sum.map(|s| s / n as f64);
        let mut se = 0.0f64;
        for c in 0..3 {
            let var = (sum2[c] / n as f64 - mean[c] * mean[c]).max(0.0);
            se = se.max((var / n as f64).sqrt());
        }
        (
            Spectrum::new(mean[0] as f32, mean[1] as f32, mean[2] as f32),
            se as f32,
        )
    }

    /// Directions to test from: normal, oblique, grazing, and from below.
    pub fn test_directions() -> [Vec3; 4] {
        [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.5, -0.3, 0.8).normalize(),
            Vec3::new(0.95, 0.2, 0.12).normalize(),
            Vec3::new(-0.4, 0.2, -0.7).normalize(),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::check::*;
    use super::*;

    fn local_bsdf(bxdfs: &[Bxdf], eta: f32) -> Bsdf {
        let mut b = Bsdf::from_frame(Frame::from_z(Vec3::Z), Vec3::Z, eta);
        for &x in bxdfs {
            assert!(b.add(x));
        }
        b
    }

    fn ggx(ax: f32, ay: f32) -> TrowbridgeReitz {
        TrowbridgeReitz::new(ax, ay)
    }

    /// Every non-specular lobe with typical, white parameters.
    fn non_specular_lobes() -> Vec<(&'static str, Bxdf)> {
        let conductor = Fresnel::Conductor {
            eta_i: Spectrum::ONE,
            eta_t: Spectrum::new(0.200438, 0.924033, 1.10221),
            k: Spectrum::new(3.91295, 2.45285, 2.14219),
        };
        vec![
            ("lambertian", Bxdf::Lambertian { r: Spectrum::ONE }),
            ("oren-nayar", Bxdf::oren_nayar(Spectrum::ONE, 20.0)),
            (
                "microfacet-dielectric",
                Bxdf::MicrofacetReflection {
                    r: Spectrum::ONE,
                    distribution: ggx(0.3, 0.3),
                    fresnel: Fresnel::Dielectric {
                        eta_i: 1.0,
                        eta_t: 1.5,
                    },
                },
            ),
            (
                "microfacet-conductor-aniso",
                Bxdf::MicrofacetReflection {
                    r: Spectrum::ONE,
                    distribution: ggx(0.2, 0.6),
                    fresnel: conductor,
                },
            ),
            (
                "microfacet-noop-rough",
                Bxdf::MicrofacetReflection {
                    r: Spectrum::ONE,
                    distribution: ggx(0.8, 0.8),
                    fresnel: Fresnel::NoOp,
                },
            ),
            (
                "microfacet-transmission",
                Bxdf::MicrofacetTransmission {
                    t: Spectrum::ONE,
                    distribution: ggx(0.3, 0.4),
                    eta_a: 1.0,
                    eta_b: 1.5,
                },
            ),
            (
                "fresnel-blend",
                Bxdf::FresnelBlend {
                    rd: Spectrum::ONE,
                    rs: Spectrum::splat(0.04),
                    distribution: ggx(0.25, 0.25),
                },
            ),
            (
                "lambertian transmission",
                Bxdf::LambertianTransmission { t: Spectrum::ONE },
            ),
            (
                "hair",
                Bxdf::Hair(crate::hair::HairBsdf::new(
                    0.3,
                    1.55,
                    Spectrum::ZERO,
                    0.3,
                    0.3,
                    2.0,
                )),
            ),
        ]
    }

    #[test]
    fn fresnel_dielectric_normal_incidence_and_tir() {
        for n in [1.33f32, 1.5, 2.4] {
            let want = ((n - 1.0) / (n + 1.0)).powi(2);
            assert!((fr_dielectric(1.0, 1.0, n) - want).abs() < 1e-6);
            // From inside, at normal incidence: the same.
            assert!((fr_dielectric(-1.0, 1.0, n) - want).abs() < 1e-6);
            // Beyond the critical angle from inside: total internal reflection.
            let crit = (1.0 / n).asin();
            let cos = -(crit + 0.05).cos();
            assert_eq!(fr_dielectric(cos, 1.0, n), 1.0);
            // Just inside the critical angle: partial.
            assert!(fr_dielectric(-(crit - 0.05).cos(), 1.0, n) < 1.0);
        }
        // Grazing from outside reflects everything; matched indices reflect nothing.
        assert!((fr_dielectric(0.0, 1.0, 1.5) - 1.0).abs() < 1e-6);
        assert_eq!(fr_dielectric(0.7, 1.5, 1.5), 0.0);
    }

    #[test]
    fn fresnel_conductor_limits() {
        // k = 0 makes a conductor a dielectric.
        let r = fr_conductor(1.0, Spectrum::ONE, Spectrum::splat(1.5), Spectrum::ZERO);
        assert!((r.x - 0.04).abs() < 1e-5, "{r}");
        let r = fr_conductor(0.6, Spectrum::ONE, Spectrum::splat(1.5), Spectrum::ZERO);
        assert!((r.x - fr_dielectric(0.6, 1.0, 1.5)).abs() < 1e-5, "{r}");
        // Copper at normal incidence: ((n-1)² + k²) / ((n+1)² + k²).
        let (n, k) = (0.2f32, 3.9f32);
        let want = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        let r = fr_conductor(1.0, Spectrum::ONE, Spectrum::splat(n), Spectrum::splat(k));
        assert!((r.x - want).abs() < 1e-4, "{r} {want}");
        // Grazing reflects everything.
        let r = fr_conductor(0.0, Spectrum::ONE, Spectrum::splat(n), Spectrum::splat(k));
        assert!((r.x - 1.0).abs() < 1e-4, "{r}");
    }

    #[test]
    fn refraction_obeys_snell() {
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let wt = refract(wo, Vec3::Z, 1.0 / 1.5).unwrap();
        assert!((wt.length() - 1.0).abs() < 1e-5);
        assert!(wt.z < 0.0);
        assert!((wt.x.abs() * 1.5 - 0.6).abs() < 1e-5, "{wt}");
        assert!(refract(Vec3::new(0.9, 0.0, 0.436), Vec3::Z, 1.5).is_none());
    }

    #[test]
    fn non_specular_sampling_matches_evaluation() {
        for (name, bxdf) in non_specular_lobes() {
            let b = local_bsdf(&[bxdf], 1.5);
            for (k, wo) in test_directions().into_iter().enumerate() {
                sample_matches_eval(&b, wo, 2000, 7 + k as u64);
                let _ = name;
            }
        }
        // And mixtures of lobes (the combined pdf and f).
        let lobes = non_specular_lobes();
        let b = local_bsdf(&[lobes[0].1, lobes[2].1, lobes[5].1], 1.5);
        for wo in test_directions() {
            sample_matches_eval(&b, wo, 2000, 3);
        }
    }

    #[test]
    fn pdfs_integrate_to_the_sampling_success_rate() {
        for (name, bxdf) in non_specular_lobes() {
            let b = local_bsdf(&[bxdf], 1.5);
            for (k, wo) in test_directions().into_iter().enumerate() {
                let (integral, se, success) = pdf_integral(&b, wo, 200, 11 + k as u64);
                // Monte Carlo error of both estimates, with a margin.
                let tol = 4.0 * se + 0.01;
                if matches!(bxdf, Bxdf::MicrofacetTransmission { .. }) && wo.z.abs() < 0.2 {
                    // pbrt-v3's transmission pdf also counts microfacets that face away from a
                    // grazing wo, which its sampler never picks: a few percent too much.
                    assert!(
                        integral < 1.1 && integral + tol > success,
                        "{name} {wo}: {integral}"
                    );
                    continue;
                }
                assert!(
                    integral <= 1.0 + tol,
                    "{name} {wo}: ∫pdf = {integral} ± {se}"
                );
                assert!(
                    (integral - success).abs() < tol,
                    "{name} {wo}: ∫pdf = {integral} ± {se}, success rate {success}"
                );
                if matches!(bxdf, Bxdf::Lambertian { .. } | Bxdf::OrenNayar { .. }) {
                    assert!((integral - 1.0).abs() < 0.01, "{name} {wo}: {integral}");
                }
            }
        }
    }

    #[test]
    fn white_lobes_conserve_energy() {
        for (name, bxdf) in non_specular_lobes() {
            let b = local_bsdf(&[bxdf], 1.5);
            for (k, wo) in test_directions().into_iter().enumerate() {
                if wo.z < 0.0 && bxdf.kind().contains(BxdfType::TRANSMISSION) {
                    // Leaving a denser medium, radiance grows by (eta_i / eta_t)²: not a loss.
                    continue;
                }
                let (a, se) = albedo(&b, wo, 20_000, 5 + k as u64);
                assert!(
                    a.max_element() <= 1.0 + 3.0 * se + 1e-3,
                    "{name} {wo}: albedo {a} ± {se}"
                );
            }
        }
        // Lambertian white reflects everything.
        let b = local_bsdf(&[Bxdf::Lambertian { r: Spectrum::ONE }], 1.0);
        let (a, _) = albedo(&b, Vec3::new(0.3, 0.1, 0.9).normalize(), 1000, 1);
        assert!((a - Spectrum::ONE).abs().max_element() < 1e-4, "{a}");
    }

    #[test]
    fn reflection_lobes_are_reciprocal() {
        let mut rng = Rng::new(99);
        for (name, bxdf) in non_specular_lobes() {
            if bxdf.kind().contains(BxdfType::TRANSMISSION) {
                continue;
            }
            for _ in 0..500 {
                let a = crate::sampling::cosine_sample_hemisphere(rng.next_2d());
                let b = crate::sampling::cosine_sample_hemisphere(rng.next_2d());
                if a.z < 1e-3 || b.z < 1e-3 {
                    continue;
                }
                let (fab, fba) = (bxdf.f(a, b), bxdf.f(b, a));
                for c in 0..3 {
                    assert!(
                        (fab[c] - fba[c]).abs() <= 1e-4 * fab[c].abs().max(1.0),
                        "{name}: f({a},{b}) = {fab} vs {fba}"
                    );
                }
            }
        }
    }

    #[test]
    fn fresnel_specular_chooses_by_fresnel_and_weights_correctly() {
        let (eta_a, eta_b) = (1.0f32, 1.5f32);
        let r = Spectrum::new(1.0, 0.8, 0.6);
        let t = Spectrum::new(0.5, 0.7, 0.9);
        let lobe = Bxdf::FresnelSpecular { r, t, eta_a, eta_b };
        for wo in test_directions() {
            let fr = fr_dielectric(wo.z, eta_a, eta_b);
            let n = 10_000;
            let (mut reflected, mut p_sum) = (0usize, 0.0f64);
            for i in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, 0.5);
                let s = lobe.sample_f(wo, u).unwrap();
                let w = s.f * s.wi.z.abs() / s.pdf;
                if s.kind.contains(BxdfType::REFLECTION) {
                    reflected += 1;
                    assert!((s.pdf - fr).abs() < 1e-6);
                    assert!((w - r).abs().max_element() < 1e-4, "{w}");
                    assert!(s.wi.z * wo.z > 0.0);
                } else {
                    assert!((s.pdf - (1.0 - fr)).abs() < 1e-6);
                    let (ei, et) = if wo.z > 0.0 {
                        (eta_a, eta_b)
                    } else {
                        (eta_b, eta_a)
                    };
                    assert!(
                        (w - t * (ei * ei) / (et * et)).abs().max_element() < 1e-4,
                        "{w}"
                    );
                    assert!(s.wi.z * wo.z < 0.0);
                }
                p_sum += s.pdf as f64;
            }
            // The two events' probabilities sum to one, and each is chosen that often.
            let frac = reflected as f64 / n as f64;
            assert!((frac - fr as f64).abs() < 2e-3, "{wo}: {frac} vs {fr}");
            let mean_p = p_sum / n as f64;
            let want = (fr * fr + (1.0 - fr) * (1.0 - fr)) as f64;
            assert!((mean_p - want).abs() < 2e-3);
        }
    }

    #[test]
    fn specular_lobes_sample_deltas() {
        let mirror = Bxdf::SpecularReflection {
            r: Spectrum::splat(0.9),
            fresnel: Fresnel::NoOp,
        };
        let b = local_bsdf(&[mirror], 1.0);
        let wo = Vec3::new(0.3, 0.4, 0.866).normalize();
        let s = b.sample_f(wo, Vec2::new(0.3, 0.6), 0.2).unwrap();
        assert!(s.specular && s.pdf == 1.0);
        assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
        assert!(
            (s.f * s.wi.z / s.pdf - Spectrum::splat(0.9))
                .abs()
                .max_element()
                < 1e-5
        );
        assert_eq!(b.f(wo, s.wi), Spectrum::ZERO);
        assert_eq!(b.pdf(wo, s.wi), 0.0);
        assert!(!b.has_non_specular());

        // Specular transmission scales radiance by (eta_i / eta_t)².
        let tr = Bxdf::SpecularTransmission {
            t: Spectrum::ONE,
            eta_a: 1.0,
            eta_b: 1.5,
        };
        let s = tr.sample_f(Vec3::Z, Vec2::ZERO).unwrap();
        let w = s.f * s.wi.z.abs() / s.pdf;
        assert!((w.x - (1.0 - 0.04) / 2.25).abs() < 1e-5, "{w}");
        assert!((s.wi + Vec3::Z).length() < 1e-6);
        // Total internal reflection from inside: nothing.
        assert!(tr
            .sample_f(Vec3::new(0.9, 0.0, -0.436).normalize(), Vec2::ZERO)
            .is_none());

        // Mixed with a diffuse lobe, the delta is chosen half the time with pdf 1/2.
        let b = local_bsdf(&[Bxdf::Lambertian { r: Spectrum::ONE }, mirror], 1.0);
        let s = b.sample_f(wo, Vec2::new(0.3, 0.6), 0.75).unwrap();
        assert!(s.specular && (s.pdf - 0.5).abs() < 1e-6);
        let s = b.sample_f(wo, Vec2::new(0.3, 0.6), 0.25).unwrap();
        assert!(!s.specular);
        assert!((s.pdf - 0.5 * s.wi.z * FRAC_1_PI).abs() < 1e-6);
        assert!(b.has_non_specular());
    }

    #[test]
    fn geometric_normal_decides_reflection() {
        // Shading normal tilted from the geometric one: a direction above the shading
        // hemisphere but below the geometric one is treated as transmission.
        let ns = Vec3::new(0.3, 0.0, 1.0).normalize();
        let mut b = Bsdf::from_frame(Frame::from_z(ns), Vec3::Z, 1.0);
        b.add(Bxdf::Lambertian { r: Spectrum::ONE });
        let wo = Vec3::new(0.0, 0.0, 1.0);
        let wi = Vec3::new(0.99, 0.0, -0.1).normalize();
        assert!(wi.dot(ns) > 0.0);
        assert_eq!(b.f(wo, wi), Spectrum::ZERO);
        assert!(b.pdf(wo, wi) > 0.0);
    }

    #[test]
    fn degenerate_inputs_give_no_nan() {
        let mut all: Vec<Bxdf> = non_specular_lobes().into_iter().map(|(_, b)| b).collect();
        all.push(Bxdf::FresnelSpecular {
            r: Spectrum::ONE,
            t: Spectrum::ONE,
            eta_a: 1.0,
            eta_b: 1.5,
        });
        all.push(Bxdf::SpecularTransmission {
            t: Spectrum::ONE,
            eta_a: 1.0,
            eta_b: 1.5,
        });
        all.push(Bxdf::MicrofacetReflection {
            r: Spectrum::ONE,
            distribution: TrowbridgeReitz::new(0.0, 0.0),
            fresnel: Fresnel::NoOp,
        });
        let dirs = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1.0, 0.0, 1e-7).normalize(),
            Vec3::new(0.0, 1.0, -1e-7).normalize(),
            Vec3::ZERO,
        ];
        let us = [Vec2::ZERO, Vec2::splat(0.5), Vec2::splat(ONE_MINUS_EPSILON)];
        for bxdf in all {
            let b = local_bsdf(&[bxdf], 1.5);
            for wo in dirs {
                for wi in dirs {
                    assert!(b.f(wo, wi).is_finite(), "{bxdf:?} {wo} {wi}");
                    assert!(b.pdf(wo, wi).is_finite(), "{bxdf:?} {wo} {wi}");
                }
                for u in us {
                    if let Some(s) = b.sample_f(wo, u, 0.5) {
                        assert!(s.f.is_finite() && s.pdf.is_finite() && s.wi.is_finite());
                        assert!(s.pdf > 0.0);
                    }
                }
            }
        }
        let empty = local_bsdf(&[], 1.0);
        assert!(empty.sample_f(Vec3::Z, Vec2::splat(0.5), 0.5).is_none());
        assert_eq!(empty.pdf(Vec3::Z, Vec3::Z), 0.0);
        assert_eq!(empty.f(Vec3::Z, Vec3::Z), Spectrum::ZERO);
    }

    #[test]
    fn at_most_eight_lobes() {
        let mut b = local_bsdf(&[], 1.0);
        for _ in 0..MAX_LOBES {
            assert!(b.add(Bxdf::Lambertian { r: Spectrum::ONE }));
        }
        assert!(!b.add(Bxdf::Lambertian { r: Spectrum::ONE }));
        assert_eq!(b.num_lobes(), MAX_LOBES);
        b.scale_lobes(Spectrum::splat(0.5));
        assert!(b.lobes().iter().all(|l| l.scale == Spectrum::splat(0.5)));
    }

    #[test]
    fn world_frame_follows_the_shading_tangent() {
        let si = SurfaceInteraction {
            p: Vec3::ZERO,
            n: Vec3::Y,
            uv: Vec2::ZERO,
            dpdu: Vec3::X,
            dpdv: Vec3::Z,
            shading_n: Vec3::Y,
            shading_dpdu: Vec3::X,
            shading_dpdv: Vec3::Y,
            dndu: Vec3::ZERO,
            dndv: Vec3::ZERO,
            wo: Vec3::Y,
            time: 0.0,
            p_error: 0.0,
        };
        let b = Bsdf::new(&si, 1.0);
        assert!((b.frame().n - Vec3::Y).length() < 1e-6);
        assert!((b.frame().s - Vec3::X).length() < 1e-6);
        // Anisotropic roughness follows the tangent: a highlight stretched along dpdu.
        let mut b = Bsdf::new(&si, 1.0);
        b.add(Bxdf::MicrofacetReflection {
            r: Spectrum::ONE,
            distribution: TrowbridgeReitz::new(0.5, 0.05),
            fresnel: Fresnel::NoOp,
        });
        let wo = Vec3::Y;
        let along_u = b.f(wo, Vec3::new(0.2, 1.0, 0.0).normalize());
        let along_v = b.f(wo, Vec3::new(0.0, 1.0, 0.2).normalize());
        assert!(along_u.x > 10.0 * along_v.x, "{along_u} {along_v}");
    }
}
