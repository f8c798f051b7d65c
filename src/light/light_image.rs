//! pbrt-v3's image-modulated point lights: `goniometric` (lights/goniometric.cpp), whose
//! intensity in each direction is read from an image over (phi, theta), and `projection`
//! (lights/projection.cpp), which casts an image through a perspective frustum. Here are their
//! images and direction-to-image mappings; [`super::Light`] holds the enum arms and their
//! constructors.
//!
//! Both read their image with pbrt-v3's `ReadImage`, which returns PNG values as stored
//! (bytes / 255, no sRGB decoding) and EXR values as linear, and look it up through a
//! `MIPMap<RGBSpectrum>` at its finest level: bilinear interpolation (`MIPMap::triangle` at
//! level 0), with the MIP map's default wrap mode, repeat, on both axes, and the image's first
//! (top) row at t = 0. acr does the same lookup in the full-resolution image, as its other
//! image lookups do; the one difference is that pbrt-v3 first resamples an image whose sides
//! are not powers of two (Lanczos) to the next powers of two, which acr does not.

use crate::geometry::{Spectrum, Vec2, Vec3};
use crate::image_io::RgbImage;
use crate::mipmap::MipMap;
use crate::texture::{ImageMap, Wrap};
use glam::Mat4;
use std::f32::consts::PI;

/// pbrt-v3's `InvPi`.
const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
/// pbrt-v3's `Inv2Pi` (exactly half of [`INV_PI`] in f32).
const INV_2PI: f32 = 0.5 * std::f32::consts::FRAC_1_PI;
/// The projection's near plane (pbrt-v3's `hither`): directions closer to the light's xy
/// plane, or behind it, get nothing.
pub(super) const HITHER: f32 = 1e-3;

/// An image a goniometric or projection light scales its intensity by.
#[derive(Clone, Debug)]
pub struct LightImage {
    /// Top row first, as read (pbrt-v3's MIP map keeps the file's order), wrapped around on
    /// both axes (pbrt-v3's `ImageWrap::Repeat`): the image as read.
    map: ImageMap<Spectrum>,
    /// Its MIP map (resampled to powers of two, as pbrt-v3's lights build one), which lookups
    /// read.
    mip: MipMap<Spectrum>,
    /// What pbrt-v3's `Power` looks up, see [`LightImage::average`].
    average: Spectrum,
}

impl LightImage {
    /// From an image as [`crate::image_io::read_image`] returns it; `None` when it has no
    /// pixels.
    pub fn new(img: &RgbImage) -> Option<Self> {
        let (width, height) = (img.width, img.height);
        if width == 0 || height == 0 || img.pixels.len() != width * height {
            return None;
        }
        let map = ImageMap::from_rows(width, height, img.pixels.clone(), Wrap::Repeat);
        let mip = MipMap::new(&map, false, 8.0);
        // pbrt-v3's Power: a trilinear lookup at the centre with width 0.5.
        let average = mip.lookup_width(Vec2::splat(0.5), 0.5);
        Some(Self { map, mip, average })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.map.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.map.height()
    }

    /// The mean pixel, as pbrt-v3's `Power` takes it: its MIP map looked up at (0.5, 0.5) with
    /// width 0.5, which lands on the 2x2 (or 2x1) level at its centre, the mean of the image
    /// (resampled to powers of two).
    pub fn average(&self) -> Spectrum {
        self.average
    }

    /// The mean over the pixels of the largest channel of `intensity` times the pixel (negative
    /// values as 0): the power bound of pbrt-v4's `Bounds` for these lights, per steradian.
    pub fn mean_max(&self, intensity: Spectrum) -> f32 {
        let texels = self.map.texels();
        let sum: f64 = texels
            .iter()
            .map(|p| f64::from((intensity * p.max(Spectrum::ZERO)).max_element()))
            .sum();
        (sum / texels.len() as f64) as f32
    }

    /// Bilinear interpolation at `st` in [0, 1]², t = 0 at the top row: pbrt-v3's
    /// `MIPMap::Lookup(st)` with no filter width, its bilinear `triangle` at level 0 (of the
    /// image resampled to powers of two).
    #[inline]
    pub fn lookup(&self, st: Vec2) -> Spectrum {
        self.mip.lookup(st, Vec2::ZERO, Vec2::ZERO)
    }
}

/// Where a goniometric light's image is read for the light-space direction `wl` (not
/// necessarily unit): pbrt-v3's `GonioPhotometricLight::Scale`, which swaps y and z, so that
/// the image's rows run from the light's +y (theta = 0, top row) to its -y, and its columns
/// around the y axis from +x (phi = 0) towards +z: (u, v) = (phi / 2pi, theta / pi).
#[inline]
pub fn goniometric_st(wl: Vec3) -> Vec2 {
    let w = wl.normalize();
    let wp = Vec3::new(w.x, w.z, w.y);
    let theta = wp.z.clamp(-1.0, 1.0).acos();
    let p = wp.y.atan2(wp.x);
    let phi = if p < 0.0 { p + 2.0 * PI } else { p };
    Vec2::new(phi * INV_2PI, theta * INV_PI)
}

/// A goniometric light's scale for the light-space direction `wl`: its image there, or 1 with
/// no image (pbrt-v3's `RGBSpectrum(1.f)` when the map could not be read).
#[inline]
pub fn goniometric_scale(map: Option<&LightImage>, wl: Vec3) -> Spectrum {
    map.map_or(Spectrum::ONE, |m| m.lookup(goniometric_st(wl)))
}

