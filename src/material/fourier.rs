//! pbrt-v3's `fourier` material (materials/fourier.cpp): a BSDF tabulated in a `.bsdf` file
//! ([`crate::fourier`]), the same at every hit.

use crate::bsdf::{Bsdf, Bxdf};
use crate::fourier::{FourierBsdf, FourierTable};
use crate::geometry::Spectrum;
use crate::texture::TextureBuilder;
use acr_parser::{Error, Loc, ParamList, Result};

/// pbrt-v3's `fourier`: the table its `bsdffile` names.
#[derive(Clone, Debug)]
pub struct Fourier {
    /// The tabulated lobe.
    pub bsdf: FourierBsdf,
}

impl Fourier {
    /// The material from its parameters: `bsdffile`, required, read once per file (a located
    /// error when it is missing or unreadable).
    pub fn from_params(t: &mut TextureBuilder, p: &ParamList, loc: &Loc) -> Result<Self> {
        let Some(name) = p.string("bsdffile")? else {
            return Err(Error::at(loc, "fourier material needs \"string bsdffile\""));
        };
        let at = p.get("bsdffile").map_or(loc, |x| &x.loc).clone();
        let path = t.resolve_file(name, &at);
        let table = FourierTable::load(&path)
            .map_err(|e| Error::at(&at, format!("fourier material: {e}")))?;
        Ok(Self {
            bsdf: FourierBsdf { table },
        })
    }

    /// Adds its lobe to `b`, weighted by `scale`.
    #[inline]
    pub fn add_lobes(&self, b: &mut Bsdf, scale: Spectrum) {
        b.add_scaled(Bxdf::Fourier(self.bsdf), scale);
    }
}
