//! pbrt-v3's `disney` material (materials/disney.{h,cpp}): Burley's 2015 Disney BSDF as pbrt-v3
//! builds it, lobe for lobe and weight for weight, quirks included (each noted where it is).
//!
//! [`DisneyMaterial::add_lobes`] is pbrt-v3's `DisneyMaterial::ComputeScatteringFunctions`; the
//! lobes pbrt-v3 defines in disney.cpp are [`DisneyBxdf`] (one [`Bxdf::Disney`] variant), and
//! the two it borrows unchanged from core/reflection.cpp are the existing
//! [`Bxdf::MicrofacetTransmission`] (the thin surface's) and [`Bxdf::LambertianTransmission`].
//!
//! Not supported: `scatterdistance` (pbrt-v3's `DisneyBSSRDF` subsurface scattering, which
//! replaces the diffuse lobe by a smooth refraction into the object): acr has no BSSRDF, so a
//! non-zero `scatterdistance` warns and the surface keeps pbrt-v3's diffuse lobe instead.

use crate::bsdf::{fr_dielectric, reflect, Bsdf, Bxdf, BxdfType, LobeSample};
use crate::geometry::{Spectrum, SurfaceInteraction, Vec2, Vec3};
use crate::microfacet::{abs_cos_theta, same_hemisphere, TrowbridgeReitz};
use crate::sampling::cosine_sample_hemisphere;
use crate::texture::{FloatTexture, SpectrumTexture, TextureBuilder};
use acr_parser::{Loc, ParamList, Result};
use std::f32::consts::{FRAC_1_PI, PI};

/// pbrt-v3's `SchlickWeight`: (1 - cos θ)⁵, with 1 - cos θ clamped to [0, 1].
#[inline]
fn schlick_weight(cos_theta: f32) -> f32 {
    let m = (1.0 - cos_theta).clamp(0.0, 1.0);
    (m * m) * (m * m) * m
}

/// pbrt-v3's `Lerp(t, a, b)` = (1 - t) a + t b, for floats.
#[inline]
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// pbrt-v3's `Lerp` for spectra.
#[inline]
fn lerp_s(t: f32, a: Spectrum, b: Spectrum) -> Spectrum {
    (1.0 - t) * a + t * b
}

/// `std::max(a, b)` as C++ has it: `a` unless `a < b`, so a NaN `b` gives `a` (pbrt-v3's
/// alphas of a NaN roughness become 0.001).
#[inline]
fn cpp_max(a: f32, b: f32) -> f32 {
    if a < b {
        b
    } else {
        a
    }
}

/// pbrt-v3's `SchlickR0FromEta`: normal-incidence reflectance of a dielectric seen from air.
#[inline]
fn schlick_r0_from_eta(eta: f32) -> f32 {
    let (a, b) = (eta - 1.0, eta + 1.0);
    (a * a) / (b * b)
}

/// pbrt-v3's `GTR1`, the clearcoat's distribution of normals (fatter tails than GGX).
#[inline]
fn gtr1(cos_theta: f32, alpha: f32) -> f32 {
    let alpha2 = alpha * alpha;
    (alpha2 - 1.0) / (PI * alpha2.ln() * (1.0 + (alpha2 - 1.0) * cos_theta * cos_theta))
}

/// pbrt-v3's `smithG_GGX`: the clearcoat's masking term with the 1 / (2 cos θ) of the microfacet
/// denominator folded in.
#[inline]
fn smith_g_ggx(cos_theta: f32, alpha: f32) -> f32 {
    let alpha2 = alpha * alpha;
    let cos2 = cos_theta * cos_theta;
    1.0 / (cos_theta + (alpha2 + cos2 - alpha2 * cos2).sqrt())
}

/// The normalised half vector of `wo` and `wi`; `None` when they are opposite (pbrt-v3's lobes
/// return zero there).
#[inline]
fn half_vector(wo: Vec3, wi: Vec3) -> Option<Vec3> {
    let wh = wi + wo;
    if wh == Vec3::ZERO {
        return None;
    }
    wh.try_normalize()
}

/// The ratio of the Disney masking-shadowing (pbrt-v3's `DisneyMicrofacetDistribution::G`, the
/// separable G1(wo) G1(wi)) to Trowbridge-Reitz's height-correlated 1 / (1 + Λ(wo) + Λ(wi)).
#[inline]
fn separable_over_correlated(d: &TrowbridgeReitz, wo: Vec3, wi: Vec3) -> f32 {
    let (lo, li) = (d.lambda(wo), d.lambda(wi));
    (1.0 + lo + li) / ((1.0 + lo) * (1.0 + li))
}

/// A lobe of pbrt-v3's Disney BSDF, in the local shading frame (z = shading normal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DisneyBxdf {
    /// `DisneyDiffuse`: R / π times Burley's diffuse Fresnel factors.
    Diffuse {
        /// Reflectance.
        r: Spectrum,
    },
    /// `DisneyFakeSS`: the Hanrahan-Krueger-like "fake subsurface" lobe of thin surfaces.
    FakeSs {
        /// Reflectance.
        r: Spectrum,
        /// Roughness (not remapped).
        roughness: f32,
    },
    /// `DisneyRetro`: the roughness-driven retro-reflection added to the diffuse lobe.
    Retro {
        /// Reflectance.
        r: Spectrum,
        /// Roughness (not remapped).
        roughness: f32,
    },
    /// `DisneySheen`: R times the Schlick weight of the half angle.
    Sheen {
        /// Sheen colour times its weights.
        r: Spectrum,
    },
    /// `DisneyClearcoat`: a GTR1 coat with a fixed 0.04 Schlick Fresnel.
    Clearcoat {
        /// The `clearcoat` weight.
        weight: f32,
        /// The GTR1 alpha (pbrt-v3 calls it gloss): lerp(clearcoatgloss, 0.1, 0.001).
        gloss: f32,
    },
    /// `MicrofacetReflection` with R = 1, `DisneyMicrofacetDistribution` (Trowbridge-Reitz with
    /// separable masking-shadowing) and `DisneyFresnel`.
    Specular {
        /// Trowbridge-Reitz alphas.
        distribution: TrowbridgeReitz,
        /// `Cspec0`, the Schlick reflectance at normal incidence of the metallic part.
        r0: Spectrum,
        /// Blend between dielectric Fresnel (0) and Schlick from `r0` (1).
        metallic: f32,
        /// Index of refraction of the dielectric Fresnel.
        eta: f32,
    },
    /// `MicrofacetTransmission` (from index 1 to `eta`) with `DisneyMicrofacetDistribution`:
    /// pbrt-v3's non-thin transmission shares the specular lobe's distribution, so its
    /// masking-shadowing is the separable one too.
    Transmission {
        /// Transmittance scale.
        t: Spectrum,
        /// Trowbridge-Reitz alphas.
        distribution: TrowbridgeReitz,
        /// Index of refraction inside.
        eta: f32,
    },
}

