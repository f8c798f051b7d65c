//! `--pipeline`: the sampler and filter a render uses when the user asks for the best image in
//! a time (or to a noise threshold) and names neither. The choice is a table keyed on what is
//! known before rendering, the scene's dimensions (motion blur, a lens, both, neither), each
//! row the pipeline measured best at equal time on the bench scenes of that kind
//! (docs/BENCHMARKS.md). Changing the choice is changing a row of [`TABLE`].

use super::args::{Pipeline, RenderArgs};
use acr_parser::SceneDescription;
use acr_plugins::Dims;

/// One row of the table: the scene's dimensions it serves and the pipeline it renders with.
#[derive(Debug, PartialEq, Eq)]
pub struct Row {
    /// Something moves during the shutter (the time dim).
    pub time: bool,
    /// The camera has a lens (the lens dims).
    pub lens: bool,
    /// The sampler, by name.
    pub sampler: &'static str,
    /// The filter, by name.
    pub filter: &'static str,
    /// Parameters, as `--set` takes them, applied before the command line's `--set`s.
    pub settings: &'static [&'static str],
    /// The measurement behind the row.
    pub measured: &'static str,
}

/// The samples per pixel an auto pipeline is capped at without `--spp`: the cap the equal-time
/// benches measured with (their `time_limited_spp`). A scene without a Sampler would otherwise
/// stop at pbrt-v3's default 16 whatever the time.
const SPP_CAP: &str = "sampler.pixelsamples=64";

/// The pipelines, by the scene's dimensions. Every row: `bench/sobol_polynomial.toml`, three
/// seeds, MSE at the times stratified+gaussian takes at 8, 16 and 32 spp.
pub const TABLE: [Row; 4] = [
    Row {
        time: false,
        lens: false,
        sampler: "cluster",
        filter: "polynomial",
        settings: &[SPP_CAP],
        measured: "docs/BENCHMARKS.md, \"The fit with and without the cluster sampler at equal \
                   time\": cornell-box-gi 0.055x / 0.017x / 0.0061x of stratified+gaussian \
                   against sobol+polynomial's 0.083x / 0.041x / 0.014x; indirect-room-gi 0.11x / \
                   0.16x / 0.20x against 0.11x / 0.15x / 0.22x",
    },
    Row {
        time: true,
        lens: false,
        sampler: "sobol",
        filter: "polynomial",
        settings: &[SPP_CAP],
        measured: "docs/BENCHMARKS.md, \"The fit with and without the cluster sampler at equal \
                   time\": motion-blur-3d 0.58x / 0.36x / 0.23x of stratified+gaussian against \
                   cluster+polynomial's 0.62x / 0.33x / 0.22x",
    },
    Row {
        time: false,
        lens: true,
        sampler: "sobol",
        filter: "polynomial",
        settings: &[SPP_CAP],
        measured: "docs/BENCHMARKS.md, \"The fit with and without the cluster sampler at equal \
                   time\": depth-of-field-4d 0.75x / 0.64x / 0.60x of stratified+gaussian \
                   against cluster+polynomial's 0.99x / 0.67x / 0.64x",
    },
    Row {
        time: true,
        lens: true,
        sampler: "sobol",
        filter: "polynomial",
        settings: &[SPP_CAP],
        measured: "docs/BENCHMARKS.md, \"The fit with and without the cluster sampler at equal \
                   time\": motion-dof-5d 0.82x / 0.75x / 0.74x of stratified+gaussian against \
                   cluster+polynomial's 1.04x / 0.81x / 0.85x",
    },
];

