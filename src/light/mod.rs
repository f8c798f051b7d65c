//! Light sources as pbrt-v3 defines them: point, spot, goniometric, projection, distant,
//! diffuse area and infinite (constant, or an environment map sampled by importance). The
//! goniometric and projection lights' image mappings are in [`light_image`].

use crate::accel::{Geometry, PrimKind};
use crate::geometry::{Frame, Spectrum, SurfaceInteraction, Vec2, Vec3};
use crate::image_io::RgbImage;
use crate::mipmap::MipMap;
use crate::sampling::Distribution2D;
use crate::shapes::triangle::{sample_triangle, triangle_area};
use crate::texture::{ImageMap, Wrap};
use glam::{DMat4, Mat4};
use light_image::{goniometric_scale, ImageProjection, LightImage};
use std::f32::consts::PI;

pub mod emission;
pub mod light_image;
pub use emission::{EmissionSample, WorldSphere};

/// A light sample as seen from a point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the point towards the light.
    pub wi: Vec3,
    /// Incident radiance (or intensity / distance² for delta lights).
    pub li: Spectrum,
    /// Solid-angle density of `wi` (1 for delta lights).
    pub pdf: f32,
    /// The point on the light a shadow ray must reach (far away for distant and infinite lights).
    pub p: Vec3,
}

/// An environment map with its sampling distribution, as pbrt-v3's `InfiniteAreaLight`
/// holds it: a MIP map of the image (resampled to powers of two, wrapping on both axes).
pub struct EnvMap {
    mip: MipMap<Spectrum>,
    distribution: Distribution2D,
    /// A one-pixel map's radiance (pbrt-v3's constant environment): such a map needs no
    /// spherical coordinates for a lookup, and is sampled uniformly over the sphere, as
    /// pbrt-v4 samples a constant environment (docs/pbrt-v3-compatibility.md, "Lights").
    constant: Option<Spectrum>,
}

/// Which static world primitive emits.
#[derive(Clone, Copy, Debug)]
pub struct AreaShape {
    /// The primitive in the world geometry.
    pub kind: PrimKind,
}

/// A light source.
pub enum Light {
    /// `point`: intensity at a position.
    Point {
        /// World position.
        pos: Vec3,
        /// Intensity.
        intensity: Spectrum,
    },
    /// `spot`: a point light within a cone, with a smooth falloff.
    Spot {
        /// World position.
        pos: Vec3,
        /// Light-from-world rotation (the cone's axis is local +z).
        light_from_world: Mat4,
        /// Intensity.
        intensity: Spectrum,
        /// Cosine of the cone's half-angle.
        cos_total: f32,
        /// Cosine of where the falloff starts.
        cos_falloff_start: f32,
    },
    /// `goniometric`: a point light whose intensity in each direction is scaled by an image
    /// over (phi, theta) around its y axis.
    Goniometric {
        /// World position.
        pos: Vec3,
        /// Light-from-world (the light's own transform, scale included, inverted).
        light_from_world: Mat4,
        /// Intensity.
        intensity: Spectrum,
        /// The image, if any (without one, the intensity in every direction).
        map: Option<LightImage>,
    },
    /// `projection`: a point light casting an image through a perspective frustum along its +z.
    Projection {
        /// World position.
        pos: Vec3,
        /// Light-from-world (the light's own transform, scale included, inverted).
        light_from_world: Mat4,
        /// Intensity.
        intensity: Spectrum,
        /// The frustum and its image.
        projection: ImageProjection,
    },
    /// `distant`: parallel light from one direction.
    Distant {
        /// Unit direction towards the light.
        w: Vec3,
        /// Radiance.
        radiance: Spectrum,
        /// Radius of the scene's bounding sphere.
        world_radius: f32,
    },
    /// `area` / `diffuse`: emission from a shape's surface.
    Area {
        /// The emitting primitive.
        shape: AreaShape,
        /// Emitted radiance.
        l_emit: Spectrum,
        /// Emits on both sides.
        two_sided: bool,
        /// Surface area (world space).
        area: f32,
    },
    /// `infinite`: radiance from every direction, constant or from a map.
    Infinite {
        /// Radiance scale (times the map when there is one).
        l: Spectrum,
        /// The environment map, if any.
        map: Option<EnvMap>,
        /// Light-from-world.
        light_from_world: Mat4,
        /// World-from-light.
        world_from_light: Mat4,
        /// Radius of the scene's bounding sphere.
        world_radius: f32,
    },
}

