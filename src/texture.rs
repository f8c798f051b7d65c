//! Float and spectrum textures (pbrt-v3's textures/*): constant, scale, mix, checkerboard (2D and
//! 3D), imagemap, bilerp, uv, and the procedural fbm, wrinkled, windy, marble and dots
//! ([`crate::procedural`]), with pbrt-v3's 2D mappings (uv, spherical, cylindrical,
//! planar), and the helper that turns a material parameter (a value or a `"texture"`
//! reference) into a texture.
//!
//! Textures are built lazily, when a material that renders refers to them ([`TextureBuilder`]);
//! each texture description is built once and shared, and each image file is read once.
//! Evaluation allocates nothing.
//!
//! Camera-ray hits carry their footprint (the ray differentials, `SurfaceInteraction::diff`):
//! the mappings turn it into (s, t) derivatives as pbrt-v3's do, image maps filter their MIP
//! map over it (`crate::mipmap`: EWA by default, trilinear on request), the 2D checkerboard
//! box-filters over it (pbrt-v3's default `aamode "closedform"`), and the noise textures stop
//! their octaves at it.

use crate::geometry::{Spectrum, SurfaceInteraction, Vec2, Vec3};
use crate::image_io::{read_image, RgbImage};
use crate::mipmap::MipMap;
use crate::procedural::{in_dot, NoisePattern};
use crate::spectrum::{is_spectrum_type, luminance, spectrum_param_to_rgb, srgb_to_linear};
use acr_parser::{
    Error, Loc, Param, ParamList, ParamType, Result, SceneDescription, TextureValue, Values,
    Warning,
};
use glam::{DMat4, Mat4};
use std::collections::{HashMap, HashSet};
use std::f32::consts::PI;
use std::fmt::Debug;
use std::ops::{Add, Mul};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A value a texture can produce: `f32` or [`Spectrum`].
pub trait TexValue:
    Copy
    + Debug
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Mul<Output = Self>
    + Mul<f32, Output = Self>
{
    /// Zero.
    const ZERO: Self;
    /// One.
    const ONE: Self;
    /// pbrt-v3's `uv` texture value at (s, t): (s - ⌊s⌋, t - ⌊t⌋, 0) as a colour; for floats,
    /// s - ⌊s⌋.
    fn from_uv(s: f32, t: f32) -> Self;
    /// A texel of an image file as pbrt-v3's image texture stores it: sRGB-decoded when `gamma`
    /// (for floats, the luminance is decoded), times `scale`; with `invert`, 1 - v, at least 0.
    fn from_texel(rgb: Spectrum, scale: f32, gamma: bool, invert: bool) -> Self;
    /// The value with negative parts set to 0.
    fn clamp_nonneg(self) -> Self;
}

impl TexValue for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;

    fn from_uv(s: f32, _t: f32) -> Self {
        s - s.floor()
    }

    fn clamp_nonneg(self) -> Self {
        self.max(0.0)
    }

    fn from_texel(rgb: Spectrum, scale: f32, gamma: bool, invert: bool) -> Self {
        let y = luminance(rgb);
        let v = scale * if gamma { srgb_to_linear(y) } else { y };
        if invert {
            (1.0 - v).max(0.0)
        } else {
            v
        }
    }
}

impl TexValue for Spectrum {
    const ZERO: Self = Spectrum::ZERO;
    const ONE: Self = Spectrum::ONE;

    fn from_uv(s: f32, t: f32) -> Self {
        Spectrum::new(s - s.floor(), t - t.floor(), 0.0)
    }

    fn clamp_nonneg(self) -> Self {
        self.max(Spectrum::ZERO)
    }

    fn from_texel(rgb: Spectrum, scale: f32, gamma: bool, invert: bool) -> Self {
        let c = if gamma {
            Spectrum::new(
                srgb_to_linear(rgb.x),
                srgb_to_linear(rgb.y),
                srgb_to_linear(rgb.z),
            )
        } else {
            rgb
        };
        let v = c * scale;
        if invert {
            (Spectrum::ONE - v).max(Spectrum::ZERO)
        } else {
            v
        }
    }
}

/// A 2D texture mapping: surface point to (s, t) texture coordinates (pbrt-v3's
/// `TextureMapping2D`s).
#[derive(Clone, Debug, PartialEq)]
pub enum Mapping2D {
    /// (su u + du, sv v + dv).
    Uv {
        /// Scale of u.
        su: f32,
        /// Scale of v.
        sv: f32,
        /// Offset of u.
        du: f32,
        /// Offset of v.
        dv: f32,
    },
    /// Spherical angles of the point in texture space: (θ / π, φ / 2π).
    Spherical {
        /// Texture-from-world (the inverse of the CTM where the texture was defined).
        texture_from_world: Mat4,
    },
    /// Cylindrical coordinates of the point in texture space: ((π + atan2(y, x)) / 2π, z) of
    /// the normalised point.
    Cylindrical {
        /// Texture-from-world.
        texture_from_world: Mat4,
    },
    /// Projection of the world-space point on two vectors: (ds + p·vs, dt + p·vt). As in
    /// pbrt-v3, the texture's transform is not applied.
    Planar {
        /// The s axis.
        vs: Vec3,
        /// The t axis.
        vt: Vec3,
        /// Offset of s.
        ds: f32,
        /// Offset of t.
        dt: f32,
    },
}

impl Mapping2D {
    /// The identity uv mapping.
    pub const UV: Mapping2D = Mapping2D::Uv {
        su: 1.0,
        sv: 1.0,
        du: 0.0,
        dv: 0.0,
    };

    /// The mapping a texture's parameters describe: `"string mapping"` uv (`uscale`, `vscale`,
    /// `udelta`, `vdelta`), spherical, cylindrical or planar (`v1`, `v2`, `udelta`, `vdelta`).
    pub fn from_params(params: &ParamList, world_from_texture: &DMat4, loc: &Loc) -> Result<Self> {
        let f = |name: &str, default: f64| -> Result<f32> {
            Ok(params.float_or(name, default)? as f32)
        };
        let texture_from_world = || -> Mat4 {
            let inv = world_from_texture.inverse();
            if inv.is_finite() {
                inv.as_mat4()
            } else {
                Mat4::IDENTITY
            }
        };
        let kind = params.string("mapping")?.unwrap_or("uv");
        Ok(match kind {
            "uv" => Mapping2D::Uv {
                su: f("uscale", 1.0)?,
                sv: f("vscale", 1.0)?,
                du: f("udelta", 0.0)?,
                dv: f("vdelta", 0.0)?,
            },
            "spherical" => Mapping2D::Spherical {
                texture_from_world: texture_from_world(),
            },
            "cylindrical" => Mapping2D::Cylindrical {
                texture_from_world: texture_from_world(),
            },
            "planar" => Mapping2D::Planar {
                vs: vector_param(params, "v1")?.unwrap_or(Vec3::X),
                vt: vector_param(params, "v2")?.unwrap_or(Vec3::Y),
                ds: f("udelta", 0.0)?,
                dt: f("vdelta", 0.0)?,
            },
            other => {
                let at = params.get("mapping").map_or(loc, |p| &p.loc);
                let hint = acr_parser::closest(other, ["uv", "spherical", "cylindrical", "planar"])
                    .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
                return Err(Error::at(
                    at,
                    format!("unknown texture mapping \"{other}\"{hint}"),
                ));
            }
        })
    }

