//! pbrt-v3's `loopsubdiv` shape: a triangle mesh refined by Loop subdivision, its vertices
//! pushed to the limit surface and given the limit surface's normals, as
//! `src/shapes/loopsubdiv.cpp` of pbrt-v3 computes them. The result is a plain triangle mesh
//! with per-vertex normals, rendered like a `trianglemesh`.
//!
//! The mesh is kept in index-based arrays that mirror pbrt-v3's `SDVertex`/`SDFace`
//! structures: each face knows its three vertices and the three faces across its edges
//! (edge `k` runs from `v[k]` to `v[k + 1]`); the children of face `i` at the next level are
//! faces `4 i .. 4 i + 3` (the same order pbrt-v3 allocates them in), and the child of vertex
//! `i` (its "even" vertex) is vertex `i` of the next level, followed by the new "odd" edge
//! vertices in the order pbrt-v3 creates them.

use crate::geometry::Vec3;
use acr_parser::{Error, Loc, Mesh, ParamList, ParamType, Result, Warning};
use std::collections::HashMap;
use std::f32::consts::PI;

/// The most subdivision levels accepted: each level multiplies the triangle count by 4.
pub const MAX_LEVELS: i32 = 10;

/// The most triangles a subdivided mesh may have (input faces times 4^levels).
pub const MAX_TRIANGLES: u64 = 1 << 26;

/// No face (a boundary edge) or no vertex.
const NONE: u32 = u32::MAX;

#[inline]
fn next(i: usize) -> usize {
    (i + 1) % 3
}

#[inline]
fn prev(i: usize) -> usize {
    (i + 2) % 3
}

/// A vertex of one subdivision level.
#[derive(Clone, Copy, Debug)]
struct SdVertex {
    p: Vec3,
    /// One face around the vertex.
    start_face: u32,
    regular: bool,
    boundary: bool,
}

/// A triangle of one subdivision level.
#[derive(Clone, Copy, Debug)]
struct SdFace {
    /// Vertices, counter-clockwise as given.
    v: [u32; 3],
    /// `f[k]`: the face across the edge from `v[k]` to `v[k + 1]`, or [`NONE`].
    f: [u32; 3],
}

/// pbrt-v3's `beta`: the one-ring weight of an even vertex of this valence.
#[inline]
fn beta(valence: usize) -> f32 {
    if valence == 3 {
        3.0 / 16.0
    } else {
        3.0 / (8.0 * valence as f32)
    }
}

/// pbrt-v3's `loopGamma`: the one-ring weight that moves a vertex to the limit surface.
#[inline]
fn loop_gamma(valence: usize) -> f32 {
    1.0 / (valence as f32 + 3.0 / (8.0 * beta(valence)))
}

/// One level of the subdivision mesh. Invariants (established by [`Level::new`] and kept by
/// [`Level::refine`]): faces have three distinct vertices, every vertex is in some face and its
/// `start_face` is one of them, and two faces are linked across an edge only when they share it
/// with opposite orientations and no other face has it.
struct Level {
    verts: Vec<SdVertex>,
    faces: Vec<SdFace>,
}

impl Level {
    /// Builds the base level; `faces` must have distinct vertices, all below `positions.len()`,
    /// and every vertex must be used. Errors for edges with more than two faces and for
    /// neighbouring faces of opposite orientation.
    fn new(positions: Vec<Vec3>, tris: &[[u32; 3]]) -> std::result::Result<Self, String> {
        let mut verts: Vec<SdVertex> = positions
            .into_iter()
            .map(|p| SdVertex {
                p,
                start_face: NONE,
                regular: false,
                boundary: false,
            })
            .collect();
        let mut faces: Vec<SdFace> = Vec::with_capacity(tris.len());
        for (i, t) in tris.iter().enumerate() {
            for &v in t {
                verts[v as usize].start_face = i as u32;
            }
            faces.push(SdFace {
                v: *t,
                f: [NONE; 3],
            });
        }
        // Link neighbours. Value: the first face seen with the edge, its edge number, and
        // whether a second face has been linked to it.
        let mut edges: HashMap<(u32, u32), (u32, u8, bool)> =
            HashMap::with_capacity(tris.len() * 2);
        for i in 0..faces.len() {
            for k in 0..3 {
                let (a, b) = (faces[i].v[k], faces[i].v[next(k)]);
                let key = (a.min(b), a.max(b));
                match edges.get_mut(&key) {
                    None => {
                        edges.insert(key, (i as u32, k as u8, false));
                    }
                    Some(e) => {
                        if e.2 {
                            return Err(format!(
                                "the edge between vertices {} and {} is shared by more than \
                                 two faces (the mesh is not manifold)",
                                key.0, key.1
                            ));
                        }
                        let (f0, k0) = (e.0 as usize, e.1 as usize);
                        if faces[f0].v[k0] != b {
                            return Err(format!(
                                "faces {f0} and {i} run through their shared edge (vertices {} \
                                 and {}) in the same direction: the faces are not consistently \
                                 oriented",
                                key.0, key.1
                            ));
                        }
                        e.2 = true;
                        faces[f0].f[k0] = i as u32;
                        faces[i].f[k] = f0 as u32;
                    }
                }
            }
        }
        let mut level = Level { verts, faces };
        for v in 0..level.verts.len() as u32 {
            let start = level.verts[v as usize].start_face;
            let mut f = start;
            for _ in 0..level.faces.len() {
                f = level.next_face(f, v);
                if f == NONE || f == start {
                    break;
                }
            }
            let boundary = f == NONE;
            level.verts[v as usize].boundary = boundary;
            let valence = level.valence(v);
            level.verts[v as usize].regular =
                (!boundary && valence == 6) || (boundary && valence == 4);
        }
        Ok(level)
    }

