//! The renderable scene, built once from a [`SceneDescription`]: camera, film settings,
//! acceleration structure, lights, materials, and which dimensions the rendering space needs.

use crate::accel::{Accel, Geometry, Instance, Placement, Prim, PrimKind};
use crate::camera::Camera;
use crate::film::FilmSettings;
use crate::geometry::{Ray, Spectrum, SurfaceInteraction, Vec3};
use crate::light::{prim_area, spot_frame, AreaShape, EnvMap, Light};
use crate::light_image::LightImage;
use crate::lightbvh::{LightBvh, LightContext};
use crate::lightdistrib::{LightDistribution, LightPmf, LightStrategy};
use crate::material::Material;
use crate::shapes::{Cylinder, Disk, Sphere, Transform, TriangleMesh};
use crate::transform::MotionTransform;
use acr_parser::{
    Error, ParamList, ParamType, PluginDesc, Result, SceneDescription, ShapeDesc, Warning,
};
use glam::DMat4;
use std::collections::HashSet;
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// What a primitive's surface is: its material and the area light it carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Surface {
    /// Index into [`Scene::materials`]; `None` for an interface (`Material ""`).
    pub material: Option<u32>,
    /// Index into [`Scene::lights`] when the primitive emits.
    pub area_light: Option<u32>,
}

pub use acr_plugins::Dims;

/// A scene ready to render.
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Film settings.
    pub film: FilmSettings,
    /// The acceleration structure.
    pub accel: Accel,
    /// Every light.
    pub lights: Vec<Light>,
    /// Shadow samples per light per shading point for `directlighting`'s "all" strategy (the
    /// area and infinite lights' `nsamples`, pbrt-v3's; 1 for the others).
    pub light_samples: Vec<u32>,
    /// Light choice for next-event estimation, one per strategy (spatial built on first use).
    light_choice: LightChoices,
    /// Indices of infinite lights (seen by rays that escape).
    pub infinite_lights: Vec<u32>,
    /// Materials by index.
    pub materials: Vec<Material>,
    /// Surfaces by index.
    pub surfaces: Vec<Surface>,
    /// Active dimensions of the rendering space.
    pub dims: Dims,
    /// Centre of the scene's bounding sphere.
    pub world_center: Vec3,
    /// Radius of the scene's bounding sphere.
    pub world_radius: f32,
    /// Render space from world space: everything the scene holds (geometry, lights, camera,
    /// textures) is in render space, the world translated so that the camera sits at the
    /// origin (pbrt-v4's "camera-world" space). f32 resolution is finest near the origin, so a
    /// scene far from the world origin renders as precisely as one at it.
    pub render_from_world: DMat4,
}

/// A ray's closest hit, resolved.
pub struct SceneHit {
    /// Where it hit.
    pub si: SurfaceInteraction,
    /// What it hit.
    pub surface: Surface,
}

