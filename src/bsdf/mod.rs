//! pbrt-v3's BxDFs and BSDF (core/reflection.{h,cpp}), for radiance transport, without heap
//! allocation: a [`Bsdf`] holds up to [`MAX_LOBES`] lobes by value, each a [`Bxdf`] enum with an
//! RGB scale (pbrt-v3's `ScaledBxDF`, used by the mix material).
//!
//! The lobes of pbrt-v3's Disney BSDF and of its hair are in [`disney`] and [`hair`]; what
//! every lobe shares (its kind, its sample, the microfacet steps) is a leaf below them all.
//!
//! The lobe slots beyond the ones a material adds are never written: building a BSDF costs
//! what its material needs, not its 0.7 kB (docs/BENCHMARKS.md, "The interiors: where the
//! time goes").
//!
//! Lobes work in the local shading frame (z = shading normal); [`Bsdf`] converts from world
//! space and decides reflection against transmission with the geometric normal, as pbrt-v3 does.
//! Where pbrt-v3 would produce NaN or infinity (grazing or degenerate directions), these return
//! zero, or no sample.

use crate::geometry::{Frame, Spectrum, SurfaceInteraction, Vec2, Vec3};
use std::mem::MaybeUninit;

mod bxdf;
pub mod disney;
mod fresnel;
pub mod hair;
mod lobe;

pub use bxdf::Bxdf;
pub use fresnel::{fr_conductor, fr_dielectric, reflect, refract, Fresnel};
pub use lobe::{BxdfType, LobeSample};
/// The most lobes a BSDF holds (pbrt-v3's `MaxBxDFs`).
pub const MAX_LOBES: usize = 8;

/// A lobe with its RGB weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lobe {
    /// The BxDF.
    pub bxdf: Bxdf,
    /// Its weight (1 unless mixed).
    pub scale: Spectrum,
}

/// A sampled direction from a [`Bsdf`], in world space.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Unit incident direction (world space), pointing away from the surface.
    pub wi: Vec3,
    /// BSDF value for (wo, wi).
    pub f: Spectrum,
    /// Density of `wi` (solid angle; for specular lobes, the discrete probability).
    pub pdf: f32,
    /// Whether a specular (delta) lobe was sampled.
    pub specular: bool,
}

/// pbrt-v3's BSDF: lobes in a shading frame, with the geometric normal and the relative index
/// of refraction (for Russian roulette's radiance scaling through refraction).
#[derive(Clone)]
pub struct Bsdf {
    frame: Frame,
    ng: Vec3,
    eta: f32,
    len: usize,
    // Only the first `len` slots are initialised (every write goes through `add_scaled`, the
    // only reads through `lobes`): a hit pays for the lobes its material adds, not for eight.
    lobes: [MaybeUninit<Lobe>; MAX_LOBES],
}

impl std::fmt::Debug for Bsdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bsdf")
            .field("frame", &self.frame)
            .field("ng", &self.ng)
            .field("eta", &self.eta)
            .field("lobes", &self.lobes())
            .finish()
    }
}

impl Bsdf {
    /// An empty BSDF at `si`: shading frame from `si.shading_n` and `si.shading_dpdu`, geometric
    /// normal `si.n`, relative index `eta` (1 for surfaces that do not refract).
    // Inlined so that the (large) BSDF is built in place rather than copied out.
    #[inline]
    pub fn new(si: &SurfaceInteraction, eta: f32) -> Self {
        Self::from_frame(Frame::from_xz(si.shading_dpdu, si.shading_n), si.n, eta)
    }

    /// An empty BSDF with the given shading frame and geometric normal.
    #[inline]
    pub fn from_frame(frame: Frame, ng: Vec3, eta: f32) -> Self {
        Self {
            frame,
            ng,
            eta,
            len: 0,
            lobes: [MaybeUninit::uninit(); MAX_LOBES],
        }
    }

    /// An empty BSDF with the identity frame, for a caller to fill in place with
    /// [`Bsdf::reset`] (or [`crate::material::Material::bsdf_into`]) at each hit: returning a
    /// BSDF by value copies it.
    #[inline]
    pub fn empty() -> Self {
        Self::from_frame(Frame::from_z(Vec3::Z), Vec3::Z, 1.0)
    }

    /// Makes this BSDF [`Bsdf::new`]'s for `si` and `eta`, in place: the lobe slots are left
    /// as they are (only the first `len` are read), so that a BSDF kept from one hit to the
    /// next is refilled without moving its 0.7 kB.
    #[inline]
    pub fn reset(&mut self, si: &SurfaceInteraction, eta: f32) {
        self.frame = Frame::from_xz(si.shading_dpdu, si.shading_n);
        self.ng = si.n;
        self.eta = eta;
        self.len = 0;
    }

