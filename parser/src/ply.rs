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

use crate::mesh::Mesh;
use std::path::Path;

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
    let bytes = crate::source::read_file(path).map_err(|e| format!("cannot read the file: {e}"))?;
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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_int(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

impl Kind {
    /// Bytes a binary value of this kind takes at least (a list: its count alone).
    fn min_size(self) -> usize {
        match self {
            Kind::Scalar(t) => t.size(),
            Kind::List { count, .. } => count.size(),
        }
    }
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

impl Element {
    /// Whether every record has the same binary size (no lists).
    fn all_scalar(&self) -> bool {
        self.props.iter().all(|p| matches!(p.kind, Kind::Scalar(_)))
    }
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Offset of the first byte after the end_header line.
    body: usize,
    /// Line number of the first body line (for ascii messages).
    body_line: usize,
}

fn parse_header(bytes: &[u8]) -> Result<Header, String> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let rest = bytes.get(pos..).unwrap_or_default();
        if rest.is_empty() {
            return Err(if line_no == 0 {
                "header: the file is empty".into()
            } else {
                "header: no end_header line".into()
            });
        }
        let (raw, next) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (rest.get(..i).unwrap_or_default(), pos + i + 1),
            None => (rest, bytes.len()),
        };
        pos = next;
        line_no += 1;
        let line = std::str::from_utf8(raw)
            .ok()
            .filter(|l| l.is_ascii())
            .ok_or_else(|| {
                if line_no == 1 {
                    "header: the file does not start with \"ply\"".to_owned()
                } else {
                    format!("header line {line_no} is not text (no end_header line?)")
                }
            })?;
        if line_no == 1 {
            if line.trim() != "ply" {
                return Err("header: the file does not start with \"ply\"".into());
            }
            continue;
        }
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        let at = |m: String| format!("header line {line_no}: {m}");
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["end_header", ..] => break,
            ["format", f, version] => {
                if format.is_some() {
                    return Err(at("a second format line".into()));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    other => return Err(at(format!("unknown format '{other}'"))),
                });
                if !matches!(*version, "1.0" | "1") {
                    return Err(at(format!("unsupported PLY version '{version}'")));
                }
            }
            ["format", ..] => return Err(at("expected 'format <type> 1.0'".into())),
            ["element", name, count] => {
                let Ok(count) = count.parse::<usize>() else {
                    return Err(at(format!("bad element count '{count}'")));
                };
                elements.push(Element {
                    name: (*name).to_owned(),
                    count,
                    props: Vec::new(),
                });
            }
            ["element", ..] => return Err(at("expected 'element <name> <count>'".into())),
            ["property", rest @ ..] => {
                let (kind, name) = match rest {
                    ["list", count, item, name] => {
                        let count_ty = parse_type(count).map_err(at)?;
                        let item = parse_type(item).map_err(at)?;
                        if !count_ty.is_int() {
                            return Err(at(format!(
                                "a list count type must be an integer type, not '{count}'"
                            )));
                        }
                        (
                            Kind::List {
                                count: count_ty,
                                item,
                            },
                            name,
                        )
                    }
                    ["list", ..] => {
                        return Err(at(
                            "expected 'property list <count type> <item type> <name>'".into(),
                        ))
                    }
                    [ty, name] => (Kind::Scalar(parse_type(ty).map_err(at)?), name),
                    _ => return Err(at("expected 'property <type> <name>'".into())),
                };
                let Some(el) = elements.last_mut() else {
                    return Err(at("property before any element".into()));
                };
                el.props.push(Property {
                    name: (*name).to_owned(),
                    kind,
                });
            }
            [other, ..] => return Err(at(format!("unknown keyword '{other}'"))),
        }
    }
    let format = format.ok_or("header: no format line")?;
    Ok(Header {
        format,
        elements,
        body: pos,
        body_line: line_no + 1,
    })
}

fn parse_type(name: &str) -> Result<Scalar, String> {
    Scalar::from_name(name).ok_or_else(|| format!("unknown property type '{name}'"))
}

