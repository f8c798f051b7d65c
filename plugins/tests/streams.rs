//! The adaptive samplers' two sample streams (docs/algorithm.md §8): each stream's points are
//! decided from the other stream's values only, the budget is spent exactly, the streams are
//! told apart by the index's parity, and the film's image is the mean of the two streams'.

mod common;

use acr_parser::Values;
use acr_plugins::film::{Film, FilmSettings};
use acr_plugins::filters::BoxFilter;
use acr_plugins::sampler::drive;
use acr_plugins::{Dims, RenderingSpace, SamplePoint};
use glam::{Vec2, Vec3};

const ADAPTIVE: [&str; 4] = ["cluster", "mdas", "gem", "awr"];

fn space() -> RenderingSpace {
    RenderingSpace {
        x0: 0,
        x1: 24,
        y0: 0,
        y1: 16,
        dims: Dims {
            time: true,
            lens: false,
        },
    }
}

/// The noisy step, `extra` noise added to the values of stream 0 (even indices) only.
fn field(q: &SamplePoint, extra: f32) -> [f32; 3] {
    common::noisy_step(q, extra, |q| q.index % 2 == 0)
}

/// The sampler `name` with `streams` set.
fn with_streams(name: &str, streams: i32, spp: u32) -> Box<dyn acr_plugins::Sampler> {
    let c = common::choice(name, &[("streams", Values::Ints(vec![streams]))]);
    common::sampler_with(c, space(), spp, 7)
}

/// The batches of stream 0 (even indices), in order, each observed before the next is asked.
fn stream_0_batches(name: &str, extra: f32) -> Vec<Vec<SamplePoint>> {
    let mut s = with_streams(name, 2, 8);
    let (mut batch, mut out) = (Vec::new(), Vec::new());
    while s.next_batch(&mut batch) {
        let r: Vec<[f32; 3]> = batch.iter().map(|q| field(q, extra)).collect();
        s.observe(&batch, &r);
        if batch.iter().all(|q| q.index % 2 == 0) {
            out.push(batch.clone());
        }
    }
    out
}

fn key(q: &SamplePoint) -> (u32, u32, u32, [u32; 2]) {
    (
        q.pixel[0],
        q.pixel[1],
        q.index,
        [q.film[0].to_bits(), q.time.to_bits()],
    )
}

#[test]
fn a_streams_first_round_does_not_depend_on_its_own_values() {
    // Stream 0's values change; its first batch (the uniform first stage) and its first
    // adaptive round, planned from stream 1's values alone, stay. Later rounds may move: the
    // other stream's later points went where stream 0's values sent them (the second-order
    // dependence docs/rivals.md states).
    for name in ADAPTIVE {
        let (a, b) = (stream_0_batches(name, 0.0), stream_0_batches(name, 2.0));
        assert!(a.len() >= 2, "{name}: {} batches", a.len());
        let keys = |v: &[SamplePoint]| v.iter().map(key).collect::<Vec<_>>();
        for k in 0..2 {
            assert!(
                keys(&a[k]) == keys(&b[k]),
                "{name}: batch {k} followed its own values"
            );
        }
        // And the values do reach the other stream.
        let odd = |extra| {
            let mut s = with_streams(name, 2, 8);
            let p = drive(
                s.as_mut(),
                |b| b.iter().map(|q| field(q, extra)).collect(),
                None,
            );
            p.iter()
                .filter(|q| q.index % 2 == 1)
                .map(key)
                .collect::<Vec<_>>()
        };
        assert!(
            odd(0.0) != odd(2.0),
            "{name}: stream 1 ignored stream 0's values"
        );
    }
}

#[test]
fn two_streams_spend_the_budget_exactly_and_are_deterministic() {
    for name in ADAPTIVE {
        for spp in [2, 5, 8] {
            let mut s = with_streams(name, 2, spp);
            assert_eq!(s.streams(), 2, "{name}");
            assert_eq!(s.spp(), spp, "{name}");
            let run = |s: &mut dyn acr_plugins::Sampler| {
                drive(s, |b| b.iter().map(|q| field(q, 0.0)).collect(), None)
            };
            let p = run(s.as_mut());
            assert_eq!(p.len() as u64, space().pixels() * u64::from(spp), "{name}");
            // Each stream gave every pixel at least one sample, and no index twice.
            let mut seen = std::collections::HashSet::new();
            let mut per = vec![[0u32; 2]; space().pixels() as usize];
            for q in &p {
                assert!(seen.insert((q.pixel, q.index)), "{name}: index repeated");
                per[space().index_of(q.pixel)][q.index as usize % 2] += 1;
            }
            assert!(per.iter().all(|c| c[0] > 0 && c[1] > 0), "{name} {spp}");
            assert!(p == run(with_streams(name, 2, spp).as_mut()), "{name}");
        }
        // One stream is the method as published.
        assert_eq!(with_streams(name, 1, 8).streams(), 1, "{name}");
    }
}

#[test]
fn a_split_film_is_the_mean_of_its_streams() {
    let mut film = Film::new(
        FilmSettings::with_resolution(2, 1),
        &BoxFilter::new(0.5, 0.5),
    );
    film.split_streams(0.5);
    // Pixel 0: stream 0 has three samples of 1, stream 1 one of 5: the mean of the stream
    // means is 3, where the mean of the samples would be 2. Pixel 1: stream 1 only.
    let s0 = [(Vec2::new(0.2, 0.5), Vec3::splat(1.0)); 3];
    film.add_stream_samples(0, &s0);
    film.add_stream_samples(
        1,
        &[
            (Vec2::new(0.7, 0.5), Vec3::splat(5.0)),
            (Vec2::new(1.5, 0.5), Vec3::splat(4.0)),
        ],
    );
    assert_eq!(film.pixels(), vec![Vec3::splat(3.0), Vec3::splat(4.0)]);
    // The pixel statistics hold both streams.
    assert_eq!(film.pixel_stats()[0].count, 4);
}
