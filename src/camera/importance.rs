//! The perspective camera's importance, for light paths that reach it (bdpt's t = 1
//! strategies): pbrt-v3's `PerspectiveCamera::We`, `Pdf_We` and `Sample_Wi`. Other projections
//! have none (pbrt-v3 leaves them unimplemented): their importance and densities are zero, so
//! that no strategy needs them and the MIS weights leave them out. docs/light-transport.md.

use super::{Camera, Projection};
use crate::geometry::{Spectrum, Vec2, Vec3};
use crate::sampling::concentric_sample_disk;
use glam::Vec4;

/// A point on the camera's lens that a light path connects to, with what it sees there.
#[derive(Clone, Copy, Debug)]
pub struct ImportanceSample {
    /// The lens point (world space).
    pub p: Vec3,
    /// The camera's viewing direction (world space), the lens's normal.
    pub n: Vec3,
    /// Unit direction from the reference point towards the lens point.
    pub wi: Vec3,
    /// The importance arriving from the lens point.
    pub we: Spectrum,
    /// Solid-angle density of `wi` at the reference point.
    pub pdf: f32,
    /// The raster position it lands on.
    pub raster: Vec2,
}

/// The area of a film of `resolution` on the plane at distance 1 (pbrt-v3's `A`).
pub(super) fn film_area(raster_to_camera: &glam::Mat4, resolution: (f32, f32)) -> f32 {
    let at = |x: f32, y: f32| {
        let p = *raster_to_camera * Vec4::new(x, y, 0.0, 1.0);
        let p = p.truncate() / p.w;
        p / p.z
    };
    let (a, b) = (at(0.0, 0.0), at(resolution.0, resolution.1));
    ((b.x - a.x) * (b.y - a.y)).abs()
}

impl Camera {
    /// The area of the full film on the plane at distance 1 (pbrt-v3's `A`).
    fn film_area(&self) -> f32 {
        self.film_area
    }

    /// The lens's area (1 for a pinhole).
    fn lens_area(&self) -> f32 {
        if self.lens_radius > 0.0 {
            std::f32::consts::PI * self.lens_radius * self.lens_radius
        } else {
            1.0
        }
    }

    /// Where a ray leaving the lens at world point `o` along unit `d` at `time` lands on the
    /// full film, with the cosine to the viewing direction; `None` off the film, behind the
    /// camera or for a projection other than perspective.
    fn raster_of(&self, o: Vec3, d: Vec3, time: f32) -> Option<(Vec2, f32)> {
        if self.projection != Projection::Perspective {
            return None;
        }
        let (forward, camera_from_world) = match (self.forward, self.camera_from_world) {
            (Some(f), Some(c)) => (f, c),
            _ => {
                let m = self.world_from_camera.at(time);
                (m.transform_vector3(Vec3::Z).normalize(), m.inverse())
            }
        };
        let cos = d.dot(forward);
        if cos <= 0.0 {
            return None;
        }
        let focus = o + d
            * ((if self.lens_radius > 0.0 {
                self.focal_distance
            } else {
                1.0
            }) / cos);
        let pc = camera_from_world.transform_point3(focus);
        let pr = self.camera_to_raster * pc.extend(1.0);
        let r = Vec2::new(pr.x / pr.w, pr.y / pr.w);
        let inside = r.x >= 0.0 && r.x < self.resolution.0 && r.y >= 0.0 && r.y < self.resolution.1;
        inside.then_some((r, cos))
    }

    /// pbrt-v3's `We`: the importance of the ray leaving lens point `o` along unit `d`, and its
    /// raster position. Bounds are the full film's, so that crops share one estimator.
    pub fn we(&self, o: Vec3, d: Vec3, time: f32) -> Option<(Spectrum, Vec2)> {
        let (r, cos) = self.raster_of(o, d, time)?;
        let c2 = cos * cos;
        Some((
            Spectrum::splat(1.0 / (self.film_area() * self.lens_area() * c2 * c2)),
            r,
        ))
    }

    /// pbrt-v3's `Pdf_We`: the densities (position on the lens, direction) of a camera ray
    /// from `o` along unit `d`; zero off the film.
    pub fn pdf_we(&self, o: Vec3, d: Vec3, time: f32) -> (f32, f32) {
        match self.raster_of(o, d, time) {
            Some((_, cos)) => (
                1.0 / self.lens_area(),
                1.0 / (self.film_area() * cos * cos * cos),
            ),
            None => (0.0, 0.0),
        }
    }

