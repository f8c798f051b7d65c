//! Float and spectrum textures (pbrt-v3's textures/*): constant, scale, mix, checkerboard (2D and
//! 3D), imagemap, bilerp, uv, and the procedural fbm, wrinkled, windy, marble and dots
//! ([`crate::procedural`]), with pbrt-v3's 2D mappings (uv, spherical, cylindrical,
//! planar), and the helper that turns a material parameter (a value or a `"texture"`
//! reference) into a texture.
//!
//! Textures are built lazily, when a material that renders refers to them ([`TextureBuilder`]);
//! each texture description is built once and shared, and each image map's MIP map once (an
//! 8-bit PNG's levels kept in bytes, `texels`). Evaluation allocates nothing.
//!
//! Camera-ray hits carry their footprint (the ray differentials, `SurfaceInteraction::diff`):
//! the mappings turn it into (s, t) derivatives as pbrt-v3's do, image maps filter their MIP
//! map over it (`crate::mipmap`: EWA by default, trilinear on request), the 2D checkerboard
//! box-filters over it (pbrt-v3's default `aamode "closedform"`), and the noise textures stop
//! their octaves at it.

use crate::geometry::{Spectrum, SurfaceInteraction};
use crate::mipmap::MipMap;
use crate::procedural::{in_dot, NoisePattern};
use crate::spectrum::{is_spectrum_type, spectrum_param_to_rgb};
use acr_parser::{Error, Loc, Param, ParamList, ParamType, Result, Values};
use glam::Mat4;
use std::fmt::Debug;
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod builder;
pub mod byte_pyramid;
pub mod image_map;
mod mapping;
pub mod pyramid;
pub mod source;
#[cfg(test)]
mod tests;
pub mod texels;
pub mod value;

pub use builder::TextureBuilder;
pub use image_map::{ImageMap, Wrap};
pub use mapping::Mapping2D;
pub use value::TexValue;

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
    acr_parser::resolve_path(name, &loc.file, main_dir)
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
