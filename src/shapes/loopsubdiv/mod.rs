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
mod tests;
