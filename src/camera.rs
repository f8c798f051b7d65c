//! pbrt-v3's cameras: `perspective` (field of view on the shorter image axis, screen window,
//! thin lens), `orthographic` (screen window, thin lens) and `environment` (the whole sphere
//! in latitude-longitude) and `realistic` (a lens system read from a file, in
//! `src/camera/realistic.rs`), with a shutter interval and a camera transform that may move.

use crate::geometry::{Ray, RayDifferentials, Vec2, Vec3};
use crate::sampling::concentric_sample_disk;
use crate::transform::MotionTransform;
use acr_parser::{CameraDesc, Error, Result};
use glam::{Mat4, Vec4};
use std::path::Path;
use std::sync::Arc;

pub mod realistic;
use realistic::{LensError, LensSystem};

/// What a camera needs besides its own directive: the film's `diagonal` (millimetres, the
/// realistic camera's film size) and the directory the lens file's name is relative to.
#[derive(Clone, Copy, Debug)]
pub struct CameraContext<'a> {
    /// The film's diagonal in millimetres (pbrt-v3's `Film` "diagonal", default 35).
    pub film_diagonal_mm: f32,
    /// Where the lens file's name is looked up when it is relative (the main scene file's
    /// directory, as pbrt-v3).
    pub dir: &'a Path,
}

mod importance;
pub use importance::ImportanceSample;

/// Where on the film, lens and shutter a camera ray starts.
#[derive(Clone, Copy, Debug, Default)]
pub struct CameraSample {
    /// Raster position in pixels (full-resolution coordinates, y down).
    pub film: Vec2,
    /// Lens position in [0,1)^2 (ignored for a pinhole).
    pub lens: Vec2,
    /// Shutter position in [0,1) (ignored when nothing moves).
    pub time: f32,
}

/// How a camera turns film positions into rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// Rays from the origin through the film (pbrt-v3's `perspective`).
    Perspective,
    /// Parallel rays along +z from the film (pbrt-v3's `orthographic`).
    Orthographic,
    /// Every direction: x is the longitude, y the latitude (pbrt-v3's `environment`).
    Environment,
    /// Through a lens system (pbrt-v3's `realistic`): rays carry a weight.
    Realistic,
}

/// A camera.
#[derive(Clone, Debug)]
pub struct Camera {
    /// The projection.
    pub projection: Projection,
    /// The film's full resolution (the environment camera's angles are fractions of it).
    resolution: (f32, f32),
    raster_to_camera: Mat4,
    /// Its inverse, for importance (bdpt's and mlt's t = 1 strategies).
    camera_to_raster: Mat4,
    world_from_camera: MotionTransform,
    /// The inverse of `world_from_camera` when the camera does not move (computed once:
    /// light tracing maps every connection to the film through it).
    camera_from_world: Option<Mat4>,
    /// The unit viewing direction in world space when the camera does not move (importance's
    /// cosine, asked for at every connection).
    forward: Option<Vec3>,
    /// The full film's area on the plane at distance 1 (pbrt-v3's `A`), for importance:
    /// computed once, where every connection to the camera asked for it.
    film_area: f32,
    /// Thin-lens radius; 0 for a pinhole.
    pub lens_radius: f32,
    /// Distance to the plane in focus.
    pub focal_distance: f32,
    /// Shutter open time.
    pub shutter_open: f32,
    /// Shutter close time.
    pub shutter_close: f32,
    /// The realistic camera's lens system.
    lens: Option<Arc<LensSystem>>,
}

impl Camera {
    /// Builds the camera from its description and the film's full resolution, placed in
    /// render space by `render_from_world`.
    pub fn new(
        desc: &CameraDesc,
        resolution: (u32, u32),
        render_from_world: glam::DMat4,
    ) -> Result<Self> {
        let context = CameraContext {
            film_diagonal_mm: 35.0,
            dir: desc.plugin.loc.file.dir(),
        };
        Self::with_context(
            desc,
            resolution,
            render_from_world,
            &context,
            &mut Vec::new(),
        )
    }

