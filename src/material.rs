//! pbrt-v3's materials (materials/*.cpp): matte, plastic, mirror, glass, metal, uber, substrate,
//! translucent, hair ([`crate::hair`]), disney ([`crate::disney`]) and mix, with textured
//! parameters, each turning a hit into a [`Bsdf`] as pbrt-v3's `ComputeScatteringFunctions` does
//! (radiance transport, several lobes allowed as the path integrator asks).
//!
//! Bump mapping (`bumpmap` on every material) is [`crate::bump`]'s. Not supported: per-shape
//! overrides of material parameters (pbrt-v3 lets a `Shape` carry `Kd` and the like), and the
//! subsurface, kdsubsurface and fourier materials (replaced by a matte with the
//! material's `Kd`, with a warning).

use crate::bsdf::{Bsdf, Bxdf, Fresnel};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::microfacet::{roughness_to_alpha, TrowbridgeReitz};
use crate::texture::{FloatTexture, SpectrumTexture, Texture};
use std::sync::Arc;

/// pbrt-v3's copper (metal.cpp's tables through `RGBSpectrum::FromSampled`): the metal
/// material's default `eta`.
pub const COPPER_ETA: Spectrum = Spectrum::new(0.200438, 0.924033, 1.10221);
/// pbrt-v3's copper absorption: the metal material's default `k`.
pub const COPPER_K: Spectrum = Spectrum::new(3.91295, 2.45285, 2.14219);

/// A surface's material, its parameters possibly textured.
// Materials are built once and kept in one Vec; boxing the large variants would add a pointer
// chase to every hit for no memory worth saving.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Material {
    /// Lambertian, or Oren-Nayar when `sigma` (degrees) is positive.
    Matte {
        /// Diffuse reflectance.
        kd: SpectrumTexture,
        /// Oren-Nayar roughness in degrees, clamped to [0, 90].
        sigma: FloatTexture,
    },
    /// Diffuse plus a glossy dielectric coat (pbrt-v3's Fresnel 1.5 -> 1 quirk included).
    Plastic {
        /// Diffuse reflectance.
        kd: SpectrumTexture,
        /// Glossy reflectance.
        ks: SpectrumTexture,
        /// Roughness of the coat.
        roughness: FloatTexture,
        /// Whether roughness goes through `roughness_to_alpha`.
        remap_roughness: bool,
    },
    /// A perfect mirror.
    Mirror {
        /// Reflectance.
        kr: SpectrumTexture,
    },
    /// A dielectric, smooth or rough.
    Glass {
        /// Reflectance scale.
        kr: SpectrumTexture,
        /// Transmittance scale.
        kt: SpectrumTexture,
        /// Index of refraction inside.
        eta: FloatTexture,
        /// Roughness along the tangent.
        u_roughness: FloatTexture,
        /// Roughness along the bitangent.
        v_roughness: FloatTexture,
        /// Whether roughness goes through `roughness_to_alpha`.
        remap_roughness: bool,
    },
    /// A rough conductor.
    Metal {
        /// Real part of the index of refraction.
        eta: SpectrumTexture,
        /// Absorption coefficient.
        k: SpectrumTexture,
        /// Roughness (both directions unless overridden).
        roughness: FloatTexture,
        /// Roughness along the tangent, overriding `roughness`.
        u_roughness: Option<FloatTexture>,
        /// Roughness along the bitangent, overriding `roughness`.
        v_roughness: Option<FloatTexture>,
        /// Whether roughness goes through `roughness_to_alpha`.
        remap_roughness: bool,
    },
    /// pbrt-v3's uber material: diffuse, glossy, specular reflection and transmission, opacity.
    Uber {
        /// Diffuse reflectance.
        kd: SpectrumTexture,
        /// Glossy reflectance.
        ks: SpectrumTexture,
        /// Specular reflectance.
        kr: SpectrumTexture,
        /// Specular transmittance.
        kt: SpectrumTexture,
        /// Roughness (both directions unless overridden).
        roughness: FloatTexture,
        /// Roughness along the tangent, overriding `roughness`.
        u_roughness: Option<FloatTexture>,
        /// Roughness along the bitangent (defaults to the tangent's).
        v_roughness: Option<FloatTexture>,
        /// Index of refraction.
        eta: FloatTexture,
        /// Opacity: below 1, a straight-through transmission lobe of 1 - opacity.
        opacity: SpectrumTexture,
        /// Whether roughness goes through `roughness_to_alpha`.
        remap_roughness: bool,
    },
    /// Glossy coat over a diffuse base (pbrt-v3's `FresnelBlend`).
    Substrate {
        /// Diffuse reflectance.
        kd: SpectrumTexture,
        /// Specular reflectance at normal incidence.
        ks: SpectrumTexture,
        /// Roughness along the tangent.
        u_roughness: FloatTexture,
        /// Roughness along the bitangent.
        v_roughness: FloatTexture,
        /// Whether roughness goes through `roughness_to_alpha`.
        remap_roughness: bool,
    },
    /// pbrt-v3's `translucent`: diffuse and glossy reflection weighted by `reflect`, diffuse
    /// and glossy transmission weighted by `transmit` (index 1.5).
    Translucent {
        /// Diffuse reflectance and transmittance.
        kd: SpectrumTexture,
        /// Glossy reflectance and transmittance.
        ks: SpectrumTexture,
        /// Share reflected.
        reflect: SpectrumTexture,
        /// Share transmitted.
        transmit: SpectrumTexture,
        /// Microfacet roughness.
        roughness: FloatTexture,
        /// Whether roughness goes through `roughness_to_alpha`.
        remap_roughness: bool,
    },
    /// pbrt-v3's hair (Chiang et al.'s fibre scattering, [`crate::hair`]), for curves: its
    /// absorption from `sigma_a`, `color` or melanin concentrations, `eta`, `beta_m`, `beta_n`,
    /// `alpha`.
    Hair(crate::hair::HairMaterial),
    /// pbrt-v3's `fourier`: a BSDF tabulated in a `.bsdf` file.
    Fourier(crate::fourier::FourierBsdf),
    /// pbrt-v3's `disney` ([`crate::disney`]).
    Disney(Box<crate::disney::DisneyMaterial>),
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

