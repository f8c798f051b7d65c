//! `triangle`: a tent falling linearly to zero at the radius (pbrt-v3 default radius 2).

use super::FilterKernel;

/// The triangle (tent) filter.
#[derive(Clone, Debug)]
pub struct TriangleFilter {
    rx: f32,
    ry: f32,
}

impl TriangleFilter {
    /// A tent of half-widths `rx`, `ry`.
    pub fn new(rx: f32, ry: f32) -> Self {
        Self { rx, ry }
    }
}

impl FilterKernel for TriangleFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        (self.rx - x.abs()).max(0.0) * (self.ry - y.abs()).max(0.0)
    }
}
