//! Materials and textures: named materials, texture references resolved to indices, and
//! the `Texture` directive.

use super::Builder;
use crate::error::{Error, Result};
use crate::params::{ParamList, Values};
use crate::scene::{MaterialDesc, PluginDesc, TextureDesc, TextureValue};
use crate::source::Loc;
use crate::suggest::did_you_mean;
use std::sync::Arc;

impl Builder {
    /// `NamedMaterial "name"`. A name not defined (yet) is a warning that keeps the current
    /// material, as pbrt-v3's `pbrtNamedMaterial` does: scenes rely on it (pbrt-v3-scenes'
    /// contemporary-bathroom names a material before the `Include` that defines it).
    pub fn named_material(&mut self, name: &str, loc: &Loc) -> Result<()> {
        self.require_world("NamedMaterial", loc)?;
        match self.graphics.named_materials.get(name) {
            Some(&i) => self.graphics.material = Some(i),
            None => {
                let message = format!(
                    "{}; the current material is kept (as pbrt-v3 does)",
                    self.unknown_material(name, loc).message()
                );
                self.warn(loc, message);
            }
        }
        Ok(())
    }

    pub(super) fn unknown_material(&self, name: &str, loc: &Loc) -> Error {
        let known = self.graphics.named_materials.keys().map(String::as_str);
        Error::at(
            loc,
            format!("no material named \"{name}\"{}", did_you_mean(name, known)),
        )
    }

    /// Resolves every texture parameter against the textures in scope.
    pub(super) fn resolve_textures(&self, params: &mut ParamList) -> Result<()> {
        for p in params.iter_mut() {
            if let Values::Texture(t) = &mut p.values {
                t.float = self.graphics.float_textures.get(&t.name).copied();
                t.spectrum = self.graphics.spectrum_textures.get(&t.name).copied();
                if t.float.is_none() && t.spectrum.is_none() {
                    let known = self
                        .graphics
                        .float_textures
                        .keys()
                        .chain(self.graphics.spectrum_textures.keys())
                        .map(String::as_str);
                    return Err(Error::at(
                        &p.loc,
                        format!(
                            "no texture named \"{}\"{}",
                            t.name,
                            did_you_mean(&t.name, known)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// For `mix`: the materials its `namedmaterial1` and `namedmaterial2` name.
    pub(super) fn resolve_mix(&self, plugin: &PluginDesc) -> Result<Option<[usize; 2]>> {
        if plugin.kind != "mix" {
            return Ok(None);
        }
        let mut out = [0; 2];
        for (slot, key) in out.iter_mut().zip(["namedmaterial1", "namedmaterial2"]) {
            let Some(name) = plugin.params.string(key)? else {
                return Err(Error::at(
                    &plugin.loc,
                    format!("mix material needs \"string {key}\""),
                ));
            };
            let loc = plugin
                .params
                .get(key)
                .map_or_else(|| plugin.loc.clone(), |p| p.loc.clone());
            *slot = *self
                .graphics
                .named_materials
                .get(name)
                .ok_or_else(|| self.unknown_material(name, &loc))?;
        }
        Ok(Some(out))
    }

    pub(super) fn add_material(
        &mut self,
        name: Option<String>,
        mut plugin: PluginDesc,
    ) -> Result<usize> {
        self.resolve_textures(&mut plugin.params)?;
        let mix = self.resolve_mix(&plugin)?;
        self.scene
            .materials
            .push(MaterialDesc { name, plugin, mix });
        Ok(self.scene.materials.len() - 1)
    }

    /// `Texture "name" "float|color|spectrum" "class" params`.
    pub fn texture(
        &mut self,
        name: String,
        value: &str,
        class: String,
        mut params: ParamList,
        loc: Loc,
    ) -> Result<()> {
        self.require_world("Texture", &loc)?;
        let value = match value {
            "float" => TextureValue::Float,
            "color" | "spectrum" | "rgb" => TextureValue::Spectrum,
            other => {
                return Err(Error::at(
                    &loc,
                    format!(
                        "texture type must be \"float\" or \"color\"/\"spectrum\", not \"{other}\""
                    ),
                ))
            }
        };
        self.resolve_textures(&mut params)?;
        let index = self.scene.textures.len();
        let table = match value {
            TextureValue::Float => &mut self.graphics.float_textures,
            TextureValue::Spectrum => &mut self.graphics.spectrum_textures,
        };
        let previous = Arc::make_mut(table).insert(name.clone(), index);
        if previous.is_some() {
            self.warn(&loc, format!("texture \"{name}\" redefined"));
        }
        self.scene.textures.push(TextureDesc {
            name,
            value,
            plugin: PluginDesc {
                kind: class,
                params,
                loc,
            },
            world_from_texture: self.ctm[0],
        });
        Ok(())
    }
}
