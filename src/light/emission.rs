//! Light emission as a light subpath starts it: pbrt-v3's `Light::Sample_Le` (a ray leaving
//! the light, with the densities of its origin and of its direction) and `Light::Pdf_Le`, for
//! bdpt's light subpaths and their MIS weights (docs/light-transport.md).

use super::{area_emission, goniometric_scale, sample_area, spot_falloff, Light};
use crate::accel::Geometry;
use crate::geometry::{offset_ray_origin, Frame, Ray, Spectrum, Vec2, Vec3};
use crate::sampling::{
    concentric_sample_disk, cosine_sample_hemisphere, uniform_cone_pdf, uniform_sample_cone,
    uniform_sample_sphere,
};
use crate::scene::Scene;
use std::f32::consts::{FRAC_1_PI, PI};

/// A ray leaving a light (pbrt-v3's `Sample_Le` result).
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    /// Where the ray starts.
    pub o: Vec3,
    /// Its unit direction.
    pub d: Vec3,
    /// The light's surface normal there (zero for lights not on a surface).
    pub n: Vec3,
    /// Emitted radiance (intensity for point lights) along the ray.
    pub le: Spectrum,
    /// Density of the origin (area measure; 1 for point lights).
    pub pdf_pos: f32,
    /// Density of the direction (solid angle).
    pub pdf_dir: f32,
}

/// The world's bounding sphere, where distant and infinite lights start their rays.
#[derive(Clone, Copy, Debug)]
pub struct WorldSphere {
    /// Centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
}

/// A point on the disk of radius `r` facing `d` through `center`, from `u`.
fn disk_point(center: Vec3, r: f32, d: Vec3, u: Vec2) -> Vec3 {
    let f = Frame::from_z(d);
    let cd = concentric_sample_disk(u);
    center + r * (cd.x * f.s + cd.y * f.t)
}

impl Light {
    /// pbrt-v3's `Sample_Le`: a ray leaving the light from `u1` (origin) and `u2`
    /// (direction); `None` when the light sends nothing or the densities are zero. Point,
    /// goniometric and projection lights sample the sphere uniformly (pbrt-v3 samples the
    /// projection's cone: the same expectation), spot lights their cone.
    pub fn sample_le(
        &self,
        world: &Geometry,
        sphere: WorldSphere,
        u1: Vec2,
        u2: Vec2,
    ) -> Option<EmissionSample> {
        let point = |pos: Vec3, d: Vec3, le: Spectrum, pdf_dir: f32| EmissionSample {
            o: pos,
            d,
            n: Vec3::ZERO,
            le,
            pdf_pos: 1.0,
            pdf_dir,
        };
        let sphere_pdf = 1.0 / (4.0 * PI);
        let s = match self {
            Light::Point { pos, intensity } => {
                point(*pos, uniform_sample_sphere(u1), *intensity, sphere_pdf)
            }
            Light::Spot {
                pos,
                light_from_world,
                intensity,
                cos_total,
                cos_falloff_start,
            } => {
                let wl = uniform_sample_cone(u1, *cos_total);
                // The spot's frame is a rotation: its transpose turns light space to world.
                let d = light_from_world
                    .transpose()
                    .transform_vector3(wl)
                    .normalize();
                let le = *intensity * spot_falloff(wl, *cos_total, *cos_falloff_start);
                point(*pos, d, le, uniform_cone_pdf(*cos_total))
            }
            Light::Goniometric {
                pos,
                light_from_world,
                intensity,
                map,
            } => {
                let d = uniform_sample_sphere(u1);
                let wl = light_from_world.transform_vector3(d);
                let le = *intensity * goniometric_scale(map.as_ref(), wl);
                point(*pos, d, le, sphere_pdf)
            }
            Light::Projection {
                pos,
                light_from_world,
                intensity,
                projection,
            } => {
                let d = uniform_sample_sphere(u1);
                let wl = light_from_world.transform_vector3(d);
                point(*pos, d, *intensity * projection.eval(wl), sphere_pdf)
            }
            Light::Distant { w, radiance, .. } => {
                let d = -*w;
                let p = disk_point(sphere.center, sphere.radius, d, u1);
                EmissionSample {
                    o: p - d * sphere.radius,
                    d,
                    n: Vec3::ZERO,
                    le: *radiance,
                    pdf_pos: 1.0 / (PI * sphere.radius * sphere.radius),
                    pdf_dir: 1.0,
                }
            }
            Light::Area {
                shape,
                l_emit,
                two_sided,
                area,
            } => {
                let (p, n) = sample_area(world, shape.kind, u1);
                if n == Vec3::ZERO {
                    return None;
                }
                let (mut u, flip) = (u2, *two_sided && u2.x >= 0.5);
                if *two_sided {
                    let x = if flip { (u.x - 0.5) * 2.0 } else { u.x * 2.0 };
                    u.x = x.min(1.0 - f32::EPSILON);
                }
                let mut wl = cosine_sample_hemisphere(u);
                if flip {
                    wl.z = -wl.z;
                }
                let pdf_dir = wl.z.abs() * FRAC_1_PI * if *two_sided { 0.5 } else { 1.0 };
                let f = Frame::from_z(n);
                let d = (wl.x * f.s + wl.y * f.t + wl.z * f.n).normalize();
                EmissionSample {
                    o: p,
                    d,
                    n,
                    le: area_emission(*l_emit, *two_sided, n, d),
                    pdf_pos: 1.0 / area,
                    pdf_dir,
                }
            }
            Light::Infinite { l, map, .. } => {
                // The direction towards the light as `sample_li` picks it; the ray comes in.
                let ls = self.sample_li(world, sphere.center, u1)?;
                let d = -ls.wi;
                let p = disk_point(sphere.center, sphere.radius, d, u2);
                let le = match map {
                    Some(_) => ls.li,
                    None => *l,
                };
                EmissionSample {
                    o: p - d * sphere.radius,
                    d,
                    n: Vec3::ZERO,
                    le,
                    pdf_pos: 1.0 / (PI * sphere.radius * sphere.radius),
                    pdf_dir: ls.pdf,
                }
            }
        };
        let ok = s.pdf_pos > 0.0 && s.pdf_dir > 0.0 && s.le != Spectrum::ZERO;
        (ok && s.pdf_pos.is_finite() && s.pdf_dir.is_finite()).then_some(s)
    }

