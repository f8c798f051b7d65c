//! pbrt-v3's watertight ray-triangle test (Woop, Benthin and Wald 2013), for a mesh's
//! triangle, for three vertices, and for a ray transformed once for many triangles.

use super::TriangleMesh;
use crate::geometry::{Ray, Vec3};
use crate::shapes::gamma;
use glam::{Vec3A, Vec3Swizzles, Vec4};

/// Where a ray meets a triangle: its parameter and barycentrics (p = b0 p0 + b1 p1 + b2 p2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter.
    pub t: f32,
    /// Barycentric weight of vertex 0.
    pub b0: f32,
    /// Barycentric weight of vertex 1.
    pub b1: f32,
    /// Barycentric weight of vertex 2.
    pub b2: f32,
}

/// pbrt-v3's `MaxDimension`.
#[inline]
fn max_dimension(v: Vec3) -> usize {
    if v.x > v.y {
        if v.x > v.z {
            0
        } else {
            2
        }
    } else if v.y > v.z {
        1
    } else {
        2
    }
}

/// pbrt-v3's watertight ray-triangle intersection: the vertices are translated to the ray
/// origin, permuted so that the ray's largest direction component is z, and sheared so that
/// the ray runs along +z; the edge functions are then evaluated in 2D (in double precision
/// when one is exactly 0) and the hit parameter is accepted only if it exceeds pbrt-v3's
/// conservative error bound. Hits with t beyond `t_max` are rejected; zero-area triangles are
/// never hit.
#[inline]
pub fn intersect_triangle(
    mesh: &TriangleMesh,
    tri: usize,
    ray: &Ray,
    t_max: f32,
) -> Option<TriangleHit> {
    intersect_triangle_vertices(&mesh.vertices(tri), &TriangleRay::new(ray), t_max)
}

/// What the watertight test needs of a ray, computed once per ray rather than per triangle:
/// its origin, the axis permutation that makes the largest direction component z, and the
/// shear that maps the direction to +z.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRay {
    o: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

impl TriangleRay {
    /// The per-ray constants of `ray`.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let kz = max_dimension(ray.d.abs());
        let kx = if kz + 1 == 3 { 0 } else { kz + 1 };
        let ky = if kx + 1 == 3 { 0 } else { kx + 1 };
        let d = Vec3::new(ray.d[kx], ray.d[ky], ray.d[kz]);
        Self {
            o: ray.o,
            kx,
            ky,
            kz,
            sx: -d.x / d.z,
            sy: -d.y / d.z,
            sz: 1.0 / d.z,
        }
    }
}

/// A triangle's vertices stored by coordinate (the x of all three, then the y, then the z),
/// so that the watertight test's per-vertex steps run on all three vertices at once. The
/// fourth lane of each row holds a vertex's index in its mesh (as a float, exact below 2^24;
/// -1 when unknown): a hit's shading normal and uvs are then read without the mesh's index
/// list, a dependent load fewer. A float, not the index's bits, because the test's lane
/// arithmetic runs over the fourth lane too, where bits read as denormals would be slow.
#[derive(Clone, Copy, Debug, Default)]
pub struct TriangleVerts {
    xyz: [Vec4; 3],
}

/// Indices from 2^24 on are not exact as floats: such a vertex's record says "unknown".
const INDEX_LIMIT: u32 = 1 << 24;

impl TriangleVerts {
    /// The record of a primitive that is not a triangle (NaN coordinates, which
    /// [`TriangleVerts::is_triangle`] tells apart).
    pub const NONE: Self = Self {
        xyz: [Vec4::NAN; 3],
    };

    /// False for [`TriangleVerts::NONE`] (and for a triangle with a NaN first x, which no ray
    /// hits either).
    #[inline(always)]
    pub fn is_triangle(&self) -> bool {
        !self.xyz[0].x.is_nan()
    }

    /// From the three vertex positions, their indices unknown.
    #[inline]
    pub fn new(p: &[Vec3; 3]) -> Self {
        Self::with_indices(p, None)
    }

    /// From the three vertex positions and, if given, their indices in the mesh.
    #[inline]
    pub fn with_indices(p: &[Vec3; 3], indices: Option<[u32; 3]>) -> Self {
        let [a, b, c] = *p;
        let w = match indices {
            Some(i) if i.iter().all(|&k| k < INDEX_LIMIT) => i.map(|k| k as f32),
            _ => [-1.0; 3],
        };
        Self {
            xyz: [
                Vec4::new(a.x, b.x, c.x, w[0]),
                Vec4::new(a.y, b.y, c.y, w[1]),
                Vec4::new(a.z, b.z, c.z, w[2]),
            ],
        }
    }

    /// Row `k` (the vertices' coordinate `k`) as the test computes on it.
    #[inline(always)]
    fn row(&self, k: usize) -> Vec3A {
        Vec3A::from_vec4(self.xyz[k])
    }

    /// Vertex `i`.
    #[inline]
    fn vertex(&self, i: usize) -> Vec3 {
        Vec3::new(self.xyz[0][i], self.xyz[1][i], self.xyz[2][i])
    }

    /// The three vertex positions (the same values as the mesh's).
    #[inline]
    pub fn vertices(&self) -> [Vec3; 3] {
        [self.vertex(0), self.vertex(1), self.vertex(2)]
    }

    /// The three vertices' indices in their mesh, when the record holds them.
    #[inline]
    pub fn indices(&self) -> Option<[usize; 3]> {
        let w = [self.xyz[0].w, self.xyz[1].w, self.xyz[2].w];
        (w[0] >= 0.0).then(|| w.map(|k| k as usize))
    }
}

