//! pbrt-v3's `curve`: cubic Bézier curves of varying width, intersected by recursive
//! subdivision in a coordinate system looking down the ray (pbrt-v3's `Curve::Intersect` and
//! `recursiveIntersect`), in three kinds: `flat` (a ribbon always facing the ray), `cylinder`
//! (flat, with a normal that turns across the width as a cylinder's would) and `ribbon` (oriented
//! by normals given at the ends). Each Bézier segment is split into 2^splitdepth pieces along u
//! that share its control points, as pbrt-v3 does, so that the BVH bounds them tightly.

use super::quadric::quadric_interaction;
use super::{coordinate_system, Transform};
use crate::geometry::{Mat3, Ray, SurfaceInteraction, Vec2, Vec3};
use acr_parser::{Error, Loc, ParamList, ParamType, Result, Warning};

/// How a curve's surface is oriented (pbrt-v3's `CurveType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveType {
    /// Always faces the ray.
    Flat,
    /// Faces the ray, shaded as a cylinder.
    Cylinder,
    /// Oriented by the normals at its ends.
    Ribbon,
}

/// What the pieces of one Bézier segment share (pbrt-v3's `CurveCommon`).
#[derive(Clone, Debug)]
pub struct CurveCommon {
    /// Object-space control points.
    pub cp: [Vec3; 4],
    /// Width at u = 0 and u = 1.
    pub width: [f32; 2],
    /// The kind of curve.
    pub kind: CurveType,
    /// Unit normals at the ends (ribbons).
    pub n: [Vec3; 2],
    /// The angle between the end normals.
    normal_angle: f32,
    /// 1 / sin(normal_angle).
    inv_sin_normal_angle: f32,
    /// Object to world.
    pub object_to_world: Transform,
    /// ReverseOrientation xor the transform swaps handedness.
    flip: bool,
    /// The transform's largest axis scale, to carry the spawn offset to world space.
    world_scale: f32,
}

/// One piece of a segment: its u range over the shared control points (pbrt-v3's `Curve`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curve {
    /// Index of its [`CurveCommon`].
    pub common: u32,
    /// Start of its u range.
    pub u_min: f32,
    /// End of its u range.
    pub u_max: f32,
}

/// Where a ray meets a curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveHit {
    /// Along the curve.
    pub u: f32,
    /// Across it, 0 to 1.
    pub v: f32,
}

/// pbrt-v3's `BlossomBezier`.
fn blossom(p: &[Vec3; 4], u0: f32, u1: f32, u2: f32) -> Vec3 {
    let a = [
        p[0].lerp(p[1], u0),
        p[1].lerp(p[2], u0),
        p[2].lerp(p[3], u0),
    ];
    let b = [a[0].lerp(a[1], u1), a[1].lerp(a[2], u1)];
    b[0].lerp(b[1], u2)
}

/// pbrt-v3's `SubdivideBezier`: the control points of the two halves, sharing the middle one.
fn subdivide(cp: &[Vec3; 4]) -> [Vec3; 7] {
    [
        cp[0],
        (cp[0] + cp[1]) / 2.0,
        (cp[0] + 2.0 * cp[1] + cp[2]) / 4.0,
        (cp[0] + 3.0 * cp[1] + 3.0 * cp[2] + cp[3]) / 8.0,
        (cp[1] + 2.0 * cp[2] + cp[3]) / 4.0,
        (cp[2] + cp[3]) / 2.0,
        cp[3],
    ]
}

/// pbrt-v3's `EvalBezier`: the point at u and the derivative (the chord where it vanishes).
fn eval(cp: &[Vec3; 4], u: f32) -> (Vec3, Vec3) {
    let c1 = [
        cp[0].lerp(cp[1], u),
        cp[1].lerp(cp[2], u),
        cp[2].lerp(cp[3], u),
    ];
    let c2 = [c1[0].lerp(c1[1], u), c1[1].lerp(c1[2], u)];
    let d = if (c2[1] - c2[0]).length_squared() > 0.0 {
        3.0 * (c2[1] - c2[0])
    } else {
        cp[3] - cp[0]
    };
    (c2[0].lerp(c2[1], u), d)
}