    /// Texture coordinates of the hit and their screen-space derivatives (pbrt-v3's
    /// `TextureMapping2D::Map`: the spherical and cylindrical mappings difference the point
    /// moved along dp/dx and dp/dy, and fold their azimuth's wrap-around as pbrt-v3 does).
    pub fn map_differentials(&self, si: &SurfaceInteraction) -> (Vec2, Vec2, Vec2) {
        let st = self.map(si);
        let d = &si.diff;
        let (dstdx, dstdy) = match *self {
            Mapping2D::Uv { su, sv, .. } => (
                Vec2::new(su * d.dudx, sv * d.dvdx),
                Vec2::new(su * d.dudy, sv * d.dvdy),
            ),
            Mapping2D::Spherical { .. } | Mapping2D::Cylindrical { .. } => {
                let delta = if matches!(self, Mapping2D::Spherical { .. }) {
                    0.1
                } else {
                    0.01
                };
                let shifted = |dp: Vec3| {
                    let moved = SurfaceInteraction {
                        p: si.p + delta * dp,
                        ..*si
                    };
                    let mut ds = (self.map(&moved) - st) / delta;
                    if ds.y > 0.5 {
                        ds.y = 1.0 - ds.y;
                    } else if ds.y < -0.5 {
                        ds.y = -(ds.y + 1.0);
                    }
                    ds
                };
                (shifted(d.dpdx), shifted(d.dpdy))
            }
            Mapping2D::Planar { vs, vt, .. } => (
                Vec2::new(d.dpdx.dot(vs), d.dpdx.dot(vt)),
                Vec2::new(d.dpdy.dot(vs), d.dpdy.dot(vt)),
            ),
        };
        (st, dstdx, dstdy)
    }

    /// Texture coordinates of the hit.
    #[inline]
    pub fn map(&self, si: &SurfaceInteraction) -> Vec2 {
        match *self {
            Mapping2D::Uv { su, sv, du, dv } => Vec2::new(su * si.uv.x + du, sv * si.uv.y + dv),
            Mapping2D::Spherical { texture_from_world } => {
                let v = texture_from_world.project_point3(si.p).normalize_or_zero();
                let theta = v.z.clamp(-1.0, 1.0).acos();
                let mut phi = v.y.atan2(v.x);
                if phi < 0.0 {
                    phi += 2.0 * PI;
                }
                Vec2::new(theta / PI, phi / (2.0 * PI))
            }
            Mapping2D::Cylindrical { texture_from_world } => {
                let v = texture_from_world.project_point3(si.p).normalize_or_zero();
                Vec2::new((PI + v.y.atan2(v.x)) / (2.0 * PI), v.z)
            }
            Mapping2D::Planar { vs, vt, ds, dt } => Vec2::new(ds + si.p.dot(vs), dt + si.p.dot(vt)),
        }
    }
}

/// A 3-vector parameter declared vector3, point3 or normal.
fn vector_param(params: &ParamList, name: &str) -> Result<Option<Vec3>> {
    let Some(ty) = params.iter().find(|p| p.name == name).map(|p| p.ty) else {
        return Ok(None);
    };
    let ty = match ty {
        ParamType::Point3 | ParamType::Normal => ty,
        _ => ParamType::Vector3,
    };
    Ok(params
        .vec3(name, ty)?
        .map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)))
}

/// What an image lookup outside [0, 1]² gives (pbrt-v3's `ImageWrap`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// Tile the image.
    Repeat,
    /// Black outside.
    Black,
    /// The nearest edge texel.
    Clamp,
}

/// An image ready for lookups: texels already converted (gamma, scale, invert), bottom row
/// first, so that t = 0 is the bottom of the picture as in pbrt-v3.
#[derive(Clone, Debug)]
pub struct ImageMap<T> {
    width: usize,
    height: usize,
    texels: Vec<T>,
    wrap: Wrap,
}

impl<T: TexValue> ImageMap<T> {
    /// From an image (top row first) and the conversion of each texel.
    pub fn new(img: &RgbImage, wrap: Wrap, convert: impl Fn(Spectrum) -> T) -> Self {
        let (width, height) = (img.width.max(1), img.height.max(1));
        let mut texels = Vec::with_capacity(width * height);
        for t in 0..height {
            for s in 0..width {
                let c = if img.width == 0 || img.height == 0 {
                    Spectrum::ZERO
                } else {
                    img.get(s, img.height - 1 - t)
                };
                texels.push(convert(c));
            }
        }
        Self {
            width,
            height,
            texels,
            wrap,
        }
    }

    /// From texels already in lookup order (row 0 at t = 0), `width` x `height` of them.
    pub fn from_rows(width: usize, height: usize, texels: Vec<T>, wrap: Wrap) -> Self {
        debug_assert_eq!(texels.len(), width * height);
        Self {
            width,
            height,
            texels,
            wrap,
        }
    }

    /// What a lookup outside [0, 1]² gives.
    pub fn wrap(&self) -> Wrap {
        self.wrap
    }

    /// The texels, row 0 first.
    pub fn texels(&self) -> &[T] {
        &self.texels
    }

    /// Width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The texel at column `s`, row `t` counted from the bottom, wrapped.
    #[inline]
    pub fn texel(&self, s: i64, t: i64) -> T {
        let (w, h) = (self.width as i64, self.height as i64);
        let (s, t) = match self.wrap {
            Wrap::Repeat => (s.rem_euclid(w), t.rem_euclid(h)),
            Wrap::Clamp => (s.clamp(0, w - 1), t.clamp(0, h - 1)),
            Wrap::Black => {
                if s < 0 || s >= w || t < 0 || t >= h {
                    return T::ZERO;
                }
                (s, t)
            }
        };
        self.texels[t as usize * self.width + s as usize]
    }

    /// Bilinear interpolation at (s, t) in [0, 1]² (pbrt-v3's `MIPMap::triangle` at level 0).
    #[inline]
    pub fn bilerp(&self, st: Vec2) -> T {
        // Keep the integer arithmetic far from overflow; NaN becomes 0.
        let fix = |v: f32| {
            if v.is_finite() {
                v.clamp(-1e9, 1e9)
            } else {
                0.0
            }
        };
        let s = fix(st.x * self.width as f32 - 0.5);
        let t = fix(st.y * self.height as f32 - 0.5);
        let (s0, t0) = (s.floor(), t.floor());
        let (ds, dt) = (s - s0, t - t0);
        let (s0, t0) = (s0 as i64, t0 as i64);
        self.texel(s0, t0) * ((1.0 - ds) * (1.0 - dt))
            + self.texel(s0, t0 + 1) * ((1.0 - ds) * dt)
            + self.texel(s0 + 1, t0) * (ds * (1.0 - dt))
            + self.texel(s0 + 1, t0 + 1) * (ds * dt)
    }
}

