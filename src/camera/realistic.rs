//! pbrt-v3's `realistic` camera: rays from the film traced through a system of spherical lens
//! elements and an aperture stop read from a lens file, the film placed by a thick-lens
//! approximation to focus at `focusdistance`, lens samples drawn over the exit pupil's bounds
//! (64 of them over the film's radius) and each ray weighted by cos^4 and the pupil's area, as
//! pbrt-v3's `RealisticCamera` (docs/cameras.md).

use crate::geometry::{Vec2, Vec3};
use rayon::prelude::*;
use std::path::Path;

/// One interface of the lens system, in metres (pbrt-v3's `LensElementInterface`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensElement {
    /// Radius of curvature; 0 for the aperture stop.
    pub curvature_radius: f32,
    /// Distance along the axis to the next interface (towards the film).
    pub thickness: f32,
    /// Index of refraction behind the interface (0 or 1: air).
    pub eta: f32,
    /// Radius of the element's aperture.
    pub aperture_radius: f32,
}

/// A row of a lens file as written (millimetres, the aperture a diameter) and its line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensRow {
    /// radius, thickness, eta, aperture diameter.
    pub values: [f32; 4],
    /// 1-based line of the row's first value.
    pub line: usize,
}

/// Reads a lens file as pbrt-v3's `ReadFloatFile`: whitespace-separated numbers, `#` to the
/// end of the line a comment, grouped by four. Text that is not a number, a count that is not
/// a multiple of four, a value that is not finite, a negative thickness, index of refraction or
/// aperture, or an element without aperture are refused with the file's line.
pub fn parse_lens_file(text: &str) -> Result<Vec<LensRow>, String> {
    let mut values = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line_no = n + 1;
        let data = line.split('#').next().unwrap_or("");
        for token in data.split_whitespace() {
            let v: f32 = token
                .parse()
                .map_err(|_| format!("line {line_no}: \"{token}\" is not a number"))?;
            values.push((v, line_no));
        }
    }
    if values.is_empty() {
        return Err("it holds no lens element".to_owned());
    }
    if values.len() % 4 != 0 {
        return Err(format!(
            "{} values is not a multiple of four (radius thickness eta aperture per row)",
            values.len()
        ));
    }
    let mut rows = Vec::with_capacity(values.len() / 4);
    for chunk in values.chunks(4) {
        let row = LensRow {
            values: [chunk[0].0, chunk[1].0, chunk[2].0, chunk[3].0],
            line: chunk[0].1,
        };
        check_row(&row)?;
        rows.push(row);
    }
    Ok(rows)
}

/// Refuses a row the tracing cannot use (a NaN would reach every ray; a negative thickness
/// puts an element behind the next one; an element with no aperture lets no light through).
fn check_row(row: &LensRow) -> Result<(), String> {
    let [_, thickness, eta, aperture] = row.values;
    let line = row.line;
    if let Some(v) = row.values.iter().find(|v| !v.is_finite()) {
        return Err(format!("line {line}: {v} is not a finite number"));
    }
    if thickness < 0.0 {
        return Err(format!("line {line}: thickness {thickness} is negative"));
    }
    if eta < 0.0 {
        return Err(format!(
            "line {line}: index of refraction {eta} is negative"
        ));
    }
    if aperture <= 0.0 {
        return Err(format!(
            "line {line}: aperture diameter {aperture} is not positive"
        ));
    }
    Ok(())
}

/// Reads and parses a lens file.
pub fn read_lens_file(path: &Path) -> Result<Vec<LensRow>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read lens file \"{}\": {e}", path.display()))?;
    parse_lens_file(&text).map_err(|e| format!("lens file \"{}\": {e}", path.display()))
}

/// An axis-aligned rectangle (pbrt-v3's `Bounds2f`); empty when `min > max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds2 {
    /// Lower corner.
    pub min: Vec2,
    /// Upper corner.
    pub max: Vec2,
}

impl Bounds2 {
    const EMPTY: Bounds2 = Bounds2 {
        min: Vec2::splat(f32::MAX),
        max: Vec2::splat(f32::MIN),
    };

