//! Reconstruction through the public API: the filters of the registry against independent
//! re-implementations of pbrt-v3's formulas, the film's weighted mean on constant and analytic
//! radiance fields, and the convergence rates of the samplers through film and filter, each
//! plugin built by name from the registry (the samplers' stratification: `stratification.rs`).
//!
//! Slopes and errors are printed (`cargo test -p acr-plugins --test reconstruction --
//! --nocapture`).

use acr_plugins::film::{Film, FilmSettings};
use acr_plugins::filters::SamplerOutput;
use acr_plugins::space::{Dims, RenderingSpace};
use acr_plugins::{Filter, FilterKernel, FILTERS};
use glam::{Vec2, Vec3};

mod common;
mod filter_reference;
use common::sampler;
use filter_reference::{batches, filter, kernel_integral, Reference};

// ------------------------------------------------------------------------------------------
// 1. Filters.

#[test]
fn registry_filters_match_pbrt_v3_formulas() {
    assert!(!FILTERS.is_empty());
    // The polynomial and nfor reconstructions splat nothing of their own (tests/polynomial.rs,
    // the nfor module's tests).
    for e in FILTERS
        .iter()
        .filter(|e| !matches!(e.info.name, "polynomial" | "nfor"))
    {
        let name = e.info.name;
        let f = filter(name);
        assert_eq!(f.name(), name);
        let k = f.kernel();
        let r = Reference::of(name);
        let (rx, ry) = k.radius();
        assert_eq!(
            (f64::from(rx), f64::from(ry)),
            r.radius,
            "{name}: radius against the declared defaults"
        );
        // Normalised by the reference's integral (computed separately in f64 per axis), the
        // kernel integrates to 1: its mass is the formula's.
        let reference_integral = r.integral_1d(r.radius.0) * r.integral_1d(r.radius.1);
        let integral = kernel_integral(k, 600);
        assert!(reference_integral > 0.0, "{name}");
        let normalised = integral / reference_integral;
        eprintln!("{name:>9}: integral {integral:.6}, normalised {normalised:.7}");
        assert!(
            (normalised - 1.0).abs() < 2e-4,
            "{name}: normalised integral {normalised}"
        );
        // Values on a grid reaching past the radius, plus the radius itself.
        let mut xs: Vec<f32> = (0..=46)
            .map(|i| (-1.3 + 2.6 * i as f64 / 46.0) as f32 * rx)
            .collect();
        xs.extend([rx, -rx, 0.0, 0.5 * rx]);
        let mut ys: Vec<f32> = (0..=38)
            .map(|i| (-1.3 + 2.6 * i as f64 / 38.0) as f32 * ry)
            .collect();
        ys.extend([ry, -ry, 0.0, 0.25 * ry]);
        let mut worst = 0.0f64;
        for &y in &ys {
            for &x in &xs {
                let v = k.eval(x, y);
                // Symmetric in each axis.
                for (sx, sy) in [(-x, y), (x, -y), (-x, -y)] {
                    let w = k.eval(sx, sy);
                    assert!(
                        (v - w).abs() <= 1e-7 * v.abs().max(1.0),
                        "{name}: ({x}, {y}) {v} vs ({sx}, {sy}) {w}"
                    );
                }
                // Zero outside the radius.
                if x.abs() > rx || y.abs() > ry {
                    assert_eq!(v, 0.0, "{name}: nonzero at ({x}, {y}) outside the radius");
                }
                let want = r.eval(f64::from(x), f64::from(y));
                let err = (f64::from(v) - want).abs() / want.abs().max(1.0);
                worst = worst.max(err);
                assert!(
                    err < 1e-5,
                    "{name}: ({x}, {y}) = {v}, pbrt-v3 formula {want}"
                );
            }
        }
        eprintln!("{name:>9}: worst deviation from the formula {worst:.2e}");
        // Far outside too.
        for (x, y) in [
            (3.0 * rx, 0.0),
            (0.0, -3.0 * ry),
            (rx * 1.0001, ry * 0.5),
            (100.0, 100.0),
        ] {
            assert_eq!(k.eval(x, y), 0.0, "{name}: ({x}, {y})");
        }
    }
    // Every registered filter was checked against a reference (Reference::of panics otherwise).
    let names: Vec<&str> = FILTERS.iter().map(|e| e.info.name).collect();
    for n in ["box", "triangle", "gaussian", "mitchell", "sinc"] {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }
}