impl DisneyBxdf {
    /// The lobe's kind, as pbrt-v3's `BxDFType`.
    pub fn kind(&self) -> BxdfType {
        use BxdfType as T;
        match self {
            DisneyBxdf::Diffuse { .. }
            | DisneyBxdf::FakeSs { .. }
            | DisneyBxdf::Retro { .. }
            | DisneyBxdf::Sheen { .. } => T::REFLECTION.or(T::DIFFUSE),
            DisneyBxdf::Clearcoat { .. } | DisneyBxdf::Specular { .. } => {
                T::REFLECTION.or(T::GLOSSY)
            }
            DisneyBxdf::Transmission { .. } => T::TRANSMISSION.or(T::GLOSSY),
        }
    }

    /// The same transmission with Trowbridge-Reitz's own masking-shadowing: pbrt-v3's
    /// `MicrofacetTransmission`, which acr's [`Bxdf::MicrofacetTransmission`] is.
    #[inline]
    fn smith_transmission(t: Spectrum, distribution: TrowbridgeReitz, eta: f32) -> Bxdf {
        Bxdf::MicrofacetTransmission {
            t,
            distribution,
            eta_a: 1.0,
            eta_b: eta,
        }
    }

    /// The lobe's value for local `wo` and `wi`. Like pbrt-v3's, the diffuse-like lobes do not
    /// look at the sides: the BSDF's geometric test keeps reflection.
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Spectrum {
        let v = match *self {
            DisneyBxdf::Diffuse { r } => {
                let fo = schlick_weight(abs_cos_theta(wo));
                let fi = schlick_weight(abs_cos_theta(wi));
                // Diffuse Fresnel: 1 at normal incidence to 0.5 at grazing (Burley 2015, eq. 4).
                r * FRAC_1_PI * (1.0 - fo / 2.0) * (1.0 - fi / 2.0)
            }
            DisneyBxdf::FakeSs { r, roughness } => {
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                let cos_d = wi.dot(wh);
                // Fss90 "flattens" the retro-reflection by roughness.
                let fss90 = cos_d * cos_d * roughness;
                let fo = schlick_weight(abs_cos_theta(wo));
                let fi = schlick_weight(abs_cos_theta(wi));
                let fss = lerp(fo, 1.0, fss90) * lerp(fi, 1.0, fss90);
                // pbrt-v3's 1.25 roughly preserves the albedo (it is not energy conserving).
                let ss = 1.25 * (fss * (1.0 / (abs_cos_theta(wo) + abs_cos_theta(wi)) - 0.5) + 0.5);
                r * FRAC_1_PI * ss
            }
            DisneyBxdf::Retro { r, roughness } => {
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                let cos_d = wi.dot(wh);
                let fo = schlick_weight(abs_cos_theta(wo));
                let fi = schlick_weight(abs_cos_theta(wi));
                let rr = 2.0 * roughness * cos_d * cos_d;
                // Burley 2015, eq. 4.
                r * FRAC_1_PI * rr * (fo + fi + fo * fi * (rr - 1.0))
            }
            DisneyBxdf::Sheen { r } => {
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                r * schlick_weight(wi.dot(wh))
            }
            DisneyBxdf::Clearcoat { weight, gloss } => {
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                // Index 1.5 (F0 = 0.04) is fixed; the geometric term always takes alpha 0.25.
                let dr = gtr1(abs_cos_theta(wh), gloss);
                let fr = lerp(schlick_weight(wo.dot(wh)), 0.04, 1.0);
                let gr =
                    smith_g_ggx(abs_cos_theta(wo), 0.25) * smith_g_ggx(abs_cos_theta(wi), 0.25);
                Spectrum::splat(weight * gr * fr * dr / 4.0)
            }
            DisneyBxdf::Specular {
                distribution,
                r0,
                metallic,
                eta,
            } => {
                let (cos_o, cos_i) = (abs_cos_theta(wo), abs_cos_theta(wi));
                if cos_i == 0.0 || cos_o == 0.0 {
                    return Spectrum::ZERO;
                }
                let Some(wh) = half_vector(wo, wi) else {
                    return Spectrum::ZERO;
                };
                // Fresnel of the half vector faced forward, as pbrt-v3's MicrofacetReflection.
                let wh_f = if wh.z < 0.0 { -wh } else { wh };
                let fr = disney_fresnel(r0, metallic, eta, wi.dot(wh_f));
                let g = distribution.g1(wo) * distribution.g1(wi);
                fr * (distribution.d(wh) * g) / (4.0 * cos_i * cos_o)
            }
            DisneyBxdf::Transmission {
                t,
                distribution,
                eta,
            } => {
                let f = Self::smith_transmission(t, distribution, eta).f(wo, wi);
                if f == Spectrum::ZERO {
                    return f;
                }
                f * separable_over_correlated(&distribution, wo, wi)
            }
        };
        if v.is_finite() {
            v
        } else {
            Spectrum::ZERO
        }
    }

