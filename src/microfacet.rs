//! pbrt-v3's Trowbridge-Reitz (GGX) microfacet distribution, with sampling of the visible normals
//! (pbrt-v3's default, `sampleVisibleArea = true`) and anisotropic roughness. Directions are in
//! the local shading frame: z is the normal.

use crate::geometry::{Vec2, Vec3};
use std::f32::consts::PI;

/// cos θ of a local direction.
#[inline]
pub fn cos_theta(w: Vec3) -> f32 {
    w.z
}

/// cos² θ.
#[inline]
pub fn cos2_theta(w: Vec3) -> f32 {
    w.z * w.z
}

/// |cos θ|.
#[inline]
pub fn abs_cos_theta(w: Vec3) -> f32 {
    w.z.abs()
}

/// sin² θ.
#[inline]
pub fn sin2_theta(w: Vec3) -> f32 {
    (1.0 - cos2_theta(w)).max(0.0)
}

/// sin θ.
#[inline]
pub fn sin_theta(w: Vec3) -> f32 {
    sin2_theta(w).sqrt()
}

/// tan θ.
#[inline]
pub fn tan_theta(w: Vec3) -> f32 {
    sin_theta(w) / cos_theta(w)
}

/// tan² θ.
#[inline]
pub fn tan2_theta(w: Vec3) -> f32 {
    sin2_theta(w) / cos2_theta(w)
}

/// cos φ.
#[inline]
pub fn cos_phi(w: Vec3) -> f32 {
    let s = sin_theta(w);
    if s == 0.0 {
        1.0
    } else {
        (w.x / s).clamp(-1.0, 1.0)
    }
}

/// sin φ.
#[inline]
pub fn sin_phi(w: Vec3) -> f32 {
    let s = sin_theta(w);
    if s == 0.0 {
        0.0
    } else {
        (w.y / s).clamp(-1.0, 1.0)
    }
}

/// cos² φ.
#[inline]
pub fn cos2_phi(w: Vec3) -> f32 {
    cos_phi(w) * cos_phi(w)
}

/// sin² φ.
#[inline]
pub fn sin2_phi(w: Vec3) -> f32 {
    sin_phi(w) * sin_phi(w)
}

/// Whether two local directions are on the same side of the surface.
#[inline]
pub fn same_hemisphere(w: Vec3, wp: Vec3) -> bool {
    w.z * wp.z > 0.0
}

/// pbrt-v3's `TrowbridgeReitzDistribution::RoughnessToAlpha`: a user-friendly roughness in [0, 1]
/// to the distribution's alpha (a fit; roughness is clamped below at 1e-3).
#[inline]
pub fn roughness_to_alpha(roughness: f32) -> f32 {
    let x = roughness.max(1e-3).ln();
    1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x
}

/// The smallest alpha used: pbrt-v3 would divide by zero for alpha = 0 (possible with
/// `remaproughness false` and roughness 0); acr makes such a lobe a very sharp one instead.
pub const MIN_ALPHA: f32 = 1e-4;

/// The Trowbridge-Reitz distribution of microfacet normals with roughness `alpha_x` along the
/// shading tangent and `alpha_y` along the bitangent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrowbridgeReitz {
    /// Roughness along local x.
    pub alpha_x: f32,
    /// Roughness along local y.
    pub alpha_y: f32,
}

impl TrowbridgeReitz {
    /// A distribution with the given alphas (not remapped; at least [`MIN_ALPHA`]).
    pub fn new(alpha_x: f32, alpha_y: f32) -> Self {
        let fix = |a: f32| if a.is_finite() { a.max(MIN_ALPHA) } else { 1.0 };
        Self {
            alpha_x: fix(alpha_x),
            alpha_y: fix(alpha_y),
        }
    }

    /// Density of microfacet normals `wh` (projected: ∫ D(wh) cos θh dωh = 1).
    pub fn d(&self, wh: Vec3) -> f32 {
        let tan2 = tan2_theta(wh);
        if !tan2.is_finite() {
            return 0.0;
        }
        let cos4 = cos2_theta(wh) * cos2_theta(wh);
        let e = (cos2_phi(wh) / (self.alpha_x * self.alpha_x)
            + sin2_phi(wh) / (self.alpha_y * self.alpha_y))
            * tan2;
        1.0 / (PI * self.alpha_x * self.alpha_y * cos4 * (1.0 + e) * (1.0 + e))
    }

    /// Smith's Λ for direction `w`.
    pub fn lambda(&self, w: Vec3) -> f32 {
        let abs_tan = tan_theta(w).abs();
        if !abs_tan.is_finite() {
            return 0.0;
        }
        let alpha = (cos2_phi(w) * self.alpha_x * self.alpha_x
            + sin2_phi(w) * self.alpha_y * self.alpha_y)
            .sqrt();
        let a2t2 = (alpha * abs_tan) * (alpha * abs_tan);
        (-1.0 + (1.0 + a2t2).sqrt()) / 2.0
    }

