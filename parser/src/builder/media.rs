//! Participating media in the graphics state: `MakeNamedMedium` records a medium,
//! `MediumInterface` names the media on either side of the shapes, lights and camera that
//! follow (pbrt-v3's `GraphicsState::CreateMediumInterface`, see docs/media.md).

use super::Builder;
use crate::error::{Error, Result};
use crate::scene::{MediumDesc, MediumInterfaceDesc, PluginDesc};
use crate::source::Loc;
use std::sync::Arc;

/// The `MediumInterface` in effect: the inside and outside media's names ("" for vacuum) and
/// where the directive was written.
#[derive(Clone, Default)]
pub(super) struct MediumNames {
    inside: Arc<str>,
    outside: Arc<str>,
    loc: Option<Loc>,
}

impl Builder {
    /// `MakeNamedMedium "name" "string type" "..." ...`: the medium in the current transform.
    /// A redefinition replaces the medium for later references, as in pbrt-v3.
    pub(super) fn make_named_medium(&mut self, plugin: PluginDesc) -> Result<()> {
        let name = plugin.kind;
        let ty = plugin.params.string("type")?.map(str::to_owned);
        let Some(ty) = ty else {
            return Err(Error::at(
                &plugin.loc,
                format!("MakeNamedMedium \"{name}\" needs a \"string type\" parameter"),
            ));
        };
        if self.ctm[0] != self.ctm[1] {
            self.warn(
                &plugin.loc,
                "animated transformation for MakeNamedMedium: its start transform is used \
                 (as pbrt-v3)",
            );
        }
        let index = self.scene.media.len();
        if self.named_media.insert(name.clone(), index).is_some() {
            self.warn(
                &plugin.loc,
                format!("named medium \"{name}\" redefined; later references use this one"),
            );
        }
        self.scene.media.push(MediumDesc {
            name,
            plugin: PluginDesc {
                kind: ty,
                params: plugin.params,
                loc: plugin.loc,
            },
            world_from_medium: self.ctm[0],
        });
        Ok(())
    }

    /// `MediumInterface "inside" "outside"`.
    pub fn medium_interface(&mut self, inside: &str, outside: &str, loc: &Loc) -> Result<()> {
        self.check_after_world_end("MediumInterface", loc)?;
        self.graphics.media = MediumNames {
            inside: inside.into(),
            outside: outside.into(),
            loc: Some(loc.clone()),
        };
        Ok(())
    }

    /// The media the current `MediumInterface` names, as defined now: a name never defined is
    /// vacuum, with a located warning (pbrt-v3's "Named medium undefined" error, after which it
    /// renders on).
    pub(super) fn current_media(&mut self) -> MediumInterfaceDesc {
        let names = self.graphics.media.clone();
        MediumInterfaceDesc {
            inside: self.medium_named(&names.inside, names.loc.as_ref()),
            outside: self.medium_named(&names.outside, names.loc.as_ref()),
        }
    }

    fn medium_named(&mut self, name: &str, loc: Option<&Loc>) -> Option<usize> {
        if name.is_empty() {
            return None;
        }
        let found = self.named_media.get(name).copied();
        if found.is_none() {
            let key = format!("undefined medium {name}");
            if let Some(loc) = loc {
                if self.warned_once.insert(key) {
                    let known = self.named_media.keys().map(String::as_str);
                    let hint = crate::suggest::closest(name, known)
                        .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
                    self.warn(
                        loc,
                        format!(
                            "named medium \"{name}\" is not defined (yet){hint}: vacuum is \
                             used there, as pbrt-v3 does"
                        ),
                    );
                }
            }
        }
        found
    }
}