impl Scene {
    /// The closest hit along the ray, if any.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<SceneHit> {
        let hit = self.accel.intersect(ray, f32::INFINITY)?;
        let si = self.accel.interaction(ray, &hit);
        Some(SceneHit {
            si,
            surface: self.surfaces[hit.prim.surface as usize],
        })
    }

    /// Whether the segment from `si` to `target` is blocked.
    #[inline]
    pub fn occluded(&self, si: &SurfaceInteraction, target: Vec3) -> bool {
        let (ray, t_max) = si.spawn_ray_to(target);
        self.accel.occluded(&ray, t_max)
    }

    /// Chooses a light for next-event estimation at `ctx` under `strategy` with `u` in
    /// [0, 1): its index and probability; `None` when the strategy finds no light that can
    /// reach the point.
    #[inline]
    pub fn choose_light(
        &self,
        strategy: LightStrategy,
        ctx: LightContext,
        u: f32,
    ) -> Option<(usize, f32)> {
        match strategy {
            LightStrategy::Bvh => self.light_bvh().sample(ctx, u),
            _ => {
                let pmf = self.light_pmf(strategy, ctx.p);
                (!pmf.is_empty()).then(|| pmf.sample(u))
            }
        }
    }

    /// Probability that [`Scene::choose_light`] at `ctx` under `strategy` picks `light`.
    #[inline]
    pub fn light_choice_pdf(
        &self,
        strategy: LightStrategy,
        ctx: LightContext,
        light: usize,
    ) -> f32 {
        match strategy {
            LightStrategy::Bvh => self.light_bvh().pmf(ctx, light),
            _ => self.light_pmf(strategy, ctx.p).pdf(light),
        }
    }

    /// The light BVH (built on first use).
    pub fn light_bvh(&self) -> &LightBvh {
        self.light_choice
            .bvh
            .get_or_init(|| LightBvh::new(&self.lights, &self.accel.world))
    }

    /// The distribution to choose a light from at `p` under a strategy other than `bvh`.
    #[inline]
    fn light_pmf(&self, strategy: LightStrategy, p: Vec3) -> &LightPmf {
        let c = &self.light_choice;
        match strategy {
            LightStrategy::Uniform => &c.uniform,
            // `Bvh` never comes here (choose_light and light_choice_pdf ask the tree).
            LightStrategy::Power | LightStrategy::Bvh => &c.power,
            LightStrategy::Spatial => c
                .spatial
                .get_or_init(|| LightDistribution::new(strategy, &self.lights, c.bounds))
                .lookup(p, &self.lights, &self.accel.world),
        }
    }
}

/// The light distributions of a scene.
struct LightChoices {
    uniform: LightPmf,
    power: LightPmf,
    spatial: OnceLock<LightDistribution>,
    bvh: OnceLock<LightBvh>,
    bounds: (Vec3, Vec3),
}

/// Shape types pbrt-v3 has and acr does not: warned about once and skipped.
const UNSUPPORTED_SHAPES: &[&str] = &[];

/// Builds scenes, collecting warnings.
struct Builder<'a> {
    desc: &'a SceneDescription,
    warnings: &'a mut Vec<Warning>,
    warned: HashSet<String>,
    surfaces: Vec<Surface>,
    lights: Vec<Light>,
    light_samples: Vec<u32>,
    /// Area lights waiting for the world's bounds: (light description, surface index).
    area_lights: Vec<(Arc<PluginDesc>, PrimKind, u32)>,
}

fn transform_of(m: &DMat4) -> Transform {
    let m32 = m.as_mat4();
    Transform {
        m: m32,
        inv: m.inverse().as_mat4(),
    }
}