/// A texture producing `T` (`f32` for [`FloatTexture`], [`Spectrum`] for
/// [`SpectrumTexture`]). Shared parts are behind `Arc`s, so cloning is cheap.
#[derive(Clone, Debug)]
pub enum Texture<T> {
    /// A constant.
    Constant(T),
    /// `tex1 * tex2`.
    Scale {
        /// First factor.
        tex1: Arc<Texture<T>>,
        /// Second factor.
        tex2: Arc<Texture<T>>,
    },
    /// `(1 - amount) * tex1 + amount * tex2`.
    Mix {
        /// Blend weight.
        amount: Arc<Texture<f32>>,
        /// Where amount is 0.
        tex1: Arc<Texture<T>>,
        /// Where amount is 1.
        tex2: Arc<Texture<T>>,
    },
    /// `tex1` where ⌊s⌋ + ⌊t⌋ is even, else `tex2`, evaluated at the hit point.
    Checkerboard2D {
        /// Texture coordinates.
        mapping: Mapping2D,
        /// Even checks.
        tex1: Arc<Texture<T>>,
        /// Odd checks.
        tex2: Arc<Texture<T>>,
        /// Box-filtered over the hit's footprint (pbrt-v3's `aamode "closedform"`, its
        /// default), else point-sampled (`"none"`).
        closed_form: bool,
    },
    /// `tex1` where ⌊x⌋ + ⌊y⌋ + ⌊z⌋ of the texture-space point is even, else `tex2`.
    Checkerboard3D {
        /// Texture-from-world.
        texture_from_world: Mat4,
        /// Even cells.
        tex1: Arc<Texture<T>>,
        /// Odd cells.
        tex2: Arc<Texture<T>>,
    },
    /// An image, filtered over the hit's footprint (pbrt-v3's MIP map).
    Image {
        /// Texture coordinates.
        mapping: Mapping2D,
        /// The converted texels' pyramid.
        image: Arc<MipMap<T>>,
    },
    /// Bilinear interpolation of four corner values over (s, t).
    Bilerp {
        /// Texture coordinates.
        mapping: Mapping2D,
        /// Values at (0, 0), (0, 1), (1, 0), (1, 1).
        v: [T; 4],
    },
    /// pbrt-v3's `uv` texture: the fractional texture coordinates as a colour.
    Uv {
        /// Texture coordinates.
        mapping: Mapping2D,
    },
    /// pbrt-v3's 3D noise textures (`fbm`, `wrinkled`, `windy`, `marble`), at the hit point in
    /// texture space.
    Noise {
        /// Texture-from-render.
        texture_from_render: Mat4,
        /// Which pattern, with its parameters.
        pattern: NoisePattern,
    },
    /// pbrt-v3's `dots`: `inside` on randomly placed dots, `outside` elsewhere.
    Dots {
        /// Texture coordinates.
        mapping: Mapping2D,
        /// On a dot.
        inside: Arc<Texture<T>>,
        /// Off the dots.
        outside: Arc<Texture<T>>,
    },
}

/// A float-valued texture.
pub type FloatTexture = Texture<f32>;
/// A colour-valued texture.
pub type SpectrumTexture = Texture<Spectrum>;

impl<T: TexValue> Texture<T> {
    /// The texture's value at a hit.
    pub fn eval(&self, si: &SurfaceInteraction) -> T {
        match self {
            Texture::Constant(v) => *v,
            Texture::Scale { tex1, tex2 } => tex1.eval(si) * tex2.eval(si),
            Texture::Mix { amount, tex1, tex2 } => {
                let a = amount.eval(si);
                tex1.eval(si) * (1.0 - a) + tex2.eval(si) * a
            }
            Texture::Checkerboard2D {
                mapping,
                tex1,
                tex2,
                closed_form,
            } => {
                let (st, dstdx, dstdy) = mapping.map_differentials(si);
                let point = || {
                    let sum = (st.x.floor() as i64).wrapping_add(st.y.floor() as i64);
                    if sum % 2 == 0 {
                        tex1.eval(si)
                    } else {
                        tex2.eval(si)
                    }
                };
                if !closed_form {
                    return point();
                }
                // pbrt-v3's closed-form box filter over the footprint.
                let ds = dstdx.x.abs().max(dstdy.x.abs());
                let dt = dstdx.y.abs().max(dstdy.y.abs());
                let (s0, s1, t0, t1) = (st.x - ds, st.x + ds, st.y - dt, st.y + dt);
                if s0.floor() == s1.floor() && t0.floor() == t1.floor() {
                    return point();
                }
                let bump_int = |x: f32| {
                    let h = (x / 2.0).floor();
                    h + 2.0 * (x / 2.0 - h - 0.5).max(0.0)
                };
                let sint = (bump_int(s1) - bump_int(s0)) / (2.0 * ds);
                let tint = (bump_int(t1) - bump_int(t0)) / (2.0 * dt);
                let mut area2 = sint + tint - 2.0 * sint * tint;
                // A footprint wider than a check: its mean, as pbrt-v3.
                if ds > 1.0 || dt > 1.0 {
                    area2 = 0.5;
                }
                // A footprint with no width in s or t (0 / 0): the point value.
                if area2.is_nan() {
                    return point();
                }
                tex1.eval(si) * (1.0 - area2) + tex2.eval(si) * area2
            }
            Texture::Checkerboard3D {
                texture_from_world,
                tex1,
                tex2,
            } => {
                let p = texture_from_world.project_point3(si.p);
                let sum = (p.x.floor() as i64)
                    .wrapping_add(p.y.floor() as i64)
                    .wrapping_add(p.z.floor() as i64);
                if sum % 2 == 0 {
                    tex1.eval(si)
                } else {
                    tex2.eval(si)
                }
            }
            Texture::Image { mapping, image } => {
                let (st, dstdx, dstdy) = mapping.map_differentials(si);
                image.lookup(st, dstdx, dstdy)
            }
            Texture::Bilerp { mapping, v } => {
                let st = mapping.map(si);
                let (s, t) = (st.x, st.y);
                v[0] * ((1.0 - s) * (1.0 - t))
                    + v[1] * ((1.0 - s) * t)
                    + v[2] * (s * (1.0 - t))
                    + v[3] * (s * t)
            }
            Texture::Uv { mapping } => {
                let st = mapping.map(si);
                T::from_uv(st.x, st.y)
            }
            Texture::Noise {
                texture_from_render,
                pattern,
            } => {
                let p = texture_from_render.project_point3(si.p);
                let dpdx = texture_from_render.transform_vector3(si.diff.dpdx);
                let dpdy = texture_from_render.transform_vector3(si.diff.dpdy);
                match pattern {
                    // Built for spectrum textures only.
                    NoisePattern::Marble { .. } => {
                        T::from_texel(pattern.colour(p, dpdx, dpdy), 1.0, false, false)
                    }
                    _ => T::ONE * pattern.scalar(p, dpdx, dpdy),
                }
            }
            Texture::Dots {
                mapping,
                inside,
                outside,
            } => {
                if in_dot(mapping.map(si)) {
                    inside.eval(si)
                } else {
                    outside.eval(si)
                }
            }
        }
    }

    /// The value, when the texture is a constant.
    pub fn as_constant(&self) -> Option<T> {
        match self {
            Texture::Constant(v) => Some(*v),
            _ => None,
        }
    }
}

/// Resolves a file name from a scene file: absolute as is; else relative to the directory of
/// the file that names it (`loc`), and failing that (when that does not exist) relative to the
/// main scene file's directory `main_dir`. When neither exists, the first candidate is returned
/// so that the error names it.
pub fn resolve_file(name: &str, loc: &Loc, main_dir: &Path) -> PathBuf {
    let p = Path::new(name);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    let local = loc.file.dir().join(p);
    if local.exists() {
        return local;
    }
    let main = main_dir.join(p);
    if main.exists() {
        main
    } else {
        local
    }
}

/// The parameter of that name, without marking it used.
fn find<'p>(params: &'p ParamList, name: &str) -> Option<&'p Param> {
    params.iter().find(|p| p.name == name)
}

