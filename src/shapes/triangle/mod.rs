//! Triangle meshes: pbrt-v3's watertight ray-triangle test (Woop, Benthin and Wald 2013) and
//! its triangle differential geometry, shading normals and area sampling.

use super::{coordinate_system, faceforward, Transform};
use crate::geometry::{Crossing, Ray, SurfaceInteraction, Vec2, Vec3};
use crate::sampling::uniform_sample_triangle;
use rayon::prelude::*;

mod intersect;
pub use intersect::{
    intersect_triangle, intersect_triangle_p, intersect_triangle_vertices,
    intersect_triangle_verts, TriangleHit, TriangleRay, TriangleVerts,
};

/// A triangle mesh with its vertices already in the space it is intersected in (world space for
/// static meshes, as pbrt-v3 stores them).
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (transformed, not normalised), if given.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, if given.
    pub uvs: Option<Vec<Vec2>>,
    /// Three vertex indices per triangle.
    pub indices: Vec<u32>,
    /// The shape's ReverseOrientation flag.
    pub reverse_orientation: bool,
    /// Whether the transform the vertices went through swaps handedness.
    pub transform_swaps_handedness: bool,
}

impl TriangleMesh {
    /// Transforms a parsed mesh's positions and normals (normals by the inverse transpose, as
    /// pbrt-v3 does) into the space of `to_world` once.
    pub fn from_mesh(
        mesh: &acr_parser::Mesh,
        to_world: &Transform,
        reverse_orientation: bool,
    ) -> Self {
        Self {
            positions: map_all(&mesh.positions, |&p| to_world.point(Vec3::from_array(p))),
            normals: mesh
                .normals
                .as_ref()
                .map(|ns| map_all(ns, |&n| to_world.normal(Vec3::from_array(n)))),
            uvs: mesh
                .uvs
                .as_ref()
                .map(|uvs| uvs.iter().map(|&uv| Vec2::from_array(uv)).collect()),
            indices: map_all(&mesh.indices, |&i| i),
            reverse_orientation,
            transform_swaps_handedness: to_world.swaps_handedness(),
        }
    }

    /// Number of triangles.
    #[inline]
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Vertex indices of triangle `tri`.
    #[inline]
    pub fn vertex_indices(&self, tri: usize) -> [usize; 3] {
        let i = &self.indices[3 * tri..3 * tri + 3];
        [i[0] as usize, i[1] as usize, i[2] as usize]
    }

    /// Vertex positions of triangle `tri`.
    #[inline]
    pub fn vertices(&self, tri: usize) -> [Vec3; 3] {
        let [a, b, c] = self.vertex_indices(tri);
        [self.positions[a], self.positions[b], self.positions[c]]
    }

    /// Texture coordinates of the triangle of vertices `at` (pbrt-v3's defaults (0,0),
    /// (1,0), (1,1)).
    #[inline]
    fn uvs_at(&self, at: &Corners) -> [Vec2; 3] {
        match &self.uvs {
            Some(uv) => {
                let [a, b, c] = at.indices(self);
                [uv[a], uv[b], uv[c]]
            }
            None => [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::ONE],
        }
    }
}

/// `f` of each item of `items`, in order: on every thread for a large mesh (a million
/// vertices took 20 ms on one), on this one for a small one (a parallel call costs
/// microseconds, and a scene may have thousands of meshes).
fn map_all<T: Sync, U: Send>(items: &[T], f: impl Fn(&T) -> U + Sync + Send) -> Vec<U> {
    if items.len() < 1 << 14 {
        return items.iter().map(f).collect();
    }
    items.par_iter().with_min_len(4096).map(f).collect()
}

/// A triangle of a mesh, with its vertices' indices when the caller already holds them
/// (from the traversal's record, [`TriangleVerts::indices`]): read from the mesh otherwise.
#[derive(Clone, Copy, Debug)]
pub struct Corners {
    /// The triangle's index in its mesh.
    pub tri: usize,
    /// Its vertices' indices, if known.
    pub known: Option<[usize; 3]>,
}

impl Corners {
    /// Triangle `tri`, its vertices' indices to be read from the mesh.
    #[inline]
    pub fn of(tri: usize) -> Self {
        Self { tri, known: None }
    }

