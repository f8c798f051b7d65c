//! pbrt-v3's spline and Fourier interpolation (`core/interpolation.cpp`), for the tabulated
//! `fourier` BSDF and the subsurface profiles of [`crate::bssrdf`]: Catmull-Rom weights,
//! integration, inversion and sampling of a 2D spline table, Fourier series evaluation and
//! sampling. Same operations in the same precision (f32, f64 where pbrt-v3
//! uses double), so that values match.

use std::f64::consts::PI;

/// pbrt-v3's `FindInterval`: the largest i in [0, size - 2] with `pred(i)` true (0 if none).
pub fn find_interval(size: usize, pred: impl Fn(usize) -> bool) -> usize {
    let (mut first, mut len) = (0usize, size);
    while len > 0 {
        let half = len >> 1;
        let middle = first + half;
        if pred(middle) {
            first = middle + 1;
            len -= half + 1;
        } else {
            len = half;
        }
    }
    first.saturating_sub(1).min(size.saturating_sub(2))
}

/// The four Catmull-Rom weights of spline nodes `offset..offset + 4` at `x` (`offset` may be
/// -1; a weight whose node lies outside is 0). `None` when `x` is outside the nodes.
pub fn catmull_rom_weights(nodes: &[f32], x: f32) -> Option<(isize, [f32; 4])> {
    let size = nodes.len();
    if size < 2 || !(x >= nodes[0] && x <= nodes[size - 1]) {
        return None;
    }
    let idx = find_interval(size, |i| nodes[i] <= x);
    let (x0, x1) = (nodes[idx], nodes[idx + 1]);
    let t = (x - x0) / (x1 - x0);
    let (t2, t3) = (t * t, t * t * t);
    let mut w = [0.0f32; 4];
    w[1] = 2.0 * t3 - 3.0 * t2 + 1.0;
    w[2] = -2.0 * t3 + 3.0 * t2;
    if idx > 0 {
        let w0 = (t3 - 2.0 * t2 + t) * (x1 - x0) / (x1 - nodes[idx - 1]);
        w[0] = -w0;
        w[2] += w0;
    } else {
        let w0 = t3 - 2.0 * t2 + t;
        w[0] = 0.0;
        w[1] -= w0;
        w[2] += w0;
    }
    if idx + 2 < size {
        let w3 = (t3 - t2) * (x1 - x0) / (nodes[idx + 2] - x0);
        w[1] -= w3;
        w[3] = w3;
    } else {
        let w3 = t3 - t2;
        w[1] -= w3;
        w[2] += w3;
        w[3] = 0.0;
    }
    Some((idx as isize - 1, w))
}

/// pbrt-v3's `SampleCatmullRom2D`: samples the second dimension of a spline table
/// `values[i * size2 + j]` (with its running integrals `cdf`) at first-dimension parameter
/// `alpha`, by `u`; returns the position, the function value and the density.
pub fn sample_catmull_rom_2d(
    nodes1: &[f32],
    nodes2: &[f32],
    values: &[f32],
    cdf: &[f32],
    alpha: f32,
    u: f32,
) -> Option<(f32, f32, f32)> {
    let size2 = nodes2.len();
    let (offset, weights) = catmull_rom_weights(nodes1, alpha)?;
    let interpolate = |array: &[f32], idx: usize| {
        let mut value = 0.0f32;
        for (i, &w) in weights.iter().enumerate() {
            if w != 0.0 {
                let row = (offset + i as isize) as usize;
                value += array[row * size2 + idx] * w;
            }
        }
        value
    };
    let maximum = interpolate(cdf, size2 - 1);
    // No positive integral to sample by (pbrt-v3 divides by it regardless).
    if !(maximum > 0.0 && maximum.is_finite()) {
        return None;
    }
    let mut u = u * maximum;
    let idx = find_interval(size2, |i| interpolate(cdf, i) <= u);
    let (f0, f1) = (interpolate(values, idx), interpolate(values, idx + 1));
    let (x0, x1) = (nodes2[idx], nodes2[idx + 1]);
    let width = x1 - x0;
    u = (u - interpolate(cdf, idx)) / width;
    let d0 = if idx > 0 {
        width * (f1 - interpolate(values, idx - 1)) / (x1 - nodes2[idx - 1])
    } else {
        f1 - f0
    };
    let d1 = if idx + 2 < size2 {
        width * (interpolate(values, idx + 2) - f0) / (nodes2[idx + 2] - x0)
    } else {
        f1 - f0
    };
    let mut t = if f0 != f1 {
        (f0 - (f0 * f0 + 2.0 * u * (f1 - f0)).max(0.0).sqrt()) / (f0 - f1)
    } else {
        u / f0
    };
    let (mut a, mut b) = (0.0f32, 1.0f32);
    let (mut big_f, mut f);
    // pbrt-v3 loops until convergence; bounded here so that a table of NaNs cannot hang.
    let mut steps = 0;
    loop {
        if !(t >= a && t <= b) {
            t = 0.5 * (a + b);
        }
        big_f = t
            * (f0
                + t * (0.5 * d0
                    + t * ((1.0 / 3.0) * (-2.0 * d0 - d1) + f1 - f0
                        + t * (0.25 * (d0 + d1) + 0.5 * (f0 - f1)))));
        f = f0
            + t * (d0 + t * (-2.0 * d0 - d1 + 3.0 * (f1 - f0) + t * (d0 + d1 + 2.0 * (f0 - f1))));
        steps += 1;
        if (big_f - u).abs() < 1e-6 || b - a < 1e-6 || steps > 100 {
            break;
        }
        if big_f - u < 0.0 {
            a = t;
        } else {
            b = t;
        }
        t -= (big_f - u) / f;
    }
    Some((x0 + width * t, f, f / maximum))
}