impl Builder<'_> {
    fn warn_once(&mut self, key: String, loc: &acr_parser::Loc, msg: String) {
        if self.warned.insert(key) {
            self.warnings.push(Warning::at(loc, msg));
        }
    }

    /// Whether a shape's size is positive and finite; if not, warns that the shape is skipped
    /// (a zero or negative radius makes a shape with no area, which no ray can hit and no
    /// light can sample without dividing by zero).
    /// Drops the area light of a shape pbrt-v3 cannot sample (its `Sample` aborts), with a
    /// warning: the shape renders, unlit by itself.
    fn no_emission<'l, L>(&mut self, area_light: Option<&'l L>, p: &PluginDesc) -> Option<&'l L> {
        if area_light.is_some() {
            self.warnings.push(Warning::at(
                &p.loc,
                format!(
                    "AreaLightSource on a {0}: pbrt-v3 cannot sample a {0} (its Sample aborts); \
                     the shape is rendered without emission",
                    p.kind
                ),
            ));
        }
        None
    }

    fn positive_size(&mut self, p: &PluginDesc, what: &str, v: f32) -> bool {
        if v > 0.0 && v.is_finite() {
            return true;
        }
        let loc = p.params.get(what).map_or(&p.loc, |x| &x.loc);
        self.warnings.push(Warning::at(
            loc,
            format!(
                "{}: {what} is {v}; the shape has no area and is skipped",
                p.kind
            ),
        ));
        false
    }

    /// Adds a triangle mesh and a primitive for each of its triangles with a positive, finite
    /// world-space area; warns once per shape about the others, which are skipped (they could
    /// never be hit, and as emitters their area would divide by zero).
    fn add_triangles(
        &mut self,
        geom: &mut Geometry,
        tm: TriangleMesh,
        prims: &mut Vec<PrimKind>,
        loc: &acr_parser::Loc,
        kind: &str,
    ) {
        let mesh_index = geom.meshes.len() as u32;
        let n = tm.triangle_count();
        let before = prims.len();
        prims.extend(
            (0..n)
                .filter(|&tri| {
                    // The intersection test's own zero-area test, and finite vertices.
                    let [a, b, c] = tm.vertices(tri);
                    let n = (a - c).cross(b - c);
                    n != Vec3::ZERO && n.is_finite()
                })
                .map(|tri| PrimKind::Triangle {
                    mesh: mesh_index,
                    tri: tri as u32,
                }),
        );
        let skipped = n - (prims.len() - before);
        if skipped > 0 {
            self.warnings.push(Warning::at(
                loc,
                format!(
                    "{kind}: {skipped} of {n} triangles are degenerate (zero area or \
                     non-finite vertices) and are skipped"
                ),
            ));
        }
        geom.meshes.push(tm);
    }

    fn surface(&mut self, s: Surface) -> u32 {
        self.surfaces.push(s);
        (self.surfaces.len() - 1) as u32
    }

    /// Adds one shape's primitives to `geom`, placed by `m` (world- or instance-from-object).
    /// Area lights are only allowed for static world shapes (`emit`).
    fn add_shape(
        &mut self,
        geom: &mut Geometry,
        shape: &ShapeDesc,
        m: &DMat4,
        emit: bool,
    ) -> Result<()> {
        let p = &shape.plugin;
        let kind = p.kind.as_str();
        if UNSUPPORTED_SHAPES.contains(&kind) {
            self.warn_once(
                format!("shape {kind}"),
                &p.loc,
                format!("shape \"{kind}\" is not supported; shapes of this type are skipped"),
            );
            return Ok(());
        }
        let mut area_light = shape.area_light.as_ref().filter(|_| emit);
        let material = shape.material.map(|m| m as u32);
        let to_world = transform_of(m);
        let params = &p.params;
        let mut prims: Vec<PrimKind> = Vec::new();
        match kind {
            "trianglemesh" | "plymesh" => {
                let Some(mesh) = &shape.mesh else {
                    return Ok(());
                };
                let tm = TriangleMesh::from_mesh(mesh, &to_world, shape.reverse_orientation);
                self.add_triangles(geom, tm, &mut prims, &p.loc, kind);
                // Parameters pbrt-v3 reads for meshes that acr has no use for.
                for unused in ["alpha", "shadowalpha", "S", "faceIndices"] {
                    if let Some(x) = params.get(unused) {
                        self.warn_once(
                            format!("mesh param {unused}"),
                            &x.loc,
                            format!("mesh parameter \"{unused}\" is not supported; ignored"),
                        );
                    }
                }
            }
            "loopsubdiv" => {
                let mesh =
                    crate::shapes::loopsubdiv::mesh_from_params(params, &p.loc, self.warnings)?;
                let tm = TriangleMesh::from_mesh(&mesh, &to_world, shape.reverse_orientation);
                self.add_triangles(geom, tm, &mut prims, &p.loc, kind);
            }
            "heightfield" => {
                let mesh = crate::shapes::heightfield::mesh_from_params(params, &p.loc)?;
                let tm = TriangleMesh::from_mesh(&mesh, &to_world, shape.reverse_orientation);
                self.add_triangles(geom, tm, &mut prims, &p.loc, kind);
            }
            "nurbs" => {
                let mesh = crate::shapes::nurbs::mesh_from_params(params, &p.loc)?;
                let tm = TriangleMesh::from_mesh(&mesh, &to_world, shape.reverse_orientation);
                self.add_triangles(geom, tm, &mut prims, &p.loc, kind);
            }
            "sphere" => {
                let r = params.float_or("radius", 1.0)? as f32;
                if !self.positive_size(p, "radius", r) {
                    return Ok(());
                }
                let s = Sphere::new(
                    r,
                    params.float_or("zmin", -r as f64)? as f32,
                    params.float_or("zmax", r as f64)? as f32,
                    params.float_or("phimax", 360.0)? as f32,
                    to_world,
                    shape.reverse_orientation,
                );
                prims.push(PrimKind::Sphere(geom.spheres.len() as u32));
                geom.spheres.push(s);
            }
            "disk" => {
                let (r, ri) = (
                    params.float_or("radius", 1.0)? as f32,
                    params.float_or("innerradius", 0.0)? as f32,
                );
                if !self.positive_size(p, "radius", r)
                    || !self.positive_size(p, "radius - innerradius", r - ri.max(0.0))
                {
                    return Ok(());
                }
                let d = Disk::new(
                    params.float_or("height", 0.0)? as f32,
                    r,
                    ri.max(0.0),
                    params.float_or("phimax", 360.0)? as f32,
                    to_world,
                    shape.reverse_orientation,
                );
                prims.push(PrimKind::Disk(geom.disks.len() as u32));
                geom.disks.push(d);
            }
            "cylinder" => {
                let r = params.float_or("radius", 1.0)? as f32;
                let (z0, z1) = (
                    params.float_or("zmin", -1.0)? as f32,
                    params.float_or("zmax", 1.0)? as f32,
                );
                if !self.positive_size(p, "radius", r)
                    || !self.positive_size(p, "|zmax - zmin|", (z1 - z0).abs())
                {
                    return Ok(());
                }
                let c = Cylinder::new(
                    r,
                    z0,
                    z1,
                    params.float_or("phimax", 360.0)? as f32,
                    to_world,
                    shape.reverse_orientation,
                );
                prims.push(PrimKind::Cylinder(geom.cylinders.len() as u32));
                geom.cylinders.push(c);
            }
            "cone" | "paraboloid" | "hyperboloid" => {
                let built = crate::shapes::revolved::from_params(
                    kind,
                    params,
                    to_world,
                    shape.reverse_orientation,
                )?;
                let shape = match built {
                    Ok(s) => s,
                    Err(why) => {
                        self.warnings.push(Warning::at(&p.loc, why));
                        return Ok(());
                    }
                };
                area_light = self.no_emission(area_light, p);
                prims.push(PrimKind::Revolved(geom.revolved.len() as u32));
                geom.revolved.push(shape);
            }
            "curve" => {
                let curves = crate::shapes::curve::from_params(
                    params,
                    &p.loc,
                    to_world,
                    shape.reverse_orientation,
                    self.warnings,
                )?;
                area_light = self.no_emission(area_light, p);
                for (common, pieces) in curves {
                    let index = geom.curve_commons.len() as u32;
                    geom.curve_commons.push(common);
                    for mut piece in pieces {
                        piece.common = index;
                        prims.push(PrimKind::Curve(geom.curves.len() as u32));
                        geom.curves.push(piece);
                    }
                }
            }
            other => {
                self.warn_once(
                    format!("shape {other}"),
                    &p.loc,
                    format!("unknown shape \"{other}\"; shapes of this type are skipped"),
                );
                return Ok(());
            }
        }
        // Coordinates beyond f32's range (or NaN) relative to the camera: no box holds them.
        let before = prims.len();
        prims.retain(|&k| {
            let (lo, hi) = geom.kind_bounds(k);
            crate::accel::finite_box(lo, hi)
        });
        if prims.len() < before {
            self.warnings.push(Warning::at(
                &p.loc,
                format!(
                    "{kind}: {} of {before} primitives lie beyond the range of 32-bit floats \
                     seen from the camera, or have NaN coordinates, and are skipped",
                    before - prims.len()
                ),
            ));
        }
        if area_light.is_none() {
            let surface = self.surface(Surface {
                material,
                area_light: None,
            });
            for kind in prims {
                geom.push(Prim { kind, surface });
            }
            return Ok(());
        }
        let light = area_light.cloned();
        for kind in prims {
            // One light per primitive, as pbrt-v3 makes one DiffuseAreaLight per shape.
            let surface = self.surface(Surface {
                material,
                area_light: None,
            });
            if let Some(l) = &light {
                self.area_lights.push((Arc::clone(l), kind, surface));
            }
            geom.push(Prim { kind, surface });
        }
        Ok(())
    }

    fn light(
        &mut self,
        p: &PluginDesc,
        world_from_light: &DMat4,
        world_radius: f32,
        main_dir: &Path,
    ) -> Result<Option<Light>> {
        let params = &p.params;
        let scale = rgb_param(params, "scale", Spectrum::ONE)?;
        let m = world_from_light.as_mat4();
        Ok(Some(match p.kind.as_str() {
            "point" => {
                let from = vec3_param(params, "from", Vec3::ZERO)?;
                Light::Point {
                    pos: m.transform_point3(from),
                    intensity: rgb_param(params, "I", Spectrum::ONE)? * scale,
                }
            }
            "spot" => {
                let from = vec3_param(params, "from", Vec3::ZERO)?;
                let to = vec3_param(params, "to", Vec3::Z)?;
                let cone = params.float_or("coneangle", 30.0)? as f32;
                let delta = params.float_or("conedeltaangle", 5.0)? as f32;
                let pos = m.transform_point3(from);
                let dir = m.transform_vector3(to - from).normalize_or_zero();
                if dir == Vec3::ZERO {
                    return Err(Error::at(
                        &p.loc,
                        "spot light: \"from\" and \"to\" coincide",
                    ));
                }
                Light::Spot {
                    pos,
                    light_from_world: spot_frame(dir),
                    intensity: rgb_param(params, "I", Spectrum::ONE)? * scale,
                    cos_total: cone.to_radians().cos(),
                    cos_falloff_start: (cone - delta).to_radians().cos(),
                }
            }
            "distant" => {
                let from = vec3_param(params, "from", Vec3::ZERO)?;
                let to = vec3_param(params, "to", Vec3::Z)?;
                let w = m.transform_vector3(from - to).normalize_or_zero();
                if w == Vec3::ZERO {
                    return Err(Error::at(
                        &p.loc,
                        "distant light: \"from\" and \"to\" coincide",
                    ));
                }
                Light::Distant {
                    w,
                    radiance: rgb_param(params, "L", Spectrum::ONE)? * scale,
                    world_radius,
                }
            }
            "infinite" | "exinfinite" => {
                let l = rgb_param(params, "L", Spectrum::ONE)? * scale;
                let map = match params.string("mapname")? {
                    Some(name) if !name.is_empty() => {
                        let loc = params.get("mapname").map_or(&p.loc, |x| &x.loc);
                        let path = crate::texture::resolve_file(name, loc, main_dir);
                        let img = crate::image_io::read_image(&path, false)
                            .map_err(|e| Error::at(loc, format!("cannot read \"{name}\": {e}")))?;
                        Some(EnvMap::new(Arc::new(img)))
                    }
                    // pbrt-v3 gives a constant environment a 1x1 map and samples it through
                    // the map's distribution (uniform in (phi, theta), denser at the poles);
                    // doing the same keeps the variance, and the spatial light choice, as
                    // pbrt-v3 has them.
                    _ => Some(EnvMap::new(Arc::new(crate::image_io::RgbImage {
                        width: 1,
                        height: 1,
                        pixels: vec![Spectrum::ONE],
                    }))),
                };
                Light::Infinite {
                    l,
                    map,
                    light_from_world: m.inverse(),
                    world_from_light: m,
                    world_radius,
                }
            }
            "goniometric" | "projection" => {
                let intensity = rgb_param(params, "I", Spectrum::ONE)? * scale;
                // pbrt-v3 reads the image with ReadImage: PNG values as stored, no sRGB
                // decoding. Without "mapname" it has no image (and emits I unscaled); acr
                // makes an unreadable one an error where pbrt-v3 goes on without it.
                let map = match params.string("mapname")? {
                    Some(name) if !name.is_empty() => {
                        let loc = params.get("mapname").map_or(&p.loc, |x| &x.loc);
                        let path = crate::texture::resolve_file(name, loc, main_dir);
                        let img = crate::image_io::read_image(&path, false)
                            .map_err(|e| Error::at(loc, format!("cannot read \"{name}\": {e}")))?;
                        Some(
                            LightImage::new(&img).ok_or_else(|| {
                                Error::at(loc, format!("\"{name}\" has no pixels"))
                            })?,
                        )
                    }
                    _ => None,
                };
                let light = if p.kind == "goniometric" {
                    Light::goniometric(world_from_light, intensity, map)
                } else {
                    let fov = params.float_or("fov", 45.0)? as f32;
                    Light::projection(world_from_light, intensity, map, fov)
                };
                light.map_err(|e| Error::at(&p.loc, format!("{} light: {e}", p.kind)))?
            }
            other => {
                let kinds = [
                    "point",
                    "spot",
                    "goniometric",
                    "projection",
                    "distant",
                    "infinite",
                ];
                let hint = acr_parser::closest(other, kinds)
                    .map_or(String::new(), |k| format!(" (did you mean {k}?)"));
                return Err(Error::at(
                    &p.loc,
                    format!("unknown light \"{other}\"{hint}"),
                ));
            }
        }))
    }
}

