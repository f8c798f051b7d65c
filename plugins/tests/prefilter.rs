//! The fit's feature prefilter (`prefilter.rs`) on hand-made cells: it averages a noisy
//! albedo, depth or normal with like neighbours, leaves a precise one alone, never crosses a
//! depth, normal or shading edge, and stays finite on degenerate cells.

use acr_plugins::cells::{CellGrid, CellSums};
use acr_plugins::first_hit::Features;
use acr_plugins::prefilter::prefilter_features;
use acr_plugins::rng::mix64;
use acr_plugins::space::{Dims, RenderingSpace, SamplePoint};

const W: u32 = 16;
const H: u32 = 8;
const SPP: u32 = 8;

/// Cells of a W x H image, `SPP` samples a pixel, each sample's radiance and features from
/// `sample(pixel, index)`.
fn cells(sample: impl Fn([u32; 2], u32) -> ([f32; 3], Features)) -> (CellGrid, CellSums) {
    let grid = CellGrid::new(RenderingSpace::whole(W, H, Dims::default()), 1.0, 1);
    let mut sums = CellSums::new(&grid).with_features();
    let (mut batch, mut radiance, mut features) = (Vec::new(), Vec::new(), Vec::new());
    for y in 0..H {
        for x in 0..W {
            for i in 0..SPP {
                let (l, f) = sample([x, y], i);
                batch.push(SamplePoint {
                    pixel: [x, y],
                    index: i,
                    film: [x as f32 + 0.5, y as f32 + 0.5],
                    time: 0.5,
                    lens: [0.5, 0.5],
                });
                radiance.push(l);
                features.push(f);
            }
        }
    }
    let mut located = Vec::new();
    grid.locate_all(&batch, &mut located);
    sums.add_batch(&located, &radiance, Some(&features));
    (grid, sums)
}

