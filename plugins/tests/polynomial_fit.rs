//! The polynomial reconstruction's fit on the abstract space, without a scene: an additive
//! polynomial field is reproduced by the matching degree, the normal equations agree with an
//! independent SVD solve (nalgebra, f64) on the same samples, and degenerate clusters give
//! finite values in range.

// The reference solver indexes several arrays at once, as the formulas do.
#![allow(clippy::needless_range_loop)]

use acr_plugins::first_hit::FEATURES;
use acr_plugins::polynomial_fit::{Fit, FitCell, FitSettings};
use acr_plugins::rng::Pcg32;
use nalgebra::DMatrix;

const DIMS: usize = 5;

/// A cell with the samples in it, kept so that a test can recompute everything from them.
struct TestCell {
    lo: [f64; DIMS],
    hi: [f64; DIMS],
    /// Sample positions and radiance.
    samples: Vec<([f64; DIMS], [f64; 3])>,
}

impl TestCell {
    fn fit_cell(&self) -> FitCell {
        let n = self.samples.len() as f64;
        let mut m1 = [0.5; DIMS];
        let mut m2 = [0.25; DIMS];
        let mut mean = [0.0; 3];
        if n > 0.0 {
            m1 = [0.0; DIMS];
            m2 = [0.0; DIMS];
            for (p, l) in &self.samples {
                for d in 0..DIMS {
                    let w = self.hi[d] - self.lo[d];
                    let o = if w > 0.0 {
                        (p[d] - self.lo[d]) / w
                    } else {
                        0.5
                    };
                    m1[d] += o / n;
                    m2[d] += o * o / n;
                }
                for k in 0..3 {
                    mean[k] += l[k] / n;
                }
            }
        }
        FitCell {
            lo: self.lo,
            hi: self.hi,
            m1,
            m2,
            mean,
            features: [0.0; 7],
            weight: n,
        }
    }
}

/// Cells on a regular grid over `dims` dims (`shape` cells per dim, each `width` wide), each
/// with 1 to 5 samples at random positions, radiance from `field`.
fn grid_cells(
    shape: &[usize],
    width: &[f64],
    field: impl Fn(&[f64; DIMS]) -> [f64; 3],
    seed: u64,
) -> Vec<TestCell> {
    let mut rng = Pcg32::new(seed, 7);
    let total: usize = shape.iter().product();
    (0..total)
        .map(|mut i| {
            let mut lo = [0.0; DIMS];
            let mut hi = [0.0; DIMS];
            for d in 0..shape.len() {
                let c = i % shape[d];
                i /= shape[d];
                lo[d] = c as f64 * width[d];
                hi[d] = lo[d] + width[d];
            }
            let n = 1 + (rng.next_u32() % 5) as usize;
            let samples = (0..n)
                .map(|_| {
                    let mut p = lo;
                    for d in 0..shape.len() {
                        p[d] = lo[d] + f64::from(rng.next_f32()) * (hi[d] - lo[d]);
                    }
                    (p, field(&p))
                })
                .collect();
            TestCell { lo, hi, samples }
        })
        .collect()
}

fn fit_cells(cells: &[TestCell]) -> Vec<FitCell> {
    cells.iter().map(TestCell::fit_cell).collect()
}

/// An additive quadratic field over x (pixels), y (pixels), t ([0, 1]).
fn additive(p: &[f64; DIMS]) -> [f64; 3] {
    let (x, y, t) = (p[0], p[1], p[2]);
    let v = 0.5 + 0.1 * x - 0.01 * x * x + 0.05 * y + 0.002 * y * y + 0.3 * t - 0.2 * t * t;
    [v, 2.0 * v, 0.5 * v + 0.1 * x]
}

/// The exact mean of `additive` over a box (each term's mean: (a + b) / 2, (a² + ab + b²) / 3).
fn additive_mean(lo: &[f64; DIMS], hi: &[f64; DIMS]) -> [f64; 3] {
    let m1 = |d: usize| 0.5 * (lo[d] + hi[d]);
    let m2 = |d: usize| (lo[d] * lo[d] + lo[d] * hi[d] + hi[d] * hi[d]) / 3.0;
    let v =
        0.5 + 0.1 * m1(0) - 0.01 * m2(0) + 0.05 * m1(1) + 0.002 * m2(1) + 0.3 * m1(2) - 0.2 * m2(2);
    [v, 2.0 * v, 0.5 * v + 0.1 * m1(0)]
}