/// Finite-difference derivatives of spline segment `i` of `values` over `x`, scaled to the
/// segment's width (pbrt-v3's, shared by its integration and inversion).
fn segment_derivatives(x: &[f32], values: &[f32], i: usize) -> (f32, f32) {
    let n = x.len();
    let (x0, x1) = (x[i], x[i + 1]);
    let (f0, f1) = (values[i], values[i + 1]);
    let width = x1 - x0;
    let d0 = if i > 0 {
        width * (f1 - values[i - 1]) / (x1 - x[i - 1])
    } else {
        f1 - f0
    };
    let d1 = if i + 2 < n {
        width * (values[i + 2] - f0) / (x[i + 2] - x0)
    } else {
        f1 - f0
    };
    (d0, d1)
}

/// pbrt-v3's `IntegrateCatmullRom`: the integral of the spline through (`x`, `values`), with
/// its running integral at each node written to `cdf` (`cdf[0]` = 0).
pub fn integrate_catmull_rom(x: &[f32], values: &[f32], cdf: &mut [f32]) -> f32 {
    let mut sum = 0.0f32;
    cdf[0] = 0.0;
    for i in 0..x.len().saturating_sub(1) {
        let (f0, f1) = (values[i], values[i + 1]);
        let width = x[i + 1] - x[i];
        let (d0, d1) = segment_derivatives(x, values, i);
        sum += ((d0 - d1) * (1.0 / 12.0) + (f0 + f1) * 0.5) * width;
        cdf[i + 1] = sum;
    }
    sum
}

/// pbrt-v3's `InvertCatmullRom`: the x where the spline through increasing `values` reaches
/// `u` (clamped to the first or last node outside their range; NaN gives the first).
pub fn invert_catmull_rom(x: &[f32], values: &[f32], u: f32) -> f32 {
    let n = x.len();
    use std::cmp::Ordering::{Greater, Less};
    if u.partial_cmp(&values[0]) != Some(Greater) {
        return x[0];
    } else if u.partial_cmp(&values[n - 1]) != Some(Less) {
        return x[n - 1];
    }
    let i = find_interval(n, |i| values[i] <= u);
    let (x0, x1) = (x[i], x[i + 1]);
    let (f0, f1) = (values[i], values[i + 1]);
    let width = x1 - x0;
    let (d0, d1) = segment_derivatives(x, values, i);
    let (mut a, mut b, mut t) = (0.0f32, 1.0f32, 0.5f32);
    // pbrt-v3 loops until convergence; bounded here so that a degenerate table cannot hang.
    for _ in 0..100 {
        if !(t > a && t < b) {
            t = 0.5 * (a + b);
        }
        let (t2, t3) = (t * t, t * t * t);
        let big_f = (2.0 * t3 - 3.0 * t2 + 1.0) * f0
            + (-2.0 * t3 + 3.0 * t2) * f1
            + (t3 - 2.0 * t2 + t) * d0
            + (t3 - t2) * d1;
        let f = (6.0 * t2 - 6.0 * t) * f0
            + (-6.0 * t2 + 6.0 * t) * f1
            + (3.0 * t2 - 4.0 * t + 1.0) * d0
            + (3.0 * t2 - 2.0 * t) * d1;
        if (big_f - u).abs() < 1e-6 || b - a < 1e-6 {
            break;
        }
        if big_f - u < 0.0 {
            a = t;
        } else {
            b = t;
        }
        t -= (big_f - u) / f;
    }
    x0 + t * width
}

/// pbrt-v3's `Fourier`: sum over k of `a[k] cos(k phi)`, in double precision.
pub fn fourier(a: &[f32], cos_phi: f64) -> f32 {
    let mut value = 0.0f64;
    let (mut cos_k_minus_one, mut cos_k) = (cos_phi, 1.0f64);
    for &ak in a {
        value += f64::from(ak) * cos_k;
        let cos_k_plus_one = 2.0 * cos_phi * cos_k - cos_k_minus_one;
        cos_k_minus_one = cos_k;
        cos_k = cos_k_plus_one;
    }
    value as f32
}