/// pbrt-v3's `Spectrum::Clamp()`: negative channels to zero.
#[inline]
fn clamp0(s: Spectrum) -> Spectrum {
    s.max(Spectrum::ZERO)
}

#[inline]
fn is_black(s: Spectrum) -> bool {
    s == Spectrum::ZERO
}

/// A Trowbridge-Reitz distribution from roughnesses, remapped or not.
#[inline]
fn distribution(u: f32, v: f32, remap: bool) -> TrowbridgeReitz {
    if remap {
        TrowbridgeReitz::new(roughness_to_alpha(u), roughness_to_alpha(v))
    } else {
        TrowbridgeReitz::new(u, v)
    }
}

impl Material {
    /// pbrt's default material: matte with Kd 0.5.
    pub fn default_matte() -> Self {
        Material::Matte {
            kd: Texture::Constant(Spectrum::splat(0.5)),
            sigma: Texture::Constant(0.0),
        }
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

    /// Adds this material's lobes to `b`, each weighted by `scale`; `first` (the material that
    /// owns the BSDF, as pbrt-v3's mix keeps its first material's) sets the relative index.
    fn add_lobes(
        &self,
        si: &SurfaceInteraction,
        allow_multiple_lobes: bool,
        b: &mut Bsdf,
        scale: Spectrum,
        first: bool,
    ) {
        match self {
            Material::Matte { kd, sigma } => {
                let r = clamp0(kd.eval(si));
                let sig = sigma.eval(si).clamp(0.0, 90.0);
                if !is_black(r) {
                    if sig == 0.0 {
                        b.add_scaled(Bxdf::Lambertian { r }, scale);
                    } else {
                        b.add_scaled(Bxdf::oren_nayar(r, sig), scale);
                    }
                }
            }
            Material::Plastic {
                kd,
                ks,
                roughness,
                remap_roughness,
            } => {
                let kd = clamp0(kd.eval(si));
                if !is_black(kd) {
                    b.add_scaled(Bxdf::Lambertian { r: kd }, scale);
                }
                let ks = clamp0(ks.eval(si));
                if !is_black(ks) {
                    let rough = roughness.eval(si);
                    b.add_scaled(
                        Bxdf::MicrofacetReflection {
                            r: ks,
                            distribution: distribution(rough, rough, *remap_roughness),
                            // pbrt-v3 builds this Fresnel with the indices swapped.
                            fresnel: Fresnel::Dielectric {
                                eta_i: 1.5,
                                eta_t: 1.0,
                            },
                        },
                        scale,
                    );
                }
            }
            Material::Mirror { kr } => {
                let r = clamp0(kr.eval(si));
                if !is_black(r) {
                    b.add_scaled(
                        Bxdf::SpecularReflection {
                            r,
                            fresnel: Fresnel::NoOp,
                        },
                        scale,
                    );
                }
            }
            Material::Glass {
                kr,
                kt,
                eta,
                u_roughness,
                v_roughness,
                remap_roughness,
            } => {
                let eta = eta.eval(si);
                let (urough, vrough) = (u_roughness.eval(si), v_roughness.eval(si));
                let r = clamp0(kr.eval(si));
                let t = clamp0(kt.eval(si));
                if first {
                    b.set_eta(eta);
                }
                if is_black(r) && is_black(t) {
                    return;
                }
                let specular = urough == 0.0 && vrough == 0.0;
                if specular && allow_multiple_lobes {
                    b.add_scaled(
                        Bxdf::FresnelSpecular {
                            r,
                            t,
                            eta_a: 1.0,
                            eta_b: eta,
                        },
                        scale,
                    );
                    return;
                }
                let dist = distribution(urough, vrough, *remap_roughness);
                if !is_black(r) {
                    let fresnel = Fresnel::Dielectric {
                        eta_i: 1.0,
                        eta_t: eta,
                    };
                    b.add_scaled(
                        if specular {
                            Bxdf::SpecularReflection { r, fresnel }
                        } else {
                            Bxdf::MicrofacetReflection {
                                r,
                                distribution: dist,
                                fresnel,
                            }
                        },
                        scale,
                    );
                }
                if !is_black(t) {
                    b.add_scaled(
                        if specular {
                            Bxdf::SpecularTransmission {
                                t,
                                eta_a: 1.0,
                                eta_b: eta,
                            }
                        } else {
                            Bxdf::MicrofacetTransmission {
                                t,
                                distribution: dist,
                                eta_a: 1.0,
                                eta_b: eta,
                            }
                        },
                        scale,
                    );
                }
            }
            Material::Metal {
                eta,
                k,
                roughness,
                u_roughness,
                v_roughness,
                remap_roughness,
            } => {
                let u = u_roughness
                    .as_ref()
                    .map_or_else(|| roughness.eval(si), |t| t.eval(si));
                let v = v_roughness
                    .as_ref()
                    .map_or_else(|| roughness.eval(si), |t| t.eval(si));
                b.add_scaled(
                    Bxdf::MicrofacetReflection {
                        r: Spectrum::ONE,
                        distribution: distribution(u, v, *remap_roughness),
                        fresnel: Fresnel::Conductor {
                            eta_i: Spectrum::ONE,
                            eta_t: eta.eval(si),
                            k: k.eval(si),
                        },
                    },
                    scale,
                );
            }
            Material::Uber {
                kd,
                ks,
                kr,
                kt,
                roughness,
                u_roughness,
                v_roughness,
                eta,
                opacity,
                remap_roughness,
            } => {
                let e = eta.eval(si);
                let op = clamp0(opacity.eval(si));
                let t = clamp0(Spectrum::ONE - op);
                if !is_black(t) {
                    b.add_scaled(
                        Bxdf::SpecularTransmission {
                            t,
                            eta_a: 1.0,
                            eta_b: 1.0,
                        },
                        scale,
                    );
                } else if first {
                    b.set_eta(e);
                }
                let kd = op * clamp0(kd.eval(si));
                if !is_black(kd) {
                    b.add_scaled(Bxdf::Lambertian { r: kd }, scale);
                }
                let ks = op * clamp0(ks.eval(si));
                if !is_black(ks) {
                    let u = u_roughness
                        .as_ref()
                        .map_or_else(|| roughness.eval(si), |t| t.eval(si));
                    let v = v_roughness.as_ref().map_or(u, |t| t.eval(si));
                    b.add_scaled(
                        Bxdf::MicrofacetReflection {
                            r: ks,
                            distribution: distribution(u, v, *remap_roughness),
                            fresnel: Fresnel::Dielectric {
                                eta_i: 1.0,
                                eta_t: e,
                            },
                        },
                        scale,
                    );
                }
                let kr = op * clamp0(kr.eval(si));
                if !is_black(kr) {
                    b.add_scaled(
                        Bxdf::SpecularReflection {
                            r: kr,
                            fresnel: Fresnel::Dielectric {
                                eta_i: 1.0,
                                eta_t: e,
                            },
                        },
                        scale,
                    );
                }
                let kt = op * clamp0(kt.eval(si));
                if !is_black(kt) {
                    b.add_scaled(
                        Bxdf::SpecularTransmission {
                            t: kt,
                            eta_a: 1.0,
                            eta_b: e,
                        },
                        scale,
                    );
                }
            }
            Material::Substrate {
                kd,
                ks,
                u_roughness,
                v_roughness,
                remap_roughness,
            } => {
                let d = clamp0(kd.eval(si));
                let s = clamp0(ks.eval(si));
                if !is_black(d) || !is_black(s) {
                    let (u, v) = (u_roughness.eval(si), v_roughness.eval(si));
                    b.add_scaled(
                        Bxdf::FresnelBlend {
                            rd: d,
                            rs: s,
                            distribution: distribution(u, v, *remap_roughness),
                        },
                        scale,
                    );
                }
            }
            Material::Translucent {
                kd,
                ks,
                reflect,
                transmit,
                roughness,
                remap_roughness,
            } => {
                // pbrt-v3's TranslucentMaterial::ComputeScatteringFunctions.
                const ETA: f32 = 1.5;
                if first {
                    b.set_eta(ETA);
                }
                let (r, t) = (clamp0(reflect.eval(si)), clamp0(transmit.eval(si)));
                if is_black(r) && is_black(t) {
                    return;
                }
                let kd = clamp0(kd.eval(si));
                if !is_black(kd) {
                    if !is_black(r) {
                        b.add_scaled(Bxdf::Lambertian { r: r * kd }, scale);
                    }
                    if !is_black(t) {
                        b.add_scaled(Bxdf::LambertianTransmission { t: t * kd }, scale);
                    }
                }
                let ks = clamp0(ks.eval(si));
                if !is_black(ks) {
                    let rough = roughness.eval(si);
                    let dist = distribution(rough, rough, *remap_roughness);
                    if !is_black(r) {
                        let fresnel = Fresnel::Dielectric {
                            eta_i: 1.0,
                            eta_t: ETA,
                        };
                        b.add_scaled(
                            Bxdf::MicrofacetReflection {
                                r: r * ks,
                                distribution: dist,
                                fresnel,
                            },
                            scale,
                        );
                    }
                    if !is_black(t) {
                        b.add_scaled(
                            Bxdf::MicrofacetTransmission {
                                t: t * ks,
                                distribution: dist,
                                eta_a: 1.0,
                                eta_b: ETA,
                            },
                            scale,
                        );
                    }
                }
            }
            Material::Hair(hair) => {
                let (bxdf, eta) = hair.bxdf(si);
                if first {
                    b.set_eta(eta);
                }
                b.add_scaled(Bxdf::Hair(bxdf), scale);
            }
            // pbrt-v3's Disney BSDF keeps the relative index 1 (its transmission is rough, and
            // only a specular one scales Russian roulette by it).
            Material::Disney(d) => d.add_lobes(si, b, scale),
            Material::Fourier(f) => {
                b.add_scaled(Bxdf::Fourier(*f), scale);
            }
            Material::Mix { amount, materials } => {
                let s1 = clamp0(amount.eval(si));
                let s2 = clamp0(Spectrum::ONE - s1);
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

mod build;
pub use build::build_materials;

#[cfg(test)]
mod tests;
