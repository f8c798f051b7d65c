//! pbrt-v3's `subsurface` and `kdsubsurface` materials (materials/subsurface.cpp,
//! kdsubsurface.cpp): a dielectric surface (smooth or rough, `Kr`, `Kt`) over a scattering
//! medium whose [`TabulatedBssrdf`] the path integrator samples when a path is transmitted
//! (docs/subsurface.md). `subsurface` takes the medium's coefficients (`sigma_a`, `sigma_s`,
//! `scale`, or a named measurement), `kdsubsurface` a diffuse reflectance `Kd` and a mean free
//! path `mfp`, inverted through the table as pbrt-v3's `SubsurfaceFromDiffuse`.

use super::glass::Glass;
use super::shared::{clamp0, remap_roughness};
use crate::bsdf::Bsdf;
use crate::bssrdf::{table_for, BssrdfTable, TabulatedBssrdf};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::medium::presets as measured;
use crate::texture::{SpectrumTexture, Texture, TextureBuilder};
use acr_parser::{Error, Loc, ParamList, Result};
use std::sync::Arc;

/// What the medium's coefficients come from.
#[derive(Clone, Debug)]
pub enum Coefficients {
    /// `subsurface`: σa and σs, each times `scale`.
    Direct {
        /// Absorption.
        sigma_a: SpectrumTexture,
        /// Scattering.
        sigma_s: SpectrumTexture,
    },
    /// `kdsubsurface`: the diffuse reflectance and the mean free path (times `scale`).
    Diffuse {
        /// Effective albedo.
        kd: SpectrumTexture,
        /// Mean free path.
        mfp: SpectrumTexture,
    },
}

/// pbrt-v3's `SubsurfaceMaterial` or `KdSubsurfaceMaterial`.
#[derive(Clone, Debug)]
pub struct Subsurface {
    /// The boundary: a dielectric of index `eta` with `Kr`, `Kt` and roughness.
    pub surface: Glass,
    /// Relative index of refraction.
    pub eta: f32,
    /// Scale of the coefficients (or of the mean free path).
    pub scale: f32,
    /// The medium's coefficients.
    pub coefficients: Coefficients,
    /// The profile table for this material's g and eta (shared by equal materials).
    pub table: Arc<BssrdfTable>,
    /// With constant coefficients: σa, σs and the sampling radius bounds, found once (the
    /// kdsubsurface inversion and the bound's spline sampling otherwise run at every hit).
    fixed: Option<Fixed>,
}

/// What a material with constant coefficients computes once.
#[derive(Clone, Copy, Debug)]
struct Fixed {
    sigma_a: Spectrum,
    sigma_s: Spectrum,
    r_max: [Option<f32>; 3],
}

/// pbrt-v3's default `subsurface` coefficients (its `Wholemilk` measurement), in mm⁻¹.
const DEFAULT_SIGMA_A: Spectrum = Spectrum::new(0.0011, 0.0024, 0.014);
/// pbrt-v3's default `subsurface` scattering.
const DEFAULT_SIGMA_S: Spectrum = Spectrum::new(2.55, 3.21, 3.77);

