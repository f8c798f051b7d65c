//! `gaussian`: exp(-alpha d^2) shifted to reach zero at the radius (pbrt-v3: radius 2, alpha 2).

use super::FilterKernel;

/// The truncated Gaussian filter.
#[derive(Clone, Debug)]
pub struct GaussianFilter {
    rx: f32,
    ry: f32,
    alpha: f32,
    exp_x: f32,
    exp_y: f32,
}

impl GaussianFilter {
    /// A Gaussian of falloff `alpha` truncated at half-widths `rx`, `ry`.
    pub fn new(rx: f32, ry: f32, alpha: f32) -> Self {
        Self {
            rx,
            ry,
            alpha,
            exp_x: (-alpha * rx * rx).exp(),
            exp_y: (-alpha * ry * ry).exp(),
        }
    }

    #[inline]
    fn gaussian(&self, d: f32, expv: f32) -> f32 {
        ((-self.alpha * d * d).exp() - expv).max(0.0)
    }
}

impl FilterKernel for GaussianFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        if x.abs() > self.rx || y.abs() > self.ry {
            return 0.0;
        }
        self.gaussian(x, self.exp_x) * self.gaussian(y, self.exp_y)
    }
}
