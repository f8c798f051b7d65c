//! The renderable scene, built once from a [`SceneDescription`]: camera, film settings,
//! acceleration structure, lights, materials, and which dimensions the rendering space needs.

use crate::accel::{Accel, Hit, PrimKind};
use crate::camera::Camera;
use crate::film::FilmSettings;
use crate::geometry::{Ray, SurfaceInteraction, Vec3};
use crate::light::Light;
use crate::lightbvh::{LightBvh, LightContext};
use crate::lightdistrib::{LightDistribution, LightPmf, LightStrategy};
use crate::material::Material;
use acr_parser::{Error, PluginDesc, Result, SceneDescription, Warning};
use glam::DMat4;
use std::collections::HashSet;
use std::sync::{Arc, OnceLock};

mod instances;
mod lights;
mod shapes;

pub use lights::rgb_param;

/// What a primitive's surface is: its material and the area light it carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Surface {
    /// Index into [`Scene::materials`]; `None` for an interface (`Material ""`).
    pub material: Option<u32>,
    /// Index into [`Scene::lights`] when the primitive emits.
    pub area_light: Option<u32>,
    /// The media on either side when it separates two (pbrt-v3's medium transition); `None`
    /// when rays keep the medium they arrived in.
    pub media: Option<crate::medium::MediumInterface>,
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
    /// Participating media (`MakeNamedMedium`), indexed by [`Surface::media`].
    pub media: Vec<crate::medium::Medium>,
    /// The medium the camera sits in (`None`: vacuum).
    pub camera_medium: Option<u32>,
    /// The media around each light, by light index (what bdpt's light subpaths start in): a
    /// `LightSource`'s is the interface's outside medium on both sides, an area light's its
    /// shape's `MediumInterface` (pbrt-v3's).
    pub light_media: Vec<crate::medium::MediumInterface>,
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
    /// How much the camera rays' differentials are scaled (pbrt-v3's 1 / sqrt(samples per
    /// pixel)): of the scene's own Sampler budget when built, of the render's whole budget
    /// once [`Scene::set_footprint_spp`] says it (`acr render` does).
    pub differential_scale: f32,
    /// Whether anything looks at a hit's footprint (image maps, checkerboards, noise textures,
    /// bump maps): when nothing does, camera rays go without differentials (two camera rays
    /// fewer per sample; the image is the same).
    pub uses_differentials: bool,
}

impl Scene {
    /// Scales the camera rays' differentials for a render of `spp` samples per pixel in all
    /// (pbrt-v3's `ScaleDifferentials(1 / sqrt(spp))`, docs/pbrt-v3-compatibility.md).
    pub fn set_footprint_spp(&mut self, spp: u32) {
        self.differential_scale = 1.0 / (spp.max(1) as f32).sqrt();
    }
}

/// Whether the scene has a texture class or a bump map that reads the ray differentials.
pub fn uses_differentials(desc: &SceneDescription) -> bool {
    let footprint = [
        "imagemap",
        "checkerboard",
        "fbm",
        "wrinkled",
        "windy",
        "marble",
    ];
    desc.textures
        .iter()
        .any(|t| footprint.contains(&t.plugin.kind.as_str()))
        || desc
            .materials
            .iter()
            .any(|m| m.plugin.params.iter().any(|p| p.name == "bumpmap"))
}

/// pbrt-v3's samples per pixel for the scene's Sampler, as its ray differentials are scaled
/// by them: `xsamples` x `ysamples` for stratified (4 x 4), `pixelsamples` (16) for the
/// others, rounded up to a power of two where pbrt-v3's sampler does (02sequence,
/// lowdiscrepancy, sobol, maxmindist). Bad values count as the defaults here: the sampler's
/// own construction reports them.
fn sampler_spp(desc: &SceneDescription) -> u32 {
    let Some(s) = &desc.sampler else {
        return 16;
    };
    let p = &s.params;
    let int = |name: &str, default: i32| -> u64 {
        p.int_or(name, default).unwrap_or(default).clamp(1, 1 << 20) as u64
    };
    let spp = match s.kind.as_str() {
        "stratified" => int("xsamples", 4) * int("ysamples", 4),
        "02sequence" | "lowdiscrepancy" | "sobol" | "maxmindist" => {
            int("pixelsamples", 16).next_power_of_two()
        }
        _ => int("pixelsamples", 16),
    };
    spp.clamp(1, 1 << 40) as u32
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

    /// The closest hit along the ray, its interaction not made yet ([`Scene::interaction`]):
    /// an integrator binds that to a fresh local, which the call fills in place, where a hit
    /// returned with its interaction was copied on its way (about 180 bytes).
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.accel.intersect(ray, f32::INFINITY)
    }

    /// The world-space interaction of `hit` on `ray` (from [`Scene::closest_hit`]).
    #[inline]
    pub fn interaction(&self, ray: &Ray, hit: &Hit) -> SurfaceInteraction {
        self.accel.interaction(ray, hit)
    }

    /// The surface `hit` found.
    #[inline]
    pub fn surface_of(&self, hit: &Hit) -> Surface {
        self.surfaces[hit.prim.surface as usize]
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

/// Builds scenes, collecting warnings.
struct Builder<'a> {
    desc: &'a SceneDescription,
    warnings: &'a mut Vec<Warning>,
    warned: HashSet<String>,
    /// Render space from world space (see [`Scene::render_from_world`]).
    render_from_world: DMat4,
    surfaces: Vec<Surface>,
    lights: Vec<Light>,
    light_samples: Vec<u32>,
    /// The media around each light.
    light_media: Vec<crate::medium::MediumInterface>,
    /// Area lights waiting for the world's bounds: (light description, surface index).
    area_lights: Vec<(
        Arc<PluginDesc>,
        PrimKind,
        u32,
        crate::medium::MediumInterface,
    )>,
}

