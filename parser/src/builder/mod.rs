//! The graphics state: what pbrt-v3's api.cpp keeps while reading (the current transforms, the
//! attribute stack, named coordinate systems, materials, textures, area lights, object
//! definitions), turning each directive into entries of a [`SceneDescription`].

use crate::error::{Error, Result, Warning};
use crate::mesh::Mesh;
use crate::params::{ParamList, ParamType, Values};
use crate::paths::{io_message, resolve_path};
use crate::scene::{
    CameraDesc, LightDesc, MaterialDesc, ObjectDesc, PluginDesc, SceneDescription, ShapeDesc,
};
use crate::source::{Loc, SourceFile};
use glam::DMat4;
use indexmap::IndexMap;
use std::collections::{HashMap, HashSet};
use std::path::PathBuf;
use std::sync::Arc;

mod blocks;
mod materials;
mod media;
mod transforms;

/// The state that `AttributeBegin` saves and `AttributeEnd` restores. Name tables are shared
/// until changed (copy on write), so deep attribute nesting stays cheap.
#[derive(Clone)]
struct GraphicsState {
    material: Option<usize>,
    area_light: Option<Arc<PluginDesc>>,
    reverse_orientation: bool,
    named_materials: Arc<IndexMap<String, usize>>,
    float_textures: Arc<IndexMap<String, usize>>,
    spectrum_textures: Arc<IndexMap<String, usize>>,
    media: media::MediumNames,
}

/// The start and end current transformation matrices.
type Ctm = [DMat4; 2];

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Block {
    Attribute,
    Transform,
    Object,
}

impl Block {
    fn begin_name(self) -> &'static str {
        match self {
            Block::Attribute => "AttributeBegin",
            Block::Transform => "TransformBegin",
            Block::Object => "ObjectBegin",
        }
    }

    /// Whether the block saves the graphics state (pbrt-v3 pushes both kinds on one stack).
    fn saves_attributes(self) -> bool {
        matches!(self, Block::Attribute | Block::Object)
    }
}

struct Saved {
    block: Block,
    graphics: Option<GraphicsState>,
    ctm: Ctm,
    active: [bool; 2],
    loc: Loc,
}

/// Where we are in the file's structure.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Phase {
    Options,
    World,
    Done,
}

/// Builds a [`SceneDescription`] from directives, as pbrt-v3's API functions do.
pub struct Builder {
    main: Arc<SourceFile>,
    scene: SceneDescription,
    phase: Phase,
    ctm: Ctm,
    active: [bool; 2],
    named_coordinate_systems: HashMap<String, Ctm>,
    graphics: GraphicsState,
    stack: Vec<Saved>,
    current_object: Option<(String, ObjectDesc)>,
    warned_once: HashSet<String>,
    ply_cache: HashMap<PathBuf, Arc<Mesh>>,
    named_media: HashMap<String, usize>,
}

impl Builder {
    /// A builder for the scene whose main file is `main`.
    pub fn new(main: Arc<SourceFile>) -> Self {
        let default_material = MaterialDesc {
            name: None,
            plugin: PluginDesc {
                kind: "matte".to_owned(),
                params: ParamList::new(),
                loc: Loc::new(&main, 0),
            },
            mix: None,
        };
        Self {
            scene: SceneDescription {
                files: vec![Arc::clone(&main)],
                camera: None,
                film: None,
                sampler: None,
                filter: None,
                integrator: None,
                accelerator: None,
                transform_times: (0.0, 1.0),
                materials: vec![default_material],
                named_materials: IndexMap::new(),
                textures: Vec::new(),
                lights: Vec::new(),
                shapes: Vec::new(),
                objects: IndexMap::new(),
                instances: Vec::new(),
                warnings: Vec::new(),
                media: Vec::new(),
                camera_medium: None,
            },
            main,
            phase: Phase::Options,
            ctm: [DMat4::IDENTITY; 2],
            active: [true; 2],
            named_coordinate_systems: HashMap::new(),
            graphics: GraphicsState {
                material: Some(0),
                area_light: None,
                reverse_orientation: false,
                named_materials: Arc::default(),
                float_textures: Arc::default(),
                spectrum_textures: Arc::default(),
                media: media::MediumNames::default(),
            },
            stack: Vec::new(),
            current_object: None,
            warned_once: HashSet::new(),
            ply_cache: HashMap::new(),
            named_media: HashMap::new(),
        }
    }

    /// The main scene file.
    pub fn main_file(&self) -> &Arc<SourceFile> {
        &self.main
    }

    /// Records a file read through `Include`.
    pub fn add_file(&mut self, file: Arc<SourceFile>) {
        self.scene.files.push(file);
    }

    /// Adds a warning.
    pub fn warn(&mut self, loc: &Loc, message: impl Into<String>) {
        self.scene.warnings.push(Warning::at(loc, message));
    }

    /// Warns about an unsupported feature the first time it is met.
    pub fn unsupported_once(&mut self, directive: &str, loc: &Loc, what: &str) {
        if self.warned_once.insert(directive.to_owned()) {
            self.warn(
                loc,
                format!("{what} ({directive}) are not supported; ignored here and hereafter"),
            );
        }
    }

