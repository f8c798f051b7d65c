//! The vertex element: positions, normals and uvs, by a specialised loop where it can.

use super::cursor::{arr, decode, Cursor};
use super::header::Element;
use super::types::{Kind, Scalar};
use crate::mesh::Mesh;

/// Slots for the vertex values pbrt uses: x y z nx ny nz u v.
pub(super) const SLOTS: usize = 8;

/// Which vertex properties feed which slot.
pub(super) struct VertexPlan {
    /// Property index of each slot (x y z always; normals and uvs when `normals`/`uvs`).
    pub(super) slots: [usize; SLOTS],
    pub(super) normals: bool,
    pub(super) uvs: bool,
    /// The slot each property feeds, if any.
    pub(super) slot_of: Vec<Option<usize>>,
}

impl VertexPlan {
    /// Whether slot `s` is read.
    pub(super) fn uses(&self, s: usize) -> bool {
        s < 3 || (s < 6 && self.normals) || (s >= 6 && self.uvs)
    }

    pub(super) fn new(el: &Element) -> Result<Self, String> {
        let find = |name: &str| el.props.iter().position(|p| p.name == name);
        let scalar = |name: &str| {
            el.props
                .iter()
                .position(|p| p.name == name && matches!(p.kind, Kind::Scalar(_)))
        };
        let mut slots = [0; SLOTS];
        for (slot, name) in slots.iter_mut().zip(["x", "y", "z"]) {
            let i =
                find(name).ok_or_else(|| format!("the vertex element has no '{name}' property"))?;
            *slot = scalar(name)
                .filter(|&j| j == i)
                .ok_or_else(|| format!("vertex property '{name}' is a list, not a number"))?;
        }
        let mut normals = false;
        if let (Some(a), Some(b), Some(c)) = (scalar("nx"), scalar("ny"), scalar("nz")) {
            slots[3..6].copy_from_slice(&[a, b, c]);
            normals = true;
        }
        // pbrt-v3 looks for these pairs, in this order.
        let mut uvs = false;
        for (u, v) in [
            ("u", "v"),
            ("s", "t"),
            ("texture_u", "texture_v"),
            ("texture_s", "texture_t"),
        ] {
            if let (Some(a), Some(b)) = (scalar(u), scalar(v)) {
                slots[6..8].copy_from_slice(&[a, b]);
                uvs = true;
                break;
            }
        }
        let mut plan = Self {
            slots,
            normals,
            uvs,
            slot_of: vec![None; el.props.len()],
        };
        for (s, &p) in slots.iter().enumerate() {
            if plan.uses(s) {
                if let Some(x) = plan.slot_of.get_mut(p) {
                    *x = Some(s);
                }
            }
        }
        Ok(plan)
    }
}

pub(super) fn read_vertices(
    cur: &mut Cursor,
    el: &Element,
    plan: &VertexPlan,
    mesh: &mut Mesh,
) -> Result<(), String> {
    let n = el.count;
    if let (Some(be), true) = (cur.big_endian(), el.all_scalar()) {
        // Fixed-size records: slice the whole block and decode at known offsets.
        let mut offsets = Vec::with_capacity(el.props.len());
        let mut stride = 0usize;
        for p in &el.props {
            offsets.push(stride);
            stride = stride
                .checked_add(p.kind.min_size())
                .ok_or("vertex records too large")?;
        }
        if stride == 0 {
            return Err("vertex records are empty".into());
        }
        let len = n.checked_mul(stride).ok_or("vertex data too large")?;
        let data = cur.take(len).ok_or("file ends inside the vertex data")?;
        // Each slot's offset in the record and type.
        let at = plan.slots.map(|p| match el.props.get(p).map(|p| p.kind) {
            Some(Kind::Scalar(t)) => (offsets.get(p).copied().unwrap_or(0), t),
            _ => (0, Scalar::F32),
        });
        let all_f32 = at
            .iter()
            .enumerate()
            .all(|(s, &(_, t))| t == Scalar::F32 || !plan.uses(s));
        let off = at.map(|(o, _)| o);
        if all_f32 && !be {
            fill(data, stride, off, plan, mesh, |r, o| {
                f32::from_le_bytes(arr(r, o))
            });
        } else if all_f32 {
            fill(data, stride, off, plan, mesh, |r, o| {
                f32::from_be_bytes(arr(r, o))
            });
        } else {
            fill(data, stride, at, plan, mesh, |r, (o, t)| {
                decode(r, o, t, be) as f32
            });
        }
        return Ok(());
    }

    // Generic: property by property (ascii, or records holding lists).
    let cap = n.min(cur.remaining() / 2);
    mesh.positions.reserve(cap);
    let mut normals = plan.normals.then(|| Vec::with_capacity(cap));
    let mut uvs = plan.uvs.then(|| Vec::with_capacity(cap));
    let mut v = [0f32; SLOTS];
    for i in 0..n {
        for (p, slot) in el.props.iter().zip(&plan.slot_of) {
            match (p.kind, slot) {
                (Kind::Scalar(ty), Some(s)) => {
                    let x = cur.scalar(ty).map_err(|e| e.context("vertex", i))?;
                    if let Some(dst) = v.get_mut(*s) {
                        *dst = x as f32;
                    }
                }
                (kind, _) => cur.skip(kind).map_err(|e| e.context("vertex", i))?,
            }
        }
        let [x, y, z, nx, ny, nz, u, vv] = v;
        mesh.positions.push([x, y, z]);
        if let Some(ns) = &mut normals {
            ns.push([nx, ny, nz]);
        }
        if let Some(uv) = &mut uvs {
            uv.push([u, vv]);
        }
    }
    mesh.normals = normals;
    mesh.uvs = uvs;
    Ok(())
}

/// Fills positions, normals and uvs from fixed-size records; `get(record, at[slot])` reads a slot.
#[inline(always)]
pub(super) fn fill<T: Copy>(
    data: &[u8],
    stride: usize,
    at: [T; SLOTS],
    plan: &VertexPlan,
    mesh: &mut Mesh,
    get: impl Fn(&[u8], T) -> f32,
) {
    let [x, y, z, nx, ny, nz, u, v] = at;
    let recs = data.chunks_exact(stride);
    mesh.positions = recs
        .clone()
        .map(|r| [get(r, x), get(r, y), get(r, z)])
        .collect();
    if plan.normals {
        mesh.normals = Some(
            recs.clone()
                .map(|r| [get(r, nx), get(r, ny), get(r, nz)])
                .collect(),
        );
    }
    if plan.uvs {
        mesh.uvs = Some(recs.map(|r| [get(r, u), get(r, v)]).collect());
    }
}