/// Fails unless `count` records of `el`, each at its smallest, fit in the rest of the file.
fn check_fits(el: &Element, cur: &Cursor) -> Result<(), String> {
    let remaining = cur.remaining();
    let (min, slack) = match cur.format {
        // A value is at least one character and a separator; the file's last needs no separator.
        Format::Ascii => (el.props.len().saturating_mul(2), 1),
        _ => (el.props.iter().map(|p| p.kind.min_size()).sum(), 0),
    };
    let need = el.count.checked_mul(min);
    if need.is_some_and(|n| n <= remaining.saturating_add(slack)) {
        return Ok(());
    }
    if cur.format != Format::Ascii && el.all_scalar() && min > 0 {
        // Fixed-size records: say exactly where the data stops.
        let more = (el.count as u128 * min as u128).saturating_sub(remaining as u128);
        return Err(format!(
            "file ends inside {} {} (expected {more} more bytes)",
            el.name,
            remaining / min
        ));
    }
    Err(format!(
        "the header declares {} '{}' records, more than the remaining {remaining} bytes can hold",
        el.count, el.name
    ))
}

/// Why a read failed; turned into a message by [`Fail::context`].
enum Fail {
    Eof,
    Negative(f64),
    Msg(String),
}

impl Fail {
    fn context(self, what: &str, i: usize) -> String {
        match self {
            Fail::Eof => format!("file ends inside {what} {i}"),
            Fail::Negative(n) => format!("{what} {i} has a list of negative length {n}"),
            Fail::Msg(m) => m,
        }
    }
}

/// Reads body values one at a time, in any of the three encodings.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    /// Ascii: the line of the current position, for messages.
    line: usize,
    format: Format,
}

impl<'a> Cursor<'a> {
    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// Binary: whether big-endian; ascii: `None`.
    fn big_endian(&self) -> Option<bool> {
        match self.format {
            Format::Ascii => None,
            Format::BinaryLe => Some(false),
            Format::BinaryBe => Some(true),
        }
    }

    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(n)?;
        let s = self.bytes.get(self.pos..end)?;
        self.pos = end;
        Some(s)
    }

    /// The next whitespace-separated ascii word.
    fn token(&mut self) -> Option<&'a [u8]> {
        let b = self.bytes;
        let mut p = self.pos;
        while let Some(&c) = b.get(p) {
            if c == b'\n' {
                self.line += 1;
            } else if !c.is_ascii_whitespace() {
                break;
            }
            p += 1;
        }
        let start = p;
        while let Some(&c) = b.get(p) {
            if c.is_ascii_whitespace() {
                break;
            }
            p += 1;
        }
        self.pos = p;
        b.get(start..p).filter(|t| !t.is_empty())
    }

    /// One value of type `ty`, as f64.
    fn scalar(&mut self, ty: Scalar) -> Result<f64, Fail> {
        let Some(be) = self.big_endian() else {
            return self.ascii(ty);
        };
        let s = self.take(ty.size()).ok_or(Fail::Eof)?;
        Ok(decode(s, 0, ty, be))
    }

    fn ascii(&mut self, ty: Scalar) -> Result<f64, Fail> {
        let tok = self.token().ok_or(Fail::Eof)?;
        let s = std::str::from_utf8(tok).ok();
        let v = if ty.is_int() {
            s.and_then(|s| s.parse::<i64>().ok()).map(|v| v as f64)
        } else {
            s.and_then(|s| s.parse::<f64>().ok())
        };
        v.ok_or_else(|| {
            let shown: String = String::from_utf8_lossy(tok).chars().take(40).collect();
            let what = if ty.is_int() {
                "an integer"
            } else {
                "a number"
            };
            Fail::Msg(format!(
                "ascii line {}: expected {what}, found '{shown}'",
                self.line
            ))
        })
    }

    /// A list's length.
    fn list_len(&mut self, ty: Scalar) -> Result<usize, Fail> {
        let n = self.scalar(ty)?;
        if n < 0.0 {
            return Err(Fail::Negative(n));
        }
        // Counts are integers (checked in the header); the cast saturates.
        Ok(n as usize)
    }

    /// Reads past one property value.
    fn skip(&mut self, kind: Kind) -> Result<(), Fail> {
        match kind {
            Kind::Scalar(ty) => self.skip_items(1, ty),
            Kind::List { count, item } => {
                let n = self.list_len(count)?;
                self.skip_items(n, item)
            }
        }
    }

    fn skip_items(&mut self, n: usize, ty: Scalar) -> Result<(), Fail> {
        if self.format == Format::Ascii {
            // Each value is a word of at least one byte, so this ends at the end of the file.
            for _ in 0..n {
                self.ascii(ty)?;
            }
            return Ok(());
        }
        let len = n.checked_mul(ty.size()).ok_or(Fail::Eof)?;
        self.take(len).map(|_| ()).ok_or(Fail::Eof)
    }
}

