//! `sinc`: sinc windowed by a Lanczos lobe of width tau (pbrt-v3: radius 4, tau 3).

use super::FilterKernel;
use std::f32::consts::PI;

/// The Lanczos-windowed sinc filter.
#[derive(Clone, Debug)]
pub struct LanczosSincFilter {
    rx: f32,
    ry: f32,
    tau: f32,
}

/// sin(pi x) / (pi x).
#[inline]
fn sinc(x: f32) -> f32 {
    let x = x.abs();
    if x < 1e-5 {
        1.0
    } else {
        (PI * x).sin() / (PI * x)
    }
}

impl LanczosSincFilter {
    /// A windowed sinc of half-widths `rx`, `ry` and window `tau`.
    pub fn new(rx: f32, ry: f32, tau: f32) -> Self {
        Self { rx, ry, tau }
    }

    #[inline]
    fn windowed(&self, x: f32, radius: f32) -> f32 {
        if x.abs() > radius {
            0.0
        } else {
            sinc(x) * sinc(x / self.tau)
        }
    }
}

impl FilterKernel for LanczosSincFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        self.windowed(x, self.rx) * self.windowed(y, self.ry)
    }
}
