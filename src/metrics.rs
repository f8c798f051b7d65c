//! Image error metrics (docs/algorithm.md §7): MSE and relMSE on linear radiance, PSNR on the
//! image clamped to [0, 1].

use crate::image_io::RgbImage;
use serde::Serialize;

/// The error of an image against a reference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Metrics {
    /// Mean over pixels and channels of `(x - ref)^2`.
    pub mse: f64,
    /// Mean of `(x - ref)^2 / (ref^2 + 0.01)`.
    pub relmse: f64,
    /// `10 log10(1 / MSE)` of the images clamped to [0, 1], in dB (infinite when equal).
    pub psnr: f64,
    /// Mean channel value of the image (a bias shows here first).
    pub mean: f64,
    /// Mean channel value of the reference.
    pub reference_mean: f64,
}

/// Compares `image` with `reference`; they must have the same size.
pub fn compare(image: &RgbImage, reference: &RgbImage) -> Result<Metrics, String> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(format!(
            "sizes differ: {}x{} and {}x{}",
            image.width, image.height, reference.width, reference.height
        ));
    }
    let n = (3 * image.pixels.len()).max(1) as f64;
    let (mut se, mut rel, mut clamped, mut sum_a, mut sum_b) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (a, b) in image.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (x, r) = (a[c] as f64, b[c] as f64);
            let d = x - r;
            se += d * d;
            rel += d * d / (r * r + 0.01);
            let dc = x.clamp(0.0, 1.0) - r.clamp(0.0, 1.0);
            clamped += dc * dc;
            sum_a += x;
            sum_b += r;
        }
    }
    Ok(Metrics {
        mse: se / n,
        relmse: rel / n,
        psnr: 10.0 * (1.0 / (clamped / n)).log10(),
        mean: sum_a / n,
        reference_mean: sum_b / n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Spectrum;

    fn image(values: &[f32]) -> RgbImage {
        RgbImage {
            width: values.len(),
            height: 1,
            pixels: values.iter().map(|&v| Spectrum::splat(v)).collect(),
        }
    }

    #[test]
    fn metrics_follow_their_definitions() {
        let m = compare(&image(&[0.5, 2.0]), &image(&[0.25, 1.0])).unwrap();
        assert!((m.mse - (0.0625 + 1.0) / 2.0).abs() < 1e-12);
        let rel = (0.0625 / (0.0625 + 0.01) + 1.0 / 1.01) / 2.0;
        assert!((m.relmse - rel).abs() < 1e-9);
        // Clamped: 0.5 vs 0.25 and 1 vs 1.
        assert!((m.psnr - 10.0 * (1.0 / (0.0625 / 2.0f64)).log10()).abs() < 1e-9);
        assert!(compare(&image(&[1.0]), &image(&[1.0, 2.0])).is_err());
    }
}
