//! Criterion benchmark of `acr parse` on a generated large scene (docs/BENCHMARKS.md): parsing, and
//! the scene-graph dump, which prints a location per directive and parameter. Run with
//! `cargo bench --bench parse`; throughput prints as bytes/s of scene text.

use acr::parser::parse_str;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use std::path::Path;

/// Shapes in the generated scene: about 1.9 MB of text (a tenth of the 19 MB scene that
/// docs/pbrt-v3-compatibility.md times `acr parse` on).
const SHAPES: u64 = 4000;

/// A scene of `SHAPES` small triangle meshes, each in its own attribute block with a material
/// and a transform, with pseudo-random numbers (fixed, so every run parses the same text).
fn scene() -> String {
    let mut state = 1u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f64 / (1u64 << 24) as f64
    };
    let mut s = String::from(
        "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\" \"float fov\" [45]\n\
         Film \"image\" \"integer xresolution\" [64] \"integer yresolution\" [64]\n\
         WorldBegin\nLightSource \"infinite\"\n",
    );
    for _ in 0..SHAPES {
        let kd: Vec<String> = (0..3).map(|_| format!("{:.3}", next())).collect();
        let t: Vec<String> = (0..3).map(|_| format!("{:.3}", next())).collect();
        let p: Vec<String> = (0..36).map(|_| format!("{:.5}", next())).collect();
        s += &format!(
            "AttributeBegin\n  Material \"matte\" \"rgb Kd\" [{}]\n  Translate {}\n  \
             Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3 4 5 6 7 8 9] \
             \"point P\" [ {} ]\nAttributeEnd\n",
            kd.join(" "),
            t.join(" "),
            p.join(" ")
        );
    }
    s + "WorldEnd\n"
}

fn parse(c: &mut Criterion) {
    let text = scene();
    let mut group = c.benchmark_group("parse");
    group.throughput(Throughput::Bytes(text.len() as u64));
    group.sample_size(10);
    group.bench_function("parse", |b| {
        b.iter(|| black_box(parse_str(&text, Path::new("large.pbrt")).unwrap()))
    });
    let desc = parse_str(&text, Path::new("large.pbrt")).unwrap();
    group.bench_function("dump", |b| b.iter(|| black_box(desc.to_text())));
    group.bench_function("parse_and_dump", |b| {
        b.iter(|| black_box(parse_str(&text, Path::new("large.pbrt")).unwrap().to_text()))
    });
    group.finish();
}

criterion_group!(benches, parse);
criterion_main!(benches);
