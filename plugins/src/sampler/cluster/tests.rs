//! The cluster sampler's tests.

use super::super::tests::{space, ALL_DIMS};
use super::*;
use crate::cells::clusters::UNASSIGNED;
use crate::registry::Choice;
use crate::sampler::SamplerSetup;

/// Runs `s` to the end on radiance `f`, halting after `halt_after` batches if given.
fn run(
    s: &mut dyn Sampler,
    f: impl Fn(&SamplePoint) -> [f32; 3],
    halt_after: Option<usize>,
) -> Vec<SamplePoint> {
    super::super::drive(s, |b| b.iter().map(&f).collect(), halt_after)
}

#[test]
fn planning_ahead_observes_every_round_before_the_partition_is_made() {
    let settings = ClusterSettings::new(8);
    let mut s = ClusterSampler::new(space(0, 0, 128, 96, ALL_DIMS[1]), settings, 3);
    let all = run(&mut s, field, None);
    assert_eq!(all.len(), 128 * 96 * 8);
    assert!(s.state.in_flight.is_empty(), "a round was never observed");
    assert!(s.state.rounds > 2, "{} rounds", s.state.rounds);
    // The partition given is the one of the final clusters, made after the last round.
    assert_eq!(s.partition(), s.state.make_partition(&s.space).as_ref());
}

/// Asks the cluster sampler for batches as the render loop does, watching the first stage.
struct WatchFirstStage<'a> {
    s: &'a mut ClusterSampler,
    /// Batches of the first stage given while one was still unobserved.
    given_ahead: usize,
    /// Samples in the cells when the first clustering was made.
    at_clustering: Option<u64>,
}

impl Sampler for WatchFirstStage<'_> {
    fn name(&self) -> &'static str {
        "watch"
    }

    fn spp(&self) -> u32 {
        self.s.spp()
    }

    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool {
        let in_first_stage = self.s.state.phase == Phase::Init;
        let more = self.s.next_batch(out);
        if in_first_stage && self.s.state.clustering.is_some() && self.at_clustering.is_none() {
            let counts = &self.s.state.sums.count;
            self.at_clustering = Some(counts.iter().map(|&n| u64::from(n)).sum());
        } else if in_first_stage && self.s.state.phase == Phase::Init && self.s.plans_ahead() {
            self.given_ahead += 1;
        }
        more
    }

    fn observe(&mut self, batch: &[SamplePoint], radiance: &[[f32; 3]]) {
        self.s.observe(batch, radiance);
    }

    fn halt(&mut self) {
        self.s.halt();
    }

    fn plans_ahead(&self) -> bool {
        self.s.plans_ahead()
    }
}

#[test]
fn the_first_stage_is_planned_ahead_and_clustered_once_every_batch_is_observed() {
    // 256x192 pixels at 2 spp in the first stage: four batches, two per pass. The first
    // three are given before the one before them is observed; the call after the last
    // clusters, so it must come after the last is observed.
    let (w, h) = (256, 192);
    let mut s = ClusterSampler::new(space(0, 0, w, h, ALL_DIMS[2]), ClusterSettings::new(8), 5);
    let first_stage = u64::from(w * h * s.settings().init_spp);
    let mut watch = WatchFirstStage {
        s: &mut s,
        given_ahead: 0,
        at_clustering: None,
    };
    let all = run(&mut watch, field, None);
    assert_eq!(all.len() as u64, u64::from(w * h * 8));
    assert_eq!(watch.given_ahead, 3);
    assert_eq!(watch.at_clustering, Some(first_stage));
}

fn field(q: &SamplePoint) -> [f32; 3] {
    let v = if q.film[0] + 8.0 * q.time > 12.0 {
        1.0
    } else {
        0.2
    };
    [v, v * 0.5, v * 0.25]
}