    /// Masking for one direction.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Masking-shadowing for a pair of directions.
    #[inline]
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Samples a microfacet normal visible from `wo` (on `wo`'s side of the surface).
    pub fn sample_wh(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let flip = wo.z < 0.0;
        let wh = tr_sample(
            if flip { -wo } else { wo },
            self.alpha_x,
            self.alpha_y,
            u.x,
            u.y,
        );
        if flip {
            -wh
        } else {
            wh
        }
    }

    /// Density of [`TrowbridgeReitz::sample_wh`] choosing `wh` given `wo`.
    pub fn pdf(&self, wo: Vec3, wh: Vec3) -> f32 {
        self.d(wh) * self.g1(wo) * wo.dot(wh).abs() / abs_cos_theta(wo)
    }
}

/// pbrt-v3's `TrowbridgeReitzSample11`: slopes of a visible normal for alpha = 1 and a view at
/// `cos_theta` from the normal.
fn tr_sample11(cos_theta: f32, u1: f32, u2: f32) -> (f32, f32) {
    // Normal incidence: a special case.
    if cos_theta > 0.9999 {
        let r = (u1 / (1.0 - u1)).sqrt();
        let phi = 2.0 * PI * u2;
        return (r * phi.cos(), r * phi.sin());
    }
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let tan_theta = sin_theta / cos_theta;
    let a = 1.0 / tan_theta;
    let g1 = 2.0 / (1.0 + (1.0 + 1.0 / (a * a)).sqrt());

    // Sample slope x.
    let aa = 2.0 * u1 / g1 - 1.0;
    let mut tmp = 1.0 / (aa * aa - 1.0);
    if tmp > 1e10 {
        tmp = 1e10;
    }
    let b = tan_theta;
    let d = (b * b * tmp * tmp - (aa * aa - b * b) * tmp)
        .max(0.0)
        .sqrt();
    let slope_x_1 = b * tmp - d;
    let slope_x_2 = b * tmp + d;
    let slope_x = if aa < 0.0 || slope_x_2 > 1.0 / tan_theta {
        slope_x_1
    } else {
        slope_x_2
    };

    // Sample slope y.
    let (s, u2) = if u2 > 0.5 {
        (1.0, 2.0 * (u2 - 0.5))
    } else {
        (-1.0, 2.0 * (0.5 - u2))
    };
    let z = (u2 * (u2 * (u2 * 0.27385 - 0.73369) + 0.46341))
        / (u2 * (u2 * (u2 * 0.093073 + 0.309420) - 1.000000) + 0.597999);
    let slope_y = s * z * (1.0 + slope_x * slope_x).sqrt();
    (slope_x, slope_y)
}

/// pbrt-v3's `TrowbridgeReitzSample`: stretch, sample slopes, rotate, unstretch.
fn tr_sample(wi: Vec3, alpha_x: f32, alpha_y: f32, u1: f32, u2: f32) -> Vec3 {
    let stretched = Vec3::new(alpha_x * wi.x, alpha_y * wi.y, wi.z).normalize();
    let (mut slope_x, mut slope_y) = tr_sample11(cos_theta(stretched), u1, u2);
    let (cp, sp) = (cos_phi(stretched), sin_phi(stretched));
    let tmp = cp * slope_x - sp * slope_y;
    slope_y = sp * slope_x + cp * slope_y;
    slope_x = tmp;
    slope_x *= alpha_x;
    slope_y *= alpha_y;
    Vec3::new(-slope_x, -slope_y, 1.0).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::uniform_sample_sphere;

    #[test]
    fn roughness_to_alpha_matches_pbrt() {
        // ln(0.1) = -2.302585: the polynomial gives about 0.4618 for plastic's default 0.1.
        assert!(
            (roughness_to_alpha(0.1) - 0.46176).abs() < 1e-3,
            "{}",
            roughness_to_alpha(0.1)
        );
        assert!((roughness_to_alpha(1.0) - 1.62142).abs() < 1e-5);
        assert!(roughness_to_alpha(0.0) > 0.0);
        assert_eq!(roughness_to_alpha(0.0), roughness_to_alpha(1e-3));
    }

    #[test]
    fn projected_d_integrates_to_one() {
        for (ax, ay) in [(0.5, 0.5), (0.3, 0.8), (1.0, 0.2)] {
            let dist = TrowbridgeReitz::new(ax, ay);
            let n = 400;
            let mut sum = 0.0f64;
            // Uniform over the upper hemisphere, stratified.
            for j in 0..n {
                for i in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    let w = uniform_sample_sphere(Vec2::new(u.x * 0.5, u.y));
                    sum += (dist.d(w) * w.z) as f64;
                }
            }
            let integral = sum / (n * n) as f64 * 2.0 * std::f64::consts::PI;
            assert!((integral - 1.0).abs() < 0.02, "{ax} {ay}: {integral}");
        }
    }

    #[test]
    fn sampled_normals_face_the_viewer_and_are_finite() {
        let dist = TrowbridgeReitz::new(0.3, 0.6);
        for wo in [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(0.0, -0.999, 0.0447),
            Vec3::new(0.3, 0.4, -0.866),
        ] {
            let wo = wo.normalize();
            for i in 0..64 {
                for j in 0..64 {
                    let u = Vec2::new((i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0);
                    let wh = dist.sample_wh(wo, u);
                    assert!(wh.is_finite() && (wh.length() - 1.0).abs() < 1e-4);
                    assert!(wh.z * wo.z > 0.0, "{wo} {wh}");
                    assert!(dist.pdf(wo, wh).is_finite());
                }
            }
        }
    }

    #[test]
    fn degenerate_alphas_stay_finite() {
        let dist = TrowbridgeReitz::new(0.0, f32::NAN);
        assert!(dist.alpha_x > 0.0 && dist.alpha_y > 0.0);
        assert!(dist.d(Vec3::Z).is_finite());
        assert_eq!(dist.d(Vec3::X), 0.0);
        assert_eq!(dist.lambda(Vec3::X), 0.0);
    }
}