/// The `N` bytes at `off` in `s`, or zeros where `s` is too short (never, for callers here).
#[inline(always)]
fn arr<const N: usize>(s: &[u8], off: usize) -> [u8; N] {
    s.get(off..off.saturating_add(N))
        .and_then(|x| <[u8; N]>::try_from(x).ok())
        .unwrap_or([0; N])
}

/// The binary value of type `ty` at `off` in `s`.
#[inline]
fn decode(s: &[u8], off: usize, ty: Scalar, be: bool) -> f64 {
    macro_rules! num {
        ($t:ty) => {{
            let a = arr(s, off);
            f64::from(if be {
                <$t>::from_be_bytes(a)
            } else {
                <$t>::from_le_bytes(a)
            })
        }};
    }
    match ty {
        Scalar::I8 => num!(i8),
        Scalar::U8 => num!(u8),
        Scalar::I16 => num!(i16),
        Scalar::U16 => num!(u16),
        Scalar::I32 => num!(i32),
        Scalar::U32 => num!(u32),
        Scalar::F32 => num!(f32),
        Scalar::F64 => num!(f64),
    }
}

/// Slots for the vertex values pbrt uses: x y z nx ny nz u v.
const SLOTS: usize = 8;

/// Which vertex properties feed which slot.
struct VertexPlan {
    /// Property index of each slot (x y z always; normals and uvs when `normals`/`uvs`).
    slots: [usize; SLOTS],
    normals: bool,
    uvs: bool,
    /// The slot each property feeds, if any.
    slot_of: Vec<Option<usize>>,
}

impl VertexPlan {
    /// Whether slot `s` is read.
    fn uses(&self, s: usize) -> bool {
        s < 3 || (s < 6 && self.normals) || (s >= 6 && self.uvs)
    }