    /// The vertices' indices.
    #[inline]
    fn indices(&self, mesh: &TriangleMesh) -> [usize; 3] {
        match self.known {
            Some(i) => i,
            None => mesh.vertex_indices(self.tri),
        }
    }
}

/// pbrt-v3's triangle dp/du and dp/dv from the vertex uvs, with its fallback (a coordinate
/// system around the normal) for degenerate uv mappings.
#[inline]
fn triangle_dpduv(p: &[Vec3; 3], uv: &[Vec2; 3]) -> (Vec3, Vec3) {
    let duv02 = uv[0] - uv[2];
    let duv12 = uv[1] - uv[2];
    let dp02 = p[0] - p[2];
    let dp12 = p[1] - p[2];
    let determinant = duv02.x * duv12.y - duv02.y * duv12.x;
    let degenerate_uv = determinant.abs() < 1e-8;
    let (mut dpdu, mut dpdv) = (Vec3::ZERO, Vec3::ZERO);
    if !degenerate_uv {
        let invdet = 1.0 / determinant;
        dpdu = (duv12.y * dp02 - duv02.y * dp12) * invdet;
        dpdv = (-duv12.x * dp02 + duv02.x * dp12) * invdet;
    }
    if degenerate_uv || dpdu.cross(dpdv).length_squared() == 0.0 {
        let (a, b) = coordinate_system((p[2] - p[0]).cross(p[1] - p[0]).normalize());
        dpdu = a;
        dpdv = b;
    }
    (dpdu, dpdv)
}

/// The interpolated, normalised shading normal at barycentrics `b`, if the mesh has normals and
/// the interpolation does not vanish.
#[inline]
pub fn shading_normal(mesh: &TriangleMesh, tri: usize, b: [f32; 3]) -> Option<Vec3> {
    shading_normal_at(mesh, &Corners::of(tri), b)
}

/// [`shading_normal`] of the triangle of vertices `at`.
#[inline]
fn shading_normal_at(mesh: &TriangleMesh, at: &Corners, b: [f32; 3]) -> Option<Vec3> {
    let normals = mesh.normals.as_ref()?;
    let [a, bb, c] = at.indices(mesh);
    let ns = b[0] * normals[a] + b[1] * normals[bb] + b[2] * normals[c];
    if ns.length_squared() > 0.0 {
        Some(ns.normalize())
    } else {
        None
    }
}

/// The full interaction of a triangle hit, as pbrt-v3's `Triangle::Intersect` builds it:
/// dp/du and dp/dv from the uvs; geometric normal normalize((p0 - p2) x (p1 - p2)), oriented and
/// with its shading frame as [`shading_geometry`] gives them.
pub fn triangle_interaction(
    mesh: &TriangleMesh,
    tri: usize,
    ray: &Ray,
    hit: &TriangleHit,
) -> SurfaceInteraction {
    triangle_interaction_at(mesh, &Corners::of(tri), mesh.vertices(tri), ray, hit)
}

/// [`triangle_interaction`] with the triangle's vertex positions `p` given (a copy the caller
/// already holds), and its vertices' indices if known: a mesh without normals or uvs is then
/// not read past its header, one with them not in its index list.
#[inline]
pub fn triangle_interaction_at(
    mesh: &TriangleMesh,
    at: &Corners,
    p: [Vec3; 3],
    ray: &Ray,
    hit: &TriangleHit,
) -> SurfaceInteraction {
    let uv = mesh.uvs_at(at);
    let (b0, b1, b2) = (hit.b0, hit.b1, hit.b2);
    let (dpdu, dpdv) = triangle_dpduv(&p, &uv);
    let p_hit = b0 * p[0] + b1 * p[1] + b2 * p[2];
    let uv_hit = b0 * uv[0] + b1 * uv[1] + b2 * uv[2];
    let n = (p[0] - p[2]).cross(p[1] - p[2]).normalize();
    let (n, shading_n, shading_dpdu, shading_dpdv) =
        shading_geometry(mesh, at, [b0, b1, b2], n, dpdu, dpdv);
    SurfaceInteraction {
        p: p_hit,
        n,
        uv: uv_hit,
        dpdu,
        dpdv,
        shading_n,
        shading_dpdu,
        shading_dpdv,
        dndu: Vec3::ZERO,
        dndv: Vec3::ZERO,
        wo: (-ray.d).normalize_or_zero(),
        time: ray.time,
        p_error: 0.0,
        diff: Default::default(),
    }
}