/// The emitting side rule of area lights.
#[inline]
fn area_emission(l_emit: Spectrum, two_sided: bool, n: Vec3, w: Vec3) -> Spectrum {
    if two_sided || n.dot(w) > 0.0 {
        l_emit
    } else {
        Spectrum::ZERO
    }
}

/// (phi, theta) of a unit vector in pbrt's spherical coordinates, as st in [0,1)^2.
#[inline]
fn direction_to_st(w: Vec3) -> Vec2 {
    let theta = w.z.clamp(-1.0, 1.0).acos();
    let p = w.y.atan2(w.x);
    let phi = if p < 0.0 { p + 2.0 * PI } else { p };
    Vec2::new(phi / (2.0 * PI), theta / PI)
}

impl EnvMap {
    /// The map of `image` (top row first, theta = 0 at the top) and its distribution, as
    /// pbrt-v3 builds them: the luminance of filtered lookups (width 0.5 over the shorter
    /// side) on a grid twice the MIP map's resolution, times sin(theta).
    pub fn new(image: &RgbImage) -> Self {
        let (w, h) = (image.width.max(1), image.height.max(1));
        let pixels = if image.pixels.len() == w * h {
            image.pixels.clone()
        } else {
            vec![Spectrum::ZERO; w * h]
        };
        let mip = MipMap::new(&ImageMap::from_rows(w, h, pixels, Wrap::Repeat), false, 8.0);
        let (mw, mh) = mip.size();
        let (dw, dh) = (2 * mw, 2 * mh);
        let filter_width = 0.5 / dw.min(dh) as f32;
        let mut values = vec![0.0f32; dw * dh];
        for v in 0..dh {
            let t = (v as f32 + 0.5) / dh as f32;
            let sin_theta = (PI * t).sin();
            for u in 0..dw {
                let st = Vec2::new((u as f32 + 0.5) / dw as f32, t);
                values[v * dw + u] =
                    crate::spectrum_luminance(mip.lookup_width(st, filter_width)) * sin_theta;
            }
        }
        let distribution = Distribution2D::new(&values, dw, dh);
        let constant = (w == 1 && h == 1).then(|| mip.lookup_width(Vec2::splat(0.5), 0.0));
        Self {
            mip,
            distribution,
            constant,
        }
    }

    /// pbrt-v3's `Lmap->Lookup(st)`: bilinear on the MIP map's finest level.
    pub fn lookup(&self, st: Vec2) -> Spectrum {
        self.mip.lookup_width(st, 0.0)
    }

    /// What pbrt-v3's `Power` takes for the map: a lookup at the centre with width 0.5, the
    /// mean of the (resampled) image.
    pub fn average(&self) -> Spectrum {
        self.mip.lookup_width(Vec2::splat(0.5), 0.5)
    }
}

