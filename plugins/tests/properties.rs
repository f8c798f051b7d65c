//! Property tests (proptest) of the samplers and the polynomial fit: every sampler keeps its
//! points in range and its budget exact on any rendering space, and the fit of any cluster,
//! however noisy, sparse or extreme its values, is finite, non-negative and within the range
//! of its cell means where it clamps.

use acr_plugins::cells::grid::MAX_DIMS;
use acr_plugins::polynomial_fit::{Fit, FitCell, FitSettings};
use acr_plugins::space::{Dims, RenderingSpace};
use acr_plugins::SAMPLERS;
use proptest::prelude::*;

mod common;
use common::sampler;

/// A cropped rendering space anywhere in a large image, with any dims.
fn spaces() -> impl Strategy<Value = RenderingSpace> {
    (
        0u32..5000,
        1u32..12,
        0u32..5000,
        1u32..10,
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(|(x0, w, y0, h, time, lens)| RenderingSpace {
            x0,
            x1: x0 + w,
            y0,
            y1: y0 + h,
            dims: Dims { time, lens },
        })
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 48,
        // Fixed: CI runs the same cases every time (a failure reproduces); change the seed
        // to explore further.
        rng_seed: proptest::test_runner::RngSeed::Fixed(0xacc0_5eed),
        ..ProptestConfig::default()
    })]

    /// Every point lies in its pixel's raster square and inside the space, time and lens in
    /// [0, 1) (0.5 when inactive), a pixel's indices are 0, 1, 2, ... in order (they key the
    /// integrator's random streams, so none may repeat), the budget is spent exactly and the
    /// fixed samplers give every pixel spp points, whatever radiance the adaptive sampler is
    /// shown (NaN, huge and zero included).
    #[test]
    fn every_sampler_keeps_its_points_in_range_and_its_budget_exact(
        space in spaces(),
        spp in 1u32..9,
        seed in any::<u64>(),
        which in 0usize..64,
    ) {
        let entry = &SAMPLERS[which % SAMPLERS.len()];
        let name = entry.info.name;
        let mut s = sampler(name, space, spp, seed);
        let spp = s.spp();
        let (w, h) = (space.width() as usize, space.height() as usize);
        let mut count = vec![0u32; w * h];
        let mut batch = Vec::new();
        while s.next_batch(&mut batch) {
            let mut radiance = Vec::with_capacity(batch.len());
            for (k, q) in batch.iter().enumerate() {
                let [px, py] = q.pixel;
                prop_assert!((space.x0..space.x1).contains(&px), "{name}: pixel x {px}");
                prop_assert!((space.y0..space.y1).contains(&py), "{name}: pixel y {py}");
                let [fx, fy] = q.film;
                prop_assert!(
                    fx >= px as f32 && fx < (px + 1) as f32,
                    "{name}: film x {fx} outside pixel {px}"
                );
                prop_assert!(
                    fy >= py as f32 && fy < (py + 1) as f32,
                    "{name}: film y {fy} outside pixel {py}"
                );
                let seen = &mut count[(py - space.y0) as usize * w + (px - space.x0) as usize];
                prop_assert_eq!(q.index, *seen, "{}: index out of order in pixel {:?}", name, q.pixel);
                *seen += 1;
                let unit = |v: f32| (0.0..1.0).contains(&v);
                if space.dims.time {
                    prop_assert!(unit(q.time), "{name}: time {}", q.time);
                } else {
                    prop_assert_eq!(q.time, 0.5);
                }
                if space.dims.lens {
                    prop_assert!(unit(q.lens[0]) && unit(q.lens[1]), "{name}: lens {:?}", q.lens);
                } else {
                    prop_assert_eq!(q.lens, [0.5, 0.5]);
                }
                // Dropped (NaN), huge and ordinary radiance mixed.
                radiance.push(match (k as u64 ^ seed) % 5 {
                    0 => [f32::NAN; 3],
                    1 => [1e30, 0.0, 1e30],
                    _ => [q.film[0].fract(); 3],
                });
            }
            s.observe(&batch, &radiance);
        }
        let total: u64 = count.iter().map(|&c| u64::from(c)).sum();
        prop_assert_eq!(total, space.pixels() * u64::from(spp), "{}: budget", name);
        // The adaptive samplers (those that report rounds) give pixels unequal shares.
        if s.report().rounds.is_none() {
            prop_assert!(count.iter().all(|&c| c == spp), "{}: uneven {:?}", name, count);
        }
    }
}

