//! What a bench writes: the CSVs, the Markdown report and the plots.

use super::{file_safe, BenchOptions, CostRow, Manifest, Measured, Method, Mode, Row};
use std::fmt::Write as _;
use std::path::Path;

/// Writes what a bench of manifest `m` measured into `opts.out`: the CSVs, a plot per scene
/// (a failed plot is only a warning) and the Markdown report.
pub(super) fn write_results(
    m: &Manifest,
    manifest_path: &Path,
    opts: &BenchOptions,
    rows: &[Row],
    costs: &[CostRow],
) -> Result<(), String> {
    write_csv(&opts.out.join("results.csv"), rows)?;
    if m.sampler_cost.is_some() {
        write_cost_csv(&opts.out.join("sampler_cost.csv"), costs)?;
    }
    for scene in &m.scenes {
        let path = opts.out.join(format!("{}.png", file_safe(&scene.name)));
        if let Err(e) = plot_scene(&path, &scene.name, &m.methods, rows) {
            eprintln!("{}: plot failed: {e}", path.display());
        }
    }
    let report = report_markdown(m, manifest_path, opts, rows, costs);
    let path = opts.out.join("report.md");
    std::fs::write(&path, report).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// `s` as one CSV field: quoted, its quotes doubled, when it holds a comma, quote or newline.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// The image's mean over the reference's (1 when the reference is black): a filter or sampler
/// that moves the mean shows here whatever its MSE.
fn mean_ratio(m: &crate::metrics::Metrics) -> f64 {
    if m.reference_mean > 0.0 {
        m.mean / m.reference_mean
    } else {
        1.0
    }
}

/// Whether a row's error is a skip (its program absent on this machine), not a failure.
fn is_skip(e: &str) -> bool {
    e.starts_with("skipped:")
}

/// The CSV: one row per run, failed runs with their reason, skipped ones with theirs; an
/// external method's command seconds (part of `seconds`) and how they were counted.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<(), String> {
    let mut s = String::from(
        "scene,method,mode,spp,seconds,samples,spp_reached,mse,relmse,psnr,peak_rss_mb,status,\
         mean_ratio,seeds,command_seconds,command_time\n",
    );
    for r in rows {
        let head = format!(
            "{},{},{},{}",
            csv_field(&r.scene),
            csv_field(&r.method),
            r.mode.name(),
            r.spp
        );
        match &r.outcome {
            Ok(m) => {
                let _ = writeln!(
                    s,
                    "{head},{:.6},{},{:.3},{:.6e},{:.6e},{:.4},{:.1},ok,{:.5},{},{},{}",
                    m.seconds,
                    m.samples,
                    m.spp_reached,
                    m.metrics.mse,
                    m.metrics.relmse,
                    m.metrics.psnr,
                    m.peak_rss_mb,
                    mean_ratio(&m.metrics),
                    r.seeds,
                    m.command_seconds
                        .map_or(String::new(), |c| format!("{c:.6}")),
                    m.command_time.map_or("", |t| t.name())
                );
            }
            Err(e) => {
                let status = if is_skip(e) {
                    e.clone()
                } else {
                    format!("failed: {e}")
                };
                let _ = writeln!(s, "{head},,,,,,,,{},,{},,", csv_field(&status), r.seeds);
            }
        }
    }
    std::fs::write(path, s).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// The sampler-cost CSV: one row per scene, method and budget, with the median share over
/// its runs, the least and the largest, and the median seconds of a render and of a replay.
pub fn write_cost_csv(path: &Path, costs: &[CostRow]) -> Result<(), String> {
    let mut s = String::from(
        "scene,method,spp,runs,sampler_share,share_min,share_max,rerender_seconds,replay_seconds,status\n",
    );
    for c in costs {
        let head = format!("{},{},{}", csv_field(&c.scene), csv_field(&c.method), c.spp);
        match c.summary() {
            Ok(c) => {
                let _ = writeln!(
                    s,
                    "{head},{},{:.4},{:.4},{:.4},{:.6},{:.6},ok",
                    c.runs, c.share, c.least, c.largest, c.rerender, c.replay
                );
            }
            Err(e) => {
                let _ = writeln!(s, "{head},,,,,,,{}", csv_field(&format!("failed: {e}")));
            }
        }
    }
    std::fs::write(path, s).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// The equal-spp and equal-time result of `method` on `scene` at `spp`.
fn find<'a>(rows: &'a [Row], scene: &str, method: &str, spp: u32, mode: Mode) -> Option<&'a Row> {
    rows.iter()
        .find(|r| r.scene == scene && r.method == method && r.spp == spp && r.mode == mode)
}

