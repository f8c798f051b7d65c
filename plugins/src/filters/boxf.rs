//! `box`: constant weight over the radius (pbrt-v3 default radius 0.5).

use super::FilterKernel;

/// The box filter.
#[derive(Clone, Debug)]
pub struct BoxFilter {
    rx: f32,
    ry: f32,
}

impl BoxFilter {
    /// A box of half-widths `rx`, `ry`.
    pub fn new(rx: f32, ry: f32) -> Self {
        Self { rx, ry }
    }
}

impl FilterKernel for BoxFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        if x.abs() <= self.rx && y.abs() <= self.ry {
            1.0
        } else {
            0.0
        }
    }
}