    /// Samples an incident direction for local `wo`: cosine-weighted for the diffuse-like lobes
    /// (pbrt-v3's default `BxDF::Sample_f`), the GTR1 normals for the clearcoat, the visible
    /// Trowbridge-Reitz normals for the specular lobes.
    pub fn sample_f(&self, wo: Vec3, u: Vec2) -> Option<LobeSample> {
        let wi = match *self {
            DisneyBxdf::Diffuse { .. }
            | DisneyBxdf::FakeSs { .. }
            | DisneyBxdf::Retro { .. }
            | DisneyBxdf::Sheen { .. } => {
                let mut wi = cosine_sample_hemisphere(u);
                if wo.z < 0.0 {
                    wi.z = -wi.z;
                }
                wi
            }
            DisneyBxdf::Clearcoat { gloss, .. } => {
                if wo.z == 0.0 {
                    return None;
                }
                let alpha2 = gloss * gloss;
                let cos_theta = ((1.0 - alpha2.powf(1.0 - u.x)) / (1.0 - alpha2))
                    .max(0.0)
                    .sqrt();
                let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                let mut wh = Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta);
                if !same_hemisphere(wo, wh) {
                    wh = -wh;
                }
                let wi = reflect(wo, wh);
                if !same_hemisphere(wo, wi) {
                    return None;
                }
                wi
            }
            DisneyBxdf::Specular { distribution, .. } => {
                if wo.z == 0.0 {
                    return None;
                }
                let wh = distribution.sample_wh(wo, u);
                // pbrt-v3 gives up below 0; at 0 its pdf would divide by zero.
                if wo.dot(wh).is_nan() || wo.dot(wh) <= 0.0 {
                    return None;
                }
                let wi = reflect(wo, wh);
                if !same_hemisphere(wo, wi) {
                    return None;
                }
                // The density of the sampled normal, as pbrt-v3 (not recomputed from wi).
                return Some(LobeSample {
                    wi,
                    f: self.f(wo, wi),
                    pdf: distribution.pdf(wo, wh) / (4.0 * wo.dot(wh)),
                    kind: self.kind(),
                });
            }
            DisneyBxdf::Transmission {
                t,
                distribution,
                eta,
            } => {
                // The same directions and density as the Trowbridge-Reitz transmission (its
                // sampling and pdf use G1(wo) only); the value is this lobe's.
                let s = Self::smith_transmission(t, distribution, eta).sample_f(wo, u)?;
                return Some(LobeSample {
                    f: s.f * separable_over_correlated(&distribution, wo, s.wi),
                    ..s
                });
            }
        };
        Some(LobeSample {
            wi,
            f: self.f(wo, wi),
            pdf: self.pdf(wo, wi),
            kind: self.kind(),
        })
    }

    /// Density with which [`DisneyBxdf::sample_f`] picks local `wi` given `wo`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let p = match *self {
            DisneyBxdf::Diffuse { .. }
            | DisneyBxdf::FakeSs { .. }
            | DisneyBxdf::Retro { .. }
            | DisneyBxdf::Sheen { .. } => {
                if same_hemisphere(wo, wi) {
                    abs_cos_theta(wi) * FRAC_1_PI
                } else {
                    0.0
                }
            }
            DisneyBxdf::Clearcoat { gloss, .. } => {
                if !same_hemisphere(wo, wi) {
                    return 0.0;
                }
                let Some(wh) = half_vector(wo, wi) else {
                    return 0.0;
                };
                // The sampler draws wh from GTR1 exactly: D cos θh, to the reflected direction.
                let dr = gtr1(abs_cos_theta(wh), gloss);
                dr * abs_cos_theta(wh) / (4.0 * wo.dot(wh))
            }
            DisneyBxdf::Specular { distribution, .. } => {
                if !same_hemisphere(wo, wi) {
                    return 0.0;
                }
                let Some(wh) = half_vector(wo, wi) else {
                    return 0.0;
                };
                distribution.pdf(wo, wh) / (4.0 * wo.dot(wh))
            }
            DisneyBxdf::Transmission {
                t,
                distribution,
                eta,
            } => Self::smith_transmission(t, distribution, eta).pdf(wo, wi),
        };
        if p.is_finite() && p > 0.0 {
            p
        } else {
            0.0
        }
    }

    /// The lobe's nominal reflectance or transmittance for first-hit features: R for the
    /// diffuse-like lobes (none for the retro-reflection, a correction of the diffuse lobe's),
    /// the normal-incidence Fresnel for the specular lobe and the clearcoat, T for transmission.
    pub fn albedo(&self) -> Spectrum {
        match *self {
            DisneyBxdf::Diffuse { r } | DisneyBxdf::FakeSs { r, .. } | DisneyBxdf::Sheen { r } => r,
            DisneyBxdf::Retro { .. } => Spectrum::ZERO,
            DisneyBxdf::Clearcoat { weight, .. } => Spectrum::splat(0.04 * weight),
            DisneyBxdf::Specular {
                r0, metallic, eta, ..
            } => disney_fresnel(r0, metallic, eta, 1.0),
            DisneyBxdf::Transmission { t, .. } => t,
        }
    }
}

/// pbrt-v3's `DisneyFresnel`: lerp(metallic, dielectric Fresnel of `eta`, Schlick from `r0`).
/// A pbrt-v3 quirk: the dielectric part ignores `r0`, so `speculartint` only shows where
/// `metallic` is strictly between 0 and 1.
#[inline]
fn disney_fresnel(r0: Spectrum, metallic: f32, eta: f32, cos_i: f32) -> Spectrum {
    let dielectric = Spectrum::splat(fr_dielectric(cos_i, 1.0, eta));
    let schlick = lerp_s(schlick_weight(cos_i), r0, Spectrum::ONE);
    lerp_s(metallic, dielectric, schlick)
}