    /// [`Camera::pdf_we`]'s direction density for unit `d` of a ray this camera generated
    /// through its film at `time` (so known to land on it): the cosine alone, without the
    /// ray mapped back to the film, when the camera does not move.
    pub fn pdf_we_dir_on_film(&self, o: Vec3, d: Vec3, time: f32) -> f32 {
        let Some(forward) = self.forward else {
            return self.pdf_we(o, d, time).1;
        };
        if self.projection != Projection::Perspective {
            return 0.0;
        }
        let cos = d.dot(forward);
        if cos <= 0.0 {
            return 0.0;
        }
        1.0 / (self.film_area() * cos * cos * cos)
    }

    /// pbrt-v3's `Sample_Wi`: a lens point seen from `p` at `time`, chosen with `u`; `None`
    /// when it sees nothing of the film.
    pub fn sample_wi(&self, p: Vec3, time: f32, u: Vec2) -> Option<ImportanceSample> {
        if self.projection != Projection::Perspective {
            return None;
        }
        let m = self.world_from_camera.at(time);
        let lens = self.lens_radius * concentric_sample_disk(u);
        let q = m.transform_point3(Vec3::new(lens.x, lens.y, 0.0));
        let n = self
            .forward
            .unwrap_or_else(|| m.transform_vector3(Vec3::Z).normalize());
        let w = q - p;
        let dist = w.length();
        if dist == 0.0 {
            return None;
        }
        let wi = w / dist;
        let cos = n.dot(wi).abs();
        if cos == 0.0 {
            return None;
        }
        let pdf = dist * dist / (cos * self.lens_area());
        let (we, raster) = self.we(q, -wi, time)?;
        Some(ImportanceSample {
            p: q,
            n,
            wi,
            we,
            pdf,
            raster,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraSample;
    use std::path::Path;

    fn camera(text: &str, res: (u32, u32)) -> Camera {
        let d = acr_parser::parse_str(text, Path::new("c.pbrt")).unwrap();
        Camera::new(d.camera.as_ref().unwrap(), res, glam::DMat4::IDENTITY).unwrap()
    }

    /// A point seen through a raster position is connected back to that raster position, with
    /// the densities `Pdf_We` gives the camera ray, for a pinhole and a thin lens.
    #[test]
    fn importance_finds_the_raster_position_a_camera_ray_came_from() {
        for text in [
            "LookAt 1 2 5 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" 50",
            "LookAt 1 2 5 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" 50 \
             \"float lensradius\" 0.2 \"float focaldistance\" 4",
        ] {
            let c = camera(text, (80, 60));
            for (film, lens) in [((40.5, 30.5), (0.3, 0.7)), ((3.2, 57.9), (0.9, 0.1))] {
                let s = CameraSample {
                    film: Vec2::new(film.0, film.1),
                    lens: Vec2::new(lens.0, lens.1),
                    time: 0.0,
                };
                let ray = c.generate_ray(&s);
                let p = ray.o + ray.d * 4.0;
                let (we, raster) = c.we(ray.o, ray.d, 0.0).unwrap();
                assert!((raster - s.film).length() < 1e-2, "{raster} vs {}", s.film);
                assert!(we.x > 0.0);
                let (pos, dir) = c.pdf_we(ray.o, ray.d, 0.0);
                assert!(pos > 0.0 && dir > 0.0);
                // From the focal point, every lens point lands on the same raster position.
                let i = c.sample_wi(p, 0.0, Vec2::new(0.5, 0.5)).unwrap();
                if c.lens_radius == 0.0 {
                    assert!((i.raster - s.film).length() < 1e-2, "{}", i.raster);
                }
                assert!(i.pdf > 0.0 && i.we.x > 0.0);
            }
        }
    }

    /// pbrt-v3's normalisation: the importance of a pinhole, times the cosine, integrates to 1
    /// over the directions through the film.
    #[test]
    fn pinhole_importance_integrates_to_one_over_the_film() {
        let c = camera("Camera \"perspective\" \"float fov\" 60", (40, 30));
        let n = 400;
        let mut sum = 0.0f64;
        for j in 0..n {
            for i in 0..n {
                let film = Vec2::new(
                    (i as f32 + 0.5) / n as f32 * 40.0,
                    (j as f32 + 0.5) / n as f32 * 30.0,
                );
                let ray = c.generate_ray(&CameraSample {
                    film,
                    ..Default::default()
                });
                let (we, _) = c.we(ray.o, ray.d, 0.0).unwrap();
                let (_, pdf_dir) = c.pdf_we(ray.o, ray.d, 0.0);
                // Uniform over the film: each direction's weight is 1 / (pdf n^2).
                let cos = ray.d.z.abs();
                sum += f64::from(we.x * cos / pdf_dir) / (n * n) as f64;
            }
        }
        assert!((sum - 1.0).abs() < 1e-3, "{sum}");
    }
}