/// The Markdown report: the setting, then per scene a table of equal-spp and equal-time errors
/// with their ratios to the first method (below 1: better than the first method).
pub fn report_markdown(
    m: &Manifest,
    manifest: &Path,
    opts: &BenchOptions,
    rows: &[Row],
    costs: &[CostRow],
) -> String {
    let mut s = String::new();
    write_setting(&mut s, m, manifest, opts);
    let failed = rows
        .iter()
        .filter(|r| r.outcome.as_ref().is_err_and(|e| !is_skip(e)))
        .count();
    if failed > 0 {
        let _ = writeln!(s, "**{failed} runs failed**; see `results.csv`.\n");
    }
    for (meth, why) in m.methods.iter().filter_map(|meth| {
        rows.iter()
            .find(|r| r.method == meth.label)
            .and_then(|r| r.outcome.as_ref().err())
            .filter(|e| is_skip(e))
            .map(|e| (meth, e))
    }) {
        let _ = writeln!(
            s,
            "**`{}` was {why}** on this machine: its rows are empty.\n",
            meth.label
        );
    }
    for scene in &m.scenes {
        write_scene_table(&mut s, m, &scene.name, rows);
    }
    if let Some(spec) = &m.sampler_cost {
        write_cost_table(&mut s, spec.runs, costs);
    }
    s
}

/// The report's title and setting: manifest, command, machine, threads, commit, seeds, and
/// what the figures mean.
fn write_setting(s: &mut String, m: &Manifest, manifest: &Path, opts: &BenchOptions) {
    let _ = writeln!(s, "# {}\n", m.title.as_deref().unwrap_or("acr bench"));
    let _ = writeln!(s, "- manifest: `{}`", manifest.display());
    let _ = writeln!(s, "- command: `{}`", opts.command);
    let _ = writeln!(s, "- machine: {}", machine());
    let _ = writeln!(
        s,
        "- threads: {}",
        m.threads.map_or_else(
            || format!("all ({})", available_threads()),
            |t| t.to_string()
        )
    );
    let _ = writeln!(s, "- commit: {}", opts.commit);
    match &m.seeds {
        Some(seeds) => {
            let list: Vec<String> = seeds.iter().map(u64::to_string).collect();
            let _ = writeln!(
                s,
                "- seeds: {} (each row the means over them; the largest peak memory)",
                list.join(", ")
            );
        }
        None => {
            let _ = writeln!(s, "- seed: {}", m.seed);
        }
    }
    let _ = writeln!(
        s,
        "- seconds: render + reconstruction of each run (its stats file); ratios are against `{}`, the first method (below 1 is better); equal time: each method given the spp its own equal-spp run says fits in the first method's seconds at that budget (at most 4x), and those seconds less its reconstruction's (and a command's) seconds in that run as `--time-limit`, since the limit stops the sampling and the reconstruction comes after (it stops at the end of the pass under way, so its time can overshoot by up to one pass)\n",
        m.methods[0].label
    );
    write_external_notes(s, m);
}

/// The external methods' lines of the setting: each command, and how its seconds count.
fn write_external_notes(s: &mut String, m: &Manifest) {
    let external: Vec<&Method> = m.methods.iter().filter(|m| m.is_external()).collect();
    if external.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "External methods render with acr, then run a command on the render; their seconds are the render's plus the command's (in brackets in the tables, column `command_seconds` of the CSV); at equal time the render's limit is the first method's seconds less the command's seconds in the method's own equal-spp run at that budget and seed:\n"
    );
    for meth in external {
        let argv = meth.command.as_deref().unwrap_or_default().join(" ");
        let counted = match meth.time.unwrap_or_default() {
            super::CommandTime::Wall => "the wall time of its whole process",
            super::CommandTime::Printed => "the seconds it prints on its last line",
        };
        let _ = writeln!(s, "- `{}`: `{argv}`; counted: {counted}", meth.label);
    }
    s.push('\n');
}

