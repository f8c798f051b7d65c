//! pbrt-v3's `nurbs` shape: a (possibly rational) NURBS patch of `nu` x `nv` control points,
//! made into a triangle mesh exactly as pbrt-v3's `CreateNURBS` does. It evaluates the surface
//! (position, dp/du, dp/dv) at 30 x 30 parameter values spread evenly over [u0, u1] x [v0, v1],
//! gives each vertex the normal normalize(dp/du x dp/dv) and the uv (u, v) it was evaluated at,
//! and joins the grid with two triangles per cell. The arithmetic is pbrt-v3's, in single
//! precision and in its order, so vertices agree with its meshes.

use crate::geometry::Vec3;
use acr_parser::{Error, Loc, Mesh, ParamList, ParamType, Result};

/// Points per parameter direction: pbrt-v3 dices every patch 30 x 30 and reads no parameter
/// for it (a `diceu` or `dicev` in a scene is unused there too).
const DICE: usize = 30;

/// A control point in homogeneous coordinates (x w, y w, z w, w).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Homogeneous {
    x: f32,
    y: f32,
    z: f32,
    w: f32,
}

impl Homogeneous {
    /// `self alpha + other (1 - alpha)`, component by component as pbrt-v3 writes it.
    #[inline]
    fn blend(self, other: Self, alpha: f32) -> Self {
        Self {
            x: self.x * alpha + other.x * (1.0 - alpha),
            y: self.y * alpha + other.y * (1.0 - alpha),
            z: self.z * alpha + other.z * (1.0 - alpha),
            w: self.w * alpha + other.w * (1.0 - alpha),
        }
    }
}

/// One parameter direction of a patch: its order, knot vector (`n + order` knots) and number
/// of control points `n`.
struct Direction {
    order: usize,
    knots: Vec<f32>,
    n: usize,
}

impl Direction {
    /// pbrt-v3's `KnotOffset`: the knot span [knots[k], knots[k + 1]] holding `t`, searched
    /// from `order - 1`. The validation in [`mesh_from_params`] keeps `t` within
    /// [knots[order - 1], knots[n]], where pbrt-v3 finds its span the same way; the search
    /// also stops at `n - 1` and steps over spans of zero length at either end, cases where
    /// pbrt-v3 instead fails an assertion (a rounding of the dicing past the last knot, too
    /// many repeated first or last knots), so that evaluation never divides by zero.
    fn knot_offset(&self, t: f32) -> usize {
        let k = &self.knots;
        let mut off = self.order - 1;
        while off + 1 < self.n && (t > k[off + 1] || k[off] == k[off + 1]) {
            off += 1;
        }
        // Only when t is past the last knot (rounding): back to the last non-empty span, which
        // the validation's knots[order - 1] < knots[n] guarantees.
        while off > self.order - 1 && k[off] == k[off + 1] {
            off -= 1;
        }
        off
    }

    /// pbrt-v3's `NURBSEvaluate`: the curve of control points `cp(0..n)` at `t` (de Boor's
    /// algorithm on homogeneous points), and, if asked, the derivative of the projected point.
    fn evaluate(
        &self,
        cp: impl Fn(usize) -> Homogeneous,
        t: f32,
        deriv: Option<&mut Vec3>,
    ) -> Homogeneous {
        let order = self.order;
        let off = self.knot_offset(t);
        // pbrt-v3 indexes knots relative to the span, reaching back up to order - 2 knots.
        let knot = |i: usize| self.knots[off + i + 1 - order];
        let first_cp = off + 1 - order;
        let mut work: Vec<Homogeneous> = (0..order).map(|i| cp(first_cp + i)).collect();
        for i in 0..order - 2 {
            for j in 0..order - 1 - i {
                // knot[1 + j] and knot[j + 2 - order + i], shifted by order - 1.
                let (hi, lo) = (knot(j + order), knot(j + 1 + i));
                let alpha = (hi - t) / (hi - lo);
                work[j] = work[j].blend(work[j + 1], alpha);
            }
        }
        let (k0, k1) = (knot(order - 1), knot(order));
        let alpha = (k1 - t) / (k1 - k0);
        let val = work[0].blend(work[1], alpha);
        if let Some(d) = deriv {
            let factor = (order - 1) as f32 / (k1 - k0);
            let delta = Homogeneous {
                x: (work[1].x - work[0].x) * factor,
                y: (work[1].y - work[0].y) * factor,
                z: (work[1].z - work[0].z) * factor,
                w: (work[1].w - work[0].w) * factor,
            };
            let ww = val.w * val.w;
            *d = Vec3::new(
                delta.x / val.w - (val.x * delta.w / ww),
                delta.y / val.w - (val.y * delta.w / ww),
                delta.z / val.w - (val.z * delta.w / ww),
            );
        }
        val
    }
}

