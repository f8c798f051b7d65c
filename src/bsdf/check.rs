//! Test helpers shared with the material tests: a deterministic generator and Monte Carlo
//! checks of a BSDF's sampling against its evaluation.

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

/// Directions that break naive BSDF code: the poles, the horizon, a hair above and below it,
/// and zero.
pub fn degenerate_directions() -> [Vec3; 6] {
    [
        Vec3::Z,
        -Vec3::Z,
        Vec3::X,
        Vec3::new(1.0, 0.0, 1e-7).normalize(),
        Vec3::new(0.0, 1.0, -1e-7).normalize(),
        Vec3::ZERO,
    ]
}

/// Sample values at the ends and the middle of [0, 1).
pub fn edge_samples() -> [Vec2; 3] {
    [
        Vec2::ZERO,
        Vec2::splat(0.5),
        Vec2::splat(super::lobe::ONE_MINUS_EPSILON),
    ]
}