/// pbrt-v3's `LookAt(o, o + d, up)`: object space to a frame at the ray's origin whose z is
/// the ray's direction; returned as the rows of the rotation and the origin.
#[derive(Clone, Copy, Debug)]
struct RayFrame {
    rows: Mat3,
    origin: Vec3,
}

impl RayFrame {
    fn new(o: Vec3, d: Vec3, up: Vec3) -> Self {
        let dir = d.normalize();
        let right = up.normalize().cross(dir).normalize();
        let new_up = dir.cross(right);
        Self {
            rows: Mat3::from_cols(right, new_up, dir).transpose(),
            origin: o,
        }
    }

    fn point(&self, p: Vec3) -> Vec3 {
        self.rows * (p - self.origin)
    }

    fn vector(&self, v: Vec3) -> Vec3 {
        self.rows * v
    }

    fn inv_vector(&self, v: Vec3) -> Vec3 {
        self.rows.transpose() * v
    }
}

/// Whether the control points' box, grown by half the width, misses the ray (the ray-space
/// x = y = 0 line between z = 0 and z_max).
fn box_misses(cp: &[Vec3], half_width: f32, z_max: f32) -> bool {
    let lo = cp[0].min(cp[1]).min(cp[2]).min(cp[3]);
    let hi = cp[0].max(cp[1]).max(cp[2]).max(cp[3]);
    hi.y + half_width < 0.0
        || lo.y - half_width > 0.0
        || hi.x + half_width < 0.0
        || lo.x - half_width > 0.0
        || hi.z + half_width < 0.0
        || lo.z - half_width > z_max
}

/// pbrt-v3's rounded `Log2` of a float from its exponent bits (0 below 1).
fn log2_rounded(v: f32) -> i32 {
    if v < 1.0 || v.is_nan() {
        return 0;
    }
    let bits = v.to_bits();
    (bits >> 23) as i32 - 127 + i32::from(bits & (1 << 22) != 0)
}

impl CurveCommon {
    /// From object-space control points, end widths, the kind and (ribbons) end normals.
    pub fn new(
        cp: [Vec3; 4],
        width: [f32; 2],
        kind: CurveType,
        normals: Option<[Vec3; 2]>,
        object_to_world: Transform,
        reverse_orientation: bool,
    ) -> Self {
        let n = normals.map_or([Vec3::Z; 2], |n| [n[0].normalize(), n[1].normalize()]);
        let normal_angle = n[0].dot(n[1]).clamp(0.0, 1.0).acos();
        let m = object_to_world.m;
        let world_scale = m
            .x_axis
            .truncate()
            .length()
            .max(m.y_axis.truncate().length())
            .max(m.z_axis.truncate().length());
        Self {
            cp,
            width,
            kind,
            n,
            normal_angle,
            inv_sin_normal_angle: 1.0 / normal_angle.sin(),
            flip: reverse_orientation ^ object_to_world.swaps_handedness(),
            object_to_world,
            world_scale,
        }
    }

    /// The width at u.
    fn width_at(&self, u: f32) -> f32 {
        self.width[0] + (self.width[1] - self.width[0]) * u
    }

    /// The ribbon's normal at u: the end normals slerped (the first where they agree, where
    /// pbrt-v3 divides zero by zero).
    fn ribbon_normal(&self, u: f32) -> Vec3 {
        if self.normal_angle <= 1e-6 {
            return self.n[0];
        }
        let s0 = ((1.0 - u) * self.normal_angle).sin() * self.inv_sin_normal_angle;
        let s1 = (u * self.normal_angle).sin() * self.inv_sin_normal_angle;
        s0 * self.n[0] + s1 * self.n[1]
    }
}

