//! Criterion micro-benchmarks of the hot paths (docs/BENCHMARKS.md): BVH traversal on a 1M-triangle
//! mesh (coherent camera rays and scattered rays; closest hit and shadow query; 1 and 2 threads),
//! one full round of every sampler, and the film's splatting and reconstruction.
//! Run with `cargo bench --bench hot_paths`; throughputs print as elements/s (rays, samples or
//! pixels per second).

use acr::accel::{Accel, Prim, PrimKind};
use acr::camera::CameraSample;
use acr::geometry::{Ray, Vec2, Vec3};
use acr::shapes::TriangleMesh;
use acr_plugins::sampler::BATCH_SAMPLES;
use acr_plugins::{
    Choice, Dims, Film, FilmSettings, RenderingSpace, SamplePoint, Sampler, SamplerSetup, FILTERS,
    SAMPLERS,
};
use criterion::{
    criterion_group, criterion_main, BatchSize, BenchmarkGroup, BenchmarkId, Criterion,
    SamplingMode, Throughput,
};
use rayon::prelude::*;
use rayon::ThreadPool;
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

/// Image side in pixels: one camera ray per pixel, and the sampler and film resolution.
const RES: u32 = 512;
/// Samples per pixel of the sampler and film benchmarks.
const SPP: u32 = 16;
/// Cube-sphere cells per face side: 6 * 2 * 289^2 = 1,002,252 triangles.
const CELLS: u32 = 289;
/// Where the mesh sits, in front of the camera at the origin (render space is then world space).
const CENTER: Vec3 = Vec3::new(0.0, 0.0, 3.0);
/// Worker threads the parallel runs use: the renderer's on the 2-core reference machine.
const THREADS: usize = 2;

/// splitmix64: a small deterministic generator, so that every run traces the same rays.
struct Rng(u64);

impl Rng {
    /// The next 64 random bits.
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix(self.0)
    }

    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// SplitMix64's finaliser: a 64-bit hash.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A pool of `n` threads, to trace as the renderer does whatever the machine's core count.
fn pool(n: usize) -> ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .expect("rayon pool")
}

/// A bumpy, noisy sphere of radius about 1 at `center`: a subdivided cube projected onto the
/// sphere (no slivers at poles), with smooth bumps and per-vertex jitter so that the BVH sees
/// an irregular surface, not a regular grid.
fn noisy_sphere(cells: u32, center: Vec3) -> TriangleMesh {
    let side = cells + 1;
    let mut positions = Vec::with_capacity(6 * (side * side) as usize);
    let mut indices = Vec::with_capacity(36 * (cells * cells) as usize);
    for face in 0..6 {
        let (axis, sign) = (face / 2, if face % 2 == 0 { 1.0 } else { -1.0 });
        let base = positions.len() as u32;
        for j in 0..side {
            for i in 0..side {
                let mut c = Vec3::ZERO;
                c[axis] = sign;
                c[(axis + 1) % 3] = -1.0 + 2.0 * i as f32 / cells as f32;
                c[(axis + 2) % 3] = -1.0 + 2.0 * j as f32 / cells as f32;
                // Jitter hashed from the cube point: seam vertices of two faces agree, so the
                // surface stays closed.
                let h = mix(u64::from(c.x.to_bits())
                    ^ u64::from(c.y.to_bits()).rotate_left(21)
                    ^ u64::from(c.z.to_bits()).rotate_left(42));
                let jitter = (h >> 40) as f32 / (1u64 << 23) as f32 - 1.0;
                let d = c.normalize();
                let bumps =
                    (5.0 * d.x + 1.0).sin() * (6.0 * d.y + 2.0).sin() * (7.0 * d.z + 3.0).sin();
                positions.push(center + d * (1.0 + 0.08 * bumps + 0.003 * jitter));
            }
        }
        for j in 0..cells {
            for i in 0..cells {
                let a = base + j * side + i;
                let (b, c, d) = (a + 1, a + side, a + side + 1);
                indices.extend([a, b, d, a, d, c]);
            }
        }
    }
    TriangleMesh {
        positions,
        indices,
        ..Default::default()
    }
}

/// The scene's acceleration structure over `mesh` alone, and the time its BVH took to build.
fn build_accel(mesh: TriangleMesh) -> (Accel, Duration) {
    let mut accel = Accel::default();
    let tris = mesh.triangle_count() as u32;
    accel.world.meshes.push(mesh);
    for tri in 0..tris {
        accel.world.push(Prim {
            kind: PrimKind::Triangle { mesh: 0, tri },
            surface: 0,
        });
    }
    let start = Instant::now();
    accel.build();
    (accel, start.elapsed())
}

