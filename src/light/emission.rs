//! Rays leaving the lights: pbrt-v3's `Light::Sample_Le`, the first vertex of a photon path
//! (sppm) or a light subpath. docs/light-transport.md.

use super::{area_emission, sample_area, EnvMap, Light};
use crate::geometry::{Frame, Ray, Spectrum, Vec2, Vec3};
use crate::sampling::{
    concentric_sample_disk, cosine_sample_hemisphere, uniform_cone_pdf, uniform_sample_cone,
    uniform_sample_sphere,
};
use crate::scene::Scene;
use std::f32::consts::PI;

/// A ray sampled leaving a light, with what it carries and its densities.
#[derive(Clone, Copy, Debug)]
pub struct LeSample {
    /// The ray (unit direction).
    pub ray: Ray,
    /// The normal at its origin (the ray's direction for point and infinite-like lights).
    pub n: Vec3,
    /// Emitted radiance (intensity for point lights) along the ray.
    pub le: Spectrum,
    /// Density of the origin (area measure; 1 for point lights).
    pub pdf_pos: f32,
    /// Density of the direction (solid angle; 1 for a distant light).
    pub pdf_dir: f32,
}

/// pbrt-v3's `Light::Sample_Le`: a ray leaving `light` (one of `scene.lights`) chosen with
/// `u1` (position, or direction for point lights) and `u2`, at `time`; `None` when it carries
/// nothing or has zero density.
pub fn sample_le(scene: &Scene, light: &Light, u1: Vec2, u2: Vec2, time: f32) -> Option<LeSample> {
    let s = match light {
        Light::Point { pos, intensity } => {
            let d = uniform_sample_sphere(u1);
            point_sample(*pos, d, *intensity, 1.0 / (4.0 * PI), time)
        }
        Light::Spot {
            pos,
            light_from_world,
            intensity,
            cos_total,
            cos_falloff_start,
        } => {
            let wl = uniform_sample_cone(u1, *cos_total);
            // A rotation: its transpose takes light space back to world space.
            let d = light_from_world
                .transpose()
                .transform_vector3(wl)
                .normalize();
            let falloff = spot_falloff(wl.z, *cos_total, *cos_falloff_start);
            point_sample(
                *pos,
                d,
                *intensity * falloff,
                uniform_cone_pdf(*cos_total),
                time,
            )
        }
        Light::Goniometric {
            pos,
            light_from_world,
            intensity,
            map,
        } => {
            let wl = uniform_sample_sphere(u1);
            let d = light_from_world.inverse().transform_vector3(wl).normalize();
            let scale = super::goniometric_scale(map.as_ref(), wl);
            point_sample(*pos, d, *intensity * scale, 1.0 / (4.0 * PI), time)
        }
        Light::Projection {
            pos,
            light_from_world,
            intensity,
            projection,
        } => {
            let cos_total = projection.cos_total_width;
            let wl = uniform_sample_cone(u1, cos_total);
            let d = light_from_world.inverse().transform_vector3(wl).normalize();
            let le = *intensity * projection.eval(wl);
            point_sample(*pos, d, le, uniform_cone_pdf(cos_total), time)
        }
        Light::Distant {
            w,
            radiance,
            world_radius,
        } => {
            let o = disk_point(scene.world_center, *world_radius, *w, u1);
            LeSample {
                ray: Ray::new(o, -*w, time),
                n: -*w,
                le: *radiance,
                pdf_pos: 1.0 / (PI * world_radius * world_radius),
                pdf_dir: 1.0,
            }
        }
        Light::Area {
            shape,
            l_emit,
            two_sided,
            area,
        } => {
            let (p, n) = sample_area(&scene.accel.world, shape.kind, u1);
            if n == Vec3::ZERO || *area <= 0.0 {
                return None;
            }
            let (wl, pdf_dir) = if *two_sided {
                // The first coordinate picks the side, then is stretched back to [0, 1).
                let below = 1.0 - f32::EPSILON / 2.0;
                let (ux, flip) = if u2.x < 0.5 {
                    ((u2.x * 2.0).min(below), false)
                } else {
                    (((u2.x - 0.5) * 2.0).min(below), true)
                };
                let mut w = cosine_sample_hemisphere(Vec2::new(ux, u2.y));
                if flip {
                    w.z = -w.z;
                }
                (w, 0.5 * w.z.abs() / PI)
            } else {
                let w = cosine_sample_hemisphere(u2);
                (w, w.z / PI)
            };
            let d = Frame::from_z(n).from_local(wl);
            // Off the surface, to the side the ray leaves by, by a margin relative to the
            // point's magnitude (the sampled point carries no error bound).
            let side = if d.dot(n) >= 0.0 { n } else { -n };
            let o = p + side * (1e-4 * (1.0 + p.abs().max_element()));
            LeSample {
                ray: Ray::new(o, d, time),
                n,
                le: area_emission(*l_emit, *two_sided, n, d),
                pdf_pos: 1.0 / area,
                pdf_dir,
            }
        }
        Light::Infinite {
            l,
            map,
            world_from_light,
            world_radius,
            ..
        } => {
            let (wi, pdf_dir, le) = infinite_direction(map.as_ref(), world_from_light, u1)?;
            // Light arrives from `wi`: the ray travels along -wi from a disk facing it.
            let o = disk_point(scene.world_center, *world_radius, wi, u2);
            LeSample {
                ray: Ray::new(o, -wi, time),
                n: -wi,
                le: *l * le,
                pdf_pos: 1.0 / (PI * world_radius * world_radius),
                pdf_dir,
            }
        }
    };
    let usable = s.pdf_pos > 0.0
        && s.pdf_dir > 0.0
        && s.pdf_pos.is_finite()
        && s.pdf_dir.is_finite()
        && s.le != Spectrum::ZERO
        && s.ray.d.is_finite();
    usable.then_some(s)
}

