//! The registry of every plugin by kind and name (samplers and filters from acr-plugins,
//! integrators from here), and the choice of the three plugins of a render: the scene's
//! directives, overridden by the command line.

use crate::geometry::Spectrum;
use crate::integrator::{Integrator, IntegratorBuild, INTEGRATORS};
use acr_parser::{Error, Result, SceneDescription, Warning};
use acr_plugins::cells::CellGrid;
use acr_plugins::filters::{FilterBuild, SamplerOutput};
use acr_plugins::registry::{check_params, lookup};
use acr_plugins::sampler::SamplerBuild;
use acr_plugins::Film;
use acr_plugins::{Choice, Entry, Filter, Kind, PluginInfo, Sampler, SamplerSetup, Setting};
use acr_plugins::{FILTERS, SAMPLERS};

/// Every plugin by kind.
pub fn all() -> impl Iterator<Item = &'static PluginInfo> {
    let s = SAMPLERS.iter().map(|e| &e.info);
    let f = FILTERS.iter().map(|e| &e.info);
    let i = INTEGRATORS.iter().map(|e| &e.info);
    s.chain(f).chain(i)
}

/// The command line's plugin choices (`--sampler`, `--filter`, `--integrator`, `--set`).
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// `--sampler NAME`.
    pub sampler: Option<String>,
    /// `--filter NAME`.
    pub filter: Option<String>,
    /// `--integrator NAME`.
    pub integrator: Option<String>,
    /// `--set KIND.PARAM=VALUE`, in order (a later one wins).
    pub settings: Vec<Setting>,
}

/// The plugins of one render.
pub struct Plugins {
    /// Where the samples go.
    pub sampler: Box<dyn Sampler>,
    /// How the image is reconstructed.
    pub filter: Box<dyn Filter>,
    /// What each sample estimates.
    pub integrator: Integrator,
}

impl Plugins {
    /// The name of what makes the image: the sampler's, when it reconstructs itself (mdas,
    /// gem, awr), else the filter's.
    pub fn reconstruction(&self) -> &'static str {
        if self.sampler.reconstructs() {
            self.sampler.name()
        } else {
            self.filter.name()
        }
    }

    /// An empty film for `scene`, splatting with the filter's kernel, and collecting the cells
    /// the filter needs when the sampler keeps none.
    pub fn film(&self, scene: &crate::scene::Scene) -> Film {
        self.film_by_rows(scene, None)
    }

    /// [`Plugins::film`]; with `by_rows`, for a render by bands ([`crate::render::Bands`]):
    /// the half buffers hold the rows under way, `by_rows` the room for them and whether the
    /// rows released keep their statistics ([`Film::keep_pixel_buffers_by_rows`]).
    pub fn film_by_rows(
        &self,
        scene: &crate::scene::Scene,
        by_rows: Option<(usize, bool)>,
    ) -> Film {
        let mut film = Film::new(scene.film.clone(), self.filter.kernel());
        if self.filter.reads_pixel_buffers() {
            match by_rows {
                Some((window, keep_stats)) => film.keep_pixel_buffers_by_rows(keep_stats, window),
                None => film.keep_pixel_buffers(),
            }
            film.set_depth_scale(crate::render::bands::depth_scale(scene));
        }
        if let Some((cell_size, bins)) = self.filter.cell_layout() {
            let features = self.filter.reads_features();
            if !self.sampler.keeps_cells() || features {
                let space = crate::render::rendering_space(scene);
                film.collect_cells(CellGrid::new(space, cell_size, bins), features);
            }
        }
        film
    }

    /// The image from `film`: the filter's reconstruction, with the sampler's partition when it
    /// has one, plus the film's unfiltered splats, times the film's `scale`; row-major over the
    /// cropped film.
    pub fn image(&self, film: &Film) -> Vec<Spectrum> {
        let filtered = |film: &Film| {
            self.filter.reconstruct(
                film,
                SamplerOutput {
                    partition: self.sampler.partition(),
                    cells: self.sampler.cells(),
                },
            )
        };
        // Two streams: each reconstructed alone, the image their mean; a filter that reads the
        // half buffers has both streams there. Unfiltered splats are added after.
        let reconstructed = self.sampler.reconstruct(film).unwrap_or_else(|| {
            if self.filter.reads_pixel_buffers() {
                filtered(film)
            } else {
                film.per_stream(|f, _| filtered(f))
            }
        });
        self.finish_image(film, reconstructed)
    }

    /// `reconstructed` (of `film`, row-major over the cropped film) with the film's unfiltered
    /// splats added, times its `scale`: the image.
    pub fn finish_image(&self, film: &Film, reconstructed: Vec<Spectrum>) -> Vec<Spectrum> {
        let scale = film.settings().scale;
        film.with_splats(reconstructed)
            .into_iter()
            .map(|c| c * scale)
            .collect()
    }
}

