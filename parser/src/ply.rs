//! PLY meshes for pbrt's `plymesh`: ascii, binary little and big endian; positions, normals,
//! texture coordinates; triangles and quads (split in two, as pbrt-v3 does).
//!
//! Never panics on any input: every read is bounds-checked and no count from the header is
//! trusted for an allocation before the bytes it implies are known to exist.

use crate::mesh::Mesh;
use std::path::Path;

/// A mesh read from a PLY file, with what was skipped.
#[derive(Debug)]
pub struct Ply {
    /// The triangles.
    pub mesh: Mesh,
    /// Things ignored, worth a warning.
    pub warnings: Vec<String>,
}

/// Reads a PLY file from disk.
pub fn read_ply(path: &Path) -> Result<Ply, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    parse_ply(&bytes)
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
    fn parse(name: &str) -> Option<Self> {
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
}

#[derive(Clone, Debug)]
enum Property {
    Scalar {
        ty: Scalar,
        name: String,
    },
    List {
        count: Scalar,
        item: Scalar,
        name: String,
    },
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar { name, .. } | Property::List { name, .. } => name,
        }
    }
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    body_start: usize,
}

fn parse_header(bytes: &[u8]) -> Result<Header, String> {
    const END: &[u8] = b"end_header";
    let end = bytes
        .windows(END.len())
        .position(|w| w == END)
        .ok_or("header: no end_header line")?;
    let mut body_start = end + END.len();
    // The header ends with the line break after end_header (\n or \r\n).
    match bytes.get(body_start) {
        Some(b'\r') if bytes.get(body_start + 1) == Some(&b'\n') => body_start += 2,
        Some(b'\n') => body_start += 1,
        None => {}
        Some(_) => return Err("header: end_header is not followed by a line break".into()),
    }
    let text = std::str::from_utf8(&bytes[..end]).map_err(|_| "header: not ASCII text")?;
    let mut lines = text.lines().map(str::trim);
    if lines.next() != Some("ply") {
        return Err("header: the file does not start with \"ply\"".into());
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (n, line) in lines.enumerate() {
        let line_no = n + 2;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    other => {
                        return Err(format!("header line {line_no}: unknown format '{other}'"))
                    }
                });
            }
            ["element", name, count] => {
                let count = count
                    .parse::<usize>()
                    .map_err(|_| format!("header line {line_no}: bad element count '{count}'"))?;
                elements.push(Element {
                    name: (*name).to_owned(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", count, item, name] => {
                let el = elements.last_mut().ok_or(format!(
                    "header line {line_no}: property before any element"
                ))?;
                let count = Scalar::parse(count).ok_or(format!(
                    "header line {line_no}: unknown property type '{count}'"
                ))?;
                let item = Scalar::parse(item).ok_or(format!(
                    "header line {line_no}: unknown property type '{item}'"
                ))?;
                if matches!(count, Scalar::F32 | Scalar::F64) {
                    return Err(format!(
                        "header line {line_no}: a list count cannot be a float"
                    ));
                }
                el.props.push(Property::List {
                    count,
                    item,
                    name: (*name).to_owned(),
                });
            }
            ["property", ty, name] => {
                let el = elements.last_mut().ok_or(format!(
                    "header line {line_no}: property before any element"
                ))?;
                let ty = Scalar::parse(ty).ok_or(format!(
                    "header line {line_no}: unknown property type '{ty}'"
                ))?;
                el.props.push(Property::Scalar {
                    ty,
                    name: (*name).to_owned(),
                });
            }
            _ => return Err(format!("header line {line_no}: cannot read '{line}'")),
        }
    }
    let format = format.ok_or("header: no format line")?;
    Ok(Header {
        format,
        elements,
        body_start,
    })
}

/// Reads scalars from the body, in whichever encoding.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: Format,
    /// Ascii: 1-based line of the current position, for messages.
    line: usize,
}

