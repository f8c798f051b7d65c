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
    /// pbrt-v3's tabulated `FourierBSDF` (the fourier material, `src/fourier.rs`).
    Fourier(crate::fourier::FourierBsdf),
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
            Bxdf::Fourier(_) => T::REFLECTION.or(T::TRANSMISSION).or(T::GLOSSY),
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
            Bxdf::Fourier(t) => t.f(wo, wi),
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
            Bxdf::Fourier(t) => {
                let (wi, f, pdf) = t.sample_f(wo, [u.x, u.y])?;
                LobeSample { wi, f, pdf, kind }
            }
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
            Bxdf::Fourier(t) => t.pdf(wo, wi),
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
                    Bxdf::Fourier(t) => t.table.albedo(),
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

    /// Samples specular lobe `index` alone, as pbrt-v3's `SpecularReflect` and
    /// `SpecularTransmit` ask `BSDF::Sample_f` for one type: its weighted value and its own
    /// probability. `None` for a lobe that is not specular or gives nothing.
    pub fn sample_specular_lobe(
        &self,
        wo_world: Vec3,
        u: Vec2,
        index: usize,
    ) -> Option<BsdfSample> {
        let lobe = self.lobes().get(index)?;
        if !lobe.bxdf.is_specular() {
            return None;
        }
        let wo = self.frame.to_local(wo_world);
        if wo.z == 0.0 {
            return None;
        }
        let s = lobe.bxdf.sample_f(wo, u)?;
        let wi = self.frame.from_local(s.wi);
        let f = lobe.scale * s.f;
        if !(s.pdf > 0.0 && s.pdf.is_finite() && f.is_finite() && wi.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi,
            f,
            pdf: s.pdf,
            specular: true,
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

#[cfg(test)]
pub(crate) mod check;

#[cfg(test)]
mod tests;