    /// [`Camera::new`] with what the realistic camera needs from the film and the scene's
    /// place; its warnings (an aperture clamped to the stop's) go to `warnings`.
    pub fn with_context(
        desc: &CameraDesc,
        resolution: (u32, u32),
        render_from_world: glam::DMat4,
        context: &CameraContext,
        warnings: &mut Vec<acr_parser::Warning>,
    ) -> Result<Self> {
        let p = &desc.plugin;
        let projection = match p.kind.as_str() {
            "perspective" => Projection::Perspective,
            "orthographic" => Projection::Orthographic,
            "environment" => Projection::Environment,
            "realistic" => Projection::Realistic,
            other => {
                return Err(Error::at(
                    &p.loc,
                    format!(
                        "camera \"{other}\" is not supported (perspective, orthographic, \
                         environment, realistic)"
                    ),
                ))
            }
        };
        let params = &p.params;
        let (xres, yres) = (resolution.0 as f32, resolution.1 as f32);
        let frame = params.float_or("frameaspectratio", (xres / yres) as f64)? as f32;
        let mut screen = if frame > 1.0 {
            [-frame, frame, -1.0, 1.0]
        } else {
            [-1.0, 1.0, -1.0 / frame, 1.0 / frame]
        };
        if let Some(sw) = params.floats("screenwindow")? {
            if sw.len() == 4 {
                screen = [sw[0] as f32, sw[1] as f32, sw[2] as f32, sw[3] as f32];
            } else if let Some(param) = params.get("screenwindow") {
                return Err(Error::at(&param.loc, "\"screenwindow\" needs four values"));
            }
        }
        let mut fov = params.float_or("fov", 90.0)? as f32;
        let half = params.float_or("halffov", -1.0)? as f32;
        if half > 0.0 {
            fov = 2.0 * half;
        }
        if !(fov > 0.0 && fov < 180.0) {
            let loc = params.get("fov").map_or(&p.loc, |x| &x.loc).clone();
            return Err(Error::at(
                &loc,
                format!("fov {fov} is not between 0 and 180 degrees"),
            ));
        }
        // The environment and realistic cameras have no thin lens (pbrt-v3 reads no lens
        // parameters for them).
        let lens_radius = if matches!(projection, Projection::Environment | Projection::Realistic) {
            0.0
        } else {
            params.float_or("lensradius", 0.0)? as f32
        };
        let focal_distance = params.float_or("focaldistance", 1e6)? as f32;
        let shutter_open = params.float_or("shutteropen", 0.0)? as f32;
        let shutter_close = params.float_or("shutterclose", 1.0)? as f32;
        if shutter_close < shutter_open {
            return Err(Error::at(
                &p.loc,
                format!("shutterclose {shutter_close} is before shutteropen {shutter_open}"),
            ));
        }
        check_degenerate(desc, projection, screen, frame, lens_radius, focal_distance)?;

        // pbrt-v3: camera -> screen (Perspective, or Orthographic(0, 1): the identity here),
        // screen -> raster.
        let camera_to_screen = match projection {
            Projection::Perspective => perspective(fov, 1e-2, 1000.0),
            _ => Mat4::IDENTITY,
        };
        let screen_to_raster = Mat4::from_scale(Vec3::new(xres, yres, 1.0))
            * Mat4::from_scale(Vec3::new(
                1.0 / (screen[1] - screen[0]),
                1.0 / (screen[2] - screen[3]),
                1.0,
            ))
            * Mat4::from_translation(Vec3::new(-screen[0], -screen[3], 0.0));
        let raster_to_camera = camera_to_screen.inverse() * screen_to_raster.inverse();
        let inverse_motion = acr_parser::AnimatedTransform {
            start: render_from_world * desc.camera_from_world.start.inverse(),
            end: render_from_world * desc.camera_from_world.end.inverse(),
            ..desc.camera_from_world
        };
        let lens = match projection {
            Projection::Realistic => Some(Arc::new(lens_system(desc, context, warnings)?)),
            _ => None,
        };
        let world_from_camera = MotionTransform::new(&inverse_motion);
        let camera_from_world =
            (!world_from_camera.is_moving()).then(|| world_from_camera.at(0.0).inverse());
        let forward = (!world_from_camera.is_moving()).then(|| {
            world_from_camera
                .at(0.0)
                .transform_vector3(Vec3::Z)
                .normalize()
        });
        Ok(Self {
            projection,
            resolution: (xres, yres),
            raster_to_camera,
            camera_to_raster: raster_to_camera.inverse(),
            world_from_camera,
            camera_from_world,
            forward,
            film_area: importance::film_area(&raster_to_camera, (xres, yres)),
            lens_radius,
            focal_distance,
            shutter_open,
            shutter_close,
            lens,
        })
    }

