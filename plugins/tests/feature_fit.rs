//! The polynomial reconstruction's regression on first-hit features, on the abstract space: a
//! textured surface (a checker of two albedos, not aligned with the pixels) under smooth light,
//! radiance = albedo × light + noise, each sample carrying the albedo at its point as its
//! feature, as the integrator records it. The feature explains the texture's edges, which the
//! polynomial alone must either smooth or keep noisy.

use acr_plugins::first_hit::Features;
use acr_plugins::rng::mix64;
use acr_plugins::space::{Dims, RenderingSpace, SamplePoint};
use acr_plugins::{Choice, Filter, Sampler, Setting, FILTERS};
use glam::Vec3;

mod common;
use common::sampler;

const W: u32 = 64;
const H: u32 = 48;
const NOISE: f64 = 0.25;

fn albedo(x: f64, y: f64) -> f64 {
    let (i, j) = (
        ((x + 0.37) / 6.0).floor() as i64,
        ((y + 0.61) / 6.0).floor() as i64,
    );
    if (i + j).rem_euclid(2) == 0 {
        0.2
    } else {
        0.8
    }
}

fn light(x: f64, y: f64) -> f64 {
    0.5 + 0.5 * x / f64::from(W) + 0.2 * (y / 12.0).sin()
}

/// A sample's radiance and features.
fn sample(q: &SamplePoint) -> (f32, Features) {
    let (x, y) = (f64::from(q.film[0]), f64::from(q.film[1]));
    let h = mix64(u64::from(q.film[0].to_bits()) ^ (u64::from(q.film[1].to_bits()) << 32));
    let noise = ((h >> 40) as f64 / (1u64 << 24) as f64 - 0.5) * 2.0 * NOISE;
    let a = albedo(x, y);
    let l = (a * light(x, y) * (1.0 + noise)) as f32;
    let a = a as f32;
    (l, [a, a, a, 0.0, 0.0, 1.0, 5.0])
}

/// The pixel's exact integral, by a 32 x 32 midpoint rule (the checker's edges fall between
/// the rule's points at most one sub-cell off: far below the errors compared).
fn exact(px: u32, py: u32) -> f64 {
    let mut s = 0.0;
    for j in 0..32 {
        for i in 0..32 {
            let (x, y) = (
                f64::from(px) + (f64::from(i) + 0.5) / 32.0,
                f64::from(py) + (f64::from(j) + 0.5) / 32.0,
            );
            s += albedo(x, y) * light(x, y);
        }
    }
    s / 1024.0
}

fn space() -> RenderingSpace {
    RenderingSpace::whole(W, H, Dims::default())
}

fn filter(name: &str, settings: &[&str]) -> Box<dyn Filter> {
    let e = FILTERS.iter().find(|e| e.info.name == name).unwrap();
    let mut c = Choice::new(None, name, None);
    for arg in settings {
        Setting::parse(arg).unwrap().apply(&e.info, &mut c).unwrap();
    }
    (e.build)(&c).unwrap()
}

/// The image `f` makes from the samples of `s` on the textured field.
fn render(s: Box<dyn Sampler>, f: &dyn Filter) -> Vec<Vec3> {
    common::render_field(space(), s, f, |q| {
        let (l, features) = sample(q);
        ([l; 3], features)
    })
}

/// RMS error against the exact pixels and the image mean over the exact mean, over 3 seeds.
fn measure(sampler_name: &str, f: &dyn Filter, spp: u32) -> (f64, f64) {
    let (mut sq, mut got, mut want, mut n) = (0.0, 0.0, 0.0, 0usize);
    for seed in 1..=3 {
        let img = render(sampler(sampler_name, space(), spp, seed), f);
        for py in 0..H {
            for px in 0..W {
                let v = f64::from(img[(py * W + px) as usize].x);
                assert!(v.is_finite() && v >= 0.0, "{v}");
                let e = exact(px, py);
                sq += (v - e).powi(2);
                got += v;
                want += e;
                n += 1;
            }
        }
    }
    ((sq / n as f64).sqrt(), got / want)
}

#[test]
fn features_explain_a_texture_that_the_polynomial_alone_smooths() {
    let gaussian = filter("gaussian", &[]);
    let plain = filter("polynomial", &["filter.features=false"]);
    let with = filter("polynomial", &[]);
    assert!(with.reads_features() && !plain.reads_features());
    for (sampler_name, spp) in [("stratified", 8), ("stratified", 16), ("cluster", 16)] {
        let (g, _) = measure(sampler_name, gaussian.as_ref(), spp);
        let (p, _) = measure(sampler_name, plain.as_ref(), spp);
        let (f, mean) = measure(sampler_name, with.as_ref(), spp);
        println!(
            "{sampler_name} {spp} spp, RMS: gaussian {g:.4}, polynomial {p:.4}, \
             polynomial+features {f:.4} (image mean / exact {mean:.4})"
        );
        // Measured (3 seeds): features 0.0302, 0.0193, 0.0138 against the polynomial alone's
        // 0.0739, 0.0510, 0.0485 and gaussian's 0.0275, 0.0221, 0.0287. At 8 spp after
        // stratified gaussian's blur still wins: a cell's 8 samples leave its mean albedo too
        // noisy at the checker's edges for the term to explain them.
        assert!(
            f < 0.6 * p,
            "{sampler_name} {spp}: features {f}, without {p}"
        );
        if spp >= 16 {
            assert!(
                f < 0.95 * g,
                "{sampler_name} {spp}: features {f}, gaussian {g}"
            );
        }
        assert!(
            (mean - 1.0).abs() < 0.005,
            "{sampler_name} {spp}: mean {mean}"
        );
    }
}