/// Looks the choice up, applies the `--set`s of its kind and checks its parameters.
fn resolve<'a, B>(
    entries: &'a [Entry<B>],
    kind: Kind,
    choice: &mut Choice,
    overrides: &Overrides,
    warnings: &mut Vec<Warning>,
) -> Result<&'a Entry<B>> {
    let entry = lookup(entries, kind, &choice.name, choice.loc.as_ref(), warnings)?;
    for s in overrides.settings.iter().filter(|s| s.kind == kind) {
        s.apply(&entry.info, choice)?;
    }
    check_params(&entry.info, choice, warnings)?;
    Ok(entry)
}

/// pbrt-v3's warning for a scene with media rendered by an integrator that ignores them.
fn media_warning(desc: &SceneDescription, integrator: &Integrator, warnings: &mut Vec<Warning>) {
    if desc.media.is_empty()
        || matches!(
            integrator,
            Integrator::VolPath(_) | Integrator::Bdpt(_) | Integrator::Mlt(_)
        )
    {
        return;
    }
    let message = format!(
        "the scene has participating media but the \"{}\" integrator ignores them (as \
         pbrt-v3's does); use \"volpath\"",
        integrator.name()
    );
    let loc = desc
        .integrator
        .as_ref()
        .map_or(&desc.media[0].plugin.loc, |i| &i.loc);
    warnings.push(Warning::at(loc, message));
}

/// mlt makes its own samples (its Markov chains): a sampler that adapts to what it traced, or
/// reconstructs the image itself, would have nothing to work on, so naming one is an error.
fn refuse_adaptive_with_mlt(
    integrator: &Integrator,
    sampler: &dyn Sampler,
    choice: &Choice,
) -> Result<()> {
    let plain = ["random", "stratified", "halton", "sobol"];
    if !matches!(integrator, Integrator::Mlt(_)) || plain.contains(&sampler.name()) {
        return Ok(());
    }
    let message = format!(
        "the mlt integrator drives its own sampling (Markov chains in primary sample space); \
         the adaptive sampler \"{}\" cannot be used with it (use halton, sobol, stratified or \
         random, whose --spp sets mlt's mutations per pixel)",
        sampler.name()
    );
    Err(match &choice.loc {
        Some(loc) => acr_parser::Error::at(loc, message),
        None => acr_parser::Error::file("--sampler", message),
    })
}