#[test]
fn mitchell_one_third_integrates_to_one() {
    use acr_plugins::filters::MitchellFilter;
    let k = MitchellFilter::new(2.0, 2.0, 1.0 / 3.0, 1.0 / 3.0);
    // Separable: eval(x, 0) = M(x) M(0), eval(0, 0) = M(0)^2, so the 1D profile's integral is
    // that of eval(x, 0) over sqrt(eval(0, 0)).
    let m0 = f64::from(k.eval(0.0, 0.0)).sqrt();
    assert!((m0 - (6.0 - 2.0 / 3.0) / 6.0).abs() < 1e-6);
    let n = 100_000;
    let h = 4.0 / n as f64;
    let one_d: f64 = (0..n)
        .map(|i| f64::from(k.eval((-2.0 + (i as f64 + 0.5) * h) as f32, 0.0)))
        .sum::<f64>()
        * h
        / m0;
    eprintln!("mitchell B = C = 1/3: 1D integral {one_d:.7}");
    assert!((one_d - 1.0).abs() < 1e-5, "1D integral {one_d}");
    let two_d = kernel_integral(&k, 800);
    assert!((two_d - 1.0).abs() < 1e-4, "2D integral {two_d}");
    // Partition of unity (what makes the integral 1): shifted copies sum to 1 everywhere.
    for i in 0..50 {
        let x = i as f64 / 50.0;
        let s: f64 = (-3..=3)
            .map(|j| f64::from(k.eval((x + j as f64) as f32, 0.0)) / m0)
            .sum();
        assert!((s - 1.0).abs() < 1e-5, "sum of shifts at {x}: {s}");
    }
}

#[test]
fn constant_radiance_reconstructs_exactly_with_every_filter() {
    // A 16 x 12 crop of a 20 x 16 image: the filters reach past the crop, samples do not.
    let mut settings = FilmSettings::with_resolution(20, 16);
    settings.crop = [2, 18, 3, 15];
    let space = RenderingSpace {
        x0: 2,
        x1: 18,
        y0: 3,
        y1: 15,
        dims: Dims::default(),
    };
    let c = Vec3::new(0.7, 1.3, 2.5);
    for e in FILTERS {
        let f = filter(e.info.name);
        for sampler_name in ["random", "sobol"] {
            let mut s = sampler(sampler_name, space, 4, 17);
            let mut film = Film::new(settings.clone(), f.kernel());
            for b in batches(s.as_mut()) {
                let samples: Vec<(Vec2, Vec3)> =
                    b.iter().map(|q| (Vec2::from(q.film), c)).collect();
                film.add_samples(&samples);
            }
            let img = f.reconstruct(&film, SamplerOutput::default());
            assert_eq!(img, film.pixels());
            assert_eq!(img.len(), 16 * 12);
            for (i, v) in img.iter().enumerate() {
                let rel = ((*v - c) / c).abs().max_element();
                assert!(
                    rel < 1e-5,
                    "{} with {sampler_name}: pixel ({}, {}) = {v}, not {c}",
                    e.info.name,
                    i % 16 + 2,
                    i / 16 + 3
                );
            }
            for st in film.pixel_stats().iter() {
                assert_eq!(st.count, 4);
                assert!(((st.mean() - c) / c).abs().max_element() < 1e-6);
                assert!(st.variance_of_mean().max_element() < 1e-10);
            }
        }
    }
}

// ------------------------------------------------------------------------------------------
// 2. Convergence.

const W: u32 = 24;
const H: u32 = 16;
const SPPS: [u32; 4] = [4, 16, 64, 256];
const SEEDS: u64 = 8;
/// Entries per axis of the film's filter table (pbrt-v3's filterTableWidth).
const TABLE: usize = 16;

#[derive(Clone, Copy, Debug)]
enum Integrand {
    Smooth,
    Edge,
}

/// The edge: radiance 1 where x cos(theta) + y sin(theta) > c, else 0.1; the line passes
/// near the image's centre at a slant.
const THETA: f64 = 1.0;
const EDGE_POINT: (f64, f64) = (12.3, 7.9);
const DARK: f64 = 0.1;

fn edge_normal() -> (f64, f64, f64) {
    let (nx, ny) = (THETA.cos(), THETA.sin());
    (nx, ny, nx * EDGE_POINT.0 + ny * EDGE_POINT.1)
}

