//! Reconstruction through the public API: the filters of the registry against independent
//! re-implementations of pbrt-v3's formulas, the film's weighted mean on constant and analytic
//! radiance fields, the convergence rates of the samplers through film and filter, and the
//! samplers' stratification, each plugin built by name from the registry.
//!
//! Slopes and errors are printed (`cargo test -p acr-plugins --test reconstruction --
//! --nocapture`).

use acr_plugins::film::{Film, FilmSettings};
use acr_plugins::filters::SamplerOutput;
use acr_plugins::space::{Dims, RenderingSpace, SamplePoint};
use acr_plugins::{Choice, Filter, FilterKernel, Sampler, FILTERS, SAMPLERS};
use glam::{Vec2, Vec3};
use std::f64::consts::PI;

mod common;
use common::sampler;

// ------------------------------------------------------------------------------------------
// Registry helpers.

/// The filter `name` with its default parameters, built through the registry.
fn filter(name: &str) -> Box<dyn Filter> {
    let e = FILTERS
        .iter()
        .find(|e| e.info.name == name)
        .unwrap_or_else(|| panic!("no filter {name}"));
    (e.build)(&Choice::new(None, name, None)).unwrap()
}

/// A parameter's declared default, as a number.
fn default_param(filter: &str, param: &str) -> f64 {
    let e = FILTERS.iter().find(|e| e.info.name == filter).unwrap();
    let p = e
        .info
        .params
        .iter()
        .find(|p| p.name == param)
        .unwrap_or_else(|| panic!("{filter} has no parameter {param}"));
    p.default.parse().unwrap()
}

/// Every point a sampler gives, batch by batch.
fn batches(s: &mut dyn Sampler) -> Vec<Vec<SamplePoint>> {
    let mut out = Vec::new();
    let mut b = Vec::new();
    while s.next_batch(&mut b) {
        out.push(b.clone());
    }
    out
}

// ------------------------------------------------------------------------------------------
// Independent f64 re-implementations of pbrt-v3's filters (1D profiles; all are separable).

/// pbrt-v3's Mitchell1D: the Mitchell-Netravali cubic in |x| on [0, 2].
fn mitchell_cubic(x: f64, b: f64, c: f64) -> f64 {
    let x = x.abs();
    if x > 2.0 {
        0.0
    } else if x > 1.0 {
        ((-b - 6.0 * c) * x.powi(3)
            + (6.0 * b + 30.0 * c) * x * x
            + (-12.0 * b - 48.0 * c) * x
            + (8.0 * b + 24.0 * c))
            / 6.0
    } else {
        ((12.0 - 9.0 * b - 6.0 * c) * x.powi(3)
            + (-18.0 + 12.0 * b + 6.0 * c) * x * x
            + (6.0 - 2.0 * b))
            / 6.0
    }
}

fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-12 {
        1.0
    } else {
        (PI * x).sin() / (PI * x)
    }
}

/// The reference kernel of a registry filter at its declared defaults: a 1D profile per axis.
struct Reference {
    name: &'static str,
    radius: (f64, f64),
    profile: Box<dyn Fn(f64, f64) -> f64>,
}

impl Reference {
    fn of(name: &'static str) -> Self {
        let d = |p: &str| default_param(name, p);
        let radius = (d("xwidth"), d("ywidth"));
        let profile: Box<dyn Fn(f64, f64) -> f64> = match name {
            "box" => Box::new(|x: f64, r: f64| if x.abs() <= r { 1.0 } else { 0.0 }),
            "triangle" => Box::new(|x: f64, r: f64| (r - x.abs()).max(0.0)),
            "gaussian" => {
                let a = d("alpha");
                Box::new(move |x: f64, r: f64| {
                    if x.abs() > r {
                        0.0
                    } else {
                        ((-a * x * x).exp() - (-a * r * r).exp()).max(0.0)
                    }
                })
            }
            "mitchell" => {
                let (b, c) = (d("B"), d("C"));
                Box::new(move |x: f64, r: f64| {
                    if x.abs() > r {
                        0.0
                    } else {
                        mitchell_cubic(2.0 * x / r, b, c)
                    }
                })
            }
            "sinc" => {
                let tau = d("tau");
                Box::new(move |x: f64, r: f64| {
                    if x.abs() > r {
                        0.0
                    } else {
                        sinc(x) * sinc(x / tau)
                    }
                })
            }
            other => panic!("no reference for filter {other}: add one"),
        };
        Self {
            name,
            radius,
            profile,
        }
    }