    /// Which of face `face`'s vertices `v` is (pbrt-v3's `vnum`).
    #[inline]
    fn vnum(&self, face: u32, v: u32) -> usize {
        let fv = &self.faces[face as usize].v;
        debug_assert!(fv.contains(&v), "vertex {v} not in face {face}");
        if fv[0] == v {
            0
        } else if fv[1] == v {
            1
        } else {
            2
        }
    }

    #[inline]
    fn next_face(&self, face: u32, v: u32) -> u32 {
        self.faces[face as usize].f[self.vnum(face, v)]
    }

    #[inline]
    fn prev_face(&self, face: u32, v: u32) -> u32 {
        self.faces[face as usize].f[prev(self.vnum(face, v))]
    }

    #[inline]
    fn next_vert(&self, face: u32, v: u32) -> u32 {
        self.faces[face as usize].v[next(self.vnum(face, v))]
    }

    #[inline]
    fn prev_vert(&self, face: u32, v: u32) -> u32 {
        self.faces[face as usize].v[prev(self.vnum(face, v))]
    }

    /// The vertex of `face` that is neither `v0` nor `v1`.
    #[inline]
    fn other_vert(&self, face: u32, v0: u32, v1: u32) -> u32 {
        let fv = self.faces[face as usize].v;
        fv.into_iter()
            .find(|&v| v != v0 && v != v1)
            .unwrap_or(fv[0])
    }

    /// pbrt-v3's `SDVertex::valence`. Walks are bounded by the face count (they end by
    /// themselves under the invariants; the bound only guards against a broken mesh).
    fn valence(&self, v: u32) -> usize {
        let vert = &self.verts[v as usize];
        let start = vert.start_face;
        if start == NONE {
            return 0;
        }
        let limit = self.faces.len();
        let mut nf = 1;
        let mut f = start;
        if !vert.boundary {
            for _ in 0..limit {
                f = self.next_face(f, v);
                if f == start || f == NONE {
                    break;
                }
                nf += 1;
            }
            nf
        } else {
            for _ in 0..limit {
                f = self.next_face(f, v);
                if f == NONE {
                    break;
                }
                nf += 1;
            }
            f = start;
            for _ in 0..limit {
                f = self.prev_face(f, v);
                if f == NONE {
                    break;
                }
                nf += 1;
            }
            nf + 1
        }
    }

    /// pbrt-v3's `SDVertex::oneRing`: the positions of the vertices around `v` into `ring`
    /// (cleared first); its length is the valence.
    fn one_ring(&self, v: u32, ring: &mut Vec<Vec3>) {
        ring.clear();
        let vert = &self.verts[v as usize];
        let start = vert.start_face;
        if start == NONE {
            return;
        }
        let limit = self.faces.len();
        let p = |i: u32| self.verts[i as usize].p;
        if !vert.boundary {
            let mut face = start;
            for _ in 0..limit {
                ring.push(p(self.next_vert(face, v)));
                face = self.next_face(face, v);
                if face == start || face == NONE {
                    break;
                }
            }
        } else {
            let mut face = start;
            for _ in 0..limit {
                let f2 = self.next_face(face, v);
                if f2 == NONE {
                    break;
                }
                face = f2;
            }
            ring.push(p(self.next_vert(face, v)));
            for _ in 0..limit {
                ring.push(p(self.prev_vert(face, v)));
                face = self.prev_face(face, v);
                if face == NONE {
                    break;
                }
            }
        }
    }