    /// Directives after `WorldEnd` are errors: acr renders one image per file.
    pub fn check_after_world_end(&self, directive: &str, loc: &Loc) -> Result<()> {
        if self.phase == Phase::Done {
            return Err(Error::at(
                loc,
                format!("{directive} after WorldEnd: a scene file describes one image"),
            ));
        }
        Ok(())
    }

    fn require_world(&self, directive: &str, loc: &Loc) -> Result<()> {
        if self.phase != Phase::World {
            return Err(Error::at(
                loc,
                format!("{directive} is only allowed between WorldBegin and WorldEnd"),
            ));
        }
        Ok(())
    }

    fn require_options(&self, directive: &str, loc: &Loc) -> Result<()> {
        if self.phase != Phase::Options {
            return Err(Error::at(
                loc,
                format!("{directive} must come before WorldBegin"),
            ));
        }
        Ok(())
    }

    /// Every directive of the form `Name "type" params`.
    pub fn plugin_directive(
        &mut self,
        directive: &str,
        kind: String,
        params: ParamList,
        loc: Loc,
    ) -> Result<()> {
        let plugin = PluginDesc { kind, params, loc };
        let loc = plugin.loc.clone();
        match directive {
            "Camera" => {
                self.require_options(directive, &loc)?;
                let camera_from_world = self.animated();
                // pbrt-v3 names the camera's space so that lights can be placed in it.
                self.named_coordinate_systems.insert(
                    "camera".to_owned(),
                    [self.ctm[0].inverse(), self.ctm[1].inverse()],
                );
                if let Some(old) = &self.scene.camera {
                    let old_loc = old.plugin.loc.clone();
                    self.warn(
                        &loc,
                        format!("{directive} given again (first at {old_loc}); this one is used"),
                    );
                }
                self.scene.camera = Some(CameraDesc {
                    plugin,
                    camera_from_world,
                });
            }
            "Film" | "Sampler" | "PixelFilter" | "Integrator" | "Accelerator" => {
                self.require_options(directive, &loc)?;
                fn slot<'s>(
                    s: &'s mut SceneDescription,
                    directive: &str,
                ) -> &'s mut Option<PluginDesc> {
                    match directive {
                        "Film" => &mut s.film,
                        "Sampler" => &mut s.sampler,
                        "PixelFilter" => &mut s.filter,
                        "Integrator" => &mut s.integrator,
                        _ => &mut s.accelerator,
                    }
                }
                if let Some(old) = slot(&mut self.scene, directive) {
                    let old_loc = old.loc.clone();
                    self.warn(
                        &loc,
                        format!("{directive} given again (first at {old_loc}); this one is used"),
                    );
                }
                *slot(&mut self.scene, directive) = Some(plugin);
            }
            "Material" => {
                self.require_world(directive, &loc)?;
                self.graphics.material = if plugin.kind.is_empty() || plugin.kind == "none" {
                    None
                } else {
                    Some(self.add_material(None, plugin)?)
                };
            }
            "MakeNamedMaterial" => {
                self.require_world(directive, &loc)?;
                let name = plugin.kind;
                let ty = plugin.params.string("type")?.map(str::to_owned);
                let Some(ty) = ty else {
                    return Err(Error::at(
                        &loc,
                        format!("MakeNamedMaterial \"{name}\" needs a \"string type\" parameter"),
                    ));
                };
                let index = self.add_material(
                    Some(name.clone()),
                    PluginDesc {
                        kind: ty,
                        params: plugin.params,
                        loc: plugin.loc,
                    },
                )?;
                if Arc::make_mut(&mut self.graphics.named_materials)
                    .insert(name.clone(), index)
                    .is_some()
                {
                    self.warn(&loc, format!("named material \"{name}\" redefined"));
                }
                self.scene.named_materials.insert(name, index);
            }
            "LightSource" => {
                self.require_world(directive, &loc)?;
                if self.current_object.is_some() {
                    return Err(Error::at(
                        &loc,
                        "LightSource inside an object definition is not supported",
                    ));
                }
                let media = self.current_media();
                self.scene.lights.push(LightDesc {
                    plugin,
                    world_from_light: self.ctm[0],
                    media,
                });
            }
            "AreaLightSource" => {
                self.require_world(directive, &loc)?;
                self.graphics.area_light = Some(Arc::new(plugin));
            }
            "Shape" => {
                self.require_world(directive, &loc)?;
                self.shape(plugin)?;
            }
            "MakeNamedMedium" => self.make_named_medium(plugin)?,
            _ => {
                return Err(Error::at(
                    &loc,
                    format!("internal: {directive} has no handler"),
                ))
            }
        }
        Ok(())
    }

    fn shape(&mut self, mut plugin: PluginDesc) -> Result<()> {
        let mesh = match plugin.kind.as_str() {
            "trianglemesh" => {
                let mesh = triangle_mesh(&plugin)?;
                // The arrays live in the mesh now: the parameters keep what the dump shows.
                for p in plugin.params.iter_mut() {
                    if matches!(p.name.as_str(), "P" | "N" | "uv" | "st" | "indices") {
                        p.keep_head();
                    }
                }
                Some(Arc::new(mesh))
            }
            "plymesh" => Some(self.ply_mesh(&plugin)?),
            _ => None,
        };
        self.resolve_textures(&mut plugin.params)?;
        let mut area_light = self.graphics.area_light.clone();
        if area_light.is_some() && self.current_object.is_some() {
            self.warn(
                &plugin.loc,
                "area lights are not supported inside object definitions (as in pbrt-v3); \
                 this shape does not emit",
            );
            area_light = None;
        }
        let media = self.current_media();
        let shape = ShapeDesc {
            plugin,
            media,
            world_from_object: self.animated(),
            reverse_orientation: self.graphics.reverse_orientation,
            material: self.graphics.material,
            area_light,
            mesh,
        };
        match &mut self.current_object {
            Some((_, def)) => def.shapes.push(shape),
            None => self.scene.shapes.push(shape),
        }
        Ok(())
    }

    fn ply_mesh(&mut self, plugin: &PluginDesc) -> Result<Arc<Mesh>> {
        let Some(name) = plugin.params.string("filename")? else {
            return Err(Error::at(
                &plugin.loc,
                "plymesh needs a \"string filename\" parameter",
            ));
        };
        let loc = plugin
            .params
            .get("filename")
            .map_or_else(|| plugin.loc.clone(), |p| p.loc.clone());
        let path = resolve_path(name, &loc.file, self.main.dir());
        if let Some(mesh) = self.ply_cache.get(&path) {
            return Ok(Arc::clone(mesh));
        }
        let bytes = crate::source::read_file(&path, crate::source::FileKind::Ply).map_err(|e| {
            Error::at(
                &loc,
                format!("cannot read PLY file \"{name}\": {}", io_message(&e)),
            )
        })?;
        let ply = crate::ply::parse_ply(&bytes)
            .map_err(|m| Error::at(&loc, format!("PLY file \"{name}\": {m}")))?;
        for w in ply.warnings {
            self.warn(&loc, format!("PLY file \"{name}\": {w}"));
        }
        let mesh = Arc::new(ply.mesh);
        self.ply_cache.insert(path, Arc::clone(&mesh));
        Ok(mesh)
    }

    /// The finished description.
    pub fn finish(mut self) -> SceneDescription {
        self.scene.camera_medium = self.current_media().outside;
        self.scene
    }
}

