//! PLY meshes for pbrt's `plymesh` shape.
//!
//! Reads ascii, binary little-endian and binary big-endian files: vertex positions, optional
//! normals and texture coordinates, and triangle and quad faces (a quad is split in two). Faces
//! of other sizes, other vertex and face properties and other elements are skipped, as pbrt-v3
//! does.
//!
//! The reader never panics and never trusts the header: every read is bounds-checked, counts are
//! multiplied with checked arithmetic, and no count from the header sizes an allocation before
//! the bytes it implies are known to be in the file. The common binary layouts (vertex records of
//! scalars only, faces whose only list is the vertex index list of 32-bit integers) are read by
//! specialised loops; everything else goes through a generic property-by-property reader.

mod cursor;
mod faces;
mod header;
mod types;
mod vertices;

use crate::mesh::Mesh;
use cursor::Cursor;
use faces::{read_faces, FacePlan};
use header::{check_fits, parse_header, Element};
use std::path::Path;
use types::Format;
use vertices::{read_vertices, VertexPlan};

/// A mesh read from a PLY file, with what was skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct Ply {
    /// The triangle mesh, with normals and uvs when the file has them.
    pub mesh: Mesh,
    /// Messages about data that was ignored, such as faces that are neither triangles nor quads.
    pub warnings: Vec<String>,
}

/// Reads a PLY file from disk.
pub fn read_ply(path: &Path) -> Result<Ply, String> {
    let bytes = crate::source::read_file(path, crate::source::FileKind::Ply)
        .map_err(|e| format!("cannot read the file: {e}"))?;
    parse_ply(&bytes)
}

/// Parses PLY bytes (ascii, binary_little_endian, binary_big_endian).
pub fn parse_ply(bytes: &[u8]) -> Result<Ply, String> {
    let header = parse_header(bytes)?;
    let elements = &header.elements;
    let (vi, vertex_el) = elements
        .iter()
        .enumerate()
        .find(|(_, e)| e.name == "vertex")
        .ok_or("the file has no vertex element")?;
    let (fi, face_el) = elements
        .iter()
        .enumerate()
        .find(|(_, e)| e.name == "face")
        .ok_or("the file has no face element")?;
    // pbrt-v3 rejects these files too ("No face/vertex elements found").
    if vertex_el.count == 0 {
        return Err("the vertex element has no vertices".into());
    }
    if face_el.count == 0 {
        return Err("the face element has no faces".into());
    }
    let nv = u32::try_from(vertex_el.count).map_err(|_| {
        format!(
            "the vertex element declares {} vertices, more than {}",
            vertex_el.count,
            u32::MAX
        )
    })?;
    let vplan = VertexPlan::new(vertex_el)?;
    let fplan = FacePlan::new(face_el)?;

    let mut cur = Cursor {
        bytes,
        pos: header.body,
        line: header.body_line,
        format: header.format,
    };
    let mut mesh = Mesh::default();
    let mut warnings = Vec::new();
    let mut skipped_faces = 0;
    for (k, el) in elements.iter().enumerate() {
        // Records without properties take no bytes, however many the header claims.
        if el.props.is_empty() {
            continue;
        }
        check_fits(el, &cur)?;
        if k == vi {
            read_vertices(&mut cur, el, &vplan, &mut mesh)?;
        } else if k == fi {
            skipped_faces = read_faces(&mut cur, el, &fplan, nv, &mut mesh.indices)?;
        } else {
            if el.name == "vertex" || el.name == "face" {
                warnings.push(format!("skipped a second '{}' element", el.name));
            }
            skip_element(&mut cur, el)?;
        }
    }
    if skipped_faces > 0 {
        let s = if skipped_faces == 1 { "" } else { "s" };
        warnings.push(format!(
            "skipped {skipped_faces} face{s} with more than 4 or fewer than 3 vertices \
             (only triangles and quads are supported)"
        ));
    }
    if let Some((i, p)) = mesh
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
    {
        return Err(format!(
            "vertex {i} has a position that is not finite: {p:?}"
        ));
    }
    mesh.validate()?;
    Ok(Ply { mesh, warnings })
}

/// Reads past every record of an element nobody uses.
fn skip_element(cur: &mut Cursor, el: &Element) -> Result<(), String> {
    if cur.format != Format::Ascii && el.all_scalar() {
        let stride: usize = el.props.iter().map(|p| p.kind.min_size()).sum();
        return el
            .count
            .checked_mul(stride)
            .and_then(|len| cur.take(len))
            .map(|_| ())
            .ok_or_else(|| format!("file ends inside the '{}' element", el.name));
    }
    for i in 0..el.count {
        for p in &el.props {
            cur.skip(p.kind).map_err(|e| e.context(&el.name, i))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
