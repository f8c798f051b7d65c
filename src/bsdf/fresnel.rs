//! Fresnel terms and the mirror and refraction directions (pbrt-v3's `FrDielectric`,
//! `FrConductor`, `Fresnel*`, `Reflect`, `Refract`).

use crate::geometry::{Spectrum, Vec3};

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
