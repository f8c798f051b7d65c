//! The scene description: everything a pbrt file says, resolved, before anything is built.

use crate::error::Warning;
use crate::mesh::Mesh;
use crate::params::ParamList;
use crate::source::{Loc, SourceFile};
use crate::transform::AnimatedTransform;
use glam::DMat4;
use indexmap::IndexMap;
use std::sync::Arc;

/// A plugin chosen by a directive: its type name, parameters and where it was written.
#[derive(Debug, Clone)]
pub struct PluginDesc {
    /// The type name, e.g. `perspective`, `matte`, `halton`.
    pub kind: String,
    /// Its parameters.
    pub params: ParamList,
    /// Where the directive is.
    pub loc: Loc,
}

/// The camera and where it is.
#[derive(Debug, Clone)]
pub struct CameraDesc {
    /// Type and parameters.
    pub plugin: PluginDesc,
    /// Camera-from-world at the shutter's start and end (pbrt's CTM at `Camera`).
    pub camera_from_world: AnimatedTransform,
}

/// A material, from `Material` or `MakeNamedMaterial`.
#[derive(Debug, Clone)]
pub struct MaterialDesc {
    /// The name given by `MakeNamedMaterial`, if any.
    pub name: Option<String>,
    /// Type (from `Material "type"` or `"string type"`) and parameters.
    pub plugin: PluginDesc,
    /// For `mix`: the two materials named by `namedmaterial1` and `namedmaterial2`.
    pub mix: Option<[usize; 2]>,
}

/// Whether a texture yields a float or a spectrum (colour).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TextureValue {
    /// `"float"`
    Float,
    /// `"color"` or `"spectrum"`
    Spectrum,
}

/// A texture from `Texture "name" "type" "class" ...`.
#[derive(Debug, Clone)]
pub struct TextureDesc {
    /// Its name.
    pub name: String,
    /// Float or spectrum.
    pub value: TextureValue,
    /// Class (checkerboard, imagemap...) and parameters.
    pub plugin: PluginDesc,
    /// World-from-texture: the CTM where the texture was defined.
    pub world_from_texture: DMat4,
}

/// A light source.
#[derive(Debug, Clone)]
pub struct LightDesc {
    /// Type and parameters.
    pub plugin: PluginDesc,
    /// World-from-light (pbrt-v3 lights use the CTM at the shutter's start).
    pub world_from_light: DMat4,
    /// The media around it (pbrt-v3 gives a light the interface's outside medium).
    pub media: MediumInterfaceDesc,
}

/// A participating medium from `MakeNamedMedium "name" "string type" ...`.
#[derive(Debug, Clone)]
pub struct MediumDesc {
    /// Its name.
    pub name: String,
    /// Type (`"string type"`: homogeneous, heterogeneous) and parameters.
    pub plugin: PluginDesc,
    /// World-from-medium: the CTM where it was defined (pbrt-v3's `medium2world`).
    pub world_from_medium: DMat4,
}

/// The media on either side of a surface, from the `MediumInterface` in effect: indices into
/// [`SceneDescription::media`], `None` for vacuum (no name, or a name never defined).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MediumInterfaceDesc {
    /// The medium on the side opposite the surface normal.
    pub inside: Option<usize>,
    /// The medium on the side the surface normal points to.
    pub outside: Option<usize>,
}

/// A shape with everything the graphics state attached to it.
#[derive(Debug, Clone)]
pub struct ShapeDesc {
    /// Type and parameters.
    pub plugin: PluginDesc,
    /// World-from-object (or instance-from-object inside `ObjectBegin`), possibly animated.
    pub world_from_object: AnimatedTransform,
    /// `ReverseOrientation` was in effect.
    pub reverse_orientation: bool,
    /// Index into `SceneDescription::materials`; `None` for `Material ""` (no surface).
    pub material: Option<usize>,
    /// The area light in effect, making this shape an emitter.
    pub area_light: Option<Arc<PluginDesc>>,
    /// The triangles of a `trianglemesh` or `plymesh`, read and checked.
    pub mesh: Option<Arc<Mesh>>,
    /// The `MediumInterface` in effect.
    pub media: MediumInterfaceDesc,
}

