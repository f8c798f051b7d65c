//! The Henyey-Greenstein phase function, as pbrt-v3's `HenyeyGreenstein` (src/core/medium.cpp):
//! `wo` and `wi` both point away from the scattering point, so `g > 0` scatters forward.

use crate::geometry::{Vec2, Vec3};

/// 1 / (4 pi).
const INV_4PI: f32 = 0.25 * std::f32::consts::FRAC_1_PI;

/// pbrt-v3's `PhaseHG`: the density of scattering by an angle whose cosine (between `wo` and
/// `wi`, both pointing away) is `cos_theta`.
#[inline]
pub fn phase_hg(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g + 2.0 * g * cos_theta;
    INV_4PI * (1.0 - g * g) / (denom * denom.max(0.0).sqrt())
}

/// A Henyey-Greenstein phase function of asymmetry `g` in (-1, 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenyeyGreenstein {
    /// Mean cosine of the scattering angle.
    pub g: f32,
}

impl HenyeyGreenstein {
    /// The phase function's value (and density) for `wo` and `wi`.
    #[inline]
    pub fn p(&self, wo: Vec3, wi: Vec3) -> f32 {
        phase_hg(wo.dot(wi), self.g)
    }

    /// Samples `wi` for `wo` with `u`: the direction and its density (which equals `p`, so
    /// the sample's weight is one).
    #[inline]
    pub fn sample_p(&self, wo: Vec3, u: Vec2) -> (Vec3, f32) {
        let g = self.g;
        let cos_theta = if g.abs() < 1e-3 {
            1.0 - 2.0 * u.x
        } else {
            let sqr = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
            -(1.0 + g * g - sqr * sqr) / (2.0 * g)
        };
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * u.y;
        let (v1, v2) = coordinate_system(wo);
        let wi = sin_theta * phi.cos() * v1 + sin_theta * phi.sin() * v2 + cos_theta * wo;
        (wi, phase_hg(cos_theta, g))
    }
}

/// pbrt-v3's `CoordinateSystem`: two unit vectors perpendicular to unit `v` and each other.
fn coordinate_system(v: Vec3) -> (Vec3, Vec3) {
    let v2 = if v.x.abs() > v.y.abs() {
        Vec3::new(-v.z, 0.0, v.x) / (v.x * v.x + v.z * v.z).sqrt()
    } else {
        Vec3::new(0.0, v.z, -v.y) / (v.y * v.y + v.z * v.z).sqrt()
    };
    (v2, v.cross(v2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The phase function integrates to one over the sphere, and its mean cosine (between the
    /// forward direction -wo and wi) is g.
    #[test]
    fn integrates_to_one_with_mean_cosine_g() {
        for g in [-0.7f32, 0.0, 0.3, 0.9] {
            let hg = HenyeyGreenstein { g };
            let wo = Vec3::new(0.0, 0.0, 1.0);
            let n = 20_000;
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let cos = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
                let p = phase_hg(cos, g) as f64;
                // dω = 2π dcos over the band.
                total += p * 2.0 * std::f64::consts::PI * 2.0 / n as f64;
                mean += -(cos as f64) * p * 2.0 * std::f64::consts::PI * 2.0 / n as f64;
            }
            assert!((total - 1.0).abs() < 2e-3, "g {g}: {total}");
            assert!((mean - g as f64).abs() < 5e-3, "g {g}: {mean}");
            // Sampled directions' mean cosine is g too, and each sample's density is p.
            let m = 64;
            let mut sampled = 0.0f64;
            for a in 0..m {
                for b in 0..m {
                    let u = Vec2::new((a as f32 + 0.5) / m as f32, (b as f32 + 0.5) / m as f32);
                    let (wi, pdf) = hg.sample_p(wo, u);
                    assert!((wi.length() - 1.0).abs() < 1e-4);
                    assert!((pdf - hg.p(wo, wi)).abs() < 1e-3 * pdf.max(1.0));
                    sampled += -wi.dot(wo) as f64;
                }
            }
            sampled /= (m * m) as f64;
            assert!(
                (sampled - g as f64).abs() < 1e-2,
                "g {g}: sampled {sampled}"
            );
        }
    }
}