    /// True when camera rays need a lens sample (a thin lens, or a lens system).
    pub fn uses_lens(&self) -> bool {
        self.lens_radius > 0.0 || self.lens.is_some()
    }

    /// The ray for a camera sample, its differentials when `differentials` (scaled to one
    /// pixel), and its weight: 1 for every camera but `realistic`, whose rays pbrt-v3
    /// weights (cos^4 and the exit pupil's area) and which returns `None` for a sample the
    /// lens vignettes (pbrt-v3's zero weight: the sample counts, black). Inlined, with the
    /// rays it makes, into the caller: returned through memory, the rays were stored in
    /// pieces and reloaded whole at once, which stalls.
    #[inline(always)]
    pub fn weighted_ray(
        &self,
        s: &CameraSample,
        differentials: bool,
    ) -> Option<(Ray, Option<RayDifferentials>, f32)> {
        let Some(lens) = &self.lens else {
            return Some(if differentials {
                let (ray, diff) = self.projected_ray_differential(s);
                (ray, Some(diff), 1.0)
            } else {
                (self.generate_ray(s), None, 1.0)
            });
        };
        self.realistic_weighted_ray(lens, s, differentials)
    }

    /// [`Camera::weighted_ray`] for the realistic camera (kept out of line).
    #[inline(never)]
    fn realistic_weighted_ray(
        &self,
        lens: &LensSystem,
        s: &CameraSample,
        differentials: bool,
    ) -> Option<(Ray, Option<RayDifferentials>, f32)> {
        let (ray, weight) = self.realistic_ray(lens, s)?;
        if !differentials {
            return Some((ray, None, weight));
        }
        // pbrt-v3's Camera::GenerateRayDifferential: the rays of film points shifted by a
        // twentieth of a pixel (back, when forward is vignetted), the same lens sample; no
        // differentials, no ray.
        let shifted = |step: Vec2| {
            [0.05f32, -0.05].into_iter().find_map(|eps| {
                let moved = CameraSample {
                    film: s.film + step * eps,
                    ..*s
                };
                let (r, _) = self.realistic_ray(lens, &moved)?;
                Some((ray.o + (r.o - ray.o) / eps, ray.d + (r.d - ray.d) / eps))
            })
        };
        let (rx_o, rx_d) = shifted(Vec2::X)?;
        let (ry_o, ry_d) = shifted(Vec2::Y)?;
        let diff = RayDifferentials {
            rx_o,
            rx_d,
            ry_o,
            ry_d,
        };
        Some((ray, Some(diff), weight))
    }

    /// A realistic camera's world-space ray and weight (pbrt-v3's
    /// `RealisticCamera::GenerateRay`).
    fn realistic_ray(&self, lens: &LensSystem, s: &CameraSample) -> Option<(Ray, f32)> {
        let time = self.time(s);
        let shutter = self.shutter_close - self.shutter_open;
        let (r, weight) = lens.camera_ray(s.film, self.resolution, s.lens, shutter)?;
        let m = self.world_from_camera.at(time);
        let d = m.transform_vector3(r.d).normalize();
        Some((Ray::new(m.transform_point3(r.o), d, time), weight))
    }

    /// True when the camera itself moves during the shutter.
    pub fn is_moving(&self) -> bool {
        self.world_from_camera.is_moving()
    }

    /// The camera-to-world transform's motion.
    pub fn motion(&self) -> &MotionTransform {
        &self.world_from_camera
    }

    /// The world-space ray for a camera sample (direction normalised). The realistic
    /// camera's weight is dropped, and a vignetted sample gives the ray along the lens's axis:
    /// [`Camera::weighted_ray`] is the whole answer for it.
    pub fn generate_ray(&self, s: &CameraSample) -> Ray {
        if let Some(lens) = &self.lens {
            return self
                .realistic_ray(lens, s)
                .map_or_else(|| self.axis_ray(self.time(s)), |(ray, _)| ray);
        }
        let time = self.time(s);
        let m = self.world_from_camera.at(time);
        let (o, d) = self.camera_space_ray(s.film, self.lens_point(s.lens));
        Ray::new(
            m.transform_point3(o),
            m.transform_vector3(d).normalize(),
            time,
        )
    }