/// pbrt-v3's `NURBSEvaluateSurface`: the point at (u, v) of the patch with control points
/// `cp[v * nu + u]`, and dp/du and dp/dv there. Evaluated as pbrt-v3 does: curves in v through
/// each column, then in u through those (point and dp/du); curves in u through each row, then
/// in v through those (dp/dv).
fn evaluate_surface(
    ud: &Direction,
    u: f32,
    vd: &Direction,
    v: f32,
    cp: &[Homogeneous],
) -> (Vec3, Vec3, Vec3) {
    let nu = ud.n;
    let u_first = ud.knot_offset(u) + 1 - ud.order;
    let iso: Vec<Homogeneous> = (0..ud.order)
        .map(|i| vd.evaluate(|k| cp[u_first + i + k * nu], v, None))
        .collect();
    let mut dpdu = Vec3::ZERO;
    let p = ud.evaluate(|k| iso[k - u_first], u, Some(&mut dpdu));

    let v_first = vd.knot_offset(v) + 1 - vd.order;
    let iso: Vec<Homogeneous> = (0..vd.order)
        .map(|i| ud.evaluate(|k| cp[(v_first + i) * nu + k], u, None))
        .collect();
    let mut dpdv = Vec3::ZERO;
    vd.evaluate(|k| iso[k - v_first], v, Some(&mut dpdv));
    (Vec3::new(p.x / p.w, p.y / p.w, p.z / p.w), dpdu, dpdv)
}

/// The NURBS patch's mesh, or a located error for missing or inconsistent parameters.
pub fn mesh_from_params(params: &ParamList, loc: &Loc) -> Result<Mesh> {
    let at = |name: &str| {
        params
            .get(name)
            .map_or_else(|| loc.clone(), |p| p.loc.clone())
    };
    let (ud, u0, u1) = direction(params, loc, 'u')?;
    let (vd, v0, v1) = direction(params, loc, 'v')?;

    let (cp, name): (Vec<Homogeneous>, &str) =
        if let Some(p) = params.numbers("P", ParamType::Point3)? {
            let cp = p
                .chunks_exact(3)
                .map(|c| Homogeneous {
                    x: c[0] as f32,
                    y: c[1] as f32,
                    z: c[2] as f32,
                    w: 1.0,
                })
                .collect();
            (cp, "P")
        } else if let Some(pw) = params.floats("Pw")? {
            if pw.len() % 4 != 0 {
                return Err(Error::at(
                    &at("Pw"),
                    "Number of \"Pw\" control points provided to NURBS shape must be multiple \
                     of four",
                ));
            }
            let cp = pw
                .chunks_exact(4)
                .map(|c| Homogeneous {
                    x: c[0] as f32,
                    y: c[1] as f32,
                    z: c[2] as f32,
                    w: c[3] as f32,
                })
                .collect();
            (cp, "Pw")
        } else {
            return Err(Error::at(
                loc,
                "Must provide control points via \"P\" or \"Pw\" parameter to NURBS shape.",
            ));
        };
    if cp.len() != ud.n * vd.n {
        return Err(Error::at(
            &at(name),
            format!(
                "NURBS shape was expecting {}x{}={} control points, was given {}",
                ud.n,
                vd.n,
                ud.n * vd.n,
                cp.len()
            ),
        ));
    }

    // pbrt-v3's Lerp((float)i / (float)(dice - 1), t0, t1).
    let dice = |t0: f32, t1: f32| -> Vec<f32> {
        (0..DICE)
            .map(|i| {
                let t = i as f32 / (DICE - 1) as f32;
                (1.0 - t) * t0 + t * t1
            })
            .collect()
    };
    let (ueval, veval) = (dice(u0, u1), dice(v0, v1));
    let mut positions = Vec::with_capacity(DICE * DICE);
    let mut normals = Vec::with_capacity(DICE * DICE);
    let mut uvs = Vec::with_capacity(DICE * DICE);
    for &v in &veval {
        for &u in &ueval {
            let (p, dpdu, dpdv) = evaluate_surface(&ud, u, &vd, v, &cp);
            positions.push(p.to_array());
            // pbrt-v3's Cross works in double precision. Where it vanishes (a pole, a collapsed
            // edge) pbrt-v3 fails an assertion normalizing it; acr leaves a zero normal there,
            // which the interpolation of the triangles' other vertex normals outweighs.
            let n = dpdu.as_dvec3().cross(dpdv.as_dvec3()).as_vec3();
            let len = n.length();
            let n = if len > 0.0 {
                n * (1.0 / len)
            } else {
                Vec3::ZERO
            };
            normals.push(n.to_array());
            uvs.push([u, v]);
        }
    }
    let vert = |u: usize, v: usize| (v * DICE + u) as u32;
    let mut indices = Vec::with_capacity(6 * (DICE - 1) * (DICE - 1));
    for v in 0..DICE - 1 {
        for u in 0..DICE - 1 {
            indices.extend([vert(u, v), vert(u + 1, v), vert(u + 1, v + 1)]);
            indices.extend([vert(u, v), vert(u + 1, v + 1), vert(u, v + 1)]);
        }
    }
    Ok(Mesh {
        positions,
        normals: Some(normals),
        uvs: Some(uvs),
        indices,
    })
}

