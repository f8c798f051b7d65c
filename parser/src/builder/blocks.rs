//! The block directives: the world block, attribute and transform blocks (saving and
//! restoring the graphics state), and object definitions and their instances.

use super::{Block, Builder, Phase, Saved};
use crate::error::{Error, Result};
use crate::scene::{InstanceDesc, ObjectDesc};
use crate::source::Loc;
use crate::suggest::did_you_mean;
use glam::DMat4;

impl Builder {
    /// `WorldBegin`.
    pub fn world_begin(&mut self, loc: &Loc) -> Result<()> {
        if self.phase != Phase::Options {
            return Err(Error::at(loc, "WorldBegin appears twice"));
        }
        if let Some(open) = self.stack.last() {
            return Err(Error::at(
                loc,
                format!(
                    "WorldBegin inside the {} at {}",
                    open.block.begin_name(),
                    open.loc
                ),
            ));
        }
        self.phase = Phase::World;
        self.ctm = [DMat4::IDENTITY; 2];
        self.active = [true; 2];
        self.named_coordinate_systems
            .insert("world".to_owned(), self.ctm);
        Ok(())
    }

    /// `WorldEnd`.
    pub fn world_end(&mut self, loc: &Loc) -> Result<()> {
        self.require_world("WorldEnd", loc)?;
        self.warn_open_blocks();
        self.phase = Phase::Done;
        Ok(())
    }

    pub(super) fn warn_open_blocks(&mut self) {
        let open: Vec<(Loc, &'static str)> = self
            .stack
            .iter()
            .map(|s| (s.loc.clone(), s.block.begin_name()))
            .collect();
        // One warning for the outermost: deep nesting would otherwise flood the output.
        if let Some((loc, name)) = open.first() {
            self.warn(
                loc,
                format!("{name} is never closed ({} blocks open in all)", open.len()),
            );
        }
    }

    /// Called once after the last token of the main file.
    pub fn end_of_input(&mut self, end: &Loc) {
        if self.phase == Phase::World {
            self.warn_open_blocks();
            self.warn(end, "the file ends without WorldEnd");
        }
    }

    pub(super) fn push(&mut self, block: Block, loc: &Loc) {
        let graphics = (block != Block::Transform).then(|| self.graphics.clone());
        self.stack.push(Saved {
            block,
            graphics,
            ctm: self.ctm,
            active: self.active,
            loc: loc.clone(),
        });
    }

    pub(super) fn pop(&mut self, block: Block, end_name: &str, loc: &Loc) -> Result<()> {
        match self.stack.last() {
            None => Err(Error::at(
                loc,
                format!("{end_name} without a matching {}", block.begin_name()),
            )),
            Some(top)
                if top.block != block
                    && !(top.block.saves_attributes() && block.saves_attributes()) =>
            {
                Err(Error::at(
                    loc,
                    format!(
                        "{end_name} closes the {} at {}",
                        top.block.begin_name(),
                        top.loc
                    ),
                ))
            }
            Some(top) => {
                if top.block != block {
                    // pbrt-v3's ObjectBegin and ObjectEnd are an AttributeBegin and an
                    // AttributeEnd on one shared stack, and real scenes (San Miguel) cross
                    // them; see docs/pbrt-v3-compatibility.md.
                    let message = format!(
                        "{end_name} closes the {} at {}; accepted, as pbrt-v3 keeps both on one stack",
                        top.block.begin_name(),
                        top.loc
                    );
                    if self
                        .warned_once
                        .insert("crossed attribute and object blocks".to_owned())
                    {
                        self.warn(loc, message);
                    }
                }
                if let Some(saved) = self.stack.pop() {
                    if let Some(g) = saved.graphics {
                        self.graphics = g;
                    }
                    self.ctm = saved.ctm;
                    self.active = saved.active;
                }
                Ok(())
            }
        }
    }

    /// `AttributeBegin`.
    pub fn attribute_begin(&mut self, loc: &Loc) -> Result<()> {
        self.require_world("AttributeBegin", loc)?;
        self.push(Block::Attribute, loc);
        Ok(())
    }

    /// `AttributeEnd`.
    pub fn attribute_end(&mut self, loc: &Loc) -> Result<()> {
        self.require_world("AttributeEnd", loc)?;
        self.pop(Block::Attribute, "AttributeEnd", loc)
    }

    /// `TransformBegin` (allowed before the world too, as in pbrt-v3).
    pub fn transform_begin(&mut self, loc: &Loc) -> Result<()> {
        self.push(Block::Transform, loc);
        Ok(())
    }

    /// `TransformEnd`.
    pub fn transform_end(&mut self, loc: &Loc) -> Result<()> {
        self.pop(Block::Transform, "TransformEnd", loc)
    }

    /// `ObjectBegin "name"`: starts an object definition (and, as in pbrt-v3, an attribute block).
    pub fn object_begin(&mut self, name: String, loc: &Loc) -> Result<()> {
        self.require_world("ObjectBegin", loc)?;
        if let Some((outer, def)) = &self.current_object {
            return Err(Error::at(
                loc,
                format!(
                    "ObjectBegin \"{name}\" inside the definition of \"{outer}\" begun at {}",
                    def.loc
                ),
            ));
        }
        self.push(Block::Object, loc);
        self.current_object = Some((
            name,
            ObjectDesc {
                shapes: Vec::new(),
                loc: loc.clone(),
            },
        ));
        Ok(())
    }

    /// `ObjectEnd`.
    pub fn object_end(&mut self, loc: &Loc) -> Result<()> {
        self.require_world("ObjectEnd", loc)?;
        if self.current_object.is_none() {
            return Err(Error::at(loc, "ObjectEnd without a matching ObjectBegin"));
        }
        self.pop(Block::Object, "ObjectEnd", loc)?;
        if let Some((name, def)) = self.current_object.take() {
            if let Some(old) = self.scene.objects.get(&name) {
                let old_loc = old.loc.clone();
                self.warn(
                    loc,
                    format!("object \"{name}\" redefined (first defined at {old_loc})"),
                );
            }
            self.scene.objects.insert(name, def);
        }
        Ok(())
    }

    /// `ObjectInstance "name"`.
    pub fn object_instance(&mut self, name: &str, loc: &Loc) -> Result<()> {
        self.require_world("ObjectInstance", loc)?;
        if let Some((outer, _)) = &self.current_object {
            return Err(Error::at(
                loc,
                format!("ObjectInstance inside the definition of object \"{outer}\""),
            ));
        }
        let Some(object) = self.scene.objects.get_index_of(name) else {
            let known = self.scene.objects.keys().map(String::as_str);
            return Err(Error::at(
                loc,
                format!("no object named \"{name}\"{}", did_you_mean(name, known)),
            ));
        };
        self.scene.instances.push(InstanceDesc {
            object,
            world_from_instance: self.animated(),
            loc: loc.clone(),
        });
        Ok(())
    }
}