/// The oriented geometric normal and the shading frame (normal, dp/du, dp/dv) at barycentrics
/// `b` from the unoriented geometric normal `n` and the tangents: with vertex normals, the frame
/// from the interpolated normal (tangent: dp/du orthogonalised against it and, as pbrt-v3
/// computes it, negated) and `n` flipped into its hemisphere; without them, `n` flipped when
/// ReverseOrientation xor the transform swaps handedness.
#[inline]
fn shading_geometry(
    mesh: &TriangleMesh,
    at: &Corners,
    b: [f32; 3],
    n: Vec3,
    dpdu: Vec3,
    dpdv: Vec3,
) -> (Vec3, Vec3, Vec3, Vec3) {
    if mesh.normals.is_some() {
        let ns = shading_normal_at(mesh, at, b).unwrap_or(n);
        let mut ss = dpdu.normalize();
        let mut ts = ss.cross(ns);
        if ts.length_squared() > 0.0 {
            ts = ts.normalize();
            ss = ts.cross(ns);
        } else {
            (ss, ts) = coordinate_system(ns);
        }
        // SetShadingGeometry(ss, ts, .., orientationIsAuthoritative = true).
        let sn = ss.cross(ts).normalize();
        (faceforward(n, sn), sn, ss, ts)
    } else {
        let n = if mesh.reverse_orientation ^ mesh.transform_swaps_handedness {
            -n
        } else {
            n
        };
        (n, n, dpdu, dpdv)
    }
}

/// The point and oriented geometric normal of a triangle hit, as [`triangle_interaction`]
/// computes them; on a mesh without vertex normals, without its (u, v) or tangents.
#[inline]
pub fn triangle_crossing(
    mesh: &TriangleMesh,
    tri: usize,
    ray: &Ray,
    hit: &TriangleHit,
) -> Crossing {
    let p = mesh.vertices(tri);
    let p_hit = hit.b0 * p[0] + hit.b1 * p[1] + hit.b2 * p[2];
    let n = (p[0] - p[2]).cross(p[1] - p[2]).normalize();
    let n = if mesh.normals.is_some() {
        // The orientation follows the shading frame, which needs the tangents.
        let at = Corners::of(tri);
        let (dpdu, dpdv) = triangle_dpduv(&p, &mesh.uvs_at(&at));
        shading_geometry(mesh, &at, [hit.b0, hit.b1, hit.b2], n, dpdu, dpdv).0
    } else if mesh.reverse_orientation ^ mesh.transform_swaps_handedness {
        -n
    } else {
        n
    };
    Crossing {
        p: p_hit,
        n,
        p_error: 0.0,
        time: ray.time,
    }
}

/// Area of triangle `tri`.
#[inline]
pub fn triangle_area(mesh: &TriangleMesh, tri: usize) -> f32 {
    let [p0, p1, p2] = mesh.vertices(tri);
    0.5 * (p1 - p0).cross(p2 - p0).length()
}

/// A point uniformly distributed (by area) on triangle `tri` and the surface normal there
/// (pbrt-v3's `Triangle::Sample`: the interpolated shading normal when the mesh has normals,
/// else the geometric one). It is oriented like the geometric normal of an interaction at
/// that point: into the shading normal's hemisphere with vertex normals, else flipped by
/// ReverseOrientation xor handedness swap.
pub fn sample_triangle(mesh: &TriangleMesh, tri: usize, u: Vec2) -> (Vec3, Vec3) {
    let b = uniform_sample_triangle(u);
    let b2 = 1.0 - b.x - b.y;
    let [p0, p1, p2] = mesh.vertices(tri);
    let p = b.x * p0 + b.y * p1 + b2 * p2;
    let ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
    let n = if mesh.normals.is_some() {
        shading_normal(mesh, tri, [b.x, b.y, b2]).unwrap_or(ng)
    } else if mesh.reverse_orientation ^ mesh.transform_swaps_handedness {
        -ng
    } else {
        ng
    };
    (p, n)
}

/// Bounds of triangle `tri`.
#[inline]
pub fn triangle_bounds(mesh: &TriangleMesh, tri: usize) -> (Vec3, Vec3) {
    let [p0, p1, p2] = mesh.vertices(tri);
    (p0.min(p1).min(p2), p0.max(p1).max(p2))
}

#[cfg(test)]
mod tests;