    fn new(el: &Element) -> Result<Self, String> {
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

fn read_vertices(
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
fn fill<T: Copy>(
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

/// Where the vertex index list is in a face record.
struct FacePlan {
    list: usize,
    count: Scalar,
    item: Scalar,
}

impl FacePlan {
    fn new(el: &Element) -> Result<Self, String> {
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
fn read_faces(
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
fn faces_fast<const BE: bool, const SIGNED: bool>(
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
fn bad_index<const SIGNED: bool>(f: usize, idx: &[u32], limit: u32, nv: u32) -> String {
    let bad = idx.iter().copied().find(|&i| i >= limit).unwrap_or(0);
    let shown = if SIGNED {
        i64::from(bad as i32)
    } else {
        i64::from(bad)
    };
    format!("face {f} has vertex index {shown} but there are {nv} vertices")
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
mod tests {
    use super::*;

    /// Writes PLY files: header lines, then values in the file's encoding.
    struct Writer {
        format: Format,
        head: String,
        body: Vec<u8>,
    }

    impl Writer {
        fn new(format: Format) -> Self {
            let name = match format {
                Format::Ascii => "ascii",
                Format::BinaryLe => "binary_little_endian",
                Format::BinaryBe => "binary_big_endian",
            };
            Self {
                format,
                head: format!("ply\nformat {name} 1.0\ncomment written by a test\n"),
                body: Vec::new(),
            }
        }

        fn head(&mut self, line: &str) -> &mut Self {
            self.head.push_str(line);
            self.head.push('\n');
            self
        }

        fn num(&mut self, ty: Scalar, v: f64) -> &mut Self {
            let be = self.format == Format::BinaryBe;
            macro_rules! put {
                ($t:ty) => {{
                    let x = v as $t;
                    self.body.extend_from_slice(&if be {
                        x.to_be_bytes()
                    } else {
                        x.to_le_bytes()
                    });
                }};
            }
            match (self.format, ty) {
                (Format::Ascii, _) => {
                    if !self.body.is_empty() && self.body.last() != Some(&b'\n') {
                        self.body.push(b' ');
                    }
                    let s = if ty.is_int() {
                        format!("{}", v as i64)
                    } else {
                        format!("{v}")
                    };
                    self.body.extend_from_slice(s.as_bytes());
                }
                (_, Scalar::I8) => put!(i8),
                (_, Scalar::U8) => put!(u8),
                (_, Scalar::I16) => put!(i16),
                (_, Scalar::U16) => put!(u16),
                (_, Scalar::I32) => put!(i32),
                (_, Scalar::U32) => put!(u32),
                (_, Scalar::F32) => put!(f32),
                (_, Scalar::F64) => put!(f64),
            }
            self
        }

        fn list(&mut self, count: Scalar, item: Scalar, values: &[f64]) -> &mut Self {
            self.num(count, values.len() as f64);
            for &v in values {
                self.num(item, v);
            }
            self
        }

        /// Ends a record (a line break in ascii).
        fn end(&mut self) -> &mut Self {
            if self.format == Format::Ascii {
                self.body.push(b'\n');
            }
            self
        }

        fn bytes(&self) -> Vec<u8> {
            let mut out = self.head.clone().into_bytes();
            out.extend_from_slice(b"end_header\n");
            out.extend_from_slice(&self.body);
            out
        }
    }

    const FORMATS: [Format; 3] = [Format::Ascii, Format::BinaryLe, Format::BinaryBe];
    const POS: [[f32; 3]; 5] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 0.5, -1.25],
    ];
    /// A quad, a triangle, a pentagon and a two-vertex face: 3 triangles, 2 skipped.
    const FACES: [&[i64]; 4] = [&[0, 1, 2, 3], &[0, 1, 4], &[0, 1, 2, 3, 4], &[3, 4]];
    const TRIS: [u32; 9] = [0, 1, 2, 0, 2, 3, 0, 1, 4];

    fn normal(i: usize) -> [f32; 3] {
        if i == 4 {
            [0.0, 0.6, 0.8]
        } else {
            [0.0, 0.0, 1.0]
        }
    }

    fn uv(i: usize) -> [f32; 2] {
        [POS[i][0] * 0.5, POS[i][1] + 0.25]
    }

    /// A file layout: types and extras that select the fast or the generic paths.
    #[derive(Clone, Copy)]
    struct Layout {
        xyz: Scalar,
        z: Scalar,
        normals: bool,
        uv_names: Option<(&'static str, &'static str)>,
        vertex_extra_scalar: bool,
        vertex_extra_list: bool,
        count: Scalar,
        item: Scalar,
        face_pre: bool,
        face_post: bool,
        face_extra_list: bool,
        index_name: &'static str,
        edge_element: bool,
        faces_first: bool,
    }

    const PLAIN: Layout = Layout {
        xyz: Scalar::F32,
        z: Scalar::F32,
        normals: false,
        uv_names: None,
        vertex_extra_scalar: false,
        vertex_extra_list: false,
        count: Scalar::U8,
        item: Scalar::I32,
        face_pre: false,
        face_post: false,
        face_extra_list: false,
        index_name: "vertex_indices",
        edge_element: false,
        faces_first: false,
    };

    fn layouts() -> Vec<Layout> {
        vec![
            PLAIN,
            Layout {
                normals: true,
                uv_names: Some(("u", "v")),
                vertex_extra_scalar: true,
                item: Scalar::U32,
                face_post: true,
                ..PLAIN
            },
            Layout {
                normals: true,
                uv_names: Some(("s", "t")),
                z: Scalar::F64,
                count: Scalar::I32,
                face_pre: true,
                index_name: "vertex_index",
                edge_element: true,
                ..PLAIN
            },
            Layout {
                xyz: Scalar::F64,
                z: Scalar::F64,
                uv_names: Some(("texture_u", "texture_v")),
                vertex_extra_list: true,
                item: Scalar::U16,
                face_extra_list: true,
                faces_first: true,
                ..PLAIN
            },
            Layout {
                xyz: Scalar::I16,
                z: Scalar::I16,
                normals: true,
                uv_names: Some(("texture_s", "texture_t")),
                vertex_extra_scalar: true,
                vertex_extra_list: true,
                count: Scalar::U16,
                item: Scalar::U8,
                face_pre: true,
                face_post: true,
                edge_element: true,
                ..PLAIN
            },
        ]
    }

    fn build(format: Format, l: &Layout, faces: &[&[i64]]) -> Vec<u8> {
        let mut w = Writer::new(format);
        let ty = |t: Scalar| match t {
            Scalar::I8 => "char",
            Scalar::U8 => "uint8",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint32",
            Scalar::F32 => "float",
            Scalar::F64 => "float64",
        };
        let vertex_head = |w: &mut Writer| {
            w.head(&format!("element vertex {}", POS.len()));
            if l.vertex_extra_list {
                w.head("property list uchar float junk");
            }
            w.head(&format!("property {} x", ty(l.xyz)));
            w.head(&format!("property {} y", ty(l.xyz)));
            if l.vertex_extra_scalar {
                w.head("property uchar red");
            }
            w.head(&format!("property {} z", ty(l.z)));
            if l.normals {
                w.head("property float nx\nproperty float ny\nproperty float nz");
            }
            if let Some((u, v)) = l.uv_names {
                w.head(&format!("property float {u}\nproperty float {v}"));
            }
        };
        let face_head = |w: &mut Writer| {
            w.head(&format!("element face {}", faces.len()));
            if l.face_pre {
                w.head("property short flags");
            }
            w.head(&format!(
                "property list {} {} {}",
                ty(l.count),
                ty(l.item),
                l.index_name
            ));
            if l.face_extra_list {
                w.head("property list uchar float texcoord");
            }
            if l.face_post {
                w.head("property int face_indices");
            }
        };
        let vertex_body = |w: &mut Writer| {
            for (i, p) in POS.iter().enumerate() {
                if l.vertex_extra_list {
                    w.list(Scalar::U8, Scalar::F32, &[1.5; 3][..i % 3]);
                }
                w.num(l.xyz, p[0].into()).num(l.xyz, p[1].into());
                if l.vertex_extra_scalar {
                    w.num(Scalar::U8, 200.0);
                }
                w.num(l.z, p[2].into());
                if l.normals {
                    for c in normal(i) {
                        w.num(Scalar::F32, c.into());
                    }
                }
                if l.uv_names.is_some() {
                    for c in uv(i) {
                        w.num(Scalar::F32, c.into());
                    }
                }
                w.end();
            }
        };
        let face_body = |w: &mut Writer| {
            for (i, f) in faces.iter().enumerate() {
                if l.face_pre {
                    w.num(Scalar::I16, -7.0);
                }
                let idx: Vec<f64> = f.iter().map(|&i| i as f64).collect();
                w.list(l.count, l.item, &idx);
                if l.face_extra_list {
                    w.list(Scalar::U8, Scalar::F32, &[0.25; 6][..i % 6]);
                }
                if l.face_post {
                    w.num(Scalar::I32, i as f64);
                }
                w.end();
            }
        };
        if l.faces_first {
            face_head(&mut w);
            vertex_head(&mut w);
            face_body(&mut w);
            vertex_body(&mut w);
        } else {
            vertex_head(&mut w);
            face_head(&mut w);
            if l.edge_element {
                w.head("element edge 2\nproperty int vertex1\nproperty list ushort short ids");
            }
            vertex_body(&mut w);
            face_body(&mut w);
            if l.edge_element {
                w.num(Scalar::I32, 3.0)
                    .list(Scalar::U16, Scalar::I16, &[1.0, -2.0]);
                w.end();
                w.num(Scalar::I32, 4.0).list(Scalar::U16, Scalar::I16, &[]);
                w.end();
            }
        }
        w.bytes()
    }

    /// Every valid test file: each layout in each format.
    fn valid_files() -> Vec<(Format, Layout, Vec<u8>)> {
        let mut all = Vec::new();
        for format in FORMATS {
            for l in layouts() {
                all.push((format, l, build(format, &l, &FACES)));
            }
        }
        all
    }

    #[test]
    fn every_layout_reads_the_same_mesh() {
        for (format, l, bytes) in valid_files() {
            let ctx = format!("{format:?} {}", String::from_utf8_lossy(&bytes[..60]));
            let p = parse_ply(&bytes).unwrap_or_else(|e| panic!("{ctx}: {e}"));
            let m = &p.mesh;
            let want: Vec<[f32; 3]> = if l.xyz == Scalar::I16 {
                POS.iter().map(|p| p.map(|c| (c as i16).into())).collect()
            } else {
                POS.to_vec()
            };
            assert_eq!(m.positions, want, "{ctx}");
            assert_eq!(m.indices, TRIS, "{ctx}");
            let normals: Vec<[f32; 3]> = (0..5).map(normal).collect();
            assert_eq!(m.normals, l.normals.then_some(normals), "{ctx}");
            let uvs: Vec<[f32; 2]> = (0..5).map(uv).collect();
            assert_eq!(m.uvs, l.uv_names.map(|_| uvs), "{ctx}");
            assert_eq!(p.warnings.len(), 1, "{ctx}");
            assert!(p.warnings[0].contains("skipped 2 faces"), "{ctx}");
        }
    }

    #[test]
    fn triangles_only_give_no_warning() {
        for format in FORMATS {
            let bytes = build(format, &PLAIN, &[&[0, 1, 2], &[2, 3, 4]]);
            let p = parse_ply(&bytes).unwrap();
            assert_eq!(p.mesh.indices, vec![0, 1, 2, 2, 3, 4]);
            assert!(p.warnings.is_empty());
            assert_eq!(p.mesh.normals, None);
            assert_eq!(p.mesh.uvs, None);
        }
    }

    #[test]
    fn incomplete_normals_and_uvs_are_ignored() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nproperty float nx\nproperty float ny\nproperty float u\n\
                    property float t\nelement face 1\nproperty list uchar int vertex_indices\n\
                    end_header\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n3 0 1 2\n";
        let m = parse_ply(text.as_bytes()).unwrap().mesh;
        assert_eq!(m.positions[2], [0.0, 1.0, 0.0]);
        assert_eq!(m.normals, None);
        assert_eq!(m.uvs, None);
    }

    #[test]
    fn crlf_headers_and_odd_spacing() {
        for format in FORMATS {
            let bytes = build(format, &PLAIN, &FACES);
            let split = bytes
                .windows(11)
                .position(|w| w == b"end_header\n")
                .unwrap()
                + 11;
            let head = String::from_utf8(bytes[..split].to_vec())
                .unwrap()
                .replace('\n', " \r\n")
                .replace("property", "property \t");
            let mut crlf = head.into_bytes();
            crlf.extend_from_slice(&bytes[split..]);
            let p = parse_ply(&crlf).unwrap();
            assert_eq!(p.mesh.indices, TRIS);
        }
        let ascii = "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\n\
                     property float y\r\nproperty float z\r\nelement face 1\r\n\
                     property list uchar int vertex_indices\r\nend_header\r\n\
                     0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2";
        assert_eq!(parse_ply(ascii.as_bytes()).unwrap().mesh.indices, [0, 1, 2]);
    }

    #[test]
    fn elements_without_properties_are_free() {
        let text = "ply\nformat binary_little_endian 1.0\nelement nothing 18446744073709551615\n\
                    element vertex 3\nproperty uchar x\nproperty uchar y\nproperty uchar z\n\
                    element face 1\nproperty list uchar uchar vertex_indices\nend_header\n";
        let mut bytes = text.as_bytes().to_vec();
        bytes.extend_from_slice(&[0, 0, 0, 1, 0, 0, 0, 1, 0, 3, 0, 1, 2]);
        let m = parse_ply(&bytes).unwrap().mesh;
        assert_eq!(
            m.positions,
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        );
        assert_eq!(m.indices, [0, 1, 2]);
    }

    #[test]
    fn second_vertex_element_is_skipped_with_a_warning() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                    element vertex 1\nproperty float x\nend_header\n\
                    0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n7\n";
        let p = parse_ply(text.as_bytes()).unwrap();
        assert_eq!(p.mesh.positions.len(), 3);
        assert_eq!(p.warnings.len(), 1);
        assert!(p.warnings[0].contains("second 'vertex'"));
    }

    #[test]
    fn read_ply_reads_a_file() {
        let path = std::env::temp_dir().join(format!("acr-ply-test-{}.ply", std::process::id()));
        std::fs::write(&path, build(Format::BinaryBe, &layouts()[1], &FACES)).unwrap();
        let p = read_ply(&path);
        let _ = std::fs::remove_file(&path);
        assert_eq!(p.unwrap().mesh.indices, TRIS);
        let err = read_ply(Path::new("/nonexistent/acr/mesh.ply")).unwrap_err();
        assert!(err.contains("cannot read"), "{err}");
    }

    fn err_of(bytes: &[u8]) -> String {
        match parse_ply(bytes) {
            Ok(p) => panic!(
                "expected an error, got {} triangles",
                p.mesh.triangle_count()
            ),
            Err(e) => e,
        }
    }

    fn assert_err(bytes: &[u8], want: &str) {
        let e = err_of(bytes);
        assert!(e.contains(want), "want {want:?} in {e:?}");
    }

    const HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                        property float y\nproperty float z\nelement face 1\n\
                        property list uchar int vertex_indices\nend_header\n";

    #[test]
    fn bad_indices_are_errors() {
        let signed = PLAIN;
        let unsigned = Layout {
            item: Scalar::U32,
            ..PLAIN
        };
        let generic = Layout {
            item: Scalar::U16,
            ..PLAIN
        };
        for format in FORMATS {
            for l in [signed, unsigned, generic] {
                let b = build(format, &l, &[&[0, 1, 2], &[0, 1, 9]]);
                assert_err(&b, "face 1 has vertex index 9 but there are 5 vertices");
                let b = build(format, &l, &[&[0, 1, 2, 5]]);
                assert_err(&b, "face 0 has vertex index 5 but there are 5 vertices");
            }
            let b = build(format, &signed, &[&[0, -1, 2]]);
            assert_err(&b, "face 0 has vertex index -1 but");
            let b = build(format, &unsigned, &[&[0, u32::MAX.into(), 2]]);
            assert_err(&b, &format!("vertex index {}", u32::MAX));
        }
        assert_err(
            format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n").as_bytes(),
            "vertex index -1 but there are 3 vertices",
        );
        let float_items = HEAD.replace("uchar int", "uchar float");
        assert_err(
            format!("{float_items}0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n").as_bytes(),
            "not an integer",
        );
    }

    #[test]
    fn truncated_data_is_an_error() {
        let bytes = build(Format::BinaryLe, &PLAIN, &FACES);
        let body = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        // Inside the vertex records (12 bytes each): the check before reading says where.
        let e = err_of(&bytes[..body + 40]);
        assert!(
            e.contains("file ends inside vertex 3 (expected 20 more bytes)"),
            "{e}"
        );
        // Inside the faces.
        let e = err_of(&bytes[..bytes.len() - 3]);
        assert!(e.contains("file ends inside face"), "{e}");
        // Inside an edge element after the faces.
        let edges = Layout {
            edge_element: true,
            ..PLAIN
        };
        let bytes = build(Format::BinaryBe, &edges, &FACES);
        assert_err(&bytes[..bytes.len() - 2], "file ends inside edge 1");
        // Ascii.
        assert_err(
            format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1").as_bytes(),
            "file ends inside face 0",
        );
    }

    #[test]
    fn header_errors() {
        let cases: &[(&[u8], &str)] = &[
            (b"", "empty"),
            (b"plx\nformat ascii 1.0\nend_header\n", "does not start with \"ply\""),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n",
             "header line 4: unknown property type 'flaot'"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar flaot x\nend_header\n",
             "unknown property type 'flaot'"),
            (b"ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n",
             "integer type"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "no end_header"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n\xff\xfe", "not text"),
            (b"ply\nformat ebcdic 1.0\nend_header\n", "unknown format 'ebcdic'"),
            (b"ply\nformat ascii 2.0\nend_header\n", "version"),
            (b"ply\nelement vertex 1\nend_header\n", "no format line"),
            (b"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "before any element"),
            (b"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", "bad element count '-3'"),
            (b"ply\nformat ascii 1.0\nelement vertex\nend_header\n", "element <name> <count>"),
            (b"ply\nformat ascii 1.0\nelemnt vertex 3\nend_header\n", "unknown keyword 'elemnt'"),
            (b"ply\nformat ascii 1.0\nelement face 1\nproperty list int vertex_indices\nend_header\n",
             "property list"),
        ];
        for (text, want) in cases {
            assert_err(text, want);
        }
    }

    #[test]
    fn content_errors() {
        let cases: Vec<(String, &str)> = vec![
            (
                format!("{HEAD}0 0 0\n1 abc 0\n0 1 0\n3 0 1 2\n"),
                "ascii line 11: expected a number, found 'abc'",
            ),
            (
                format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3.0 0 1 2\n"),
                "ascii line 13: expected an integer, found '3.0'",
            ),
            (
                format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n"),
                "face 0 has a list of negative length -3",
            ),
            (
                format!("{HEAD}0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"),
                "vertex 1 has a position that is not finite",
            ),
            (
                format!("{HEAD}0 0 0\ninf 0 0\n0 1 0\n3 0 1 2\n"),
                "not finite",
            ),
            (HEAD.replace("property float x\n", ""), "no 'x' property"),
            (
                HEAD.replace("property float z", "property list uchar float z"),
                "vertex property 'z' is a list",
            ),
            (
                HEAD.replace(
                    "element face 1\nproperty list uchar int vertex_indices\n",
                    "",
                ),
                "no face element",
            ),
            (
                HEAD.replace("element vertex 3", "element point 3"),
                "no vertex element",
            ),
            (
                HEAD.replace("list uchar int vertex_indices", "int vertex_indices"),
                "'vertex_indices' is not a list",
            ),
            (
                HEAD.replace("vertex_indices", "indices"),
                "no 'vertex_indices' list",
            ),
            (HEAD.replace("face 1", "face 0"), "no faces"),
            (HEAD.replace("vertex 3", "vertex 0"), "no vertices"),
            (
                HEAD.replace("vertex 3", "vertex 5000000000"),
                "more than 4294967295",
            ),
            (
                format!(
                    "{}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                    HEAD.replace("vertex 3", "vertex 3000")
                ),
                "declares 3000 'vertex' records",
            ),
        ];
        for (text, want) in cases {
            assert_err(text.as_bytes(), want);
        }
    }

    #[test]
    fn hostile_counts_are_errors_not_allocations() {
        let bin = |head: &str, body: &[u8]| {
            let mut b =
                format!("ply\nformat binary_little_endian 1.0\n{head}end_header\n").into_bytes();
            b.extend_from_slice(body);
            b
        };
        let v3 = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
        let verts: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let faces = "property list uchar int vertex_indices\n";
        // Huge vertex count: exact message for fixed-size records.
        assert_err(
            &bin(
                &format!(
                    "{}element face 1\n{faces}",
                    v3.replace("vertex 3", "vertex 4000000000")
                ),
                &verts,
            ),
            "file ends inside vertex 3 (expected 47999999964 more bytes)",
        );
        // Huge face count.
        assert_err(
            &bin(&format!("{v3}element face 4000000000\n{faces}"), &verts),
            "declares 4000000000 'face' records",
        );
        // usize::MAX records of an element with properties.
        assert_err(
            &bin(&format!("element junk 18446744073709551615\nproperty double a\n{v3}element face 1\n{faces}"), &verts),
            "file ends inside junk 4 (expected 147573952589676412884 more bytes)",
        );
        // A list claiming 4 billion items.
        let mut body = verts.clone();
        body.extend_from_slice(&[3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
        body.extend_from_slice(&u32::MAX.to_le_bytes());
        assert_err(
            &bin(
                &format!(
                    "{v3}element face 1\n{faces}element edge 1\nproperty list uint double w\n"
                ),
                &body,
            ),
            "file ends inside edge 0",
        );
        let mut body = verts.clone();
        body.extend_from_slice(&u32::MAX.to_le_bytes());
        assert_err(
            &bin(
                &format!("{v3}element face 1\nproperty list uint int vertex_indices\n"),
                &body,
            ),
            "file ends inside face 0",
        );
        let mut body = verts;
        body.extend_from_slice(&(-5i32).to_le_bytes());
        assert_err(
            &bin(
                &format!("{v3}element face 1\nproperty list int int vertex_indices\n"),
                &body,
            ),
            "negative length -5",
        );
        // Ascii list with a huge length ends at the end of the file.
        assert_err(
            format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n").as_bytes(),
            "file ends inside face 0",
        );
    }

    /// A small deterministic generator for the corruption test.
    fn xorshift(state: &mut u64) -> u64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        *state
    }

    #[test]
    fn truncated_and_corrupted_files_never_panic() {
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        for (format, _, full) in valid_files() {
            for end in 0..full.len() {
                let r = parse_ply(&full[..end]);
                if format != Format::Ascii {
                    assert!(r.is_err(), "{format:?} truncated to {end} bytes parsed");
                }
            }
            for _ in 0..300 {
                let mut b = full.clone();
                for _ in 0..1 + xorshift(&mut rng) % 3 {
                    let i = (xorshift(&mut rng) % b.len() as u64) as usize;
                    b[i] = match xorshift(&mut rng) % 4 {
                        0 => 0xff,
                        1 => 0,
                        2 => b[i] ^ (1 << (xorshift(&mut rng) % 8)),
                        _ => xorshift(&mut rng) as u8,
                    };
                }
                let _ = parse_ply(&b);
            }
        }
    }
}