/// A projection light's frustum and image: pbrt-v3's `ProjectionLight` without its transform.
#[derive(Clone, Debug)]
pub struct ImageProjection {
    /// The image, if any (without one, 1 inside the frustum).
    map: Option<LightImage>,
    /// The screen window's least corner.
    screen_lo: Vec2,
    /// The screen window's greatest corner.
    screen_hi: Vec2,
    /// 1 / tan(fov / 2), the perspective's scale.
    inv_tan: f32,
    /// Cosine of the angle between the light's +z and the screen window's corner: the
    /// frustum's widest direction (pbrt-v3's `cosTotalWidth`).
    pub cos_total_width: f32,
}

impl ImageProjection {
    /// pbrt-v3's `ProjectionLight` constructor: the screen window spans [-1, 1] on the image's
    /// shorter side and keeps its aspect ratio on the longer (a square without an image), and
    /// the perspective has field of view `fov_degrees` across the shorter side.
    pub fn new(map: Option<LightImage>, fov_degrees: f32) -> Self {
        let aspect = map
            .as_ref()
            .map_or(1.0, |m| m.width() as f32 / m.height() as f32);
        let (screen_lo, screen_hi) = if aspect > 1.0 {
            (Vec2::new(-aspect, -1.0), Vec2::new(aspect, 1.0))
        } else {
            (Vec2::new(-1.0, -1.0 / aspect), Vec2::new(1.0, 1.0 / aspect))
        };
        // pbrt-v3's Perspective(fov, 1e-3, 1e30): Radians is (Pi / 180) * deg.
        let inv_tan = 1.0 / ((PI / 180.0) * fov_degrees / 2.0).tan();
        // pbrt-v3 un-projects the window's corner (screen z = 0 is the near plane) and takes the
        // cosine of its direction; in closed form, the corner's direction is (x, y, tan)-like.
        let corner = Vec3::new(screen_hi.x / inv_tan, screen_hi.y / inv_tan, 1.0).normalize();
        Self {
            map,
            screen_lo,
            screen_hi,
            inv_tan,
            cos_total_width: corner.z,
        }
    }

    /// The image, if any.
    pub fn map(&self) -> Option<&LightImage> {
        self.map.as_ref()
    }

    /// The screen point of the light-space direction `wl`: pbrt-v3's `lightProjection` applied
    /// to the point `wl` (x and y scaled by 1 / tan(fov / 2), then times 1 / z, in that order).
    #[inline]
    pub fn screen_point(&self, wl: Vec3) -> Vec2 {
        let inv_z = 1.0 / wl.z;
        Vec2::new(inv_z * (self.inv_tan * wl.x), inv_z * (self.inv_tan * wl.y))
    }

    /// The screen window: least and greatest corners.
    pub fn screen_window(&self) -> (Vec2, Vec2) {
        (self.screen_lo, self.screen_hi)
    }

    /// pbrt-v3's `ProjectionLight::Projection` for the light-space direction `wl` (as the light
    /// transform gives it, not normalised): nothing behind the near plane or outside the screen
    /// window (edges included), else the image at the screen point mapped to [0, 1]² (1 without
    /// an image).
    #[inline]
    pub fn eval(&self, wl: Vec3) -> Spectrum {
        if wl.z < HITHER {
            return Spectrum::ZERO;
        }
        let p = self.screen_point(wl);
        let (lo, hi) = (self.screen_lo, self.screen_hi);
        // Written so that NaN is outside.
        let inside = p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y;
        if !inside {
            return Spectrum::ZERO;
        }
        match &self.map {
            None => Spectrum::ONE,
            Some(m) => m.lookup(Vec2::new(
                (p.x - lo.x) / (hi.x - lo.x),
                (p.y - lo.y) / (hi.y - lo.y),
            )),
        }
    }

    /// A cone around which every direction the light sends goes, in world space, for the light
    /// BVH: axis, and the cosine of its half-angle. The frustum is the convex cone spanned by
    /// its four corner directions and a linear map keeps it one, so the corners' largest angle
    /// from the mapped +z bounds it whatever the transform's scale or shear (with a small
    /// margin for rounding). Every direction when that angle reaches 90 degrees.
    pub fn world_cone(&self, world_from_light: &Mat4) -> (Vec3, f32) {
        let axis = world_from_light
            .transform_vector3(Vec3::Z)
            .normalize_or_zero();
        let mut cos = 1.0f32;
        for (x, y) in [
            (self.screen_lo.x, self.screen_lo.y),
            (self.screen_lo.x, self.screen_hi.y),
            (self.screen_hi.x, self.screen_lo.y),
            (self.screen_hi.x, self.screen_hi.y),
        ] {
            let corner = Vec3::new(x / self.inv_tan, y / self.inv_tan, 1.0);
            let c = world_from_light
                .transform_vector3(corner)
                .normalize_or_zero();
            cos = cos.min(axis.dot(c));
        }
        let angle = cos.clamp(-1.0, 1.0).acos() + 1e-3;
        if axis == Vec3::ZERO || !cos.is_finite() || angle >= 0.5 * PI {
            return (Vec3::Z, -1.0);
        }
        (axis, angle.cos())
    }
}
