//! Building a scene's lights from their pbrt-v3 descriptions: `LightSource` directives, and the
//! parameters area lights share with them.

use super::Builder;
use crate::accel::Accel;
use crate::geometry::{Spectrum, Vec3};
use crate::image_io::RgbImage;
use crate::light::light_image::LightImage;
use crate::light::{prim_area, spot_frame, AreaShape, EnvMap, Light};
use acr_parser::{Error, ParamList, ParamType, PluginDesc, Result};
use glam::{DMat4, Mat4};
use std::path::Path;

impl Builder<'_> {
    /// The area lights of the world's shapes, one per primitive of positive area that emits,
    /// each attached to its primitive's surface (`accel` placed, so that areas are final).
    pub(super) fn add_area_lights(&mut self, accel: &Accel) -> Result<()> {
        for (light, kind, surface, media) in std::mem::take(&mut self.area_lights) {
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
                self.lights.push(Light::Area {
                    shape: AreaShape { kind },
                    l_emit,
                    two_sided,
                    area,
                });
                self.light_samples.push(samples);
                self.light_media.push(media);
                self.surfaces[surface as usize].area_light = Some((self.lights.len() - 1) as u32);
            }
        }
        Ok(())
    }

    /// The `LightSource` lights, in render space, with their shadow sample counts; an infinite
    /// light surrounds a world of radius `world_radius`.
    pub(super) fn add_lights(&mut self, world_radius: f32, main_dir: &Path) -> Result<()> {
        let desc = self.desc;
        for l in &desc.lights {
            let world_from_light = self.render_from_world * l.world_from_light;
            let light = light(&l.plugin, &world_from_light, world_radius, main_dir)?;
            let samples = match light {
                Light::Infinite { .. } => light_sample_count(&l.plugin.params)?,
                _ => 1,
            };
            self.lights.push(light);
            self.light_samples.push(samples);
            let outside = l.media.outside.map(|m| m as u32);
            self.light_media.push(crate::medium::MediumInterface {
                inside: outside,
                outside,
            });
        }
        Ok(())
    }
}

/// One `LightSource` light, placed by `world_from_light` (render space from light space); an
/// infinite or distant light surrounds a world of radius `world_radius`.
fn light(
    p: &PluginDesc,
    world_from_light: &DMat4,
    world_radius: f32,
    main_dir: &Path,
) -> Result<Light> {
    let scale = rgb_param(&p.params, "scale", Spectrum::ONE)?;
    let m = world_from_light.as_mat4();
    match p.kind.as_str() {
        "point" => point_light(&p.params, m, scale),
        "spot" => spot_light(p, m, scale),
        "distant" => distant_light(p, m, scale, world_radius),
        "infinite" | "exinfinite" => infinite_light(p, m, scale, world_radius, main_dir),
        "goniometric" | "projection" => image_light(p, world_from_light, scale, main_dir),
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
            Err(Error::at(
                &p.loc,
                format!("unknown light \"{other}\"{hint}"),
            ))
        }
    }
}

/// A `point` light at `from`, placed by `m`.
fn point_light(params: &ParamList, m: Mat4, scale: Spectrum) -> Result<Light> {
    let from = vec3_param(params, "from", Vec3::ZERO)?;
    Ok(Light::Point {
        pos: m.transform_point3(from),
        intensity: rgb_param(params, "I", Spectrum::ONE)? * scale,
    })
}

/// A `spot` light from `from` towards `to`, placed by `m`, its cone falling off over
/// `conedeltaangle`.
fn spot_light(p: &PluginDesc, m: Mat4, scale: Spectrum) -> Result<Light> {
    let params = &p.params;
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
    Ok(Light::Spot {
        pos,
        light_from_world: spot_frame(dir),
        intensity: rgb_param(params, "I", Spectrum::ONE)? * scale,
        cos_total: cone.to_radians().cos(),
        cos_falloff_start: (cone - delta).to_radians().cos(),
    })
}

