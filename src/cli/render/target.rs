//! The files a render writes, planned and checked before it starts: the output image (its
//! path, format and whether it is mergeable) and the AOVs, as channels of it or files of
//! their own.

use super::prepare::Job;
use super::RenderArgs;
use crate::cli::aov::{parse_aovs, AovRequest};
use crate::cli::output::{scene_hash, Output, CHANNEL_AOVS};
use crate::image_io::{is_exr, Frame};
use acr_parser::SceneDescription;
use std::path::{Path, PathBuf};

/// Where a render's image and AOVs go.
pub(super) struct Target {
    /// The output image, with the AOVs it holds as channels.
    pub(super) out: Output,
    /// Every AOV asked for.
    pub(super) aovs: Vec<AovRequest>,
}

impl Target {
    /// The output and AOV files of `args` for `job`, each checked to be writable; an EXR
    /// output carries `scene_hash` ([`scene_hash_of`]).
    pub(super) fn plan(args: &RenderArgs, job: &Job, scene_hash: i32) -> Result<Target, String> {
        let output = output_path(args, job.scene.film.filename.as_deref());
        let is_exr = is_exr(&output);
        if args.mergeable && !is_exr {
            return Err(format!(
                "--mergeable writes an EXR, not {}",
                output.display()
            ));
        }
        check_writable(&output)?;
        let aovs: Vec<AovRequest> = args
            .aov
            .iter()
            .map(|a| parse_aovs(a))
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .flatten()
            .collect();
        let mut out = output_of(args, job, output, is_exr);
        if is_exr {
            out.scene = scene_hash;
        }
        for a in &aovs {
            place_aov(a, &mut out, job, is_exr)?;
        }
        Ok(Target { out, aovs })
    }
}

/// The hash of the scene's text (the files of `desc`) an EXR output carries, or 0 when the
/// output is not an EXR: a PNG or PFM render does not read the scene again.
pub(super) fn scene_hash_of(args: &RenderArgs, desc: &SceneDescription) -> i32 {
    let film_name = desc
        .film
        .as_ref()
        .and_then(|f| f.params.string("filename").ok().flatten());
    if is_exr(&output_path(args, film_name)) {
        scene_hash(desc)
    } else {
        0
    }
}

/// The output image `path` of `job`, as yet without channel AOVs.
fn output_of(args: &RenderArgs, job: &Job, path: PathBuf, is_exr: bool) -> Output {
    let film = &job.scene.film;
    let frame = Frame {
        width: film.resolution.0 as usize,
        height: film.resolution.1 as usize,
        x0: film.crop[0] as usize,
        y0: film.crop[2] as usize,
    };
    let (w, h) = job.size();
    Output {
        path,
        frame,
        size: (w as usize, h as usize),
        scale: film.scale,
        mergeable: args.mergeable,
        // mlt's image is normalised by its own bootstrap: its ranges do not add up; sppm's
        // image is not a sum of samples: nothing to merge.
        // A render by bands keeps no sums of the rows it released.
        can_merge: is_exr
            && job.splats
            && !job.by_bands
            && job.plugins.sampler.streams() == 1
            && !matches!(
                job.plugins.integrator,
                crate::integrator::Integrator::Mlt(_) | crate::integrator::Integrator::Sppm(_)
            ),
        offset: args.sample_offset,
        channel_aovs: Vec::new(),
        // Set by the caller, which has the description.
        scene: 0,
        footprint: job
            .scene
            .uses_differentials
            .then(|| super::prepare::footprint_spp(args, job.plugins.sampler.spp())),
    }
}

/// Makes AOV `a` a channel of `out` when it goes there, else checks its own file and that
/// the render makes it.
fn place_aov(a: &AovRequest, out: &mut Output, job: &Job, is_exr: bool) -> Result<(), String> {
    if out.holds(a) {
        if !is_exr {
            return Err(format!(
                "--aov {}: AOVs go into the output as channels only when it is an .exr, not {}",
                a.name,
                out.path.display()
            ));
        }
        if !CHANNEL_AOVS.iter().any(|(n, _)| *n == a.name) {
            return Err(format!(
                "--aov {}: cannot be a channel of the output (give it a file of its own)",
                a.name
            ));
        }
        out.channel_aovs.push(a.name.clone());
        return Ok(());
    }
    check_writable(&a.path)?;
    if a.name == "clusters" && job.plugins.sampler.report().cells.is_none() {
        return Err(format!(
            "--aov clusters: the {} sampler makes no clusters (use --sampler cluster)",
            job.plugins.sampler.name()
        ));
    }
    Ok(())
}

/// The output path: the command line's, else the Film's filename (relative to the working
/// directory, as pbrt-v3 writes it), else the scene's path with `.exr`.
fn output_path(args: &RenderArgs, film_filename: Option<&str>) -> PathBuf {
    if let Some(o) = &args.output {
        return o.clone();
    }
    match film_filename {
        Some(name) if !name.is_empty() => PathBuf::from(name),
        _ => args.scene.with_extension("exr"),
    }
}

/// Fails early, before the render, when the output cannot be written (unknown format or a
/// folder that does not exist), so that no render time is lost.
fn check_writable(output: &Path) -> Result<(), String> {
    let ext = output
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if !matches!(ext.as_str(), "exr" | "png" | "pfm") {
        return Err(format!(
            "{}: cannot write image format \"{ext}\" (acr writes .exr, .png and .pfm)",
            output.display()
        ));
    }
    let dir = output.parent().filter(|d| !d.as_os_str().is_empty());
    if let Some(d) = dir {
        if !d.is_dir() {
            return Err(format!(
                "{}: folder {} does not exist",
                output.display(),
                d.display()
            ));
        }
    }
    Ok(())
}
