//! The paper's rivals (`mdas`, `gem`, `awr`) on the abstract space, as the cluster sampler is
//! tested: a noisy step edge, still in 2D, moving in time in 3D (x = 20 + 20t) and defocused in
//! 4D (x = 32 + 12(u - 0.5)). Each spends its budget exactly, gives every pixel the indices
//! 0, 1, 2, ..., is deterministic, reconstructs a finite image, and its error against the exact
//! pixel integrals falls as samples grow. Errors are printed:
//! `cargo test -p acr-plugins --test rivals -- --nocapture`.

use acr_plugins::film::{Film, FilmSettings};
use acr_plugins::rng::mix64;
use acr_plugins::space::{Dims, RenderingSpace, SamplePoint};
use acr_plugins::{Choice, FILTERS};
use glam::{Vec2, Vec3};

mod common;
use common::sampler;

const W: u32 = 64;
const H: u32 = 48;
const RIVALS: [&str; 3] = ["mdas", "gem", "awr"];

/// Where the edge is for a point: still, moving, or defocused.
#[derive(Clone, Copy, Debug)]
enum Edge {
    Still,
    Moving,
    Defocused,
}

impl Edge {
    fn dims(self) -> Dims {
        match self {
            Edge::Still => Dims::default(),
            Edge::Moving => Dims {
                time: true,
                lens: false,
            },
            Edge::Defocused => Dims {
                time: false,
                lens: true,
            },
        }
    }

    /// The edge's x for a value of the extra dim (time or lens u).
    fn at(self, s: f64) -> f64 {
        match self {
            Edge::Still => 31.4,
            Edge::Moving => 20.0 + 20.0 * s,
            Edge::Defocused => 32.0 + 12.0 * (s - 0.5),
        }
    }

    fn extra(self, q: &SamplePoint) -> f64 {
        match self {
            Edge::Still => 0.5,
            Edge::Moving => f64::from(q.time),
            Edge::Defocused => f64::from(q.lens[0]),
        }
    }

    /// 0.1 left of the edge, 1.0 right of it, plus +-0.05 noise hashed from the point.
    fn field(self, q: &SamplePoint) -> f32 {
        let x = f64::from(q.film[0]);
        let h = mix64(
            u64::from(q.film[0].to_bits())
                ^ (u64::from(q.film[1].to_bits()) << 32)
                ^ mix64(self.extra(q).to_bits()),
        );
        let noise = ((h >> 40) as f64 / (1u64 << 24) as f64 - 0.5) * 0.1;
        let v = if x >= self.at(self.extra(q)) {
            1.0
        } else {
            0.1
        };
        (v + noise) as f32
    }

    /// The exact mean of the noiseless field over pixel column px (midpoint rule over the
    /// extra dim, exact coverage in x).
    fn exact(self, px: u32) -> f64 {
        const STEPS: usize = 4000;
        let x0 = f64::from(px);
        let mut sum = 0.0;
        for k in 0..STEPS {
            let s = (k as f64 + 0.5) / STEPS as f64;
            let covered = (x0 + 1.0 - self.at(s).max(x0)).clamp(0.0, 1.0);
            sum += 0.1 + 0.9 * covered;
        }
        sum / STEPS as f64
    }
}

/// Runs `name` on `edge` at `spp`: the image it reconstructs and the points per pixel.
fn run(name: &str, edge: Edge, spp: u32, seed: u64) -> (Vec<Vec3>, Vec<u32>) {
    let mut s = sampler(name, RenderingSpace::whole(W, H, edge.dims()), spp, seed);
    assert!(s.reconstructs(), "{name} reconstructs itself");
    let box_filter = FILTERS.iter().find(|e| e.info.name == "box").unwrap();
    let kernel = (box_filter.build)(&Choice::new(None, "box", None)).unwrap();
    let mut film = Film::new(FilmSettings::with_resolution(W, H), kernel.kernel());
    let mut count = vec![0u32; (W * H) as usize];
    let mut batch = Vec::new();
    while s.next_batch(&mut batch) {
        let mut rows = batch.iter().map(|q| q.pixel[1]);
        let mut last = 0;
        assert!(
            rows.all(|r| std::mem::replace(&mut last, r) <= r),
            "{name}: unsorted batch"
        );
        let radiance: Vec<[f32; 3]> = batch.iter().map(|q| [edge.field(q); 3]).collect();
        for q in &batch {
            let i = (q.pixel[1] * W + q.pixel[0]) as usize;
            assert_eq!(q.index, count[i], "{name}: index out of order");
            count[i] += 1;
            assert!(q.film[0] >= q.pixel[0] as f32 && q.film[0] < (q.pixel[0] + 1) as f32);
            assert!(q.film[1] >= q.pixel[1] as f32 && q.film[1] < (q.pixel[1] + 1) as f32);
        }
        s.observe(&batch, &radiance);
        let samples: Vec<(Vec2, Vec3)> = batch
            .iter()
            .zip(&radiance)
            .map(|(q, l)| (Vec2::from(q.film), Vec3::from_array(*l)))
            .collect();
        film.add_samples(&samples);
    }
    (s.reconstruct(&film).unwrap(), count)
}

/// RMS error of an image against the exact pixel values.
fn rms(edge: Edge, image: &[Vec3]) -> f64 {
    let sum: f64 = image
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let d = f64::from(p.x) - edge.exact(i as u32 % W);
            d * d
        })
        .sum();
    (sum / image.len() as f64).sqrt()
}

#[test]
fn rivals_spend_the_budget_exactly_and_are_deterministic() {
    for name in RIVALS {
        for edge in [Edge::Still, Edge::Moving, Edge::Defocused] {
            let (image, count) = run(name, edge, 8, 3);
            let total: u64 = count.iter().map(|&c| u64::from(c)).sum();
            assert_eq!(total, u64::from(W * H) * 8, "{name} {edge:?}");
            assert!(
                count.iter().all(|&c| c >= 1),
                "{name} {edge:?}: a pixel without samples"
            );
            assert!(image
                .iter()
                .all(|p| p.is_finite() && p.min_element() >= 0.0));
            let (again, _) = run(name, edge, 8, 3);
            assert_eq!(image, again, "{name} {edge:?}: not deterministic");
        }
    }
}

#[test]
fn rivals_error_falls_as_samples_grow_on_an_edge() {
    for name in RIVALS {
        for edge in [Edge::Still, Edge::Moving, Edge::Defocused] {
            // Two seeds each, so that one lucky image does not decide.
            let e = |spp| {
                (rms(edge, &run(name, edge, spp, 1).0) + rms(edge, &run(name, edge, spp, 2).0))
                    / 2.0
            };
            let (e4, e16, e64) = (e(4), e(16), e(64));
            eprintln!("{name} {edge:?}: RMS 4 spp {e4:.4}, 16 spp {e16:.4}, 64 spp {e64:.4}");
            assert!(e16 < 0.85 * e4, "{name} {edge:?}: {e4} -> {e16}");
            assert!(e64 < 0.85 * e16, "{name} {edge:?}: {e16} -> {e64}");
        }
    }
}