/// The `nu`, `uorder`, `uknots`, `u0`, `u1` parameters (or the `v` ones, for `dir` 'v'),
/// checked: pbrt-v3's checks (present, as many knots as control points plus order), and those
/// its evaluation assumes without checking (order at least 2 and at most the number of
/// control points, finite non-decreasing knots, knots[order - 1] <= t0 < t1 <= knots[n]).
fn direction(params: &ParamList, loc: &Loc, dir: char) -> Result<(Direction, f32, f32)> {
    let at = |name: &str| {
        params
            .get(name)
            .map_or_else(|| loc.clone(), |p| p.loc.clone())
    };
    let (n_name, order_name, knots_name) = (
        format!("n{dir}"),
        format!("{dir}order"),
        format!("{dir}knots"),
    );
    let Some(n) = params.int(&n_name)? else {
        return Err(Error::at(
            loc,
            format!("Must provide number of control points \"{n_name}\" with NURBS shape."),
        ));
    };
    let Some(order) = params.int(&order_name)? else {
        return Err(Error::at(
            loc,
            format!("Must provide {dir} order \"{order_name}\" with NURBS shape."),
        ));
    };
    let Some(knots) = params.floats(&knots_name)? else {
        return Err(Error::at(
            loc,
            format!("Must provide {dir} knot vector \"{knots_name}\" with NURBS shape."),
        ));
    };
    if knots.len() as i64 != i64::from(n) + i64::from(order) {
        return Err(Error::at(
            &at(&knots_name),
            format!(
                "Number of knots in {dir} knot vector {} doesn't match sum of number of {dir} \
                 control points {n} and {dir} order {order}.",
                knots.len()
            ),
        ));
    }
    if order < 2 || n < order {
        return Err(Error::at(
            &at(if order < 2 { &order_name } else { &n_name }),
            format!(
                "NURBS shape needs {dir} order at least 2 and at most the number of {dir} \
                 control points (found order {order}, {n} control points)"
            ),
        ));
    }
    let knots: Vec<f32> = knots.iter().map(|&k| k as f32).collect();
    if let Some(i) = knots.iter().position(|k| !k.is_finite()) {
        return Err(Error::at(
            &at(&knots_name),
            format!("NURBS {dir} knot {i} is not finite ({})", knots[i]),
        ));
    }
    if let Some(i) = (1..knots.len()).find(|&i| knots[i] < knots[i - 1]) {
        return Err(Error::at(
            &at(&knots_name),
            format!(
                "NURBS {dir} knot vector must not decrease: knot {i} ({}) is below knot {} ({})",
                knots[i],
                i - 1,
                knots[i - 1]
            ),
        ));
    }
    let (order, n) = (order as usize, n as usize);
    let (lo, hi) = (knots[order - 1], knots[n]);
    let (t0_name, t1_name) = (format!("{dir}0"), format!("{dir}1"));
    let t0 = params.float_or(&t0_name, f64::from(lo))? as f32;
    let t1 = params.float_or(&t1_name, f64::from(hi))? as f32;
    // Written so that NaN fails too.
    if !(lo <= t0 && t0 < t1 && t1 <= hi) {
        let name = if params.get(&t0_name).is_some() && !(lo <= t0 && t0 < t1) {
            t0_name.as_str()
        } else if params.get(&t1_name).is_some() {
            t1_name.as_str()
        } else {
            knots_name.as_str()
        };
        return Err(Error::at(
            &at(name),
            format!(
                "NURBS {dir} range [{t0}, {t1}] must be increasing and within the knots' \
                 [{lo}, {hi}] (knots {} and {n} of \"{knots_name}\")",
                order - 1
            ),
        ));
    }
    Ok((Direction { order, knots, n }, t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape_params(text: &str) -> (ParamList, Loc) {
        super::super::test_util::shape_params(text, "n.pbrt")
    }

    fn list(v: &[f32]) -> String {
        v.iter().map(|x| format!("{x} ")).collect()
    }

    /// The two patches of tests/data/pbrt-v3/nurbscheck.cpp, as scene text.
    fn check_patches() -> [String; 2] {
        let z = [
            0.0, 0.3, -0.2, 0.5, 0.1, 0.4, 1.2, 0.8, -0.3, 0.2, -0.1, 0.9, 1.5, 0.6, 0.0, 0.2, 0.1,
            -0.4, 0.3, 0.5f32,
        ];
        let mut p = Vec::new();
        for v in 0..4 {
            for u in 0..5 {
                let (uf, vf) = (u as f32, v as f32);
                p.extend([0.5 * uf + 0.1 * vf, 0.6 * vf - 0.05 * uf * uf, z[v * 5 + u]]);
            }
        }
        let a = format!(
            r#"Shape "nurbs" "integer nu" 5 "integer uorder" 4 "float uknots" [0 0 0 0 0.3 1 1 1 1]
               "float u1" 0.9 "integer nv" 4 "integer vorder" 3 "float vknots" [0 0 0 0.6 1 1 1]
               "point3 P" [{}]"#,
            list(&p)
        );
        let h = 0.5f32.sqrt();
        let (cx, cy, wu) = (
            [1.0, 1.0, 0.0, -1.0, -1.0f32],
            [0.0, 1.0, 1.0, 1.0, 0.0f32],
            [1.0, h, 1.0, h, 1.0],
        );
        let (r, zz, wv) = (
            [1.0, 1.2, 0.9, 0.7f32],
            [0.0, 0.5, 1.2, 2.0f32],
            [1.0, 0.8, 1.3, 1.0f32],
        );
        let mut pw = Vec::new();
        for v in 0..4 {
            for u in 0..5 {
                let w = wu[u] * wv[v];
                pw.extend([r[v] * cx[u] * w, r[v] * cy[u] * w, zz[v] * w, w]);
            }
        }
        let b = format!(
            r#"Shape "nurbs" "integer nu" 5 "integer uorder" 3 "float uknots" [0 0 0 0.4 0.4 1 1 1]
               "integer nv" 4 "integer vorder" 3 "float vknots" [1 1 1 1.5 3 3 3]
               "float v0" 1.2 "float v1" 2.8 "float Pw" [{}]"#,
            list(&pw)
        );
        [a, b]
    }

    #[track_caller]
    fn close(a: &[f32], b: &[f32], eps: f32, what: &str) {
        for (x, y) in a.iter().zip(b) {
            assert!(
                (x - y).abs() <= eps * (1.0 + y.abs()),
                "{what}: {a:?} != pbrt-v3's {b:?}"
            );
        }
    }

    /// pbrt-v3's own meshes for a non-rational patch (cubic x quadratic, interior knots, a
    /// u sub-range) and a rational one (Pw, a double interior knot, knots not starting at 0,
    /// a v sub-range), printed by tests/data/pbrt-v3/nurbscheck.cpp (compiled against
    /// libpbrt.a as the other programs there): the same vertices, normals, uvs and
    /// triangles. (pbrt-v3 is built with -march=native, so its fused multiply-adds may change
    /// the last bits.)
    #[test]
    fn meshes_match_pbrt_v3() {
        let data = include_str!("../../tests/data/pbrt-v3/nurbs-mesh.txt");
        let mut lines = data.lines();
        let patches = check_patches();
        for (k, text) in patches.iter().enumerate() {
            let head: Vec<usize> = lines
                .next()
                .unwrap()
                .split_whitespace()
                .skip(1)
                .map(|w| w.parse().unwrap())
                .collect();
            assert_eq!(head, [k, DICE * DICE, 2 * (DICE - 1) * (DICE - 1)]);
            let (p, loc) = shape_params(text);
            let m = mesh_from_params(&p, &loc).unwrap();
            assert!(m.validate().is_ok());
            let (ns, uvs) = (m.normals.as_ref().unwrap(), m.uvs.as_ref().unwrap());
            for i in 0..DICE * DICE {
                let f: Vec<f32> = lines
                    .next()
                    .unwrap()
                    .split_whitespace()
                    .map(|w| w.parse().unwrap())
                    .collect();
                close(&m.positions[i], &f[0..3], 1e-6, "position");
                close(&ns[i], &f[3..6], 5e-6, "normal");
                close(&uvs[i], &f[6..8], 2e-7, "uv");
            }
            let idx: Vec<u32> = lines
                .next()
                .unwrap()
                .split_whitespace()
                .map(|w| w.parse().unwrap())
                .collect();
            assert_eq!(m.indices, idx);
        }
        assert!(lines.next().is_none());
    }

    /// A rational quadratic quarter circle swept along z: every vertex is on the unit
    /// cylinder with the outward normal, which a non-rational evaluation would miss.
    #[test]
    fn a_rational_patch_is_an_exact_quarter_cylinder() {
        let h = 0.5f32.sqrt();
        let (p, loc) = shape_params(&format!(
            r#"Shape "nurbs" "integer nu" 3 "integer uorder" 3 "float uknots" [0 0 0 1 1 1]
               "integer nv" 2 "integer vorder" 2 "float vknots" [0 0 1 1]
               "float Pw" [1 0 0 1  {h} {h} 0 {h}  0 1 0 1  1 0 2 1  {h} {h} {h2} {h}  0 1 2 1]"#,
            h2 = 2.0 * h
        ));
        let m = mesh_from_params(&p, &loc).unwrap();
        let ns = m.normals.as_ref().unwrap();
        for (q, n) in m.positions.iter().zip(ns) {
            let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
            assert!((r - 1.0).abs() < 1e-5, "{q:?}");
            assert!((0.0..=2.0).contains(&q[2]));
            // dp/du x dp/dv with u around the axis and v up: outward.
            close(n, &[q[0], q[1], 0.0], 1e-4, "normal");
        }
        assert_eq!(m.uvs.as_ref().unwrap()[DICE * DICE - 1], [1.0, 1.0]);
    }

    /// A patch closing at a pole (a bilinear pyramid with its top row of control points at
    /// the apex): dp/du vanishes on the apex's row, where pbrt-v3 fails an assertion; acr gives
    /// those vertices a zero normal, the others unit ones. (Where rounding leaves a tiny
    /// dp/du, as at the pole of a rational dome, both normalize it.)
    #[test]
    fn a_pole_gets_a_zero_normal() {
        let (p, loc) = shape_params(
            r#"Shape "nurbs" "integer nu" 3 "integer uorder" 2 "float uknots" [0 0 0.5 1 1]
               "integer nv" 2 "integer vorder" 2 "float vknots" [0 0 1 1]
               "point3 P" [1 0 0  0 1 0  -1 0 0  0 0 1  0 0 1  0 0 1]"#,
        );
        let m = mesh_from_params(&p, &loc).unwrap();
        let ns = m.normals.as_ref().unwrap();
        for (i, n) in ns.iter().enumerate() {
            if i >= DICE * (DICE - 1) {
                assert_eq!(*n, [0.0; 3]);
                assert_eq!(m.positions[i], [0.0, 0.0, 1.0]);
            } else {
                let len = Vec3::from_array(*n).length();
                assert!((len - 1.0).abs() < 1e-5, "{i}: {n:?}");
            }
        }
    }

    /// Too many repeated first knots make pbrt-v3's first knot span empty (it fails an
    /// assertion); acr evaluates in the next span instead of dividing by zero, and in the last
    /// non-empty one past too many repeated last knots.
    #[test]
    fn an_empty_first_knot_span_is_stepped_over() {
        let (p, loc) = shape_params(
            r#"Shape "nurbs" "integer nu" 4 "integer uorder" 3 "float uknots" [0 0 0 0 1 1 1]
               "integer nv" 2 "integer vorder" 2 "float vknots" [0 0 1 1]
               "point3 P" [0 0 0  1 0 0  2 0 1  3 0 0  0 1 0  1 1 0  2 1 1  3 1 0]"#,
        );
        let m = mesh_from_params(&p, &loc).unwrap();
        assert!(m.positions.iter().flatten().all(|c| c.is_finite()));
        assert_eq!(m.positions[0], [1.0, 0.0, 0.0]);
        // Likewise at the end, for a parameter rounded past too many repeated last knots.
        let d = Direction {
            order: 3,
            knots: vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
            n: 4,
        };
        assert_eq!(d.knot_offset(1.0), 2);
        assert_eq!(d.knot_offset(1.0 + f32::EPSILON), 2);
    }

    #[test]
    fn missing_or_inconsistent_parameters_are_located_errors() {
        let v = r#""integer nv" 2 "integer vorder" 2 "float vknots" [0 0 1 1]"#;
        let p4 = r#""point3 P" [0 0 0 1 0 0 0 1 0 1 1 0]"#;
        for (text, says) in [
            (
                format!(r#""integer uorder" 2 "float uknots" [0 0 1 1] {v} {p4}"#),
                "\"nu\"",
            ),
            (
                format!(r#""integer nu" 2 "float uknots" [0 0 1 1] {v} {p4}"#),
                "\"uorder\"",
            ),
            (
                format!(r#""integer nu" 2 "integer uorder" 2 {v} {p4}"#),
                "\"uknots\"",
            ),
            (
                format!(r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 0 1] {v} {p4}"#),
                "Number of knots in u knot vector 3",
            ),
            (
                format!(r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 0 1 1] {p4}"#),
                "\"nv\"",
            ),
            (
                r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 0 1 1]
                   "integer nv" 3 "integer vorder" 1 "float vknots" [0 1 2 3]"#
                    .to_string(),
                "v order at least 2",
            ),
            (
                format!(r#""integer nu" 1 "integer uorder" 2 "float uknots" [0 0 1] {v} {p4}"#),
                "at most the number of u control points",
            ),
            (
                format!(r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 1 0.5 1] {v} {p4}"#),
                "must not decrease",
            ),
            (
                format!(r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 0 0 0] {v} {p4}"#),
                "must be increasing",
            ),
            (
                format!(
                    r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 0 1 1] "float u0" 0.5
                       "float u1" 0.5 {v} {p4}"#
                ),
                "[0.5, 0.5]",
            ),
            (
                format!(
                    r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 0 1 1] "float u1" 1.5
                       {v} {p4}"#
                ),
                "within the knots' [0, 1]",
            ),
            (
                format!(r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 0 1 1] {v}"#),
                "\"P\" or \"Pw\"",
            ),
            (
                format!(
                    r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 0 1 1] {v}
                       "float Pw" [0 0 0 1 1 0 0 1 0 1 0]"#
                ),
                "multiple of four",
            ),
            (
                format!(
                    r#""integer nu" 2 "integer uorder" 2 "float uknots" [0 0 1 1] {v}
                       "point3 P" [0 0 0 1 0 0 0 1 0]"#
                ),
                "expecting 2x2=4 control points, was given 3",
            ),
        ] {
            let (p, loc) = shape_params(&format!(r#"Shape "nurbs" {text}"#));
            let e = mesh_from_params(&p, &loc).unwrap_err();
            assert!(e.to_string().contains(says), "{e}");
            assert!(e.to_string().contains("n.pbrt:"), "{e}");
        }
    }
}