/// One ray through each pixel centre of a `RES` x `RES` pinhole camera at the origin looking
/// down +z (fov 40 degrees: the sphere fills most of the frame), made by acr's own camera.
fn camera_rays() -> Vec<Ray> {
    let text = format!(
        "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" [40]\n\
         Film \"image\" \"integer xresolution\" [{RES}] \"integer yresolution\" [{RES}]\n\
         WorldBegin\nWorldEnd\n"
    );
    let desc = acr::parser::parse_str(&text, Path::new("hot_paths.pbrt")).expect("camera scene");
    let scene = acr::scene::Scene::build(&desc, &mut Vec::new()).expect("camera scene");
    (0..RES * RES)
        .map(|i| {
            let (x, y) = (i % RES, i / RES);
            scene.camera.generate_ray(&CameraSample {
                film: Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
                lens: Vec2::splat(0.5),
                time: 0.5,
            })
        })
        .collect()
}

/// `n` incoherent rays: origins uniform in the mesh's bounds, directions uniform on the
/// sphere (about half start inside the closed mesh and must hit it from within).
fn scattered_rays(n: usize, bounds: (Vec3, Vec3)) -> Vec<Ray> {
    let mut rng = Rng(5);
    let (lo, hi) = bounds;
    (0..n)
        .map(|_| {
            let o = lo + (hi - lo) * Vec3::new(rng.f(), rng.f(), rng.f());
            let z = 1.0 - 2.0 * rng.f();
            let phi = std::f32::consts::TAU * rng.f();
            let r = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(o, Vec3::new(r * phi.cos(), r * phi.sin(), z), 0.5)
        })
        .collect()
}

/// Rays of `rays` that hit something (closest-hit query), on the calling thread.
fn closest_hits(accel: &Accel, rays: &[Ray]) -> usize {
    rays.iter()
        .filter(|r| accel.intersect(r, f32::INFINITY).is_some())
        .count()
}

/// Rays of `rays` that are blocked (shadow query, stops at the first hit), on the calling thread.
fn occluded(accel: &Accel, rays: &[Ray]) -> usize {
    rays.iter()
        .filter(|r| accel.occluded(r, f32::INFINITY))
        .count()
}

/// Closest hits on `pool`'s threads, a `par_iter` over the rays as the render loop traces.
fn closest_hits_par(accel: &Accel, rays: &[Ray], pool: &ThreadPool) -> usize {
    pool.install(|| {
        rays.par_iter()
            .filter(|r| accel.intersect(r, f32::INFINITY).is_some())
            .count()
    })
}

/// Shadow queries on `pool`'s threads.
fn occluded_par(accel: &Accel, rays: &[Ray], pool: &ThreadPool) -> usize {
    pool.install(|| {
        rays.par_iter()
            .filter(|r| accel.occluded(r, f32::INFINITY))
            .count()
    })
}

/// Few samples, flat sampling and short times: an iteration takes up to a second, and the
/// whole suite must stay within a few minutes.
fn configure<M: criterion::measurement::Measurement>(group: &mut BenchmarkGroup<'_, M>) {
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
}

/// BVH traversal in rays/s on a 1M-triangle mesh: coherent camera rays and scattered rays,
/// closest hit (both sets) and shadow query (scattered), on 1 and 2 threads.
fn bvh(c: &mut Criterion) {
    let mesh = noisy_sphere(CELLS, CENTER);
    let tris = mesh.triangle_count();
    let (accel, build_time) = build_accel(mesh);
    let coherent = camera_rays();
    let scattered = scattered_rays((RES * RES) as usize, accel.bounds());
    let pool = pool(THREADS);
    eprintln!(
        "bvh: {tris} triangles, BVH built in {:.2} s; camera rays hitting: {} of {}; \
         scattered rays hitting: {} of {}",
        build_time.as_secs_f64(),
        closest_hits_par(&accel, &coherent, &pool),
        coherent.len(),
        closest_hits_par(&accel, &scattered, &pool),
        scattered.len(),
    );
    // The two queries must agree, or the shadow figures measure something else.
    assert_eq!(
        occluded_par(&accel, &scattered, &pool),
        closest_hits_par(&accel, &scattered, &pool)
    );

    let mut group = c.benchmark_group("bvh");
    configure(&mut group);
    for (set, rays) in [("coherent", &coherent), ("scattered", &scattered)] {
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.bench_function(BenchmarkId::new(format!("closest/{set}"), "1t"), |b| {
            b.iter(|| black_box(closest_hits(&accel, rays)))
        });
        group.bench_function(BenchmarkId::new(format!("closest/{set}"), "2t"), |b| {
            b.iter(|| black_box(closest_hits_par(&accel, rays, &pool)))
        });
    }
    group.throughput(Throughput::Elements(scattered.len() as u64));
    group.bench_function(BenchmarkId::new("shadow/scattered", "1t"), |b| {
        b.iter(|| black_box(occluded(&accel, &scattered)))
    });
    group.bench_function(BenchmarkId::new("shadow/scattered", "2t"), |b| {
        b.iter(|| black_box(occluded_par(&accel, &scattered, &pool)))
    });
    group.finish();
}