impl Subsurface {
    /// `subsurface` from its parameters (pbrt-v3's `CreateSubsurfaceMaterial`): `name` (a
    /// measurement: its reduced coefficients, and g forced to 0), `sigma_a`, `sigma_s`, `g` (0),
    /// `scale` (1), `eta` (1.33), `Kr`, `Kt` (1), `uroughness`, `vroughness` (0),
    /// `remaproughness`. Warnings (an unknown name, negative coefficients) go to `t`.
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList, loc: &Loc) -> Result<Self> {
        let (mut sig_a, mut sig_s) = (DEFAULT_SIGMA_A, DEFAULT_SIGMA_S);
        let mut measurement = false;
        if let Some(name) = p.string("name")? {
            let at = p.get("name").map_or(loc, |q| &q.loc);
            match measured::lookup(name) {
                Some((a, s)) => (sig_a, sig_s, measurement) = (a, s, true),
                None if !name.is_empty() => {
                    let hint = acr_parser::closest(name, measured::names())
                        .map_or(String::new(), |n| format!(" (did you mean \"{n}\"?)"));
                    t.warn_once(
                        format!("subsurface name {name}"),
                        at,
                        format!(
                            "subsurface measurement \"{name}\" not found{hint}; \
                             pbrt-v3's defaults are used"
                        ),
                    );
                }
                None => {}
            }
        }
        // The measurements are reduced coefficients: pbrt-v3 sets g to 0 (whatever is given).
        let g = if measurement {
            p.get("g");
            0.0
        } else {
            checked(p, "g", 0.0, loc, |g| g > -1.0 && g < 1.0, "in (-1, 1)")?
        };
        let sigma_a = t.spectrum_param(p, "sigma_a", sig_a)?;
        let sigma_s = t.spectrum_param(p, "sigma_s", sig_s)?;
        warn_negative(t, p, &["sigma_a", "sigma_s"]);
        Self::with(t, p, loc, g, Coefficients::Direct { sigma_a, sigma_s })
    }

    /// `kdsubsurface` from its parameters (pbrt-v3's `CreateKdSubsurfaceMaterial`): `Kd`
    /// (0.5), `mfp` (1), `g` (0), `scale` (1), `eta` (1.33), and the surface's as `subsurface`.
    pub fn kd_from_params(t: &mut TextureBuilder, p: &ParamList, loc: &Loc) -> Result<Self> {
        let kd = t.spectrum_param(p, "Kd", Spectrum::splat(0.5))?;
        let mfp = t.spectrum_param(p, "mfp", Spectrum::ONE)?;
        warn_negative(t, p, &["Kd", "mfp"]);
        let g = checked(p, "g", 0.0, loc, |g| g > -1.0 && g < 1.0, "in (-1, 1)")?;
        Self::with(t, p, loc, g, Coefficients::Diffuse { kd, mfp })
    }

    /// The parameters both share, and the table for `g` and eta.
    fn with(
        t: &mut TextureBuilder,
        p: &ParamList,
        loc: &Loc,
        g: f32,
        coefficients: Coefficients,
    ) -> Result<Self> {
        // Below 1 the single-scattering term has no critical angle (pbrt-v3's table is NaN).
        let eta = checked(p, "eta", 1.33, loc, |e| e >= 1.0, "at least 1")?;
        let scale = checked(p, "scale", 1.0, loc, |s| s >= 0.0, "non-negative")?;
        let surface = Glass {
            kr: t.spectrum_param(p, "Kr", Spectrum::ONE)?,
            kt: t.spectrum_param(p, "Kt", Spectrum::ONE)?,
            eta: Texture::Constant(eta),
            u_roughness: t.float_param(p, "uroughness", 0.0)?,
            v_roughness: t.float_param(p, "vroughness", 0.0)?,
            remap_roughness: remap_roughness(p)?,
        };
        let mut m = Self {
            surface,
            eta,
            scale,
            coefficients,
            table: table_for(g, eta),
            fixed: None,
        };
        let constant = match &m.coefficients {
            Coefficients::Direct { sigma_a, sigma_s } => {
                sigma_a.as_constant().zip(sigma_s.as_constant())
            }
            Coefficients::Diffuse { kd, mfp } => kd.as_constant().zip(mfp.as_constant()),
        };
        if let Some((a, b)) = constant {
            let (sigma_a, sigma_s) = m.coefficients_from(a, b);
            let frame = crate::geometry::Frame::from_z(crate::geometry::Vec3::Z);
            let r_max =
                TabulatedBssrdf::with_frame(frame.n, frame, eta, sigma_a, sigma_s, &m.table)
                    .radius_bounds();
            m.fixed = Some(Fixed {
                sigma_a,
                sigma_s,
                r_max,
            });
        }
        Ok(m)
    }

    /// σa and σs from the two coefficient values evaluated at a hit (σa and σs, or Kd and
    /// mfp), with pbrt-v3's clamps and scale.
    fn coefficients_from(&self, a: Spectrum, b: Spectrum) -> (Spectrum, Spectrum) {
        match self.coefficients {
            Coefficients::Direct { .. } => (self.scale * clamp0(a), self.scale * clamp0(b)),
            Coefficients::Diffuse { .. } => self
                .table
                .subsurface_from_diffuse(clamp0(a), self.scale * clamp0(b)),
        }
    }

    /// Adds the boundary's lobes (pbrt-v3's dielectric: one `FresnelSpecular` where smooth and
    /// `allow_multiple_lobes`), weighted by `scale`; sets the BSDF's index when `first`.
    #[inline]
    pub fn add_lobes(
        &self,
        si: &SurfaceInteraction,
        allow_multiple_lobes: bool,
        b: &mut Bsdf,
        scale: Spectrum,
        first: bool,
    ) {
        self.surface
            .add_lobes(si, allow_multiple_lobes, b, scale, first)
    }

    /// The BSSRDF at (shaded) hit `si`: the coefficients evaluated there, clamped at zero.
    pub fn bssrdf(&self, si: &SurfaceInteraction) -> TabulatedBssrdf<'_> {
        if let Some(f) = &self.fixed {
            let mut b = TabulatedBssrdf::new(si, self.eta, f.sigma_a, f.sigma_s, &self.table);
            b.r_max = Some(f.r_max);
            return b;
        }
        let (a, b) = match &self.coefficients {
            Coefficients::Direct { sigma_a, sigma_s } => (sigma_a.eval(si), sigma_s.eval(si)),
            Coefficients::Diffuse { kd, mfp } => (kd.eval(si), mfp.eval(si)),
        };
        let (sigma_a, sigma_s) = self.coefficients_from(a, b);
        TabulatedBssrdf::new(si, self.eta, sigma_a, sigma_s, &self.table)
    }
}

/// A float parameter `name` (`default` when absent) that must pass `ok`: a located error
/// saying it must be `what` otherwise.
fn checked(
    p: &ParamList,
    name: &str,
    default: f64,
    loc: &Loc,
    ok: impl Fn(f32) -> bool,
    what: &str,
) -> Result<f32> {
    let v = p.float_or(name, default)? as f32;
    if ok(v) {
        return Ok(v);
    }
    let at = p.get(name).map_or(loc, |q| &q.loc);
    Err(Error::at(
        at,
        format!("subsurface \"{name}\" {v} must be {what}"),
    ))
}

/// Warns, once per parameter, where a constant colour parameter has a negative channel
/// (pbrt-v3 clamps it to zero silently).
fn warn_negative(t: &mut TextureBuilder, p: &ParamList, names: &[&str]) {
    for name in names {
        let Some(param) = p.get(name) else { continue };
        let Ok(Some(v)) = crate::texture::spectrum_value(p, name) else {
            continue;
        };
        if v.min_element() < 0.0 {
            t.warn_once(
                format!("negative {name}"),
                &param.loc,
                format!("\"{name}\" {v} has a negative channel; it is taken as 0, as pbrt-v3 does"),
            );
        }
    }
}