impl Reader<'_> {
    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    #[inline]
    fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let end = self.pos.checked_add(N).ok_or("offset overflow")?;
        let s = self
            .bytes
            .get(self.pos..end)
            .ok_or("the file ends early: the header promises more data")?;
        self.pos = end;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    fn ascii_token(&mut self) -> Result<&str, String> {
        while let Some(&b) = self.bytes.get(self.pos) {
            if b == b'\n' {
                self.line += 1;
            }
            if !b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while let Some(&b) = self.bytes.get(self.pos) {
            if b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        if start == self.pos {
            return Err("the file ends early: the header promises more data".into());
        }
        std::str::from_utf8(&self.bytes[start..self.pos])
            .map_err(|_| format!("ascii line {}: not a number", self.line))
    }

    /// One scalar as f64.
    #[inline]
    fn read(&mut self, ty: Scalar) -> Result<f64, String> {
        if self.format == Format::Ascii {
            let line = self.line;
            let tok = self.ascii_token()?;
            return tok
                .parse::<f64>()
                .map_err(|_| format!("ascii line {line}: expected a number, found '{tok}'"));
        }
        let le = self.format == Format::BinaryLe;
        macro_rules! num {
            ($t:ty, $n:literal) => {{
                let b = self.take::<$n>()?;
                (if le {
                    <$t>::from_le_bytes(b)
                } else {
                    <$t>::from_be_bytes(b)
                }) as f64
            }};
        }
        Ok(match ty {
            Scalar::I8 => num!(i8, 1),
            Scalar::U8 => num!(u8, 1),
            Scalar::I16 => num!(i16, 2),
            Scalar::U16 => num!(u16, 2),
            Scalar::I32 => num!(i32, 4),
            Scalar::U32 => num!(u32, 4),
            Scalar::F32 => num!(f32, 4),
            Scalar::F64 => num!(f64, 8),
        })
    }

    /// A list's length.
    fn read_count(&mut self, ty: Scalar) -> Result<usize, String> {
        let v = self.read(ty)?;
        if v < 0.0 || v.fract() != 0.0 || v > u32::MAX as f64 {
            return Err(format!("bad list length {v}"));
        }
        Ok(v as usize)
    }

    fn skip(&mut self, p: &Property) -> Result<(), String> {
        match p {
            Property::Scalar { ty, .. } => {
                self.read(*ty)?;
            }
            Property::List { count, item, .. } => {
                let n = self.read_count(*count)?;
                if self.format == Format::Ascii {
                    for _ in 0..n {
                        self.read(*item)?;
                    }
                } else {
                    let len = n.checked_mul(item.size()).ok_or("list too long")?;
                    if len > self.remaining() {
                        return Err("the file ends inside a list".into());
                    }
                    self.pos += len;
                }
            }
        }
        Ok(())
    }
}

/// Where each wanted vertex property is in a vertex record.
#[derive(Default)]
struct VertexLayout {
    xyz: [Option<usize>; 3],
    normal: [Option<usize>; 3],
    uv: [Option<usize>; 2],
}

fn vertex_layout(el: &Element) -> VertexLayout {
    let mut l = VertexLayout::default();
    for (i, p) in el.props.iter().enumerate() {
        if !matches!(p, Property::Scalar { .. }) {
            continue;
        }
        match p.name() {
            "x" => l.xyz[0] = Some(i),
            "y" => l.xyz[1] = Some(i),
            "z" => l.xyz[2] = Some(i),
            "nx" => l.normal[0] = Some(i),
            "ny" => l.normal[1] = Some(i),
            "nz" => l.normal[2] = Some(i),
            "u" | "s" | "texture_u" | "texture_s" => l.uv[0] = Some(i),
            "v" | "t" | "texture_v" | "texture_t" => l.uv[1] = Some(i),
            _ => {}
        }
    }
    l
}

/// Parses PLY bytes (ascii, binary_little_endian, binary_big_endian).
pub fn parse_ply(bytes: &[u8]) -> Result<Ply, String> {
    let header = parse_header(bytes)?;
    let mut r = Reader {
        bytes,
        pos: header.body_start,
        format: header.format,
        line: 1 + bytes[..header.body_start.min(bytes.len())]
            .iter()
            .filter(|&&b| b == b'\n')
            .count(),
    };
    let mut warnings = Vec::new();
    let mut mesh = Mesh::default();
    let mut have_vertices = false;
    let mut have_faces = false;
    let mut skipped_faces = 0usize;
    for el in &header.elements {
        // Each record is at least one byte (binary) or two (ascii: a digit and a space).
        let min_record = if header.format == Format::Ascii { 2 } else { 1 };
        if el.count.saturating_mul(min_record) > r.remaining() && !el.props.is_empty() {
            return Err(format!(
                "element '{}' claims {} records, more than the file holds",
                el.name, el.count
            ));
        }
        match el.name.as_str() {
            "vertex" => {
                have_vertices = true;
                read_vertices(&mut r, el, &mut mesh)?;
            }
            "face" => {
                have_faces = true;
                skipped_faces += read_faces(&mut r, el, &mut mesh)?;
            }
            // An element without properties has nothing to read, however many it claims.
            _ if el.props.is_empty() => {}
            _ => {
                for _ in 0..el.count {
                    for p in &el.props {
                        r.skip(p)?;
                    }
                }
            }
        }
    }
    if !have_vertices {
        return Err("no vertex element".into());
    }
    if !have_faces {
        return Err("no face element".into());
    }
    if skipped_faces > 0 {
        warnings.push(format!(
            "skipped {skipped_faces} faces with fewer than 3 or more than 4 vertices"
        ));
    }
    mesh.validate()?;
    Ok(Ply { mesh, warnings })
}

fn read_vertices(r: &mut Reader, el: &Element, mesh: &mut Mesh) -> Result<(), String> {
    let l = vertex_layout(el);
    let [Some(ix), Some(iy), Some(iz)] = l.xyz else {
        return Err("vertex element lacks x, y or z".into());
    };
    let has_normals = l.normal.iter().all(Option::is_some);
    let has_uv = l.uv.iter().all(Option::is_some);
    mesh.positions.reserve(el.count);
    if has_normals {
        mesh.normals = Some(Vec::with_capacity(el.count));
    }
    if has_uv {
        mesh.uvs = Some(Vec::with_capacity(el.count));
    }
    let all_scalar = el
        .props
        .iter()
        .all(|p| matches!(p, Property::Scalar { .. }));
    let all_f32 = el.props.iter().all(|p| {
        matches!(
            p,
            Property::Scalar {
                ty: Scalar::F32,
                ..
            }
        )
    });
    // Fast path: fixed-size records of f32, the common binary layout.
    if r.format != Format::Ascii && all_scalar && all_f32 {
        let stride = 4 * el.props.len();
        let len = el
            .count
            .checked_mul(stride)
            .ok_or("vertex data too large")?;
        let data = r
            .bytes
            .get(r.pos..r.pos.checked_add(len).ok_or("vertex data too large")?)
            .ok_or("the file ends inside the vertex data")?;
        let le = r.format == Format::BinaryLe;
        let f = |rec: &[u8], i: usize| -> f32 {
            let b = [rec[4 * i], rec[4 * i + 1], rec[4 * i + 2], rec[4 * i + 3]];
            if le {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            }
        };
        for rec in data.chunks_exact(stride) {
            mesh.positions.push([f(rec, ix), f(rec, iy), f(rec, iz)]);
            if let (Some(n), [Some(a), Some(b), Some(c)]) = (&mut mesh.normals, l.normal) {
                n.push([f(rec, a), f(rec, b), f(rec, c)]);
            }
            if let (Some(uv), [Some(a), Some(b)]) = (&mut mesh.uvs, l.uv) {
                uv.push([f(rec, a), f(rec, b)]);
            }
        }
        r.pos += len;
        return Ok(());
    }
    let mut values = vec![0.0f64; el.props.len()];
    for _ in 0..el.count {
        for (i, p) in el.props.iter().enumerate() {
            match p {
                Property::Scalar { ty, .. } => values[i] = r.read(*ty)?,
                Property::List { .. } => r.skip(p)?,
            }
        }
        mesh.positions
            .push([values[ix] as f32, values[iy] as f32, values[iz] as f32]);
        if let (Some(n), [Some(a), Some(b), Some(c)]) = (&mut mesh.normals, l.normal) {
            n.push([values[a] as f32, values[b] as f32, values[c] as f32]);
        }
        if let (Some(uv), [Some(a), Some(b)]) = (&mut mesh.uvs, l.uv) {
            uv.push([values[a] as f32, values[b] as f32]);
        }
    }
    Ok(())
}

/// Reads the faces; returns how many were skipped for their vertex count.
fn read_faces(r: &mut Reader, el: &Element, mesh: &mut Mesh) -> Result<usize, String> {
    let Some(list_index) = el.props.iter().position(|p| {
        matches!(p, Property::List { .. }) && matches!(p.name(), "vertex_indices" | "vertex_index")
    }) else {
        return Err("face element lacks a vertex_indices list".into());
    };
    let Property::List { count, item, .. } = el.props[list_index] else {
        return Err("face element lacks a vertex_indices list".into());
    };
    mesh.indices.reserve(el.count.saturating_mul(3));
    let n_vertices = mesh.positions.len();
    let mut skipped = 0;
    let le = r.format == Format::BinaryLe;
    // Fast path: the face holds only the list, with a uchar count and 32-bit indices.
    let fast = r.format != Format::Ascii
        && el.props.len() == 1
        && count == Scalar::U8
        && matches!(item, Scalar::I32 | Scalar::U32);
    let mut face = [0i64; 4];
    for f in 0..el.count {
        let mut n = 0;
        if fast {
            let k = *r
                .bytes
                .get(r.pos)
                .ok_or("the file ends inside the face data")? as usize;
            let rec = r
                .bytes
                .get(r.pos + 1..r.pos + 1 + 4 * k)
                .ok_or("the file ends inside the face data")?;
            r.pos += 1 + 4 * k;
            if k == 3 || k == 4 {
                for (i, c) in rec.chunks_exact(4).enumerate() {
                    let b = [c[0], c[1], c[2], c[3]];
                    face[i] = if item == Scalar::I32 {
                        i64::from(if le {
                            i32::from_le_bytes(b)
                        } else {
                            i32::from_be_bytes(b)
                        })
                    } else {
                        i64::from(if le {
                            u32::from_le_bytes(b)
                        } else {
                            u32::from_be_bytes(b)
                        })
                    };
                }
                n = k;
            }
        } else {
            for (i, p) in el.props.iter().enumerate() {
                if i != list_index {
                    r.skip(p)?;
                    continue;
                }
                let k = r.read_count(count)?;
                for j in 0..k {
                    let v = r.read(item)?;
                    if let Some(slot) = face.get_mut(j) {
                        if v.fract() != 0.0 {
                            return Err(format!("face {f} has a non-integer vertex index {v}"));
                        }
                        *slot = v as i64;
                    }
                }
                if k == 3 || k == 4 {
                    n = k;
                }
            }
        }
        if n == 0 {
            skipped += 1;
            continue;
        }
        for &v in &face[..n] {
            if v < 0 || v as usize >= n_vertices {
                return Err(format!(
                    "face {f} has vertex index {v} but there are {n_vertices} vertices"
                ));
            }
        }
        let idx = |i: usize| face[i] as u32;
        mesh.indices.extend([idx(0), idx(1), idx(2)]);
        if n == 4 {
            mesh.indices.extend([idx(0), idx(2), idx(3)]);
        }
    }
    Ok(skipped)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes a PLY: vertices (x y z [nx ny nz] [u v]) and faces, in the given format.
    fn ply(
        format: Format,
        verts: &[Vec<f32>],
        props: &[&str],
        faces: &[Vec<i32>],
        extra: bool,
    ) -> Vec<u8> {
        let fmt = match format {
            Format::Ascii => "ascii",
            Format::BinaryLe => "binary_little_endian",
            Format::BinaryBe => "binary_big_endian",
        };
        let mut h = format!(
            "ply\nformat {fmt} 1.0\ncomment test\nelement vertex {}\n",
            verts.len()
        );
        for p in props {
            h += &format!("property float {p}\n");
        }
        if extra {
            h += "property uchar red\n";
        }
        h += &format!(
            "element face {}\nproperty list uchar int vertex_indices\n",
            faces.len()
        );
        if extra {
            h += "property int flags\nelement edge 1\nproperty int vertex1\nproperty list uchar float w\n";
        }
        h += "end_header\n";
        let mut out = h.into_bytes();
        let num = |out: &mut Vec<u8>, b4: [u8; 4], b4be: [u8; 4]| match format {
            Format::BinaryLe => out.extend_from_slice(&b4),
            Format::BinaryBe => out.extend_from_slice(&b4be),
            Format::Ascii => {}
        };
        for v in verts {
            if format == Format::Ascii {
                let s: Vec<String> = v.iter().map(|x| x.to_string()).collect();
                out.extend_from_slice(s.join(" ").as_bytes());
                if extra {
                    out.extend_from_slice(b" 255");
                }
                out.push(b'\n');
            } else {
                for x in v {
                    num(&mut out, x.to_le_bytes(), x.to_be_bytes());
                }
                if extra {
                    out.push(255);
                }
            }
        }
        for f in faces {
            if format == Format::Ascii {
                let s: Vec<String> = f.iter().map(|x| x.to_string()).collect();
                out.extend_from_slice(format!("{} {}", f.len(), s.join(" ")).as_bytes());
                if extra {
                    out.extend_from_slice(b" 7");
                }
                out.push(b'\n');
            } else {
                out.push(f.len() as u8);
                for x in f {
                    num(&mut out, x.to_le_bytes(), x.to_be_bytes());
                }
                if extra {
                    num(&mut out, 7i32.to_le_bytes(), 7i32.to_be_bytes());
                }
            }
        }
        if extra {
            if format == Format::Ascii {
                out.extend_from_slice(b"3 2 0.5 0.25\n");
            } else {
                num(&mut out, 3i32.to_le_bytes(), 3i32.to_be_bytes());
                out.push(2);
                num(&mut out, 0.5f32.to_le_bytes(), 0.5f32.to_be_bytes());
                num(&mut out, 0.25f32.to_le_bytes(), 0.25f32.to_be_bytes());
            }
        }
        out
    }

    fn quad_and_triangle(format: Format, extra: bool) -> Vec<u8> {
        let verts = vec![
            vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            vec![1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0],
            vec![1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0],
            vec![0.5, 0.5, 1.0, 0.0, 1.0, 0.0, 0.5, 0.5],
        ];
        let props = ["x", "y", "z", "nx", "ny", "nz", "u", "v"];
        let faces = vec![vec![0, 1, 2, 3], vec![0, 1, 4]];
        ply(format, &verts, &props, &faces, extra)
    }

    #[test]
    fn every_format_reads_the_same_mesh() {
        for format in [Format::Ascii, Format::BinaryLe, Format::BinaryBe] {
            for extra in [false, true] {
                let p = parse_ply(&quad_and_triangle(format, extra)).unwrap();
                let m = &p.mesh;
                assert_eq!(m.positions.len(), 5, "{format:?}");
                assert_eq!(m.positions[4], [0.5, 0.5, 1.0]);
                assert_eq!(m.indices, vec![0, 1, 2, 0, 2, 3, 0, 1, 4]);
                assert_eq!(m.normals.as_ref().unwrap()[4], [0.0, 1.0, 0.0]);
                assert_eq!(m.uvs.as_ref().unwrap()[2], [1.0, 1.0]);
                assert!(p.warnings.is_empty());
            }
        }
    }

    #[test]
    fn positions_only_and_crlf_header() {
        let verts = vec![
            vec![0.0, 0.0, 0.0],
            vec![1.0, 0.0, 0.0],
            vec![0.0, 1.0, 0.0],
        ];
        let bytes = ply(
            Format::BinaryLe,
            &verts,
            &["x", "y", "z"],
            &[vec![0, 1, 2]],
            false,
        );
        let text =
            String::from_utf8_lossy(&bytes[..bytes.iter().position(|&b| b == b'e').unwrap()]);
        assert!(text.starts_with("ply"));
        let m = parse_ply(&bytes).unwrap().mesh;
        assert!(m.normals.is_none() && m.uvs.is_none());
        let crlf = String::from_utf8(ply(
            Format::Ascii,
            &verts,
            &["x", "y", "z"],
            &[vec![0, 1, 2]],
            false,
        ))
        .unwrap()
        .replace('\n', "\r\n");
        assert_eq!(
            parse_ply(crlf.as_bytes()).unwrap().mesh.indices,
            vec![0, 1, 2]
        );
    }

    #[test]
    fn pentagons_are_skipped_with_a_warning() {
        let verts: Vec<Vec<f32>> = (0..5)
            .map(|i| vec![i as f32, (i * i) as f32, 0.0])
            .collect();
        let faces = vec![vec![0, 1, 2, 3, 4], vec![0, 1, 2]];
        let p = parse_ply(&ply(
            Format::BinaryLe,
            &verts,
            &["x", "y", "z"],
            &faces,
            false,
        ))
        .unwrap();
        assert_eq!(p.mesh.indices, vec![0, 1, 2]);
        assert_eq!(p.warnings.len(), 1);
        assert!(p.warnings[0].contains("skipped 1 faces"));
    }

    #[test]
    fn errors_are_reported() {
        let verts = vec![
            vec![0.0, 0.0, 0.0],
            vec![1.0, 0.0, 0.0],
            vec![0.0, 1.0, 0.0],
        ];
        let xyz = ["x", "y", "z"];
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (ply(Format::BinaryLe, &verts, &xyz, &[vec![0, 1, 9]], false), "vertex index 9"),
            (ply(Format::Ascii, &verts, &xyz, &[vec![0, -1, 2]], false), "vertex index -1"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n".to_vec(), "unknown property type 'flaot'"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n".to_vec(), "end_header"),
            (b"plx\nformat ascii 1.0\nend_header\n".to_vec(), "does not start"),
            (b"ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nend_header\n0\n".to_vec(), "more than the file holds"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 zero 0\n".to_vec(), "expected a number"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0\n".to_vec(), "lacks x"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n".to_vec(), "no face element"),
        ];
        for (bytes, want) in cases {
            let err = parse_ply(&bytes).unwrap_err();
            assert!(err.contains(want), "want {want:?}, got {err:?}");
        }
        let mut truncated = ply(Format::BinaryLe, &verts, &xyz, &[vec![0, 1, 2]], false);
        truncated.truncate(truncated.len() - 3);
        assert!(parse_ply(&truncated).unwrap_err().contains("ends"));
    }

    #[test]
    fn truncations_and_corruptions_never_panic() {
        for format in [Format::Ascii, Format::BinaryLe, Format::BinaryBe] {
            let full = quad_and_triangle(format, true);
            for end in 0..full.len() {
                let _ = parse_ply(&full[..end]);
            }
            for i in 0..full.len() {
                let mut b = full.clone();
                b[i] = b[i].wrapping_add(0x55);
                let _ = parse_ply(&b);
            }
        }
    }
}