impl Light {
    /// True for lights that a ray can never hit (point, spot, goniometric, projection,
    /// distant).
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point { .. }
                | Light::Spot { .. }
                | Light::Goniometric { .. }
                | Light::Projection { .. }
                | Light::Distant { .. }
        )
    }

    /// Total emitted power (its luminance drives the power-based light choice).
    pub fn power(&self) -> Spectrum {
        match self {
            Light::Point { intensity, .. } => *intensity * 4.0 * PI,
            Light::Spot {
                intensity,
                cos_total,
                cos_falloff_start,
                ..
            } => *intensity * 2.0 * PI * (1.0 - 0.5 * (cos_falloff_start + cos_total)),
            // pbrt-v3: 4 pi I times the image's mean (see `LightImage::average`).
            Light::Goniometric { intensity, map, .. } => {
                *intensity * 4.0 * PI * map.as_ref().map_or(Spectrum::ONE, |m| m.average())
            }
            // pbrt-v3: the image's mean times I times the solid angle of the cone through the
            // screen window's corners.
            Light::Projection {
                intensity,
                projection,
                ..
            } => {
                projection.map().map_or(Spectrum::ONE, |m| m.average())
                    * *intensity
                    * 2.0
                    * PI
                    * (1.0 - projection.cos_total_width)
            }
            Light::Distant {
                radiance,
                world_radius,
                ..
            } => *radiance * PI * world_radius * world_radius,
            Light::Area {
                l_emit,
                two_sided,
                area,
                ..
            } => *l_emit * (if *two_sided { 2.0 } else { 1.0 }) * *area * PI,
            Light::Infinite {
                l,
                map,
                world_radius,
                ..
            } => {
                let avg = map.as_ref().map_or(Spectrum::ONE, EnvMap::average);
                *l * avg * PI * world_radius * world_radius
            }
        }
    }

    /// Samples incident light at `p`; `None` when there is none to sample.
    pub fn sample_li(&self, world: &Geometry, p: Vec3, u: Vec2) -> Option<LightSample> {
        match self {
            Light::Point { pos, intensity } => {
                let d2 = pos.distance_squared(p);
                Some(LightSample {
                    wi: (*pos - p).normalize(),
                    li: *intensity / d2,
                    pdf: 1.0,
                    p: *pos,
                })
            }
            Light::Spot {
                pos,
                light_from_world,
                intensity,
                cos_total,
                cos_falloff_start,
            } => {
                let wi = (*pos - p).normalize();
                let wl = light_from_world.transform_vector3(-wi).normalize();
                let falloff = spot_falloff(wl, *cos_total, *cos_falloff_start);
                if falloff == 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    li: *intensity * falloff / pos.distance_squared(p),
                    pdf: 1.0,
                    p: *pos,
                })
            }
            // pbrt-v3's Sample_Li: intensity scaled by the image in the direction the light
            // sends towards p (-wi, in light space), over the squared distance, pdf 1.
            Light::Goniometric {
                pos,
                light_from_world,
                intensity,
                map,
            } => {
                let wi = (*pos - p).normalize();
                let wl = light_from_world.transform_vector3(-wi);
                delta_sample(
                    *pos,
                    p,
                    wi,
                    *intensity * goniometric_scale(map.as_ref(), wl),
                )
            }
            Light::Projection {
                pos,
                light_from_world,
                intensity,
                projection,
            } => {
                let wi = (*pos - p).normalize();
                let wl = light_from_world.transform_vector3(-wi);
                delta_sample(*pos, p, wi, *intensity * projection.eval(wl))
            }
            Light::Distant {
                w,
                radiance,
                world_radius,
            } => Some(LightSample {
                wi: *w,
                li: *radiance,
                pdf: 1.0,
                p: p + *w * (2.0 * world_radius),
            }),
            Light::Area {
                shape,
                l_emit,
                two_sided,
                area,
            } => {
                let (q, n, pdf) = match shape.kind {
                    PrimKind::Sphere(i) => {
                        let s = &world.spheres[i as usize];
                        match s.sample_solid_angle(p, u) {
                            Some((q, n, pdf)) => (q, n, pdf),
                            None => {
                                let (q, n) = s.sample_area(u);
                                (q, n, area_to_solid_angle(p, q, n, *area)?)
                            }
                        }
                    }
                    _ => {
                        let (q, n) = sample_area(world, shape.kind, u);
                        (q, n, area_to_solid_angle(p, q, n, *area)?)
                    }
                };
                area_light_sample(p, q, n, pdf, *l_emit, *two_sided)
            }
            Light::Infinite {
                l,
                map,
                world_from_light,
                world_radius,
                ..
            } => {
                let (wi, pdf, li) = match map {
                    Some(EnvMap {
                        constant: Some(c), ..
                    }) => {
                        let wi = crate::sampling::uniform_sample_sphere(u);
                        (wi, 1.0 / (4.0 * PI), *l * *c)
                    }
                    Some(m) => {
                        let (st, map_pdf) = m.distribution.sample(u);
                        if map_pdf == 0.0 {
                            return None;
                        }
                        let (theta, phi) = (st.y * PI, st.x * 2.0 * PI);
                        let sin_theta = theta.sin();
                        if sin_theta == 0.0 {
                            return None;
                        }
                        let wl =
                            Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), theta.cos());
                        let wi = world_from_light.transform_vector3(wl).normalize();
                        (wi, map_pdf / (2.0 * PI * PI * sin_theta), *l * m.lookup(st))
                    }
                    None => {
                        // Uniform over the sphere, as a one-pixel map is.
                        let wi = crate::sampling::uniform_sample_sphere(u);
                        (wi, 1.0 / (4.0 * PI), *l)
                    }
                };
                Some(LightSample {
                    wi,
                    li,
                    pdf,
                    p: p + wi * (2.0 * world_radius),
                })
            }
        }
    }

    /// The point and normal that [`Light::sample_li`] picks with `u` on an area light whose
    /// choice does not depend on the receiving point (every shape but the sphere, which samples
    /// the cone it subtends); `None` for every other light.
    pub fn sample_point(&self, world: &Geometry, u: Vec2) -> Option<(Vec3, Vec3)> {
        match self {
            Light::Area { shape, .. } if !matches!(shape.kind, PrimKind::Sphere(_)) => {
                Some(sample_area(world, shape.kind, u))
            }
            _ => None,
        }
    }

    /// [`Light::sample_li`] from `p` given the point `q` and normal `n` that
    /// [`Light::sample_point`] chose: the same sample, without sampling the shape again.
    pub fn sample_li_at_point(&self, p: Vec3, q: Vec3, n: Vec3) -> Option<LightSample> {
        match self {
            Light::Area {
                l_emit,
                two_sided,
                area,
                ..
            } => {
                let pdf = area_to_solid_angle(p, q, n, *area)?;
                area_light_sample(p, q, n, pdf, *l_emit, *two_sided)
            }
            _ => None,
        }
    }

    /// Solid-angle density with which [`Light::sample_li`] from `p` would pick the point `q`
    /// with normal `n` on this area light.
    pub fn pdf_area_hit(&self, world: &Geometry, p: Vec3, q: Vec3, n: Vec3) -> f32 {
        match self {
            Light::Area { shape, area, .. } => {
                if let PrimKind::Sphere(i) = shape.kind {
                    let s = &world.spheres[i as usize];
                    let pdf = s.pdf_solid_angle(p);
                    if pdf > 0.0 {
                        return pdf;
                    }
                }
                area_to_solid_angle(p, q, n, *area).unwrap_or(0.0)
            }
            _ => 0.0,
        }
    }

    /// Radiance an area light emits from `si` towards `w`.
    pub fn l(&self, si: &SurfaceInteraction, w: Vec3) -> Spectrum {
        match self {
            Light::Area {
                l_emit, two_sided, ..
            } => area_emission(*l_emit, *two_sided, si.n, w),
            _ => Spectrum::ZERO,
        }
    }

    /// Radiance of an infinite light along a ray that escapes the scene (direction `d`).
    pub fn le(&self, d: Vec3) -> Spectrum {
        match self {
            Light::Infinite {
                l,
                map,
                light_from_world,
                ..
            } => match map {
                Some(EnvMap {
                    constant: Some(c), ..
                }) => *l * *c,
                Some(m) => {
                    let wl = light_from_world.transform_vector3(d).normalize();
                    *l * m.lookup(direction_to_st(wl))
                }
                None => *l,
            },
            _ => Spectrum::ZERO,
        }
    }

    /// Solid-angle density of sampling direction `d` from an infinite light.
    pub fn pdf_le(&self, d: Vec3) -> f32 {
        match self {
            Light::Infinite {
                map,
                light_from_world,
                ..
            } => match map {
                Some(EnvMap {
                    constant: Some(_), ..
                }) => 1.0 / (4.0 * PI),
                Some(m) => {
                    let wl = light_from_world.transform_vector3(d).normalize();
                    let st = direction_to_st(wl);
                    let sin_theta = (st.y * PI).sin();
                    if sin_theta == 0.0 {
                        0.0
                    } else {
                        m.distribution.pdf(st) / (2.0 * PI * PI * sin_theta)
                    }
                }
                None => 1.0 / (4.0 * PI),
            },
            _ => 0.0,
        }
    }
}

