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

impl Camera {
    /// The area of the full film on the plane at distance 1 (pbrt-v3's `A`).
    fn film_area(&self) -> f32 {
        let at = |x: f32, y: f32| {
            let p = self.raster_to_camera * Vec4::new(x, y, 0.0, 1.0);
            let p = p.truncate() / p.w;
            p / p.z
        };
        let (a, b) = (at(0.0, 0.0), at(self.resolution.0, self.resolution.1));
        ((b.x - a.x) * (b.y - a.y)).abs()
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
        let m = self.world_from_camera.at(time);
        let cos = d.dot(m.transform_vector3(Vec3::Z).normalize());
        if cos <= 0.0 {
            return None;
        }
        let focus = o + d
            * ((if self.lens_radius > 0.0 {
                self.focal_distance
            } else {
                1.0
            }) / cos);
        let pc = m.inverse().transform_point3(focus);
        let pr = self.raster_to_camera.inverse() * pc.extend(1.0);
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

    /// pbrt-v3's `Sample_Wi`: a lens point seen from `p` at `time`, chosen with `u`; `None`
    /// when it sees nothing of the film.
    pub fn sample_wi(&self, p: Vec3, time: f32, u: Vec2) -> Option<ImportanceSample> {
        if self.projection != Projection::Perspective {
            return None;
        }
        let m = self.world_from_camera.at(time);
        let lens = self.lens_radius * concentric_sample_disk(u);
        let q = m.transform_point3(Vec3::new(lens.x, lens.y, 0.0));
        let n = m.transform_vector3(Vec3::Z).normalize();
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