    fn inside(&self, p: Vec2) -> bool {
        p.x >= self.min.x && p.x <= self.max.x && p.y >= self.min.y && p.y <= self.max.y
    }

    fn union(&self, p: Vec2) -> Bounds2 {
        Bounds2 {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The area (pbrt-v3's `Area`).
    pub fn area(&self) -> f32 {
        let d = self.max - self.min;
        d.x * d.y
    }

    fn lerp(&self, t: Vec2) -> Vec2 {
        Vec2::new(
            (1.0 - t.x) * self.min.x + t.x * self.max.x,
            (1.0 - t.y) * self.min.y + t.y * self.max.y,
        )
    }
}

/// A ray inside the lens system (camera space with z flipped: the film at z = 0, the lens
/// towards -z).
#[derive(Clone, Copy, Debug)]
pub struct LensRay {
    /// Origin.
    pub o: Vec3,
    /// Direction (not necessarily normalised).
    pub d: Vec3,
}

/// Why a lens system cannot be built; the caller locates it at the parameter concerned.
#[derive(Debug)]
pub enum LensError {
    /// No ray passes parallel to the axis (an aperture too small).
    NoParaxialRay,
    /// `focusdistance` is too close for the lens to focus.
    TooClose(f32),
}

/// A lens system focused for a film: pbrt-v3's `RealisticCamera` less its transform.
#[derive(Clone, Debug)]
pub struct LensSystem {
    /// The interfaces, from the scene side to the film side; the last one's thickness is the
    /// distance to the film.
    pub elements: Vec<LensElement>,
    /// The exit pupil's bounds on the rear element's plane, for 64 rings of the film.
    pub exit_pupil_bounds: Vec<Bounds2>,
    /// The film's diagonal in metres.
    pub film_diagonal: f32,
    /// `simpleweighting`: weights relative to the pupil at the film's centre.
    pub simple_weighting: bool,
}

impl LensSystem {
    /// Builds the system from the lens file's rows (millimetres), the stop opened to
    /// `aperture_diameter` (mm; clamped to the stop's own, which `clamped` then reports),
    /// focused at `focus_distance` (metres), for a film of diagonal `film_diagonal` (metres);
    /// `pupil_samples` lens points per ring bound the exit pupil (pbrt-v3: 1024 x 1024).
    pub fn new(
        rows: &[LensRow],
        aperture_diameter: f32,
        focus_distance: f32,
        film_diagonal: f32,
        simple_weighting: bool,
        pupil_samples: u32,
        clamped: &mut Option<f32>,
    ) -> Result<Self, LensError> {
        let elements = rows
            .iter()
            .map(|r| {
                let [radius, thickness, eta, mut aperture] = r.values;
                if radius == 0.0 {
                    if aperture_diameter > aperture {
                        *clamped = Some(aperture);
                    } else {
                        aperture = aperture_diameter;
                    }
                }
                LensElement {
                    curvature_radius: radius * 0.001,
                    thickness: thickness * 0.001,
                    eta,
                    aperture_radius: aperture * 0.001 / 2.0,
                }
            })
            .collect();
        let mut lens = LensSystem {
            elements,
            exit_pupil_bounds: Vec::new(),
            film_diagonal,
            simple_weighting,
        };
        let thickness = lens.focus_thick_lens(focus_distance)?;
        if let Some(last) = lens.elements.last_mut() {
            last.thickness = thickness;
        }
        let n = 64;
        lens.exit_pupil_bounds = (0..n)
            .into_par_iter()
            .map(|i| {
                let r0 = i as f32 / n as f32 * film_diagonal / 2.0;
                let r1 = (i + 1) as f32 / n as f32 * film_diagonal / 2.0;
                lens.bound_exit_pupil(r0, r1, pupil_samples)
            })
            .collect();
        Ok(lens)
    }

    /// The rear element's z (the film is at 0).
    pub fn rear_z(&self) -> f32 {
        self.elements.last().map_or(0.0, |e| e.thickness)
    }

    /// The front element's z.
    fn front_z(&self) -> f32 {
        self.elements.iter().map(|e| e.thickness).sum()
    }

    /// The rear element's aperture radius.
    fn rear_radius(&self) -> f32 {
        self.elements.last().map_or(0.0, |e| e.aperture_radius)
    }

    /// Traces a camera-space ray from the film out through the elements (pbrt-v3's
    /// `TraceLensesFromFilm`); `None` when an element or the stop blocks it or it is totally
    /// reflected.
    pub fn trace_from_film(&self, r: LensRay) -> Option<LensRay> {
        let flip = Vec3::new(1.0, 1.0, -1.0);
        let mut ray = LensRay {
            o: r.o * flip,
            d: r.d * flip,
        };
        let mut element_z = 0.0;
        for (i, e) in self.elements.iter().enumerate().rev() {
            element_z -= e.thickness;
            let is_stop = e.curvature_radius == 0.0;
            let (t, n) = if is_stop {
                // A ray refracted back towards the film cannot reach the stop.
                if ray.d.z >= 0.0 {
                    return None;
                }
                ((element_z - ray.o.z) / ray.d.z, Vec3::ZERO)
            } else {
                intersect_spherical(e.curvature_radius, element_z + e.curvature_radius, &ray)?
            };
            // Behind the ray, or NaN.
            if t.is_nan() || t < 0.0 {
                return None;
            }
            let hit = ray.o + ray.d * t;
            if hit.x * hit.x + hit.y * hit.y > e.aperture_radius * e.aperture_radius {
                return None;
            }
            ray.o = hit;
            if !is_stop {
                let eta_i = e.eta;
                let eta_t = match i.checked_sub(1).map(|j| self.elements[j].eta) {
                    Some(eta) if eta != 0.0 => eta,
                    _ => 1.0,
                };
                ray.d = refract((-ray.d).normalize(), n, eta_i / eta_t)?;
            }
        }
        Some(LensRay {
            o: ray.o * flip,
            d: ray.d * flip,
        })
    }

    /// Traces a camera-space ray from the scene in through the elements (pbrt-v3's
    /// `TraceLensesFromScene`).
    fn trace_from_scene(&self, r: LensRay) -> Option<LensRay> {
        let flip = Vec3::new(1.0, 1.0, -1.0);
        let mut ray = LensRay {
            o: r.o * flip,
            d: r.d * flip,
        };
        let mut element_z = -self.front_z();
        for (i, e) in self.elements.iter().enumerate() {
            let is_stop = e.curvature_radius == 0.0;
            let (t, n) = if is_stop {
                ((element_z - ray.o.z) / ray.d.z, Vec3::ZERO)
            } else {
                intersect_spherical(e.curvature_radius, element_z + e.curvature_radius, &ray)?
            };
            // Behind the ray, or NaN.
            if t.is_nan() || t < 0.0 {
                return None;
            }
            let hit = ray.o + ray.d * t;
            if hit.x * hit.x + hit.y * hit.y > e.aperture_radius * e.aperture_radius {
                return None;
            }
            ray.o = hit;
            if !is_stop {
                let eta_i = match i.checked_sub(1).map(|j| self.elements[j].eta) {
                    Some(eta) if eta != 0.0 => eta,
                    _ => 1.0,
                };
                let eta_t = if e.eta != 0.0 { e.eta } else { 1.0 };
                ray.d = refract((-ray.d).normalize(), n, eta_i / eta_t)?;
            }
            element_z += e.thickness;
        }
        Some(LensRay {
            o: ray.o * flip,
            d: ray.d * flip,
        })
    }

    /// The principal plane's and focal point's z on each side of the lens (pbrt-v3's
    /// `ComputeThickLensApproximation`): [film side, scene side].
    fn thick_lens(&self) -> Result<([f32; 2], [f32; 2]), LensError> {
        let x = 0.001 * self.film_diagonal;
        let scene_in = LensRay {
            o: Vec3::new(x, 0.0, self.front_z() + 1.0),
            d: Vec3::new(0.0, 0.0, -1.0),
        };
        let film_out = self
            .trace_from_scene(scene_in)
            .ok_or(LensError::NoParaxialRay)?;
        let (p0, f0) = cardinal_points(&scene_in, &film_out);
        let film_in = LensRay {
            o: Vec3::new(x, 0.0, self.rear_z() - 1.0),
            d: Vec3::new(0.0, 0.0, 1.0),
        };
        let scene_out = self
            .trace_from_film(film_in)
            .ok_or(LensError::NoParaxialRay)?;
        let (p1, f1) = cardinal_points(&film_in, &scene_out);
        Ok(([p0, p1], [f0, f1]))
    }

    /// The rear element's distance from the film that focuses at `focus_distance` (pbrt-v3's
    /// `FocusThickLens`).
    fn focus_thick_lens(&self, focus_distance: f32) -> Result<f32, LensError> {
        let (pz, fz) = self.thick_lens()?;
        let f = fz[0] - pz[0];
        let z = -focus_distance;
        let c = (pz[1] - z - pz[0]) * (pz[1] - z - 4.0 * f - pz[0]);
        if c.is_nan() || c <= 0.0 {
            return Err(LensError::TooClose(focus_distance));
        }
        let delta = 0.5 * (pz[1] - z + pz[0] - c.sqrt());
        Ok(self.rear_z() + delta)
    }

    /// Bounds of the points on the rear element's plane through which rays from film points
    /// (x in [x0, x1], y = 0) leave the lens (pbrt-v3's `BoundExitPupil`).
    fn bound_exit_pupil(&self, x0: f32, x1: f32, samples: u32) -> Bounds2 {
        let rear = self.rear_radius();
        let proj = Bounds2 {
            min: Vec2::splat(-1.5 * rear),
            max: Vec2::splat(1.5 * rear),
        };
        let mut pupil = Bounds2::EMPTY;
        let mut exiting = 0u32;
        let rear_z = self.rear_z();
        for i in 0..samples {
            let t = (i as f32 + 0.5) / samples as f32;
            let film = Vec3::new((1.0 - t) * x0 + t * x1, 0.0, 0.0);
            let u = Vec2::new(radical_inverse_2(i), radical_inverse_3(i));
            let p = proj.lerp(u);
            let rear_point = Vec3::new(p.x, p.y, rear_z);
            if pupil.inside(p)
                || self
                    .trace_from_film(LensRay {
                        o: film,
                        d: rear_point - film,
                    })
                    .is_some()
            {
                pupil = pupil.union(p);
                exiting += 1;
            }
        }
        if exiting == 0 {
            return proj;
        }
        let delta = 2.0 * (proj.max - proj.min).length() / (samples as f32).sqrt();
        Bounds2 {
            min: pupil.min - Vec2::splat(delta),
            max: pupil.max + Vec2::splat(delta),
        }
    }

    /// A point on the rear element's plane for film point `film` and lens sample `u`, with
    /// the area of the bounds it was drawn from (pbrt-v3's `SampleExitPupil`).
    pub fn sample_exit_pupil(&self, film: Vec2, u: Vec2) -> (Vec3, f32) {
        let r_film = film.length();
        let n = self.exit_pupil_bounds.len();
        let index = ((r_film / (self.film_diagonal / 2.0) * n as f32) as usize).min(n - 1);
        let bounds = self.exit_pupil_bounds[index];
        let p = bounds.lerp(u);
        let (sin, cos) = if r_film != 0.0 {
            (film.y / r_film, film.x / r_film)
        } else {
            (0.0, 1.0)
        };
        (
            Vec3::new(cos * p.x - sin * p.y, sin * p.x + cos * p.y, self.rear_z()),
            bounds.area(),
        )
    }

    /// The camera-space ray for raster point `raster` of a film `resolution` pixels wide and
    /// high, with lens sample `u`, and its weight (pbrt-v3's `GenerateRay` before the camera
    /// transform); `None` when the lens vignettes it. `shutter` is the shutter's length.
    pub fn camera_ray(
        &self,
        raster: Vec2,
        resolution: (f32, f32),
        u: Vec2,
        shutter: f32,
    ) -> Option<(LensRay, f32)> {
        let s = Vec2::new(raster.x / resolution.0, raster.y / resolution.1);
        let aspect = resolution.1 / resolution.0;
        let d = self.film_diagonal;
        let x = (d * d / (1.0 + aspect * aspect)).sqrt();
        let y = aspect * x;
        let film2 = Vec2::new(-x / 2.0 + s.x * x, -y / 2.0 + s.y * y);
        let film = Vec3::new(-film2.x, film2.y, 0.0);
        let (rear, area) = self.sample_exit_pupil(Vec2::new(film.x, film.y), u);
        let r_film = LensRay {
            o: film,
            d: rear - film,
        };
        let out = self.trace_from_film(r_film)?;
        let cos = r_film.d.normalize().z;
        let cos4 = (cos * cos) * (cos * cos);
        let weight = if self.simple_weighting {
            cos4 * area / self.exit_pupil_bounds[0].area()
        } else {
            shutter * (cos4 * area) / (self.rear_z() * self.rear_z())
        };
        Some((out, weight))
    }
}

/// pbrt-v3's `RadicalInverse(0, i)`: the bits of `i` reversed, as a fraction.
fn radical_inverse_2(i: u32) -> f32 {
    (f64::from(i.reverse_bits()) * (1.0 / 4_294_967_296.0)) as f32
}

/// pbrt-v3's `RadicalInverse(1, i)`: the base-3 digits of `i` reversed, in f32 as pbrt-v3's.
fn radical_inverse_3(mut i: u32) -> f32 {
    let inv_base = 1.0f32 / 3.0;
    let (mut reversed, mut inv_base_n) = (0u64, 1.0f32);
    while i > 0 {
        let next = i / 3;
        reversed = reversed * 3 + u64::from(i - next * 3);
        inv_base_n *= inv_base;
        i = next;
    }
    (reversed as f32 * inv_base_n).min(1.0 - f32::EPSILON / 2.0)
}

/// pbrt-v3's `ComputeCardinalPoints`: the z of the focal point and of the principal plane
/// from a ray parallel to the axis and the ray it leaves as.
fn cardinal_points(r_in: &LensRay, r_out: &LensRay) -> (f32, f32) {
    let tf = -r_out.o.x / r_out.d.x;
    let fz = -(r_out.o.z + r_out.d.z * tf);
    let tp = (r_in.o.x - r_out.o.x) / r_out.d.x;
    let pz = -(r_out.o.z + r_out.d.z * tp);
    (pz, fz)
}

/// The ray's hit on a spherical element of `radius` centred on the axis at `z_center` and the
/// normal there facing the ray (pbrt-v3's `IntersectSphericalElement`).
fn intersect_spherical(radius: f32, z_center: f32, ray: &LensRay) -> Option<(f32, Vec3)> {
    let o = ray.o - Vec3::new(0.0, 0.0, z_center);
    let a = ray.d.length_squared();
    let b = 2.0 * ray.d.dot(o);
    let c = o.length_squared() - radius * radius;
    let (t0, t1) = quadratic(a, b, c)?;
    let closer = (ray.d.z > 0.0) ^ (radius < 0.0);
    let t = if closer { t0.min(t1) } else { t0.max(t1) };
    if t < 0.0 {
        return None;
    }
    let n = (o + ray.d * t).normalize();
    let n = if n.dot(-ray.d) < 0.0 { -n } else { n };
    Some((t, n))
}

/// pbrt-v3's `Quadratic`: the discriminant in double precision, the roots ordered.
fn quadratic(a: f32, b: f32, c: f32) -> Option<(f32, f32)> {
    let discrim = f64::from(b) * f64::from(b) - 4.0 * f64::from(a) * f64::from(c);
    if discrim.is_nan() || discrim < 0.0 {
        return None;
    }
    let root = discrim.sqrt();
    let q = if b < 0.0 {
        -0.5 * (f64::from(b) - root)
    } else {
        -0.5 * (f64::from(b) + root)
    };
    let (t0, t1) = ((q / f64::from(a)) as f32, (f64::from(c) / q) as f32);
    Some(if t0 > t1 { (t1, t0) } else { (t0, t1) })
}

/// pbrt-v3's `Refract`: `wi` (towards where the ray came from) through the surface of normal
/// `n` with relative index `eta`; `None` on total internal reflection.
fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = n.dot(wi);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = eta * eta * sin2_i;
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * -wi + (eta * cos_i - cos_t) * n)
}

#[cfg(test)]
mod tests;