/// The mesh of a `trianglemesh` shape, checked as pbrt-v3 checks it.
fn triangle_mesh(plugin: &PluginDesc) -> Result<Mesh> {
    let params = &plugin.params;
    let err_at = |name: &str, message: String| {
        let loc = params
            .get(name)
            .map_or_else(|| plugin.loc.clone(), |p| p.loc.clone());
        Error::at(&loc, message)
    };
    let Some(p) = params.numbers("P", ParamType::Point3)? else {
        return Err(Error::at(
            &plugin.loc,
            "trianglemesh needs a \"point3 P\" parameter",
        ));
    };
    let positions: Vec<[f32; 3]> = p
        .chunks_exact(3)
        .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
        .collect();
    let indices: Vec<u32> = match params.ints("indices")? {
        Some(ix) => ix
            .iter()
            .map(|&i| {
                u32::try_from(i).map_err(|_| {
                    err_at(
                        "indices",
                        format!("trianglemesh: negative vertex index {i}"),
                    )
                })
            })
            .collect::<Result<_>>()?,
        // pbrt-v4 allows a single triangle without indices.
        None if positions.len() == 3 => vec![0, 1, 2],
        None => {
            return Err(Error::at(
                &plugin.loc,
                "trianglemesh needs an \"integer indices\" parameter",
            ))
        }
    };
    let normals = params.numbers("N", ParamType::Normal)?.map(|n| {
        n.chunks_exact(3)
            .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
            .collect::<Vec<_>>()
    });
    let uv_param = ["uv", "st"].into_iter().find_map(|k| params.get(k));
    let uvs = match uv_param {
        Some(param) => match (&param.values, param.ty) {
            (Values::Floats(v), ParamType::Float | ParamType::Point2) => Some(
                v.chunks_exact(2)
                    .map(|c| [c[0] as f32, c[1] as f32])
                    .collect::<Vec<_>>(),
            ),
            _ => {
                return Err(Error::at(
                    &param.loc,
                    format!(
                        "trianglemesh: \"{}\" must be float or point2, not {}",
                        param.name,
                        param.ty.name()
                    ),
                ))
            }
        },
        None => None,
    };
    if let Some(param) = uv_param {
        if let Values::Floats(v) = &param.values {
            if v.len() != 2 * positions.len() {
                return Err(Error::at(
                    &param.loc,
                    format!(
                        "trianglemesh: {} \"{}\" values for {} vertices (expected {})",
                        v.len(),
                        param.name,
                        positions.len(),
                        2 * positions.len()
                    ),
                ));
            }
        }
    }
    let mesh = Mesh {
        positions,
        normals,
        uvs,
        indices,
    };
    mesh.validate()
        .map_err(|m| err_at("indices", format!("trianglemesh: {m}")))?;
    Ok(mesh)
}
