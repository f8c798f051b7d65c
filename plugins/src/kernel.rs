//! The filter kernel the film splats with: below the film, so that the film does not read the
//! filters that read it.

/// A pixel filter's kernel: the film splats every sample with it.
pub trait FilterKernel: Send + Sync {
    /// Half-widths in x and y (pixels).
    fn radius(&self) -> (f32, f32);
    /// The weight at offset (x, y) from the pixel centre; zero outside the radius.
    fn eval(&self, x: f32, y: f32) -> f32;
}