    fn eval(&self, x: f64, y: f64) -> f64 {
        (self.profile)(x, self.radius.0) * (self.profile)(y, self.radius.1)
    }

    /// The integral of one axis' profile (fine midpoint rule; kinks only at 0 and the ends).
    fn integral_1d(&self, r: f64) -> f64 {
        let n = 200_000;
        let h = 2.0 * r / n as f64;
        (0..n)
            .map(|i| (self.profile)(-r + (i as f64 + 0.5) * h, r))
            .sum::<f64>()
            * h
    }
}

/// Midpoint-rule integral of a kernel over its support, `n` x `n` points.
fn kernel_integral(k: &dyn FilterKernel, n: usize) -> f64 {
    let (rx, ry) = k.radius();
    let (rx, ry) = (f64::from(rx), f64::from(ry));
    let (hx, hy) = (2.0 * rx / n as f64, 2.0 * ry / n as f64);
    let mut sum = 0.0;
    for j in 0..n {
        let y = (-ry + (j as f64 + 0.5) * hy) as f32;
        for i in 0..n {
            let x = (-rx + (i as f64 + 0.5) * hx) as f32;
            sum += f64::from(k.eval(x, y));
        }
    }
    sum * hx * hy
}

// ------------------------------------------------------------------------------------------
// 1. Filters.

