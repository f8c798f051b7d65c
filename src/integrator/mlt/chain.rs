//! mlt's render (pbrt-v3's `MLTIntegrator::Render`): the bootstrap, then the Markov chains,
//! run in rounds so that their splats reach the film in chain order whatever the thread count
//! (the image is the same for a seed), and so that a time limit or a signal stops them between
//! rounds (docs/light-transport.md, `## mlt`).

use super::bdpt_path::BdptContribution;
use super::contribution::{Contribution, PathContribution};
use super::sampler::MltSampler;
use super::MltSettings;
use crate::geometry::{is_valid_radiance, Spectrum, Vec2};
use crate::lightdistrib::LightStrategy;
use crate::render::{rendering_space, Halt, RenderCounts, Stop};
use crate::scene::Scene;
use crate::spectrum_luminance;
use crate::stream::{mix64, Pcg32};
use acr_plugins::{Film, RenderingSpace};
use rayon::prelude::*;
use std::time::Instant;

/// Mutations of all chains together per round: between rounds the time limit is looked at,
/// and a round's splats go to the film while the chains make the next round's (about a tenth
/// of a second's work on two cores for a simple scene; the two rounds' splat buffers, about
/// 10 bytes a mutation, bound mlt's memory).
const MUTATIONS_PER_ROUND: u64 = 1 << 17;

/// A splat: a raster position and the radiance added there.
type Splat = (Vec2, Spectrum);

/// One chain's round: what it counted, the mutations it made (its splats are in the chain).
type Round = (Tally, u64);

/// What the chains share: the path function, the scene and the settings.
struct Setup<'a, F> {
    f: &'a F,
    scene: &'a Scene,
    space: RenderingSpace,
    settings: &'a MltSettings,
    seed: u64,
}

impl<F: PathContribution> Setup<'_, F> {
    /// The path function at `sampler`'s point, radiance that is NaN, infinite or negative
    /// made zero and counted in `dropped`.
    fn eval(&self, sampler: &mut MltSampler, depth: u32, tally: &mut Tally) -> Contribution {
        let mut c = self.f.l(self.scene, &self.space, sampler, depth);
        tally.rays += u64::from(c.rays);
        if !is_valid_radiance(c.l) {
            tally.dropped += 1;
            c.l = Spectrum::ZERO;
        }
        c
    }

    /// The sampler of bootstrap path `index`.
    fn sampler(&self, index: u64) -> MltSampler {
        let s = self.settings;
        MltSampler::new(self.seed, index, s.sigma, s.large_step_probability)
    }
}

/// Rays and dropped samples counted on the way.
#[derive(Clone, Copy, Debug, Default)]
struct Tally {
    rays: u64,
    dropped: u64,
}

impl Tally {
    fn add(&mut self, o: Tally) {
        self.rays += o.rays;
        self.dropped += o.dropped;
    }
}

/// The bootstrap: `bootstrapsamples` independent paths of every depth, their luminances
/// (the weights the chains start from, indexed `i * (maxdepth + 1) + depth`). Written in
/// place, chunk by chunk, and the tallies summed: a vector of (weight, tally) pairs would be
/// six times the weights' memory, most of mlt's peak.
fn bootstrap<F: PathContribution>(setup: &Setup<F>, tally: &mut Tally) -> Vec<f32> {
    let depths = setup.f.max_depth() + 1;
    let n = setup.settings.bootstrap_samples as usize * depths as usize;
    let mut weights = vec![0.0f32; n];
    const CHUNK: usize = 64;
    let counted = weights
        .par_chunks_mut(CHUNK)
        .enumerate()
        .map_init(
            || setup.sampler(0),
            |sampler, (c, chunk)| {
                let mut t = Tally::default();
                for (k, w) in chunk.iter_mut().enumerate() {
                    let index = (c * CHUNK + k) as u64;
                    let depth = (index % u64::from(depths)) as u32;
                    sampler.reset(setup.seed, index);
                    *w = spectrum_luminance(setup.eval(sampler, depth, &mut t).l);
                }
                t
            },
        )
        .reduce(Tally::default, |mut a, b| {
            a.add(b);
            a
        });
    tally.add(counted);
    weights
}

/// The running sums of the bootstrap weights, for choosing chains' first states.
struct Bootstrap {
    cumulative: Vec<f64>,
}

impl Bootstrap {
    fn new(weights: &[f32]) -> Self {
        let mut sum = 0.0f64;
        let cumulative = weights
            .iter()
            .map(|&w| {
                sum += f64::from(w);
                sum
            })
            .collect();
        Self { cumulative }
    }

