//! pbrt-v3's `hair` material (materials/hair.{h,cpp}): the parameters, textured, from which a
//! hit on a curve gets its lobe, [`crate::bsdf::hair::HairBsdf`].

use crate::bsdf::hair::{sigma_a_from_concentration, sigma_a_from_reflectance, HairBsdf};
use crate::bsdf::{Bsdf, Bxdf};
use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::texture::{FloatTexture, SpectrumTexture, Texture, TextureBuilder};
use acr_parser::{Error, Loc, ParamList, Result};

/// pbrt-v3's `HairMaterial`: the parameters, textured, from which a hit gets its [`HairBsdf`].
/// Its absorption comes from `sigma_a` if given, else from `color`, else from the melanin
/// concentrations (pbrt-v3's precedence; with none of them, eumelanin 1.3 as `sigma_a`).
#[derive(Clone, Debug)]
pub struct HairMaterial {
    /// Absorption coefficient of the interior, per unit radius.
    pub sigma_a: Option<SpectrumTexture>,
    /// The colour the hair should look, turned into an absorption.
    pub color: Option<SpectrumTexture>,
    /// Eumelanin concentration (brown-black).
    pub eumelanin: Option<FloatTexture>,
    /// Pheomelanin concentration (red-yellow).
    pub pheomelanin: Option<FloatTexture>,
    /// Index of refraction of the interior (1.55).
    pub eta: FloatTexture,
    /// Longitudinal roughness in (0, 1] (0.3).
    pub beta_m: FloatTexture,
    /// Azimuthal roughness in (0, 1] (0.3).
    pub beta_n: FloatTexture,
    /// The scales' tilt in degrees (2).
    pub alpha: FloatTexture,
}

impl HairMaterial {
    /// pbrt-v3's `CreateHairMaterial`: its precedence among `sigma_a`, `color` and the melanins,
    /// with its warnings for the ones ignored (at their location). A constant `beta_m` or
    /// `beta_n` outside (0, 1] or `eta` below 1 is a located error: pbrt-v3 aborts on them.
    pub fn from_params(t: &mut TextureBuilder<'_>, p: &ParamList, loc: &Loc) -> Result<Self> {
        let mut sigma_a = t.spectrum_param_opt(p, "sigma_a")?;
        let color = t.spectrum_param_opt(p, "color")?;
        let eumelanin = t.float_param_opt(p, "eumelanin")?;
        let pheomelanin = t.float_param_opt(p, "pheomelanin")?;
        let used = if sigma_a.is_some() {
            Some("\"sigma_a\"")
        } else if color.is_some() {
            Some("\"color\"")
        } else if eumelanin.is_some() || pheomelanin.is_some() {
            Some("\"eumelanin\"/\"pheomelanin\"")
        } else {
            None
        };
        if let Some(used) = used {
            let given = [
                ("sigma_a", sigma_a.is_some()),
                ("color", color.is_some()),
                ("eumelanin", eumelanin.is_some()),
                ("pheomelanin", pheomelanin.is_some()),
            ];
            for (name, present) in given {
                if present && !used.contains(&format!("\"{name}\"")) {
                    let at = p.get(name).map_or_else(|| loc.clone(), |q| q.loc.clone());
                    t.warn_once(
                        format!("hair ignores {name} at {at}"),
                        &at,
                        format!("Ignoring \"{name}\" parameter since {used} was provided."),
                    );
                }
            }
        } else {
            // pbrt-v3's default: brown-ish hair.
            sigma_a = Some(Texture::Constant(sigma_a_from_concentration(1.3, 0.0)));
        }
        let mut float = |name: &str, default: f32, ok: fn(f32) -> bool, range: &str| {
            let tex = t.float_param(p, name, default)?;
            match tex.as_constant() {
                Some(v) if !ok(v) => {
                    let at = p.get(name).map_or_else(|| loc.clone(), |q| q.loc.clone());
                    Err(Error::at(
                        &at,
                        format!("hair \"{name}\" {v} is not {range} (pbrt-v3 aborts on it)"),
                    ))
                }
                _ => Ok(tex),
            }
        };
        let beta_ok: fn(f32) -> bool = |v| v > 0.0 && v <= 1.0;
        Ok(Self {
            sigma_a,
            color,
            eumelanin,
            pheomelanin,
            eta: float("eta", 1.55, |v| v >= 1.0, "at least 1")?,
            beta_m: float("beta_m", 0.3, beta_ok, "in (0, 1]")?,
            beta_n: float("beta_n", 0.3, beta_ok, "in (0, 1]")?,
            alpha: float("alpha", 2.0, f32::is_finite, "finite")?,
        })
    }

    /// The lobe at a hit and the BSDF's relative index (pbrt-v3's
    /// `HairMaterial::ComputeScatteringFunctions`): h = -1 + 2 v across the curve.
    pub fn bxdf(&self, si: &SurfaceInteraction) -> (HairBsdf, f32) {
        let bm = self.beta_m.eval(si);
        let bn = self.beta_n.eval(si);
        let a = self.alpha.eval(si);
        let e = self.eta.eval(si);
        let sig_a = if let Some(s) = &self.sigma_a {
            s.eval(si).max(Spectrum::ZERO)
        } else if let Some(c) = &self.color {
            sigma_a_from_reflectance(c.eval(si).max(Spectrum::ZERO), bn)
        } else {
            let c = |t: &Option<FloatTexture>| t.as_ref().map_or(0.0, |t| t.eval(si)).max(0.0);
            sigma_a_from_concentration(c(&self.eumelanin), c(&self.pheomelanin))
        };
        let h = -1.0 + 2.0 * si.uv.y;
        (HairBsdf::new(h, e, sig_a, bm, bn, a), e)
    }

    /// Adds its lobe to `b`, weighted by `scale`; as the `first` material (the one that owns
    /// the BSDF) it sets the BSDF's relative index to the hair's.
    #[inline]
    pub fn add_lobes(&self, si: &SurfaceInteraction, b: &mut Bsdf, scale: Spectrum, first: bool) {
        let (bxdf, eta) = self.bxdf(si);
        if first {
            b.set_eta(eta);
        }
        b.add_scaled(Bxdf::Hair(bxdf), scale);
    }
}