/// An object definition (`ObjectBegin`/`ObjectEnd`).
#[derive(Debug, Clone)]
pub struct ObjectDesc {
    /// Its shapes, in instance space.
    pub shapes: Vec<ShapeDesc>,
    /// Where `ObjectBegin` is.
    pub loc: Loc,
}

/// A use of an object (`ObjectInstance`).
#[derive(Debug, Clone)]
pub struct InstanceDesc {
    /// Index into `SceneDescription::objects`.
    pub object: usize,
    /// World-from-instance, possibly animated.
    pub world_from_instance: AnimatedTransform,
    /// Where the directive is.
    pub loc: Loc,
}

/// Everything a scene file says: the scene graph, parsed once and then built by the renderer.
#[derive(Debug, Clone)]
pub struct SceneDescription {
    /// Every file read, the main one first.
    pub files: Vec<Arc<SourceFile>>,
    /// The camera; `None` when the file has no `Camera`.
    pub camera: Option<CameraDesc>,
    /// `Film`.
    pub film: Option<PluginDesc>,
    /// `Sampler`.
    pub sampler: Option<PluginDesc>,
    /// `PixelFilter`.
    pub filter: Option<PluginDesc>,
    /// `Integrator`.
    pub integrator: Option<PluginDesc>,
    /// `Accelerator` (accepted; acr always builds its own BVH).
    pub accelerator: Option<PluginDesc>,
    /// `TransformTimes` (default 0 1).
    pub transform_times: (f64, f64),
    /// Every material; index 0 is the default (matte) that shapes get with no `Material`.
    pub materials: Vec<MaterialDesc>,
    /// Named materials at the end of the file (scoped ones are resolved into shapes already).
    pub named_materials: IndexMap<String, usize>,
    /// Every texture, in definition order.
    pub textures: Vec<TextureDesc>,
    /// Light sources (area lights are on their shapes).
    pub lights: Vec<LightDesc>,
    /// Shapes outside object definitions.
    pub shapes: Vec<ShapeDesc>,
    /// Object definitions by name.
    pub objects: IndexMap<String, ObjectDesc>,
    /// Object instances.
    pub instances: Vec<InstanceDesc>,
    /// Warnings found while parsing.
    pub warnings: Vec<Warning>,
    /// Participating media (`MakeNamedMedium`), in definition order.
    pub media: Vec<MediumDesc>,
    /// The camera's medium: the outside medium of the `MediumInterface` in effect at the end of
    /// the world block (pbrt-v3 makes the camera there); `None` for vacuum.
    pub camera_medium: Option<usize>,
}

impl SceneDescription {
    /// Every parameter list in the scene, for the unused-parameter report.
    pub fn all_plugins(&self) -> Vec<&PluginDesc> {
        let mut out: Vec<&PluginDesc> = Vec::new();
        if let Some(c) = &self.camera {
            out.push(&c.plugin);
        }
        out.extend(
            [
                &self.film,
                &self.sampler,
                &self.filter,
                &self.integrator,
                &self.accelerator,
            ]
            .into_iter()
            .flatten(),
        );
        out.extend(self.materials.iter().map(|m| &m.plugin));
        out.extend(self.textures.iter().map(|t| &t.plugin));
        out.extend(self.lights.iter().map(|l| &l.plugin));
        out.extend(self.media.iter().map(|m| &m.plugin));
        let shapes = self
            .shapes
            .iter()
            .chain(self.objects.values().flat_map(|o| o.shapes.iter()));
        let mut seen_area = std::collections::HashSet::new();
        for s in shapes {
            out.push(&s.plugin);
            if let Some(a) = &s.area_light {
                // Area lights are shared by the shapes of one attribute block: list each once.
                if seen_area.insert(Arc::as_ptr(a)) {
                    out.push(a);
                }
            }
        }
        out
    }

    /// Warnings for every parameter that nothing looked up (misspelled or unsupported), as pbrt
    /// gives after building the scene.
    pub fn unused_parameter_warnings(&self) -> Vec<Warning> {
        self.all_plugins()
            .into_iter()
            .flat_map(|p| {
                p.params.unused().map(move |param| {
                    Warning::at(
                        &param.loc,
                        format!(
                            "parameter \"{} {}\" of {} was not used",
                            param.ty.name(),
                            param.name,
                            p.kind
                        ),
                    )
                })
            })
            .collect()
    }
}
