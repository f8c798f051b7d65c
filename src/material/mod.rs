//! pbrt-v3's materials (materials/*.cpp), one type per material, each in its own file: matte,
//! plastic, mirror, glass, metal, uber, substrate, translucent, hair, disney, fourier, and
//! subsurface and kdsubsurface (whose [`Material::bssrdf`] the path integrator samples), with
//! textured parameters, each turning a hit into a [`Bsdf`]'s lobes as pbrt-v3's
//! `ComputeScatteringFunctions` does (radiance transport, several lobes allowed as the path
//! integrator asks). [`Material`] is the enum a hit dispatches on; mix and bump mapping wrap
//! other materials and live here.
//!
//! Bump mapping (`bumpmap` on every material) is [`crate::bump`]'s. Not supported: per-shape
//! overrides of material parameters (pbrt-v3 lets a `Shape` carry `Kd` and the like).

use crate::bsdf::Bsdf;
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{FloatTexture, SpectrumTexture};
use std::sync::Arc;

mod build;
pub mod disney;
pub mod fourier;
pub mod glass;
pub mod hair;
pub mod matte;
pub mod metal;
pub mod mirror;
pub mod plastic;
mod shared;
pub mod substrate;
pub mod subsurface;
pub mod translucent;
pub mod uber;

pub use build::build_materials;
pub use disney::DisneyMaterial;
pub use fourier::Fourier;
pub use glass::Glass;
pub use hair::HairMaterial;
pub use matte::Matte;
pub use metal::{Metal, COPPER_ETA, COPPER_K};
pub use mirror::Mirror;
pub use plastic::Plastic;
pub use substrate::Substrate;
pub use subsurface::Subsurface;
pub use translucent::Translucent;
pub use uber::Uber;

/// A surface's material, its parameters possibly textured.
// Materials are built once and kept in one Vec; boxing the large variants would add a pointer
// chase to every hit for no memory worth saving.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Material {
    /// Lambertian, or Oren-Nayar when `sigma` (degrees) is positive.
    Matte(Matte),
    /// Diffuse plus a glossy dielectric coat.
    Plastic(Plastic),
    /// A perfect mirror.
    Mirror(Mirror),
    /// A dielectric, smooth or rough.
    Glass(Glass),
    /// A rough conductor.
    Metal(Metal),
    /// pbrt-v3's uber material: diffuse, glossy, specular reflection and transmission, opacity.
    Uber(Uber),
    /// Glossy coat over a diffuse base (pbrt-v3's `FresnelBlend`).
    Substrate(Substrate),
    /// pbrt-v3's `translucent`: diffuse and glossy reflection and transmission.
    Translucent(Translucent),
    /// pbrt-v3's hair (Chiang et al.'s fibre scattering), for curves.
    Hair(HairMaterial),
    /// pbrt-v3's `fourier`: a BSDF tabulated in a `.bsdf` file.
    Fourier(Fourier),
    /// pbrt-v3's `disney`.
    Disney(Box<DisneyMaterial>),
    /// pbrt-v3's `subsurface` or `kdsubsurface`: a dielectric boundary over a scattering
    /// medium (docs/subsurface.md).
    Subsurface(Box<Subsurface>),
    /// pbrt-v3's mix: the lobes of `materials[0]` weighted by `amount`, those of `materials[1]`
    /// by 1 - amount.
    Mix {
        /// Weight of the first material.
        amount: SpectrumTexture,
        /// `namedmaterial1` and `namedmaterial2`.
        materials: [Arc<Material>; 2],
    },
    /// A material with a `bumpmap`: its shading geometry bumped by the displacement texture
    /// ([`Material::shading`]), its lobes the inner material's.
    Bumped {
        /// The displacement.
        map: Arc<FloatTexture>,
        /// The material bumped.
        inner: Arc<Material>,
    },
    /// No surface (`"none"`, `"interface"`): an empty BSDF. A renderer should let rays pass
    /// through shapes with this material, as pbrt-v3 does for `Material ""`.
    Interface,
}

impl Material {
    /// pbrt's default material: matte with Kd 0.5.
    pub fn default_matte() -> Self {
        Material::Matte(Matte::default())
    }

    /// Whether the material makes no surface (rays should pass through).
    pub fn is_interface(&self) -> bool {
        matches!(self, Material::Interface)
    }

    /// The hit as this material shades it: with its shading geometry bumped when the material
    /// has a `bumpmap` (pbrt-v3's `Material::Bump`, called first in every material's
    /// `ComputeScatteringFunctions`); a mix takes its first material's, as pbrt-v3's mix
    /// builds its BSDF in the frame its first material left. Integrators shade and take
    /// cosines with the result.
    pub fn shading(&self, si: &SurfaceInteraction) -> SurfaceInteraction {
        match self {
            Material::Bumped { map, .. } => crate::bump::bump(map, si),
            Material::Mix { materials, .. } => materials[0].shading(si),
            _ => *si,
        }
    }

