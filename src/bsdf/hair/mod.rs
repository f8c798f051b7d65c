//! pbrt-v3's hair BSDF (materials/hair.{h,cpp}): Chiang et al.'s hair scattering model as
//! pbrt-v3 implements it ("The Implementation of a Hair Scattering Model", pbrt.org/hair.pdf),
//! [`HairBsdf`]. The material that builds it at a hit is [`crate::material::hair`].
//!
//! The lobe works in the BSDF's local frame as pbrt-v3's does: x along the hair (the curve's
//! dp/du, which the BSDF takes as its first axis), z the shading normal, so that
//! `w.x` is sin theta (the angle to the plane normal to the hair) and atan2(w.z, w.y) is phi
//! about the hair. The offset across the hair is h = -1 + 2 v, from the curve's v.
//!
//! The arithmetic follows pbrt-v3's single-precision code step by step (its double-precision
//! literals included) so that values match its own to a few ulps; where pbrt-v3 `CHECK`s and
//! aborts (h outside [-1, 1], beta outside [0, 1]), the inputs are clamped, and a NaN from a
//! degenerate direction is left for the BSDF to turn into zero.

use super::fresnel::fr_dielectric;
use crate::geometry::{Spectrum, Vec2, Vec3};
use std::f32::consts::PI;

/// pbrt-v3's `pMax`: the scattering orders modelled one by one (R, TT, TRT); the rest are
/// summed into one more term.
const P_MAX: usize = 3;
/// sqrt(pi / 8), pbrt-v3's `SqrtPiOver8`, its literal as written.
#[allow(clippy::excessive_precision)]
const SQRT_PI_OVER_8: f32 = 0.626657069;

#[inline]
fn sqr(v: f32) -> f32 {
    v * v
}

/// pbrt-v3's `Pow<n>`, with its order of multiplications (so that results round alike).
fn pow_n(v: f32, n: u32) -> f32 {
    match n {
        0 => 1.0,
        1 => v,
        _ => {
            let n2 = pow_n(v, n / 2);
            n2 * n2 * pow_n(v, n & 1)
        }
    }
}

/// asin with its argument clamped to [-1, 1] (pbrt-v3's `SafeASin`, without its check).
#[inline]
fn safe_asin(x: f32) -> f32 {
    x.clamp(-1.0, 1.0).asin()
}

/// sqrt of max(0, x) (pbrt-v3's `SafeSqrt`, without its check; NaN gives 0, as there).
#[inline]
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// A local direction's angles to the fibre (x along it): sin and cos of the longitudinal angle,
/// and the azimuth about the fibre.
#[inline]
fn fibre_angles(w: Vec3) -> (f32, f32, f32) {
    (w.x, safe_sqrt(1.0 - sqr(w.x)), w.z.atan2(w.y))
}

/// The modified Bessel function I0 by its first ten series terms (pbrt-v3's `I0`).
fn i0(x: f32) -> f32 {
    let mut val = 0.0f32;
    let mut x2i = 1.0f32;
    let mut ifact: i64 = 1;
    let mut i4: i32 = 1;
    for i in 0..10i64 {
        if i > 1 {
            ifact *= i;
        }
        val += x2i / (i4 as f32 * sqr(ifact as f32));
        x2i *= x * x;
        i4 *= 4;
    }
    val
}

/// log I0(x), asymptotic past 12 (pbrt-v3's `LogI0`; its `0.5` is a double, so the last steps
/// are in double precision there and here).
fn log_i0(x: f32) -> f32 {
    if x > 12.0 {
        let inner = -(2.0 * PI).ln() + (1.0 / x).ln() + 1.0 / (8.0 * x);
        (x as f64 + 0.5 * inner as f64) as f32
    } else {
        i0(x).ln()
    }
}

/// The longitudinal scattering function M_p (pbrt-v3's `Mp`), in log space for small variance.
// pbrt-v3 writes ln 2 as 0.6931f: kept, so that values round alike.
#[allow(clippy::approx_constant)]
fn mp(cos_theta_i: f32, cos_theta_o: f32, sin_theta_i: f32, sin_theta_o: f32, v: f32) -> f32 {
    let a = cos_theta_i * cos_theta_o / v;
    let b = sin_theta_i * sin_theta_o / v;
    // pbrt-v3 compares with the double 0.1, which 0.1f32 exceeds.
    if v as f64 <= 0.1 {
        (log_i0(a) - b - 1.0 / v + 0.6931 + (1.0 / (2.0 * v)).ln()).exp()
    } else {
        ((-b).exp() * i0(a)) / ((1.0 / v).sinh() * 2.0 * v)
    }
}