/// Checks that each live cluster has one current queue entry and that it agrees with the
/// cluster; returns the entries checked.
fn check_queue(s: &ClusterSampler) -> usize {
    let Some(clustering) = s.clustering() else {
        return 0;
    };
    let mut seen = vec![0u32; clustering.clusters.len()];
    let mut checked = 0;
    for e in s.state.queue.iter() {
        if s.state.version[e.id as usize] != e.version {
            continue;
        }
        seen[e.id as usize] += 1;
        let c = &clustering.clusters[e.id as usize];
        let (p, now) = s
            .state
            .entry(s.settings.priority, e.id)
            .expect("a current entry's cluster lives");
        assert_eq!(e.cells as usize, c.cells.len());
        assert_eq!(e.samples, c.samples, "cluster {}", e.id);
        assert_eq!(e.weight.to_bits(), now.weight.to_bits());
        assert_eq!(
            state::priority(s.settings.priority, e).to_bits(),
            p.to_bits()
        );
        checked += 1;
    }
    for (id, c) in clustering.clusters.iter().enumerate() {
        assert_eq!(seen[id], u32::from(!c.cells.is_empty()), "cluster {id}");
    }
    checked
}

#[test]
fn each_live_cluster_has_one_current_queue_entry_that_agrees_with_it() {
    // The planning reads the entries, not the clusters: an entry whose cells, samples or
    // weight fell behind its cluster would choose wrongly without a sign. Checked after
    // each plan (the chosen clusters' entries went back with their planned samples) and
    // after each update (the changed clusters' entries were made again).
    for priority in [Priority::PerSample, Priority::Paper] {
        let set = ClusterSettings {
            priority,
            ..ClusterSettings::new(12)
        };
        let sp = space(0, 0, 48, 32, ALL_DIMS[1]);
        let mut s = ClusterSampler::new(sp, set, 9);
        let mut b = Vec::new();
        let mut checked = 0;
        while s.next_batch(&mut b) {
            checked += check_queue(&s);
            let r: Vec<[f32; 3]> = b.iter().map(field).collect();
            s.observe(&b, &r);
            checked += check_queue(&s);
        }
        assert!(checked > 1000, "{checked}");
    }
}

#[test]
fn an_unbiased_halfs_queue_entries_agree_with_its_clusters_after_each_round() {
    // A half of an unbiased pair queues its round's clusters again from the entries it
    // picked (`requeue_picked`), not from the clusters: those must stay what `entry` makes.
    let sp = space(0, 0, 48, 32, ALL_DIMS[1]);
    let half = |colour| ClusterSampler::new(sp, ClusterSettings::new(12), 9).for_colour(colour);
    let mut pair = crossed::Crossed::new([half(0), half(1)]);
    let mut b = Vec::new();
    let mut checked = 0;
    while pair.next_batch(&mut b) {
        let r: Vec<[f32; 3]> = b.iter().map(field).collect();
        pair.observe(&b, &r);
        checked += pair.halves().iter().map(check_queue).sum::<usize>();
    }
    assert!(checked > 1000, "{checked}");
}

#[test]
fn every_dims_spends_the_budget_and_stays_in_range() {
    for dims in ALL_DIMS {
        let sp = space(3, 2, 20, 12, dims);
        for bins in [1, 2] {
            let set = ClusterSettings {
                bins,
                ..ClusterSettings::new(6)
            };
            let mut s = ClusterSampler::new(sp, set, 4);
            let pts = run(&mut s, field, None);
            assert_eq!(pts.len(), 20 * 12 * 6, "{dims:?}");
            for q in &pts {
                assert!(q.pixel[0] >= 3 && q.pixel[0] < 23 && q.pixel[1] >= 2 && q.pixel[1] < 14);
                if dims.time {
                    assert!((0.0..1.0).contains(&q.time));
                } else {
                    assert_eq!(q.time, 0.5);
                }
                if dims.lens {
                    assert!(q.lens.iter().all(|l| (0.0..1.0).contains(l)));
                } else {
                    assert_eq!(q.lens, [0.5; 2]);
                }
            }
            let p = s.partition().expect("a partition at the end");
            assert_eq!((p.width, p.height), (20, 12));
            assert_eq!(p.cluster.len(), 240);
            // Every cell in exactly one cluster.
            let c = s.clustering().expect("clustered");
            let total: usize = c.clusters.iter().map(|k| k.cells.len()).sum();
            assert_eq!(total, s.grid().len());
            assert!(c.of_cell.iter().all(|&k| k != UNASSIGNED));
        }
    }
}