/// An RGB-valued parameter (`rgb`, `spectrum` or `blackbody`) as linear RGB, if present and of
/// such a type. A parameter of another type is left alone (not marked used), as pbrt-v3's
/// typed lookups ignore it, so that the unused-parameter report names it.
pub fn spectrum_value(params: &ParamList, name: &str) -> Result<Option<Spectrum>> {
    match find(params, name) {
        Some(p) if is_spectrum_type(p.ty) => {
            p.mark_used();
            spectrum_param_to_rgb(p).map(Some)
        }
        _ => Ok(None),
    }
}

/// A `float` parameter's first value, if present and of that type (others are left alone).
pub fn float_value(params: &ParamList, name: &str) -> Result<Option<f32>> {
    match find(params, name) {
        Some(p) if p.ty == ParamType::Float => {
            p.mark_used();
            match &p.values {
                Values::Floats(v) if !v.is_empty() => Ok(Some(v[0] as f32)),
                _ => Err(Error::at(
                    &p.loc,
                    format!("parameter \"{}\" has no value", p.name),
                )),
            }
        }
        _ => Ok(None),
    }
}

/// The texture classes pbrt-v3 has that acr does not implement (pbrt-v3 builds `ptex` only
/// with the Ptex library).
const UNSUPPORTED_CLASSES: [&str; 1] = ["ptex"];
/// The texture classes acr implements.
const CLASSES: [&str; 12] = [
    "constant",
    "scale",
    "mix",
    "checkerboard",
    "imagemap",
    "bilerp",
    "uv",
    "fbm",
    "wrinkled",
    "windy",
    "marble",
    "dots",
];

/// The pattern of a 3D noise texture class from its parameters, with pbrt-v3's defaults.
fn noise_pattern(kind: &str, p: &ParamList) -> Result<NoisePattern> {
    let octaves = || -> Result<u32> {
        let v = p.int_or("octaves", 8)?;
        if !(0..=64).contains(&v) {
            let loc = &p.get("octaves").expect("given").loc;
            return Err(Error::at(
                loc,
                format!("octaves {v} is out of range (0 to 64)"),
            ));
        }
        Ok(v as u32)
    };
    let float = |name: &str, default: f64| -> Result<f32> {
        let v = p.float_or(name, default)?;
        if !v.is_finite() {
            let loc = &p.get(name).expect("given").loc;
            return Err(Error::at(loc, format!("{name} must be finite")));
        }
        Ok(v as f32)
    };
    Ok(match kind {
        "fbm" => NoisePattern::Fbm {
            omega: float("roughness", 0.5)?,
            octaves: octaves()?,
        },
        "wrinkled" => NoisePattern::Wrinkled {
            omega: float("roughness", 0.5)?,
            octaves: octaves()?,
        },
        "windy" => NoisePattern::Windy,
        _ => NoisePattern::Marble {
            omega: float("roughness", 0.5)?,
            octaves: octaves()?,
            scale: float("scale", 1.0)?,
            variation: float("variation", 0.2)?,
        },
    })
}

/// What identifies a converted image map and its MIP map (pbrt-v3's `TexInfo`).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct ImageKey {
    path: PathBuf,
    gamma: bool,
    scale: u32,
    invert: bool,
    wrap: Wrap,
    trilinear: bool,
    max_anisotropy: u32,
}

/// Builds textures on demand from a scene description's texture definitions, each at most once,
/// reading each image file at most once; collects warnings (each kind once).
pub struct TextureBuilder<'a> {
    desc: &'a SceneDescription,
    main_dir: PathBuf,
    floats: Vec<Option<Arc<FloatTexture>>>,
    spectra: Vec<Option<Arc<SpectrumTexture>>>,
    files: HashMap<PathBuf, Arc<RgbImage>>,
    float_maps: HashMap<ImageKey, Arc<MipMap<f32>>>,
    spectrum_maps: HashMap<ImageKey, Arc<MipMap<Spectrum>>>,
    warned: HashSet<String>,
    warnings: Vec<Warning>,
    /// Render space from world space (see [`crate::scene::Scene::render_from_world`]).
    render_from_world: DMat4,
}

/// Per-value-type access to the builder's caches and parameter lookups.
trait Build: TexValue {
    fn cache<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut Vec<Option<Arc<Texture<Self>>>>;
    fn maps<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut HashMap<ImageKey, Arc<MipMap<Self>>>;
    fn param(
        b: &mut TextureBuilder<'_>,
        params: &ParamList,
        name: &str,
    ) -> Result<Option<Texture<Self>>>;
    fn kind() -> TextureValue;
}

impl Build for f32 {
    fn cache<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut Vec<Option<Arc<Texture<Self>>>> {
        &mut b.floats
    }
    fn maps<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut HashMap<ImageKey, Arc<MipMap<Self>>> {
        &mut b.float_maps
    }
    fn param(
        b: &mut TextureBuilder<'_>,
        params: &ParamList,
        name: &str,
    ) -> Result<Option<Texture<Self>>> {
        b.float_param_opt(params, name)
    }
    fn kind() -> TextureValue {
        TextureValue::Float
    }
}

impl Build for Spectrum {
    fn cache<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut Vec<Option<Arc<Texture<Self>>>> {
        &mut b.spectra
    }
    fn maps<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut HashMap<ImageKey, Arc<MipMap<Self>>> {
        &mut b.spectrum_maps
    }
    fn param(
        b: &mut TextureBuilder<'_>,
        params: &ParamList,
        name: &str,
    ) -> Result<Option<Texture<Self>>> {
        b.spectrum_param_opt(params, name)
    }
    fn kind() -> TextureValue {
        TextureValue::Spectrum
    }
}

impl<'a> TextureBuilder<'a> {
    /// A file named in the scene at `loc`, found as [`resolve_file`] finds it.
    pub fn resolve_file(&self, name: &str, loc: &Loc) -> PathBuf {
        resolve_file(name, loc, &self.main_dir)
    }

    /// A builder for `desc`'s textures; `main_dir` is the main scene file's directory.
    pub fn new(desc: &'a SceneDescription, main_dir: &Path) -> Self {
        let n = desc.textures.len();
        Self {
            desc,
            main_dir: main_dir.to_path_buf(),
            floats: vec![None; n],
            spectra: vec![None; n],
            files: HashMap::new(),
            float_maps: HashMap::new(),
            spectrum_maps: HashMap::new(),
            warned: HashSet::new(),
            warnings: Vec::new(),
            render_from_world: DMat4::IDENTITY,
        }
    }

    /// Places textures in render space (a 3D texture or a planar mapping keeps its world
    /// position on the surface).
    pub fn with_render_from_world(mut self, m: DMat4) -> Self {
        self.render_from_world = m;
        self
    }

    /// The main scene file's directory.
    pub fn main_dir(&self) -> &Path {
        &self.main_dir
    }

    /// Records a warning at `loc` unless one with the same `key` was already given.
    pub fn warn_once(&mut self, key: impl Into<String>, loc: &Loc, message: impl Into<String>) {
        if self.warned.insert(key.into()) {
            self.warnings.push(Warning::at(loc, message));
        }
    }

    /// Number of distinct image files read so far.
    pub fn files_read(&self) -> usize {
        self.files.len()
    }

    /// The warnings collected. Parameters of textures that were never built (no rendering
    /// material uses them) are marked used, so that the unused-parameter report does not list
    /// them.
    pub fn finish(self) -> Vec<Warning> {
        for (i, t) in self.desc.textures.iter().enumerate() {
            if self.floats[i].is_none() && self.spectra[i].is_none() {
                for p in t.plugin.params.iter() {
                    p.mark_used();
                }
            }
        }
        self.warnings
    }

