//! `--sampler-cost`: what the sampler adds to the render's wall time, measured by replaying
//! its recorded batches with a sampler doing no work, alternating with fresh renders.

use super::RenderArgs;
use crate::cli::replay::Replay;
use crate::cli::stats::median;
use crate::integrator::Integrator;
use crate::registry::{choose_for_scene, Overrides};
use crate::render::render;
use crate::scene::Scene;
use acr_parser::SceneDescription;
use acr_plugins::{Film, SamplePoint, Sampler};
use std::time::Instant;

/// What `--sampler-cost` measured: times of the render loop alone, medians over
/// [`SamplerCostRun::PAIRS`] runs each.
#[derive(Clone, Copy, Debug)]
pub(super) struct SamplerCost {
    /// The render again, by a fresh sampler of the same choice.
    pub(super) render: f64,
    /// The recorded batches replayed by a sampler doing no work.
    pub(super) replay: f64,
    /// The median over pairs of (render - replay) / render, each pair run back to back: the
    /// machine's drift cancels within a pair.
    pub(super) share: f64,
    /// Each pair's [render, replay], in the order run.
    pub(super) pairs: [[f64; 2]; SamplerCostRun::PAIRS],
}

/// What `--sampler-cost` needs to render the scene again, and the first render's film.
pub(super) struct SamplerCostRun<'a> {
    /// The scene as parsed, to choose its plugins again.
    pub(super) desc: &'a SceneDescription,
    /// The scene built.
    pub(super) scene: &'a Scene,
    /// The command line's choices of plugins.
    pub(super) overrides: &'a Overrides,
    /// The command line (its spp and seed).
    pub(super) args: &'a RenderArgs,
    /// The first render's film, which every image must equal.
    pub(super) film: &'a Film,
}

impl SamplerCostRun<'_> {
    /// Replays and fresh renders, alternating: single runs on this noisy a machine differ by
    /// tens of percent.
    const PAIRS: usize = 3;

    /// Times replays of `batches` and fresh renders alike, after the first render (which
    /// recorded them) warmed what any render warms: lazily built light distributions, the
    /// thread pool, the caches (against that first render, a replay ran 10% faster with the
    /// random sampler, which does next to nothing). Every sampler and film is kept to the end,
    /// so that each fresh sampler's memory comes fresh from the system, its page faults paid
    /// as in the first render. Every image is checked to be the first's.
    pub(super) fn measure(&self, batches: Vec<Vec<SamplePoint>>) -> Result<SamplerCost, String> {
        let mut scratch = Vec::new();
        let (mut renders, mut replays, mut kept) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..Self::PAIRS {
            let mut plugins = choose_for_scene(
                self.desc,
                self.scene,
                self.overrides,
                self.args.spp,
                self.args.seed,
                &mut scratch,
            )
            .map_err(|e| e.to_string())?;
            let mut replay =
                Replay::new(plugins.sampler.spp(), plugins.sampler.streams(), &batches);
            let mut films = [plugins.film(self.scene), plugins.film(self.scene)];
            let [replayed, rendered] = &mut films;
            let integrator = &plugins.integrator;
            replays.push(self.time(integrator, replayed, &mut replay, "the replayed batches")?);
            let sampler = plugins.sampler.as_mut();
            renders.push(self.time(integrator, rendered, sampler, "a second render")?);
            kept.push((plugins, films));
        }
        let mut shares: Vec<f64> = renders
            .iter()
            .zip(&replays)
            .map(|(r, p)| (r - p) / r.max(1e-9))
            .collect();
        let pairs = std::array::from_fn(|i| [renders[i], replays[i]]);
        Ok(SamplerCost {
            pairs,
            render: median(&mut renders),
            replay: median(&mut replays),
            share: median(&mut shares).max(0.0),
        })
    }

    /// The render loop's wall time with `sampler`, its image checked.
    fn time(
        &self,
        integrator: &Integrator,
        film: &mut Film,
        sampler: &mut dyn Sampler,
        what: &str,
    ) -> Result<f64, String> {
        let t = Instant::now();
        render(
            self.scene,
            integrator,
            sampler,
            film,
            self.args.seed,
            None,
            None,
        );
        let s = t.elapsed().as_secs_f64();
        if film.pixels() != self.film.pixels() {
            return Err(format!("--sampler-cost: {what} gave another image"));
        }
        Ok(s)
    }
}