/// The attenuations A_p for p = 0..=3 (pbrt-v3's `Ap`): Fresnel reflection at the cylinder and
/// the transmittance `t` of one pass through it; the last sums every higher order.
fn ap(cos_theta_o: f32, eta: f32, h: f32, t: Spectrum) -> [Spectrum; P_MAX + 1] {
    let cos_gamma_o = safe_sqrt(1.0 - h * h);
    let cos_theta = cos_theta_o * cos_gamma_o;
    let f = fr_dielectric(cos_theta, 1.0, eta);
    let mut a = [Spectrum::ZERO; P_MAX + 1];
    a[0] = Spectrum::splat(f);
    a[1] = sqr(1.0 - f) * t;
    for p in 2..P_MAX {
        a[p] = a[p - 1] * t * f;
    }
    a[P_MAX] = a[P_MAX - 1] * f * t / (Spectrum::ONE - t * f);
    a
}

/// The azimuthal angle out of the hair after p internal passes (pbrt-v3's `Phi`).
#[inline]
fn phi(p: usize, gamma_o: f32, gamma_t: f32) -> f32 {
    (2 * p) as f32 * gamma_t - 2.0 * gamma_o + p as f32 * PI
}

/// The logistic distribution's density, scale `s` (pbrt-v3's `Logistic`).
#[inline]
fn logistic(x: f32, s: f32) -> f32 {
    let x = x.abs();
    (-x / s).exp() / (s * sqr(1.0 + (-x / s).exp()))
}

/// The logistic distribution's CDF (pbrt-v3's `LogisticCDF`).
#[inline]
fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + (-x / s).exp())
}

/// The logistic density renormalised over [a, b] (pbrt-v3's `TrimmedLogistic`).
#[inline]
fn trimmed_logistic(x: f32, s: f32, a: f32, b: f32) -> f32 {
    logistic(x, s) / (logistic_cdf(b, s) - logistic_cdf(a, s))
}

/// The azimuthal scattering function N_p (pbrt-v3's `Np`): a trimmed logistic about
/// [`phi`], the difference taken into [-pi, pi].
fn np(phi_: f32, p: usize, s: f32, gamma_o: f32, gamma_t: f32) -> f32 {
    let mut dphi = phi_ - phi(p, gamma_o, gamma_t);
    while dphi > PI {
        dphi -= 2.0 * PI;
    }
    while dphi < -PI {
        dphi += 2.0 * PI;
    }
    trimmed_logistic(dphi, s, -PI, PI)
}

/// Samples the trimmed logistic by inverting its CDF (pbrt-v3's `SampleTrimmedLogistic`).
fn sample_trimmed_logistic(u: f32, s: f32, a: f32, b: f32) -> f32 {
    let k = logistic_cdf(b, s) - logistic_cdf(a, s);
    let x = -s * (1.0 / (u * k + logistic_cdf(a, s)) - 1.0).ln();
    x.clamp(a, b)
}

/// Keeps the even bits of `x`, packed into its low 16 (pbrt-v3's `Compact1By1`).
fn compact1by1(mut x: u32) -> u32 {
    x &= 0x5555_5555;
    x = (x ^ (x >> 1)) & 0x3333_3333;
    x = (x ^ (x >> 2)) & 0x0f0f_0f0f;
    x = (x ^ (x >> 4)) & 0x00ff_00ff;
    x = (x ^ (x >> 8)) & 0x0000_ffff;
    x
}

/// Two 16-bit samples from one in [0, 1): its 32 fraction bits, even and odd ones
/// de-interleaved (pbrt-v3's `DemuxFloat`, which lets `Sample_f` take four numbers from two).
pub fn demux_float(f: f32) -> Vec2 {
    // pbrt-v3 checks 0 <= f < 1; out-of-range samples are clamped instead.
    let f = f.clamp(0.0, 1.0 - f32::EPSILON / 2.0);
    let v = (f * 4_294_967_296.0) as u64;
    let bits = [compact1by1(v as u32), compact1by1((v >> 1) as u32)];
    Vec2::new(
        bits[0] as f32 / (1u32 << 16) as f32,
        bits[1] as f32 / (1u32 << 16) as f32,
    )
}