    /// The weights' sum.
    fn total(&self) -> f64 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// The index of a weight chosen in proportion to it by `u` in [0, 1) (one above 0, when
    /// the total is).
    fn sample(&self, u: f32) -> usize {
        let target = f64::from(u) * self.total();
        let i = self.cumulative.partition_point(|&c| c <= target);
        i.min(self.cumulative.len().saturating_sub(1))
    }
}

/// One Markov chain: its state and what it has left to do. Aligned to 128 bytes (two cache
/// lines, what the prefetcher pairs) so that chains run on different threads share none.
#[repr(align(128))]
struct Chain {
    sampler: MltSampler,
    /// Decides acceptance (and chose the first state).
    rng: Pcg32,
    /// The path length it samples.
    depth: u32,
    /// The current state's contribution and its luminance.
    current: Contribution,
    current_y: f32,
    /// Mutations left.
    left: u64,
    /// The splats of the round under way (kept from round to round: no allocation per round).
    splats: Vec<Splat>,
}

impl Chain {
    /// Chain `i` of `setup`, making `mutations` mutations, started from a bootstrap path chosen
    /// in proportion to its weight.
    fn start<F: PathContribution>(
        setup: &Setup<F>,
        boot: &Bootstrap,
        i: u64,
        mutations: u64,
        tally: &mut Tally,
    ) -> Self {
        let key = mix64(setup.seed ^ 0x6368_6169_6e5f_726e);
        let mut rng = Pcg32::new(mix64(key ^ mix64(i)), mix64(key).wrapping_add(i));
        let index = boot.sample(rng.next_f32()) as u64;
        let depth = (index % u64::from(setup.f.max_depth() + 1)) as u32;
        let mut sampler = setup.sampler(index);
        let current = setup.eval(&mut sampler, depth, tally);
        Self {
            sampler,
            rng,
            depth,
            current,
            current_y: spectrum_luminance(current.l),
            left: mutations,
            splats: Vec::new(),
        }
    }

    /// Makes up to `n` mutations, pushing their splats to `self.splats` (pbrt-v3's: the
    /// proposal weighted by the acceptance, the current state by its complement, each over its
    /// luminance). The current state's weights are summed while it stays and splatted once
    /// when it changes or the round ends: the same sum as pbrt-v3's splat per mutation, in
    /// fewer splats.
    fn run<F: PathContribution>(&mut self, setup: &Setup<F>, n: u64, tally: &mut Tally) -> u64 {
        let splats = &mut self.splats;
        let n = n.min(self.left);
        // The current state's summed weight not yet splatted.
        let mut held = 0.0f32;
        for _ in 0..n {
            self.sampler.start_iteration();
            let proposed = setup.eval(&mut self.sampler, self.depth, tally);
            let proposed_y = spectrum_luminance(proposed.l);
            let accept = if self.current_y > 0.0 {
                (proposed_y / self.current_y).min(1.0)
            } else {
                1.0
            };
            if accept > 0.0 && proposed_y > 0.0 {
                splats.push((proposed.raster, proposed.l * (accept / proposed_y)));
            }
            if accept < 1.0 && self.current_y > 0.0 {
                held += (1.0 - accept) / self.current_y;
            }
            if self.rng.next_f32() < accept {
                if held > 0.0 {
                    splats.push((self.current.raster, self.current.l * held));
                    held = 0.0;
                }
                self.current = proposed;
                self.current_y = proposed_y;
                self.sampler.accept();
            } else {
                self.sampler.reject();
            }
        }
        if held > 0.0 {
            splats.push((self.current.raster, self.current.l * held));
        }
        self.left -= n;
        n
    }
}

/// Renders `scene` with mlt into `film`'s unfiltered splats: the bootstrap (always whole),
/// then the chains' mutations until done or until `stop` says (between rounds); the splats'
/// scale is `b` over the mutations per pixel actually made.
pub fn render(
    scene: &Scene,
    settings: &MltSettings,
    film: &mut Film,
    seed: u64,
    stop: &Stop,
    progress: Option<&indicatif::ProgressBar>,
) -> RenderCounts {
    let f = BdptContribution {
        max_depth: settings.max_depth,
        // pbrt-v3's mlt chooses every light by power (its `lightDistr`), s = 1 included.
        light_strategy: LightStrategy::Power,
        differential_scale: 1.0 / (settings.mutations_per_pixel.max(1) as f32).sqrt(),
    };
    render_with(&f, scene, settings, film, seed, stop, progress)
}