#[test]
fn knobs_change_the_grid_and_the_first_stage() {
    let sp = space(0, 0, 16, 8, ALL_DIMS[1]);
    let mut set = ClusterSettings::new(8);
    set.cell_size = 0.5;
    set.bins = 3;
    set.init_spp = 3;
    set.min_spp = 5;
    let mut s = ClusterSampler::new(sp, set, 1);
    // minspp raises the first stage: every pixel gets 5 before any adapts.
    assert_eq!(s.settings().init_spp, 5);
    assert_eq!(s.grid().shape(), [32, 16, 3]);
    let pts = run(&mut s, field, None);
    let mut count = vec![0; 128];
    for q in &pts {
        count[(q.pixel[1] * 16 + q.pixel[0]) as usize] += 1;
    }
    assert!(count.iter().all(|&c| c >= 5));
    assert_eq!(pts.len(), 128 * 8);
}

#[test]
fn halting_in_the_first_stage_finishes_its_pass_and_stops() {
    let sp = space(0, 0, 300, 200, ALL_DIMS[0]);
    let mut s = ClusterSampler::new(sp, ClusterSettings::new(16), 2);
    let pts = run(&mut s, field, Some(1));
    // The first stage's first pass (4 spp over 60,000 pixels spans several batches).
    let mut count = vec![0u32; 60_000];
    for q in &pts {
        count[(q.pixel[1] * 300 + q.pixel[0]) as usize] += 1;
    }
    let first = count[0];
    assert!(first >= 1 && count.iter().all(|&c| c == first));
    assert!(s.partition().is_some(), "clusters still made for the AOV");
    // Halted in the adaptive stage: stops at once.
    let sp = space(0, 0, 40, 30, ALL_DIMS[1]);
    let mut s = ClusterSampler::new(sp, ClusterSettings::new(16), 2);
    let mut b = Vec::new();
    while s.state.phase != Phase::Adaptive || s.state.rounds == 0 {
        assert!(s.next_batch(&mut b));
        let r: Vec<[f32; 3]> = b.iter().map(field).collect();
        s.observe(&b, &r);
    }
    s.halt();
    assert!(!s.next_batch(&mut b));
    assert!(s.partition().is_some());
}