impl Curve {
    /// The piece's own control points (blossoms of the segment's).
    fn control_points(&self, c: &CurveCommon) -> [Vec3; 4] {
        let (a, b) = (self.u_min, self.u_max);
        [
            blossom(&c.cp, a, a, a),
            blossom(&c.cp, a, a, b),
            blossom(&c.cp, a, b, b),
            blossom(&c.cp, b, b, b),
        ]
    }

    /// World-space bounds: the control points' box grown by half the larger width.
    pub fn world_bound(&self, c: &CurveCommon) -> (Vec3, Vec3) {
        let cp = self.control_points(c);
        let half = 0.5 * c.width_at(self.u_min).max(c.width_at(self.u_max));
        let lo = cp[0].min(cp[1]).min(cp[2]).min(cp[3]) - Vec3::splat(half);
        let hi = cp[0].max(cp[1]).max(cp[2]).max(cp[3]) + Vec3::splat(half);
        c.object_to_world.bounds(lo, hi)
    }

    /// The ray's frame for this piece (pbrt-v3's `objectToRay`).
    fn ray_frame(&self, c: &CurveCommon, o: Vec3, d: Vec3) -> RayFrame {
        let cp = self.control_points(c);
        let mut dx = d.cross(cp[3] - cp[0]);
        if dx.length_squared() == 0.0 {
            dx = coordinate_system(d.normalize()).0;
        }
        RayFrame::new(o, d, dx)
    }

    /// The closest hit with t in (0, t_max], as pbrt-v3 finds it: in the ray's frame, halving
    /// the curve to a depth set by its curvature, then the distance to the piece's chord.
    /// (pbrt-v3 keeps the last of several hits on one piece; this keeps the nearest.)
    pub fn intersect(&self, c: &CurveCommon, ray: &Ray, t_max: f32) -> Option<(f32, CurveHit)> {
        let o = c.object_to_world.inv_point(ray.o);
        let d = c.object_to_world.inv_vector(ray.d);
        let frame = self.ray_frame(c, o, d);
        let cp_obj = self.control_points(c);
        let cp = cp_obj.map(|p| frame.point(p));
        let max_width = c.width_at(self.u_min).max(c.width_at(self.u_max));
        let ray_length = d.length();
        let z_max = ray_length * t_max;
        if box_misses(&cp, 0.5 * max_width, z_max) {
            return None;
        }
        let mut l0 = 0.0f32;
        for i in 0..2 {
            let v = (cp[i] - 2.0 * cp[i + 1] + cp[i + 2]).abs();
            l0 = l0.max(v.max_element());
        }
        let eps = c.width[0].max(c.width[1]) * 0.05;
        let r0 = log2_rounded(std::f32::consts::SQRT_2 * 6.0 * l0 / (8.0 * eps)) / 2;
        let depth = r0.clamp(0, 10);
        let mut best = None;
        let mut z_limit = z_max;
        self.recurse(
            c,
            &cp,
            d,
            ray_length,
            self.u_min,
            self.u_max,
            depth,
            &mut z_limit,
            &mut best,
        );
        best
    }