/// pbrt-v3's `SigmaAFromConcentration`: absorption from eumelanin and pheomelanin
/// concentrations (RGB, as pbrt-v3's default `RGBSpectrum` build).
pub fn sigma_a_from_concentration(ce: f32, cp: f32) -> Spectrum {
    const EUMELANIN: [f32; 3] = [0.419, 0.697, 1.37];
    const PHEOMELANIN: [f32; 3] = [0.187, 0.4, 1.05];
    Spectrum::from_array(std::array::from_fn(|i| {
        ce * EUMELANIN[i] + cp * PHEOMELANIN[i]
    }))
}

/// The polynomial in beta_n that relates sqrt(sigma_a) to -ln(colour) (Chiang et al.'s fit).
fn reflectance_poly(beta_n: f32) -> f32 {
    5.969 - 0.215 * beta_n + 2.532 * sqr(beta_n) - 10.73 * pow_n(beta_n, 3)
        + 5.574 * pow_n(beta_n, 4)
        + 0.245 * pow_n(beta_n, 5)
}

/// pbrt-v3's `SigmaAFromReflectance`: the absorption that gives a hair of azimuthal roughness
/// `beta_n` about the colour `c` after multiple scattering.
pub fn sigma_a_from_reflectance(c: Spectrum, beta_n: f32) -> Spectrum {
    let d = reflectance_poly(beta_n);
    Spectrum::from_array(c.to_array().map(|ci| sqr(ci.ln() / d)))
}

/// pbrt-v3's `HairBSDF` at one point across a hair: reflection and transmission in every
/// direction (glossy), its values precomputed as pbrt-v3's constructor does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HairBsdf {
    /// Offset across the hair, in [-1, 1].
    h: f32,
    /// asin(h).
    gamma_o: f32,
    /// Index of refraction of the hair's interior.
    eta: f32,
    /// Absorption coefficient of the interior (per unit radius).
    sigma_a: Spectrum,
    /// Azimuthal roughness (kept for [`HairBsdf::albedo`]).
    beta_n: f32,
    /// Longitudinal variance v_0; pbrt-v3's v_1 and v_2 (= v_3) are v_0 / 4 and 4 v_0.
    v0: f32,
    /// Logistic scale of the azimuthal lobes.
    s: f32,
    /// sin(2^k alpha), k = 0, 1, 2: the scales' tilt.
    sin_2k_alpha: [f32; 3],
    /// cos(2^k alpha).
    cos_2k_alpha: [f32; 3],
}

impl HairBsdf {
    /// pbrt-v3's `HairBSDF(h, eta, sigma_a, beta_m, beta_n, alpha)`, `alpha` in degrees. `h` is
    /// clamped to [-1, 1] and the betas to [0, 1] (pbrt-v3 aborts outside them).
    pub fn new(h: f32, eta: f32, sigma_a: Spectrum, beta_m: f32, beta_n: f32, alpha: f32) -> Self {
        let h = h.clamp(-1.0, 1.0);
        let beta_m = beta_m.clamp(0.0, 1.0);
        let beta_n = beta_n.clamp(0.0, 1.0);
        let v0 = sqr(0.726 * beta_m + 0.812 * sqr(beta_m) + 3.7 * pow_n(beta_m, 20));
        let s = SQRT_PI_OVER_8 * (0.265 * beta_n + 1.194 * sqr(beta_n) + 5.372 * pow_n(beta_n, 22));
        let mut sin_2k_alpha = [0.0; 3];
        let mut cos_2k_alpha = [0.0; 3];
        sin_2k_alpha[0] = ((PI / 180.0) * alpha).sin();
        cos_2k_alpha[0] = safe_sqrt(1.0 - sqr(sin_2k_alpha[0]));
        for i in 1..3 {
            sin_2k_alpha[i] = 2.0 * cos_2k_alpha[i - 1] * sin_2k_alpha[i - 1];
            cos_2k_alpha[i] = sqr(cos_2k_alpha[i - 1]) - sqr(sin_2k_alpha[i - 1]);
        }
        Self {
            h,
            gamma_o: safe_asin(h),
            eta,
            sigma_a,
            beta_n,
            v0,
            s,
            sin_2k_alpha,
            cos_2k_alpha,
        }
    }