#[test]
fn dropped_samples_count_against_the_budget_and_poison_nothing() {
    let sp = space(0, 0, 24, 16, ALL_DIMS[3]);
    let mut s = ClusterSampler::new(sp, ClusterSettings::new(8), 3);
    // Half the samples are NaN (dropped by the render loop).
    let pts = run(
        &mut s,
        |q| {
            if q.index % 2 == 0 {
                [f32::NAN; 3]
            } else {
                field(q)
            }
        },
        None,
    );
    assert_eq!(pts.len(), 24 * 16 * 8);
    let sums = s.sums();
    let kept: u64 = sums.count.iter().map(|&c| u64::from(c)).sum();
    assert!(kept > 0 && kept < pts.len() as u64);
    assert!(sums.lum.iter().all(|v| v.is_finite()));
    assert!(s.state.squashed.iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn memory_per_cell_keeps_1024_squared_5d_within_2_gib() {
    // Measured on a small grid after a full run, then scaled to 1024 x 1024 x 8 cells.
    let sp = space(0, 0, 64, 64, ALL_DIMS[3]);
    let set = ClusterSettings {
        bins: 2,
        ..ClusterSettings::new(16)
    };
    let mut s = ClusterSampler::new(sp, set, 3);
    run(&mut s, field, None);
    let per_cell = s.bytes() as f64 / s.grid().len() as f64;
    let at_1024 = per_cell * (1024.0 * 1024.0 * 8.0);
    eprintln!(
        "cluster sampler: {per_cell:.1} bytes per cell, {:.0} MiB at 1024^2 5D",
        at_1024 / 1048576.0
    );
    assert!(
        at_1024 < 1.5 * 1024.0 * 1024.0 * 1024.0,
        "{per_cell} bytes per cell"
    );
}

#[test]
fn bad_knobs_are_located_errors() {
    use crate::registry::Setting;
    let setup = SamplerSetup {
        space: space(0, 0, 8, 8, ALL_DIMS[0]),
        spp: None,
        seed: 1,
        reconstruction_reads_cells: true,
        stream: Default::default(),
    };
    for (arg, want) in [
        ("sampler.omega=0", "omega 0 is out of range"),
        ("sampler.bins=0", "bins 0 is out of range"),
        ("sampler.initspp=99", "initspp 99 is out of range"),
        ("sampler.cellsize=100", "cellsize 100 is out of range"),
        ("sampler.priority=most", "priority \"most\" is not known"),
        ("sampler.guide=most", "guide \"most\" is not known"),
    ] {
        let mut c = Choice::new(None, "cluster", None);
        Setting::parse(arg)
            .expect(arg)
            .apply(&ENTRY.info, &mut c)
            .expect(arg);
        let e = build(&c, &setup).err().expect(arg).to_string();
        assert!(e.contains("--set:1:") && e.contains(want), "{e}");
    }
}

/// Left of x = 32 a flat 0.2; right of it noise in [0, 1), a value per point.
fn half_noisy(q: &SamplePoint) -> [f32; 3] {
    if q.film[0] < 32.0 {
        return [0.2; 3];
    }
    let key = u64::from(q.pixel[0]) << 40 ^ u64::from(q.pixel[1]) << 20 ^ u64::from(q.index);
    let v = (super::super::mix64(key) >> 40) as f32 / (1u64 << 24) as f32;
    [v; 3]
}

#[test]
fn a_noise_threshold_shrinks_the_first_stage_and_settled_clusters_get_no_more() {
    let (w, h) = (64, 48);
    let per_pixel = |all: &[SamplePoint]| {
        let mut n = vec![0u32; (w * h) as usize];
        for q in all {
            n[(q.pixel[1] * w + q.pixel[0]) as usize] += 1;
        }
        n
    };
    let quarter_mean = |n: &[u32], x0: u32| {
        let cols = x0..x0 + w / 4;
        let total: u32 = (0..h)
            .flat_map(|y| cols.clone().map(move |x| (y * w + x) as usize))
            .map(|i| n[i])
            .sum();
        f64::from(total) / f64::from(w / 4 * h)
    };
    for settle in [false, true] {
        let mut settings = ClusterSettings::new(16);
        settings.settle = settle;
        let mut s = ClusterSampler::new(space(0, 0, w, h, ALL_DIMS[0]), settings, 7);
        assert!(s.stop_at_noise(0.05, 2));
        // The first stage is the two samples every pixel must have, not a quarter of 16.
        assert_eq!(s.settings().init_spp, 2);
        let all = run(&mut s, half_noisy, None);
        let n = per_pixel(&all);
        assert!(n.iter().all(|&k| k >= 2));
        let (flat, noisy) = (quarter_mean(&n, 0), quarter_mean(&n, 3 * w / 4));
        if settle {
            // The flat side settles at once; the noisy side (relative error about 0.14 at 16
            // samples) never does, and takes what is left until the budget runs out there.
            assert!(flat < 2.2, "{flat} samples a flat pixel");
            assert!(noisy > 20.0, "{noisy} samples a noisy pixel");
        } else {
            // Without settling the budget is spent, more of it where the noise is.
            assert_eq!(all.len() as u32, w * h * 16);
            assert!(noisy > flat, "{noisy} against {flat}");
        }
    }
    // A first stage given explicitly is kept.
    let mut settings = ClusterSettings::new(16);
    settings.init_given = true;
    let mut s = ClusterSampler::new(space(0, 0, w, h, ALL_DIMS[0]), settings, 7);
    s.stop_at_noise(0.05, 2);
    assert_eq!(s.settings().init_spp, 4);
}

#[test]
fn guided_rounds_follow_the_error_map_in_pairs_read_once_after_the_first_stage() {
    use crate::registry::Setting;
    use crate::sampler::ErrorMap;
    let (w, h) = (64, 48);
    let setup = SamplerSetup {
        space: space(0, 0, w, h, ALL_DIMS[1]),
        spp: Some(12),
        seed: 3,
        reconstruction_reads_cells: false,
        stream: Default::default(),
    };
    let mut c = Choice::new(None, "cluster", None);
    Setting::parse("sampler.guide=reconstruction")
        .expect("guide")
        .apply(&ENTRY.info, &mut c)
        .expect("guide");
    // The unbiased pair, by default.
    let mut s = build(&c, &setup).expect("guided");
    // Large error right of x = 32, small left of it.
    let map = ErrorMap {
        x0: 0,
        y0: 0,
        width: w,
        height: h,
        error: (0..w * h)
            .map(|i| if i % w >= 32 { 1.0 } else { 0.01 })
            .collect(),
    };
    // The render loop's order without planning ahead: each batch observed, then guidance
    // when asked, then the next batch.
    let (mut all, mut batch) = (Vec::new(), Vec::new());
    let mut asked_at = Vec::new();
    while s.next_batch(&mut batch) {
        let r: Vec<[f32; 3]> = batch.iter().map(half_noisy).collect();
        s.observe(&batch, &r);
        all.extend_from_slice(&batch);
        if s.wants_guidance() {
            asked_at.push(all.len());
            s.guide(&map);
            assert!(!s.wants_guidance(), "asks again once answered");
        }
    }
    // Asked once, when the first stage (12 / 4 = 3 samples per pixel, made even: 4) was all
    // given.
    assert_eq!(asked_at, [(w * h * 4) as usize]);
    assert_eq!(all.len() as u32, w * h * 12);
    let sorted = crate::sampler::tests::by_pixel(&setup.space, &[all]);
    let mut n = vec![0u32; (w * h) as usize];
    for q in &sorted {
        let k = (q.pixel[1] * w + q.pixel[0]) as usize;
        // Each pixel's indices 0, 1, 2, ... once each.
        assert_eq!(q.index, n[k]);
        n[k] += 1;
    }
    // Pairs: both index parities of every pixel equally many.
    assert!(n.iter().all(|&k| k >= 4 && k % 2 == 0), "{n:?}");
    let n = &n;
    let mean = |cols: std::ops::Range<u32>| {
        let total: u32 = (0..h)
            .flat_map(|y| cols.clone().map(move |x| n[(y * w + x) as usize]))
            .sum();
        f64::from(total) / f64::from(cols.len() as u32 * h)
    };
    let (low, high) = (mean(0..30), mean(34..64));
    assert!(high > 2.0 * low, "{high} against {low}");
}

#[test]
fn guided_first_stage_gives_each_half_two_samples_before_the_estimate_is_read() {
    use crate::registry::Setting;
    let guided = |spp: u32, extra: Option<&str>| {
        let setup = SamplerSetup {
            space: space(0, 0, 16, 16, ALL_DIMS[1]),
            spp: Some(spp),
            seed: 3,
            reconstruction_reads_cells: false,
            stream: Default::default(),
        };
        let mut c = Choice::new(None, "cluster", None);
        for text in std::iter::once("sampler.guide=reconstruction").chain(extra) {
            let set = Setting::parse(text).expect("setting");
            set.apply(&ENTRY.info, &mut c).expect("setting");
        }
        let mut s = build(&c, &setup).expect("guided");
        // The first stage is what is given before the sampler first asks for the map.
        let (mut given, mut batch) = (0usize, Vec::new());
        while s.next_batch(&mut batch) {
            let r: Vec<[f32; 3]> = batch.iter().map(half_noisy).collect();
            s.observe(&batch, &r);
            given += batch.len();
            if s.wants_guidance() {
                return given / 256;
            }
        }
        panic!("never asked for the map");
    };
    // A quarter of 8 would be one sample per half.
    assert_eq!(guided(8, None), 4);
    assert_eq!(guided(16, None), 4);
    assert_eq!(guided(32, None), 8);
    // Below 8 the quarter (at least 2) stays, leaving half the budget or more for rounds.
    assert_eq!(guided(4, None), 2);
    assert_eq!(guided(6, None), 2);
    // A first stage given explicitly is kept (made even).
    assert_eq!(guided(8, Some("sampler.initspp=2")), 2);
}
