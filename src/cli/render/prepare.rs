//! The steps before the render: the worker threads started, the scene read and built, its
//! plugins chosen and checked against the flags, the warnings printed.

use super::pipeline::{self, Row};
use super::RenderArgs;
use crate::integrator::{sppm, Integrator};
use crate::registry::{choose_for_scene, Overrides, Plugins};
use crate::scene::Scene;
use acr_parser::{SceneDescription, Warning};
use acr_plugins::Setting;

/// Starts `--threads` worker threads (without it, rayon starts one per core).
pub(super) fn start_threads(threads: Option<u32>) -> Result<(), String> {
    if let Some(n) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .map_err(|e| format!("cannot start {n} threads: {e}"))?;
    }
    Ok(())
}

/// Hands the pages of freed small blocks back to the system (glibc keeps them, inside its
/// heap, for later allocations): once the scene description is freed, the render's film
/// would otherwise come on top of its resident remains.
pub(super) fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free pages of the allocator's arenas to the system.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// The scene file parsed, at a quarter of its resolution under `--quick`.
pub(super) fn read_scene(args: &RenderArgs) -> Result<SceneDescription, String> {
    let mut desc = acr_parser::parse_file(&args.scene).map_err(|e| e.to_string())?;
    if args.quick {
        quarter_resolution(&mut desc).map_err(|e| e.to_string())?;
    }
    Ok(desc)
}

/// What is rendered: the scene and the plugins chosen for it.
pub(super) struct Job {
    /// The scene built.
    pub(super) scene: Scene,
    /// The command line's choices of plugins and their parameters (with an auto pipeline's).
    pub(super) overrides: Overrides,
    /// The auto pipeline's row, when it chose the sampler and filter.
    pub(super) pipeline: Option<&'static Row>,
    /// The seconds the render leaves its reconstruction out of `--time-limit` (the auto
    /// pipeline's nfor; 0 otherwise).
    pub(super) reserve: f64,
    /// The sampler, filter and integrator.
    pub(super) plugins: Plugins,
    /// Whether the film splats each sample with the filter's kernel (neither the filter's
    /// cells nor the sampler make the image).
    pub(super) splats: bool,
    /// Whether it renders by bands ([`by_bands`]; the sampler then walks by rows).
    pub(super) by_bands: bool,
}

impl Job {
    /// Builds the scene with the command line's crop, chooses its plugins, checks them against
    /// `--sample-offset` and `--mergeable`, and prints the warnings.
    pub(super) fn prepare(args: &RenderArgs, desc: &SceneDescription) -> Result<Job, String> {
        let spp = if args.quick { Some(1) } else { args.spp };
        let mut warnings = desc.warnings.clone();
        let mut scene = build_scene(args, desc, &mut warnings)?;
        let (w, h) = scene.film.size();
        let pixels = u64::from(w) * u64::from(h);
        // The pool is started ([`start_threads`]): its size is the render's.
        let threads = rayon::current_num_threads() as u32;
        let auto = pipeline::choose(args, desc, scene.dims, pixels, threads)?;
        let reserve = pipeline::reserve(auto, pixels, threads);
        let overrides = overrides(args, auto)?;
        let mut plugins = choose_for_scene(desc, &scene, &overrides, spp, args.seed, &mut warnings)
            .map_err(|e| e.to_string())?;
        if matches!(plugins.integrator, Integrator::Sppm(_)) {
            let threshold = args.noise_threshold.is_some();
            if let Some(why) = sppm::refuse(plugins.sampler.as_ref(), threshold) {
                return Err(why);
            }
            if args.mergeable || args.sample_offset != 0 {
                return Err("--mergeable and --sample-offset do not apply to the sppm \
                            integrator: its image is not a sum of samples (each iteration \
                            shrinks every pixel's radius)"
                    .into());
            }
        }
        start_at_sample_offset(args.sample_offset, &mut plugins)?;
        scene.set_footprint_spp(footprint_spp(args, plugins.sampler.spp()));
        let splats = plugins.filter.cell_layout().is_none() && !plugins.sampler.reconstructs();
        if args.mergeable && (!splats || plugins.sampler.streams() > 1) {
            return Err(format!(
                "--mergeable needs a splatting filter (box, gaussian, mitchell, sinc, triangle) \
                 and a sampler that does not reconstruct the image itself, not {} + {}",
                plugins.sampler.name(),
                plugins.filter.name()
            ));
        }
        let by_bands = by_bands(args, &mut plugins, scene.film.size().1);
        print_warnings(desc, warnings);
        if let Some(row) = auto {
            eprintln!("{}", pipeline::announce(row));
        }
        Ok(Job {
            scene,
            overrides,
            pipeline: auto,
            reserve,
            plugins,
            splats,
            by_bands,
        })
    }

    /// The film's crop size, in pixels.
    pub(super) fn size(&self) -> (u32, u32) {
        self.scene.film.size()
    }
}