    /// The float texture defined at `desc.textures[index]`.
    pub fn float_texture(&mut self, index: usize) -> Result<Arc<FloatTexture>> {
        self.texture::<f32>(index)
    }

    /// The spectrum texture defined at `desc.textures[index]`.
    pub fn spectrum_texture(&mut self, index: usize) -> Result<Arc<SpectrumTexture>> {
        self.texture::<Spectrum>(index)
    }

    /// A float material parameter as a texture: a `"texture"` reference to a float texture, or
    /// a `float` value; `None` when absent (or of another type, which is left unused).
    pub fn float_param_opt(
        &mut self,
        params: &ParamList,
        name: &str,
    ) -> Result<Option<FloatTexture>> {
        let Some(p) = find(params, name) else {
            return Ok(None);
        };
        if let Values::Texture(t) = &p.values {
            p.mark_used();
            return match t.float {
                Some(i) => Ok(Some((*self.float_texture(i)?).clone())),
                None => {
                    self.warn_once(
                        format!("texture kind {}", t.name),
                        &p.loc,
                        format!(
                            "\"{}\" is not a float texture, as parameter \"{name}\" needs; \
                             its default is used",
                            t.name
                        ),
                    );
                    Ok(None)
                }
            };
        }
        Ok(float_value(params, name)?.map(Texture::Constant))
    }

    /// [`TextureBuilder::float_param_opt`] with a default.
    pub fn float_param(
        &mut self,
        params: &ParamList,
        name: &str,
        default: f32,
    ) -> Result<FloatTexture> {
        Ok(self
            .float_param_opt(params, name)?
            .unwrap_or(Texture::Constant(default)))
    }

    /// A colour material parameter as a texture: a `"texture"` reference to a spectrum texture,
    /// or an `rgb`, `spectrum` or `blackbody` value; `None` when absent (or of another type,
    /// which is left unused).
    pub fn spectrum_param_opt(
        &mut self,
        params: &ParamList,
        name: &str,
    ) -> Result<Option<SpectrumTexture>> {
        let Some(p) = find(params, name) else {
            return Ok(None);
        };
        if let Values::Texture(t) = &p.values {
            p.mark_used();
            return match t.spectrum {
                Some(i) => Ok(Some((*self.spectrum_texture(i)?).clone())),
                None => {
                    self.warn_once(
                        format!("texture kind {}", t.name),
                        &p.loc,
                        format!(
                            "\"{}\" is not a spectrum texture, as parameter \"{name}\" needs; \
                             its default is used",
                            t.name
                        ),
                    );
                    Ok(None)
                }
            };
        }
        Ok(spectrum_value(params, name)?.map(Texture::Constant))
    }

    /// [`TextureBuilder::spectrum_param_opt`] with a default.
    pub fn spectrum_param(
        &mut self,
        params: &ParamList,
        name: &str,
        default: Spectrum,
    ) -> Result<SpectrumTexture> {
        Ok(self
            .spectrum_param_opt(params, name)?
            .unwrap_or(Texture::Constant(default)))
    }

    fn param_or<T: Build>(
        &mut self,
        params: &ParamList,
        name: &str,
        default: T,
    ) -> Result<Arc<Texture<T>>> {
        Ok(Arc::new(
            T::param(self, params, name)?.unwrap_or(Texture::Constant(default)),
        ))
    }

    /// The 3D textures' mapping from render space, as pbrt-v3 builds it: its
    /// `IdentityMapping3D(tex2world)` takes the texture's transform as the world-to-texture
    /// one, so the texture's CTM is applied to the world point, not its inverse (`Scale 0.5`
    /// before a `Texture` makes a 3D pattern twice as coarse, where a 2D mapping's would be
    /// twice as fine). Kept, so that images match.
    fn texture_from_render_3d(&self, world_from_texture: DMat4) -> Mat4 {
        let m = world_from_texture * self.render_from_world.inverse();
        if m.is_finite() {
            m.as_mat4()
        } else {
            Mat4::IDENTITY
        }
    }

    fn texture<T: Build>(&mut self, index: usize) -> Result<Arc<Texture<T>>> {
        if let Some(t) = T::cache(self).get(index).cloned().flatten() {
            return Ok(t);
        }
        let desc: &'a SceneDescription = self.desc;
        let Some(td) = desc.textures.get(index) else {
            return Err(Error::file(
                self.main_dir.clone(),
                format!("internal: no texture #{index}"),
            ));
        };
        if td.value != T::kind() {
            return Err(Error::at(
                &td.plugin.loc,
                format!("internal: texture \"{}\" has the wrong value type", td.name),
            ));
        }
        let p = &td.plugin.params;
        let loc = &td.plugin.loc;
        let tex = match td.plugin.kind.as_str() {
            "constant" => Texture::Constant(
                T::param(self, p, "value")?
                    .and_then(|t| t.as_constant())
                    .unwrap_or(T::ONE),
            ),
            "scale" => Texture::Scale {
                tex1: self.param_or(p, "tex1", T::ONE)?,
                tex2: self.param_or(p, "tex2", T::ONE)?,
            },
            "mix" => Texture::Mix {
                amount: Arc::new(self.float_param(p, "amount", 0.5)?),
                tex1: self.param_or(p, "tex1", T::ZERO)?,
                tex2: self.param_or(p, "tex2", T::ONE)?,
            },
            "checkerboard" => {
                let tex1 = self.param_or(p, "tex1", T::ONE)?;
                let tex2 = self.param_or(p, "tex2", T::ZERO)?;
                match p.int_or("dimension", 2)? {
                    2 => {
                        let mapping = Mapping2D::from_params(
                            p,
                            &(self.render_from_world * td.world_from_texture),
                            loc,
                        )?;
                        let closed_form = match p.string("aamode")? {
                            Some("none") => false,
                            None | Some("closedform") => true,
                            Some(other) => {
                                let at = p.get("aamode").map_or(loc, |x| &x.loc);
                                self.warn_once(
                                    format!("aamode {other}"),
                                    at,
                                    format!(
                                        "checkerboard antialiasing mode \"{other}\" is unknown \
                                         (none or closedform); closedform is used, as pbrt-v3 \
                                         does"
                                    ),
                                );
                                true
                            }
                        };
                        Texture::Checkerboard2D {
                            mapping,
                            tex1,
                            tex2,
                            closed_form,
                        }
                    }
                    3 => Texture::Checkerboard3D {
                        texture_from_world: self.texture_from_render_3d(td.world_from_texture),
                        tex1,
                        tex2,
                    },
                    d => {
                        let at = p.get("dimension").map_or(loc, |x| &x.loc);
                        return Err(Error::at(
                            at,
                            format!(
                                "{d}-dimensional checkerboard texture is not supported (2 or 3)"
                            ),
                        ));
                    }
                }
            }
            "imagemap" => {
                let mapping = Mapping2D::from_params(
                    p,
                    &(self.render_from_world * td.world_from_texture),
                    loc,
                )?;
                let image = self.image_map::<T>(p, loc)?;
                Texture::Image { mapping, image }
            }
            "bilerp" => {
                let mapping = Mapping2D::from_params(
                    p,
                    &(self.render_from_world * td.world_from_texture),
                    loc,
                )?;
                let mut v = [T::ZERO, T::ONE, T::ZERO, T::ONE];
                for (slot, name) in v.iter_mut().zip(["v00", "v01", "v10", "v11"]) {
                    if let Some(c) = T::param(self, p, name)?.and_then(|t| t.as_constant()) {
                        *slot = c;
                    }
                }
                Texture::Bilerp { mapping, v }
            }
            "uv" if T::kind() == TextureValue::Spectrum => Texture::Uv {
                mapping: Mapping2D::from_params(
                    p,
                    &(self.render_from_world * td.world_from_texture),
                    loc,
                )?,
            },
            "uv" => {
                return Err(Error::at(
                    loc,
                    "the \"uv\" texture is a spectrum texture; pbrt-v3 has no float one",
                ))
            }
            "fbm" | "wrinkled" | "windy" | "marble" => {
                let kind = td.plugin.kind.as_str();
                if kind == "marble" && T::kind() != TextureValue::Spectrum {
                    return Err(Error::at(
                        loc,
                        "the \"marble\" texture is a spectrum texture; pbrt-v3 has no float one",
                    ));
                }
                Texture::Noise {
                    texture_from_render: self.texture_from_render_3d(td.world_from_texture),
                    pattern: noise_pattern(kind, p)?,
                }
            }
            // pbrt-v3 hands its "inside" parameter to the texture's outside and "outside" to
            // its dots (`CreateDotsFloatTexture` against the constructor's order): the images
            // people have show it so, and so does acr.
            "dots" => Texture::Dots {
                mapping: Mapping2D::from_params(
                    p,
                    &(self.render_from_world * td.world_from_texture),
                    loc,
                )?,
                inside: self.param_or(p, "outside", T::ZERO)?,
                outside: self.param_or(p, "inside", T::ONE)?,
            },
            other if UNSUPPORTED_CLASSES.contains(&other) => {
                self.warn_once(
                    format!("texture class {other}"),
                    loc,
                    format!(
                        "texture class \"{other}\" is not supported (acr, like a pbrt-v3 built \
                         without the Ptex library, has no Ptex reader); a constant 0.5 is used"
                    ),
                );
                Texture::Constant(T::ONE * 0.5)
            }
            other => {
                let hint = acr_parser::closest(other, CLASSES.iter().copied())
                    .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
                return Err(Error::at(
                    loc,
                    format!("unknown texture class \"{other}\"{hint}"),
                ));
            }
        };
        let tex = Arc::new(tex);
        if let Some(slot) = T::cache(self).get_mut(index) {
            *slot = Some(Arc::clone(&tex));
        }
        Ok(tex)
    }

