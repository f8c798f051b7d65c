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
use crate::texture::{FloatTexture, SpectrumTexture, Texture, TextureBuilder};
use acr_parser::{Error, MaterialDesc, ParamList, Result, SceneDescription, Warning};
use std::path::Path;
use std::sync::Arc;

/// pbrt-v3's copper (metal.cpp's tables through `RGBSpectrum::FromSampled`): the metal
/// material's default `eta`.
pub const COPPER_ETA: Spectrum = Spectrum::new(0.200438, 0.924033, 1.10221);
/// pbrt-v3's copper absorption: the metal material's default `k`.
pub const COPPER_K: Spectrum = Spectrum::new(3.91295, 2.45285, 2.14219);

/// Material types acr builds.
const KINDS: [&str; 12] = [
    "matte",
    "translucent",
    "plastic",
    "mirror",
    "glass",
    "metal",
    "uber",
    "substrate",
    "hair",
    "disney",
    "mix",
    "fourier",
];
/// pbrt-v3 material types acr replaces by a matte.
const UNSUPPORTED_KINDS: [&str; 2] = ["subsurface", "kdsubsurface"];
/// Types that make no surface: rays pass through.
const INTERFACE_KINDS: [&str; 3] = ["", "none", "interface"];
/// Parameters pbrt-v3 (or pbrt-v4) materials take that acr ignores, with a warning.
const UNSUPPORTED_PARAMS: [&str; 2] = ["displacement", "normalmap"];

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

/// Builds materials from their descriptions, textures on demand.
struct MaterialBuilder<'a> {
    desc: &'a SceneDescription,
    textures: TextureBuilder<'a>,
    built: Vec<Option<Arc<Material>>>,
    in_progress: Vec<bool>,
}

impl<'a> MaterialBuilder<'a> {
    fn build(&mut self, index: usize) -> Result<Arc<Material>> {
        if let Some(m) = &self.built[index] {
            return Ok(Arc::clone(m));
        }
        let md: &'a MaterialDesc = &self.desc.materials[index];
        if self.in_progress[index] {
            return Err(Error::at(
                &md.plugin.loc,
                "mix material refers to itself through its named materials",
            ));
        }
        self.in_progress[index] = true;
        let mut m = Arc::new(self.make(md)?);
        let p = &md.plugin.params;
        // pbrt-v3's hair reads no bumpmap (left unused, so reported as such).
        if !m.is_interface() && !matches!(*m, Material::Hair(_)) {
            if let Some(map) = self.textures.float_param_opt(p, "bumpmap")? {
                m = Arc::new(Material::Bumped {
                    map: Arc::new(map),
                    inner: m,
                });
            }
        }
        self.in_progress[index] = false;
        self.built[index] = Some(Arc::clone(&m));
        Ok(m)
    }