    /// Longitudinal variance of order p (pbrt-v3's `v[p]`: exact scalings of v_0).
    #[inline]
    fn v(&self, p: usize) -> f32 {
        match p {
            0 => self.v0,
            1 => 0.25 * self.v0,
            _ => 4.0 * self.v0,
        }
    }

    /// sin and cos of theta_o rotated by the scales' tilt for order p: -2 alpha for R,
    /// alpha for TT, 4 alpha for TRT, none beyond.
    #[inline]
    fn tilt(&self, p: usize, sin_o: f32, cos_o: f32) -> (f32, f32) {
        let (s, c) = (&self.sin_2k_alpha, &self.cos_2k_alpha);
        match p {
            0 => (sin_o * c[1] - cos_o * s[1], cos_o * c[1] + sin_o * s[1]),
            1 => (sin_o * c[0] + cos_o * s[0], cos_o * c[0] - sin_o * s[0]),
            2 => (sin_o * c[2] + cos_o * s[2], cos_o * c[2] - sin_o * s[2]),
            _ => (sin_o, cos_o),
        }
    }

    /// gamma_t, the refracted ray's offset angle, for sin theta_o and cos theta_o.
    #[inline]
    fn gamma_t(&self, sin_o: f32, cos_o: f32) -> f32 {
        let etap = (self.eta * self.eta - sqr(sin_o)).sqrt() / cos_o;
        safe_asin(self.h / etap)
    }

    /// The transmittance of one pass through the cylinder (pbrt-v3's `T`).
    #[inline]
    fn transmittance(&self, sin_o: f32, cos_o: f32) -> Spectrum {
        let sin_theta_t = sin_o / self.eta;
        let cos_theta_t = safe_sqrt(1.0 - sqr(sin_theta_t));
        let etap = (self.eta * self.eta - sqr(sin_o)).sqrt() / cos_o;
        let sin_gamma_t = self.h / etap;
        let cos_gamma_t = safe_sqrt(1.0 - sqr(sin_gamma_t));
        let d = 2.0 * cos_gamma_t / cos_theta_t;
        Spectrum::from_array((-self.sigma_a * d).to_array().map(f32::exp))
    }

    /// The lobe's value for local `wo` and `wi` (pbrt-v3's `HairBSDF::f`): the sum over
    /// orders of M_p A_p N_p, divided by |cos theta| to the normal as pbrt-v3 does (the
    /// integrator's cosine cancels it: a fibre is not a surface).
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Spectrum {
        let (sin_o, cos_o, phi_o) = fibre_angles(wo);
        let (sin_i, cos_i, phi_i) = fibre_angles(wi);
        let t = self.transmittance(sin_o, cos_o);
        let gamma_t = self.gamma_t(sin_o, cos_o);
        let dphi = phi_i - phi_o;
        let a = ap(cos_o, self.eta, self.h, t);
        let mut fsum = Spectrum::ZERO;
        for (p, ap) in a.iter().enumerate().take(P_MAX) {
            let (sin_op, cos_op) = self.tilt(p, sin_o, cos_o);
            // The tilt can take theta_o past the pole.
            let cos_op = cos_op.abs();
            fsum += *ap
                * mp(cos_i, cos_op, sin_i, sin_op, self.v(p))
                * np(dphi, p, self.s, self.gamma_o, gamma_t);
        }
        fsum += a[P_MAX] * mp(cos_i, cos_o, sin_i, sin_o, self.v(P_MAX)) / (2.0 * PI);
        let abs_cos = wi.z.abs();
        if abs_cos > 0.0 {
            fsum /= abs_cos;
        }
        fsum
    }

    /// The probability of choosing each order in [`HairBsdf::sample_f`]: A_p's luminances,
    /// normalised (pbrt-v3's `ComputeApPdf`).
    fn ap_pdf(&self, cos_o: f32) -> [f32; P_MAX + 1] {
        let sin_o = safe_sqrt(1.0 - cos_o * cos_o);
        let t = self.transmittance(sin_o, cos_o);
        let a = ap(cos_o, self.eta, self.h, t);
        let y = a.map(crate::spectrum_luminance);
        let sum_y = y.iter().fold(0.0f32, |s, &v| s + v);
        y.map(|v| v / sum_y)
    }