    /// pbrt-v3's `weightOneRing` given the ring of `v`.
    #[inline]
    fn weight_one_ring(&self, v: u32, ring: &[Vec3], beta: f32) -> Vec3 {
        let mut p = (1.0 - ring.len() as f32 * beta) * self.verts[v as usize].p;
        for &r in ring {
            p += beta * r;
        }
        p
    }

    /// pbrt-v3's `weightBoundary` given the ring of `v`.
    #[inline]
    fn weight_boundary(&self, v: u32, ring: &[Vec3], beta: f32) -> Vec3 {
        let mut p = (1.0 - 2.0 * beta) * self.verts[v as usize].p;
        if let (Some(&first), Some(&last)) = (ring.first(), ring.last()) {
            p += beta * first;
            p += beta * last;
        }
        p
    }

    /// One step of Loop subdivision: every face split in four, even vertices moved by the
    /// one-ring (interior) or boundary rule, odd vertices placed on the edges.
    fn refine(&self) -> Level {
        let nf = self.faces.len();
        let mut verts: Vec<SdVertex> = self
            .verts
            .iter()
            .map(|v| SdVertex {
                p: Vec3::ZERO,
                start_face: NONE,
                regular: v.regular,
                boundary: v.boundary,
            })
            .collect();

        // Even vertices.
        let mut ring = Vec::with_capacity(16);
        for (i, (v, child)) in self.verts.iter().zip(verts.iter_mut()).enumerate() {
            let i = i as u32;
            self.one_ring(i, &mut ring);
            child.p = if ring.is_empty() {
                v.p
            } else if !v.boundary {
                if v.regular {
                    self.weight_one_ring(i, &ring, 1.0 / 16.0)
                } else {
                    self.weight_one_ring(i, &ring, beta(ring.len()))
                }
            } else {
                self.weight_boundary(i, &ring, 1.0 / 8.0)
            };
        }

        // Odd vertices: created by the first face (in face order) that has the edge.
        let mut edge_verts = vec![[NONE; 3]; nf];
        for fi in 0..nf {
            let face = self.faces[fi];
            for k in 0..3 {
                let nb = face.f[k];
                if nb != NONE && (nb as usize) < fi {
                    // The neighbour runs through the edge from v[k + 1] to v[k].
                    let j = self.vnum(nb, face.v[next(k)]);
                    edge_verts[fi][k] = edge_verts[nb as usize][j];
                    continue;
                }
                let (a, b) = (face.v[k], face.v[next(k)]);
                let (e0, e1) = (a.min(b), a.max(b));
                let (p0, p1) = (self.verts[e0 as usize].p, self.verts[e1 as usize].p);
                let boundary = nb == NONE;
                let p = if boundary {
                    let mut p = 0.5 * p0;
                    p += 0.5 * p1;
                    p
                } else {
                    let mut p = 3.0 / 8.0 * p0;
                    p += 3.0 / 8.0 * p1;
                    p += 1.0 / 8.0 * self.verts[self.other_vert(fi as u32, e0, e1) as usize].p;
                    p += 1.0 / 8.0 * self.verts[self.other_vert(nb, e0, e1) as usize].p;
                    p
                };
                edge_verts[fi][k] = verts.len() as u32;
                verts.push(SdVertex {
                    p,
                    start_face: 4 * fi as u32 + 3,
                    regular: true,
                    boundary,
                });
            }
        }

        // Even vertices' faces.
        for (i, v) in self.verts.iter().enumerate() {
            if v.start_face != NONE {
                verts[i].start_face = 4 * v.start_face + self.vnum(v.start_face, i as u32) as u32;
            }
        }

        // Children's neighbours and vertices.
        let mut faces = vec![
            SdFace {
                v: [NONE; 3],
                f: [NONE; 3],
            };
            4 * nf
        ];
        for (fi, face) in self.faces.iter().enumerate() {
            let c = |k: usize| 4 * fi + k;
            let child_at = |f2: u32, v: u32| {
                if f2 == NONE {
                    NONE
                } else {
                    4 * f2 + self.vnum(f2, v) as u32
                }
            };
            for j in 0..3 {
                faces[c(3)].f[j] = c(next(j)) as u32;
                faces[c(j)].f[next(j)] = c(3) as u32;
                faces[c(j)].f[j] = child_at(face.f[j], face.v[j]);
                faces[c(j)].f[prev(j)] = child_at(face.f[prev(j)], face.v[j]);
            }
            for j in 0..3 {
                faces[c(j)].v[j] = face.v[j];
                let vert = edge_verts[fi][j];
                faces[c(j)].v[next(j)] = vert;
                faces[c(next(j))].v[j] = vert;
                faces[c(3)].v[j] = vert;
            }
        }
        Level { verts, faces }
    }