/// pbrt-v3's `disney` material's parameters, possibly textured (defaults as its
/// `CreateDisneyMaterial`).
#[derive(Clone, Debug)]
pub struct DisneyMaterial {
    /// Base colour (0.5).
    pub color: SpectrumTexture,
    /// Metallic weight (0).
    pub metallic: FloatTexture,
    /// Index of refraction (1.5).
    pub eta: FloatTexture,
    /// Roughness, squared into the alphas (0.5).
    pub roughness: FloatTexture,
    /// Tint of the specular reflectance toward the colour's hue (0).
    pub specular_tint: FloatTexture,
    /// Anisotropy: alphas r² / aspect and r² aspect with aspect = sqrt(1 - 0.9 a) (0).
    pub anisotropic: FloatTexture,
    /// Sheen weight (0).
    pub sheen: FloatTexture,
    /// Tint of the sheen toward the colour's hue (0.5).
    pub sheen_tint: FloatTexture,
    /// Clearcoat weight (0).
    pub clearcoat: FloatTexture,
    /// Clearcoat glossiness (1).
    pub clearcoat_gloss: FloatTexture,
    /// Specular transmission weight (0).
    pub spec_trans: FloatTexture,
    /// A thin surface: diffuse and fake-subsurface blend, diffuse transmission (false).
    pub thin: bool,
    /// Thin surfaces: share of the diffuse given to the fake subsurface lobe (0).
    pub flatness: FloatTexture,
    /// Thin surfaces: diffuse transmission, halved by pbrt-v3 (1).
    pub diff_trans: FloatTexture,
}

