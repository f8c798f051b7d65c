//! Parsing throughput: scene text in MB/s, and a 1M-triangle binary PLY.
//! Run with `cargo bench -p acr-parser --bench parse`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::fmt::Write as _;
use std::hint::black_box;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// A scene like an exporter writes: many meshes, numbers with 6-8 significant digits.
fn scene_text(target_bytes: usize) -> String {
    let mut s = String::from(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [45]\nWorldBegin\n",
    );
    let mut k = 0u64;
    while s.len() < target_bytes {
        let _ = writeln!(
            s,
            "AttributeBegin\n  Translate {} 0 0\n  Material \"plastic\" \"rgb Kd\" [0.25 0.5 0.75]",
            k % 17
        );
        s.push_str("  Shape \"trianglemesh\"\n    \"point3 P\" [");
        for i in 0..300u64 {
            let x = ((i * 7919 + k) % 10007) as f64 / 10007.0;
            let _ = write!(s, "{:.7} {:.6} {:.7} ", x - 0.5, x * 3.1, 1.0 - x);
        }
        s.push_str("]\n    \"integer indices\" [");
        for i in 0..298u64 {
            let _ = write!(s, "{} {} {} ", i, i + 1, i + 2);
        }
        s.push_str("]\nAttributeEnd\n");
        k += 1;
    }
    s.push_str("WorldEnd\n");
    s
}

/// Writes a binary little-endian PLY grid with `2 * n * n` triangles.
fn write_ply(path: &Path, n: usize) {
    let verts = (n + 1) * (n + 1);
    let mut out = Vec::with_capacity(verts * 12 + 2 * n * n * 13 + 256);
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\nelement vertex {verts}\n\
         property float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        2 * n * n
    )
    .unwrap();
    for j in 0..=n {
        for i in 0..=n {
            for c in [i as f32, j as f32, ((i * j) % 7) as f32 * 0.1] {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let idx = |i: usize, j: usize| (j * (n + 1) + i) as i32;
    for j in 0..n {
        for i in 0..n {
            for tri in [
                [idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)],
                [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)],
            ] {
                out.push(3);
                for v in tri {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
    }
    std::fs::write(path, out).unwrap();
}

fn bench_text(c: &mut Criterion) {
    let text = scene_text(8 << 20);
    let mut g = c.benchmark_group("parse");
    g.sample_size(10);
    g.throughput(Throughput::Bytes(text.len() as u64));
    g.bench_function("scene_text_8MB", |b| {
        b.iter(|| acr_parser::parse_str(black_box(&text), Path::new("bench.pbrt")).unwrap())
    });
    g.finish();
}

fn bench_ply(c: &mut Criterion) {
    let dir: PathBuf = std::env::temp_dir().join(format!("acr-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ply = dir.join("grid.ply");
    write_ply(&ply, 708); // 2 * 708^2 = 1,002,528 triangles
    let scene = dir.join("scene.pbrt");
    std::fs::write(
        &scene,
        "WorldBegin\nShape \"plymesh\" \"string filename\" \"grid.ply\"\nWorldEnd\n",
    )
    .unwrap();
    let mut g = c.benchmark_group("ply");
    g.sample_size(10);
    g.bench_function("plymesh_1M_triangles", |b| {
        b.iter(|| {
            let d = acr_parser::parse_file(black_box(&scene)).unwrap();
            assert_eq!(
                d.shapes[0].mesh.as_ref().unwrap().triangle_count(),
                1_002_528
            );
            d
        })
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench_text, bench_ply);
criterion_main!(benches);