    #[allow(clippy::too_many_arguments)]
    fn recurse(
        &self,
        c: &CurveCommon,
        cp: &[Vec3; 4],
        d: Vec3,
        ray_length: f32,
        u0: f32,
        u1: f32,
        depth: i32,
        z_max: &mut f32,
        best: &mut Option<(f32, CurveHit)>,
    ) {
        if depth > 0 {
            let split = subdivide(cp);
            let u = [u0, (u0 + u1) / 2.0, u1];
            for seg in 0..2 {
                let cps = [
                    split[3 * seg],
                    split[3 * seg + 1],
                    split[3 * seg + 2],
                    split[3 * seg + 3],
                ];
                let max_width = c.width_at(u[seg]).max(c.width_at(u[seg + 1]));
                if box_misses(&cps, 0.5 * max_width, *z_max) {
                    continue;
                }
                self.recurse(
                    c,
                    &cps,
                    d,
                    ray_length,
                    u[seg],
                    u[seg + 1],
                    depth - 1,
                    z_max,
                    best,
                );
            }
            return;
        }
        // The ray must pass between the perpendiculars at the ends.
        let edge = (cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x);
        if edge < 0.0 {
            return;
        }
        let edge = (cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x);
        if edge < 0.0 {
            return;
        }
        let seg = Vec2::new(cp[3].x - cp[0].x, cp[3].y - cp[0].y);
        let denom = seg.length_squared();
        if denom == 0.0 {
            return;
        }
        let w = Vec2::new(-cp[0].x, -cp[0].y).dot(seg) / denom;
        let u = (u0 + (u1 - u0) * w).clamp(u0, u1);
        let mut hit_width = c.width_at(u);
        if c.kind == CurveType::Ribbon {
            hit_width *= c.ribbon_normal(u).dot(d).abs() / ray_length;
        }
        let (pc, dpcdw) = eval(cp, w.clamp(0.0, 1.0));
        let dist2 = pc.x * pc.x + pc.y * pc.y;
        if dist2 > hit_width * hit_width * 0.25 || pc.z < 0.0 || pc.z > *z_max {
            return;
        }
        let dist = dist2.sqrt();
        let edge_func = dpcdw.x * -pc.y + pc.x * dpcdw.y;
        let v = if edge_func > 0.0 {
            0.5 + dist / hit_width
        } else {
            0.5 - dist / hit_width
        };
        let t = pc.z / ray_length;
        if t > 0.0 {
            *z_max = pc.z;
            *best = Some((t, CurveHit { u, v }));
        }
    }

    /// The interaction at a hit: pbrt-v3's dp/du (the curve's tangent) and dp/dv (across the
    /// width: in the plane facing the ray, turned about dp/du for cylinders, along n x dp/du
    /// for ribbons), n = normalize(dpdu x dpdv); the spawn offset is pbrt-v3's error bound, two
    /// widths.
    pub fn interaction(
        &self,
        c: &CurveCommon,
        ray: &Ray,
        t: f32,
        hit: &CurveHit,
    ) -> SurfaceInteraction {
        let o = c.object_to_world.inv_point(ray.o);
        let d = c.object_to_world.inv_vector(ray.d);
        let (_, dpdu) = eval(&c.cp, hit.u);
        let mut hit_width = c.width_at(hit.u);
        let dpdv = if c.kind == CurveType::Ribbon {
            let n = c.ribbon_normal(hit.u);
            hit_width *= n.dot(d).abs() / d.length();
            n.cross(dpdu).normalize_or_zero() * hit_width
        } else {
            let frame = self.ray_frame(c, o, d);
            let dpdu_plane = frame.vector(dpdu);
            let mut dpdv_plane =
                Vec3::new(-dpdu_plane.y, dpdu_plane.x, 0.0).normalize_or_zero() * hit_width;
            if c.kind == CurveType::Cylinder {
                let theta = -90.0 + 180.0 * hit.v;
                let rot = Mat3::from_axis_angle(dpdu_plane.normalize(), (-theta).to_radians());
                dpdv_plane = rot * dpdv_plane;
            }
            frame.inv_vector(dpdv_plane)
        };
        let mut si = quadric_interaction(
            &c.object_to_world,
            c.flip,
            ray,
            o + d * t,
            Vec2::new(hit.u, hit.v),
            dpdu,
            dpdv,
            None,
        );
        si.p_error = 2.0 * hit_width * c.world_scale;
        si
    }
}

