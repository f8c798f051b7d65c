//! pbrt-v3's 2D texture mappings (uv, spherical, cylindrical, planar) and their screen-space
//! derivatives.

use crate::geometry::{SurfaceInteraction, Vec2, Vec3};
use acr_parser::{Error, Loc, ParamList, ParamType, Result};
use glam::{DMat4, Mat4};
use std::f32::consts::PI;
use std::fmt::Debug;

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