/// A `distant` light shining from `from` towards `to`, placed by `m`.
fn distant_light(p: &PluginDesc, m: Mat4, scale: Spectrum, world_radius: f32) -> Result<Light> {
    let params = &p.params;
    let from = vec3_param(params, "from", Vec3::ZERO)?;
    let to = vec3_param(params, "to", Vec3::Z)?;
    let w = m.transform_vector3(from - to).normalize_or_zero();
    if w == Vec3::ZERO {
        return Err(Error::at(
            &p.loc,
            "distant light: \"from\" and \"to\" coincide",
        ));
    }
    Ok(Light::Distant {
        w,
        radiance: rgb_param(params, "L", Spectrum::ONE)? * scale,
        world_radius,
    })
}

/// An `infinite` light: its environment map (`mapname`), or a constant one, oriented by `m`.
fn infinite_light(
    p: &PluginDesc,
    m: Mat4,
    scale: Spectrum,
    world_radius: f32,
    main_dir: &Path,
) -> Result<Light> {
    let l = rgb_param(&p.params, "L", Spectrum::ONE)? * scale;
    let map = match map_image(p, main_dir)? {
        Some((img, _, _)) => Some(EnvMap::new(&img)),
        // pbrt-v3 gives a constant environment a 1x1 map and samples it through the map's
        // distribution (uniform in (phi, theta), denser at the poles); doing the same keeps
        // the variance, and the spatial light choice, as pbrt-v3 has them.
        None => Some(EnvMap::new(&crate::image_io::RgbImage {
            width: 1,
            height: 1,
            pixels: vec![Spectrum::ONE],
        })),
    };
    Ok(Light::Infinite {
        l,
        map,
        light_from_world: m.inverse(),
        world_from_light: m,
        world_radius,
    })
}

/// A `goniometric` or `projection` light, placed by `world_from_light`, with its image
/// (`mapname`) if it has one.
fn image_light(
    p: &PluginDesc,
    world_from_light: &DMat4,
    scale: Spectrum,
    main_dir: &Path,
) -> Result<Light> {
    let params = &p.params;
    let intensity = rgb_param(params, "I", Spectrum::ONE)? * scale;
    // pbrt-v3 reads the image with ReadImage: PNG values as stored, no sRGB decoding. Without
    // "mapname" it has no image (and emits I unscaled); acr makes an unreadable one an error
    // where pbrt-v3 goes on without it.
    let map = match map_image(p, main_dir)? {
        Some((img, loc, name)) => Some(
            LightImage::new(&img)
                .ok_or_else(|| Error::at(&loc, format!("\"{name}\" has no pixels")))?,
        ),
        None => None,
    };
    let light = if p.kind == "goniometric" {
        Light::goniometric(world_from_light, intensity, map)
    } else {
        let fov = params.float_or("fov", 45.0)? as f32;
        Light::projection(world_from_light, intensity, map, fov)
    };
    light.map_err(|e| Error::at(&p.loc, format!("{} light: {e}", p.kind)))
}

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

/// An RGB-valued parameter (rgb, spectrum or blackbody) or its default.
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

/// The image a light's `"string mapname"` names, read as pbrt-v3's `ReadImage` does (values
/// as stored, no sRGB decoding), with where and how it was named; `None` without one (or with
/// an empty name). An unreadable file is an error there.
fn map_image(
    p: &PluginDesc,
    main_dir: &Path,
) -> Result<Option<(RgbImage, acr_parser::Loc, String)>> {
    let name = match p.params.string("mapname")? {
        Some(name) if !name.is_empty() => name,
        _ => return Ok(None),
    };
    let loc = p.params.get("mapname").map_or(&p.loc, |x| &x.loc).clone();
    let path = crate::texture::resolve_file(name, &loc, main_dir);
    let img = crate::image_io::read_image(&path, false)
        .map_err(|e| Error::at(&loc, format!("cannot read \"{name}\": {e}")))?;
    Ok(Some((img, loc, name.to_owned())))
}