    /// The MIP map an `imagemap` texture's parameters describe, read, converted and built
    /// once.
    fn image_map<T: Build>(&mut self, p: &ParamList, loc: &Loc) -> Result<Arc<MipMap<T>>> {
        let Some(name) = p.string("filename")? else {
            return Err(Error::at(loc, "imagemap texture needs \"string filename\""));
        };
        let at = p.get("filename").map_or(loc, |x| &x.loc).clone();
        let path = resolve_file(name, &at, &self.main_dir);
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let gamma = p.bool("gamma")?.unwrap_or(ext == "png" || ext == "tga");
        let scale = p.float_or("scale", 1.0)? as f32;
        let invert = p.bool_or("invert", false)?;
        let wrap = match p.string("wrap")?.unwrap_or("repeat") {
            "repeat" => Wrap::Repeat,
            "black" => Wrap::Black,
            "clamp" => Wrap::Clamp,
            other => {
                let wloc = p.get("wrap").map_or(loc, |x| &x.loc).clone();
                self.warn_once(
                    format!("wrap {other}"),
                    &wloc,
                    format!(
                        "unknown wrap mode \"{other}\" (repeat, black or clamp); repeat is used"
                    ),
                );
                Wrap::Repeat
            }
        };
        let trilinear = p.bool_or("trilinear", false)?;
        let max_anisotropy = p.float_or("maxanisotropy", 8.0)? as f32;

        let key_path = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
        let key = ImageKey {
            path: key_path.clone(),
            gamma,
            scale: scale.to_bits(),
            invert,
            wrap,
            trilinear,
            max_anisotropy: max_anisotropy.to_bits(),
        };
        if let Some(m) = T::maps(self).get(&key) {
            return Ok(Arc::clone(m));
        }
        let img = match self.files.get(&key_path) {
            Some(img) => Arc::clone(img),
            None => {
                let img = read_image(&path, false).map_err(|e| {
                    Error::at(
                        &at,
                        format!("cannot read image \"{}\": {e}", path.display()),
                    )
                })?;
                let img = Arc::new(img);
                self.files.insert(key_path, Arc::clone(&img));
                img
            }
        };
        let map = ImageMap::new(&img, wrap, |c| T::from_texel(c, scale, gamma, invert));
        let map = Arc::new(MipMap::new(&map, trilinear, max_anisotropy));
        T::maps(self).insert(key, Arc::clone(&map));
        Ok(map)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use acr_parser::parse_str;

    fn si_uv(u: f32, v: f32) -> SurfaceInteraction {
        SurfaceInteraction::flat(Vec3::new(u, v, 0.0), Vec2::new(u, v))
    }

    fn si_p(p: Vec3) -> SurfaceInteraction {
        SurfaceInteraction {
            p,
            ..si_uv(0.0, 0.0)
        }
    }

    fn scene(text: &str, dir: &Path) -> SceneDescription {
        let full = format!("WorldBegin\n{text}\nWorldEnd\n");
        parse_str(&full, &dir.join("scene.pbrt")).unwrap()
    }

    fn named(desc: &SceneDescription, name: &str) -> usize {
        desc.textures.iter().rposition(|t| t.name == name).unwrap()
    }

    #[test]
    fn checkerboard_alternates_on_uv() {
        let desc = scene(
            r#"Texture "c" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]
               "float uscale" 4 "float vscale" 4"#,
            Path::new("/tmp"),
        );
        let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
        let t = b.spectrum_texture(named(&desc, "c")).unwrap();
        let red = Spectrum::new(1.0, 0.0, 0.0);
        let blue = Spectrum::new(0.0, 0.0, 1.0);
        assert_eq!(t.eval(&si_uv(0.1, 0.1)), red);
        assert_eq!(t.eval(&si_uv(0.3, 0.1)), blue);
        assert_eq!(t.eval(&si_uv(0.3, 0.3)), red);
        assert_eq!(t.eval(&si_uv(0.1, 0.3)), blue);
        // Negative coordinates continue the pattern.
        assert_eq!(t.eval(&si_uv(-0.1, 0.1)), blue);
        assert_eq!(t.eval(&si_uv(-0.1, -0.1)), red);
        assert!(b.finish().is_empty());

        // Float checkerboard with defaults 1 and 0, and a 3D one.
        let desc = scene(
            r#"Texture "f" "float" "checkerboard"
               Texture "g" "float" "checkerboard" "integer dimension" 3"#,
            Path::new("/tmp"),
        );
        let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
        let f = b.float_texture(named(&desc, "f")).unwrap();
        assert_eq!(f.eval(&si_uv(0.5, 0.5)), 1.0);
        assert_eq!(f.eval(&si_uv(1.5, 0.5)), 0.0);
        let g = b.float_texture(named(&desc, "g")).unwrap();
        assert_eq!(g.eval(&si_p(Vec3::new(0.5, 0.5, 0.5))), 1.0);
        assert_eq!(g.eval(&si_p(Vec3::new(0.5, 0.5, 1.5))), 0.0);
        let desc = scene(
            r#"Texture "h" "float" "checkerboard" "integer dimension" 4"#,
            Path::new("/tmp"),
        );
        let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
        assert!(b.float_texture(0).is_err());
    }

    #[test]
    fn uv_mapping_scales_and_offsets() {
        let desc = scene(
            r#"Texture "u" "spectrum" "uv" "float uscale" 2 "float vscale" 3
               "float udelta" 0.25 "float vdelta" 0.5"#,
            Path::new("/tmp"),
        );
        let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
        let t = b.spectrum_texture(0).unwrap();
        // s = 2 * 0.1 + 0.25 = 0.45; t = 3 * 0.1 + 0.5 = 0.8.
        let c = t.eval(&si_uv(0.1, 0.1));
        assert!(
            (c - Spectrum::new(0.45, 0.8, 0.0)).abs().max_element() < 1e-5,
            "{c}"
        );
        // Fractional parts: s = 2 * 0.5 + 0.25 = 1.25 -> 0.25.
        let c = t.eval(&si_uv(0.5, 0.5));
        assert!(
            (c - Spectrum::new(0.25, 0.0, 0.0)).abs().max_element() < 1e-5,
            "{c}"
        );
    }

    #[test]
    fn spherical_cylindrical_and_planar_mappings() {
        let world_from_texture = DMat4::from_translation(glam::DVec3::new(0.0, 0.0, 5.0));
        let sph = Mapping2D::Spherical {
            texture_from_world: world_from_texture.inverse().as_mat4(),
        };
        // A point above the texture-space origin: theta = 0.
        let st = sph.map(&si_p(Vec3::new(0.0, 0.0, 7.0)));
        assert!(st.x.abs() < 1e-6);
        // On the texture-space +y axis: theta = pi/2, phi = pi/2.
        let st = sph.map(&si_p(Vec3::new(0.0, 2.0, 5.0)));
        assert!((st - Vec2::new(0.5, 0.25)).length() < 1e-5, "{st}");
        let cyl = Mapping2D::Cylindrical {
            texture_from_world: world_from_texture.inverse().as_mat4(),
        };
        let st = cyl.map(&si_p(Vec3::new(-1.0, 0.0, 5.0)));
        assert!((st.x - 1.0).abs() < 1e-5 || st.x.abs() < 1e-5, "{st}");
        let st = cyl.map(&si_p(Vec3::new(1.0, 0.0, 5.0)));
        assert!((st - Vec2::new(0.5, 0.0)).length() < 1e-5, "{st}");
        let planar = Mapping2D::Planar {
            vs: Vec3::X,
            vt: Vec3::Z,
            ds: 0.5,
            dt: -1.0,
        };
        let st = planar.map(&si_p(Vec3::new(2.0, 9.0, 3.0)));
        assert_eq!(st, Vec2::new(2.5, 2.0));
        // Unknown mappings are errors.
        let desc = scene(
            r#"Texture "c" "float" "checkerboard" "string mapping" "sphere""#,
            Path::new("/tmp"),
        );
        let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
        let e = b.float_texture(0).unwrap_err();
        assert!(e.message().contains("unknown texture mapping"), "{e}");
    }

    #[test]
    fn scale_and_mix() {
        let desc = scene(
            r#"Texture "a" "float" "constant" "float value" 0.25
               Texture "s" "spectrum" "scale" "rgb tex1" [1 2 3] "rgb tex2" [0.5 0.5 2]
               Texture "m" "spectrum" "mix" "rgb tex1" [1 0 0] "rgb tex2" [0 1 0] "texture amount" "a"
               Texture "fs" "float" "scale" "texture tex1" "a" "float tex2" 4
               Texture "fm" "float" "mix"
               Texture "check" "float" "checkerboard" "float uscale" 2
               Texture "mc" "spectrum" "mix" "texture amount" "check""#,
            Path::new("/tmp"),
        );
        let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
        let si = si_uv(0.1, 0.1);
        let s = b.spectrum_texture(named(&desc, "s")).unwrap();
        assert_eq!(s.eval(&si), Spectrum::new(0.5, 1.0, 6.0));
        let m = b.spectrum_texture(named(&desc, "m")).unwrap();
        assert!(
            (m.eval(&si) - Spectrum::new(0.75, 0.25, 0.0))
                .abs()
                .max_element()
                < 1e-6
        );
        let fs = b.float_texture(named(&desc, "fs")).unwrap();
        assert_eq!(fs.eval(&si), 1.0);
        // Mix defaults: tex1 0, tex2 1, amount 0.5.
        let fm = b.float_texture(named(&desc, "fm")).unwrap();
        assert_eq!(fm.eval(&si), 0.5);
        // A textured amount: all of tex2 on even checks, all of tex1 on odd.
        let mc = b.spectrum_texture(named(&desc, "mc")).unwrap();
        assert_eq!(mc.eval(&si_uv(0.1, 0.1)), Spectrum::ONE);
        assert_eq!(mc.eval(&si_uv(0.6, 0.1)), Spectrum::ZERO);
        // The float texture "a" was built once and shared.
        assert!(b.floats[named(&desc, "a")].is_some());
    }

    /// A 2x2 PFM: top row (1, 2), bottom row (3, 4) in every channel.
    fn write_2x2(dir: &Path, name: &str) {
        let mut img = RgbImage::new(2, 2);
        img.set(0, 0, Spectrum::splat(1.0));
        img.set(1, 0, Spectrum::splat(2.0));
        img.set(0, 1, Spectrum::splat(3.0));
        img.set(1, 1, Spectrum::splat(4.0));
        crate::image_io::write_image(&dir.join(name), &img).unwrap();
    }

    fn temp_dir(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("acr-texture-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn image_bilinear_on_2x2() {
        let dir = temp_dir("bilerp");
        write_2x2(&dir, "quad.pfm");
        let desc = scene(
            r#"Texture "i" "float" "imagemap" "string filename" "quad.pfm" "string wrap" "clamp"
               Texture "j" "spectrum" "imagemap" "string filename" "quad.pfm" "float scale" 2
               Texture "k" "float" "imagemap" "string filename" "quad.pfm" "string wrap" "black""#,
            &dir,
        );
        let mut b = TextureBuilder::new(&desc, &dir);
        let i = b.float_texture(named(&desc, "i")).unwrap();
        // Texel centres: t = 0.25 is the bottom row (3, 4), t = 0.75 the top (1, 2).
        assert!((i.eval(&si_uv(0.25, 0.25)) - 3.0).abs() < 1e-5);
        assert!((i.eval(&si_uv(0.75, 0.25)) - 4.0).abs() < 1e-5);
        assert!((i.eval(&si_uv(0.25, 0.75)) - 1.0).abs() < 1e-5);
        assert!((i.eval(&si_uv(0.75, 0.75)) - 2.0).abs() < 1e-5);
        // The centre is the average; halfway along the bottom row, 3.5.
        assert!((i.eval(&si_uv(0.5, 0.5)) - 2.5).abs() < 1e-5);
        assert!((i.eval(&si_uv(0.5, 0.25)) - 3.5).abs() < 1e-5);
        // Clamped beyond the edge.
        assert!((i.eval(&si_uv(0.0, 0.0)) - 3.0).abs() < 1e-5);
        // Repeat (default) wraps: at s = 0 the left column blends with the right one.
        let j = b.spectrum_texture(named(&desc, "j")).unwrap();
        assert!((j.eval(&si_uv(0.0, 0.25)).x - 2.0 * 3.5).abs() < 1e-5);
        // Black fades to zero outside.
        let k = b.float_texture(named(&desc, "k")).unwrap();
        assert!((k.eval(&si_uv(0.0, 0.25)) - 1.5).abs() < 1e-5);
        assert_eq!(k.eval(&si_uv(-1.0, 0.25)), 0.0);
        // One file read for the three textures.
        assert_eq!(b.files_read(), 1);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn png_gamma_and_invert() {
        let dir = temp_dir("gamma");
        let buf = image::RgbImage::from_raw(1, 1, vec![128, 128, 128]).unwrap();
        buf.save(dir.join("grey.png")).unwrap();
        let desc = scene(
            r#"Texture "a" "spectrum" "imagemap" "string filename" "grey.png"
               Texture "b" "spectrum" "imagemap" "string filename" "grey.png" "bool gamma" false
               Texture "c" "float" "imagemap" "string filename" "grey.png" "bool invert" true"#,
            &dir,
        );
        let mut b = TextureBuilder::new(&desc, &dir);
        let si = si_uv(0.3, 0.3);
        let a = b.spectrum_texture(0).unwrap().eval(&si);
        assert!((a.x - srgb_to_linear(128.0 / 255.0)).abs() < 1e-5, "{a}");
        let raw = b.spectrum_texture(1).unwrap().eval(&si);
        assert!((raw.x - 128.0 / 255.0).abs() < 1e-5, "{raw}");
        let c = b.float_texture(2).unwrap().eval(&si);
        assert!(
            (c - (1.0 - srgb_to_linear(128.0 / 255.0))).abs() < 1e-4,
            "{c}"
        );
        assert_eq!(b.files_read(), 1);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn missing_images_are_errors_where_named() {
        let dir = temp_dir("missing");
        let desc = scene(
            r#"Texture "a" "spectrum" "imagemap" "string filename" "nope.png""#,
            &dir,
        );
        let mut b = TextureBuilder::new(&desc, &dir);
        let e = b.spectrum_texture(0).unwrap_err();
        assert!(e.message().contains("nope.png"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn params_become_textures() {
        let desc = scene(
            r#"Texture "t" "spectrum" "constant" "rgb value" [0.1 0.2 0.3]
               Texture "f" "float" "constant" "float value" 0.7
               Material "matte" "texture Kd" "t" "float sigma" 10 "rgb Ks" [1 1 1]
                 "texture roughness" "f" "float weird" 1 "texture bad" "f""#,
            Path::new("/tmp"),
        );
        let params = &desc.materials.last().unwrap().plugin.params;
        let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
        let si = si_uv(0.5, 0.5);
        let kd = b.spectrum_param(params, "Kd", Spectrum::ONE).unwrap();
        assert!(
            (kd.eval(&si) - Spectrum::new(0.1, 0.2, 0.3))
                .abs()
                .max_element()
                < 1e-6
        );
        let sigma = b.float_param(params, "sigma", 0.0).unwrap();
        assert_eq!(sigma.as_constant(), Some(10.0));
        let rough = b.float_param(params, "roughness", 0.0).unwrap();
        assert!((rough.eval(&si) - 0.7).abs() < 1e-6);
        let ks = b.spectrum_param(params, "Ks", Spectrum::ZERO).unwrap();
        assert_eq!(ks.as_constant(), Some(Spectrum::ONE));
        // Absent: the default. Wrong type: the default, and left unused.
        let kr = b
            .spectrum_param(params, "Kr", Spectrum::splat(0.5))
            .unwrap();
        assert_eq!(kr.as_constant(), Some(Spectrum::splat(0.5)));
        let weird = b
            .spectrum_param(params, "weird", Spectrum::splat(0.5))
            .unwrap();
        assert_eq!(weird.as_constant(), Some(Spectrum::splat(0.5)));
        assert!(params.unused().any(|p| p.name == "weird"));
        // A float texture where a spectrum is needed: the default, with a warning.
        let bad = b
            .spectrum_param(params, "bad", Spectrum::splat(0.25))
            .unwrap();
        assert_eq!(bad.as_constant(), Some(Spectrum::splat(0.25)));
        assert_eq!(b.finish().len(), 1);
    }

    #[test]
    fn unsupported_and_unknown_classes() {
        let desc = scene(
            r#"Texture "a" "float" "ptex"
               Texture "b" "float" "checkerbord"
               Texture "c" "float" "bilerp" "float v00" 1 "float v01" 2 "float v10" 3 "float v11" 4"#,
            Path::new("/tmp"),
        );
        let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
        assert_eq!(b.float_texture(0).unwrap().as_constant(), Some(0.5));
        let e = b.float_texture(1).unwrap_err();
        assert!(e.message().contains("checkerboard"), "{e}");
        let c = b.float_texture(2).unwrap();
        // (1-s)(1-t) 1 + (1-s) t 2 + s (1-t) 3 + s t 4 at (0.5, 0.25).
        let v = c.eval(&si_uv(0.5, 0.25));
        assert!((v - (0.375 + 0.25 + 1.125 + 0.5)).abs() < 1e-5, "{v}");
        assert_eq!(b.finish().len(), 1);
    }

    #[test]
    fn procedural_classes_build_and_check_their_parameters() {
        let desc = scene(
            r#"Texture "f" "float" "fbm" "integer octaves" 3 "float roughness" 0.7
               Texture "m" "float" "marble"
               Texture "o" "float" "wrinkled" "integer octaves" -2
               Texture "d" "spectrum" "dots" "rgb inside" [1 0 0] "rgb outside" [0 0 1]
               Texture "s" "spectrum" "marble" "float scale" 2"#,
            Path::new("/tmp"),
        );
        let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
        let f = b.float_texture(0).unwrap();
        let p = Vec3::new(0.3, 1.7, -2.2);
        assert_eq!(
            f.eval(&si_p(p)),
            crate::noise::fbm(p, Vec3::ZERO, Vec3::ZERO, 0.7, 3)
        );
        let e = b.float_texture(1).unwrap_err();
        assert!(e.message().contains("spectrum texture"), "{e}");
        let e = b.float_texture(2).unwrap_err();
        assert!(e.message().contains("octaves -2"), "{e}");
        // pbrt-v3's order: "inside" off the dots, "outside" on them.
        let d = b.spectrum_texture(3).unwrap();
        let off = d.eval(&si_uv(0.0, 0.0));
        assert_eq!(off, Spectrum::new(1.0, 0.0, 0.0));
        let m = b.spectrum_texture(4).unwrap();
        assert!(m.eval(&si_p(p)).is_finite());
        assert!(b.finish().is_empty());
    }

    #[test]
    fn files_resolve_next_to_the_naming_file_then_the_main_dir() {
        let dir = temp_dir("resolve");
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("main.txt"), "").unwrap();
        std::fs::write(dir.join("sub").join("local.txt"), "").unwrap();
        let file = acr_parser::SourceFile::new(dir.join("sub").join("inc.pbrt"), "");
        let loc = Loc::new(&file, 0);
        assert_eq!(
            resolve_file("local.txt", &loc, &dir),
            dir.join("sub").join("local.txt")
        );
        assert_eq!(resolve_file("main.txt", &loc, &dir), dir.join("main.txt"));
        assert_eq!(
            resolve_file("none.txt", &loc, &dir),
            dir.join("sub").join("none.txt")
        );
        assert_eq!(
            resolve_file("/abs/x.png", &loc, &dir),
            PathBuf::from("/abs/x.png")
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