const EXACT: FitSettings = FitSettings {
    degree: 2,
    ridge: 0.0,
    clamp: false,
    features: false,
};

#[test]
fn an_additive_quadratic_field_is_reproduced_by_degree_2() {
    // 8 x 6 pixels, time in 4 bins; 1 to 5 samples per cell at random positions.
    let cells = grid_cells(&[8, 6, 4], &[1.0, 1.0, 0.25], additive, 1);
    let fit = Fit::new(&fit_cells(&cells), 3, &EXACT);
    assert_eq!(fit.degree(), 2);
    let mut worst: f64 = 0.0;
    // Every cell, and every pixel (a box over the whole shutter: four cells' worth).
    for c in &cells {
        let (got, want) = (
            fit.mean_over(&c.lo, &c.hi, None),
            additive_mean(&c.lo, &c.hi),
        );
        for k in 0..3 {
            worst = worst.max((got[k] - want[k]).abs());
        }
    }
    for py in 0..6 {
        for px in 0..8 {
            let lo = [f64::from(px), f64::from(py), 0.0, 0.0, 0.0];
            let hi = [lo[0] + 1.0, lo[1] + 1.0, 1.0, 0.0, 0.0];
            let (got, want) = (fit.mean_over(&lo, &hi, None), additive_mean(&lo, &hi));
            for k in 0..3 {
                worst = worst.max((got[k] - want[k]).abs());
            }
        }
    }
    println!("additive quadratic, degree 2: worst error {worst:.3e}");
    assert!(worst < 1e-6, "worst error {worst}");

    // A linear field and degree 1; at degree 1 the quadratic field is not reproduced.
    let linear = |p: &[f64; DIMS]| {
        let v = 0.2 + 0.03 * p[0] - 0.02 * p[1] + 0.1 * p[2];
        [v, v, v]
    };
    let cells = grid_cells(&[8, 6, 4], &[1.0, 1.0, 0.25], linear, 2);
    let one = FitSettings { degree: 1, ..EXACT };
    let fit = Fit::new(&fit_cells(&cells), 3, &one);
    for c in &cells {
        let got = fit.mean_over(&c.lo, &c.hi, None);
        let mid: [f64; DIMS] = std::array::from_fn(|d| 0.5 * (c.lo[d] + c.hi[d]));
        assert!((got[0] - linear(&mid)[0]).abs() < 1e-9);
    }
    let cells = grid_cells(&[8, 6, 4], &[1.0, 1.0, 0.25], additive, 1);
    let fit = Fit::new(&fit_cells(&cells), 3, &one);
    let c = &cells[0];
    let err = (fit.mean_over(&c.lo, &c.hi, None)[0] - additive_mean(&c.lo, &c.hi)[0]).abs();
    assert!(err > 1e-4, "degree 1 fits a quadratic too well: {err}");
}

/// P_0..P_2 at x.
fn legendre(x: f64) -> [f64; 3] {
    [1.0, x, 0.5 * (3.0 * x * x - 1.0)]
}