/// A ray from point light position `pos` along unit `d`.
fn point_sample(pos: Vec3, d: Vec3, le: Spectrum, pdf_dir: f32, time: f32) -> LeSample {
    LeSample {
        ray: Ray::new(pos, d, time),
        n: d,
        le,
        pdf_pos: 1.0,
        pdf_dir,
    }
}

/// pbrt-v3's spot falloff at light-space cosine `cos_theta` (as `Light::sample_li`).
fn spot_falloff(cos_theta: f32, cos_total: f32, cos_falloff_start: f32) -> f32 {
    if cos_theta < cos_total {
        0.0
    } else if cos_theta >= cos_falloff_start {
        1.0
    } else {
        let delta = (cos_theta - cos_total) / (cos_falloff_start - cos_total);
        (delta * delta) * (delta * delta)
    }
}

/// A point on the disk of radius `radius` facing unit `w`, centred `radius` from `center`
/// towards `w` (where rays arriving from direction `w` start).
fn disk_point(center: Vec3, radius: f32, w: Vec3, u: Vec2) -> Vec3 {
    let f = Frame::from_z(w);
    let cd = concentric_sample_disk(u);
    center + radius * (cd.x * f.s + cd.y * f.t) + radius * w
}

/// The direction light arrives from (world), its solid-angle density and the map's value
/// there (1 without a map), as `Light::sample_li` picks it for an infinite light.
fn infinite_direction(
    map: Option<&EnvMap>,
    world_from_light: &glam::Mat4,
    u: Vec2,
) -> Option<(Vec3, f32, Spectrum)> {
    match map {
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
            let wl = Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), theta.cos());
            let wi = world_from_light.transform_vector3(wl).normalize();
            Some((wi, map_pdf / (2.0 * PI * PI * sin_theta), m.lookup(st)))
        }
        None => Some((uniform_sample_sphere(u), 1.0 / (4.0 * PI), Spectrum::ONE)),
    }
}
