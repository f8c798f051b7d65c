//! Warping uniform samples to the distributions the integrators need, and 1D/2D piecewise-
//! constant distributions for importance sampling (pbrt-v3's sampling.h).

use crate::geometry::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Concentric mapping of the unit square to the unit disk (Shirley and Chiu).
#[inline]
pub fn concentric_sample_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction on the hemisphere around +z; pdf = cos(theta) / pi.
#[inline]
pub fn cosine_sample_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_sample_disk(u);
    let z = (1.0 - d.x * d.x - d.y * d.y).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Uniform direction on the unit sphere; pdf = 1 / (4 pi).
#[inline]
pub fn uniform_sample_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone around +z with the given cosine of its half-angle.
#[inline]
pub fn uniform_sample_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_theta = (1.0 - u.x) + u.x * cos_max;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = u.y * 2.0 * PI;
    Vec3::new(phi.cos() * sin_theta, phi.sin() * sin_theta, cos_theta)
}

/// The pdf of [`uniform_sample_cone`].
#[inline]
pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform barycentrics (b0, b1) on a triangle.
#[inline]
pub fn uniform_sample_triangle(u: Vec2) -> Vec2 {
    let su0 = u.x.sqrt();
    Vec2::new(1.0 - su0, u.y * su0)
}

/// Veach's power heuristic with beta = 2.
#[inline]
pub fn power_heuristic(nf: f32, f_pdf: f32, ng: f32, g_pdf: f32) -> f32 {
    let f = nf * f_pdf;
    let g = ng * g_pdf;
    if f.is_infinite() {
        return 1.0;
    }
    let d = f * f + g * g;
    if d == 0.0 {
        0.0
    } else {
        f * f / d
    }
}

/// A piecewise-constant 1D distribution over [0, 1).
#[derive(Clone, Debug)]
pub struct Distribution1D {
    func: Vec<f32>,
    cdf: Vec<f32>,
    integral: f32,
}

impl Distribution1D {
    /// From non-negative function values (negative or non-finite values count as 0). An
    /// all-zero function becomes uniform.
    pub fn new(values: &[f32]) -> Self {
        let n = values.len().max(1);
        let func: Vec<f32> = (0..n)
            .map(|i| {
                let v = values.get(i).copied().unwrap_or(0.0);
                if v.is_finite() && v > 0.0 {
                    v
                } else {
                    0.0
                }
            })
            .collect();
        let mut cdf = vec![0.0f32; n + 1];
        let mut acc = 0.0f64;
        for i in 0..n {
            acc += func[i] as f64 / n as f64;
            cdf[i + 1] = acc as f32;
        }
        let integral = acc as f32;
        if integral > 0.0 {
            for c in &mut cdf[1..] {
                *c /= integral;
            }
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f32 / n as f32;
            }
        }
        cdf[n] = 1.0;
        Self {
            func,
            cdf,
            integral,
        }
    }

    /// Number of pieces.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// True when it has no pieces (never: a distribution has at least one).
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// The integral of the function over [0, 1].
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Samples a continuous value in [0, 1); returns it, its pdf and the piece index.
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let n = self.func.len();
        // The last cdf entry <= u.
        let i = self.cdf.partition_point(|&c| c <= u).clamp(1, n) - 1;
        let width = self.cdf[i + 1] - self.cdf[i];
        let du = if width > 0.0 {
            (u - self.cdf[i]) / width
        } else {
            0.0
        };
        let pdf = if self.integral > 0.0 {
            self.func[i] / self.integral
        } else {
            1.0
        };
        let x = ((i as f32 + du) / n as f32).min(1.0 - f32::EPSILON / 2.0);
        (x, pdf, i)
    }

    /// Samples a piece; returns it, its probability and `u` remapped to [0, 1) within it.
    pub fn sample_discrete(&self, u: f32) -> (usize, f32, f32) {
        let n = self.func.len();
        let i = self.cdf.partition_point(|&c| c <= u).clamp(1, n) - 1;
        let width = self.cdf[i + 1] - self.cdf[i];
        let remapped = if width > 0.0 {
            ((u - self.cdf[i]) / width).min(1.0 - f32::EPSILON / 2.0)
        } else {
            0.0
        };
        (i, self.discrete_pdf(i), remapped)
    }

    /// Probability of piece `i` under [`Distribution1D::sample_discrete`].
    pub fn discrete_pdf(&self, i: usize) -> f32 {
        let n = self.func.len();
        if self.integral > 0.0 {
            self.func.get(i).copied().unwrap_or(0.0) / (self.integral * n as f32)
        } else {
            1.0 / n as f32
        }
    }

    /// Density of the continuous sample at `x` in [0, 1).
    pub fn pdf(&self, x: f32) -> f32 {
        let n = self.func.len();
        let i = ((x * n as f32) as usize).min(n - 1);
        if self.integral > 0.0 {
            self.func[i] / self.integral
        } else {
            1.0
        }
    }
}