/// pbrt-v3's `CreateCurveShape`: the segments' shared data and their pieces, from `P` in the
/// `bezier` or `bspline` basis of degree 2 or 3, `width`/`width0`/`width1`, `type`, `N` (ribbons)
/// and `splitdepth`. Malformed parameters are located errors.
pub fn from_params(
    params: &ParamList,
    loc: &Loc,
    object_to_world: Transform,
    reverse_orientation: bool,
    warnings: &mut Vec<Warning>,
) -> Result<Vec<(CurveCommon, Vec<Curve>)>> {
    let width = params.float_or("width", 1.0)? as f32;
    let width0 = params.float_or("width0", width as f64)? as f32;
    let width1 = params.float_or("width1", width as f64)? as f32;
    let degree = curve_degree(params, loc)?;
    let basis = Basis::from_params(params, loc)?;
    let cp = control_points(params, loc)?;
    let segments = basis.segments(cp.len(), degree, params, loc)?;
    let kind = curve_type(params, loc, warnings)?;
    let normals = ribbon_normals(params, loc, kind, segments, warnings)?;
    let pieces = 1usize << split_depth(params)?.clamp(0, 10);
    let mut out = Vec::with_capacity(segments);
    for seg in 0..segments {
        let w = |i: usize| width0 + (width1 - width0) * (i as f32 / segments as f32);
        let common = CurveCommon::new(
            basis.bezier(&cp, degree, seg),
            [w(seg), w(seg + 1)],
            kind,
            normals.as_ref().map(|n| [n[seg], n[seg + 1]]),
            object_to_world,
            reverse_orientation,
        );
        let pieces: Vec<Curve> = (0..pieces)
            .map(|i| Curve {
                common: 0,
                u_min: i as f32 / pieces as f32,
                u_max: (i + 1) as f32 / pieces as f32,
            })
            .collect();
        out.push((common, pieces));
    }
    Ok(out)
}

/// Where parameter `name` was written, else where the shape was.
fn param_loc(params: &ParamList, loc: &Loc, name: &str) -> Loc {
    params
        .get(name)
        .map_or_else(|| loc.clone(), |p| p.loc.clone())
}

/// The curve's `degree`: 2 or 3.
fn curve_degree(params: &ParamList, loc: &Loc) -> Result<usize> {
    let degree = params.int_or("degree", 3)?;
    if degree != 2 && degree != 3 {
        return Err(Error::at(
            &param_loc(params, loc, "degree"),
            format!("curve: degree {degree}; only degree 2 and 3 curves are supported"),
        ));
    }
    Ok(degree as usize)
}

/// The control points `P`, which a curve must have.
fn control_points(params: &ParamList, loc: &Loc) -> Result<Vec<Vec3>> {
    let Some(flat) = params.numbers("P", ParamType::Point3)? else {
        return Err(Error::at(
            loc,
            "curve needs its control points \"point3 P\"",
        ));
    };
    Ok(vec3s(flat))
}

/// Three numbers at a time as vectors.
fn vec3s(flat: &[f64]) -> Vec<Vec3> {
    flat.chunks_exact(3)
        .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
        .collect()
}

/// The basis the control points are in (`basis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Basis {
    /// Bézier segments sharing their end points.
    Bezier,
    /// A uniform b-spline.
    BSpline,
}

impl Basis {
    /// The `basis` parameter: `bezier` (the default) or `bspline`.
    fn from_params(params: &ParamList, loc: &Loc) -> Result<Basis> {
        match params.string("basis")?.unwrap_or("bezier") {
            "bezier" => Ok(Basis::Bezier),
            "bspline" => Ok(Basis::BSpline),
            basis => Err(Error::at(
                &param_loc(params, loc, "basis"),
                format!("curve: basis \"{basis}\"; only \"bezier\" and \"bspline\" are supported"),
            )),
        }
    }