/// pbrt-v3's `SampleFourier`: samples phi in [0, 2 pi) in proportion to the series `ak`
/// (`recip[k]` = 1 / k); returns the series' value there, the density and phi.
pub fn sample_fourier(ak: &[f32], recip: &[f32], u: f32) -> (f32, f32, f32) {
    let m = ak.len();
    let flip = u >= 0.5;
    let u = if flip { 1.0 - 2.0 * (u - 0.5) } else { u * 2.0 };
    let (mut a, mut b, mut phi) = (0.0f64, PI, 0.5 * PI);
    let (mut big_f, mut f);
    let mut steps = 0;
    loop {
        let cos_phi = phi.cos();
        let sin_phi = (1.0 - cos_phi * cos_phi).max(0.0).sqrt();
        let (mut cos_prev, mut cos_cur) = (cos_phi, 1.0f64);
        let (mut sin_prev, mut sin_cur) = (-sin_phi, 0.0f64);
        big_f = f64::from(ak[0]) * phi;
        f = f64::from(ak[0]);
        for k in 1..m {
            let sin_next = 2.0 * cos_phi * sin_cur - sin_prev;
            let cos_next = 2.0 * cos_phi * cos_cur - cos_prev;
            sin_prev = sin_cur;
            sin_cur = sin_next;
            cos_prev = cos_cur;
            cos_cur = cos_next;
            big_f += f64::from(ak[k]) * f64::from(recip[k]) * sin_next;
            f += f64::from(ak[k]) * cos_next;
        }
        big_f -= f64::from(u) * f64::from(ak[0]) * PI;
        if big_f > 0.0 {
            b = phi;
        } else {
            a = phi;
        }
        steps += 1;
        if big_f.abs() < 1e-6 || b - a < 1e-6 || steps > 100 {
            break;
        }
        phi -= big_f / f;
        if !(phi > a && phi < b) {
            phi = 0.5 * (a + b);
        }
    }
    if flip {
        phi = 2.0 * PI - phi;
    }
    let pdf = (0.5 / PI * f / f64::from(ak[0])) as f32;
    (f as f32, pdf, phi as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_reproduce_a_cubic_and_sum_to_one() {
        let nodes = [-1.0, -0.5, 0.0, 0.4, 1.0];
        for x in [-1.0f32, -0.7, 0.0, 0.2, 0.99, 1.0] {
            let (offset, w) = catmull_rom_weights(&nodes, x).unwrap();
            let sum: f32 = w.iter().sum();
            assert!((sum - 1.0).abs() < 1e-5, "{x}: {w:?}");
            // A linear function is reproduced exactly.
            let v: f32 = (0..4)
                .filter(|&i| w[i] != 0.0)
                .map(|i| w[i] * (2.0 * nodes[(offset + i as isize) as usize] + 1.0))
                .sum();
            assert!((v - (2.0 * x + 1.0)).abs() < 1e-5, "{x}: {v}");
        }
        assert!(catmull_rom_weights(&nodes, 1.01).is_none());
        assert!(catmull_rom_weights(&nodes, f32::NAN).is_none());
    }

    #[test]
    fn fourier_sampling_density_matches_the_series() {
        let ak = [1.0f32, 0.6, 0.2];
        let recip = [0.0f32, 1.0, 0.5];
        for u in [0.01f32, 0.3, 0.5, 0.77, 0.99] {
            let (y, pdf, phi) = sample_fourier(&ak, &recip, u);
            let expect = fourier(&ak, f64::from(phi).cos());
            assert!((y - expect).abs() < 1e-4, "{u}");
            assert!((pdf - expect / (2.0 * std::f32::consts::PI)).abs() < 1e-4);
        }
    }
    #[test]
    fn spline_integral_and_inverse_of_a_smooth_function() {
        let x: Vec<f32> = (0..33).map(|i| i as f32 / 32.0).collect();
        let v: Vec<f32> = x.iter().map(|&t| t * t).collect();
        let mut cdf = vec![0.0; x.len()];
        let total = integrate_catmull_rom(&x, &v, &mut cdf);
        assert!((total - 1.0 / 3.0).abs() < 1e-3, "{total}");
        assert!((cdf[16] - 0.5f32.powi(3) / 3.0).abs() < 1e-3, "{}", cdf[16]);
        for u in [0.01f32, 0.2, 0.5, 0.81] {
            let t = invert_catmull_rom(&x, &v, u);
            assert!((t - u.sqrt()).abs() < 1e-3, "{u}: {t}");
        }
        assert_eq!(invert_catmull_rom(&x, &v, -1.0), 0.0);
        assert_eq!(invert_catmull_rom(&x, &v, 2.0), 1.0);
        assert_eq!(invert_catmull_rom(&x, &v, f32::NAN), 0.0);
    }
}