    /// pbrt-v3's `Pdf_Le`: the densities (origin, direction) with which [`Light::sample_le`]
    /// starts a ray at `p` (normal `n` on an area light) along unit `d`.
    pub fn pdf_emission(&self, sphere: WorldSphere, n: Vec3, d: Vec3) -> (f32, f32) {
        let sphere_pdf = 1.0 / (4.0 * PI);
        let disk_pdf = 1.0 / (PI * sphere.radius * sphere.radius);
        match self {
            Light::Point { .. } | Light::Goniometric { .. } | Light::Projection { .. } => {
                (1.0, sphere_pdf)
            }
            Light::Spot {
                light_from_world,
                cos_total,
                ..
            } => {
                let wl = light_from_world.transform_vector3(d);
                let inside = wl.z >= *cos_total;
                (
                    1.0,
                    if inside {
                        uniform_cone_pdf(*cos_total)
                    } else {
                        0.0
                    },
                )
            }
            Light::Distant { .. } => (disk_pdf, 0.0),
            Light::Area {
                two_sided, area, ..
            } => {
                let c = n.dot(d);
                let pdf_dir = if *two_sided {
                    0.5 * c.abs() * FRAC_1_PI
                } else {
                    c.max(0.0) * FRAC_1_PI
                };
                (1.0 / area, pdf_dir)
            }
            Light::Infinite { .. } => (disk_pdf, self.pdf_le(-d)),
        }
    }
}