    /// How many segments `ncp` control points of `degree` make; an error at `P` when the
    /// count does not fit the basis.
    fn segments(self, ncp: usize, degree: usize, params: &ParamList, loc: &Loc) -> Result<usize> {
        let at = || param_loc(params, loc, "P");
        match self {
            Basis::Bezier => {
                if ncp < degree + 1 || (ncp - 1 - degree) % degree != 0 {
                    return Err(Error::at(
                        &at(),
                        format!(
                            "curve: {ncp} control points; the degree {degree} Bezier basis needs \
                             {} + n * {degree}, for n >= 0",
                            degree + 1
                        ),
                    ));
                }
                Ok((ncp - 1) / degree)
            }
            Basis::BSpline => {
                if ncp < degree + 1 {
                    return Err(Error::at(
                        &at(),
                        format!(
                            "curve: {ncp} control points; the degree {degree} b-spline basis \
                             needs at least {}",
                            degree + 1
                        ),
                    ));
                }
                Ok(ncp - degree)
            }
        }
    }

    /// The cubic Bézier control points of segment `seg` of `cp` (degree 2 elevated to 3,
    /// b-splines converted), as pbrt-v3 computes them.
    fn bezier(self, cp: &[Vec3], degree: usize, seg: usize) -> [Vec3; 4] {
        let lerp = |t: f32, a: Vec3, b: Vec3| a.lerp(b, t);
        match (self, degree) {
            (Basis::Bezier, 2) => {
                let b = &cp[seg * degree..];
                [
                    b[0],
                    lerp(2.0 / 3.0, b[0], b[1]),
                    lerp(1.0 / 3.0, b[1], b[2]),
                    b[2],
                ]
            }
            (Basis::Bezier, _) => {
                let b = &cp[seg * degree..];
                [b[0], b[1], b[2], b[3]]
            }
            (Basis::BSpline, 2) => {
                let b = &cp[seg..];
                let p11 = lerp(0.5, b[0], b[1]);
                let p22 = lerp(0.5, b[1], b[2]);
                [
                    p11,
                    lerp(2.0 / 3.0, p11, b[1]),
                    lerp(1.0 / 3.0, b[1], p22),
                    p22,
                ]
            }
            (Basis::BSpline, _) => {
                let b = &cp[seg..];
                let p122 = lerp(2.0 / 3.0, b[0], b[1]);
                let p223 = lerp(1.0 / 3.0, b[1], b[2]);
                let p233 = lerp(2.0 / 3.0, b[1], b[2]);
                let p334 = lerp(1.0 / 3.0, b[2], b[3]);
                [lerp(0.5, p122, p223), p223, p233, lerp(0.5, p233, p334)]
            }
        }
    }
}

/// The curve's `type`; an unknown one warns and is a cylinder, as in pbrt-v3.
fn curve_type(params: &ParamList, loc: &Loc, warnings: &mut Vec<Warning>) -> Result<CurveType> {
    Ok(match params.string("type")?.unwrap_or("flat") {
        "flat" => CurveType::Flat,
        "ribbon" => CurveType::Ribbon,
        "cylinder" => CurveType::Cylinder,
        other => {
            warnings.push(Warning::at(
                &param_loc(params, loc, "type"),
                format!("curve: unknown type \"{other}\"; using \"cylinder\", as pbrt-v3 does"),
            ));
            CurveType::Cylinder
        }
    })
}

/// A ribbon's normals `N`, one at each segment end, which it must have; other kinds ignore
/// them with a warning.
fn ribbon_normals(
    params: &ParamList,
    loc: &Loc,
    kind: CurveType,
    segments: usize,
    warnings: &mut Vec<Warning>,
) -> Result<Option<Vec<Vec3>>> {
    let at = || param_loc(params, loc, "N");
    match params.numbers("N", ParamType::Normal)? {
        Some(_) if kind != CurveType::Ribbon => {
            warnings.push(Warning::at(
                &at(),
                "curve: normals are only used with \"ribbon\" curves; ignored",
            ));
            Ok(None)
        }
        Some(n) => {
            let n = vec3s(n);
            if n.len() != segments + 1 {
                return Err(Error::at(
                    &at(),
                    format!(
                        "curve: {} normals; ribbon curves with {segments} segments need {}",
                        n.len(),
                        segments + 1
                    ),
                ));
            }
            Ok(Some(n))
        }
        None if kind == CurveType::Ribbon => Err(Error::at(
            loc,
            "ribbon curves need normals \"N\" at the segment ends",
        )),
        None => Ok(None),
    }
}

