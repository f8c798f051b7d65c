//! `mitchell`: the Mitchell-Netravali cubic with parameters B and C (pbrt-v3: radius 2, 1/3, 1/3).

use super::FilterKernel;

/// The Mitchell-Netravali filter.
#[derive(Clone, Debug)]
pub struct MitchellFilter {
    rx: f32,
    ry: f32,
    b: f32,
    c: f32,
}

impl MitchellFilter {
    /// A Mitchell filter of half-widths `rx`, `ry` and parameters `b`, `c`.
    pub fn new(rx: f32, ry: f32, b: f32, c: f32) -> Self {
        Self { rx, ry, b, c }
    }

    /// pbrt-v3's Mitchell1D on x in [-1, 1].
    #[inline]
    fn mitchell_1d(&self, x: f32) -> f32 {
        let (b, c) = (self.b, self.c);
        let x = (2.0 * x).abs();
        if x > 2.0 {
            0.0
        } else if x > 1.0 {
            ((-b - 6.0 * c) * x * x * x
                + (6.0 * b + 30.0 * c) * x * x
                + (-12.0 * b - 48.0 * c) * x
                + (8.0 * b + 24.0 * c))
                * (1.0 / 6.0)
        } else {
            ((12.0 - 9.0 * b - 6.0 * c) * x * x * x
                + (-18.0 + 12.0 * b + 6.0 * c) * x * x
                + (6.0 - 2.0 * b))
                * (1.0 / 6.0)
        }
    }
}

impl FilterKernel for MitchellFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        if x.abs() > self.rx || y.abs() > self.ry {
            return 0.0;
        }
        self.mitchell_1d(x / self.rx) * self.mitchell_1d(y / self.ry)
    }
}
