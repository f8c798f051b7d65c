//! A time limit that adapts (docs/algorithm.md §9): told after a batch how many samples per pixel
//! fit in the time ([`Sampler::plan_for`]), an adaptive sampler (the cluster sampler, gem, awr,
//! mdas) ends its first stage at its share of them (not inside a pass) and gives the rest in
//! rounds, exactly that budget in all.

mod common;

use acr_parser::Values;
use acr_plugins::sampler::drive_with;
use acr_plugins::{Dims, RenderingSpace, SamplePoint, Sampler};
use std::collections::HashMap;

/// More pixels than a batch holds, so that a pass is one sample per pixel.
fn space() -> RenderingSpace {
    RenderingSpace {
        x0: 0,
        x1: 220,
        y0: 0,
        y1: 160,
        dims: Dims {
            time: true,
            lens: false,
        },
    }
}

/// The adaptive samplers, each with and without its `unbiased` checkerboard (mdas has none).
const ADAPTIVE: [(&str, Option<bool>); 7] = [
    ("cluster", Some(true)),
    ("cluster", Some(false)),
    ("gem", Some(true)),
    ("gem", Some(false)),
    ("awr", Some(true)),
    ("awr", Some(false)),
    ("mdas", None),
];

fn adaptive(name: &str, unbiased: Option<bool>, spp: u32) -> Box<dyn Sampler> {
    let params: Vec<_> = unbiased
        .map(|u| ("unbiased", Values::Bools(vec![u])))
        .into_iter()
        .collect();
    common::sampler_with(common::choice(name, &params), space(), spp, 3)
}

fn cluster(unbiased: bool, spp: u32) -> Box<dyn Sampler> {
    adaptive("cluster", Some(unbiased), spp)
}

/// Every point `s` gives, in the render loop's order of calls, with `plan_for(plan)` called
/// after batch `after` (the render loop calls it after every batch; once is what matters).
fn points_with_plan(s: &mut dyn Sampler, after: usize, plan: u32) -> Vec<SamplePoint> {
    let radiance = |b: &[SamplePoint]| {
        b.iter()
            .map(|q| common::noisy_step(q, 0.0, |_| false))
            .collect()
    };
    drive_with(s, radiance, |s, batches| {
        if batches == after {
            assert!(s.plan_for(plan), "{} plans for the time", s.name());
        }
    })
}

/// Each pixel's count, after checking that its indices run 0, 1, 2, ...
fn counts(points: &[SamplePoint]) -> Vec<u32> {
    let mut by_pixel: HashMap<[u32; 2], Vec<u32>> = HashMap::new();
    for q in points {
        by_pixel.entry(q.pixel).or_default().push(q.index);
    }
    assert_eq!(
        by_pixel.len() as u64,
        space().pixels(),
        "a pixel got nothing"
    );
    by_pixel
        .into_values()
        .map(|mut ix| {
            ix.sort_unstable();
            assert!(ix.iter().enumerate().all(|(k, &i)| k as u32 == i), "{ix:?}");
            ix.len() as u32
        })
        .collect()
}

/// The first stage's count: the most whole passes the points begin with (a pass: every
/// pixel's next index, the first `k * pixels` points holding indices below `k` alone).
fn first_stage(points: &[SamplePoint]) -> u32 {
    let pixels = space().pixels() as usize;
    counts(points);
    (1..=64)
        .take_while(|&k| {
            let head = points.get(..k as usize * pixels).unwrap_or(points);
            head.len() == k as usize * pixels && head.iter().all(|q| q.index < k)
        })
        .last()
        .unwrap_or(0)
}

#[test]
fn planned_for_fewer_samples_the_first_stage_shrinks_and_the_rounds_adapt() {
    let pixels = space().pixels();
    let batches_per_pass = pixels.div_ceil(1 << 15) as usize;
    for (name, unbiased) in ADAPTIVE {
        let which = format!("{name} unbiased {unbiased:?}");
        // Planned for 64 spp, its first stage would be 16; told after the first batch (the
        // first pass under way) that 8 fit, it makes the first stage a quarter of 8 (2 for a
        // checkerboard, which needs two, and for gem and awr, whose least it is) and spends
        // exactly 8 spp.
        let points = points_with_plan(adaptive(name, unbiased, 64).as_mut(), 1, 8);
        assert_eq!(points.len() as u64, 8 * pixels, "{which}");
        assert_eq!(first_stage(&points), 2, "{which}");
        let c = counts(&points);
        assert!(*c.iter().max().unwrap() > 8, "{which}: it adapts");
        // Told late, inside its fourth pass, the first stage keeps the passes it began (the
        // cluster sampler's checkerboard gives each pass in twice the batches).
        let per_pass = if name == "cluster" && unbiased == Some(true) {
            2 * batches_per_pass
        } else {
            batches_per_pass
        };
        let points = points_with_plan(adaptive(name, unbiased, 64).as_mut(), 3 * per_pass + 1, 8);
        assert_eq!(points.len() as u64, 8 * pixels, "{which}");
        assert_eq!(first_stage(&points), 4, "{which}");
    }
}

#[test]
fn a_plan_of_the_whole_budget_changes_nothing() {
    let plain = points_with_plan(cluster(true, 8).as_mut(), usize::MAX, 8);
    let planned = points_with_plan(cluster(true, 8).as_mut(), 1, 8);
    let key = |q: &SamplePoint| (q.pixel, q.index, q.film[0].to_bits(), q.time.to_bits());
    assert_eq!(plain.len(), planned.len());
    assert!(plain.iter().zip(&planned).all(|(a, b)| key(a) == key(b)));
}

#[test]
fn samplers_that_do_not_plan_say_so() {
    for name in ["stratified", "sobol", "random"] {
        let mut s = common::sampler(name, space(), 16, 1);
        assert!(!s.plan_for(4), "{name}");
    }
}