/// A value in [0, 1) from a pixel and a sample index.
fn noise(p: [u32; 2], i: u32, salt: u64) -> f32 {
    let h = mix64(u64::from(p[0]) << 40 ^ u64::from(p[1]) << 20 ^ u64::from(i) ^ salt << 50);
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// A surface seen at depth 5 facing +z, lit by 1: radiance equals albedo.
fn surface(a: f32) -> ([f32; 3], Features) {
    ([a; 3], [a, a, a, 0.0, 0.0, 1.0, 5.0])
}

/// The sums with their feature sums replaced by `features` (the prefilter's output).
fn with(sums: &CellSums, features: Vec<Features>) -> CellSums {
    let mut out = sums.clone();
    out.features = features;
    out
}

fn mean_albedo(sums: &CellSums, i: usize) -> f64 {
    sums.mean_features(i).unwrap()[0]
}

fn spread(sums: &CellSums, ids: &[usize]) -> f64 {
    let m = ids.iter().map(|&i| mean_albedo(sums, i)).sum::<f64>() / ids.len() as f64;
    ids.iter()
        .map(|&i| (mean_albedo(sums, i) - m).powi(2))
        .sum::<f64>()
        / ids.len() as f64
}

#[test]
fn a_noisy_albedo_is_averaged_and_a_precise_one_kept() {
    // Left half: a texture finer than the samples (each sample 0.2 or 0.8 at random: a cell's
    // mean albedo is noisy); right half: a checker of whole pixels (every sample of a pixel
    // agrees: its mean is exact).
    let (grid, sums) = cells(|p, i| {
        let a = if p[0] < W / 2 {
            if noise(p, i, 1) < 0.5 {
                0.2
            } else {
                0.8
            }
        } else if (p[0] + p[1]) % 2 == 0 {
            0.2
        } else {
            0.8
        };
        surface(a)
    });
    let out = with(&sums, prefilter_features(&grid, &sums, 1, 1.0));
    let index = |x: u32, y: u32| (y * W + x) as usize;
    let left: Vec<usize> = (1..H - 1)
        .flat_map(|y| (1..W / 2 - 1).map(move |x| index(x, y)))
        .collect();
    let (before, after) = (spread(&sums, &left), spread(&out, &left));
    assert!(after < 0.5 * before, "spread {before} -> {after}");
    for y in 0..H {
        for x in W / 2 + 1..W {
            let i = index(x, y);
            assert_eq!(
                mean_albedo(&out, i),
                mean_albedo(&sums, i),
                "pixel {x}, {y}"
            );
        }
    }
    // Normals and depth, the same exact values everywhere, stay as they were.
    for i in 0..grid.len() {
        let (a, b) = (
            out.mean_features(i).unwrap(),
            sums.mean_features(i).unwrap(),
        );
        for k in 3..7 {
            assert!((a[k] - b[k]).abs() < 1e-6, "cell {i} feature {k}");
        }
    }
}

/// The spread over `ids` of feature `k`'s cell means.
fn spread_of(sums: &CellSums, ids: &[usize], k: usize) -> f64 {
    let of = |i: usize| sums.mean_features(i).unwrap()[k];
    let m = ids.iter().map(|&i| of(i)).sum::<f64>() / ids.len() as f64;
    ids.iter().map(|&i| (of(i) - m).powi(2)).sum::<f64>() / ids.len() as f64
}

#[test]
fn a_noisy_depth_and_normal_are_averaged_and_an_exact_step_kept() {
    // Left half: a silhouette blurred by the lens, each sample meeting the foreground (depth
    // 2, facing +z) or the background (depth 10, facing +x) at random, so a cell's mean depth
    // and normal are noisy; right half: a step of whole pixels between depth 5 and 50, exact
    // within each pixel.
    let (grid, sums) = cells(|p, i| {
        if p[0] < W / 2 {
            if noise(p, i, 4) < 0.5 {
                ([0.5; 3], [0.5, 0.5, 0.5, 0.0, 0.0, 1.0, 2.0])
            } else {
                ([0.5; 3], [0.5, 0.5, 0.5, 1.0, 0.0, 0.0, 10.0])
            }
        } else {
            let depth = if p[1] % 2 == 0 { 5.0 } else { 50.0 };
            ([0.5; 3], [0.5, 0.5, 0.5, 0.0, 0.0, 1.0, depth])
        }
    });
    let out = with(&sums, prefilter_features(&grid, &sums, 1, 2.0));
    let index = |x: u32, y: u32| (y * W + x) as usize;
    let left: Vec<usize> = (1..H - 1)
        .flat_map(|y| (1..W / 2 - 1).map(move |x| index(x, y)))
        .collect();
    for (k, name) in [(6, "depth"), (3, "normal x"), (5, "normal z")] {
        let (before, after) = (spread_of(&sums, &left, k), spread_of(&out, &left, k));
        assert!(after < 0.5 * before, "{name}: spread {before} -> {after}");
    }
    for y in 0..H {
        for x in W / 2 + 1..W {
            let i = index(x, y);
            let (a, b) = (
                out.mean_features(i).unwrap()[6],
                sums.mean_features(i).unwrap()[6],
            );
            assert!((a - b).abs() < 1e-3 * b, "pixel {x}, {y}: depth {b} -> {a}");
        }
    }
}

#[test]
fn depth_normal_and_shading_edges_are_not_crossed() {
    // The left half is the same noisy texture each time; what lies right of it differs only
    // in its albedo (0.1 or 0.9, noisy), behind an edge of depth, of normal or of shading
    // (an emitter: radiance ten times its albedo). The left half's prefiltered albedo must
    // not depend on it.
    type Side = fn(f32) -> ([f32; 3], Features);
    let far: Side = |a| ([a; 3], [a, a, a, 0.0, 0.0, 1.0, 50.0]);
    let turned: Side = |a| ([a; 3], [a, a, a, 1.0, 0.0, 0.0, 5.0]);
    let emitting: Side = |a| ([10.0 * a; 3], [a, a, a, 0.0, 0.0, 1.0, 5.0]);
    for (edge, right, tolerance) in [
        ("depth", far, 1e-9),
        ("normal", turned, 2e-3),
        ("shading", emitting, 1e-6),
    ] {
        let left_of = |level: f32| {
            let (grid, sums) = cells(move |p, i| {
                let n = noise(p, i, 2) - 0.5;
                if p[0] < W / 2 {
                    surface(0.5 + 0.4 * n)
                } else {
                    right(level + 0.2 * n)
                }
            });
            let out = with(&sums, prefilter_features(&grid, &sums, 1, 4.0));
            (0..H)
                .flat_map(|y| (0..W / 2).map(move |x| (y * W + x) as usize))
                .map(|i| mean_albedo(&out, i))
                .collect::<Vec<_>>()
        };
        let (a, b) = (left_of(0.1), left_of(0.9));
        for (k, (x, y)) in a.iter().zip(&b).enumerate() {
            assert!(
                (x - y).abs() <= tolerance,
                "{edge}: cell {k}: {x} against {y}"
            );
        }
    }
}

#[test]
fn degenerate_cells_stay_finite_and_unfiltered_sums_pass_through() {
    // Black surfaces in the dark, one sample a pixel (no noise estimate), zero depth: finite
    // and unchanged.
    let (grid, sums) = cells(|p, i| {
        if i > 0 {
            return ([f32::NAN; 3], [0.0; 7]);
        }
        let a = if p[0] % 3 == 0 { 0.0 } else { 0.5 };
        ([0.0; 3], [a, a, a, 0.0, 0.0, 1.0, 0.0])
    });
    let out = with(&sums, prefilter_features(&grid, &sums, 2, 1.0));
    for i in 0..grid.len() {
        assert_eq!(out.count[i], 1);
        let f = out.mean_features(i).unwrap();
        assert!(f.iter().all(|v| v.is_finite()));
        assert_eq!(f, sums.mean_features(i).unwrap(), "cell {i}");
    }
    // A radius of 0, or sums without features: the input.
    let (grid, sums) = cells(|p, i| surface(noise(p, i, 3)));
    assert_eq!(prefilter_features(&grid, &sums, 0, 1.0), sums.features);
    let plain = CellSums::new(&grid);
    assert!(prefilter_features(&grid, &plain, 1, 1.0).is_empty());
}