impl<'a> Builder<'a> {
    /// A builder of `desc`'s scene placed by `render_from_world`, with nothing built yet.
    fn new(
        desc: &'a SceneDescription,
        warnings: &'a mut Vec<Warning>,
        render_from_world: DMat4,
    ) -> Self {
        Builder {
            desc,
            warnings,
            warned: HashSet::new(),
            render_from_world,
            surfaces: Vec::new(),
            lights: Vec::new(),
            light_samples: Vec::new(),
            light_media: Vec::new(),
            area_lights: Vec::new(),
        }
    }
}

impl Builder<'_> {
    /// Warns at `loc`, once per `key`.
    fn warn_once(&mut self, key: String, loc: &acr_parser::Loc, msg: String) {
        if self.warned.insert(key) {
            self.warnings.push(Warning::at(loc, msg));
        }
    }

    /// Adds surface `s`; its index.
    fn surface(&mut self, s: Surface) -> u32 {
        self.surfaces.push(s);
        (self.surfaces.len() - 1) as u32
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

/// The scene's camera description; a scene without one is an error.
fn camera_of(desc: &SceneDescription) -> Result<&acr_parser::CameraDesc> {
    let Some(camera_desc) = &desc.camera else {
        let path = desc
            .files
            .first()
            .map(|f| f.path.clone())
            .unwrap_or_default();
        return Err(Error::file(path, "the scene has no Camera"));
    };
    Ok(camera_desc)
}

/// The centre and radius of the sphere around the box from `lo` to `hi`; the unit sphere
/// when the box is empty.
fn bounding_sphere(lo: Vec3, hi: Vec3) -> (Vec3, f32) {
    if lo.cmple(hi).all() {
        ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
    } else {
        (Vec3::ZERO, 1.0)
    }
}

impl LightChoices {
    /// The distributions over `lights`, in a world whose geometry spans `bounds`.
    fn new(lights: &[Light], bounds: (Vec3, Vec3)) -> Self {
        let powers: Vec<f32> = lights
            .iter()
            .map(|l| crate::spectrum_luminance(l.power()))
            .collect();
        LightChoices {
            uniform: LightPmf::new(&vec![1.0; powers.len()]),
            power: LightPmf::new(&powers),
            spatial: OnceLock::new(),
            bvh: OnceLock::new(),
            bounds,
        }
    }
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
        let camera_desc = camera_of(desc)?;
        let film = FilmSettings::new(desc.film.as_ref())?;
        let render_from_world = render_from_world(camera_desc)?;
        let diagonal = match &desc.film {
            Some(f) => f.params.float_or("diagonal", 35.0)? as f32,
            None => 35.0,
        };
        let context = crate::camera::CameraContext {
            film_diagonal_mm: diagonal,
            dir: &main_dir,
        };
        let camera = Camera::with_context(
            camera_desc,
            film.resolution,
            render_from_world,
            &context,
            warnings,
        )?;
        let mut b = Builder::new(desc, warnings, render_from_world);
        // The materials (their image textures' decoding and MIP maps) and the geometry's
        // BVHs need nothing of each other: built at once, each keeps the cores busy while the
        // other waits on a serial step (a PNG's inflating, a BVH's top levels). Their warnings
        // keep the order of a build one after the other.
        let mut material_warnings = Vec::new();
        let (accel, materials) = rayon::join(
            || b.accel(),
            || {
                crate::material::build_materials(
                    desc,
                    &main_dir,
                    render_from_world,
                    &mut material_warnings,
                )
            },
        );
        let accel = accel?;
        let (lo, hi) = accel.bounds();
        let (world_center, world_radius) = bounding_sphere(lo, hi);
        // Area lights, now that the world geometry has its final layout.
        b.add_area_lights(&accel)?;
        b.add_lights(world_radius, &main_dir)?;
        let materials = materials?;
        b.warnings.append(&mut material_warnings);
        let media = crate::medium::build_media(&desc.media, render_from_world, b.warnings)?;
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
            lens: camera.uses_lens(),
        };
        Ok(Scene {
            camera,
            film,
            accel,
            light_choice: LightChoices::new(&b.lights, (lo, hi)),
            lights: b.lights,
            light_samples: b.light_samples,
            light_media: b.light_media,
            infinite_lights,
            materials,
            surfaces: b.surfaces,
            media,
            camera_medium: desc.camera_medium.map(|m| m as u32),
            dims,
            world_center,
            world_radius,
            render_from_world,
            differential_scale: 1.0 / (sampler_spp(desc) as f32).sqrt(),
            uses_differentials: uses_differentials(desc),
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
