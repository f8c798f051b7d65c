//! What the lobes share, below them all: a lobe's kind and sample, and the microfacet steps
//! that pbrt-v3's own lobes ([`super::Bxdf`]) and the Disney ones ([`super::disney`]) both
//! take. A leaf: it reads only the Fresnel terms, the microfacet distribution and geometry.

use super::fresnel::{fr_dielectric, reflect, refract};
use crate::geometry::{Spectrum, Vec2, Vec3};
use crate::microfacet::{cos_theta, same_hemisphere, TrowbridgeReitz};

/// The largest u < 1 in f32 (pbrt-v3's `OneMinusEpsilon`).
pub(crate) const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

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

impl LobeSample {
    /// The sample, if its density is positive and it is all finite (else the lobe gives
    /// nothing).
    #[inline]
    pub(crate) fn valid(self) -> Option<Self> {
        if self.pdf > 0.0 && self.pdf.is_finite() && self.f.is_finite() && self.wi.is_finite() {
            Some(self)
        } else {
            None
        }
    }
}

/// A density kept where it is positive and finite, else zero.
#[inline]
pub(crate) fn finite_pdf(p: f32) -> f32 {
    if p.is_finite() && p > 0.0 {
        p
    } else {
        0.0
    }
}

/// Samples a microfacet normal of `distribution` for local `wo` and reflects `wo` about it
/// (pbrt-v3's `MicrofacetReflection::Sample_f`): the direction and its density, from the
/// sampled normal's (not recomputed from the direction). `None` when `wo` is grazing, the
/// normal faces away (pbrt-v3 gives up below 0; at 0 its density would divide by zero), or the
/// reflection leaves the hemisphere.
pub(crate) fn sample_microfacet_reflection(
    distribution: &TrowbridgeReitz,
    wo: Vec3,
    u: Vec2,
) -> Option<(Vec3, f32)> {
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
    Some((wi, distribution.pdf(wo, wh) / (4.0 * wo.dot(wh))))
}

/// pbrt-v3's generalised half vector of a refraction from local `wo` to `wi` across the
/// boundary between `eta_a` (the normal's side) and `eta_b`, faced to +z, with the relative
/// index eta it was made with; `None` when it is degenerate or `wo` and `wi` lie on the same
/// side of it (not a refraction). The transmission's value and density share it.
fn refraction_half_vector(wo: Vec3, wi: Vec3, eta_a: f32, eta_b: f32) -> Option<(Vec3, f32)> {
    let eta = if cos_theta(wo) > 0.0 {
        eta_b / eta_a
    } else {
        eta_a / eta_b
    };
    let wh = (wo + wi * eta).try_normalize()?;
    let wh = if wh.z < 0.0 { -wh } else { wh };
    if wo.dot(wh) * wi.dot(wh) > 0.0 {
        return None;
    }
    Some((wh, eta))
}

/// Walter et al.'s microfacet refraction through a dielectric (pbrt-v3's
/// `MicrofacetTransmission`): the lobe behind [`super::Bxdf::MicrofacetTransmission`], and the
/// Disney transmission's directions and density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MicrofacetTransmission {
    /// Transmittance scale.
    pub t: Spectrum,
    /// Microfacet distribution.
    pub distribution: TrowbridgeReitz,
    /// Index on the normal's side.
    pub eta_a: f32,
    /// Index on the other side.
    pub eta_b: f32,
}

impl MicrofacetTransmission {
    /// The kind: glossy transmission.
    pub const KIND: BxdfType = BxdfType::TRANSMISSION.or(BxdfType::GLOSSY);

    /// The lobe's value for local `wo` and `wi` (zero on the same side).
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Spectrum {
        let Self {
            t,
            distribution,
            eta_a,
            eta_b,
        } = *self;
        if same_hemisphere(wo, wi) {
            return Spectrum::ZERO;
        }
        let (cos_o, cos_i) = (cos_theta(wo), cos_theta(wi));
        if cos_i == 0.0 || cos_o == 0.0 {
            return Spectrum::ZERO;
        }
        let Some((wh, eta)) = refraction_half_vector(wo, wi, eta_a, eta_b) else {
            return Spectrum::ZERO;
        };
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

    /// Samples a refracted direction through a visible microfacet normal: the sample, or
    /// `None` when `wo` is grazing, the normal faces away, or the refraction is total internal
    /// reflection.
    pub fn sample_f(&self, wo: Vec3, u: Vec2) -> Option<LobeSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wh = self.distribution.sample_wh(wo, u);
        if wo.dot(wh).is_nan() || wo.dot(wh) <= 0.0 {
            return None;
        }
        let eta = if cos_theta(wo) > 0.0 {
            self.eta_a / self.eta_b
        } else {
            self.eta_b / self.eta_a
        };
        let wi = refract(wo, wh, eta)?;
        LobeSample {
            wi,
            f: self.f(wo, wi),
            pdf: self.pdf(wo, wi),
            kind: Self::KIND,
        }
        .valid()
    }

    /// Density with which [`Self::sample_f`] picks local `wi` given `wo`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if same_hemisphere(wo, wi) {
            return 0.0;
        }
        // The half vector faced to +z: the density is the same for either side.
        let Some((wh, eta)) = refraction_half_vector(wo, wi, self.eta_a, self.eta_b) else {
            return 0.0;
        };
        let sqrt_denom = wo.dot(wh) + eta * wi.dot(wh);
        let dwh_dwi = ((eta * eta * wi.dot(wh)) / (sqrt_denom * sqrt_denom)).abs();
        finite_pdf(self.distribution.pdf(wo, wh) * dwh_dwi)
    }
}