impl DisneyMaterial {
    /// The material from its parameters, as pbrt-v3's `CreateDisneyMaterial` (`bumpmap` is the
    /// material builder's); a non-zero `scatterdistance` warns (no subsurface scattering).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList, loc: &Loc) -> Result<Self> {
        let sd = t.spectrum_param_opt(p, "scatterdistance")?;
        if sd.is_some_and(|sd| sd.as_constant() != Some(Spectrum::ZERO)) {
            t.warn_once(
                "disney scatterdistance",
                loc,
                "disney \"scatterdistance\" (subsurface scattering) is not supported; \
                 the diffuse lobe is used",
            );
        }
        Ok(Self {
            color: t.spectrum_param(p, "color", Spectrum::splat(0.5))?,
            metallic: t.float_param(p, "metallic", 0.0)?,
            eta: t.float_param(p, "eta", 1.5)?,
            roughness: t.float_param(p, "roughness", 0.5)?,
            specular_tint: t.float_param(p, "speculartint", 0.0)?,
            anisotropic: t.float_param(p, "anisotropic", 0.0)?,
            sheen: t.float_param(p, "sheen", 0.0)?,
            sheen_tint: t.float_param(p, "sheentint", 0.5)?,
            clearcoat: t.float_param(p, "clearcoat", 0.0)?,
            clearcoat_gloss: t.float_param(p, "clearcoatgloss", 1.0)?,
            spec_trans: t.float_param(p, "spectrans", 0.0)?,
            thin: p.bool_or("thin", false)?,
            flatness: t.float_param(p, "flatness", 0.0)?,
            diff_trans: t.float_param(p, "difftrans", 1.0)?,
        })
    }

    /// Adds the lobes pbrt-v3's `DisneyMaterial::ComputeScatteringFunctions` adds, each weighted
    /// by `scale`. Lobes of zero weight are added too, as pbrt-v3 does: the lobe count decides
    /// the sampling probabilities.
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum) {
        let mut add = |x: Bxdf| {
            b.add_scaled(x, scale);
        };
        let c = self.color.eval(si).max(Spectrum::ZERO);
        let metallic = self.metallic.eval(si);
        let e = self.eta.eval(si);
        let strans = self.spec_trans.eval(si);
        let diffuse_weight = (1.0 - metallic) * (1.0 - strans);
        // 0: all the diffuse is reflected; 1: half of it transmitted (pbrt-v3 halves it).
        let dt = self.diff_trans.eval(si) / 2.0;
        let rough = self.roughness.eval(si);
        let lum = crate::spectrum_luminance(c);
        // The colour's hue and saturation.
        let c_tint = if lum > 0.0 { c / lum } else { Spectrum::ONE };
        let sheen = self.sheen.eval(si);
        let c_sheen = if sheen > 0.0 {
            lerp_s(self.sheen_tint.eval(si), Spectrum::ONE, c_tint)
        } else {
            Spectrum::ZERO
        };

        if diffuse_weight > 0.0 {
            if self.thin {
                // Diffuse and fake subsurface blended by flatness, both weighted by 1 - dt.
                let flat = self.flatness.eval(si);
                add(Bxdf::Disney(DisneyBxdf::Diffuse {
                    r: diffuse_weight * (1.0 - flat) * (1.0 - dt) * c,
                }));
                add(Bxdf::Disney(DisneyBxdf::FakeSs {
                    r: diffuse_weight * flat * (1.0 - dt) * c,
                    roughness: rough,
                }));
            } else {
                // pbrt-v3 swaps this for a refraction and its BSSRDF when scatterdistance is
                // not black: not supported (a warning at build time).
                add(Bxdf::Disney(DisneyBxdf::Diffuse {
                    r: diffuse_weight * c,
                }));
            }
            // A pbrt-v3 quirk: the retro-reflection is not weighted by 1 - dt on thin surfaces.
            add(Bxdf::Disney(DisneyBxdf::Retro {
                r: diffuse_weight * c,
                roughness: rough,
            }));
            if sheen > 0.0 {
                add(Bxdf::Disney(DisneyBxdf::Sheen {
                    r: diffuse_weight * sheen * c_sheen,
                }));
            }
        }

        // Roughness is squared, not remapped, into the alphas.
        let aspect = (1.0 - self.anisotropic.eval(si) * 0.9).sqrt();
        let alphas = |r: f32| {
            TrowbridgeReitz::new(
                cpp_max(0.001, r * r / aspect),
                cpp_max(0.001, r * r * aspect),
            )
        };
        let distribution = alphas(rough);
        let spec_tint = self.specular_tint.eval(si);
        let r0 = lerp_s(
            metallic,
            schlick_r0_from_eta(e) * lerp_s(spec_tint, Spectrum::ONE, c_tint),
            c,
        );
        add(Bxdf::Disney(DisneyBxdf::Specular {
            distribution,
            r0,
            metallic,
            eta: e,
        }));

        let cc = self.clearcoat.eval(si);
        if cc > 0.0 {
            add(Bxdf::Disney(DisneyBxdf::Clearcoat {
                weight: cc,
                gloss: lerp(self.clearcoat_gloss.eval(si), 0.1, 0.001),
            }));
        }

        if strans > 0.0 {
            // Scaled by sqrt(colour), so that two refractions give the colour back.
            let t = strans * c.map(f32::sqrt);
            if self.thin {
                // Roughness scaled by the index (Burley 2015, figure 15), and, unlike the
                // reflection, Trowbridge-Reitz's own masking-shadowing. A thin surface still
                // refracts with `eta` in pbrt-v3.
                let rscaled = (0.65 * e - 0.35) * rough;
                add(Bxdf::MicrofacetTransmission {
                    t,
                    distribution: alphas(rscaled),
                    eta_a: 1.0,
                    eta_b: e,
                });
            } else {
                add(Bxdf::Disney(DisneyBxdf::Transmission {
                    t,
                    distribution,
                    eta: e,
                }));
            }
        }
        if self.thin {
            // pbrt-v3's comment says "weighted by (1 - diffTrans)"; it is weighted by dt, and
            // added even where the diffuse weight is zero (a thin metal transmits diffusely).
            add(Bxdf::LambertianTransmission { t: dt * c });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::check::*;
    use crate::material::{build_materials, Material};
    use crate::sampling::uniform_sample_sphere;
    use acr_parser::parse_str;
    use std::path::Path;

    /// pbrt-v3's `OneMinusEpsilon`.
    const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

    /// The material of one `Material "disney" ...` line (no warnings allowed).
    fn material(params: &str) -> Material {
        let text =
            format!("WorldBegin\nMaterial \"disney\" {params}\nShape \"sphere\"\nWorldEnd\n");
        let desc = parse_str(&text, Path::new("/tmp/scene.pbrt")).unwrap();
        let mut w = Vec::new();
        let m = build_materials(&desc, Path::new("/tmp"), glam::DMat4::IDENTITY, &mut w).unwrap();
        assert!(w.is_empty(), "{params}: {w:?}");
        m.last().unwrap().clone()
    }

    /// A hit whose shading frame is the local frame (normal z, tangent x).
    fn flat_hit() -> SurfaceInteraction {
        SurfaceInteraction {
            p: Vec3::ZERO,
            n: Vec3::Z,
            uv: Vec2::new(0.3, 0.6),
            dpdu: Vec3::X,
            dpdv: Vec3::Y,
            shading_n: Vec3::Z,
            shading_dpdu: Vec3::X,
            shading_dpdv: Vec3::Y,
            dndu: Vec3::ZERO,
            dndv: Vec3::ZERO,
            wo: Vec3::Z,
            time: 0.0,
            p_error: 0.0,
        }
    }

    fn close(got: f32, want: f32, rel: f32) -> bool {
        (got - want).abs() <= rel * got.abs().max(want.abs()) + 1e-6
    }

    fn close_s(got: Spectrum, want: Spectrum, rel: f32) -> bool {
        (0..3).all(|c| close(got[c], want[c], rel))
    }

    /// pbrt-v3's `BxDFType` bits (the same as acr's) of a kind.
    fn bits(k: BxdfType) -> u32 {
        use BxdfType as T;
        [
            T::REFLECTION,
            T::TRANSMISSION,
            T::DIFFUSE,
            T::GLOSSY,
            T::SPECULAR,
        ]
        .iter()
        .enumerate()
        .map(|(i, t)| if k.contains(*t) { 1 << i } else { 0 })
        .sum()
    }

    /// The pbrt-v3 class a lobe is.
    fn pbrt_name(b: &Bxdf) -> &'static str {
        match b {
            Bxdf::Disney(DisneyBxdf::Diffuse { .. }) => "DisneyDiffuse",
            Bxdf::Disney(DisneyBxdf::FakeSs { .. }) => "DisneyFakeSS",
            Bxdf::Disney(DisneyBxdf::Retro { .. }) => "DisneyRetro",
            Bxdf::Disney(DisneyBxdf::Sheen { .. }) => "DisneySheen",
            Bxdf::Disney(DisneyBxdf::Clearcoat { .. }) => "DisneyClearcoat",
            Bxdf::Disney(DisneyBxdf::Specular { .. }) => "MicrofacetReflection",
            Bxdf::Disney(DisneyBxdf::Transmission { .. }) | Bxdf::MicrofacetTransmission { .. } => {
                "MicrofacetTransmission"
            }
            Bxdf::LambertianTransmission { .. } => "LambertianTransmission",
            _ => "other",
        }
    }

    /// The BSDF of every parameter set of tests/data/pbrt-v3/disneycheck.cpp (pbrt-v3's own
    /// DisneyMaterial on a hit with tilted geometric and shading frames): the same lobes, the
    /// same f and pdf, whole and lobe by lobe, for 49 pairs of directions (some below the
    /// surface), and the same samples for 12 sample values from each of 7 directions.
    #[test]
    fn bsdf_matches_pbrt_v3() {
        let data = include_str!("../tests/data/pbrt-v3/disney-bsdf.txt");
        let num = |w: &[&str], i: usize| -> f32 { w[i].parse().unwrap() };
        let v3 = |w: &[&str], i: usize| Vec3::new(num(w, i), num(w, i + 1), num(w, i + 2));
        let mut si = flat_hit();
        let mut dirs = Vec::new();
        let mut bsdf = None;
        let (mut cases, mut values, mut samples, mut lobe_values) = (0, 0, 0, 0);
        let (mut nones, mut one_lobe_below) = (0, 0);
        let mut pair = (0, 0);
        for line in data.lines() {
            let w: Vec<&str> = line.split_whitespace().collect();
            match w[0] {
                "frame" => {
                    si.n = v3(&w, 2);
                    si.shading_n = v3(&w, 6);
                    si.shading_dpdu = v3(&w, 10);
                    si.shading_dpdv = v3(&w, 14);
                }
                "dir" => dirs.push(v3(&w, 2)),
                "case" => {
                    // "case NAME color r g b metallic m ... lobes N": the same Material line.
                    let mut params = format!("\"rgb color\" [{} {} {}]", w[3], w[4], w[5]);
                    let mut i = 6;
                    while w[i] != "lobes" {
                        params += &match w[i] {
                            "thin" => format!(" \"bool thin\" \"{}\"", w[i + 1] == "1"),
                            name => format!(" \"float {name}\" {}", w[i + 1]),
                        };
                        i += 2;
                    }
                    let b = material(&params).bsdf(&si);
                    assert_eq!(b.num_lobes(), w[i + 1].parse::<usize>().unwrap(), "{line}");
                    bsdf = Some(b);
                    cases += 1;
                }
                "lobe" => {
                    let b = bsdf.as_ref().unwrap();
                    let k: usize = w[1].parse().unwrap();
                    assert_eq!(pbrt_name(&b.lobes()[k].bxdf), w[3], "{line}");
                }
                "f" => {
                    let b = bsdf.as_ref().unwrap();
                    let (o, i): (usize, usize) = (w[1].parse().unwrap(), w[2].parse().unwrap());
                    let f = b.f(dirs[o], dirs[i]);
                    let pdf = b.pdf(dirs[o], dirs[i]);
                    assert!(close_s(f, v3(&w, 4), 1e-4), "f {f}\n{line}");
                    assert!(close(pdf, num(&w, 8), 1e-4), "pdf {pdf}\n{line}");
                    (pair, values, lobe_values) = ((o, i), values + 1, 0);
                }
                "l" => {
                    let b = bsdf.as_ref().unwrap();
                    let k: usize = w[1].parse().unwrap();
                    // The pair is the previous "f" line's.
                    let (o, i) = pair;
                    let (lo, li) = (b.frame().to_local(dirs[o]), b.frame().to_local(dirs[i]));
                    let lobe = &b.lobes()[k];
                    let f = lobe.scale * lobe.bxdf.f(lo, li);
                    let pdf = lobe.bxdf.pdf(lo, li);
                    assert!(close_s(f, v3(&w, 3), 1e-4), "lobe {k} f {f}\n{line}");
                    assert!(close(pdf, num(&w, 7), 1e-4), "lobe {k} pdf {pdf}\n{line}");
                    lobe_values += 1;
                    assert!(lobe_values <= b.num_lobes());
                }
                "s" => {
                    let b = bsdf.as_ref().unwrap();
                    let o: usize = w[1].parse().unwrap();
                    let (u0, u1) = (num(&w, 2), num(&w, 3));
                    // pbrt-v3 picks the lobe with u0 and reuses what is left of it.
                    let n = b.num_lobes();
                    let comp = ((u0 * n as f32).floor() as usize).min(n - 1);
                    let u = Vec2::new((u0 * n as f32 - comp as f32).min(ONE_MINUS_EPSILON), u1);
                    let got = b.sample_f(dirs[o], u, u0);
                    if w[4] == "none" {
                        assert!(
                            got.is_none(),
                            "acr samples {got:?} where pbrt-v3 does not:\n{line}"
                        );
                        nones += 1;
                        continue;
                    }
                    let s = got.unwrap_or_else(|| panic!("no sample where pbrt-v3 has:\n{line}"));
                    let kind: u32 = w[15].parse().unwrap();
                    assert_eq!(bits(b.lobes()[comp].bxdf.kind()), kind, "{line}");
                    let want_wi = v3(&w, 5);
                    assert!((s.wi - want_wi).length() < 1e-4, "wi {}\n{line}", s.wi);
                    let reflect = s.wi.dot(si.n) * dirs[o].dot(si.n) > 0.0;
                    let lobe_kind = b.lobes()[comp].bxdf.kind();
                    if n == 1 && !reflect && !lobe_kind.contains(BxdfType::TRANSMISSION) {
                        // A known difference (src/bsdf.rs): with one lobe pbrt-v3 keeps the
                        // lobe's value below the geometric surface; acr applies its test.
                        assert_eq!(s.f, Spectrum::ZERO, "{line}");
                        one_lobe_below += 1;
                    } else {
                        assert!(close_s(s.f, v3(&w, 9), 1e-3), "f {}\n{line}", s.f);
                    }
                    assert!(close(s.pdf, num(&w, 13), 1e-3), "pdf {}\n{line}", s.pdf);
                    samples += 1;
                }
                _ => panic!("unexpected line {line}"),
            }
        }
        assert_eq!((cases, values), (10, 10 * 49));
        assert_eq!((samples, nones), (10 * 7 * 12 - 26, 26));
        assert!(one_lobe_below <= 2, "{one_lobe_below}");
    }

    /// A white material's BSDF in the local frame.
    fn white(params: &str) -> Bsdf {
        material(&format!("\"rgb color\" [1 1 1] {params}")).bsdf(&flat_hit())
    }

    /// Outgoing directions from normal incidence to grazing (cosines 1 to 0.08).
    fn elevations() -> impl Iterator<Item = Vec3> {
        [1.0f32, 0.7, 0.4, 0.2, 0.08]
            .into_iter()
            .map(|c| Vec3::new((1.0 - c * c).sqrt(), 0.0, c))
    }

    /// White furnace: the directional albedo of white materials. Where pbrt-v3's model
    /// conserves energy (metals, specular transmission) it stays at most 1; its diffuse part
    /// does not (Burley's model adds the diffuse and retro-reflection lobes to the specular one
    /// without a 1 - F weight, the retro-reflection grows toward grazing, and the thin fake
    /// subsurface lobe's 1 / (cos θo + cos θi) does more so): those gains are pbrt-v3's, pinned
    /// here so that they are not mistaken for acr's.
    #[test]
    fn white_furnace_matches_pbrt_v3_energy() {
        let conserving = [
            "\"float roughness\" 0.3 \"float metallic\" 1",
            "\"float roughness\" 1 \"float metallic\" 1",
            "\"float roughness\" 0.5 \"float metallic\" 0.5 \"float speculartint\" 1",
            "\"float roughness\" 0.4 \"float anisotropic\" 0.9 \"float metallic\" 1",
            "\"float roughness\" 0.3 \"float spectrans\" 1",
            "\"float roughness\" 0.3 \"float spectrans\" 0.5",
        ];
        for (k, p) in conserving.iter().enumerate() {
            let b = white(p);
            for wo in elevations() {
                let (a, se) = albedo(&b, wo, 40_000, 3 + k as u64);
                assert!(
                    a.max_element() <= 1.0 + 3.0 * se + 1e-3,
                    "{p} {wo}: {a} ± {se}"
                );
            }
        }
        // (parameters, albedo range at normal incidence, at cos θo = 0.2): measured with
        // 100,000 samples, 1.018-1.326 for roughness 0.05 across the elevations, 1.05-1.45 for
        // roughness 1, 0.96-2.05 for the thin fake subsurface.
        let gaining = [
            ("\"float roughness\" 0.05", (1.0, 1.05), (1.12, 1.22)),
            ("\"float roughness\" 0.5", (1.02, 1.07), (1.12, 1.2)),
            (
                "\"float roughness\" 1 \"float sheen\" 1",
                (1.02, 1.08),
                (1.28, 1.37),
            ),
            (
                "\"float roughness\" 0.5 \"float clearcoat\" 1",
                (1.02, 1.08),
                (1.15, 1.25),
            ),
            (
                "\"float roughness\" 1 \"bool thin\" \"true\" \"float flatness\" 1",
                (0.93, 0.98),
                (1.62, 1.72),
            ),
        ];
        for (k, (p, normal, grazing)) in gaining.iter().enumerate() {
            let b = white(p);
            for (c, (lo, hi)) in [(1.0f32, normal), (0.2, grazing)] {
                let wo = Vec3::new((1.0 - c * c).sqrt(), 0.0, c);
                let (a, se) = albedo(&b, wo, 40_000, 7 + k as u64);
                let a = a.max_element();
                assert!(
                    *lo <= a + 3.0 * se && a - 3.0 * se <= *hi,
                    "{p} {wo}: {a} ± {se}"
                );
            }
        }
    }

    /// ∫ f |cos θi| dωi over the sphere with stratified uniform directions, and its standard
    /// error (that of independent samples, an overestimate).
    fn uniform_albedo(b: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (Spectrum, f32) {
        let mut rng = Rng::new(seed);
        let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
        for j in 0..n {
            for i in 0..n {
                let u = Vec2::new(
                    (i as f32 + rng.next_f32()) / n as f32,
                    (j as f32 + rng.next_f32()) / n as f32,
                );
                let wi = uniform_sample_sphere(u);
                let v = b.f(wo, wi) * wi.z.abs() * (4.0 * PI);
                for c in 0..3 {
                    sum[c] += v[c] as f64;
                    sum2[c] += (v[c] as f64).powi(2);
                }
            }
        }
        let m = (n * n) as f64;
        let mean = sum.map(|s| s / m);
        let se = (0..3)
            .map(|c| ((sum2[c] / m - mean[c] * mean[c]).max(0.0) / m).sqrt())
            .fold(0.0, f64::max);
        (
            Spectrum::new(mean[0] as f32, mean[1] as f32, mean[2] as f32),
            se as f32,
        )
    }

    /// Sampling agrees with evaluation: each sample's f and pdf are `f()` and `pdf()`, the pdf
    /// integrates to the rate at which sampling succeeds, and ∫ f cos estimated by sampling
    /// (E[f cos / pdf]) equals the estimate over uniform directions.
    #[test]
    fn sampling_agrees_with_evaluation() {
        let sets = [
            "\"rgb color\" [0.8 0.5 0.3]",
            "\"rgb color\" [0.9 0.6 0.3] \"float metallic\" 1 \"float roughness\" 0.4",
            "\"rgb color\" [0.7 0.7 0.7] \"float metallic\" 0.6 \"float anisotropic\" 0.8 \"float roughness\" 0.6 \"float speculartint\" 0.5",
            "\"rgb color\" [0.1 0.3 0.6] \"float clearcoat\" 1 \"float clearcoatgloss\" 0",
            "\"rgb color\" [0.6 0.2 0.4] \"float sheen\" 1 \"float roughness\" 0.8",
            "\"rgb color\" [0.9 0.9 0.7] \"float spectrans\" 0.7 \"float roughness\" 0.5 \"float eta\" 1.33",
            "\"rgb color\" [0.5 0.8 0.3] \"bool thin\" \"true\" \"float spectrans\" 0.6 \"float flatness\" 0.4 \"float difftrans\" 0.8 \"float roughness\" 0.6",
            "\"rgb color\" [0.7 0.4 0.3] \"bool thin\" \"true\" \"float spectrans\" 0.5 \"float flatness\" 0.7 \"float sheen\" 0.6 \"float clearcoat\" 0.5 \"float clearcoatgloss\" 0 \"float metallic\" 0.2 \"float roughness\" 0.7 \"float anisotropic\" 0.5",
        ];
        for (k, p) in sets.iter().enumerate() {
            let b = material(p).bsdf(&flat_hit());
            for (j, wo) in test_directions().into_iter().enumerate() {
                let seed = (10 * k + j) as u64;
                sample_matches_eval(&b, wo, 2000, seed);
                let (integral, se, success) = pdf_integral(&b, wo, 200, seed);
                let transmits = b.lobes().iter().any(|l| {
                    l.bxdf.kind().contains(BxdfType::TRANSMISSION)
                        && l.bxdf.kind().contains(BxdfType::GLOSSY)
                });
                if transmits && wo.z.abs() < 0.2 {
                    // pbrt-v3's rough transmission pdf also counts microfacets facing away from
                    // a grazing wo, which its sampler never picks (see src/bsdf.rs's tests).
                    assert!(
                        integral < 1.1 && integral + 4.0 * se + 0.01 > success,
                        "{p} {wo}"
                    );
                } else {
                    assert!(
                        (integral - success).abs() < 4.0 * se + 0.01,
                        "{p} {wo}: ∫pdf {integral} ± {se}, success {success}"
                    );
                }
                let (a, se_a) = albedo(&b, wo, 100_000, seed);
                let (u, se_u) = uniform_albedo(&b, wo, 400, seed);
                for c in 0..3 {
                    assert!(
                        (a[c] - u[c]).abs() <= 4.0 * (se_a + se_u) + 0.005,
                        "{p} {wo}: sampled {a} ± {se_a}, uniform {u} ± {se_u}"
                    );
                }
            }
        }
    }

    /// The reflection lobes are symmetric in wo and wi, as pbrt-v3's.
    #[test]
    fn reflection_lobes_are_reciprocal() {
        let b = material(
            "\"rgb color\" [0.7 0.4 0.3] \"bool thin\" \"true\" \"float spectrans\" 0.5 \"float flatness\" 0.7 \"float sheen\" 0.6 \"float clearcoat\" 0.5 \"float metallic\" 0.2 \"float anisotropic\" 0.5",
        )
        .bsdf(&flat_hit());
        assert_eq!(b.num_lobes(), 8);
        let mut rng = Rng::new(5);
        for _ in 0..500 {
            let x = cosine_sample_hemisphere(rng.next_2d());
            let y = cosine_sample_hemisphere(rng.next_2d());
            for l in b.lobes() {
                if l.bxdf.kind().contains(BxdfType::REFLECTION) {
                    let (fxy, fyx) = (l.bxdf.f(x, y), l.bxdf.f(y, x));
                    assert!(close_s(fxy, fyx, 1e-4), "{:?}: {fxy} vs {fyx}", l.bxdf);
                }
            }
        }
    }

    /// Defaults are pbrt-v3's (colour 0.5, roughness 0.5, eta 1.5: three lobes), a non-zero
    /// `scatterdistance` warns, and degenerate directions give finite values.
    #[test]
    fn defaults_warnings_and_degenerate_directions() {
        let b = material("").bsdf(&flat_hit());
        let names: Vec<_> = b.lobes().iter().map(|l| pbrt_name(&l.bxdf)).collect();
        assert_eq!(
            names,
            ["DisneyDiffuse", "DisneyRetro", "MicrofacetReflection"]
        );
        let Bxdf::Disney(DisneyBxdf::Specular {
            distribution,
            r0,
            metallic,
            eta,
        }) = b.lobes()[2].bxdf
        else {
            panic!()
        };
        assert_eq!(
            (distribution.alpha_x, distribution.alpha_y, metallic, eta),
            (0.25, 0.25, 0.0, 1.5)
        );
        assert!((r0 - Spectrum::splat(0.04)).abs().max_element() < 1e-7);

        let text = "WorldBegin\nMaterial \"disney\" \"rgb scatterdistance\" [1 1 1]\nShape \"sphere\"\nWorldEnd\n";
        let desc = parse_str(text, Path::new("/tmp/scene.pbrt")).unwrap();
        let mut w = Vec::new();
        let m = build_materials(&desc, Path::new("/tmp"), glam::DMat4::IDENTITY, &mut w).unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].message.contains("scatterdistance") && w[0].loc.is_some());
        assert_eq!(m.last().unwrap().bsdf(&flat_hit()).num_lobes(), 3);

        let b = material(
            "\"bool thin\" \"true\" \"float spectrans\" 0.5 \"float flatness\" 0.7 \"float sheen\" 0.6 \"float clearcoat\" 0.5 \"float anisotropic\" 0.5 \"float roughness\" 0",
        )
        .bsdf(&flat_hit());
        let mut lobes: Vec<Bxdf> = b.lobes().iter().map(|l| l.bxdf).collect();
        lobes.push(Bxdf::Disney(DisneyBxdf::Transmission {
            t: Spectrum::ONE,
            distribution: TrowbridgeReitz::new(0.001, 0.001),
            eta: 1.5,
        }));
        let dirs = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1.0, 0.0, 1e-7).normalize(),
            Vec3::new(0.0, 1.0, -1e-7).normalize(),
            Vec3::ZERO,
        ];
        let us = [Vec2::ZERO, Vec2::splat(0.5), Vec2::splat(ONE_MINUS_EPSILON)];
        for l in lobes {
            for wo in dirs {
                for wi in dirs {
                    assert!(
                        l.f(wo, wi).is_finite() && l.pdf(wo, wi).is_finite(),
                        "{l:?} {wo} {wi}"
                    );
                }
                for u in us {
                    if let Some(s) = l.sample_f(wo, u) {
                        assert!(
                            s.f.is_finite() && s.pdf > 0.0 && s.pdf.is_finite() && s.wi.is_finite()
                        );
                    }
                }
            }
        }
    }

    /// The Disney lobes fit in the space of the largest other lobes.
    #[test]
    fn lobes_stay_small() {
        assert!(std::mem::size_of::<DisneyBxdf>() <= 32);
        println!("Bxdf: {} bytes", std::mem::size_of::<Bxdf>());
    }
}