/// [`intersect_triangle`] on the triangle's three vertices and a prepared ray.
#[inline]
pub fn intersect_triangle_vertices(
    p: &[Vec3; 3],
    r: &TriangleRay,
    t_max: f32,
) -> Option<TriangleHit> {
    intersect_triangle_verts(&TriangleVerts::new(p), r, t_max)
}

/// [`intersect_triangle`] on vertices stored by coordinate and a prepared ray.
#[inline(always)]
pub fn intersect_triangle_verts(
    v: &TriangleVerts,
    r: &TriangleRay,
    t_max: f32,
) -> Option<TriangleHit> {
    // One version per permutation: with the axes known at compile time, permuting the
    // vertices is a choice of rows instead of three indexed selections per coordinate.
    match (r.kx, r.ky, r.kz) {
        (1, 2, 0) => intersect_permuted::<1, 2, 0>(v, r, t_max),
        (2, 0, 1) => intersect_permuted::<2, 0, 1>(v, r, t_max),
        _ => intersect_permuted::<0, 1, 2>(v, r, t_max),
    }
}

/// [`intersect_triangle_verts`] for the ray's axis permutation (`KX`, `KY`, `KZ`). Lane `i`
/// of `xs`, `ys`, `zs` is vertex `i`'s transformed coordinate; every lane operation is the
/// scalar operation pbrt-v3 performs per vertex, so the results are the same bits.
#[inline(always)]
fn intersect_permuted<const KX: usize, const KY: usize, const KZ: usize>(
    v: &TriangleVerts,
    r: &TriangleRay,
    t_max: f32,
) -> Option<TriangleHit> {
    debug_assert_eq!((r.kx, r.ky, r.kz), (KX, KY, KZ));
    // Translate to the ray origin and permute.
    let mut xs = v.row(KX) - Vec3A::splat(r.o[KX]);
    let mut ys = v.row(KY) - Vec3A::splat(r.o[KY]);
    let zs = v.row(KZ) - Vec3A::splat(r.o[KZ]);

    // Shear so that the ray direction becomes +z.
    xs += Vec3A::splat(r.sx) * zs;
    ys += Vec3A::splat(r.sy) * zs;

    // Edge function coefficients: e_i from the two other vertices (i + 1, i + 2).
    let mut e = xs.yzx() * ys.zxy() - ys.yzx() * xs.zxy();
    let [p0x, p1x, p2x] = xs.to_array();
    let [p0y, p1y, p2y] = ys.to_array();

    // Fall back to double precision at triangle edges.
    if e.cmpeq(Vec3A::ZERO).any() {
        let p2txp1ty = p2x as f64 * p1y as f64;
        let p2typ1tx = p2y as f64 * p1x as f64;
        let e0 = (p2typ1tx - p2txp1ty) as f32;
        let p0txp2ty = p0x as f64 * p2y as f64;
        let p0typ2tx = p0y as f64 * p2x as f64;
        let e1 = (p0typ2tx - p0txp2ty) as f32;
        let p1txp0ty = p1x as f64 * p0y as f64;
        let p1typ0tx = p1y as f64 * p0x as f64;
        let e2 = (p1typ0tx - p1txp0ty) as f32;
        e = Vec3A::new(e0, e1, e2);
    }

    // Edge and determinant tests: edges of both signs miss. One branch on the lanes' signs
    // (most triangles a ray is tested against fail here, unpredictably).
    if e.cmplt(Vec3A::ZERO).any() & e.cmpgt(Vec3A::ZERO).any() {
        return None;
    }
    let (e0, e1, e2) = (e.x, e.y, e.z);
    let det = e0 + e1 + e2;
    // (NaN: a degenerate ray direction.)
    if det == 0.0 || det.is_nan() {
        return None;
    }

    // Scaled hit distance and the ray's t range.
    let [p0z, p1z, p2z] = (zs * Vec3A::splat(r.sz)).to_array();
    let t_scaled = e0 * p0z + e1 * p1z + e2 * p2z;
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return None;
    }

    // Barycentrics and t.
    let inv_det = 1.0 / det;
    let b0 = e0 * inv_det;
    let b1 = e1 * inv_det;
    let b2 = e2 * inv_det;
    let t = t_scaled * inv_det;

    // Ensure that t is conservatively greater than zero (pbrt-v3's error bounds).
    let max_zt = p0z.abs().max(p1z.abs()).max(p2z.abs());
    let delta_z = gamma(3) * max_zt;
    let max_xt = p0x.abs().max(p1x.abs()).max(p2x.abs());
    let max_yt = p0y.abs().max(p1y.abs()).max(p2y.abs());
    let delta_x = gamma(5) * (max_xt + max_zt);
    let delta_y = gamma(5) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t =
        3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    if t <= delta_t {
        return None;
    }

    // Zero-area triangles are kept in the mesh but never hit (their normal is undefined).
    let (p0, p1, p2) = (v.vertex(0), v.vertex(1), v.vertex(2));
    if (p0 - p2).cross(p1 - p2) == Vec3::ZERO {
        return None;
    }
    Some(TriangleHit { t, b0, b1, b2 })
}

/// Any-hit variant of [`intersect_triangle`] (for shadow rays).
#[inline]
pub fn intersect_triangle_p(mesh: &TriangleMesh, tri: usize, ray: &Ray, t_max: f32) -> bool {
    intersect_triangle(mesh, tri, ray, t_max).is_some()
}