impl Integrand {
    fn eval(self, x: f64, y: f64) -> f64 {
        match self {
            Integrand::Smooth => 1.0 + 0.5 * (0.7 * x).sin() * (0.45 * y).cos() + 0.02 * x,
            Integrand::Edge => {
                let (nx, ny, c) = edge_normal();
                if nx * x + ny * y > c {
                    1.0
                } else {
                    DARK
                }
            }
        }
    }

    /// The exact integral over [x0, x1] x [y0, y1].
    fn rect_integral(self, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
        let area = (x1 - x0) * (y1 - y0);
        match self {
            Integrand::Smooth => {
                let sx = ((0.7 * x0).cos() - (0.7 * x1).cos()) / 0.7;
                let cy = ((0.45 * y1).sin() - (0.45 * y0).sin()) / 0.45;
                area + 0.5 * sx * cy + 0.02 * 0.5 * (x1 * x1 - x0 * x0) * (y1 - y0)
            }
            Integrand::Edge => {
                let lit = halfplane_area(x0, x1, y0, y1);
                DARK * area + (1.0 - DARK) * lit
            }
        }
    }
}

/// The exact area of the rectangle's part where x cos(theta) + y sin(theta) > c: the
/// rectangle clipped by the line (Sutherland-Hodgman), then the shoelace formula.
fn halfplane_area(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let (nx, ny, c) = edge_normal();
    let s = |p: (f64, f64)| nx * p.0 + ny * p.1 - c;
    let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)];
    let mut poly = Vec::with_capacity(5);
    for i in 0..4 {
        let (a, b) = (corners[i], corners[(i + 1) % 4]);
        let (sa, sb) = (s(a), s(b));
        if sa > 0.0 {
            poly.push(a);
        }
        if (sa > 0.0) != (sb > 0.0) {
            let t = sa / (sa - sb);
            poly.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
        }
    }
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (p, q) = (poly[i], poly[(i + 1) % n]);
            p.0 * q.1 - q.0 * p.1
        })
        .sum::<f64>()
        .abs()
        * 0.5
}

/// The limit of the film's weighted mean at pixel (i, j) as the samples fill the image: the
/// integral of f times the film's tabulated filter weight around the pixel centre, over the
/// integral of the weight, both over the rendered image only (samples land nowhere else).
/// The table is constant on cells r/16 wide, so each is exact: weights times cell integrals.
fn limit(reference: &Reference, f: Integrand, i: u32, j: u32) -> f64 {
    let (rx, ry) = reference.radius;
    let (cx, cy) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
    let (hx, hy) = (rx / TABLE as f64, ry / TABLE as f64);
    let (mut num, mut den) = (0.0, 0.0);
    for b in 0..2 * TABLE {
        // Cell b covers offsets [(b - 16) h, (b - 15) h); its table row is that of |offset|.
        let oy = b as f64 - TABLE as f64;
        let ty = if oy >= 0.0 { oy } else { -oy - 1.0 };
        let (y0, y1) = (
            (cy + oy * hy).max(0.0),
            (cy + (oy + 1.0) * hy).min(f64::from(H)),
        );
        if y0 >= y1 {
            continue;
        }
        for a in 0..2 * TABLE {
            let ox = a as f64 - TABLE as f64;
            let tx = if ox >= 0.0 { ox } else { -ox - 1.0 };
            let (x0, x1) = (
                (cx + ox * hx).max(0.0),
                (cx + (ox + 1.0) * hx).min(f64::from(W)),
            );
            if x0 >= x1 {
                continue;
            }
            // The film's table entry: the kernel at the centre of the cell.
            let w = reference.eval((tx + 0.5) * hx, (ty + 0.5) * hy);
            num += w * f.rect_integral(x0, x1, y0, y1);
            den += w * (x1 - x0) * (y1 - y0);
        }
    }
    num / den
}

/// The image `sampler_name` and the filter `filter_name` make of `f` at `spp`.
fn render(sampler_name: &str, f: &dyn Filter, g: Integrand, spp: u32, seed: u64) -> Vec<f64> {
    let mut s = sampler(
        sampler_name,
        RenderingSpace::whole(W, H, Dims::default()),
        spp,
        seed,
    );
    assert_eq!(s.spp(), spp, "{sampler_name}");
    let mut film = Film::new(FilmSettings::with_resolution(W, H), f.kernel());
    let mut b = Vec::new();
    let mut samples = Vec::new();
    while s.next_batch(&mut b) {
        samples.clear();
        samples.extend(b.iter().map(|q| {
            let v = g.eval(f64::from(q.film[0]), f64::from(q.film[1])) as f32;
            (Vec2::from(q.film), Vec3::splat(v))
        }));
        film.add_samples(&samples);
    }
    f.reconstruct(&film, SamplerOutput::default())
        .iter()
        .map(|v| f64::from(v.x))
        .collect()
}