/// Chooses and builds the sampler, filter and integrator: the scene's directives, with the
/// command line's names and settings on top. Without a directive, pbrt-v3's defaults: the
/// `halton` sampler at 16 spp, the `box` filter and the `path` integrator. The sampler's
/// setup says whether the chosen filter reads its cells, and gets the filter's radius.
pub fn choose(
    desc: &SceneDescription,
    overrides: &Overrides,
    setup: impl Fn((f32, f32)) -> SamplerSetup,
    warnings: &mut Vec<Warning>,
) -> Result<Plugins> {
    let mut ic = Choice::new(
        desc.integrator.as_ref(),
        "path",
        overrides.integrator.as_deref(),
    );
    let ie: &Entry<IntegratorBuild> =
        resolve(INTEGRATORS, Kind::Integrator, &mut ic, overrides, warnings)?;
    let mut integrator = (ie.build)(&ic)?;
    media_warning(desc, &integrator, warnings);
    if let Integrator::Mlt(m) = &mut integrator {
        // `--spp` is mlt's mutations per pixel (docs/light-transport.md).
        if let Some(spp) = setup((0.0, 0.0)).spp {
            m.mutations_per_pixel = spp.max(1);
        }
    }

    let mut fc = Choice::new(desc.filter.as_ref(), "box", overrides.filter.as_deref());
    let fe: &Entry<FilterBuild> = resolve(FILTERS, Kind::Filter, &mut fc, overrides, warnings)?;
    let filter = (fe.build)(&fc)?;

    let mut sc = Choice::new(
        desc.sampler.as_ref(),
        "halton",
        overrides.sampler.as_deref(),
    );
    let se: &Entry<SamplerBuild> = resolve(SAMPLERS, Kind::Sampler, &mut sc, overrides, warnings)?;
    let reads_cells = filter.cell_layout().is_some();
    let setup = |radius| SamplerSetup {
        reconstruction_reads_cells: reads_cells,
        ..setup(radius)
    };
    let mut sampler = (se.build)(&sc, &setup((0.0, 0.0)))?;
    refuse_adaptive_with_mlt(&integrator, sampler.as_ref(), &sc)?;
    if !reads_cells && !sampler.reconstructs() {
        // A splatting filter: sample the crop widened by its radius, so that crops tile the
        // frame. Reconstructions over cells keep to the crop (their cells cover it alone).
        sampler = (se.build)(&sc, &setup(filter.kernel().radius()))?;
    }
    if sampler.reconstructs() {
        // The method's reconstruction is part of it: a filter asked for is not used.
        let named = overrides
            .filter
            .as_deref()
            .map(|f| (f.to_owned(), None))
            .or_else(|| desc.filter.as_ref().map(|f| (f.kind.clone(), Some(&f.loc))));
        if let Some((name, loc)) = named {
            let message = format!(
                "the {} sampler reconstructs the image itself; filter \"{name}\" is not used",
                sampler.name()
            );
            warnings.push(match loc {
                Some(loc) => Warning::at(loc, message),
                None => Warning { loc: None, message },
            });
        }
    }
    // `check_params` has warned of what the plugins do not declare, on its copies; the
    // directives' own parameters need no second, vaguer warning.
    for d in [&desc.sampler, &desc.filter, &desc.integrator]
        .into_iter()
        .flatten()
    {
        for p in d.params.iter() {
            p.mark_used();
        }
    }
    Ok(Plugins {
        sampler,
        filter,
        integrator,
    })
}

/// [`choose`] for a built scene: the sampler covers the scene's crop widened by the filter's
/// radius ([`crate::render::sample_space`]), with the command line's `spp` (if any) and `seed`.
pub fn choose_for_scene(
    desc: &SceneDescription,
    scene: &crate::scene::Scene,
    overrides: &Overrides,
    spp: Option<u32>,
    seed: u64,
    warnings: &mut Vec<Warning>,
) -> Result<Plugins> {
    let setup = |radius| SamplerSetup {
        space: crate::render::sample_space(scene, radius),
        spp,
        seed,
        // `choose` sets it from the filter it chooses.
        reconstruction_reads_cells: false,
        stream: Default::default(),
    };
    let mut plugins = choose(desc, overrides, setup, warnings)?;
    if let Integrator::Sppm(s) = &mut plugins.integrator {
        // sppm draws its own samples: `--spp` is its iteration count (docs/light-transport.md).
        if let Some(n) = spp {
            s.iterations = n.max(1);
        }
        if let Some(why) = crate::integrator::sppm::refuse(plugins.sampler.as_ref(), false) {
            return Err(match &desc.integrator {
                Some(i) => Error::at(&i.loc, why),
                None => Error::file("sppm", why),
            });
        }
    }
    Ok(plugins)
}

/// `acr plugins`: every plugin by kind, with its parameters and defaults, as text.
pub fn describe() -> String {
    let mut out = String::new();
    for kind in [Kind::Sampler, Kind::Filter, Kind::Integrator] {
        out.push_str(&format!("{}s:\n", kind.name()));
        for info in all().filter(|i| i.kind == kind) {
            out.push_str(&format!("  {:<16}{}\n", info.name, info.doc));
            for p in info.params {
                let decl = format!("{} {}", p.ty.name(), p.name);
                out.push_str(&format!(
                    "      {:<28} default {:<10} {}\n",
                    decl, p.default, p.doc
                ));
            }
        }
        out.push('\n');
    }
    out.push_str(
        "pbrt-v3 names mapped to the nearest plugin, with a warning: samplers 02sequence, \
         lowdiscrepancy, maxmindist -> sobol.\n",
    );
    out
}