    /// The ray for a camera sample and its differentials: the rays through the film point one
    /// pixel right and one pixel down, with the same lens point and time (pbrt-v3's
    /// perspective and orthographic cameras compute the same rays in closed form; its
    /// environment camera shifts the film point as here).
    pub fn generate_ray_differential(&self, s: &CameraSample) -> (Ray, RayDifferentials) {
        if self.lens.is_some() {
            if let Some((ray, Some(diff), _)) = self.weighted_ray(s, true) {
                return (ray, diff);
            }
            let ray = self.generate_ray(s);
            let diff = RayDifferentials {
                rx_o: ray.o,
                rx_d: ray.d,
                ry_o: ray.o,
                ry_d: ray.d,
            };
            return (ray, diff);
        }
        self.projected_ray_differential(s)
    }

    /// [`Camera::generate_ray_differential`] for every camera but the realistic one.
    #[inline(always)]
    fn projected_ray_differential(&self, s: &CameraSample) -> (Ray, RayDifferentials) {
        let time = self.time(s);
        let m = self.world_from_camera.at(time);
        let world =
            |(o, d): (Vec3, Vec3)| (m.transform_point3(o), m.transform_vector3(d).normalize());
        // The three rays share the lens point: sampled once.
        let lens = self.lens_point(s.lens);
        let (o, d) = world(self.camera_space_ray(s.film, lens));
        let (rx_o, rx_d) = world(self.camera_space_ray(s.film + Vec2::X, lens));
        let (ry_o, ry_d) = world(self.camera_space_ray(s.film + Vec2::Y, lens));
        (
            Ray::new(o, d, time),
            RayDifferentials {
                rx_o,
                rx_d,
                ry_o,
                ry_d,
            },
        )
    }

    /// The ray from the camera's origin along its axis at `time` (a realistic camera's
    /// stand-in for a vignetted ray where no weight is asked for).
    fn axis_ray(&self, time: f32) -> Ray {
        let m = self.world_from_camera.at(time);
        Ray::new(
            m.transform_point3(Vec3::ZERO),
            m.transform_vector3(Vec3::Z).normalize(),
            time,
        )
    }

    /// The time of `s`'s ray: [`Camera::generate_ray`]'s, without the ray.
    pub fn sample_time(&self, s: &CameraSample) -> f32 {
        self.time(s)
    }

    /// The sample's time within the shutter.
    fn time(&self, s: &CameraSample) -> f32 {
        self.shutter_open + s.time * (self.shutter_close - self.shutter_open)
    }

    /// The point on the thin lens (camera space, z = 0) for lens sample `lens`; `None` for a
    /// pinhole.
    #[inline]
    fn lens_point(&self, lens: Vec2) -> Option<Vec2> {
        (self.lens_radius > 0.0).then(|| self.lens_radius * concentric_sample_disk(lens))
    }

    /// The camera-space ray through raster point `film` and the lens point `lens` (from
    /// [`Camera::lens_point`]; direction normalised).
    fn camera_space_ray(&self, film: Vec2, lens: Option<Vec2>) -> (Vec3, Vec3) {
        let p = self.raster_to_camera * Vec4::new(film.x, film.y, 0.0, 1.0);
        let p_camera = p.truncate() / p.w;
        let (mut o, mut d) = match self.projection {
            Projection::Perspective => (Vec3::ZERO, p_camera.normalize()),
            Projection::Orthographic => (p_camera, Vec3::Z),
            // Traced through the lens system by `realistic_ray` instead.
            Projection::Realistic => (Vec3::ZERO, Vec3::Z),
            Projection::Environment => {
                let theta = std::f32::consts::PI * film.y / self.resolution.1;
                let phi = 2.0 * std::f32::consts::PI * film.x / self.resolution.0;
                let d = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                (Vec3::ZERO, d)
            }
        };
        if let Some(lens) = lens {
            let ft = self.focal_distance / d.z;
            let focus = o + d * ft;
            // pbrt-v3's orthographic camera, too, puts the lens point at (lens.x, lens.y, 0),
            // not beside the film point: kept, so that images match.
            o = Vec3::new(lens.x, lens.y, 0.0);
            d = (focus - o).normalize();
        }
        (o, d)
    }
}

