//! pbrt-v3's pixel reconstruction filters: each sample is splatted into every pixel whose
//! centre lies within the filter's radius, weighted by the filter at the offset.

mod boxf;
mod gaussian;
mod mitchell;
mod sinc;
mod triangle;

pub use boxf::BoxFilter;
pub use gaussian::GaussianFilter;
pub use mitchell::MitchellFilter;
pub use sinc::LanczosSincFilter;
pub use triangle::TriangleFilter;

/// A separable or non-separable 2D filter of finite support.
pub trait FilterKernel: Send + Sync {
    /// Half-widths in x and y (pixels).
    fn radius(&self) -> (f32, f32);
    /// The weight at offset (x, y) from the pixel centre; zero outside the radius.
    fn eval(&self, x: f32, y: f32) -> f32;
}

/// The built-in kernels as one closed set, so the splatting loop dispatches without a vtable.
#[derive(Clone, Debug)]
pub enum Kernel {
    /// `box`
    Box(BoxFilter),
    /// `triangle`
    Triangle(TriangleFilter),
    /// `gaussian`
    Gaussian(GaussianFilter),
    /// `mitchell`
    Mitchell(MitchellFilter),
    /// `sinc`
    Sinc(LanczosSincFilter),
}

impl FilterKernel for Kernel {
    #[inline]
    fn radius(&self) -> (f32, f32) {
        match self {
            Kernel::Box(f) => f.radius(),
            Kernel::Triangle(f) => f.radius(),
            Kernel::Gaussian(f) => f.radius(),
            Kernel::Mitchell(f) => f.radius(),
            Kernel::Sinc(f) => f.radius(),
        }
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        match self {
            Kernel::Box(f) => f.eval(x, y),
            Kernel::Triangle(f) => f.eval(x, y),
            Kernel::Gaussian(f) => f.eval(x, y),
            Kernel::Mitchell(f) => f.eval(x, y),
            Kernel::Sinc(f) => f.eval(x, y),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Midpoint-rule integral over the support.
    fn integral(k: &dyn FilterKernel) -> f64 {
        let (rx, ry) = k.radius();
        let n = 400;
        let (dx, dy) = (2.0 * rx as f64 / n as f64, 2.0 * ry as f64 / n as f64);
        let mut sum = 0.0;
        for j in 0..n {
            for i in 0..n {
                let x = -rx as f64 + (i as f64 + 0.5) * dx;
                let y = -ry as f64 + (j as f64 + 0.5) * dy;
                sum += k.eval(x as f32, y as f32) as f64;
            }
        }
        sum * dx * dy
    }

    #[test]
    fn kernels_are_zero_outside_and_symmetric() {
        let kernels = [
            Kernel::Box(BoxFilter::new(0.5, 0.5)),
            Kernel::Triangle(TriangleFilter::new(2.0, 2.0)),
            Kernel::Gaussian(GaussianFilter::new(2.0, 2.0, 2.0)),
            Kernel::Mitchell(MitchellFilter::new(2.0, 2.0, 1.0 / 3.0, 1.0 / 3.0)),
            Kernel::Sinc(LanczosSincFilter::new(4.0, 4.0, 3.0)),
        ];
        for k in &kernels {
            let (rx, ry) = k.radius();
            assert_eq!(k.eval(rx * 1.01, 0.0), 0.0);
            assert_eq!(k.eval(0.0, -ry * 1.01), 0.0);
            for (x, y) in [(0.3, 0.1), (0.45, -0.2), (0.1, 0.4)] {
                assert!((k.eval(x, y) - k.eval(-x, -y)).abs() < 1e-6);
            }
            assert!(integral(k) > 0.0);
        }
    }

    #[test]
    fn formulas_match_pbrt_v3() {
        let g = GaussianFilter::new(2.0, 2.0, 2.0);
        let e = (-2.0f32 * 4.0).exp();
        assert!((g.eval(1.0, 0.0) - ((-2.0f32).exp() - e) * (1.0 - e)).abs() < 1e-6);
        let t = TriangleFilter::new(2.0, 2.0);
        assert!((t.eval(0.5, 1.0) - 1.5 * 1.0).abs() < 1e-6);
        // Mitchell-Netravali with B = C = 1/3 at the centre: (6 - 2B) / 6 per axis.
        let m = MitchellFilter::new(2.0, 2.0, 1.0 / 3.0, 1.0 / 3.0);
        let c = (6.0 - 2.0 / 3.0) / 6.0;
        assert!((m.eval(0.0, 0.0) - c * c).abs() < 1e-6);
        let s = LanczosSincFilter::new(4.0, 4.0, 3.0);
        assert!((s.eval(0.0, 0.0) - 1.0).abs() < 1e-6);
        assert!(s.eval(1.0, 0.0).abs() < 1e-6);
        assert_eq!(BoxFilter::new(0.5, 0.5).eval(0.49, -0.49), 1.0);
    }
}