    /// [`Material::shading`] in place: `si` is left as it is unless the material bumps it
    /// (an interaction is about 180 bytes, and each hit of a path copied it).
    #[inline]
    pub fn shade(&self, si: &mut SurfaceInteraction) {
        match self {
            Material::Bumped { map, .. } => *si = crate::bump::bump(map, si),
            Material::Mix { materials, .. } => materials[0].shade(si),
            _ => {}
        }
    }

    /// The BSSRDF at (shaded) hit `si`, for a subsurface material (bumped or not); `None`
    /// otherwise. A mix gives none: pbrt-v3's mix leaves its first material's BSSRDF, whose
    /// probe rays then look for that material and never find the mix, so its paths end.
    pub fn bssrdf(&self, si: &SurfaceInteraction) -> Option<crate::bssrdf::TabulatedBssrdf<'_>> {
        match self {
            Material::Subsurface(m) => Some(m.bssrdf(si)),
            Material::Bumped { inner, .. } => inner.bssrdf(si),
            _ => None,
        }
    }

    /// The BSDF at a hit (several lobes allowed, as pbrt-v3's path integrators ask: a smooth
    /// glass is one `FresnelSpecular` lobe).
    pub fn bsdf(&self, si: &SurfaceInteraction) -> Bsdf {
        self.bsdf_with(si, true)
    }

    /// The BSDF at a hit. With `allow_multiple_lobes` false (pbrt-v3's direct-lighting and
    /// Whitted integrators), a smooth glass gets separate specular reflection and transmission
    /// lobes instead of one `FresnelSpecular`.
    #[inline]
    pub fn bsdf_with(&self, si: &SurfaceInteraction, allow_multiple_lobes: bool) -> Bsdf {
        // Built in place: a Bsdf is about 700 bytes, and returning one from each arm copied it
        // (2-4% of a render in memcpy, perf).
        let mut b = Bsdf::new(si, 1.0);
        self.add_lobes(si, allow_multiple_lobes, &mut b, Spectrum::ONE, true);
        b
    }

    /// [`Material::bsdf`] written into `b` (whatever it held): bdpt's vertices keep their
    /// BSDFs from path to path and refill them in place.
    #[inline]
    pub fn bsdf_into(&self, si: &SurfaceInteraction, b: &mut Bsdf) {
        b.reset(si, 1.0);
        self.add_lobes(si, true, b, Spectrum::ONE, true);
    }

    /// Adds this material's lobes to `b`, each weighted by `scale`; `first` (the material that
    /// owns the BSDF, as pbrt-v3's mix keeps its first material's) sets the relative index.
    /// Each material's own `add_lobes` takes what it needs of these.
    fn add_lobes(
        &self,
        si: &SurfaceInteraction,
        allow_multiple_lobes: bool,
        b: &mut Bsdf,
        scale: Spectrum,
        first: bool,
    ) {
        match self {
            Material::Matte(m) => m.add_lobes(si, b, scale),
            Material::Plastic(m) => m.add_lobes(si, b, scale),
            Material::Mirror(m) => m.add_lobes(si, b, scale),
            Material::Glass(m) => m.add_lobes(si, allow_multiple_lobes, b, scale, first),
            Material::Metal(m) => m.add_lobes(si, b, scale),
            Material::Uber(m) => m.add_lobes(si, b, scale, first),
            Material::Substrate(m) => m.add_lobes(si, b, scale),
            Material::Translucent(m) => m.add_lobes(si, b, scale, first),
            Material::Hair(m) => m.add_lobes(si, b, scale, first),
            Material::Disney(m) => m.add_lobes(si, b, scale),
            Material::Fourier(m) => m.add_lobes(b, scale),
            Material::Subsurface(m) => m.add_lobes(si, allow_multiple_lobes, b, scale, first),
            Material::Mix { amount, materials } => {
                let s1 = shared::clamp0(amount.eval(si));
                let s2 = shared::clamp0(Spectrum::ONE - s1);
                // pbrt-v3 asserts when more than 8 lobes result; acr drops the extras.
                materials[0].add_lobes(si, allow_multiple_lobes, b, s1 * scale, first);
                materials[1].add_lobes(si, allow_multiple_lobes, b, s2 * scale, false);
            }
            Material::Bumped { inner, .. } => {
                inner.add_lobes(si, allow_multiple_lobes, b, scale, first)
            }
            Material::Interface => {}
        }
    }
}

#[cfg(test)]
mod tests;