    /// Removes every lobe (the BSDF is then black: a vertex whose scattering nothing reads).
    #[inline]
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Adds a lobe with weight 1; returns false (and adds nothing) when full.
    #[inline]
    pub fn add(&mut self, bxdf: Bxdf) -> bool {
        self.add_scaled(bxdf, Spectrum::ONE)
    }

    /// Adds a lobe with an RGB weight; returns false (and adds nothing) when full.
    #[inline]
    pub fn add_scaled(&mut self, bxdf: Bxdf, scale: Spectrum) -> bool {
        if self.len == MAX_LOBES {
            return false;
        }
        self.lobes[self.len] = MaybeUninit::new(Lobe { bxdf, scale });
        self.len += 1;
        true
    }

    /// Sets the relative index of refraction (inside over outside).
    #[inline]
    pub fn set_eta(&mut self, eta: f32) {
        self.eta = eta;
    }

    /// Multiplies every lobe's weight by `s`.
    pub fn scale_lobes(&mut self, s: Spectrum) {
        let len = self.len;
        // SAFETY: the first `len` slots were written by `add_scaled` (`len` grows only there,
        // after the write, and never past MAX_LOBES), and MaybeUninit<Lobe> has Lobe's layout.
        let lobes =
            unsafe { std::slice::from_raw_parts_mut(self.lobes.as_mut_ptr().cast::<Lobe>(), len) };
        for l in lobes {
            l.scale *= s;
        }
    }

    /// The lobes.
    #[inline]
    pub fn lobes(&self) -> &[Lobe] {
        debug_assert!(self.len <= MAX_LOBES);
        // SAFETY: as in `scale_lobes`: the first `len` slots are initialised.
        unsafe { std::slice::from_raw_parts(self.lobes.as_ptr().cast::<Lobe>(), self.len) }
    }

    /// Number of lobes.
    pub fn num_lobes(&self) -> usize {
        self.len
    }

    /// The relative index of refraction (inside over outside) of a refracting surface, else 1.
    pub fn eta(&self) -> f32 {
        self.eta
    }

    /// The shading frame.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The geometric normal.
    pub fn ng(&self) -> Vec3 {
        self.ng
    }

    /// The albedo for first-hit features: each lobe's nominal reflectance or transmittance
    /// (its `r`, `t`, or `rd + rs`) times its weight, summed and kept in [0, 1].
    pub fn albedo(&self) -> Spectrum {
        let sum: Spectrum = self
            .lobes()
            .iter()
            .map(|l| {
                let nominal = match l.bxdf {
                    Bxdf::Lambertian { r }
                    | Bxdf::OrenNayar { r, .. }
                    | Bxdf::SpecularReflection { r, .. }
                    | Bxdf::MicrofacetReflection { r, .. } => r,
                    Bxdf::SpecularTransmission { t, .. }
                    | Bxdf::LambertianTransmission { t }
                    | Bxdf::MicrofacetTransmission { t, .. } => t,
                    Bxdf::FresnelSpecular { r, t, .. } => r.max(t),
                    Bxdf::FresnelBlend { rd, rs, .. } => rd + rs,
                    Bxdf::Hair(h) => h.albedo(),
                    Bxdf::Disney(d) => d.albedo(),
                    Bxdf::Fourier(t) => t.table.albedo(),
                    Bxdf::BssrdfAdapter { .. } => Spectrum::ONE,
                };
                nominal * l.scale
            })
            .sum();
        sum.clamp(Spectrum::ZERO, Spectrum::ONE)
    }

    /// Whether any lobe is not a delta distribution (so light sampling can help).
    pub fn has_non_specular(&self) -> bool {
        self.lobes().iter().any(|l| !l.bxdf.is_specular())
    }

    /// The BSDF for world directions `wo` and `wi` (both pointing away from the surface):
    /// reflection lobes when both are on the same side of the geometric normal, transmission
    /// lobes otherwise.
    pub fn f(&self, wo_world: Vec3, wi_world: Vec3) -> Spectrum {
        let wo = self.frame.to_local(wo_world);
        let wi = self.frame.to_local(wi_world);
        if wo.z == 0.0 {
            return Spectrum::ZERO;
        }
        let reflect = wi_world.dot(self.ng) * wo_world.dot(self.ng) > 0.0;
        let f = self.sum_f(wo, wi, reflect);
        if f.is_finite() {
            f
        } else {
            Spectrum::ZERO
        }
    }