    /// The density of `wi` given the orders' probabilities, with `dphi` the azimuth
    /// difference (unwrapped or not).
    #[allow(clippy::too_many_arguments)]
    fn pdf_terms(
        &self,
        ap_pdf: &[f32; P_MAX + 1],
        sin_o: f32,
        cos_o: f32,
        sin_i: f32,
        cos_i: f32,
        dphi: f32,
        gamma_t: f32,
    ) -> f32 {
        let mut pdf = 0.0f32;
        for (p, &w) in ap_pdf.iter().enumerate().take(P_MAX) {
            let (sin_op, cos_op) = self.tilt(p, sin_o, cos_o);
            let cos_op = cos_op.abs();
            pdf += mp(cos_i, cos_op, sin_i, sin_op, self.v(p))
                * w
                * np(dphi, p, self.s, self.gamma_o, gamma_t);
        }
        pdf += mp(cos_i, cos_o, sin_i, sin_o, self.v(P_MAX)) * ap_pdf[P_MAX] * (1.0 / (2.0 * PI));
        pdf
    }

    /// Samples `wi` for local `wo` (pbrt-v3's `HairBSDF::Sample_f`): each of `u`'s two numbers
    /// is split into two ([`demux_float`]); one chooses the order p by [`HairBsdf::ap_pdf`], one
    /// samples N_p and two M_p. Returns (wi, f, pdf).
    pub fn sample_f(&self, wo: Vec3, u2: Vec2) -> (Vec3, Spectrum, f32) {
        let (sin_o, cos_o, phi_o) = fibre_angles(wo);
        let mut u = [demux_float(u2.x), demux_float(u2.y)];
        let ap_pdf = self.ap_pdf(cos_o);
        let mut p = 0;
        while p < P_MAX {
            if u[0].x < ap_pdf[p] {
                break;
            }
            u[0].x -= ap_pdf[p];
            p += 1;
        }
        let (sin_op, cos_op) = self.tilt(p, sin_o, cos_o);
        // Sample M_p for theta_i.
        u[1].x = u[1].x.max(1e-5);
        let vp = self.v(p);
        let cos_theta = 1.0 + vp * (u[1].x + (1.0 - u[1].x) * (-2.0 / vp).exp()).ln();
        let sin_theta = safe_sqrt(1.0 - sqr(cos_theta));
        let cos_phi = (2.0 * PI * u[1].y).cos();
        let sin_i = -cos_theta * sin_op + sin_theta * cos_phi * cos_op;
        let cos_i = safe_sqrt(1.0 - sqr(sin_i));
        // Sample N_p for the azimuth.
        let gamma_t = self.gamma_t(sin_o, cos_o);
        let dphi = if p < P_MAX {
            phi(p, self.gamma_o, gamma_t) + sample_trimmed_logistic(u[0].y, self.s, -PI, PI)
        } else {
            2.0 * PI * u[0].y
        };
        let phi_i = phi_o + dphi;
        let wi = Vec3::new(sin_i, cos_i * phi_i.cos(), cos_i * phi_i.sin());
        let pdf = self.pdf_terms(&ap_pdf, sin_o, cos_o, sin_i, cos_i, dphi, gamma_t);
        (wi, self.f(wo, wi), pdf)
    }

    /// The density with which [`HairBsdf::sample_f`] picks `wi` (pbrt-v3's `HairBSDF::Pdf`).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (sin_o, cos_o, phi_o) = fibre_angles(wo);
        let (sin_i, cos_i, phi_i) = fibre_angles(wi);
        let gamma_t = self.gamma_t(sin_o, cos_o);
        let ap_pdf = self.ap_pdf(cos_o);
        self.pdf_terms(&ap_pdf, sin_o, cos_o, sin_i, cos_i, phi_i - phi_o, gamma_t)
    }

    /// A nominal colour for first-hit features: the reflectance that pbrt-v3's
    /// [`sigma_a_from_reflectance`] maps to this absorption (its inverse).
    pub fn albedo(&self) -> Spectrum {
        let d = reflectance_poly(self.beta_n);
        Spectrum::from_array(
            self.sigma_a
                .to_array()
                .map(|s| (-s.max(0.0).sqrt() * d).exp()),
        )
    }
}

#[cfg(test)]
mod tests;
