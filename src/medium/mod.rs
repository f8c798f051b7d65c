//! Participating media (docs/media.md): pbrt-v3's homogeneous and grid-density media, the
//! Henyey-Greenstein phase function, the measured presets, and the interfaces surfaces put
//! between media. Only `volpath` reads them; `path` and `directlighting` ignore media as
//! pbrt-v3's do.

use crate::geometry::{Ray, Spectrum, Vec3};

mod build;
pub mod grid;
pub mod homogeneous;
pub mod phase;
pub mod presets;

pub use build::build_media;
pub use grid::Grid;
pub use homogeneous::Homogeneous;
pub use phase::HenyeyGreenstein;

/// A medium: how it attenuates and where it scatters, and its phase function.
#[derive(Clone, Debug)]
pub struct Medium {
    /// Its kind and coefficients.
    pub kind: MediumKind,
    /// The phase function at every point.
    pub phase: HenyeyGreenstein,
}

/// The two kinds pbrt-v3 has.
#[derive(Clone, Debug)]
pub enum MediumKind {
    /// `homogeneous`.
    Homogeneous(Homogeneous),
    /// `heterogeneous`: a density grid.
    Grid(Box<Grid>),
}

/// What sampling a distance along a ray in a medium gave: a scattering point (its ray
/// parameter) or none (the ray reaches its end), and the sample's weight (pbrt-v3's return
/// value of `Medium::Sample`: transmittance times sigma_s over the density, or one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumSample {
    /// The factor for the path's throughput.
    pub weight: Spectrum,
    /// The scattering point's ray parameter, if the path scatters in the medium.
    pub t: Option<f32>,
}

impl Medium {
    /// Transmittance along `ray` from its origin to parameter `t_max` (infinite for a ray that
    /// escapes), drawing numbers from `u` where the medium estimates it.
    #[inline]
    pub fn tr(&self, ray: &Ray, t_max: f32, u: &mut impl FnMut() -> f32) -> Spectrum {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.tr(t_max * ray.d.length()),
            MediumKind::Grid(g) => g.tr(ray.o, ray.d, t_max, u),
        }
    }

    /// Samples where along `ray` (up to parameter `t_max`) the path next scatters.
    #[inline]
    pub fn sample(&self, ray: &Ray, t_max: f32, u: &mut impl FnMut() -> f32) -> MediumSample {
        match &self.kind {
            MediumKind::Homogeneous(h) => h.sample(ray.d.length(), t_max, u),
            MediumKind::Grid(g) => g.sample(ray.o, ray.d, t_max, u),
        }
    }

    /// The single-scattering albedo sigma_s / sigma_t (zero where sigma_t is zero): what the
    /// first-hit albedo of a path that scatters in the medium first is (docs/media.md).
    pub fn albedo(&self) -> Spectrum {
        let ratio = |s: f32, t: f32| {
            if t > 0.0 {
                (s / t).clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        match &self.kind {
            MediumKind::Homogeneous(h) => Spectrum::new(
                ratio(h.sigma_s.x, h.sigma_t.x),
                ratio(h.sigma_s.y, h.sigma_t.y),
                ratio(h.sigma_s.z, h.sigma_t.z),
            ),
            MediumKind::Grid(g) => Spectrum::new(
                ratio(g.sigma_s.x, g.sigma_t),
                ratio(g.sigma_s.y, g.sigma_t),
                ratio(g.sigma_s.z, g.sigma_t),
            ),
        }
    }
}

/// The media on either side of a surface that separates two (pbrt-v3's `MediumInterface`
/// where `IsMediumTransition`): indices into the scene's media, `None` for vacuum.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MediumInterface {
    /// The medium behind the surface (against its normal).
    pub inside: Option<u32>,
    /// The medium in front of it (the side its normal points to).
    pub outside: Option<u32>,
}

impl MediumInterface {
    /// The medium a ray leaving the surface along `d` travels in, `n` the surface's
    /// geometric normal (pbrt-v3's `Interaction::GetMedium`).
    #[inline]
    pub fn toward(&self, n: Vec3, d: Vec3) -> Option<u32> {
        if d.dot(n) > 0.0 {
            self.outside
        } else {
            self.inside
        }
    }
}