    fn sum_f(&self, wo: Vec3, wi: Vec3, reflect: bool) -> Spectrum {
        let wanted = if reflect {
            BxdfType::REFLECTION
        } else {
            BxdfType::TRANSMISSION
        };
        self.lobes()
            .iter()
            .filter(|l| l.bxdf.kind().contains(wanted))
            .map(|l| l.scale * l.bxdf.f(wo, wi))
            .sum()
    }

    /// Samples an incident direction: a lobe chosen uniformly with `u_lobe`, then sampled with
    /// `u`. For a non-specular lobe, the value and density are those of the whole BSDF (the
    /// other lobes' values added, the densities averaged), as in pbrt-v3's `BSDF::Sample_f`.
    /// `None` when nothing can be sampled.
    pub fn sample_f(&self, wo_world: Vec3, u: Vec2, u_lobe: f32) -> Option<BsdfSample> {
        let n = self.len;
        if n == 0 {
            return None;
        }
        let comp = ((u_lobe * n as f32) as usize).min(n - 1);
        let wo = self.frame.to_local(wo_world);
        if wo.z == 0.0 {
            return None;
        }
        let lobe = &self.lobes()[comp];
        let s = lobe.bxdf.sample_f(wo, u)?;
        let wi_world = self.frame.from_local(s.wi);
        let specular = s.kind.contains(BxdfType::SPECULAR);
        let mut pdf = s.pdf;
        let mut f = lobe.scale * s.f;
        if !specular {
            // As pbrt-v3, with one lobe too: a direction on the other side of the geometric
            // surface than a reflection lobe allows gives nothing (it applied only with several
            // lobes, so a bumped or smooth-shaded matte lit the sky below its surface: +0.45%
            // on scenes/pbrt-v3/bump-map.pbrt's floor under the sky alone).
            let reflect = wi_world.dot(self.ng) * wo_world.dot(self.ng) > 0.0;
            let wanted = if reflect {
                BxdfType::REFLECTION
            } else {
                BxdfType::TRANSMISSION
            };
            // `sum_f`'s sum in its order, where the sampled lobe's value is the sample's own
            // when that is its `f` (not evaluated twice: a microfacet lobe's costs).
            let reuse = lobe.bxdf.sample_is_f();
            f = Spectrum::ZERO;
            for (i, other) in self.lobes().iter().enumerate() {
                if i != comp {
                    pdf += other.bxdf.pdf(wo, s.wi);
                }
                if other.bxdf.kind().contains(wanted) {
                    f += if i == comp && reuse {
                        lobe.scale * s.f
                    } else {
                        other.scale * other.bxdf.f(wo, s.wi)
                    };
                }
            }
        }
        if n > 1 {
            pdf /= n as f32;
        }
        if !pdf.is_finite() || pdf <= 0.0 || !f.is_finite() || !wi_world.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi: wi_world,
            f,
            pdf,
            specular,
        })
    }

    /// Samples specular lobe `index` alone, as pbrt-v3's `SpecularReflect` and
    /// `SpecularTransmit` ask `BSDF::Sample_f` for one type: its weighted value and its own
    /// probability. `None` for a lobe that is not specular or gives nothing.
    pub fn sample_specular_lobe(
        &self,
        wo_world: Vec3,
        u: Vec2,
        index: usize,
    ) -> Option<BsdfSample> {
        let lobe = self.lobes().get(index)?;
        if !lobe.bxdf.is_specular() {
            return None;
        }
        let wo = self.frame.to_local(wo_world);
        if wo.z == 0.0 {
            return None;
        }
        let s = lobe.bxdf.sample_f(wo, u)?;
        let wi = self.frame.from_local(s.wi);
        let f = lobe.scale * s.f;
        if !(s.pdf > 0.0 && s.pdf.is_finite() && f.is_finite() && wi.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi,
            f,
            pdf: s.pdf,
            specular: true,
        })
    }

    /// Density with which [`Bsdf::sample_f`] picks world direction `wi` given `wo` (specular
    /// lobes count as zero).
    pub fn pdf(&self, wo_world: Vec3, wi_world: Vec3) -> f32 {
        let n = self.len;
        if n == 0 {
            return 0.0;
        }
        let wo = self.frame.to_local(wo_world);
        let wi = self.frame.to_local(wi_world);
        if wo.z == 0.0 {
            return 0.0;
        }
        let sum: f32 = self.lobes().iter().map(|l| l.bxdf.pdf(wo, wi)).sum();
        let p = sum / n as f32;
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }
}

#[cfg(test)]
pub(crate) mod check;

#[cfg(test)]
mod tests;