#[test]
fn the_fit_agrees_with_an_svd_solve_of_the_same_samples() {
    for (seed, dims, ridge) in [(3u64, 2usize, 0.0), (4, 3, 1e-6), (5, 5, 1e-3)] {
        let shape = [6, 5, 3, 2, 2];
        let width = [1.0, 1.0, 1.0 / 3.0, 0.5, 0.5];
        let mut noise = Pcg32::new(seed, 11);
        let noisy = |p: &[f64; DIMS]| {
            let v = 0.3 + 0.05 * p[0] + 0.2 * (p[1] * 0.7).sin() + p[2] * p[3];
            [v, v * 0.5, v * v]
        };
        let mut cells = grid_cells(&shape[..dims], &width[..dims], noisy, seed);
        for c in &mut cells {
            for s in &mut c.samples {
                for v in &mut s.1 {
                    *v += 0.05 * f64::from(noise.next_f32());
                }
            }
        }
        let settings = FitSettings {
            degree: 2,
            ridge,
            clamp: false,
            features: false,
        };
        let fit = Fit::new(&fit_cells(&cells), dims, &settings);
        assert_eq!(fit.degree(), 2);
        // A dim with 2 cell positions gets degree 1 (docs/algorithm.md §5: no more than it can
        // fit).
        let degree: Vec<usize> = shape[..dims].iter().map(|&n| (n - 1).min(2)).collect();

        // The same problem from the raw samples: each cell's row is the mean of the basis over
        // its samples, weighted by its count; the ridge as extra rows.
        let mut lo = [f64::INFINITY; DIMS];
        let mut hi = [f64::NEG_INFINITY; DIMS];
        for c in &cells {
            for d in 0..dims {
                lo[d] = lo[d].min(c.lo[d]);
                hi[d] = hi[d].max(c.hi[d]);
            }
        }
        let m = 1 + degree.iter().sum::<usize>();
        let rows: Vec<(Vec<f64>, f64, [f64; 3])> = cells
            .iter()
            .map(|c| {
                let n = c.samples.len() as f64;
                let mut row = vec![0.0; m];
                let mut mean = [0.0; 3];
                for (p, l) in &c.samples {
                    row[0] += 1.0 / n;
                    let mut col = 1;
                    for d in 0..dims {
                        let u = (p[d] - 0.5 * (lo[d] + hi[d])) / (0.5 * (hi[d] - lo[d]));
                        let b = legendre(u);
                        for k in 1..=degree[d] {
                            row[col] += b[k] / n;
                            col += 1;
                        }
                    }
                    for k in 0..3 {
                        mean[k] += l[k] / n;
                    }
                }
                (row, n, mean)
            })
            .collect();
        let mut trace = 0.0;
        for (row, w, _) in &rows {
            trace += row.iter().map(|v| w * v * v).sum::<f64>();
        }
        let lambda = ridge * trace / m as f64;
        let extra = m - 1;
        let mut a = DMatrix::<f64>::zeros(rows.len() + extra, m);
        let mut b = DMatrix::<f64>::zeros(rows.len() + extra, 3);
        for (i, (row, w, mean)) in rows.iter().enumerate() {
            for j in 0..m {
                a[(i, j)] = w.sqrt() * row[j];
            }
            for k in 0..3 {
                b[(i, k)] = w.sqrt() * mean[k];
            }
        }
        for j in 1..m {
            a[(rows.len() + j - 1, j)] = lambda.sqrt();
        }
        let svd = a.svd(true, true);
        let x = svd.solve(&b, 1e-14).expect("svd solve");
        let scale = x.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let mut worst: f64 = 0.0;
        for (j, c) in fit.coefficients().iter().enumerate() {
            for k in 0..3 {
                worst = worst.max((c[k] - x[(j, k)]).abs() / scale);
            }
        }
        println!("{dims} dims, ridge {ridge}: largest relative difference to SVD {worst:.3e}");
        assert!(worst < 1e-9, "{dims} dims: {worst}");
    }
}

/// Every value the fit gives over its cells and over the whole extent is finite, non-negative
/// and within the range of the usable cell means.
fn check_in_range(name: &str, cells: &[FitCell], dims: usize, settings: &FitSettings) {
    let fit = Fit::new(cells, dims, settings);
    let usable: Vec<&FitCell> = cells
        .iter()
        .filter(|c| c.weight > 0.0 && c.mean.iter().all(|v| v.is_finite()))
        .collect();
    let (lo, hi) = if usable.is_empty() {
        (0.0, 0.0)
    } else {
        let lo = usable
            .iter()
            .flat_map(|c| c.mean)
            .fold(f64::INFINITY, f64::min)
            .max(0.0);
        let hi = usable.iter().flat_map(|c| c.mean).fold(0.0, f64::max);
        (lo, hi)
    };
    let mut boxes: Vec<([f64; DIMS], [f64; DIMS])> = cells.iter().map(|c| (c.lo, c.hi)).collect();
    let mut all = (cells[0].lo, cells[0].hi);
    for c in cells {
        for d in 0..DIMS {
            all.0[d] = all.0[d].min(c.lo[d]);
            all.1[d] = all.1[d].max(c.hi[d]);
        }
    }
    boxes.push(all);
    // Each cell's box with its own features too (and every box with none: the cluster's mean
    // features).
    let with_features = cells.iter().map(|c| ((c.lo, c.hi), Some(&c.features)));
    let plain = boxes.iter().map(|&b| (b, None));
    for ((blo, bhi), f) in with_features.chain(plain) {
        for v in fit.mean_over(&blo, &bhi, f) {
            assert!(v.is_finite(), "{name}: {v}");
            assert!(v >= 0.0, "{name}: {v}");
            assert!(
                v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12),
                "{name}: {v} outside [{lo}, {hi}]"
            );
        }
    }
}