impl Light {
    /// [`Light::sample_li`] with the light's surface normal at the point chosen (zero for
    /// lights not on a surface), as bdpt's light vertices need it. Area lights pick their
    /// point uniformly by area (spheres too: the normal must be the chosen point's).
    pub fn sample_li_with_normal(
        &self,
        world: &Geometry,
        p: Vec3,
        u: Vec2,
    ) -> Option<(super::LightSample, Vec3)> {
        match self {
            Light::Area {
                shape,
                l_emit,
                two_sided,
                area,
            } => {
                let (q, n) = sample_area(world, shape.kind, u);
                let pdf = super::area_to_solid_angle(p, q, n, *area)?;
                let ls = super::area_light_sample(p, q, n, pdf, *l_emit, *two_sided)?;
                Some((ls, n))
            }
            _ => self.sample_li(world, p, u).map(|ls| (ls, Vec3::ZERO)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::spot_frame;

    /// `pdf_emission` gives the densities `sample_le` drew its ray with.
    #[test]
    fn emission_densities_match_their_samples() {
        let sphere = WorldSphere {
            center: Vec3::new(0.5, 0.0, -1.0),
            radius: 7.0,
        };
        let world = Geometry::default();
        let lights = [
            Light::Point {
                pos: Vec3::new(1.0, 2.0, 3.0),
                intensity: Spectrum::ONE,
            },
            Light::Spot {
                pos: Vec3::ZERO,
                light_from_world: spot_frame(Vec3::new(0.3, -1.0, 0.2).normalize()),
                intensity: Spectrum::ONE,
                cos_total: 0.8,
                cos_falloff_start: 0.9,
            },
            Light::Distant {
                w: Vec3::new(0.0, 1.0, 0.0),
                radiance: Spectrum::ONE,
                world_radius: 7.0,
            },
            Light::Infinite {
                l: Spectrum::ONE,
                map: None,
                light_from_world: glam::Mat4::IDENTITY,
                world_from_light: glam::Mat4::IDENTITY,
                world_radius: 7.0,
            },
        ];
        for (k, light) in lights.iter().enumerate() {
            for u in [(0.1, 0.2, 0.3, 0.4), (0.8, 0.6, 0.05, 0.95)] {
                let s = light
                    .sample_le(&world, sphere, Vec2::new(u.0, u.1), Vec2::new(u.2, u.3))
                    .unwrap();
                let (pos, dir) = light.pdf_emission(sphere, s.n, s.d);
                assert!(
                    (pos - s.pdf_pos).abs() <= 1e-4 * pos,
                    "light {k}: {pos} {}",
                    s.pdf_pos
                );
                if !matches!(light, Light::Distant { .. }) {
                    assert!(
                        (dir - s.pdf_dir).abs() <= 1e-3 * dir,
                        "light {k}: {dir} {}",
                        s.pdf_dir
                    );
                }
                assert!((s.d.length() - 1.0).abs() < 1e-4);
            }
        }
    }
}

/// A ray sampled leaving a light, ready to trace (sppm's photons).
#[derive(Clone, Copy, Debug)]
pub struct LeSample {
    /// The ray (unit direction), off the light's surface.
    pub ray: Ray,
    /// The normal at its origin (the ray's direction for lights not on a surface).
    pub n: Vec3,
    /// Emitted radiance (intensity for point lights) along the ray.
    pub le: Spectrum,
    /// Density of the origin (area measure; 1 for point lights).
    pub pdf_pos: f32,
    /// Density of the direction (solid angle).
    pub pdf_dir: f32,
}

/// [`Light::sample_le`] for `light` (one of `scene.lights`) as a ray at `time`: from the
/// scene's world sphere, the origin moved off an area light's surface to the side the ray
/// leaves by, and a light not on a surface given the ray's direction as its normal (as bdpt's
/// light subpaths take it).
pub fn sample_le(scene: &Scene, light: &Light, u1: Vec2, u2: Vec2, time: f32) -> Option<LeSample> {
    let sphere = WorldSphere {
        center: scene.world_center,
        radius: scene.world_radius,
    };
    let e = light.sample_le(&scene.accel.world, sphere, u1, u2)?;
    let on_area = e.n != Vec3::ZERO;
    let (n, o) = if on_area {
        let side = if e.n.dot(e.d) < 0.0 { -e.n } else { e.n };
        (e.n, offset_ray_origin(e.o, side))
    } else {
        (e.d, e.o)
    };
    Some(LeSample {
        ray: Ray::new(o, e.d, time),
        n,
        le: e.le,
        pdf_pos: e.pdf_pos,
        pdf_dir: e.pdf_dir,
    })
}