    /// The triangle mesh of the limit surface: vertices pushed to their limit positions, with
    /// normals from the limit tangents (not normalised, as in pbrt-v3).
    fn into_limit_mesh(mut self) -> Mesh {
        let mut ring = Vec::with_capacity(16);
        let limit: Vec<Vec3> = (0..self.verts.len() as u32)
            .map(|i| {
                self.one_ring(i, &mut ring);
                let v = &self.verts[i as usize];
                if ring.is_empty() {
                    v.p
                } else if v.boundary {
                    self.weight_boundary(i, &ring, 1.0 / 5.0)
                } else {
                    self.weight_one_ring(i, &ring, loop_gamma(ring.len()))
                }
            })
            .collect();
        for (v, &p) in self.verts.iter_mut().zip(&limit) {
            v.p = p;
        }
        let normals: Vec<[f32; 3]> = (0..self.verts.len() as u32)
            .map(|i| {
                self.one_ring(i, &mut ring);
                let v = &self.verts[i as usize];
                let valence = ring.len();
                if valence == 0 {
                    return [0.0; 3];
                }
                let (s, t) = if !v.boundary {
                    let mut s = Vec3::ZERO;
                    let mut t = Vec3::ZERO;
                    for (j, &r) in ring.iter().enumerate() {
                        let angle = 2.0 * PI * j as f32 / valence as f32;
                        s += angle.cos() * r;
                        t += angle.sin() * r;
                    }
                    (s, t)
                } else {
                    let s = ring[valence - 1] - ring[0];
                    let t = match valence {
                        1 => Vec3::ZERO,
                        2 => ring[0] + ring[1] - 2.0 * v.p,
                        3 => ring[1] - v.p,
                        4 => {
                            -1.0 * ring[0]
                                + 2.0 * ring[1]
                                + 2.0 * ring[2]
                                + -1.0 * ring[3]
                                + -2.0 * v.p
                        }
                        _ => {
                            let theta = PI / (valence - 1) as f32;
                            let mut t = theta.sin() * (ring[0] + ring[valence - 1]);
                            for (k, &r) in ring.iter().enumerate().take(valence - 1).skip(1) {
                                let wt = (2.0 * theta.cos() - 2.0) * (k as f32 * theta).sin();
                                t += wt * r;
                            }
                            -t
                        }
                    };
                    (s, t)
                };
                s.cross(t).to_array()
            })
            .collect();
        let mut indices = Vec::with_capacity(3 * self.faces.len());
        for f in &self.faces {
            indices.extend_from_slice(&f.v);
        }
        Mesh {
            positions: limit.iter().map(|p| p.to_array()).collect(),
            normals: Some(normals),
            uvs: None,
            indices,
        }
    }
}

/// Loop-subdivides the triangle mesh (`indices`, three per triangle, into `positions`) `levels`
/// times and returns its limit surface as a mesh with per-vertex normals, as pbrt-v3's
/// `LoopSubdivide` does. Faces with a repeated vertex are skipped and unused vertices dropped,
/// with a message in `warnings`; invalid indices, more than [`MAX_LEVELS`] levels, too many
/// output triangles, non-finite positions, edges with more than two faces, and neighbouring
/// faces of opposite orientation are errors.
pub fn loop_subdivide(
    positions: &[[f32; 3]],
    indices: &[u32],
    levels: u32,
    warnings: &mut Vec<String>,
) -> std::result::Result<Mesh, String> {
    if levels > MAX_LEVELS as u32 {
        return Err(format!(
            "{levels} subdivision levels is too many (at most {MAX_LEVELS})"
        ));
    }
    if indices.len() % 3 != 0 {
        return Err(format!(
            "{} vertex indices, not a multiple of 3",
            indices.len()
        ));
    }
    let n = positions.len();
    if let Some((i, &bad)) = indices.iter().enumerate().find(|&(_, &v)| v as usize >= n) {
        return Err(format!(
            "vertex index {bad} (index #{i}) is out of range: there are {n} vertices"
        ));
    }
    if let Some(p) = positions.iter().find(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(format!("vertex position {p:?} is not finite"));
    }
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(indices.len() / 3);
    let mut degenerate = 0usize;
    for t in indices.chunks_exact(3) {
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
            degenerate += 1;
        } else {
            tris.push([t[0], t[1], t[2]]);
        }
    }
    if degenerate > 0 {
        warnings.push(format!(
            "{degenerate} face(s) with a repeated vertex skipped"
        ));
    }
    let triangles = (tris.len() as u64).saturating_mul(1u64 << (2 * levels));
    if triangles > MAX_TRIANGLES {
        return Err(format!(
            "{} faces subdivided {levels} times would make {triangles} triangles (at most \
             {MAX_TRIANGLES})",
            tris.len()
        ));
    }
    // Drop unused vertices (pbrt-v3 cannot handle them).
    let mut remap = vec![NONE; n];
    let mut used: Vec<Vec3> = Vec::with_capacity(n);
    for t in &mut tris {
        for v in t.iter_mut() {
            let r = &mut remap[*v as usize];
            if *r == NONE {
                *r = used.len() as u32;
                used.push(Vec3::from_array(positions[*v as usize]));
            }
            *v = *r;
        }
    }
    if used.len() < n {
        warnings.push(format!(
            "{} vertex(es) not used by any face dropped",
            n - used.len()
        ));
    }
    let mut level = Level::new(used, &tris)?;
    // Vertices where separate fans of faces meet are subdivided from one fan only.
    let mut incident = vec![0usize; level.verts.len()];
    for t in &tris {
        for &v in t {
            incident[v as usize] += 1;
        }
    }
    let pinched = (0..level.verts.len() as u32)
        .filter(|&v| {
            let vert = &level.verts[v as usize];
            let fan = level.valence(v).saturating_sub(usize::from(vert.boundary));
            fan != incident[v as usize]
        })
        .count();
    if pinched > 0 {
        warnings.push(format!(
            "{pinched} vertex(es) where separate fans of faces meet (not manifold); each is \
             subdivided from one fan only"
        ));
    }
    for _ in 0..levels {
        level = level.refine();
    }
    let mesh = level.into_limit_mesh();
    mesh.validate()?;
    Ok(mesh)
}