/// The pipeline once the time limit leaves room for NFOR's reconstruction, whatever the dims:
/// `bench/denoise.toml`, three seeds, at the time stratified+box takes at 64 spp (where nfor
/// took about a quarter of the time) cluster+nfor had 0.38x, 0.27x, 0.29x, 0.095x and 0.081x of
/// stratified+box's MSE on the five scenes, against cluster+polynomial's 0.43x, 0.50x, 0.51x,
/// 0.20x and 0.12x; at the time of 16 spp (nfor about half the time or more) it lost to
/// cluster+polynomial on four of five.
pub const NFOR_ROW: Row = Row {
    time: false,
    lens: false,
    sampler: "cluster",
    filter: "nfor",
    settings: &[SPP_CAP],
    measured: "docs/BENCHMARKS.md, \"Against Open Image Denoise\": at the time of 64 \
               stratified+box spp, cluster+nfor 0.38x / 0.27x / 0.29x / 0.095x / 0.081x of \
               stratified+box against cluster+polynomial's 0.43x / 0.50x / 0.51x / 0.20x / \
               0.12x",
};

/// nfor's reconstruction, in thread-seconds per pixel: its CPU time 3.8e-6 to 4.1e-6 a pixel at
/// 256x256, 320x240 and 1024x1024 (fits on every second pixel), 0.34x to 0.39x the 9.9e-6 to
/// 1.16e-5 it took before (docs/reconstruction.md, "NFOR", cost).
const NFOR_THREAD_SECONDS_PER_PIXEL: f64 = 4.0e-6;

/// The largest share of the time limit nfor's reconstruction may take for the auto pipeline to
/// choose it: it won at about a quarter, lost at a half (`NFOR_ROW`).
const NFOR_MAX_SHARE: f64 = 0.3;

/// nfor's estimated reconstruction seconds for `pixels` on `threads`.
pub fn nfor_seconds(pixels: u64, threads: u32) -> f64 {
    pixels as f64 * NFOR_THREAD_SECONDS_PER_PIXEL / f64::from(threads.max(1))
}

/// The row for a render of `dims`, `pixels` on `threads`, stopped at `time_limit` seconds (if
/// any): nfor's once its reconstruction fits in [`NFOR_MAX_SHARE`] of the limit, else the
/// table's.
pub fn row_for_time(
    dims: Dims,
    time_limit: Option<f64>,
    pixels: u64,
    threads: u32,
) -> &'static Row {
    match time_limit {
        Some(t) if nfor_seconds(pixels, threads) <= NFOR_MAX_SHARE * t => &NFOR_ROW,
        _ => row_for(dims),
    }
}

/// The row for a scene of dimensions `dims`.
pub fn row_for(dims: Dims) -> &'static Row {
    TABLE
        .iter()
        .find(|r| r.time == dims.time && r.lens == dims.lens)
        .expect("the table has a row for every combination of time and lens")
}

/// The row the render uses, or `None` for the scene's pipeline: `--pipeline auto`, or, without
/// `--pipeline`, a render stopped by `--time-limit` or `--noise-threshold` that names no
/// sampler or filter on the command line or in the scene (and asks for nothing only some
/// samplers and filters give: `--mergeable`, `--sample-offset`).
pub(super) fn choose(
    args: &RenderArgs,
    desc: &SceneDescription,
    dims: Dims,
    pixels: u64,
    threads: u32,
) -> Result<Option<&'static Row>, String> {
    let row_for = |dims| row_for_time(dims, args.time_limit, pixels, threads);
    let named_here = args.sampler.is_some() || args.filter.is_some();
    match args.pipeline {
        Some(Pipeline::Scene) => Ok(None),
        Some(Pipeline::Auto) if named_here => Err("--pipeline auto chooses the sampler and \
                                                   filter: drop --sampler and --filter, or \
                                                   --pipeline auto"
            .to_owned()),
        Some(Pipeline::Auto) => Ok(Some(row_for(dims))),
        None => {
            let stopped = args.time_limit.is_some() || args.noise_threshold.is_some();
            let named = named_here || desc.sampler.is_some() || desc.filter.is_some();
            // mlt makes its own samples: no sampler nor filter to choose.
            let integrator = args
                .integrator
                .as_deref()
                .or(desc.integrator.as_ref().map(|i| i.kind.as_str()));
            let needs_scene = args.mergeable || args.sample_offset > 0 || integrator == Some("mlt");
            Ok((stopped && !named && !needs_scene).then(|| row_for(dims)))
        }
    }
}