#[test]
fn degenerate_clusters_give_finite_values_in_range() {
    let settings = FitSettings {
        degree: 2,
        ridge: 1e-6,
        clamp: true,
        features: false,
    };
    let exact = FitSettings {
        ridge: 0.0,
        ..settings
    };
    let cell = |x: f64, y: f64, mean: [f64; 3], weight: f64| FitCell {
        lo: [x, y, 0.0, 0.0, 0.0],
        hi: [x + 1.0, y + 1.0, 1.0, 1.0, 1.0],
        m1: [0.5; DIMS],
        m2: [1.0 / 3.0; DIMS],
        mean,
        features: [0.0; 7],
        weight,
    };
    for s in [&settings, &exact] {
        // One cell, one sample.
        check_in_range("one cell", &[cell(0.0, 0.0, [0.4, 0.2, 0.1], 1.0)], 2, s);
        // Every sample at one position: several cells on the same spot.
        let same: Vec<FitCell> = (0..6)
            .map(|i| {
                let mut c = cell(3.0, 3.0, [0.1 * f64::from(i), 0.5, 1.0], 2.0);
                c.m1 = [0.25; DIMS];
                c.m2 = [0.0625; DIMS];
                c
            })
            .collect();
        check_in_range("one position", &same, 2, s);
        // Collinear positions: cells along the diagonal, so x and y terms are the same column.
        let diagonal: Vec<FitCell> = (0..8)
            .map(|i| {
                let v = f64::from(i);
                cell(v, v, [0.1 + v * v, 0.2, 0.3 * v], 3.0)
            })
            .collect();
        check_in_range("collinear", &diagonal, 2, s);
        // Zero weights: all of them, and some of them.
        let zero: Vec<FitCell> = (0..4)
            .map(|i| cell(f64::from(i), 0.0, [1.0, 1.0, 1.0], 0.0))
            .collect();
        check_in_range("no weight", &zero, 2, s);
        assert_eq!(
            Fit::new(&zero, 2, s).mean_over(&zero[0].lo, &zero[0].hi, None),
            [0.0; 3]
        );
        let some: Vec<FitCell> = (0..9)
            .map(|i| {
                let w = if i % 3 == 0 { 0.0 } else { 1.0 };
                cell(
                    f64::from(i % 3),
                    f64::from(i / 3),
                    [f64::from(i) * 0.1; 3],
                    w,
                )
            })
            .collect();
        check_in_range("some weightless", &some, 2, s);
        // A 1e6 dynamic range, with a steep spike.
        let range: Vec<FitCell> = (0..25)
            .map(|i| {
                let v = if i == 12 {
                    1e3
                } else {
                    1e-3 * f64::from(1 + i % 4)
                };
                cell(f64::from(i % 5), f64::from(i / 5), [v, v * 0.5, v], 4.0)
            })
            .collect();
        check_in_range("1e6 range", &range, 2, s);
        // NaN and infinite means (samples that should have been dropped) are skipped.
        let mut bad = range.clone();
        bad[3].mean = [f64::NAN, 0.1, 0.1];
        bad[7].mean = [f64::INFINITY, 0.1, 0.1];
        check_in_range("NaN", &bad, 2, s);
    }
}

/// A cell of a 2D cluster at pixel (x, y) with mean `mean`, 4 samples and features `f`.
fn featured(x: f64, y: f64, mean: [f64; 3], f: [f64; FEATURES]) -> FitCell {
    FitCell {
        lo: [x, y, 0.0, 0.0, 0.0],
        hi: [x + 1.0, y + 1.0, 1.0, 1.0, 1.0],
        m1: [0.5; DIMS],
        m2: [1.0 / 3.0; DIMS],
        mean,
        features: f,
        weight: 4.0,
    }
}

const WITH_FEATURES: FitSettings = FitSettings {
    degree: 2,
    ridge: 0.0,
    clamp: true,
    features: true,
};