/// Reads a `loopsubdiv` shape's parameters (`integer levels` or `nlevels`, default 3;
/// `integer indices`; `point3 P`) and returns its subdivided mesh; errors carry the location of
/// the offending parameter (or of the shape, `loc`), warnings are appended to `warnings`.
pub fn mesh_from_params(
    params: &ParamList,
    loc: &Loc,
    warnings: &mut Vec<Warning>,
) -> Result<Mesh> {
    let param_loc = |name: &str| {
        params
            .get(name)
            .map_or_else(|| loc.clone(), |p| p.loc.clone())
    };
    // pbrt-v3: FindOneInt("levels", FindOneInt("nlevels", 3)).
    let nlevels = params.int_or("nlevels", 3)?;
    let (levels, levels_name) = match params.int("levels")? {
        Some(l) => (l, "levels"),
        None => (nlevels, "nlevels"),
    };
    if !(0..=MAX_LEVELS).contains(&levels) {
        return Err(Error::at(
            &param_loc(levels_name),
            format!(
                "loopsubdiv: \"{levels_name}\" is {levels}; it must be between 0 and {MAX_LEVELS}"
            ),
        ));
    }
    // pbrt-v3 reads and ignores it.
    let _ = params.string("scheme")?;
    let Some(ix) = params.ints("indices")? else {
        return Err(Error::at(
            loc,
            "loopsubdiv needs an \"integer indices\" parameter",
        ));
    };
    let Some(p) = params.numbers("P", ParamType::Point3)? else {
        return Err(Error::at(loc, "loopsubdiv needs a \"point3 P\" parameter"));
    };
    if p.len() % 3 != 0 {
        return Err(Error::at(
            &param_loc("P"),
            format!("loopsubdiv: {} \"P\" values, not a multiple of 3", p.len()),
        ));
    }
    let positions: Vec<[f32; 3]> = p
        .chunks_exact(3)
        .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
        .collect();
    if let Some(q) = positions.iter().find(|q| !q.iter().all(|c| c.is_finite())) {
        return Err(Error::at(
            &param_loc("P"),
            format!("loopsubdiv: vertex position {q:?} is not finite (in single precision)"),
        ));
    }
    let indices: Vec<u32> = ix
        .iter()
        .map(|&i| {
            u32::try_from(i).map_err(|_| {
                Error::at(
                    &param_loc("indices"),
                    format!("loopsubdiv: negative vertex index {i}"),
                )
            })
        })
        .collect::<Result<_>>()?;
    let mut messages = Vec::new();
    let mesh = loop_subdivide(&positions, &indices, levels as u32, &mut messages)
        .map_err(|m| Error::at(&param_loc("indices"), format!("loopsubdiv: {m}")))?;
    warnings.extend(
        messages
            .into_iter()
            .map(|m| Warning::at(loc, format!("loopsubdiv: {m}"))),
    );
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;
    use crate::scene::Scene;
    use std::collections::HashMap;
    use std::path::Path;

    /// The regular octahedron |x| + |y| + |z| = 1, faces counter-clockwise seen from outside.
    fn octahedron() -> (Vec<[f32; 3]>, Vec<u32>) {
        let p = vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let i = vec![
            0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5,
        ];
        (p, i)
    }

    /// A tetrahedron, faces counter-clockwise seen from outside.
    fn tetrahedron() -> (Vec<[f32; 3]>, Vec<u32>) {
        let p = vec![
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ];
        (p, vec![0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2])
    }

    /// An n x n grid of unit squares in z = 0, two counter-clockwise triangles each.
    fn grid(n: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
        let mut p = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                p.push([x as f32, y as f32, 0.0]);
            }
        }
        let mut i = Vec::new();
        let at = |x: u32, y: u32| y * (n + 1) + x;
        for y in 0..n {
            for x in 0..n {
                // Alternate the diagonals so boundary valences vary.
                if (x + y) % 2 == 0 {
                    i.extend([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                    i.extend([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
                } else {
                    i.extend([at(x, y), at(x + 1, y), at(x, y + 1)]);
                    i.extend([at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)]);
                }
            }
        }
        (p, i)
    }

    fn subdivide(p: &[[f32; 3]], i: &[u32], levels: u32) -> Mesh {
        let mut w = Vec::new();
        let m = loop_subdivide(p, i, levels, &mut w).unwrap();
        assert!(w.is_empty(), "{w:?}");
        m.validate().unwrap();
        m
    }

    /// Every undirected edge is used by exactly two triangles, once in each direction.
    fn assert_watertight(m: &Mesh) {
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for t in m.indices.chunks_exact(3) {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &directed {
            assert_eq!(n, 1, "edge {a}-{b} used {n} times in one direction");
            assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
    }

    fn face_normal(m: &Mesh, t: &[u32]) -> Vec3 {
        let p = |i: u32| Vec3::from_array(m.positions[i as usize]);
        (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]))
    }

    #[test]
    fn closed_meshes_refine_into_watertight_limit_surfaces() {
        for (name, (p, i)) in [("octahedron", octahedron()), ("tetrahedron", tetrahedron())] {
            let faces = i.len() / 3;
            for levels in 0..=4 {
                let m = subdivide(&p, &i, levels);
                assert_eq!(m.triangle_count(), faces << (2 * levels), "{name} {levels}");
                // Euler characteristic 2: V = F / 2 + 2 for a closed triangle mesh.
                assert_eq!(m.positions.len(), m.triangle_count() / 2 + 2, "{name}");
                assert_watertight(&m);
                let normals = m.normals.as_ref().unwrap();
                assert_eq!(normals.len(), m.positions.len());
                for (&q, &n) in m.positions.iter().zip(normals) {
                    let (q, n) = (Vec3::from_array(q), Vec3::from_array(n));
                    assert!(q.is_finite() && n.is_finite(), "{name}: {q} {n}");
                    // Inside the convex hull of the control mesh (the faces' planes).
                    for t in i.chunks_exact(3) {
                        let a = Vec3::from_array(p[t[0] as usize]);
                        let fn_ = (Vec3::from_array(p[t[1] as usize]) - a)
                            .cross(Vec3::from_array(p[t[2] as usize]) - a);
                        assert!((q - a).dot(fn_) <= 1e-5, "{name} {levels}: {q} outside");
                    }
                    // pbrt-v3's limit normals point into a counter-clockwise closed mesh
                    // (its one-ring runs clockwise); the centre is the origin.
                    assert!(n.length() > 0.0 && n.normalize().dot(q.normalize()) < -0.5);
                }
                // Triangles keep the orientation of the control mesh.
                for t in m.indices.chunks_exact(3) {
                    let c = t
                        .iter()
                        .map(|&v| Vec3::from_array(m.positions[v as usize]))
                        .sum::<Vec3>();
                    assert!(face_normal(&m, t).dot(c) > 0.0);
                }
            }
        }
    }

    #[test]
    fn limit_positions_follow_pbrt_weights() {
        // Octahedron vertices have valence 4: beta = 3/32, gamma = 1/(4 + 4) = 1/8, so the
        // limit of (1, 0, 0) is (1 - 4/8) (1, 0, 0) + 1/8 (sum of its ring = 0) = (0.5, 0, 0).
        let (p, i) = octahedron();
        let m0 = subdivide(&p, &i, 0);
        assert_eq!(m0.positions[0], [0.5, 0.0, 0.0]);
        // The limit point of an original vertex does not depend on the level.
        for levels in 1..=3 {
            let m = subdivide(&p, &i, levels);
            for (a, b) in m0.positions.iter().zip(&m.positions) {
                assert!((Vec3::from_array(*a) - Vec3::from_array(*b)).length() < 1e-5);
            }
        }
        // One level by hand: the even vertex (1, 0, 0) moves to (1 - 4 beta) (1, 0, 0) = 5/8,
        // the odd vertex of edge 0-2 to 3/8 (1, 0, 0) + 3/8 (0, 1, 0) + 1/8 (z + -z) =
        // (3/8, 3/8, 0); its limit (valence 6, gamma = 1/12) is (1/2) itself + 1/12 ring.
        let m1 = subdivide(&p, &i, 1);
        assert_eq!(m1.positions.len(), 18);
        let q = Vec3::from_array(m1.positions[0]);
        // Even (5/8, 0, 0), ring: four odd vertices (3/8, +-3/8, 0), (3/8, 0, +-3/8);
        // gamma(4) = 1/8: (1 - 1/2) 5/8 + 1/8 * 4 * 3/8 = 5/16 + 3/16 = 1/2.
        assert!((q - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6, "{q}");
    }

    #[test]
    fn planar_patch_stays_planar_with_z_normals() {
        let (p, i) = grid(3);
        for levels in 0..=3 {
            let m = subdivide(&p, &i, levels);
            assert_eq!(m.triangle_count(), 18 << (2 * levels));
            let normals = m.normals.as_ref().unwrap();
            let mut sign = 0.0f32;
            for (&q, &n) in m.positions.iter().zip(normals) {
                assert_eq!(q[2], 0.0);
                assert!(
                    (0.0..=3.0).contains(&q[0]) && (0.0..=3.0).contains(&q[1]),
                    "{q:?}"
                );
                let n = Vec3::from_array(n);
                assert!(n.z != 0.0, "{q:?}: {n}");
                assert!(n.x.abs() <= 1e-5 * n.z.abs() && n.y.abs() <= 1e-5 * n.z.abs());
                if sign == 0.0 {
                    sign = n.z.signum();
                }
                assert_eq!(n.z.signum(), sign, "normals disagree at {q:?}");
            }
            // As for closed meshes, opposite to the counter-clockwise faces' normal (+z).
            assert_eq!(sign, -1.0);
            for t in m.indices.chunks_exact(3) {
                assert!(face_normal(&m, t).z > 0.0);
            }
        }
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        let (p, i) = octahedron();
        let mut w = Vec::new();
        let err = |p: &[[f32; 3]], i: &[u32], levels: u32| match loop_subdivide(
            p,
            i,
            levels,
            &mut Vec::new(),
        ) {
            Ok(m) => panic!("no error ({} triangles)", m.triangle_count()),
            Err(e) => e,
        };
        assert!(err(&p, &i[..7], 1).contains("multiple of 3"));
        assert!(err(&p, &[0, 1, 6], 1).contains("out of range"));
        assert!(err(&p, &i, 11).contains("too many"));
        let (gp, gi) = grid(6);
        assert!(err(&gp, &gi, MAX_LEVELS as u32).contains("triangles"));
        let mut nan = p.clone();
        nan[3][1] = f32::NAN;
        assert!(err(&nan, &i, 1).contains("not finite"));
        // Three faces on the edge 0-1.
        let q = [
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        assert!(err(&q, &[0, 1, 2, 1, 0, 3, 0, 1, 4], 1).contains("more than two faces"));
        // Two faces through edge 0-1 the same way.
        assert!(err(&q, &[0, 1, 2, 0, 1, 3], 1).contains("oriented"));
        // A repeated vertex: the face is skipped, with a warning.
        let m = loop_subdivide(&q, &[0, 1, 2, 0, 0, 3], 1, &mut w).unwrap();
        assert_eq!(m.triangle_count(), 4);
        assert_eq!(w.len(), 2, "{w:?}"); // the face, and vertex 3 now unused
                                         // Nothing at all.
        let m = loop_subdivide(&[], &[], 3, &mut w).unwrap();
        assert_eq!(m.triangle_count(), 0);
        // Two fans meeting at one vertex (a bow tie): subdivided, with a warning.
        let bow = [
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [-1.0, -1.0, 0.0],
        ];
        w.clear();
        let m = loop_subdivide(&bow, &[0, 1, 2, 0, 3, 4], 2, &mut w).unwrap();
        assert_eq!(m.triangle_count(), 32);
        assert!(w.iter().any(|m| m.contains("fans")), "{w:?}");
        m.validate().unwrap();
    }

    #[test]
    fn random_meshes_never_panic() {
        let mut rng = crate::shapes::test_util::Rng::new(11);
        for _ in 0..500 {
            let nv = 3 + (rng.f() * 8.0) as usize;
            let p: Vec<[f32; 3]> = (0..nv).map(|_| rng.v3().to_array()).collect();
            let nf = 1 + (rng.f() * 12.0) as usize;
            let i: Vec<u32> = (0..3 * nf).map(|_| (rng.f() * nv as f32) as u32).collect();
            if let Ok(m) = loop_subdivide(&p, &i, 2, &mut Vec::new()) {
                m.validate().unwrap();
                assert!(m.positions.iter().flatten().all(|c| c.is_finite()));
            }
        }
    }

    /// A scene with the camera at the world origin: render space is then world space.
    fn scene(shape: &str) -> acr_parser::SceneDescription {
        let text = format!(
            "LookAt 0 0 0  0 0 -1  0 1 0\nCamera \"perspective\"\nWorldBegin\n{shape}\nWorldEnd\n"
        );
        acr_parser::parse_str(&text, Path::new("/tmp/loop.pbrt")).unwrap()
    }

    const OCTAHEDRON: &str = "\"point P\" [1 0 0 -1 0 0 0 1 0 0 -1 0 0 0 1 0 0 -1] \
         \"integer indices\" [0 2 4 2 1 4 1 3 4 3 0 4 2 0 5 1 2 5 3 1 5 0 3 5]";

    #[test]
    fn loopsubdiv_shapes_render_as_triangle_meshes() {
        let desc = scene(&format!(
            "Shape \"loopsubdiv\" \"integer nlevels\" [2] \"string scheme\" \"loop\" {OCTAHEDRON}"
        ));
        let mut w = Vec::new();
        let s = Scene::build(&desc, &mut w).unwrap();
        assert!(w.is_empty(), "{w:?}");
        // The limit point of the vertex (0, 0, 1) is (0, 0, 0.5), and the surface is smooth
        // there. Both directions must hit: -Vec3::Z has -0.0 components, which obvhs's
        // traversal once missed.
        let ray = |d: Vec3| Ray::new(Vec3::new(0.0, 0.0, 5.0), d, 0.0);
        assert!(s.intersect(&ray(-Vec3::Z)).is_some(), "-0.0 components");
        let hit = s
            .intersect(&ray(Vec3::new(0.0, 0.0, -1.0)))
            .expect("the ray hits the subdivided octahedron");
        assert!(
            (hit.si.p - Vec3::new(0.0, 0.0, 0.5)).length() < 1e-4,
            "{}",
            hit.si.p
        );
        assert!(hit.si.shading_n.z.abs() > 0.999, "{}", hit.si.shading_n);
        // Default levels (3) and "levels" winning over "nlevels", as in pbrt-v3.
        let params = |shape: &str| scene(shape).shapes[0].plugin.clone();
        for (shape, tris) in [
            (format!("Shape \"loopsubdiv\" {OCTAHEDRON}"), 8 * 64),
            (
                format!(
                    "Shape \"loopsubdiv\" \"integer levels\" [1] \"integer nlevels\" [4] \
                     {OCTAHEDRON}"
                ),
                8 * 4,
            ),
        ] {
            let p = params(&shape);
            let m = mesh_from_params(&p.params, &p.loc, &mut w).unwrap();
            assert_eq!(m.triangle_count(), tris);
        }
    }

    #[test]
    fn loopsubdiv_parameter_errors_point_at_the_parameter() {
        let line_col = |shape: &str| {
            let desc = scene(shape);
            match Scene::build(&desc, &mut Vec::new()) {
                Err(Error::At { loc, message }) => (loc.line_col(), message),
                Err(e) => panic!("{e}"),
                Ok(_) => panic!("no error for {shape}"),
            }
        };
        let ((line, col), m) = line_col(&format!(
            "Shape \"loopsubdiv\" \"integer nlevels\" [11] {OCTAHEDRON}"
        ));
        assert_eq!((line, col), (4, 20), "{m}");
        assert!(m.contains("nlevels"), "{m}");
        let (_, m) = line_col(&format!(
            "Shape \"loopsubdiv\" \"integer levels\" [-1] {OCTAHEDRON}"
        ));
        assert!(m.contains("levels"), "{m}");
        let ((_, col), m) = line_col(
            "Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]",
        );
        assert!(m.contains("out of range"), "{m}");
        assert_eq!(col, 50, "{m}");
        let (_, m) = line_col(
            "Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 -2]",
        );
        assert!(m.contains("negative"), "{m}");
        let ((_, col), m) = line_col(
            "Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 1e39] \"integer indices\" [0 1 2]",
        );
        assert!(m.contains("not finite"), "{m}");
        assert_eq!(col, 20, "{m}");
        let (_, m) = line_col("Shape \"loopsubdiv\" \"integer indices\" [0 1 2]");
        assert!(m.contains("\"point3 P\""), "{m}");
        let (_, m) = line_col("Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 0]");
        assert!(m.contains("indices"), "{m}");
    }
}