/// A scene's section: its plot, and a line per budget and method.
fn write_scene_table(s: &mut String, m: &Manifest, scene: &str, rows: &[Row]) {
    let _ = writeln!(s, "## {scene}\n");
    let _ = writeln!(s, "![{0}]({0}.png)\n", file_safe(scene));
    if let Some(&spp) = m.budgets.spp.iter().min() {
        let mut modes = vec![Mode::EqualSpp];
        if m.budgets.equal_time && m.methods.len() > 1 {
            modes.push(Mode::EqualTime);
        }
        for mode in modes {
            let name = format!("{}-images-{}-{spp}", file_safe(scene), mode.name());
            let _ = writeln!(
                s,
                "Images at {spp} spp, {}: [side by side]({name}.png), [where they differ most]({name}-crop.png)\n",
                mode.name()
            );
        }
    }
    let _ = writeln!(
        s,
        "| spp | method | seconds | MSE | relMSE | MSE ratio | relMSE ratio | mean / reference | equal-time seconds | equal-time spp | equal-time MSE | MSE ratio | relMSE ratio |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for &spp in &m.budgets.spp {
        let base = find(rows, scene, &m.methods[0].label, spp, Mode::EqualSpp)
            .and_then(|r| r.outcome.as_ref().ok());
        for meth in &m.methods {
            let eq = find(rows, scene, &meth.label, spp, Mode::EqualSpp);
            let et = find(rows, scene, &meth.label, spp, Mode::EqualTime);
            let mut line = format!("| {spp} | {} ", meth.label);
            equal_spp_cells(&mut line, eq, base);
            equal_time_cells(&mut line, et, base);
            let _ = writeln!(s, "{line}");
        }
    }
    s.push('\n');
}

/// The equal-spp cells of a method's line: seconds, errors, their ratios to `base`'s, the
/// mean ratio.
fn equal_spp_cells(line: &mut String, row: Option<&Row>, base: Option<&Measured>) {
    match row.map(|r| &r.outcome) {
        Some(Ok(r)) => {
            let _ = write!(
                line,
                "| {} | {:.3e} | {:.3e} | {} | {} | {:.4} ",
                seconds_cell(r),
                r.metrics.mse,
                r.metrics.relmse,
                ratio(r.metrics.mse, base.map(|b| b.metrics.mse)),
                ratio(r.metrics.relmse, base.map(|b| b.metrics.relmse)),
                mean_ratio(&r.metrics)
            );
        }
        Some(Err(e)) if is_skip(e) => line.push_str("| skipped | | | | | "),
        Some(Err(_)) => line.push_str("| failed | | | | | "),
        None => line.push_str("| | | | | | "),
    }
}

/// The equal-time cells of a method's line: seconds, spp reached, MSE, the ratios of its
/// errors to `base`'s.
fn equal_time_cells(line: &mut String, row: Option<&Row>, base: Option<&Measured>) {
    match row.map(|r| &r.outcome) {
        Some(Ok(r)) => {
            let _ = write!(
                line,
                "| {} | {:.1} | {:.3e} | {} | {} |",
                seconds_cell(r),
                r.spp_reached,
                r.metrics.mse,
                ratio(r.metrics.mse, base.map(|b| b.metrics.mse)),
                ratio(r.metrics.relmse, base.map(|b| b.metrics.relmse))
            );
        }
        Some(Err(e)) if is_skip(e) => line.push_str("| skipped | | | | |"),
        Some(Err(_)) => line.push_str("| failed | | | | |"),
        None => line.push_str("| | | | | |"),
    }
}

/// A run's seconds, an external command's share in brackets.
fn seconds_cell(r: &Measured) -> String {
    match r.command_seconds {
        Some(c) => format!("{:.3} ({c:.3})", r.seconds),
        None => format!("{:.3}", r.seconds),
    }
}

/// The sampler-cost section: how it is measured (`runs` processes each), and a line per
/// measure.
fn write_cost_table(s: &mut String, runs: u32, costs: &[CostRow]) {
    let _ = writeln!(s, "## The sampler's share of wall time\n");
    let _ = writeln!(
        s,
        "`acr render --sampler-cost`, {runs} processes each (`sampler_cost.csv`): a render by a fresh sampler against a replay of its points, share = (render - replay) / render; the median over the processes, then the least and the largest.\n",
    );
    let _ = writeln!(
        s,
        "| scene | spp | method | share | least | largest | render s | replay s |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for c in costs {
        let figures = match c.summary() {
            Ok(c) => format!(
                "{:.1}% | {:.1}% | {:.1}% | {:.3} | {:.3}",
                100.0 * c.share,
                100.0 * c.least,
                100.0 * c.largest,
                c.rerender,
                c.replay
            ),
            Err(_) => "failed | | | |".to_owned(),
        };
        let _ = writeln!(s, "| {} | {} | {} | {figures} |", c.scene, c.spp, c.method);
    }
    s.push('\n');
}

