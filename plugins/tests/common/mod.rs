//! What the plugin tests share.

use acr_plugins::cells::CellGrid;
use acr_plugins::film::{Film, FilmSettings};
use acr_plugins::filters::SamplerOutput;
use acr_plugins::first_hit::Features;
use acr_plugins::space::{RenderingSpace, SamplePoint};
use acr_plugins::{Choice, Filter, Sampler, SamplerSetup, SAMPLERS};
use glam::{Vec2, Vec3};

/// The sampler `name` on `space` at `spp`, built through the registry as the command line's
/// `--spp` does. Not every test file uses it.
#[allow(dead_code)]
pub fn sampler(name: &str, space: RenderingSpace, spp: u32, seed: u64) -> Box<dyn Sampler> {
    sampler_with(Choice::new(None, name, None), space, spp, seed)
}

/// The sampler of `choice` (a name and parameters) on `space` at `spp`.
pub fn sampler_with(
    choice: Choice,
    space: RenderingSpace,
    spp: u32,
    seed: u64,
) -> Box<dyn Sampler> {
    try_sampler_with(choice, space, spp, seed).unwrap()
}

/// The sampler of `choice`, or the error its parameters give.
#[allow(dead_code)]
pub fn try_sampler_with(
    choice: Choice,
    space: RenderingSpace,
    spp: u32,
    seed: u64,
) -> acr_parser::Result<Box<dyn Sampler>> {
    let name = choice.name.clone();
    let e = SAMPLERS
        .iter()
        .find(|e| e.info.name == name)
        .unwrap_or_else(|| panic!("no sampler {name}"));
    let setup = SamplerSetup {
        space,
        spp: Some(spp),
        seed,
        reconstruction_reads_cells: true,
        stream: Default::default(),
    };
    (e.build)(&choice, &setup)
}

/// The image `f` makes over `space` from the samples of `s` on a field that gives each point
/// its radiance and first-hit features; the film collects cells (with the features) as the
/// renderer's does for the filter. Not every test file renders.
#[allow(dead_code)]
pub fn render_field(
    space: RenderingSpace,
    mut s: Box<dyn Sampler>,
    f: &dyn Filter,
    field: impl Fn(&SamplePoint) -> ([f32; 3], Features),
) -> Vec<Vec3> {
    let mut film = Film::new(
        FilmSettings::with_resolution(space.width(), space.height()),
        f.kernel(),
    );
    if let Some((cell_size, bins)) = f.cell_layout() {
        if !s.keeps_cells() || f.reads_features() {
            let grid = CellGrid::new(space, cell_size, bins);
            film.collect_cells(grid, f.reads_features());
        }
    }
    // A paired sampler's two streams are kept apart, as the render loop does.
    if s.streams() == 2 {
        film.split_streams(s.stream_weight());
    }
    let mut batch = Vec::new();
    while s.next_batch(&mut batch) {
        let (radiance, features): (Vec<[f32; 3]>, Vec<Features>) = batch.iter().map(&field).unzip();
        s.observe(&batch, &radiance);
        film.add_points(&batch, &radiance, Some(&features));
        for stream in 0..s.streams() {
            let samples: Vec<(Vec2, Vec3)> = batch
                .iter()
                .zip(&radiance)
                .filter(|(q, _)| q.index % s.streams() == stream)
                .map(|(q, l)| (Vec2::from(q.film), Vec3::from_array(*l)))
                .collect();
            film.add_stream_samples(stream as usize, &samples);
        }
    }
    film.per_stream(|half, _| {
        f.reconstruct(
            half,
            SamplerOutput {
                partition: s.partition(),
                cells: s.cells(),
            },
        )
    })
}

/// A noisy step moving in time, with a bright outlier now and then: what adaptive samplers
/// steer by. `extra` adds noise to the values of the samples `changed` picks.
#[allow(dead_code)]
pub fn noisy_step(q: &SamplePoint, extra: f32, changed: impl Fn(&SamplePoint) -> bool) -> [f32; 3] {
    let h = acr_plugins::rng::mix64(
        u64::from(q.film[0].to_bits()) ^ acr_plugins::rng::mix64(u64::from(q.time.to_bits())),
    );
    let u = (h >> 40) as f32 / (1u64 << 24) as f32;
    let base = if q.film[0] > 8.0 + 8.0 * q.time {
        1.0
    } else {
        0.1
    };
    let firefly = if u > 0.97 { 20.0 } else { 0.0 };
    let v = base + 0.2 * u + firefly;
    let w = (h & 0xffff) as f32 / 65536.0;
    [if changed(q) { v + extra * w } else { v }; 3]
}

/// The choice of plugin `name` with the parameters `params` (name and values, typed by the
/// values: bools, floats, else integers), as a scene would give them.
#[allow(dead_code)]
pub fn choice(name: &str, params: &[(&str, acr_parser::Values)]) -> Choice {
    use acr_parser::{Loc, Param, ParamType, SourceFile, Values};
    let mut c = Choice::new(None, name, None);
    let file = SourceFile::new("test", "");
    for (p, v) in params {
        let ty = match v {
            Values::Bools(_) => ParamType::Bool,
            Values::Floats(_) => ParamType::Float,
            _ => ParamType::Integer,
        };
        c.params
            .push(Param::new(ty, *p, v.clone(), Loc::new(&file, 0)));
    }
    c
}