/// A point and normal uniformly distributed by area on a primitive.
fn sample_area(world: &Geometry, kind: PrimKind, u: Vec2) -> (Vec3, Vec3) {
    match kind {
        PrimKind::Triangle { mesh, tri } => {
            sample_triangle(&world.meshes[mesh as usize], tri as usize, u)
        }
        PrimKind::Sphere(i) => world.spheres[i as usize].sample_area(u),
        PrimKind::Disk(i) => world.disks[i as usize].sample_area(u),
        PrimKind::Cylinder(i) => world.cylinders[i as usize].sample_area(u),
        // Never an emitter: the scene refuses area lights on these shapes (pbrt-v3 cannot
        // sample them either). A point with no normal contributes nothing.
        PrimKind::Revolved(_) | PrimKind::Curve(_) => (Vec3::ZERO, Vec3::ZERO),
    }
}

/// Area of a primitive (world space).
pub fn prim_area(world: &Geometry, kind: PrimKind) -> f32 {
    match kind {
        PrimKind::Triangle { mesh, tri } => {
            triangle_area(&world.meshes[mesh as usize], tri as usize)
        }
        PrimKind::Sphere(i) => world.spheres[i as usize].area(),
        PrimKind::Disk(i) => world.disks[i as usize].area(),
        PrimKind::Cylinder(i) => world.cylinders[i as usize].area(),
        // Never an emitter (see `sample_area`).
        PrimKind::Revolved(_) | PrimKind::Curve(_) => 0.0,
    }
}