    fn make(&mut self, md: &'a MaterialDesc) -> Result<Material> {
        let p: &ParamList = &md.plugin.params;
        let loc = &md.plugin.loc;
        let kind = md.plugin.kind.as_str();
        for name in UNSUPPORTED_PARAMS {
            if let Some(param) = p.get(name) {
                self.textures.warn_once(
                    format!("material parameter {name}"),
                    &param.loc,
                    format!("material parameter \"{name}\" is not supported; ignored"),
                );
            }
        }
        let t = &mut self.textures;
        let remap = |p: &ParamList| p.bool_or("remaproughness", true);
        Ok(match kind {
            "matte" => Material::Matte {
                kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.5))?,
                sigma: t.float_param(p, "sigma", 0.0)?,
            },
            "plastic" => Material::Plastic {
                kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.25))?,
                ks: t.spectrum_param(p, "Ks", Spectrum::splat(0.25))?,
                roughness: t.float_param(p, "roughness", 0.1)?,
                remap_roughness: remap(p)?,
            },
            "mirror" => Material::Mirror {
                kr: t.spectrum_param(p, "Kr", Spectrum::splat(0.9))?,
            },
            "glass" => {
                let eta = match t.float_param_opt(p, "eta")? {
                    Some(e) => e,
                    None => t.float_param(p, "index", 1.5)?,
                };
                Material::Glass {
                    kr: t.spectrum_param(p, "Kr", Spectrum::ONE)?,
                    kt: t.spectrum_param(p, "Kt", Spectrum::ONE)?,
                    eta,
                    u_roughness: t.float_param(p, "uroughness", 0.0)?,
                    v_roughness: t.float_param(p, "vroughness", 0.0)?,
                    remap_roughness: remap(p)?,
                }
            }
            "metal" => Material::Metal {
                eta: t.spectrum_param(p, "eta", COPPER_ETA)?,
                k: t.spectrum_param(p, "k", COPPER_K)?,
                roughness: t.float_param(p, "roughness", 0.01)?,
                u_roughness: t.float_param_opt(p, "uroughness")?,
                v_roughness: t.float_param_opt(p, "vroughness")?,
                remap_roughness: remap(p)?,
            },
            "uber" => {
                let eta = match t.float_param_opt(p, "eta")? {
                    Some(e) => e,
                    None => t.float_param(p, "index", 1.5)?,
                };
                Material::Uber {
                    kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.25))?,
                    ks: t.spectrum_param(p, "Ks", Spectrum::splat(0.25))?,
                    kr: t.spectrum_param(p, "Kr", Spectrum::ZERO)?,
                    kt: t.spectrum_param(p, "Kt", Spectrum::ZERO)?,
                    roughness: t.float_param(p, "roughness", 0.1)?,
                    u_roughness: t.float_param_opt(p, "uroughness")?,
                    v_roughness: t.float_param_opt(p, "vroughness")?,
                    eta,
                    opacity: t.spectrum_param(p, "opacity", Spectrum::ONE)?,
                    remap_roughness: remap(p)?,
                }
            }
            "substrate" => Material::Substrate {
                kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.5))?,
                ks: t.spectrum_param(p, "Ks", Spectrum::splat(0.5))?,
                u_roughness: t.float_param(p, "uroughness", 0.1)?,
                v_roughness: t.float_param(p, "vroughness", 0.1)?,
                remap_roughness: remap(p)?,
            },
            "translucent" => Material::Translucent {
                kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.25))?,
                ks: t.spectrum_param(p, "Ks", Spectrum::splat(0.25))?,
                reflect: t.spectrum_param(p, "reflect", Spectrum::splat(0.5))?,
                transmit: t.spectrum_param(p, "transmit", Spectrum::splat(0.5))?,
                roughness: t.float_param(p, "roughness", 0.1)?,
                remap_roughness: remap(p)?,
            },
            "hair" => Material::Hair(crate::hair::HairMaterial::from_params(t, p, loc)?),
            "fourier" => {
                let Some(name) = p.string("bsdffile")? else {
                    return Err(Error::at(loc, "fourier material needs \"string bsdffile\""));
                };
                let at = p.get("bsdffile").map_or(loc, |x| &x.loc).clone();
                let path = t.resolve_file(name, &at);
                let table = crate::fourier::FourierTable::load(&path)
                    .map_err(|e| Error::at(&at, format!("fourier material: {e}")))?;
                Material::Fourier(crate::fourier::FourierBsdf { table })
            }
            "disney" => Material::Disney(Box::new(crate::disney::DisneyMaterial::from_params(
                t, p, loc,
            )?)),
            "mix" => {
                let amount = t.spectrum_param(p, "amount", Spectrum::splat(0.5))?;
                let Some([a, b]) = md.mix else {
                    return Err(Error::at(
                        loc,
                        "mix material needs \"string namedmaterial1\" and \"namedmaterial2\"",
                    ));
                };
                Material::Mix {
                    amount,
                    materials: [self.build(a)?, self.build(b)?],
                }
            }
            k if INTERFACE_KINDS.contains(&k) => Material::Interface,
            k if UNSUPPORTED_KINDS.contains(&k) => {
                t.warn_once(
                    format!("material {k}"),
                    loc,
                    format!("material \"{k}\" is not supported; a matte with its Kd is used"),
                );
                Material::Matte {
                    kd: t.spectrum_param(p, "Kd", Spectrum::splat(0.5))?,
                    sigma: Texture::Constant(0.0),
                }
            }
            other => return Err(unknown_kind(other, loc)),
        })
    }
}

fn unknown_kind(kind: &str, loc: &acr_parser::Loc) -> Error {
    let hint = acr_parser::closest(kind, KINDS.iter().chain(&UNSUPPORTED_KINDS).copied())
        .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
    Error::at(loc, format!("unknown material \"{kind}\"{hint}"))
}

/// Which materials shapes use, directly or through mix materials.
fn used_materials(desc: &SceneDescription) -> Vec<bool> {
    let n = desc.materials.len();
    let mut used = vec![false; n];
    let mut stack: Vec<usize> = desc
        .shapes
        .iter()
        .chain(desc.objects.values().flat_map(|o| o.shapes.iter()))
        .filter_map(|s| s.material)
        .collect();
    while let Some(i) = stack.pop() {
        if i >= n || used[i] {
            continue;
        }
        used[i] = true;
        if let Some(pair) = desc.materials[i].mix {
            stack.extend(pair);
        }
    }
    used
}

/// Builds `desc.materials` (index i is `desc.materials[i]`). Materials no shape uses (directly
/// or through a mix) are not built: they get pbrt's default matte, their parameters are marked
/// used, and their textures are never read. Every material's type is checked: an unknown type
/// is an error at its location. Warnings (unsupported parameters or types, each once) are
/// appended to `warnings`. `main_dir` is the main scene file's directory, where file names
/// that are not next to the file naming them are looked for.
pub fn build_materials(
    desc: &SceneDescription,
    main_dir: &Path,
    render_from_world: glam::DMat4,
    warnings: &mut Vec<Warning>,
) -> Result<Vec<Material>> {
    for md in &desc.materials {
        let k = md.plugin.kind.as_str();
        if !(KINDS.contains(&k) || UNSUPPORTED_KINDS.contains(&k) || INTERFACE_KINDS.contains(&k)) {
            return Err(unknown_kind(k, &md.plugin.loc));
        }
    }
    let used = used_materials(desc);
    let n = desc.materials.len();
    let mut b = MaterialBuilder {
        desc,
        textures: TextureBuilder::new(desc, main_dir).with_render_from_world(render_from_world),
        built: vec![None; n],
        in_progress: vec![false; n],
    };
    let mut out = Vec::with_capacity(n);
    for (i, md) in desc.materials.iter().enumerate() {
        if used[i] {
            out.push((*b.build(i)?).clone());
        } else {
            for p in md.plugin.params.iter() {
                p.mark_used();
            }
            out.push(Material::default_matte());
        }
    }
    warnings.extend(b.textures.finish());
    Ok(out)
}

#[cfg(test)]
mod tests;