#[test]
fn a_field_linear_in_the_albedo_is_reproduced_through_its_edges() {
    // 8 x 8 cells: radiance = albedo × (0.5 + 0.05 x), the albedo 0.2 or 0.8 in a checker. A
    // polynomial in x, y cannot follow the checker; with the albedo as a feature the model
    // (quadratic in x and y, linear in the albedo) is off only by the product term, which
    // the test bounds: 5x smaller error than without.
    let mut rng = Pcg32::new(7, 1);
    let cells: Vec<FitCell> = (0..64)
        .map(|i| {
            let (x, y) = (f64::from(i % 8), f64::from(i / 8));
            let a = if (i % 8 + i / 8) % 2 == 0 { 0.2 } else { 0.8 };
            let light = 0.5 + 0.05 * x;
            let jitter = 1e-3 * f64::from(rng.next_f32());
            featured(x, y, [a * light + jitter; 3], [a, a, a, 0.0, 0.0, 1.0, 3.0])
        })
        .collect();
    let err = |settings: &FitSettings| {
        let fit = Fit::new(&cells, 2, settings);
        let sq: f64 = cells
            .iter()
            .map(|c| (fit.mean_over(&c.lo, &c.hi, Some(&c.features))[0] - c.mean[0]).powi(2))
            .sum();
        (sq / cells.len() as f64).sqrt()
    };
    let with = err(&WITH_FEATURES);
    let without = err(&FitSettings {
        features: false,
        ..WITH_FEATURES
    });
    assert!(
        with < 0.2 * without,
        "with features {with}, without {without}"
    );
    // Albedo the same in all three channels (the green and blue terms repeat the red one and
    // are dropped at their collapsed pivots), normal and depth constant: one term.
    let fit = Fit::new(&cells, 2, &WITH_FEATURES);
    assert_eq!(fit.feature_terms().collect::<Vec<_>>(), vec![0]);
}

#[test]
fn degenerate_features_give_finite_values_in_range() {
    let settings = [
        WITH_FEATURES,
        FitSettings {
            ridge: 1e-6,
            ..WITH_FEATURES
        },
    ];
    let grid = |f: &dyn Fn(f64, f64) -> [f64; FEATURES]| -> Vec<FitCell> {
        (0..36)
            .map(|i| {
                let (x, y) = (f64::from(i % 6), f64::from(i / 6));
                let v = 0.1 + 0.05 * x + 0.3 * ((i * 7) % 5) as f64 / 5.0;
                featured(x, y, [v, 0.5 * v, 2.0 * v], f(x, y))
            })
            .collect()
    };
    for s in &settings {
        // Constant albedo, one normal, zero depth range: no feature term at all.
        let constant = grid(&|_, _| [0.5, 0.5, 0.5, 0.0, 1.0, 0.0, 2.0]);
        check_in_range("constant features", &constant, 2, s);
        assert_eq!(Fit::new(&constant, 2, s).feature_terms().count(), 0);
        let plain = FitSettings {
            features: false,
            ..*s
        };
        assert_eq!(
            Fit::new(&constant, 2, s).coefficients(),
            Fit::new(&constant, 2, &plain).coefficients(),
            "constant features change nothing"
        );
        // A feature collinear with a coordinate: the depth is x, the albedo is y.
        let collinear = grid(&|x, y| [y, y, y, 0.0, 0.0, 1.0, 1.0 + x]);
        check_in_range("collinear features", &collinear, 2, s);
        // Features collinear with each other (the normal's x is the albedo).
        let twins = grid(&|x, _| {
            let a = 0.1 * x;
            [a, a, a, a, 0.0, 1.0, 2.0]
        });
        check_in_range("twin features", &twins, 2, s);
        // A cluster of one cell, and of two.
        check_in_range("one cell", &collinear[..1], 2, s);
        check_in_range("two cells", &collinear[..2], 2, s);
        // NaN and infinite features: no feature term, finite values.
        let mut broken = grid(&|x, _| [0.1 * x, 0.2, 0.3, 0.0, 0.0, 1.0, 2.0]);
        broken[3].features[0] = f64::NAN;
        broken[7].features[6] = f64::INFINITY;
        check_in_range("non-finite features", &broken, 2, s);
        assert_eq!(Fit::new(&broken, 2, s).feature_terms().count(), 0);
        // Huge feature values (a depth of 1e30).
        let far = grid(&|x, _| [0.5, 0.5, 0.5, 0.0, 0.0, 1.0, 1e30 * (1.0 + x)]);
        check_in_range("huge depth", &far, 2, s);
    }
}