/// A piecewise-constant 2D distribution over [0, 1)^2: a marginal over rows, a conditional per
/// row. Used for environment-map importance sampling.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    conditional: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// From `values[v * nu + u]`.
    pub fn new(values: &[f32], nu: usize, nv: usize) -> Self {
        let conditional: Vec<Distribution1D> = (0..nv)
            .map(|v| Distribution1D::new(&values[v * nu..(v + 1) * nu]))
            .collect();
        let marginal_values: Vec<f32> = conditional.iter().map(|c| c.integral()).collect();
        Self {
            marginal: Distribution1D::new(&marginal_values),
            conditional,
        }
    }

    /// Samples a point in [0, 1)^2 and its density.
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (d1, pdf1, v) = self.marginal.sample_continuous(u.y);
        let (d0, pdf0, _) = self.conditional[v].sample_continuous(u.x);
        (Vec2::new(d0, d1), pdf0 * pdf1)
    }

    /// Density at `p`.
    pub fn pdf(&self, p: Vec2) -> f32 {
        let nv = self.conditional.len();
        let v = ((p.y * nv as f32) as usize).min(nv - 1);
        let c = &self.conditional[v];
        let marginal = self.marginal.integral();
        if marginal > 0.0 {
            let nu = c.len();
            let u = ((p.x * nu as f32) as usize).min(nu - 1);
            c.func[u] / marginal
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distribution_1d_samples_proportionally() {
        let d = Distribution1D::new(&[1.0, 3.0, 0.0, 4.0]);
        assert!((d.integral() - 2.0).abs() < 1e-6);
        let mut counts = [0usize; 4];
        let n = 80_000;
        for i in 0..n {
            let (x, pdf, piece) = d.sample_continuous((i as f32 + 0.5) / n as f32);
            assert_eq!(piece, ((x * 4.0) as usize).min(3));
            assert!((pdf - d.pdf(x)).abs() < 1e-5);
            counts[piece] += 1;
        }
        let f: Vec<f64> = counts.iter().map(|&c| c as f64 / n as f64).collect();
        assert!((f[0] - 0.125).abs() < 1e-3 && (f[1] - 0.375).abs() < 1e-3);
        assert_eq!(counts[2], 0);
        assert!((f[3] - 0.5).abs() < 1e-3);
    }

    #[test]
    fn distribution_2d_pdf_integrates_to_one() {
        let vals: Vec<f32> = (0..32).map(|i| (i % 7) as f32).collect();
        let d = Distribution2D::new(&vals, 8, 4);
        let mut sum = 0.0;
        let n = 64;
        for j in 0..n {
            for i in 0..n {
                sum += d.pdf(Vec2::new(
                    (i as f32 + 0.5) / n as f32,
                    (j as f32 + 0.5) / n as f32,
                ));
            }
        }
        assert!((sum / (n * n) as f32 - 1.0).abs() < 1e-4, "{sum}");
        let (p, pdf) = d.sample(Vec2::new(0.3, 0.7));
        assert!((pdf - d.pdf(p)).abs() < 1e-4);
    }

    #[test]
    fn warps_stay_in_their_domains() {
        for i in 0..100 {
            for j in 0..100 {
                let u = Vec2::new(i as f32 / 100.0, j as f32 / 100.0);
                assert!(concentric_sample_disk(u).length() <= 1.0 + 1e-6);
                let h = cosine_sample_hemisphere(u);
                assert!(h.z >= 0.0 && (h.length() - 1.0).abs() < 1e-5);
                assert!((uniform_sample_sphere(u).length() - 1.0).abs() < 1e-5);
                let b = uniform_sample_triangle(u);
                assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            }
        }
    }
}