/// Least-squares slope of log(err) against log(spp).
fn slope(errs: &[f64]) -> f64 {
    let xs: Vec<f64> = SPPS.iter().map(|&n| f64::from(n).ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

struct Convergence {
    /// RMS error over pixels and seeds, per spp.
    errors: Vec<f64>,
    slope: f64,
}

/// RMS errors of `sampler_name` with `filter_name` on `g` at every spp of SPPS, and their
/// log-log slope.
fn convergence(sampler_name: &str, filter_name: &'static str, g: Integrand) -> Convergence {
    let f = filter(filter_name);
    let reference = Reference::of(filter_name);
    let exact: Vec<f64> = (0..W * H)
        .map(|k| limit(&reference, g, k % W, k / W))
        .collect();
    let errors: Vec<f64> = SPPS
        .iter()
        .map(|&spp| {
            let mut sum_sq = 0.0;
            for seed in 0..SEEDS {
                let img = render(sampler_name, f.as_ref(), g, spp, 1000 + seed);
                sum_sq += img
                    .iter()
                    .zip(&exact)
                    .map(|(v, e)| (v - e).powi(2))
                    .sum::<f64>();
            }
            (sum_sq / (SEEDS as f64 * exact.len() as f64)).sqrt()
        })
        .collect();
    let slope = slope(&errors);
    eprintln!(
        "{sampler_name:>10} {:>8} {:<6}: slope {slope:+.3}, RMS error at spp {SPPS:?}: {}",
        reference.name,
        format!("{g:?}"),
        errors
            .iter()
            .map(|e| format!("{e:.2e}"))
            .collect::<Vec<_>>()
            .join(" ")
    );
    Convergence { errors, slope }
}

/// Checks the rates every (filter, integrand) pair shares and returns them for the
/// pair-specific ones.
fn check_rates(filter_name: &'static str, g: Integrand) -> [Convergence; 4] {
    let [random, stratified, halton, sobol] =
        ["random", "stratified", "halton", "sobol"].map(|s| convergence(s, filter_name, g));
    let tag = format!("{filter_name} {g:?}");
    // Independent points: the Monte Carlo rate N^-1/2.
    assert!(
        (-0.65..=-0.35).contains(&random.slope),
        "{tag}: random slope {}",
        random.slope
    );
    // Errors fall at every step for the stratified samplers.
    for (name, c) in [("stratified", &stratified), ("sobol", &sobol)] {
        assert!(
            c.errors.windows(2).all(|w| w[1] < w[0]),
            "{tag}: {name} errors {:?}",
            c.errors
        );
    }
    // Sobol (Owen-scrambled (0, 2)-sequence) is at least as good as jittered strata, up to
    // a margin for noise in the measured errors.
    assert!(
        sobol.slope < stratified.slope + 0.1,
        "{tag}: sobol slope {} vs stratified {}",
        sobol.slope,
        stratified.slope
    );
    assert!(
        sobol.errors[3] < 1.3 * stratified.errors[3],
        "{tag}: sobol error {} vs stratified {} at 256 spp",
        sobol.errors[3],
        stratified.errors[3]
    );
    // Everything beats independent points at 256 spp.
    for (name, c) in [
        ("stratified", &stratified),
        ("halton", &halton),
        ("sobol", &sobol),
    ] {
        assert!(
            c.errors[3] < random.errors[3],
            "{tag}: {name} error {} vs random {} at 256 spp",
            c.errors[3],
            random.errors[3]
        );
    }
    [random, stratified, halton, sobol]
}

#[test]
fn box_filter_converges_on_smooth_integrand() {
    let [random, stratified, halton, sobol] = check_rates("box", Integrand::Smooth);
    // Jittered strata on a smooth integrand: N^-1 (variance N^-1-2/d, d = 2).
    assert!(
        stratified.slope < -0.8,
        "stratified slope {}",
        stratified.slope
    );
    assert!(
        stratified.errors[3] < 5e-4,
        "stratified error {}",
        stratified.errors[3]
    );
    // Owen-scrambled Sobol on a smooth integrand: N^-3/2.
    assert!(sobol.slope < -1.2, "sobol slope {}", sobol.slope);
    assert!(sobol.errors[3] < 5e-5, "sobol error {}", sobol.errors[3]);
    assert!(halton.slope < -0.8, "halton slope {}", halton.slope);
    check_random_box(&random, Integrand::Smooth);
}

#[test]
fn box_filter_converges_on_edge() {
    let [random, stratified, halton, sobol] = check_rates("box", Integrand::Edge);
    // Jittered strata across an edge: N^-3/4 (variance N^-1-1/d, d = 2).
    assert!(
        stratified.slope < -0.6,
        "stratified slope {}",
        stratified.slope
    );
    assert!(sobol.slope < -0.6, "sobol slope {}", sobol.slope);
    assert!(halton.slope < -0.6, "halton slope {}", halton.slope);
    assert!(
        stratified.errors[3] < 3e-3,
        "stratified error {}",
        stratified.errors[3]
    );
    assert!(sobol.errors[3] < 3e-3, "sobol error {}", sobol.errors[3]);
    check_random_box(&random, Integrand::Edge);
}

/// With the box filter and independent points a pixel is the mean of N uniform samples of f
/// over it, so the RMS error is exactly sqrt(mean over pixels of Var_pixel(f) / N): the
/// measured errors must match that up to the noise of the 8 seeds' estimate. That noise was
/// measured over 30 other sets of 8 seeds (first seeds 5000, 5100, ..., 7900): the ratio's
/// standard deviation is 1.3-1.6% on the smooth image (means 0.998-1.001) and 4.1-5.8% on the
/// edge (means 0.979-0.997; only the pixels the edge crosses have any variance). The window
/// is 4 of those deviations, the larger over spp, each side of 1.
fn check_random_box(random: &Convergence, g: Integrand) {
    let sigma = match g {
        Integrand::Smooth => 0.016,
        Integrand::Edge => 0.058,
    };
    let window = 1.0 - 4.0 * sigma..1.0 + 4.0 * sigma;
    for ((e, &n), predicted) in random.errors.iter().zip(&SPPS).zip(random_box_rms(g)) {
        eprintln!("    random box {g:?} spp {n}: RMS {e:.3e}, predicted {predicted:.3e}");
        let ratio = e / predicted;
        assert!(
            window.contains(&ratio),
            "random box {g:?} spp {n}: RMS {e} vs predicted {predicted} (ratio {ratio}, \
             window {window:?})"
        );
    }
}

/// The RMS error of the box filter with independent points on `g` at each spp of SPPS:
/// sqrt(mean over pixels of Var_pixel(f) / N).
fn random_box_rms(g: Integrand) -> Vec<f64> {
    let mut var = 0.0;
    for k in 0..W * H {
        let (i, j) = (f64::from(k % W), f64::from(k / W));
        var += match g {
            Integrand::Smooth => {
                let n = 64;
                let (mut s, mut s2) = (0.0, 0.0);
                for m in 0..n * n {
                    let x = i + ((m % n) as f64 + 0.5) / n as f64;
                    let y = j + ((m / n) as f64 + 0.5) / n as f64;
                    let v = g.eval(x, y);
                    s += v;
                    s2 += v * v;
                }
                let nn = (n * n) as f64;
                s2 / nn - (s / nn).powi(2)
            }
            Integrand::Edge => {
                let a = halfplane_area(i, i + 1.0, j, j + 1.0);
                (1.0 - DARK).powi(2) * a * (1.0 - a)
            }
        };
    }
    var /= f64::from(W * H);
    SPPS.iter().map(|&n| (var / f64::from(n)).sqrt()).collect()
}

#[test]
fn gaussian_filter_converges_on_smooth_integrand() {
    let [random, stratified, halton, sobol] = check_rates("gaussian", Integrand::Smooth);
    assert!(
        stratified.slope < -0.8,
        "stratified slope {}",
        stratified.slope
    );
    assert!(sobol.slope < -1.2, "sobol slope {}", sobol.slope);
    assert!(halton.slope < -0.8, "halton slope {}", halton.slope);
    assert!(
        stratified.errors[3] < 3e-4,
        "stratified error {}",
        stratified.errors[3]
    );
    // Below the 1.6e-4 by which the table moves the limit (references_are_consistent): the
    // film converges to the tabulated filter's weighted mean, border pixels included.
    assert!(sobol.errors[3] < 5e-5, "sobol error {}", sobol.errors[3]);
    assert!(random.errors[3] < 4e-3, "random error {}", random.errors[3]);
}

#[test]
fn gaussian_filter_converges_on_edge() {
    let [random, stratified, halton, sobol] = check_rates("gaussian", Integrand::Edge);
    assert!(
        stratified.slope < -0.6,
        "stratified slope {}",
        stratified.slope
    );
    assert!(sobol.slope < -0.6, "sobol slope {}", sobol.slope);
    assert!(halton.slope < -0.6, "halton slope {}", halton.slope);
    assert!(
        stratified.errors[3] < 2e-3,
        "stratified error {}",
        stratified.errors[3]
    );
    assert!(random.errors[3] < 7e-3, "random error {}", random.errors[3]);
}

/// The references themselves: the box limit is the pixel's mean, the tabulated gaussian
/// differs from the exact one (so the table matters), and the half-plane area is exact.
#[test]
fn references_are_consistent() {
    // Half-plane area against a fine midpoint count on a pixel the edge crosses.
    let (nx, ny, c) = edge_normal();
    let mut crossed = 0;
    for k in 0..W * H {
        let (i, j) = (f64::from(k % W), f64::from(k / W));
        let corners = [(i, j), (i + 1.0, j), (i, j + 1.0), (i + 1.0, j + 1.0)];
        let lit = corners.iter().filter(|p| nx * p.0 + ny * p.1 > c).count();
        let a = halfplane_area(i, i + 1.0, j, j + 1.0);
        match lit {
            0 => assert_eq!(a, 0.0),
            4 => assert!((a - 1.0).abs() < 1e-12),
            _ => {
                crossed += 1;
                let n = 400;
                let inside = (0..n * n)
                    .filter(|m| {
                        let x = i + ((m % n) as f64 + 0.5) / n as f64;
                        let y = j + ((m / n) as f64 + 0.5) / n as f64;
                        nx * x + ny * y > c
                    })
                    .count() as f64
                    / (n * n) as f64;
                assert!(
                    (a - inside).abs() < 2e-3,
                    "pixel ({i}, {j}): {a} vs {inside}"
                );
            }
        }
    }
    assert!(crossed > 20, "the edge crosses {crossed} pixels");
    // Smooth rect integral against a midpoint sum.
    let g = Integrand::Smooth;
    let (x0, x1, y0, y1) = (3.25, 4.5, 7.0, 7.125);
    let n = 200;
    let mid: f64 = (0..n * n)
        .map(|m| {
            let x = x0 + (x1 - x0) * ((m % n) as f64 + 0.5) / n as f64;
            let y = y0 + (y1 - y0) * ((m / n) as f64 + 0.5) / n as f64;
            g.eval(x, y)
        })
        .sum::<f64>()
        * (x1 - x0)
        * (y1 - y0)
        / (n * n) as f64;
    assert!((mid - g.rect_integral(x0, x1, y0, y1)).abs() < 1e-6);
    // The box limit is the pixel mean.
    let bx = Reference::of("box");
    for (i, j) in [(0, 0), (5, 7), (23, 15)] {
        let want = g.rect_integral(
            f64::from(i),
            f64::from(i) + 1.0,
            f64::from(j),
            f64::from(j) + 1.0,
        );
        assert!((limit(&bx, g, i, j) - want).abs() < 1e-12);
    }
    // Tabulation moves the gaussian's limit by more than the errors measured at 256 spp.
    let gs = Reference::of("gaussian");
    let (i, j) = (11u32, 8u32);
    let (cx, cy) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
    let n = 800;
    let h = 4.0 / n as f64;
    let (mut num, mut den) = (0.0, 0.0);
    for b in 0..n {
        for a in 0..n {
            let (dx, dy) = (-2.0 + (a as f64 + 0.5) * h, -2.0 + (b as f64 + 0.5) * h);
            let w = gs.eval(dx, dy);
            num += w * g.eval(cx + dx, cy + dy);
            den += w;
        }
    }
    let untabulated = num / den;
    let tabulated = limit(&gs, g, i, j);
    eprintln!(
        "gaussian limit at ({i}, {j}): tabulated {tabulated:.7}, exact kernel {untabulated:.7}"
    );
    assert!((tabulated - untabulated).abs() > 1e-4);
}