/// `splitdepth` (default 3): pbrt-v3 reads it as an integer, or failing that as a float.
fn split_depth(params: &ParamList) -> Result<i32> {
    Ok(match params.int("splitdepth") {
        Ok(Some(s)) => s,
        Ok(None) => 3,
        Err(_) => params.float_or("splitdepth", 3.0)? as i32,
    })
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;
    use crate::geometry::Mat4;

    fn shape_params(text: &str) -> (ParamList, Loc) {
        super::super::test_util::shape_params(text, "c.pbrt")
    }

    /// The three curves of `tests/data/pbrt-v3/curvecheck.cpp`, placed as there.
    fn curves() -> Vec<Vec<(CurveCommon, Vec<Curve>)>> {
        let texts = [
            r#"Shape "curve" "point3 P" [-1 -0.5 0  -0.5 0.8 0.3  0 -0.6 -0.2  0.3 0.1 0.4
                0.6 0.7 0.1  0.9 -0.3 0.2  1.1 0.4 -0.3] "float width0" 0.25
                "float width1" 0.08 "string type" "flat""#,
            r#"Shape "curve" "point3 P" [-0.9 0 -0.6  -0.4 0.5 0.2  0.1 -0.4 0.5  0.5 0.3 -0.1
                1.0 -0.2 0.3] "float width" 0.3 "string type" "cylinder"
                "string basis" "bspline" "integer splitdepth" 2"#,
            r#"Shape "curve" "point3 P" [-1 0 0  -0.3 0.6 0.2  0.4 -0.5 0.1  0.7 0.2 0.5
                1.0 0.5 -0.2] "float width" 0.35 "string type" "ribbon" "integer degree" 2
                "normal N" [0 0 1  0.3 0.2 1  -0.5 0.6 0.4]"#,
        ];
        let transforms = [
            Mat4::from_translation(Vec3::new(0.1, 0.2, -0.3))
                * Mat4::from_rotation_z(25f32.to_radians()),
            Mat4::from_rotation_y(-20f32.to_radians()) * Mat4::from_scale(Vec3::new(1.0, 1.5, 1.0)),
            Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)),
        ];
        texts
            .iter()
            .zip(transforms)
            .enumerate()
            .map(|(i, (text, m))| {
                let (p, loc) = shape_params(text);
                let mut warnings = Vec::new();
                let c = from_params(&p, &loc, Transform::new(m), i == 1, &mut warnings).unwrap();
                assert!(warnings.is_empty(), "{warnings:?}");
                c
            })
            .collect()
    }

    /// Rays against pbrt-v3's own curves (flat Bézier with tapering width, a reversed cylinder
    /// in the b-spline basis, a degree-2 ribbon with turning normals; transformed, one
    /// mirrored): the same hits and misses, t, point, normal, uv, dp/du and dp/dv.
    #[test]
    fn hits_match_pbrt_v3() {
        let curves = curves();
        let data = include_str!("../../tests/data/pbrt-v3/curve-hits.txt");
        let (mut hits, mut total) = ([0; 3], [0; 3]);
        for line in data.lines() {
            let w: Vec<&str> = line.split_whitespace().collect();
            if w[0] == "pieces" {
                let s: usize = w[1].parse().unwrap();
                let n: usize = curves[s].iter().map(|(_, p)| p.len()).sum();
                assert_eq!(n.to_string(), w[2], "pieces of curve {s}");
                continue;
            }
            let f = |i: usize| -> f32 { w[i].parse().unwrap() };
            let v3 = |i: usize| Vec3::new(f(i), f(i + 1), f(i + 2));
            let s: usize = w[0].parse().unwrap();
            total[s] += 1;
            let ray = Ray::new(v3(1), v3(4), 0.0);
            let mut best = None;
            let mut t_max = f32::INFINITY;
            for (common, pieces) in &curves[s] {
                for piece in pieces {
                    if let Some((t, h)) = piece.intersect(common, &ray, t_max) {
                        t_max = t;
                        best = Some((common, piece, t, h));
                    }
                }
            }
            if w[7] == "miss" {
                assert!(best.is_none(), "acr hits where pbrt-v3 misses:\n{line}");
                continue;
            }
            let (common, piece, t, h) =
                best.unwrap_or_else(|| panic!("acr misses where pbrt-v3 hits:\n{line}"));
            hits[s] += 1;
            assert!((t - f(8)).abs() <= 1e-4 * f(8), "t {t}\n{line}");
            let si = piece.interaction(common, &ray, t, &h);
            close_rel(si.p, v3(9), 1e-4, "p", line);
            close_rel(si.n, v3(12), 1e-3, "n", line);
            close(si.uv.x, f(15), 1e-4);
            close(si.uv.y, f(16), 2e-3);
            close_rel(si.dpdu, v3(17), 1e-4, "dpdu", line);
            close_rel(si.dpdv, v3(20), 1e-3, "dpdv", line);
            assert!(si.p_error > 0.0);
        }
        assert_eq!(hits, [52, 47, 42]);
        assert_eq!(total, [400; 3]);
    }

    #[test]
    fn malformed_curves_are_located_errors() {
        for (text, says) in [
            (
                r#"Shape "curve" "point3 P" [0 0 0 1 0 0 2 0 0]"#,
                "3 control points",
            ),
            (
                r#"Shape "curve" "point3 P" [0 0 0 1 0 0 2 0 0 3 0 0] "integer degree" 4"#,
                "degree 4",
            ),
            (
                r#"Shape "curve" "point3 P" [0 0 0 1 0 0 2 0 0 3 0 0] "string basis" "hermite""#,
                "basis",
            ),
            (
                r#"Shape "curve" "point3 P" [0 0 0 1 0 0 2 0 0 3 0 0] "string type" "ribbon""#,
                "normals",
            ),
            (
                r#"Shape "curve" "point3 P" [0 0 0 1 0 0 2 0 0 3 0 0] "string type" "ribbon"
                    "normal N" [0 0 1]"#,
                "1 normals",
            ),
            (r#"Shape "curve" "float width" 1"#, "control points"),
        ] {
            let (p, loc) = shape_params(text);
            let e = from_params(&p, &loc, Transform::IDENTITY, false, &mut Vec::new())
                .err()
                .unwrap_or_else(|| panic!("no error for {text}"));
            assert!(e.to_string().contains(says), "{e}");
            assert!(e.to_string().starts_with("c.pbrt:"), "{e}");
        }
        // Parallel ribbon normals (pbrt-v3 divides 0 by 0 there) give finite hits.
        let (p, loc) = shape_params(
            r#"Shape "curve" "point3 P" [0 0 0 1 0 0 2 0 0 3 0 0] "string type" "ribbon"
                "normal N" [0 0 1 0 0 1] "float width" 0.5"#,
        );
        let c = from_params(&p, &loc, Transform::IDENTITY, false, &mut Vec::new()).unwrap();
        let ray = Ray::new(Vec3::new(1.5, 0.1, 3.0), -Vec3::Z, 0.0);
        let (common, pieces) = &c[0];
        let (t, h) = pieces
            .iter()
            .find_map(|piece| piece.intersect(common, &ray, f32::INFINITY))
            .unwrap();
        close(t, 3.0, 1e-5);
        assert!(h.v.is_finite());
    }
}