/// The realistic camera's lens system: `lensfile` read relative to the scene's directory,
/// `aperturediameter` (mm), `focusdistance` (m), `simpleweighting`, for the film's diagonal.
/// A missing or malformed file is an error at the directive (with the file's line), a
/// nonsensical number at its parameter.
fn lens_system(
    desc: &CameraDesc,
    context: &CameraContext,
    warnings: &mut Vec<acr_parser::Warning>,
) -> Result<LensSystem> {
    let p = &desc.plugin;
    let params = &p.params;
    let at = |name: &str| params.get(name).map_or(&p.loc, |x| &x.loc).clone();
    let Some(name) = params.string("lensfile")?.filter(|n| !n.is_empty()) else {
        return Err(Error::at(
            &p.loc,
            "camera \"realistic\" needs a \"string lensfile\" (a lens description file)",
        ));
    };
    let path = context.dir.join(name);
    let rows = realistic::read_lens_file(&path).map_err(|e| Error::at(&at("lensfile"), e))?;
    let aperture = params.float_or("aperturediameter", 1.0)? as f32;
    if !(aperture.is_finite() && aperture > 0.0) {
        return Err(Error::at(
            &at("aperturediameter"),
            format!("aperturediameter {aperture} is not a positive diameter (mm)"),
        ));
    }
    let focus = params.float_or("focusdistance", 10.0)? as f32;
    if !(focus.is_finite() && focus > 0.0) {
        return Err(Error::at(
            &at("focusdistance"),
            format!("focusdistance {focus} is not a positive distance (m)"),
        ));
    }
    let diagonal = context.film_diagonal_mm;
    if !(diagonal.is_finite() && diagonal > 0.0) {
        return Err(Error::at(
            &p.loc,
            format!("the film's diagonal {diagonal} mm is not a positive length"),
        ));
    }
    let simple = params.bool_or("simpleweighting", true)?;
    let mut clamped = None;
    let lens = LensSystem::new(
        &rows,
        aperture,
        focus,
        diagonal * 0.001,
        simple,
        1024 * 1024,
        &mut clamped,
    )
    .map_err(|e| match e {
        LensError::NoParaxialRay => Error::at(
            &at("aperturediameter"),
            format!(
                "no ray passes through the lens system of \"{}\" (is the aperture stop too \
                 small?)",
                path.display()
            ),
        ),
        LensError::TooClose(d) => Error::at(
            &at("focusdistance"),
            format!(
                "focusdistance {d} m is too close for the lens of \"{}\" to focus",
                path.display()
            ),
        ),
    })?;
    if let Some(max) = clamped {
        warnings.push(acr_parser::Warning::at(
            &at("aperturediameter"),
            format!(
                "aperturediameter {aperture} mm is greater than the stop's {max} mm; clamped \
                 to it (as pbrt-v3)"
            ),
        ));
    }
    if simple {
        // pbrt-v3 warns on every realistic camera with simple weighting (its default).
        warnings.push(acr_parser::Warning::at(
            &p.loc,
            "\"simpleweighting\" weights rays relative to the film's centre: images need not \
             match other cameras' and vary a bit with the aperture (as pbrt-v3 warns)",
        ));
    }
    Ok(lens)
}

/// Refuses what pbrt-v3 would take and render nothing sensible from: an empty, inverted or
/// non-finite screen window (an all-black image), a frame aspect ratio that is not positive
/// (the window it makes is empty), a negative or non-finite lens radius, a focal distance
/// that is not positive with a lens, a shutter time that is not a number. Each at its
/// parameter.
fn check_degenerate(
    desc: &CameraDesc,
    projection: Projection,
    screen: [f32; 4],
    frame: f32,
    lens_radius: f32,
    focal_distance: f32,
) -> Result<()> {
    let p = &desc.plugin;
    let params = &p.params;
    let refuse = |name: &str, why: String| {
        let loc = params.get(name).map_or(&p.loc, |x| &x.loc);
        Err(Error::at(loc, why))
    };
    // The environment camera covers the sphere whatever its window (as pbrt-v3's); the
    // realistic camera's film is its diagonal, not a window.
    if !matches!(projection, Projection::Environment | Projection::Realistic) {
        if params.get("screenwindow").is_none() && !(frame.is_finite() && frame > 0.0) {
            return refuse(
                "frameaspectratio",
                format!("frameaspectratio {frame} is not a positive number"),
            );
        }
        let [x0, x1, y0, y1] = screen;
        if !(screen.iter().all(|v| v.is_finite()) && x0 < x1 && y0 < y1) {
            return refuse(
                "screenwindow",
                format!(
                    "screenwindow [{x0} {x1} {y0} {y1}] is empty or inverted: it needs \
                     xmin < xmax and ymin < ymax (the image would be black)"
                ),
            );
        }
    }
    if !(lens_radius.is_finite() && lens_radius >= 0.0) {
        return refuse(
            "lensradius",
            format!("lensradius {lens_radius} is not a number >= 0"),
        );
    }
    if lens_radius > 0.0 && !(focal_distance.is_finite() && focal_distance > 0.0) {
        return refuse(
            "focaldistance",
            format!("focaldistance {focal_distance} is not a positive distance"),
        );
    }
    for name in ["shutteropen", "shutterclose"] {
        let t = params.float_or(name, 0.0)?;
        if !t.is_finite() {
            return refuse(name, format!("{name} {t} is not a finite time"));
        }
    }
    Ok(())
}

