//! pbrt-v3's `HomogeneousMedium` (src/media/homogeneous.cpp): constant coefficients, so the
//! transmittance is exponential and distances are sampled exactly (one channel chosen at
//! random, the densities of all three averaged, as pbrt-v3's spectral MIS).

use super::MediumSample;
use crate::geometry::Spectrum;

/// A medium of constant absorption and scattering.
#[derive(Clone, Debug, PartialEq)]
pub struct Homogeneous {
    /// Absorption coefficient per unit distance.
    pub sigma_a: Spectrum,
    /// Scattering coefficient per unit distance.
    pub sigma_s: Spectrum,
    /// sigma_a + sigma_s.
    pub sigma_t: Spectrum,
}

/// exp(-sigma_t * dist) per channel, where a zero coefficient leaves light whole over any
/// distance (pbrt-v3 clamps the distance to the largest float, so 0 * it stays 0).
#[inline]
fn attenuation(sigma_t: Spectrum, dist: f32) -> Spectrum {
    let e = |s: f32| if s == 0.0 { 1.0 } else { (-s * dist).exp() };
    Spectrum::new(e(sigma_t.x), e(sigma_t.y), e(sigma_t.z))
}

impl Homogeneous {
    /// The medium of coefficients `sigma_a` and `sigma_s`.
    pub fn new(sigma_a: Spectrum, sigma_s: Spectrum) -> Self {
        Self {
            sigma_a,
            sigma_s,
            sigma_t: sigma_a + sigma_s,
        }
    }

    /// Transmittance over `dist` (which may be infinite).
    #[inline]
    pub fn tr(&self, dist: f32) -> Spectrum {
        attenuation(self.sigma_t, dist)
    }

    /// pbrt-v3's `HomogeneousMedium::Sample` along a ray of direction length `len_d` that ends
    /// at parameter `t_max` (infinite when it escapes); two numbers from `u`.
    pub fn sample(&self, len_d: f32, t_max: f32, u: &mut impl FnMut() -> f32) -> MediumSample {
        let channel = ((u() * 3.0) as usize).min(2);
        let s = self.sigma_t[channel];
        let xi = u();
        let dist = if s > 0.0 {
            -(1.0 - xi).ln() / s
        } else {
            f32::INFINITY
        };
        let t = (dist / len_d).min(t_max);
        let sampled = t < t_max;
        let tr = attenuation(self.sigma_t, t * len_d);
        let density = if sampled { self.sigma_t * tr } else { tr };
        let mut pdf = (density.x + density.y + density.z) / 3.0;
        if pdf == 0.0 {
            pdf = 1.0;
        }
        if sampled {
            MediumSample {
                weight: tr * self.sigma_s / pdf,
                t: Some(t),
            }
        } else {
            MediumSample {
                weight: tr / pdf,
                t: None,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The estimator's expectation over many samples: the fraction of paths that pass a slab
    /// of optical depth tau, weighted, is exp(-tau) per channel; and scattering events
    /// weighted sum to sigma_s / sigma_t * (1 - exp(-tau)) (the single-scatter share).
    #[test]
    fn sampling_is_unbiased_per_channel() {
        let m = Homogeneous::new(Spectrum::new(0.1, 0.5, 1.0), Spectrum::new(0.4, 0.5, 1.0));
        let t_max = 1.3;
        let n = 200_000;
        let mut state = 12345u64;
        let mut u = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        let (mut pass, mut scatter) = (Spectrum::ZERO, Spectrum::ZERO);
        for _ in 0..n {
            let s = m.sample(1.0, t_max, &mut u);
            match s.t {
                Some(_) => scatter += s.weight,
                None => pass += s.weight,
            }
        }
        pass /= n as f32;
        scatter /= n as f32;
        let tr = m.tr(t_max);
        let single = m.sigma_s / m.sigma_t * (Spectrum::ONE - tr);
        for c in 0..3 {
            assert!((pass[c] - tr[c]).abs() < 0.01, "{pass} {tr}");
            assert!((scatter[c] - single[c]).abs() < 0.01, "{scatter} {single}");
        }
        // Vacuum channels and infinite rays stay finite.
        let v = Homogeneous::new(Spectrum::new(0.0, 1.0, 0.0), Spectrum::ZERO);
        let s = v.sample(1.0, f32::INFINITY, &mut u);
        assert!(s.weight.is_finite());
        assert_eq!(v.tr(f32::INFINITY), Spectrum::new(1.0, 0.0, 1.0));
    }
}