/// The translation that takes the camera's position (at its start transform) to the origin.
/// Exact in f64; a camera description that cannot be inverted gives the identity. A camera
/// beyond the range of 32-bit floats is an error: nothing could be placed relative to it.
fn render_from_world(camera: &acr_parser::CameraDesc) -> Result<DMat4> {
    let camera_pos = camera
        .camera_from_world
        .start
        .inverse()
        .transform_point3(glam::DVec3::ZERO);
    if !camera_pos.is_finite() {
        return Ok(DMat4::IDENTITY);
    }
    if camera_pos.abs().max_element() > f64::from(f32::MAX) {
        return Err(Error::at(
            &camera.plugin.loc,
            format!(
                "the camera stands at ({:.3e}, {:.3e}, {:.3e}), beyond the range of 32-bit \
                 floats (3.4e38); move the scene nearer the origin",
                camera_pos.x, camera_pos.y, camera_pos.z
            ),
        ));
    }
    Ok(DMat4::from_translation(-camera_pos))
}

/// An RGB-valued parameter (rgb, spectrum or blackbody) or its default.
/// Most shadow samples a light may ask for per shading point.
const MAX_LIGHT_SAMPLES: i32 = 4096;

/// An area or infinite light's shadow samples per shading point: pbrt-v3's
/// `FindOneInt("samples", FindOneInt("nsamples", 1))`; below 1 counts as 1 (pbrt-v3 then takes
/// one sample), above [`MAX_LIGHT_SAMPLES`] is an error at the parameter.
fn light_sample_count(params: &ParamList) -> Result<u32> {
    let nsamples = params.int_or("nsamples", 1)?;
    let n = params.int_or("samples", nsamples)?;
    if n > MAX_LIGHT_SAMPLES {
        let name = if params.get("samples").is_some() {
            "samples"
        } else {
            "nsamples"
        };
        let loc = &params.get(name).expect("given").loc;
        return Err(Error::at(
            loc,
            format!("{name} {n} is more than {MAX_LIGHT_SAMPLES} shadow samples per point"),
        ));
    }
    Ok(n.max(1) as u32)
}