#[test]
fn registry_filters_match_pbrt_v3_formulas() {
    assert!(!FILTERS.is_empty());
    // The polynomial reconstruction splats nothing of its own (tests/polynomial.rs).
    for e in FILTERS.iter().filter(|e| e.info.name != "polynomial") {
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
            for st in film.pixel_stats() {
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
/// measured errors must match that (up to the noise of 8 seeds' estimate, about 2%). The
/// window is wide on the low side because the random sampler's points are correlated
/// (`random_sampler_points_are_independent`): at 64 and 256 spp the smooth image's error is
/// 12% below the prediction.
fn check_random_box(random: &Convergence, g: Integrand) {
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
    for (e, &n) in random.errors.iter().zip(&SPPS) {
        let predicted = (var / f64::from(n)).sqrt();
        eprintln!("    random box {g:?} spp {n}: RMS {e:.3e}, predicted {predicted:.3e}");
        let ratio = e / predicted;
        assert!(
            (0.8..1.25).contains(&ratio),
            "random box {g:?} spp {n}: RMS {e} vs predicted {predicted}"
        );
    }
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

// ------------------------------------------------------------------------------------------
// 3. Stratification through the registry.

/// Counts of 2D points in an nx x ny grid of [0, 1)^2.
fn grid_counts(pts: &[(f64, f64)], nx: usize, ny: usize) -> Vec<usize> {
    let mut c = vec![0; nx * ny];
    for &(u, v) in pts {
        assert!(
            (0.0..1.0).contains(&u) && (0.0..1.0).contains(&v),
            "({u}, {v})"
        );
        c[(v * ny as f64) as usize * nx + (u * nx as f64) as usize] += 1;
    }
    c
}

/// Every cell of the nx x ny grid holds floor or ceil of n / (nx ny) points.
fn balanced(pts: &[(f64, f64)], nx: usize, ny: usize) -> bool {
    let cells = nx * ny;
    let (lo, hi) = (pts.len() / cells, pts.len().div_ceil(cells));
    grid_counts(pts, nx, ny).iter().all(|&k| k == lo || k == hi)
}

/// The five coordinates of a point: film offsets inside the pixel, t, u, v.
fn coords(q: &SamplePoint) -> [f64; 5] {
    [
        f64::from(q.film[0]) - f64::from(q.pixel[0]),
        f64::from(q.film[1]) - f64::from(q.pixel[1]),
        f64::from(q.time),
        f64::from(q.lens[0]),
        f64::from(q.lens[1]),
    ]
}

/// Each pixel's points, checked complete, in range and row-sorted, grouped by pixel.
fn pixels_of(name: &str, space: RenderingSpace, spp: u32, seed: u64) -> Vec<Vec<SamplePoint>> {
    let mut s = sampler(name, space, spp, seed);
    assert_eq!(s.spp(), spp, "{name}");
    let mut per_pixel = vec![Vec::new(); space.pixels() as usize];
    for b in batches(s.as_mut()) {
        assert!(
            b.windows(2)
                .all(|w| (w[0].pixel[1], w[0].pixel[0]) <= (w[1].pixel[1], w[1].pixel[0])),
            "{name}: batch not row-sorted"
        );
        for q in b {
            for (v, what) in coords(&q).iter().zip(["x", "y", "t", "u", "v"]) {
                assert!((0.0..1.0).contains(v), "{name}: {what} = {v} in {q:?}");
            }
            let k = (q.pixel[1] - space.y0) * space.width() + (q.pixel[0] - space.x0);
            per_pixel[k as usize].push(q);
        }
    }
    for px in &mut per_pixel {
        px.sort_by_key(|q| q.index);
        let idx: Vec<u32> = px.iter().map(|q| q.index).collect();
        assert_eq!(idx, (0..spp).collect::<Vec<_>>(), "{name}: indices");
    }
    per_pixel
}

#[test]
fn registry_samplers_stratify_the_rendering_space() {
    let all = Dims {
        time: true,
        lens: true,
    };
    let space = RenderingSpace::whole(4, 4, all);
    let names: Vec<&str> = SAMPLERS.iter().map(|e| e.info.name).collect();
    for n in ["random", "stratified", "halton", "sobol"] {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }
    // The adaptive samplers give pixels unequal counts by design (plugins/tests/cluster.rs,
    // plugins/tests/rivals.rs).
    let adaptive = ["cluster", "mdas", "gem", "awr"];
    for e in SAMPLERS.iter().filter(|e| !adaptive.contains(&e.info.name)) {
        let name = e.info.name;
        for seed in [1, 2, 3] {
            for px in pixels_of(name, space, 16, seed) {
                let d: Vec<[f64; 5]> = px.iter().map(coords).collect();
                let proj = |a: usize, b: usize| -> Vec<(f64, f64)> {
                    d.iter()
                        .map(|c| (c[a], if b < 5 { c[b] } else { 0.0 }))
                        .collect()
                };
                let one = |a: usize| proj(a, 5);
                match name {
                    "stratified" => {
                        // 4 x 4 strata of the film and of the lens; 16 of time.
                        assert_eq!(grid_counts(&proj(0, 1), 4, 4), vec![1; 16], "film");
                        assert_eq!(grid_counts(&proj(3, 4), 4, 4), vec![1; 16], "lens");
                        assert_eq!(grid_counts(&one(2), 16, 1), vec![1; 16], "time");
                    }
                    "sobol" => {
                        // One per 1/16 of every 1D projection, and the film is a (0, 4, 2)-net:
                        // one point in each elementary interval of area 1/16.
                        for a in 0..5 {
                            assert_eq!(grid_counts(&one(a), 16, 1), vec![1; 16], "sobol dim {a}");
                        }
                        for (nx, ny) in [(1, 16), (2, 8), (4, 4), (8, 2), (16, 1)] {
                            assert_eq!(
                                grid_counts(&proj(0, 1), nx, ny),
                                vec![1; 16],
                                "sobol film {nx}x{ny}"
                            );
                        }
                    }
                    "halton" => {
                        // Base 2 in x: one per 1/16. The other bases (3, 5, 7, 11) cannot put
                        // one point per 1/16 with 16 points; each interval of width b^-m holds
                        // floor or ceil of 16 / b^m (at most one once b^m >= 16).
                        assert_eq!(grid_counts(&one(0), 16, 1), vec![1; 16], "halton x");
                        for (a, b) in [(1usize, 3usize), (2, 5), (3, 7), (4, 11)] {
                            let mut bm = b;
                            while bm < 16 * b {
                                assert!(balanced(&one(a), bm, 1), "halton dim {a} 1/{bm}");
                                bm *= b;
                            }
                        }
                        // Film: every 2^i x 3^j grid is balanced (Chinese remainder theorem).
                        for (nx, ny) in [(2, 3), (4, 3), (8, 3), (2, 9), (16, 9), (4, 27)] {
                            assert!(balanced(&proj(0, 1), nx, ny), "halton film {nx}x{ny}");
                        }
                    }
                    "random" => {}
                    other => panic!("no stratification check for sampler {other}: add one"),
                }
            }
        }
    }
    // Random: uniform by chi-square over many pixels, each projection and two pairs
    // (63 degrees of freedom: the 1e-6 tails lie near 25 and 120).
    let pts: Vec<[f64; 5]> = pixels_of("random", RenderingSpace::whole(32, 32, all), 16, 5)
        .concat()
        .iter()
        .map(coords)
        .collect();
    let chi2 = |c: &[usize]| {
        let e = pts.len() as f64 / c.len() as f64;
        c.iter().map(|&k| (k as f64 - e).powi(2) / e).sum::<f64>()
    };
    let mut stats = Vec::new();
    for a in 0..5 {
        let p: Vec<(f64, f64)> = pts.iter().map(|c| (c[a], 0.0)).collect();
        stats.push(chi2(&grid_counts(&p, 64, 1)));
    }
    for (a, b) in [(0, 1), (2, 3), (1, 4)] {
        let p: Vec<(f64, f64)> = pts.iter().map(|c| (c[a], c[b])).collect();
        stats.push(chi2(&grid_counts(&p, 8, 8)));
    }
    eprintln!("random chi2 (63 dof) x y t u v xy tu yv: {stats:.1?}");
    assert!(
        stats.iter().all(|&s| s > 25.0 && s < 120.0),
        "chi2 {stats:?}"
    );
}

/// The random sampler promises independent points: the variance of a pixel's mean of each
/// coordinate must then be 1 / (12 spp). It is 20-35% lower in x, y, t and u (the points of a
/// pixel are correlated: sample k is the first output of `Pcg32::new(key, k)`, PCG streams of
/// one seed whose states start on an arithmetic progression), and for some frequencies the
/// error is instead up to ~1.8 times that of independent points.
#[test]
fn random_sampler_points_are_independent() {
    let all = Dims {
        time: true,
        lens: true,
    };
    let spp = 256;
    let px = pixels_of("random", RenderingSpace::whole(64, 64, all), spp, 7);
    let ratios: Vec<f64> = (0..5)
        .map(|d| {
            let v = px
                .iter()
                .map(|p| {
                    (p.iter().map(|q| coords(q)[d]).sum::<f64>() / f64::from(spp) - 0.5).powi(2)
                })
                .sum::<f64>()
                / px.len() as f64;
            v * 12.0 * f64::from(spp)
        })
        .collect();
    eprintln!("random: variance of the pixel mean over 1 / (12 spp), x y t u v: {ratios:.3?}");
    // 4096 pixels: each ratio is 1 within about 2% if the points are independent.
    assert!(
        ratios.iter().all(|r| (0.85..1.15).contains(r)),
        "{ratios:?}"
    );
}
