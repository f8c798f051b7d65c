//! Bump mapping: pbrt-v3's `Material::Bump`. A float texture displaces the surface along its
//! shading normal; the shading tangents tilt by the displacement's finite differences in u and
//! v, and the shading normal becomes their cross product, turned to the geometric normal's
//! side.
//!
//! The finite-difference steps are pbrt-v3's: half the hit's footprint in u and v, from the
//! camera ray's differentials (du = (|du/dx| + |du/dy|) / 2), and 0.0005 where there is none
//! (later bounces). One simplification: on triangle meshes the normal's derivatives are zero
//! (pbrt-v3 differentiates the vertex normals; the quadrics' come from the Weingarten equations
//! as in pbrt-v3).

use crate::geometry::SurfaceInteraction;
use crate::texture::FloatTexture;

/// pbrt-v3's step in u and v when a ray carries no differentials.
const STEP: f32 = 0.0005;

/// pbrt-v3's step: half the footprint `(|dx| + |dy|) / 2`, else [`STEP`].
fn step(dx: f32, dy: f32) -> f32 {
    let s = 0.5 * (dx.abs() + dy.abs());
    if s == 0.0 {
        STEP
    } else {
        s
    }
}

/// The interaction `si` with its shading geometry bumped by the displacement texture `d`.
pub fn bump(d: &FloatTexture, si: &SurfaceInteraction) -> SurfaceInteraction {
    let (dpdu, dpdv) = (si.shading_dpdu, si.shading_dpdv);
    let du = step(si.diff.dudx, si.diff.dudy);
    let dv = step(si.diff.dvdx, si.diff.dvdy);
    let mut eval = *si;
    // Shifted in u.
    eval.p = si.p + du * dpdu;
    eval.uv = si.uv + glam::Vec2::new(du, 0.0);
    let u_displace = d.eval(&eval);
    // Shifted in v.
    eval.p = si.p + dv * dpdv;
    eval.uv = si.uv + glam::Vec2::new(0.0, dv);
    let v_displace = d.eval(&eval);
    let displace = d.eval(si);

    let n = si.shading_n;
    let bumped_dpdu = dpdu + (u_displace - displace) / du * n + displace * si.dndu;
    let bumped_dpdv = dpdv + (v_displace - displace) / dv * n + displace * si.dndv;
    let ns = bumped_dpdu.cross(bumped_dpdv).normalize_or_zero();
    let mut out = *si;
    if !ns.is_finite() || ns == glam::Vec3::ZERO {
        // A displacement that is not finite, or tangents that collapse: the surface as it is.
        return out;
    }
    // SetShadingGeometry(.., orientationIsAuthoritative = false): the shading normal turns to
    // the geometric normal's side.
    out.shading_n = if ns.dot(si.n) < 0.0 { -ns } else { ns };
    out.shading_dpdu = bumped_dpdu;
    out.shading_dpdv = bumped_dpdv;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Vec2, Vec3};
    use crate::texture::Texture;

    fn si() -> SurfaceInteraction {
        SurfaceInteraction::flat(Vec3::new(0.2, 0.3, 0.0), Vec2::new(0.2, 0.3))
    }

    #[test]
    fn a_constant_displacement_leaves_the_shading_normal() {
        let b = bump(&Texture::Constant(0.3), &si());
        assert_eq!(b.shading_n, Vec3::Z);
    }

    #[test]
    fn a_linear_ramp_tilts_the_normal_by_its_slope() {
        // d = 0.5 u on the plane z = 0 (u = x): the bumped surface z = 0.5 x has the normal
        // (-0.5, 0, 1) normalised, whatever the step.
        let ramp = Texture::Scale {
            tex1: std::sync::Arc::new(Texture::Constant(0.5)),
            tex2: std::sync::Arc::new(Texture::Uv {
                mapping: crate::texture::Mapping2D::Uv {
                    su: 1.0,
                    sv: 1.0,
                    du: 0.0,
                    dv: 0.0,
                },
            }),
        };
        let b = bump(&ramp, &si());
        let want = Vec3::new(-0.5, 0.0, 1.0).normalize();
        assert!((b.shading_n - want).length() < 1e-3, "{}", b.shading_n);
        // Turned to the geometric normal's side when the surface faces the other way.
        let mut flipped = si();
        flipped.n = -Vec3::Z;
        let b = bump(&ramp, &flipped);
        assert!((b.shading_n + want).length() < 1e-3, "{}", b.shading_n);
    }

    #[test]
    // The values as pbrt-v3 printed them.
    #[allow(clippy::excessive_precision)]
    fn bump_matches_pbrt_v3_on_a_sphere() {
        // Hits on pbrt-v3's sphere (radius 0.9 at (0, 0.9, 1.2)) and its Material::Bump with
        // 0.04 x fbm (4 octaves) defined under `Scale 0.6 0.6 0.6`, printed by
        // tests/data/pbrt-v3/bumpcheck.cpp linked with pbrt-v3's libpbrt: the hit's p, uv, n,
        // dpdu, dpdv, and the bumped shading normal; pbrt-v3's dndu and dndv there are dpdu
        // and dpdv over the radius (it prints them too).
        let fbm = Texture::Noise {
            texture_from_render: glam::Mat4::from_scale(Vec3::splat(0.6)),
            pattern: crate::procedural::NoisePattern::Fbm {
                omega: 0.5,
                octaves: 4,
            },
        };
        let d = Texture::Scale {
            tex1: std::sync::Arc::new(fbm),
            tex2: std::sync::Arc::new(Texture::Constant(0.04)),
        };
        let cases = [
            (
                [0.0, 0.969729, 0.302705],
                [0.25, 0.024687],
                [0.0, 0.077477, -0.996994],
                [-0.43812, 0.0, 0.0],
                [0.0, 2.81893, 0.21906],
                [-0.059199, 0.032228, -0.997726],
            ),
            (
                [0.548920, 0.841296, 0.489198],
                [0.983044, 0.210194],
                [0.609912, -0.065226, -0.789781],
                [0.36885, 3.44897, 0.0],
                [2.22039, -0.23746, 1.73432],
                [0.667782, -0.091265, -0.738741],
            ),
            (
                [-0.438794, 1.225755, 0.484918],
                [0.398362, 0.207714],
                [-0.487550, 0.361950, -0.794536],
                [-2.04678, -2.75703, 0.0],
                [-1.80377, 1.33909, 1.71687],
                [-0.505520, 0.337662, -0.793999],
            ),
        ];
        for (p, uv, n, dpdu, dpdv, want) in cases {
            let n = Vec3::from_array(n);
            let (dpdu, dpdv) = (Vec3::from_array(dpdu), Vec3::from_array(dpdv));
            let hit = SurfaceInteraction {
                p: Vec3::from_array(p),
                n,
                uv: Vec2::from_array(uv),
                dpdu,
                dpdv,
                shading_n: n,
                shading_dpdu: dpdu,
                shading_dpdv: dpdv,
                dndu: dpdu / 0.9,
                dndv: dpdv / 0.9,
                wo: -n,
                time: 0.0,
                p_error: 0.0,
                diff: Default::default(),
            };
            let got = bump(&d, &hit).shading_n;
            let want = Vec3::from_array(want);
            assert!((got - want).length() < 1e-4, "{got} against {want}");
        }
    }
}
