//! What mlt's chains sample: a path function of primary sample space, one path length at a
//! time ([`PathContribution`]; bdpt's is `super::bdpt_path::BdptContribution`), see
//! docs/light-transport.md, `## mlt`.

use super::sampler::MltSampler;
use crate::geometry::{Spectrum, Vec2};
use crate::scene::Scene;
use acr_plugins::RenderingSpace;

/// One evaluation of the path function: the radiance it carries to the film and where.
#[derive(Clone, Copy, Debug, Default)]
pub struct Contribution {
    /// The contribution (pbrt-v3's `L`'s value, already divided by its sampling density).
    pub l: Spectrum,
    /// The raster position it lands on (full-image coordinates).
    pub raster: Vec2,
    /// Rays traced for it.
    pub rays: u32,
}

/// The function of primary sample space whose paths of one length mlt's chains sample
/// (pbrt-v3's `MLTIntegrator::L`). Summed over depths 0 to [`PathContribution::max_depth`],
/// its expectation over the unit hypercube is the image (each pixel's radiance times the
/// raster area sampled): mlt's bootstrap estimates that total, and the chains its share per
/// pixel.
///
/// pbrt-v3's `L`, as `super::bdpt_path::BdptContribution` implements it:
///
/// 1. `start_stream(CAMERA_STREAM)`; for `depth` 0 the one strategy `s = 0, t = 2`
///    (`n_strategies = 1`), else `n_strategies = depth + 2`,
///    `s = min(floor(next_1d() * n_strategies), n_strategies - 1)`, `t = n_strategies - s`;
/// 2. the raster position `space.min + next_2d() * extent`, the time `next_1d()`, the lens
///    `next_2d()`; `generate_camera_subpath(.., t, ..)` (zero unless it made all `t` vertices);
/// 3. `start_stream(LIGHT_STREAM)`, `generate_light_subpath(.., s, ..)` (zero unless it made
///    all `s`); acr makes none for `s = 1`, whose light vertex the connection samples itself,
///    nor the camera ray for `t = 1`, which connects to a lens point of its own;
/// 4. `start_stream(CONNECTION_STREAM)`, `connect(.., s, t, ..)` (which may move the raster
///    position, for `t = 1`), times `n_strategies` (one strategy chosen uniformly of them).
pub trait PathContribution: Sync {
    /// The longest path, in scattering vertices (pbrt-v3's `maxdepth`).
    fn max_depth(&self) -> u32;

    /// The contribution of paths of exactly `depth` scattering vertices at the primary sample
    /// space point `sampler` holds, over the raster region `space`.
    fn l(
        &self,
        scene: &Scene,
        space: &RenderingSpace,
        sampler: &mut MltSampler,
        depth: u32,
    ) -> Contribution;
}

/// The raster position of `u` in [0, 1)^2 over `space`'s pixels, kept inside them (rounding
/// could carry it onto the far edge).
pub fn raster_position(space: &RenderingSpace, u: Vec2) -> Vec2 {
    let lo = Vec2::new(space.x0 as f32, space.y0 as f32);
    let hi = Vec2::new(space.x1 as f32, space.y1 as f32);
    let below = |v: f32| f32::from_bits(v.to_bits() - 1);
    (lo + u * (hi - lo)).min(Vec2::new(below(hi.x), below(hi.y)))
}