pub fn rgb_param(params: &ParamList, name: &str, default: Spectrum) -> Result<Spectrum> {
    Ok(crate::texture::spectrum_value(params, name)?.unwrap_or(default))
}

fn vec3_param(params: &ParamList, name: &str, default: Vec3) -> Result<Vec3> {
    let Some(p) = params.get(name) else {
        return Ok(default);
    };
    let v = match p.ty {
        ParamType::Point3 | ParamType::Vector3 | ParamType::Normal => params.vec3(name, p.ty)?,
        _ => return Err(Error::at(&p.loc, format!("\"{name}\" must be a point3"))),
    };
    Ok(v.map_or(default, |a| {
        Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
    }))
}

impl Scene {
    /// Builds the scene from its description. Warnings (unsupported features, unused
    /// parameters) are appended to `warnings`.
    pub fn build(desc: &SceneDescription, warnings: &mut Vec<Warning>) -> Result<Scene> {
        let main_dir = desc
            .files
            .first()
            .map(|f| f.dir().to_path_buf())
            .unwrap_or_default();
        let Some(camera_desc) = &desc.camera else {
            let path = desc
                .files
                .first()
                .map(|f| f.path.clone())
                .unwrap_or_default();
            return Err(Error::file(path, "the scene has no Camera"));
        };
        let film = FilmSettings::new(desc.film.as_ref())?;
        let render_from_world = render_from_world(camera_desc)?;
        let in_render = |t: &acr_parser::AnimatedTransform| acr_parser::AnimatedTransform {
            start: render_from_world * t.start,
            end: render_from_world * t.end,
            ..*t
        };
        let camera = Camera::new(camera_desc, film.resolution, render_from_world)?;
        let mut b = Builder {
            desc,
            warnings,
            warned: HashSet::new(),
            surfaces: Vec::new(),
            lights: Vec::new(),
            light_samples: Vec::new(),
            area_lights: Vec::new(),
        };
        let mut accel = Accel::default();
        let mut world = Geometry::default();
        for shape in &desc.shapes {
            let moving = shape.world_from_object.is_animated()
                && shape.world_from_object.end_time > shape.world_from_object.start_time;
            if moving {
                if let Some(al) = &shape.area_light {
                    b.warn_once(
                        "moving area light".into(),
                        &al.loc,
                        "area lights on moving shapes are not supported (as in pbrt-v3); \
                         the shape does not emit"
                            .into(),
                    );
                }
                let mut g = Geometry::default();
                b.add_shape(&mut g, shape, &DMat4::IDENTITY, false)?;
                accel.objects.push(g);
                accel.instances.push(Instance {
                    object: (accel.objects.len() - 1) as u32,
                    placement: Placement::Moving(Box::new(MotionTransform::new(&in_render(
                        &shape.world_from_object,
                    )))),
                });
            } else {
                let m = render_from_world * shape.world_from_object.start;
                b.add_shape(&mut world, shape, &m, true)?;
            }
        }
        let first_object = accel.objects.len() as u32;
        for object in b.desc.objects.values() {
            let mut g = Geometry::default();
            for shape in &object.shapes {
                if shape.world_from_object.is_animated() {
                    b.warn_once(
                        "animated in object".into(),
                        &shape.plugin.loc,
                        "motion inside an object definition is not supported; the shape is \
                         placed at its start transform (move the instance instead)"
                            .into(),
                    );
                }
                b.add_shape(&mut g, shape, &shape.world_from_object.start, false)?;
            }
            accel.objects.push(g);
        }
        for inst in &desc.instances {
            let t = &in_render(&inst.world_from_instance);
            let placement = if t.is_animated() && t.end_time > t.start_time {
                Placement::Moving(Box::new(MotionTransform::new(t)))
            } else {
                Placement::Fixed {
                    to_world: t.start.as_mat4(),
                    to_local: t.start.inverse().as_mat4(),
                }
            };
            accel.instances.push(Instance {
                object: first_object + inst.object as u32,
                placement,
            });
        }
        accel.world = world;
        let dropped = accel.build();
        if dropped > 0 {
            b.warnings.push(Warning {
                loc: None,
                message: format!(
                    "{dropped} object instances are placed beyond the range of 32-bit floats \
                     and are skipped"
                ),
            });
        }
        let (lo, hi) = accel.bounds();
        let (world_center, world_radius) = if lo.cmple(hi).all() {
            ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
        } else {
            (Vec3::ZERO, 1.0)
        };
        // Area lights, now that the world geometry has its final layout.
        for (light, kind, surface) in std::mem::take(&mut b.area_lights) {
            if !matches!(light.kind.as_str(), "area" | "diffuse") {
                return Err(Error::at(
                    &light.loc,
                    format!(
                        "area light \"{}\" is not supported (only \"diffuse\")",
                        light.kind
                    ),
                ));
            }
            let params = &light.params;
            let l_emit =
                rgb_param(params, "L", Spectrum::ONE)? * rgb_param(params, "scale", Spectrum::ONE)?;
            let two_sided = params.bool_or("twosided", false)?;
            let samples = light_sample_count(params)?;
            let area = prim_area(&accel.world, kind);
            if area > 0.0 && l_emit.max_element() > 0.0 {
                b.lights.push(Light::Area {
                    shape: AreaShape { kind },
                    l_emit,
                    two_sided,
                    area,
                });
                b.light_samples.push(samples);
                b.surfaces[surface as usize].area_light = Some((b.lights.len() - 1) as u32);
            }
        }
        for l in &desc.lights {
            if let Some(light) = b.light(
                &l.plugin,
                &(render_from_world * l.world_from_light),
                world_radius,
                &main_dir,
            )? {
                let samples = match light {
                    Light::Infinite { .. } => light_sample_count(&l.plugin.params)?,
                    _ => 1,
                };
                b.lights.push(light);
                b.light_samples.push(samples);
            }
        }
        let materials =
            crate::material::build_materials(desc, &main_dir, render_from_world, b.warnings)?;
        let powers: Vec<f32> = b
            .lights
            .iter()
            .map(|l| crate::spectrum_luminance(l.power()))
            .collect();
        let infinite_lights = b
            .lights
            .iter()
            .enumerate()
            .filter(|(_, l)| matches!(l, Light::Infinite { .. }))
            .map(|(i, _)| i as u32)
            .collect();
        let dims = Dims {
            time: (accel.has_motion() || camera.is_moving())
                && camera.shutter_close > camera.shutter_open,
            lens: camera.lens_radius > 0.0,
        };
        Ok(Scene {
            camera,
            film,
            accel,
            light_choice: LightChoices {
                uniform: LightPmf::new(&vec![1.0; powers.len()]),
                power: LightPmf::new(&powers),
                spatial: OnceLock::new(),
                bvh: OnceLock::new(),
                bounds: (lo, hi),
            },
            lights: b.lights,
            light_samples: b.light_samples,
            infinite_lights,
            materials,
            surfaces: b.surfaces,
            dims,
            world_center,
            world_radius,
            render_from_world,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// pbrt-v3's spot light reads its falloff from "conedeltaangle" (default 5 degrees).
    #[test]
    fn a_spot_light_falls_off_over_conedeltaangle() {
        for (param, delta) in [("\"float conedeltaangle\" 12", 12.0f32), ("", 5.0)] {
            let text = format!(
                "Camera \"perspective\"\nWorldBegin\nLightSource \"spot\" \
                 \"float coneangle\" 40 {param}\nShape \"sphere\"\nWorldEnd"
            );
            let desc = acr_parser::parse_str(&text, Path::new("spot.pbrt")).unwrap();
            let mut warnings = Vec::new();
            let scene = Scene::build(&desc, &mut warnings).unwrap();
            let Some(Light::Spot {
                cos_total,
                cos_falloff_start,
                ..
            }) = scene.lights.first()
            else {
                panic!("no spot light");
            };
            assert!((cos_total - 40f32.to_radians().cos()).abs() < 1e-6);
            let expected = (40.0 - delta).to_radians().cos();
            assert!((cos_falloff_start - expected).abs() < 1e-6, "{param}");
            assert!(desc.unused_parameter_warnings().is_empty(), "{param}");
        }
    }
}