/// A cluster of cells on a regular grid in the first `dims` dims, with random sample moments,
/// weights (some zero) and means (some huge, some NaN, some zero).
fn clusters() -> impl Strategy<Value = (Vec<FitCell>, usize)> {
    (2usize..=MAX_DIMS, 1usize..40).prop_flat_map(|(dims, n)| {
        let cell = (
            proptest::collection::vec(0u32..4, MAX_DIMS),
            proptest::collection::vec(0.0f64..1.0, MAX_DIMS),
            proptest::collection::vec(0.0f64..1.0, MAX_DIMS),
            prop_oneof![Just(0.0), 1.0f64..64.0],
            proptest::collection::vec(
                prop_oneof![
                    4 => 0.0f64..1.0,
                    1 => 0.0f64..1e8,
                    1 => Just(0.0),
                    1 => Just(f64::NAN),
                ],
                3,
            ),
        );
        (proptest::collection::vec(cell, n), Just(dims)).prop_map(|(cells, dims)| {
            let cells = cells
                .into_iter()
                .map(|(pos, a, b, weight, mean)| {
                    let mut c = FitCell {
                        lo: [0.0; MAX_DIMS],
                        hi: [0.0; MAX_DIMS],
                        m1: [0.5; MAX_DIMS],
                        m2: [1.0 / 3.0; MAX_DIMS],
                        mean: [mean[0], mean[1], mean[2]],
                        features: [0.0; 7],
                        weight,
                    };
                    for d in 0..MAX_DIMS {
                        // Pixels for x and y, [0, 1) quarters for the others.
                        let size = if d < 2 { 1.0 } else { 0.25 };
                        c.lo[d] = pos[d] as f64 * size;
                        c.hi[d] = c.lo[d] + size;
                        // Moments of samples inside the cell: m1^2 <= m2 <= m1.
                        let m1 = a[d];
                        c.m1[d] = m1;
                        c.m2[d] = m1 * m1 + b[d] * (m1 - m1 * m1);
                    }
                    c
                })
                .collect();
            (cells, dims)
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        // Fixed: CI runs the same cases every time (a failure reproduces); change the seed
        // to explore further.
        rng_seed: proptest::test_runner::RngSeed::Fixed(0xacc0_5eed),
        ..ProptestConfig::default()
    })]

    /// The fit's value over every cell and over boxes reaching outside the cluster is finite
    /// and non-negative, and, where it clamps, within the range of the usable cell means.
    #[test]
    fn the_polynomial_fit_of_any_cluster_is_finite_and_in_range(
        (cells, dims) in clusters(),
        degree in 0u32..=2,
        ridge in prop_oneof![Just(0.0), 1e-9f64..1e-1],
        clamp in any::<bool>(),
    ) {
        let fit = Fit::new(&cells, dims, &FitSettings { degree, ridge, clamp, features: false });
        let usable: Vec<&FitCell> = cells
            .iter()
            .filter(|c| c.weight > 0.0 && c.mean.iter().all(|v| v.is_finite()))
            .collect();
        prop_assert_eq!(fit.is_empty(), usable.is_empty());
        let mut boxes: Vec<([f64; MAX_DIMS], [f64; MAX_DIMS])> =
            cells.iter().map(|c| (c.lo, c.hi)).collect();
        // Beyond the cluster and a degenerate (point) box.
        boxes.push(([-3.0; MAX_DIMS], [7.0; MAX_DIMS]));
        boxes.push(([0.5; MAX_DIMS], [0.5; MAX_DIMS]));
        for (lo, hi) in &boxes {
            let v = fit.mean_over(lo, hi, None);
            for ch in 0..3 {
                prop_assert!(v[ch].is_finite() && v[ch] >= 0.0, "value {:?}", v);
                if clamp && !usable.is_empty() {
                    let min = usable.iter().map(|c| c.mean[ch]).fold(f64::INFINITY, f64::min);
                    let max = usable.iter().map(|c| c.mean[ch]).fold(0.0, f64::max);
                    prop_assert!(
                        v[ch] >= min.max(0.0) && v[ch] <= max,
                        "channel {} value {} outside [{}, {}]", ch, v[ch], min, max
                    );
                }
            }
        }
        // A constant field is fitted exactly, at any degree.
        let constant: Vec<FitCell> = cells
            .iter()
            .map(|c| FitCell { mean: [0.25, 0.5, 3.0], weight: c.weight.max(1.0), ..*c })
            .collect();
        let fit = Fit::new(&constant, dims, &FitSettings { degree, ridge, clamp, features: false });
        for (lo, hi) in &boxes[..cells.len()] {
            let v = fit.mean_over(lo, hi, None);
            for (ch, want) in [0.25, 0.5, 3.0].into_iter().enumerate() {
                prop_assert!((v[ch] - want).abs() <= 1e-6 * want, "constant {}: {:?}", want, v);
            }
        }
    }
}