/// The sample of an area light seen from `p` when the point `q` (normal `n`) was picked with
/// solid-angle density `pdf`; `None` when it contributes nothing.
#[inline]
fn area_light_sample(
    p: Vec3,
    q: Vec3,
    n: Vec3,
    pdf: f32,
    l_emit: Spectrum,
    two_sided: bool,
) -> Option<LightSample> {
    let wi = (q - p).normalize_or_zero();
    if pdf <= 0.0 || !pdf.is_finite() || wi == Vec3::ZERO {
        return None;
    }
    let li = area_emission(l_emit, two_sided, n, -wi);
    if li == Spectrum::ZERO {
        return None;
    }
    Some(LightSample { wi, li, pdf, p: q })
}

/// Converts the uniform area density 1/area at `q` (normal `n`) to solid angle seen from `p`.
#[inline]
fn area_to_solid_angle(p: Vec3, q: Vec3, n: Vec3, area: f32) -> Option<f32> {
    let d = q - p;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        return None;
    }
    let cos = n.dot(-d / d2.sqrt()).abs();
    if cos == 0.0 {
        return None;
    }
    let pdf = d2 / (cos * area);
    pdf.is_finite().then_some(pdf)
}

/// A frame for a spot light: local +z along `dir`.
pub fn spot_frame(dir: Vec3) -> Mat4 {
    let f = Frame::from_z(dir);
    // Rows are the frame axes: world -> local.
    Mat4::from_cols(
        f.s.extend(0.0),
        f.t.extend(0.0),
        f.n.extend(0.0),
        glam::Vec4::W,
    )
    .transpose()
}

/// A delta light's sample at `p` from `pos` along unit `wi` with intensity `intensity`
/// (already scaled for the direction): intensity / distance², pdf 1; `None` when it sends
/// nothing that way.
#[inline]
fn delta_sample(pos: Vec3, p: Vec3, wi: Vec3, intensity: Spectrum) -> Option<LightSample> {
    if intensity == Spectrum::ZERO {
        return None;
    }
    Some(LightSample {
        wi,
        li: intensity / pos.distance_squared(p),
        pdf: 1.0,
        p: pos,
    })
}

/// The world-to-light transform of a light placed by `world_from_light`, if it has one.
fn light_from(world_from_light: &DMat4) -> Result<Mat4, String> {
    let m = world_from_light.inverse().as_mat4();
    if m.is_finite() && world_from_light.determinant() != 0.0 {
        Ok(m)
    } else {
        Err("the light's transform cannot be inverted".into())
    }
}

impl Light {
    /// pbrt-v3's `GonioPhotometricLight` at the origin of `world_from_light`, with intensity
    /// `intensity` (I times scale) and its image, if any.
    pub fn goniometric(
        world_from_light: &DMat4,
        intensity: Spectrum,
        map: Option<LightImage>,
    ) -> Result<Light, String> {
        Ok(Light::Goniometric {
            pos: world_from_light.as_mat4().transform_point3(Vec3::ZERO),
            light_from_world: light_from(world_from_light)?,
            intensity,
            map,
        })
    }

    /// pbrt-v3's `ProjectionLight` at the origin of `world_from_light`, looking along its +z,
    /// with intensity `intensity` (I times scale), its image, if any, and field of view
    /// `fov_degrees`.
    pub fn projection(
        world_from_light: &DMat4,
        intensity: Spectrum,
        map: Option<LightImage>,
        fov_degrees: f32,
    ) -> Result<Light, String> {
        if !(fov_degrees > 0.0 && fov_degrees < 180.0) {
            return Err(format!(
                "fov {fov_degrees} is not between 0 and 180 degrees"
            ));
        }
        Ok(Light::Projection {
            pos: world_from_light.as_mat4().transform_point3(Vec3::ZERO),
            light_from_world: light_from(world_from_light)?,
            intensity,
            projection: ImageProjection::new(map, fov_degrees),
        })
    }
}

/// pbrt-v3's spot falloff for the light-space direction `wl` (unit): 1 inside the falloff
/// cone, 0 outside the total cone, a quartic of the cosines between. `sample_li` and
/// `sample_le` share it.
fn spot_falloff(wl: Vec3, cos_total: f32, cos_falloff_start: f32) -> f32 {
    let cos_theta = wl.z;
    if cos_theta < cos_total {
        0.0
    } else if cos_theta >= cos_falloff_start {
        1.0
    } else {
        let delta = (cos_theta - cos_total) / (cos_falloff_start - cos_total);
        (delta * delta) * (delta * delta)
    }
}

#[cfg(test)]
mod tests;