/// The stats file's `pipeline`: "scene", or "auto:SAMPLER+FILTER".
pub(super) fn stats_name(row: Option<&Row>) -> String {
    match row {
        None => "scene".to_owned(),
        Some(r) => format!("auto:{}+{}", r.sampler, r.filter),
    }
}

/// The seconds an auto pipeline's render leaves its reconstruction out of the time limit: the
/// limit stops the sampling, and the best image in the time is the reconstructed one.
pub(super) fn reserve(row: Option<&Row>, pixels: u64, threads: u32) -> f64 {
    match row {
        Some(r) if r.filter == "nfor" => nfor_seconds(pixels, threads),
        _ => 0.0,
    }
}

/// What stderr says of an auto pipeline: the row and where its measurement is.
pub(super) fn announce(row: &Row) -> String {
    if row.filter == "nfor" {
        let source = row.measured.split(':').next().unwrap_or(row.measured);
        return format!(
            "acr: pipeline auto: {} + {}: the time limit leaves room for its reconstruction, \
             measured best at equal time ({source}); --pipeline scene renders with the \
             scene's sampler and filter",
            row.sampler, row.filter
        );
    }
    let dims = match (row.time, row.lens) {
        (false, false) => "no motion blur, no lens",
        (true, false) => "motion blur",
        (false, true) => "a lens",
        (true, true) => "motion blur and a lens",
    };
    let source = row.measured.split(':').next().unwrap_or(row.measured);
    format!(
        "acr: pipeline auto: {} + {} for a scene with {dims}, measured best at equal time \
         ({source}); --pipeline scene renders with the scene's sampler and filter",
        row.sampler, row.filter
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nfor_is_chosen_once_the_limit_leaves_room_for_its_reconstruction() {
        let dims = Dims {
            time: true,
            lens: false,
        };
        // 76,800 pixels on 2 threads: about 0.15 s of reconstruction.
        let px = 320 * 240;
        assert_eq!(row_for_time(dims, Some(1.5), px, 2).filter, "nfor");
        assert_eq!(row_for_time(dims, Some(0.6), px, 2).filter, "nfor");
        assert_eq!(row_for_time(dims, Some(0.4), px, 2).filter, "polynomial");
        assert_eq!(row_for_time(dims, None, px, 2), row_for(dims));
        // Four times the pixels want four times the time.
        assert_eq!(
            row_for_time(dims, Some(1.5), 4 * px, 2).filter,
            "polynomial"
        );
        assert!((reserve(Some(&NFOR_ROW), px, 2) - 0.1536).abs() < 1e-9);
        assert_eq!(reserve(Some(row_for(dims)), px, 2), 0.0);
        let names: Vec<&str> = crate::registry::all().map(|i| i.name).collect();
        assert!(names.contains(&NFOR_ROW.filter));
    }

    #[test]
    fn every_combination_of_dims_has_one_row_of_known_plugins() {
        for time in [false, true] {
            for lens in [false, true] {
                let n = TABLE
                    .iter()
                    .filter(|r| r.time == time && r.lens == lens)
                    .count();
                assert_eq!(n, 1, "time {time}, lens {lens}");
            }
        }
        let names: Vec<&str> = crate::registry::all().map(|i| i.name).collect();
        for r in &TABLE {
            assert!(names.contains(&r.sampler), "{}", r.sampler);
            assert!(names.contains(&r.filter), "{}", r.filter);
            assert!(r.measured.contains("docs/BENCHMARKS.md"), "{}", r.measured);
            for s in r.settings {
                acr_plugins::Setting::parse(s).unwrap();
            }
        }
    }
}