/// How many threads a run without `threads` uses: the machine's.
fn available_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The CPU model and core count, from /proc/cpuinfo where there is one.
fn machine() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    format!(
        "{model}, {} hardware threads, {}",
        available_threads(),
        std::env::consts::OS
    )
}

/// `x` over `base` to three decimals; `-` without a positive base.
fn ratio(x: f64, base: Option<f64>) -> String {
    match base {
        Some(b) if b > 0.0 => format!("{:.3}", x / b),
        _ => "-".to_owned(),
    }
}

/// Axis ticks at 1, 2 and 5 times the powers of ten within `lo..hi` (plotters' log axes label
/// only powers of ten, which a narrow range may not contain).
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut v = Vec::new();
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi {
        for m in [1.0, 2.0, 5.0] {
            let t = decade * m;
            if t >= lo && t <= hi {
                v.push(t);
            }
        }
        decade *= 10.0;
    }
    v
}

static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

/// Registers the embedded font with plotters once (its ab_glyph text needs one; no system
/// font library is used).
pub(super) fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ =
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT);
    });
}

/// The log-log plot of MSE against seconds for one scene: a line per method through its
/// equal-spp runs, and its equal-time runs as hollow circles.
pub fn plot_scene(
    path: &Path,
    scene: &str,
    methods: &[Method],
    rows: &[Row],
) -> Result<(), String> {
    use plotters::prelude::*;
    register_font();
    let ok: Vec<(&Row, &Measured)> = rows
        .iter()
        .filter(|r| r.scene == scene)
        .filter_map(|r| r.outcome.as_ref().ok().map(|m| (r, m)))
        .filter(|(_, m)| m.seconds > 0.0 && m.metrics.mse > 0.0)
        .collect();
    if ok.is_empty() {
        return Err("no successful run to plot".to_owned());
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (_, m) in &ok {
        x0 = x0.min(m.seconds);
        x1 = x1.max(m.seconds);
        y0 = y0.min(m.metrics.mse);
        y1 = y1.max(m.metrics.mse);
    }
    let pad = |lo: f64, hi: f64| (lo / 1.3, (hi * 1.3).max(lo * 1.5));
    let ((x0, x1), (y0, y1)) = (pad(x0, x1), pad(y0, y1));
    let root = BitMapBackend::new(path, (720, 480)).into_drawing_area();
    let e = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{scene}: MSE against time (dots: equal spp, rings: equal time)"),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x0..x1).log_scale().with_key_points(ticks(x0, x1)),
            (y0..y1).log_scale().with_key_points(ticks(y0, y1)),
        )
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_labels(8)
        .y_labels(8)
        .light_line_style(WHITE)
        .x_desc("seconds (render + reconstruction)")
        .y_desc("MSE")
        .y_label_formatter(&|v| format!("{v:.1e}"))
        .x_label_formatter(&|v| format!("{v:.2}"))
        .draw()
        .map_err(|x| e(&x))?;
    for (k, meth) in methods.iter().enumerate() {
        let colour = Palette99::pick(k).to_rgba();
        let mut line: Vec<(f64, f64)> = ok
            .iter()
            .filter(|(r, _)| r.method == meth.label && r.mode == Mode::EqualSpp)
            .map(|(_, m)| (m.seconds, m.metrics.mse))
            .collect();
        line.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(meth.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(line.iter().map(|&p| Circle::new(p, 3, colour.filled())))
            .map_err(|x| e(&x))?;
        let timed: Vec<(f64, f64)> = ok
            .iter()
            .filter(|(r, _)| r.method == meth.label && r.mode == Mode::EqualTime)
            .map(|(_, m)| (m.seconds, m.metrics.mse))
            .collect();
        chart
            .draw_series(
                timed
                    .iter()
                    .map(|&p| Circle::new(p, 6, colour.stroke_width(1))),
            )
            .map_err(|x| e(&x))?;
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}