/// pbrt's Perspective(fov, near, far): projective divide by z, then scale so that the field of
/// view spans [-1, 1].
fn perspective(fov_degrees: f32, n: f32, f: f32) -> Mat4 {
    let persp = Mat4::from_cols(
        Vec4::new(1.0, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 1.0, 0.0, 0.0),
        Vec4::new(0.0, 0.0, f / (f - n), 1.0),
        Vec4::new(0.0, 0.0, -f * n / (f - n), 0.0),
    );
    let inv_tan = 1.0 / (fov_degrees.to_radians() / 2.0).tan();
    Mat4::from_scale(Vec3::new(inv_tan, inv_tan, 1.0)) * persp
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn camera(text: &str, res: (u32, u32)) -> Camera {
        let d = acr_parser::parse_str(text, Path::new("c.pbrt")).unwrap();
        Camera::new(d.camera.as_ref().unwrap(), res, glam::DMat4::IDENTITY).unwrap()
    }

    #[test]
    fn centre_pixel_looks_down_the_view_direction() {
        let c = camera(
            "LookAt 0 0 5 0 0 0 0 1 0 Camera \"perspective\" \"float fov\" 90",
            (100, 50),
        );
        let r = c.generate_ray(&CameraSample {
            film: Vec2::new(50.0, 25.0),
            ..Default::default()
        });
        assert!((r.o - Vec3::new(0.0, 0.0, 5.0)).length() < 1e-5);
        assert!((r.d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5, "{}", r.d);
        // fov spans the shorter (vertical) axis: the top edge is 45 degrees up.
        let top = c.generate_ray(&CameraSample {
            film: Vec2::new(50.0, 0.0),
            ..Default::default()
        });
        assert!((top.d.y - top.d.z.abs()).abs() < 1e-5, "{}", top.d);
        // Raster x grows to the camera's right: pbrt's camera space is left-handed, so looking
        // down -z from +z with y up, raster right is world -x.
        let right = c.generate_ray(&CameraSample {
            film: Vec2::new(100.0, 25.0),
            ..Default::default()
        });
        assert!(right.d.x < -0.5, "{}", right.d);
    }

    #[test]
    fn thin_lens_rays_meet_on_the_focal_plane() {
        let c = camera(
            "Camera \"perspective\" \"float fov\" 40 \"float lensradius\" 0.5 \
             \"float focaldistance\" 3",
            (64, 64),
        );
        let mut points = Vec::new();
        for lens in [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.9, 0.5),
            Vec2::new(0.4, 0.95),
        ] {
            let r = c.generate_ray(&CameraSample {
                film: Vec2::new(20.0, 40.0),
                lens,
                time: 0.0,
            });
            points.push(r.at((3.0 - r.o.z) / r.d.z));
        }
        assert!((points[0] - points[1]).length() < 1e-4);
        assert!((points[0] - points[2]).length() < 1e-4);
    }

    #[test]
    fn orthographic_rays_are_parallel_and_span_the_screen_window() {
        let c = camera(
            "LookAt 0 0 5 0 0 0 0 1 0 Camera \"orthographic\" \"float screenwindow\" [-2 2 -1 1]",
            (100, 50),
        );
        let at = |x: f32, y: f32| {
            c.generate_ray(&CameraSample {
                film: Vec2::new(x, y),
                ..Default::default()
            })
        };
        for r in [at(0.0, 0.0), at(50.0, 25.0), at(100.0, 50.0)] {
            assert!((r.d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6, "{}", r.d);
        }
        // The film's corners are the screen window's: raster (0, 0) is camera (-2, 1), which
        // pbrt's left-handed camera space puts at world (2, 1, 5).
        assert!((at(0.0, 0.0).o - Vec3::new(2.0, 1.0, 5.0)).length() < 1e-5);
        assert!((at(100.0, 50.0).o - Vec3::new(-2.0, -1.0, 5.0)).length() < 1e-5);
    }

    #[test]
    fn the_environment_camera_sees_every_direction() {
        let c = camera("Camera \"environment\"", (200, 100));
        let at = |x: f32, y: f32| {
            c.generate_ray(&CameraSample {
                film: Vec2::new(x, y),
                ..Default::default()
            })
            .d
        };
        // pbrt-v3's (sin t cos p, cos t, sin t sin p), t = pi y / height, p = 2 pi x / width.
        assert!((at(0.0, 0.0) - Vec3::Y).length() < 1e-6);
        assert!((at(0.0, 50.0) - Vec3::X).length() < 1e-6);
        assert!((at(50.0, 50.0) - Vec3::Z).length() < 1e-5);
        assert!((at(100.0, 50.0) + Vec3::X).length() < 1e-5);
        assert!((at(10.0, 100.0) + Vec3::Y).length() < 1e-5);
        for (x, y) in [(13.0, 7.0), (150.0, 80.0)] {
            assert!((at(x, y).length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn degenerate_camera_parameters_are_located_errors() {
        let cases = [
            (
                "Camera \"orthographic\" \"float screenwindow\" [0 0 0 0]",
                "screenwindow [0 0 0 0] is empty",
            ),
            (
                "Camera \"perspective\" \"float screenwindow\" [1 -1 -1 1]",
                "is empty or inverted",
            ),
            (
                "Camera \"perspective\" \"float screenwindow\" [-1 1 1 1]",
                "is empty or inverted",
            ),
            (
                "Camera \"orthographic\" \"float frameaspectratio\" 0",
                "frameaspectratio 0 is not a positive number",
            ),
            (
                "Camera \"perspective\" \"float frameaspectratio\" -2",
                "frameaspectratio -2 is not a positive number",
            ),
            (
                "Camera \"perspective\" \"float fov\" 0",
                "not between 0 and 180",
            ),
            (
                "Camera \"perspective\" \"float fov\" 180",
                "not between 0 and 180",
            ),
            (
                "Camera \"perspective\" \"float lensradius\" -1",
                "lensradius -1 is not a number >= 0",
            ),
            (
                "Camera \"orthographic\" \"float lensradius\" 0.1 \"float focaldistance\" 0",
                "focaldistance 0 is not a positive distance",
            ),
        ];
        for (text, says) in cases {
            let d = acr_parser::parse_str(text, Path::new("c.pbrt")).unwrap();
            let e = Camera::new(d.camera.as_ref().unwrap(), (8, 8), glam::DMat4::IDENTITY)
                .err()
                .unwrap_or_else(|| panic!("{text}: accepted"));
            assert!(e.to_string().contains(says), "{text}: {e}");
            // At the parameter, not at the directive.
            assert!(e.to_string().contains("c.pbrt:1:"), "{text}: {e}");
            assert!(!e.to_string().contains("c.pbrt:1:1:"), "{text}: {e}");
        }
        // What the environment camera does not use is not checked.
        camera(
            "Camera \"environment\" \"float screenwindow\" [0 0 0 0]",
            (8, 8),
        );
    }

    #[test]
    fn unknown_cameras_are_located_errors() {
        let d = acr_parser::parse_str("Camera \"fisheye\"", Path::new("c.pbrt")).unwrap();
        let e = Camera::new(d.camera.as_ref().unwrap(), (8, 8), glam::DMat4::IDENTITY).unwrap_err();
        assert!(e.to_string().contains("not supported"), "{e}");
        assert!(e.to_string().contains("c.pbrt:1:1"), "{e}");
    }

    /// A directory holding the double-Gauss lens file and a malformed one, new for each call
    /// (tests run at once must not remove each other's).
    fn lens_dir(tag: &str) -> std::path::PathBuf {
        static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("acr-lens-{}-{tag}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("dgauss.dat"),
            include_str!("../scenes/pbrt-v3/lenses/dgauss.50mm.dat"),
        )
        .unwrap();
        std::fs::write(dir.join("bad.dat"), "# a lens\n30 4 1.6 20\n0 nan 0 10\n").unwrap();
        dir
    }

    fn realistic(params: &str, tag: &str) -> Result<Camera> {
        let dir = lens_dir(tag);
        let text = format!("Camera \"realistic\" {params}");
        let d = acr_parser::parse_str(&text, &dir.join("c.pbrt")).unwrap();
        let camera = Camera::new(d.camera.as_ref().unwrap(), (32, 32), glam::DMat4::IDENTITY);
        let _ = std::fs::remove_dir_all(&dir);
        camera
    }

    #[test]
    fn bad_realistic_cameras_are_located_errors() {
        let cases = [
            ("", "needs a \"string lensfile\"", "c.pbrt:1:1:"),
            (
                "\"string lensfile\" \"nope.dat\"",
                "cannot read lens file",
                "c.pbrt:1:20:",
            ),
            (
                "\"string lensfile\" \"bad.dat\"",
                "line 3: NaN is not a finite",
                "c.pbrt:1:20:",
            ),
            (
                "\"string lensfile\" \"dgauss.dat\" \"float aperturediameter\" 0",
                "aperturediameter 0 is not a positive diameter",
                "c.pbrt:1:",
            ),
            (
                "\"string lensfile\" \"dgauss.dat\" \"float aperturediameter\" -2",
                "aperturediameter -2 is not a positive diameter",
                "c.pbrt:1:",
            ),
            (
                "\"string lensfile\" \"dgauss.dat\" \"float focusdistance\" 0.01",
                "too close for the lens",
                "c.pbrt:1:",
            ),
        ];
        for (params, says, at) in cases {
            let e = realistic(params, "bad")
                .err()
                .unwrap_or_else(|| panic!("{params}: accepted"));
            let e = e.to_string();
            assert!(e.contains(says), "{params}: {e}");
            assert!(e.contains(at), "{params}: {e}");
        }
    }

    #[test]
    fn the_realistic_camera_weighs_its_rays_and_moves() {
        let c = realistic(
            "\"string lensfile\" \"dgauss.dat\" \"float aperturediameter\" 8 \
             \"float focusdistance\" 3",
            "good",
        )
        .unwrap();
        assert!(c.uses_lens());
        let s = CameraSample {
            film: Vec2::new(16.0, 16.0),
            lens: Vec2::splat(0.5),
            time: 0.0,
        };
        let (ray, diff, w) = c.weighted_ray(&s, true).unwrap();
        assert!((w - 1.0).abs() < 1e-4, "{w}");
        // pbrt-v3's camera looks down +z; the lens inverts the image.
        assert!(ray.d.z > 0.99, "{}", ray.d);
        let diff = diff.unwrap();
        // The lens inverts the image onto the film: the raster's axes point the perspective
        // camera's ways (right is camera +x, down is camera -y).
        assert!(diff.rx_d.x > ray.d.x, "{diff:?}");
        assert!(diff.ry_d.y < ray.d.y, "{diff:?}");
        // Without differentials, the same ray.
        let (same, none, w2) = c.weighted_ray(&s, false).unwrap();
        assert!(none.is_none() && w2 == w && same.d == ray.d);
        // A moving camera carries its lens along.
        let dir = lens_dir("good");
        let text = "ActiveTransform StartTime Translate 0 0 0 ActiveTransform EndTime \
                    Translate 1 0 0 ActiveTransform All \
                    Camera \"realistic\" \"string lensfile\" \"dgauss.dat\"";
        let d = acr_parser::parse_str(text, &dir.join("c.pbrt")).unwrap();
        let c = Camera::new(d.camera.as_ref().unwrap(), (32, 32), glam::DMat4::IDENTITY).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        assert!(c.is_moving());
        let at = |time| {
            c.weighted_ray(&CameraSample { time, ..s }, false)
                .unwrap()
                .0
                .o
        };
        assert!(((at(1.0) - at(0.0)).length() - 1.0).abs() < 1e-3);
    }
}
