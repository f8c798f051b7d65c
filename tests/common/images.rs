//! What the agreement tests share to compare images.

use acr::geometry::Spectrum;

/// MSE of two images after pbrt's 8-bit sRGB conversion (clamp, gamma, round), the measure
/// every agreement with pbrt-v3 is stated in.
pub fn srgb8_mse(a: &[Spectrum], b: &[Spectrum]) -> f64 {
    let q = |v: f32| -> f64 {
        let v = v.clamp(0.0, 1.0);
        let s = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round() as f64 / 255.0
    };
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (0..3).map(|c| (q(x[c]) - q(y[c])).powi(2)).sum::<f64>())
        .sum();
    sum / (3 * a.len()) as f64
}
