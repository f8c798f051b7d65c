//! Materials from the scene description: each built once, on demand (a mix builds the two it
//! blends), with its textures; unknown types and unsupported parameters reported where they
//! are written.

use super::{
    DisneyMaterial, Fourier, Glass, HairMaterial, Material, Matte, Metal, Mirror, Plastic,
    Substrate, Subsurface, Translucent, Uber,
};
use crate::geometry::Spectrum;
use crate::texture::TextureBuilder;
use acr_parser::{Error, MaterialDesc, ParamList, Result, SceneDescription, Warning};
use std::path::Path;
use std::sync::Arc;

/// Material types acr builds.
const KINDS: [&str; 14] = [
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
    "subsurface",
    "kdsubsurface",
];
/// Types that make no surface: rays pass through.
const INTERFACE_KINDS: [&str; 3] = ["", "none", "interface"];
/// Parameters pbrt-v3 (or pbrt-v4) materials take that acr ignores, with a warning.
const UNSUPPORTED_PARAMS: [&str; 2] = ["displacement", "normalmap"];

/// Builds materials from their descriptions, textures on demand.
pub(super) struct MaterialBuilder<'a> {
    /// The scene whose materials these are.
    pub(super) desc: &'a SceneDescription,
    /// The textures, built as materials ask for them.
    pub(super) textures: TextureBuilder<'a>,
    /// Each material once built (a mix shares the two it blends).
    pub(super) built: Vec<Option<Arc<Material>>>,
    /// Materials being built: a mix that reaches one again refers to itself.
    pub(super) in_progress: Vec<bool>,
}

impl<'a> MaterialBuilder<'a> {
    /// Material `index` of the description, built once (with its `bumpmap`, if any).
    pub(super) fn build(&mut self, index: usize) -> Result<Arc<Material>> {
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
        Ok(match kind {
            "matte" => Material::Matte(Matte::from_params(t, p)?),
            "plastic" => Material::Plastic(Plastic::from_params(t, p)?),
            "mirror" => Material::Mirror(Mirror::from_params(t, p)?),
            "glass" => Material::Glass(Glass::from_params(t, p)?),
            "metal" => Material::Metal(Metal::from_params(t, p)?),
            "uber" => Material::Uber(Uber::from_params(t, p)?),
            "substrate" => Material::Substrate(Substrate::from_params(t, p)?),
            "translucent" => Material::Translucent(Translucent::from_params(t, p)?),
            "hair" => Material::Hair(HairMaterial::from_params(t, p, loc)?),
            "fourier" => Material::Fourier(Fourier::from_params(t, p, loc)?),
            "disney" => Material::Disney(Box::new(DisneyMaterial::from_params(t, p, loc)?)),
            "subsurface" => Material::Subsurface(Box::new(Subsurface::from_params(t, p, loc)?)),
            "kdsubsurface" => {
                Material::Subsurface(Box::new(Subsurface::kd_from_params(t, p, loc)?))
            }
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
            other => return Err(unknown_kind(other, loc)),
        })
    }
}

fn unknown_kind(kind: &str, loc: &acr_parser::Loc) -> Error {
    let hint = acr_parser::closest(kind, KINDS.iter().copied())
        .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
    Error::at(loc, format!("unknown material \"{kind}\"{hint}"))
}

/// Which materials shapes use, directly or through mix materials.
pub(super) fn used_materials(desc: &SceneDescription) -> Vec<bool> {
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
        if !(KINDS.contains(&k) || INTERFACE_KINDS.contains(&k)) {
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