/// [`render`] with any path function.
pub fn render_with<F: PathContribution>(
    f: &F,
    scene: &Scene,
    settings: &MltSettings,
    film: &mut Film,
    seed: u64,
    stop: &Stop,
    progress: Option<&indicatif::ProgressBar>,
) -> RenderCounts {
    let start = Instant::now();
    let space = rendering_space(scene);
    let setup = Setup {
        f,
        scene,
        space,
        settings,
        seed,
    };
    let mut counts = RenderCounts::default();
    let mut tally = Tally::default();
    let weights = if scene.lights.is_empty() {
        Vec::new()
    } else {
        bootstrap(&setup, &mut tally)
    };
    let boot = Bootstrap::new(&weights);
    // pbrt-v3's b: the mean bootstrap weight times the number of depths.
    let b = if weights.is_empty() {
        0.0
    } else {
        boot.total() / weights.len() as f64 * f64::from(f.max_depth() + 1)
    };
    drop(weights);
    let area = space.pixels();
    let total = u64::from(settings.mutations_per_pixel) * area;
    let n_chains = u64::from(settings.chains);
    if let Some(p) = progress {
        p.set_length(total);
    }
    let mut chains: Vec<Chain> = Vec::new();
    if b > 0.0 {
        // pbrt-v3's split of the mutations over the chains.
        let share = |i: u64| (u128::from(i) * u128::from(total) / u128::from(n_chains)) as u64;
        let started: Vec<(Chain, Tally)> = (0..n_chains)
            .into_par_iter()
            .map(|i| {
                let mut t = Tally::default();
                let c = Chain::start(&setup, &boot, i, share(i + 1) - share(i), &mut t);
                (c, t)
            })
            .collect();
        for (c, t) in started {
            tally.add(t);
            chains.push(c);
        }
    }
    let per_round = (MUTATIONS_PER_ROUND / n_chains).max(1);
    let mut made = 0u64;
    // The last round's splats, per chain: they go to the film (in chain order, one thread)
    // while the chains make the next round's, instead of the threads waiting on the merge.
    let mut pending: Vec<Vec<Splat>> = chains.iter().map(|_| Vec::new()).collect();
    let mut last_look = vec![Instant::now(); stop.checkpoints.len()];
    while chains.iter().any(|c| c.left > 0) {
        let (rounds, ()) = rayon::join(
            || {
                chains
                    .par_iter_mut()
                    .map(|c| {
                        let mut t = Tally::default();
                        let n = c.run(&setup, per_round, &mut t);
                        (t, n)
                    })
                    .collect::<Vec<Round>>()
            },
            || merge(film, &mut pending),
        );
        let on_film = made;
        for ((c, p), (t, n)) in chains.iter_mut().zip(&mut pending).zip(rounds) {
            std::mem::swap(&mut c.splats, p);
            tally.add(t);
            made += n;
        }
        // The film holds the rounds before this one.
        film.unfiltered_mut().set_scale(scale(b, area, on_film));
        if let Some(p) = progress {
            p.set_position(made);
        }
        for (c, last) in stop.checkpoints.iter().zip(&mut last_look) {
            if last.elapsed() >= c.every {
                (c.look)(film, start.elapsed().as_secs_f64());
                *last = Instant::now();
            }
        }
        if let Some(why) = halt(stop, start) {
            counts.halted = made < total;
            counts.halted_by = counts.halted.then_some(why);
            break;
        }
    }
    merge(film, &mut pending);
    film.unfiltered_mut().set_scale(scale(b, area, made));
    counts.samples = made;
    counts.rays = tally.rays;
    counts.dropped = tally.dropped;
    counts
}

/// Adds `pending`'s splats to `film`, chain by chain, and empties them.
fn merge(film: &mut Film, pending: &mut [Vec<Splat>]) {
    for p in pending {
        film.add_splats(p);
        p.clear();
    }
}

/// The splats' scale: `b` over the mutations per pixel made (pbrt-v3's `b /
/// mutationsPerPixel` when all were).
fn scale(b: f64, pixels: u64, made: u64) -> f64 {
    if made == 0 {
        0.0
    } else {
        b * pixels as f64 / made as f64
    }
}

/// Why `stop` ends the render now, if it does: a signal or the time limit.
fn halt(stop: &Stop, start: Instant) -> Option<Halt> {
    if stop
        .interrupt
        .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed))
    {
        Some(Halt::Signal)
    } else if stop.time_limit.is_some_and(|t| start.elapsed() >= t) {
        Some(Halt::Time)
    } else {
        None
    }
}
