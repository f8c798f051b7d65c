//! pbrt-v3's `matte` material (materials/matte.cpp): Lambertian, or Oren-Nayar when `sigma`
//! is positive.

use super::shared::{clamp0, is_black};
use crate::bsdf::{Bsdf, Bxdf};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{FloatTexture, SpectrumTexture, Texture, TextureBuilder};
use acr_parser::{ParamList, Result};

/// Lambertian, or Oren-Nayar when `sigma` (degrees) is positive.
#[derive(Clone, Debug)]
pub struct Matte {
    /// Diffuse reflectance.
    pub kd: SpectrumTexture,
    /// Oren-Nayar roughness in degrees, clamped to [0, 90].
    pub sigma: FloatTexture,
}

impl Default for Matte {
    /// pbrt's default material: `Kd` 0.5, Lambertian.
    fn default() -> Self {
        Self {
            kd: Texture::Constant(Spectrum::splat(0.5)),
            sigma: Texture::Constant(0.0),
        }
    }
}

impl Matte {
    /// The material from its parameters (`Kd` 0.5, `sigma` 0).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList) -> Result<Self> {
        Ok(Self {
            kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.5))?,
            sigma: t.float_param(p, "sigma", 0.0)?,
        })
    }

    /// Adds its lobe to `b`, weighted by `scale`: none where `Kd` is black.
    #[inline]
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum) {
        let r = clamp0(self.kd.eval(si));
        let sig = self.sigma.eval(si).clamp(0.0, 90.0);
        if !is_black(r) {
            if sig == 0.0 {
                b.add_scaled(Bxdf::Lambertian { r }, scale);
            } else {
                b.add_scaled(Bxdf::oren_nayar(r, sig), scale);
            }
        }
    }
}
