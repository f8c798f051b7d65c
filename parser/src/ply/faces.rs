//! The face element: triangles and quads from the vertex index lists.

use super::cursor::{decode, Cursor};
use super::header::Element;
use super::types::{Format, Kind, Scalar};

/// Where the vertex index list is in a face record.
pub(super) struct FacePlan {
    pub(super) list: usize,
    pub(super) count: Scalar,
    pub(super) item: Scalar,
}

impl FacePlan {
    pub(super) fn new(el: &Element) -> Result<Self, String> {
        let (list, p) = el
            .props
            .iter()
            .enumerate()
            .find(|(_, p)| p.name == "vertex_indices")
            .or_else(|| {
                el.props
                    .iter()
                    .enumerate()
                    .find(|(_, p)| p.name == "vertex_index")
            })
            .ok_or("the face element has no 'vertex_indices' list")?;
        match p.kind {
            Kind::List { count, item } => Ok(Self { list, count, item }),
            Kind::Scalar(_) => Err(format!("face property '{}' is not a list", p.name)),
        }
    }
}

/// Reads the faces into `out`; returns how many were skipped for their vertex count.
pub(super) fn read_faces(
    cur: &mut Cursor,
    el: &Element,
    plan: &FacePlan,
    nv: u32,
    out: &mut Vec<u32>,
) -> Result<usize, String> {
    let others_scalar = el
        .props
        .iter()
        .enumerate()
        .all(|(i, p)| i == plan.list || matches!(p.kind, Kind::Scalar(_)));
    let signed = plan.item == Scalar::I32;
    if let (Some(be), true, true) = (
        cur.big_endian(),
        others_scalar,
        matches!(plan.item, Scalar::I32 | Scalar::U32),
    ) {
        let size = |r: std::ops::Range<usize>| -> usize {
            el.props
                .get(r)
                .unwrap_or_default()
                .iter()
                .map(|p| p.kind.min_size())
                .sum()
        };
        let pre = size(0..plan.list);
        let post = size(plan.list.saturating_add(1)..el.props.len());
        let tri = pre + post + plan.count.size() + 12;
        out.reserve(el.count.min(cur.remaining() / tri).saturating_mul(3));
        let f = match (be, signed) {
            (false, false) => faces_fast::<false, false>,
            (false, true) => faces_fast::<false, true>,
            (true, false) => faces_fast::<true, false>,
            (true, true) => faces_fast::<true, true>,
        };
        let (pos, skipped) = f(cur.bytes, cur.pos, el.count, plan.count, pre, post, nv, out)?;
        cur.pos = pos;
        return Ok(skipped);
    }

    // Generic: property by property.
    let per_tri = if cur.format == Format::Ascii {
        2 * (el.props.len() + 3)
    } else {
        el.props.iter().map(|p| p.kind.min_size()).sum::<usize>() + 3 * plan.item.size()
    };
    out.reserve(
        el.count
            .min(cur.remaining() / per_tri.max(1))
            .saturating_mul(3),
    );
    let mut skipped = 0;
    let mut face = [0f64; 4];
    for f in 0..el.count {
        let mut k = 0;
        for (p, prop) in el.props.iter().enumerate() {
            match prop.kind {
                Kind::List { count, item } if p == plan.list => {
                    k = cur.list_len(count).map_err(|e| e.context("face", f))?;
                    for j in 0..k {
                        let v = cur.scalar(item).map_err(|e| e.context("face", f))?;
                        if let Some(dst) = face.get_mut(j) {
                            *dst = v;
                        }
                    }
                }
                kind => cur.skip(kind).map_err(|e| e.context("face", f))?,
            }
        }
        if k != 3 && k != 4 {
            skipped += 1;
            continue;
        }
        let mut idx = [0u32; 4];
        for (&v, dst) in face.iter().zip(&mut idx).take(k) {
            if v.fract() != 0.0 {
                return Err(format!(
                    "face {f} has vertex index {v}, which is not an integer"
                ));
            }
            if !(v >= 0.0 && v < f64::from(nv)) {
                return Err(format!(
                    "face {f} has vertex index {v} but there are {nv} vertices"
                ));
            }
            *dst = v as u32;
        }
        let [a, b, c, d] = idx;
        if k == 3 {
            out.extend_from_slice(&[a, b, c]);
        } else {
            out.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    Ok(skipped)
}

/// Faces whose other properties are scalars and whose index list holds 32-bit integers.
/// Returns the position after the faces and how many faces were skipped.
#[allow(clippy::too_many_arguments)]
pub(super) fn faces_fast<const BE: bool, const SIGNED: bool>(
    bytes: &[u8],
    mut pos: usize,
    count: usize,
    count_ty: Scalar,
    pre: usize,
    post: usize,
    nv: u32,
    out: &mut Vec<u32>,
) -> Result<(usize, usize), String> {
    let word = |b: [u8; 4]| {
        if BE {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        }
    };
    // A negative i32 read as u32 is at least 2^31, so one comparison rejects it.
    let limit = if SIGNED { nv.min(1 << 31) } else { nv };
    let cs = count_ty.size();
    let mut skipped = 0;
    for f in 0..count {
        let eof = || format!("file ends inside face {f}");
        let head = pos.checked_add(pre).ok_or_else(eof)?;
        let k = match bytes.get(head..head.saturating_add(cs)) {
            Some(&[n]) if count_ty == Scalar::U8 => f64::from(n),
            Some(s) => decode(s, 0, count_ty, BE),
            None => return Err(eof()),
        };
        if k < 0.0 {
            return Err(format!("face {f} has a list of negative length {k}"));
        }
        let start = head + cs;
        let len = (k as usize).checked_mul(4).ok_or_else(eof)?;
        let end = start.checked_add(len).ok_or_else(eof)?;
        let list = bytes.get(start..end).ok_or_else(eof)?;
        pos = end.checked_add(post).ok_or_else(eof)?;
        if pos > bytes.len() {
            return Err(eof());
        }
        if let Ok(&[a0, a1, a2, a3, b0, b1, b2, b3, c0, c1, c2, c3]) = <&[u8; 12]>::try_from(list) {
            let t = [
                word([a0, a1, a2, a3]),
                word([b0, b1, b2, b3]),
                word([c0, c1, c2, c3]),
            ];
            if t.iter().any(|&i| i >= limit) {
                return Err(bad_index::<SIGNED>(f, &t, limit, nv));
            }
            out.extend_from_slice(&t);
        } else if let Ok(&[a0, a1, a2, a3, b0, b1, b2, b3, c0, c1, c2, c3, d0, d1, d2, d3]) =
            <&[u8; 16]>::try_from(list)
        {
            let [a, b, c, d] = [
                word([a0, a1, a2, a3]),
                word([b0, b1, b2, b3]),
                word([c0, c1, c2, c3]),
                word([d0, d1, d2, d3]),
            ];
            if a >= limit || b >= limit || c >= limit || d >= limit {
                return Err(bad_index::<SIGNED>(f, &[a, b, c, d], limit, nv));
            }
            out.extend_from_slice(&[a, b, c, a, c, d]);
        } else {
            skipped += 1;
        }
    }
    Ok((pos, skipped))
}

#[cold]
pub(super) fn bad_index<const SIGNED: bool>(f: usize, idx: &[u32], limit: u32, nv: u32) -> String {
    let bad = idx.iter().copied().find(|&i| i >= limit).unwrap_or(0);
    let shown = if SIGNED {
        i64::from(bad as i32)
    } else {
        i64::from(bad)
    };
    format!("face {f} has vertex index {shown} but there are {nv} vertices")
}