/// Whether the render goes by bands of rows (docs/reconstruction.md, "Rendering by bands"):
/// when the filter makes the image band by band and the image has more than one band, the
/// sampler's points depend on the pixel and index alone (it is then set to walk by rows), the
/// integrator samples the camera's pixels (not mlt, sppm, nor bdpt, whose light paths splat
/// anywhere), and nothing needs the whole film before the end: no time limit nor noise
/// threshold (which stop the image as a whole), no mergeable sums, partial images, viewer or
/// sampler-cost replay.
fn by_bands(args: &RenderArgs, plugins: &mut Plugins, height: u32) -> bool {
    let bands = plugins.filter.bands(height as usize);
    let several = bands.is_some_and(|b| b.layout(height as usize).len() > 1);
    let camera_pixels = !matches!(
        plugins.integrator,
        Integrator::Mlt(_) | Integrator::Sppm(_) | Integrator::Bdpt(_)
    );
    let whole_film_later = args.time_limit.is_none()
        && args.noise_threshold.is_none()
        && !args.mergeable
        && args.write_partial_images.is_none()
        && args.display_server.is_none()
        && !args.sampler_cost;
    several
        && camera_pixels
        && whole_film_later
        && plugins.filter.reads_pixel_buffers()
        && plugins.sampler.streams() == 1
        && plugins
            .sampler
            .walk_by_rows(crate::render::bands::CHUNK_ROWS)
}

/// The scene built, cropped by `--cropwindow` or `--pixelbounds`.
fn build_scene(
    args: &RenderArgs,
    desc: &SceneDescription,
    warnings: &mut Vec<Warning>,
) -> Result<Scene, String> {
    let mut scene = Scene::build(desc, warnings).map_err(|e| e.to_string())?;
    if let Some(w) = args.cropwindow {
        scene
            .film
            .set_crop_window(w)
            .map_err(|e| format!("--cropwindow {e}"))?;
    }
    if let Some(b) = args.pixelbounds {
        scene
            .film
            .set_pixel_bounds(b)
            .map_err(|e| format!("--pixelbounds {e}"))?;
    }
    Ok(scene)
}

/// The plugins and parameters the command line names, or the auto pipeline's `row` with the
/// command line's `--set`s after its own.
fn overrides(args: &RenderArgs, row: Option<&Row>) -> Result<Overrides, String> {
    let named = |r: Option<&Row>, name: fn(&Row) -> &'static str, given: &Option<String>| {
        r.map(|r| name(r).to_owned()).or_else(|| given.clone())
    };
    let row_settings = row.map_or(&[][..], |r| r.settings).iter().copied();
    Ok(Overrides {
        sampler: named(row, |r| r.sampler, &args.sampler),
        filter: named(row, |r| r.filter, &args.filter),
        integrator: args.integrator.clone(),
        settings: row_settings
            .chain(args.set.iter().map(String::as_str))
            .map(Setting::parse)
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?,
    })
}

/// `--sample-offset`: the sampler's samples start at index `offset`, where it can.
fn start_at_sample_offset(offset: u32, plugins: &mut Plugins) -> Result<(), String> {
    if offset == 0 {
        return Ok(());
    }
    let fits = plugins.sampler.spp().checked_add(offset).is_some();
    if !fits || !plugins.sampler.set_sample_offset(offset) {
        return Err(format!(
            "--sample-offset {offset}: the {} sampler cannot start its samples there (sample \
             ranges need a sampler whose points depend on the index alone: random or sobol)",
            plugins.sampler.name()
        ));
    }
    Ok(())
}

/// The samples per pixel of the whole render, which set the texture footprint:
/// `--footprint-spp`, else the last sample index this render reaches (`--sample-offset` +
/// `spp`, the sampler's budget: the most an adaptive sampler or a time limit may reach).
pub(super) fn footprint_spp(args: &RenderArgs, spp: u32) -> u32 {
    args.footprint_spp
        .unwrap_or_else(|| args.sample_offset.saturating_add(spp))
}

/// Prints the scene's warnings and those of its unused parameters, each once.
fn print_warnings(desc: &SceneDescription, mut warnings: Vec<Warning>) {
    if let Some(a) = &desc.accelerator {
        // acr has one acceleration structure; pbrt-v3's choice of its own is moot.
        for p in a.params.iter() {
            p.mark_used();
        }
    }
    warnings.extend(desc.unused_parameter_warnings());
    // A file included twice repeats its warnings word for word: print each once.
    let mut printed = std::collections::HashSet::new();
    for w in &warnings {
        let text = w.to_string();
        if printed.insert(text.clone()) {
            eprintln!("{text}");
        }
    }
}

/// `--quick`: the Film's resolution divided by 4 in each direction (at least 1 pixel), as
/// pbrt-v4 does; a scene without a Film gets pbrt-v3's default 1280x720, quartered.
fn quarter_resolution(desc: &mut SceneDescription) -> acr_parser::Result<()> {
    use acr_parser::{Param, ParamList, ParamType, PluginDesc, Values};
    let loc = match (&desc.film, &desc.camera) {
        (Some(f), _) => f.loc.clone(),
        (None, Some(c)) => c.plugin.loc.clone(),
        (None, None) => return Ok(()),
    };
    let film = desc.film.get_or_insert_with(|| PluginDesc {
        kind: "image".to_owned(),
        params: ParamList::new(),
        loc: loc.clone(),
    });
    for (name, default) in [("xresolution", 1280), ("yresolution", 720)] {
        let v = film.params.int_or(name, default)?;
        let quarter = Values::Ints(vec![(v / 4).max(1)]);
        film.params
            .push(Param::new(ParamType::Integer, name, quarter, loc.clone()));
    }
    Ok(())
}