/// The rendering space of the sampler and film benchmarks: the whole `RES` x `RES` image.
fn space(dims: Dims) -> RenderingSpace {
    RenderingSpace::whole(RES, RES, dims)
}

/// Builds sampler `name` through the registry, as the renderer does, at `SPP` samples per pixel.
fn sampler(name: &str, dims: Dims) -> Box<dyn Sampler> {
    let entry = SAMPLERS
        .iter()
        .find(|e| e.info.name == name)
        .expect("registered sampler");
    let setup = SamplerSetup {
        space: space(dims),
        spp: Some(SPP),
        seed: 1,
        reconstruction_reads_cells: false,
        stream: Default::default(),
    };
    (entry.build)(&Choice::new(None, name, None), &setup).expect("sampler")
}

/// Every point a sampler gives (all its `next_batch` calls), returning how many.
fn drain(sampler: &mut dyn Sampler, out: &mut Vec<SamplePoint>) -> u64 {
    let mut n = 0;
    while sampler.next_batch(out) {
        n += out.len() as u64;
        black_box(&out);
    }
    n
}

/// One sampler round: every batch of each registered sampler over `RES` x `RES` at `SPP` spp,
/// in 2D (x, y) and 5D (x, y, t, u, v), in samples/s (single-threaded, as the render loop
/// calls it).
fn samplers(c: &mut Criterion) {
    let total = u64::from(RES * RES * SPP);
    let mut group = c.benchmark_group("sampler");
    configure(&mut group);
    group.throughput(Throughput::Elements(total));
    let mut out = Vec::new();
    for entry in SAMPLERS {
        let name = entry.info.name;
        for (label, dims) in [
            ("2d", Dims::default()),
            (
                "5d",
                Dims {
                    time: true,
                    lens: true,
                },
            ),
        ] {
            assert_eq!(drain(&mut *sampler(name, dims), &mut out), total, "{name}");
            group.bench_function(BenchmarkId::new(name, label), |b| {
                b.iter_batched(
                    || sampler(name, dims),
                    |mut s| drain(&mut *s, &mut out),
                    BatchSize::PerIteration,
                )
            });
        }
    }
    group.finish();
}

/// A 16-spp image's samples as the render loop hands them to the film: the halton sampler's
/// batches (sorted by row), each sample with a smooth radiance plus noise.
fn film_batches() -> Vec<Vec<(Vec2, Vec3)>> {
    let mut s = sampler("halton", Dims::default());
    let mut out = Vec::with_capacity(BATCH_SAMPLES as usize);
    let mut rng = Rng(9);
    let mut batches = Vec::new();
    while s.next_batch(&mut out) {
        batches.push(
            out.iter()
                .map(|q| {
                    let p = Vec2::from(q.film);
                    let base = Vec3::new(
                        0.5 + 0.5 * (p.x * 0.05).sin(),
                        0.5 + 0.5 * (p.y * 0.07).cos(),
                        0.5,
                    );
                    (p, base * (0.5 + rng.f()))
                })
                .collect(),
        );
    }
    batches
}

/// The reconstruction: adding a 16-spp image's batches to the film (samples/s, on 2 threads as
/// the render loop does) and the filter's `reconstruct` (pixels/s), for the box and gaussian
/// filters at `RES` x `RES`.
fn film(c: &mut Criterion) {
    let batches = film_batches();
    let samples: u64 = batches.iter().map(|b| b.len() as u64).sum();
    assert_eq!(samples, u64::from(RES * RES * SPP));
    let pool = pool(THREADS);
    let mut group = c.benchmark_group("film");
    configure(&mut group);
    for name in ["box", "gaussian"] {
        let entry = FILTERS
            .iter()
            .find(|e| e.info.name == name)
            .expect("registered filter");
        let filter = (entry.build)(&Choice::new(None, name, None)).expect("filter");
        let mut film = Film::new(FilmSettings::with_resolution(RES, RES), filter.kernel());
        group.throughput(Throughput::Elements(samples));
        group.bench_function(BenchmarkId::new("add_samples", name), |b| {
            b.iter(|| {
                pool.install(|| {
                    for batch in &batches {
                        film.add_samples(batch);
                    }
                })
            })
        });
        group.throughput(Throughput::Elements(u64::from(RES * RES)));
        group.bench_function(BenchmarkId::new("reconstruct", name), |b| {
            b.iter(|| {
                pool.install(|| {
                    black_box(
                        filter.reconstruct(&film, acr_plugins::filters::SamplerOutput::default()),
                    )
                })
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    // No plots: plotters finds no fonts on a bare machine and panics (FontUnavailable).
    config = Criterion::default().without_plots();
    targets = bvh, samplers, film
}
criterion_main!(benches);
