//! The PLY reader's tests.

use super::types::Scalar;
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
                self.body
                    .extend_from_slice(&if be { x.to_be_bytes() } else { x.to_le_bytes() });
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
        &bin(
            &format!(
                "element junk 18446744073709551615\nproperty double a\n{v3}element face 1\n{faces}"
            ),
            &verts,
        ),
        "file ends inside junk 4 (expected 147573952589676412884 more bytes)",
    );
    // A list claiming 4 billion items.
    let mut body = verts.clone();
    body.extend_from_slice(&[3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
    body.extend_from_slice(&u32::MAX.to_le_bytes());
    assert_err(
        &bin(
            &format!("{v3}element face 1\n{faces}element edge 1\nproperty list uint double w\n"),
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
