//! Registry filters and independent f64 re-implementations of pbrt-v3's filter formulas, for
//! the reconstruction tests. Each test file uses part of it.
#![allow(dead_code)]

use acr_plugins::space::SamplePoint;
use acr_plugins::{Choice, Filter, FilterKernel, Sampler, FILTERS};
use std::f64::consts::PI;

// ------------------------------------------------------------------------------------------
// Registry helpers.

/// The filter `name` with its default parameters, built through the registry.
pub fn filter(name: &str) -> Box<dyn Filter> {
    let e = FILTERS
        .iter()
        .find(|e| e.info.name == name)
        .unwrap_or_else(|| panic!("no filter {name}"));
    (e.build)(&Choice::new(None, name, None)).unwrap()
}

/// A parameter's declared default, as a number.
pub fn default_param(filter: &str, param: &str) -> f64 {
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
pub fn batches(s: &mut dyn Sampler) -> Vec<Vec<SamplePoint>> {
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
pub fn mitchell_cubic(x: f64, b: f64, c: f64) -> f64 {
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

pub fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-12 {
        1.0
    } else {
        (PI * x).sin() / (PI * x)
    }
}

/// The reference kernel of a registry filter at its declared defaults: a 1D profile per axis.
pub struct Reference {
    pub name: &'static str,
    pub radius: (f64, f64),
    pub profile: Box<dyn Fn(f64, f64) -> f64>,
}

impl Reference {
    pub fn of(name: &'static str) -> Self {
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

    pub fn eval(&self, x: f64, y: f64) -> f64 {
        (self.profile)(x, self.radius.0) * (self.profile)(y, self.radius.1)
    }

    /// The integral of one axis' profile (fine midpoint rule; kinks only at 0 and the ends).
    pub fn integral_1d(&self, r: f64) -> f64 {
        let n = 200_000;
        let h = 2.0 * r / n as f64;
        (0..n)
            .map(|i| (self.profile)(-r + (i as f64 + 0.5) * h, r))
            .sum::<f64>()
            * h
    }
}

/// Midpoint-rule integral of a kernel over its support, `n` x `n` points.
pub fn kernel_integral(k: &dyn FilterKernel, n: usize) -> f64 {
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
