//! The film: pbrt-v3's image film. Each sample is splatted into every pixel within the filter's
//! radius, weighted; a pixel's value is its weighted mean. Beside the splats it keeps each
//! pixel's own samples' count, sum and sum of squares, for the spp and variance AOVs and for
//! filters that reconstruct from per-pixel statistics.

use crate::cluster::grid::MAX_DIMS;
use crate::cluster::{CellGrid, CellSums, CellView};
use crate::first_hit::Features;
use crate::kernel::FilterKernel;
use crate::space::SamplePoint;
use acr_parser::{Error, PluginDesc, Result};
use glam::Vec2;

pub use crate::color::{luminance, Spectrum};

/// Entries per axis of the filter table (pbrt-v3's filterTableWidth).
const TABLE_SIZE: usize = 16;

/// Largest accepted resolution per axis: keeps a typo from allocating terabytes.
pub const MAX_RESOLUTION: u32 = 1 << 15;

/// Largest accepted number of rendered (cropped) pixels, 8192 x 8192: the film keeps about
/// 100 bytes per pixel, so this bounds it near 7 GiB before anything is allocated.
pub const MAX_PIXELS: u64 = 1 << 26;

/// Film settings from the `Film` directive.
#[derive(Clone, Debug)]
pub struct FilmSettings {
    /// Full image resolution.
    pub resolution: (u32, u32),
    /// Pixel bounds actually rendered: [x0, x1) x [y0, y1).
    pub crop: [u32; 4],
    /// Output file name from the scene ("string filename").
    pub filename: Option<String>,
    /// Scale applied to pixel values on output.
    pub scale: f32,
    /// Samples whose luminance exceeds this are scaled down to it (pbrt-v3's
    /// maxsampleluminance); infinite by default.
    pub max_sample_luminance: f32,
    /// Samples whose largest RGB component exceeds this are scaled down to it (pbrt-v4's
    /// maxcomponentvalue); infinite by default.
    pub max_component_value: f32,
}

impl FilmSettings {
    /// Reads the `Film` directive (pbrt-v3's defaults when absent).
    pub fn new(desc: Option<&PluginDesc>) -> Result<Self> {
        let Some(p) = desc else {
            return Ok(Self::with_resolution(1280, 720));
        };
        if p.kind != "image" {
            return Err(Error::at(
                &p.loc,
                format!("film \"{}\" is not supported (only \"image\")", p.kind),
            ));
        }
        let params = &p.params;
        let res = |name: &str, default: i32| -> Result<u32> {
            let v = params.int_or(name, default)?;
            if v < 1 || v as u32 > MAX_RESOLUTION {
                let loc = params.get(name).map_or(&p.loc, |x| &x.loc).clone();
                return Err(Error::at(
                    &loc,
                    format!("{name} {v} is out of range (1 to {MAX_RESOLUTION})"),
                ));
            }
            Ok(v as u32)
        };
        let mut s = Self::with_resolution(res("xresolution", 1280)?, res("yresolution", 720)?);
        if let Some(c) = params.floats("cropwindow")? {
            let loc = params.get("cropwindow").map_or(&p.loc, |x| &x.loc).clone();
            let window = <[f64; 4]>::try_from(c)
                .map_err(|_| Error::at(&loc, "\"cropwindow\" needs four values"))?;
            s.set_crop_window(window)
                .map_err(|e| Error::at(&loc, format!("\"cropwindow\" {e}")))?;
        }
        s.filename = params.string("filename")?.map(str::to_owned);
        s.scale = params.float_or("scale", 1.0)? as f32;
        let positive = |name: &str| -> Result<f32> {
            let v = params.float_or(name, f64::INFINITY)?;
            if v.is_nan() || v <= 0.0 {
                let loc = params.get(name).map_or(&p.loc, |x| &x.loc);
                return Err(Error::at(loc, format!("{name} must be positive, not {v}")));
            }
            Ok(v as f32)
        };
        s.max_sample_luminance = positive("maxsampleluminance")?;
        s.max_component_value = positive("maxcomponentvalue")?;
        let (w, h) = s.size();
        if u64::from(w) * u64::from(h) > MAX_PIXELS {
            let loc = params.get("xresolution").map_or(&p.loc, |x| &x.loc);
            return Err(Error::at(
                loc,
                format!(
                    "{w}x{h} = {} pixels to render is more than {MAX_PIXELS} (8192x8192); \
                     lower the resolution or set a cropwindow",
                    u64::from(w) * u64::from(h)
                ),
            ));
        }
        // Accepted, and meaningless for an RGB film.
        let _ = params.float("diagonal")?;
        Ok(s)
    }

    /// Crops to a window given in fractions of the image, [x0, x1, y0, y1] (pbrt-v3's
    /// `cropwindow`: the ceiling of each edge in raster space; values clamped to [0, 1]).
    pub fn set_crop_window(&mut self, window: [f64; 4]) -> std::result::Result<(), String> {
        let [x0, x1, y0, y1] = window.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) });
        let (w, h) = (self.resolution.0 as f64, self.resolution.1 as f64);
        self.set_pixel_bounds([
            (w * x0.min(x1)).ceil() as u32,
            (w * x0.max(x1)).ceil() as u32,
            (h * y0.min(y1)).ceil() as u32,
            (h * y0.max(y1)).ceil() as u32,
        ])
    }

    /// Crops to the pixels [x0, x1) x [y0, y1) (pbrt-v4's `--pixelbounds`), which must lie in
    /// the image and hold at least one pixel.
    pub fn set_pixel_bounds(&mut self, bounds: [u32; 4]) -> std::result::Result<(), String> {
        let [x0, x1, y0, y1] = bounds;
        let (w, h) = self.resolution;
        if x0 >= x1 || y0 >= y1 {
            return Err(format!("{x0},{x1},{y0},{y1} contains no pixel"));
        }
        if x1 > w || y1 > h {
            return Err(format!(
                "{x0},{x1},{y0},{y1} reaches beyond the {w}x{h} image"
            ));
        }
        if u64::from(x1 - x0) * u64::from(y1 - y0) > MAX_PIXELS {
            return Err(format!(
                "{x0},{x1},{y0},{y1} holds more than {MAX_PIXELS} pixels (8192x8192)"
            ));
        }
        self.crop = bounds;
        Ok(())
    }

    /// The defaults at a given resolution.
    pub fn with_resolution(x: u32, y: u32) -> Self {
        Self {
            resolution: (x, y),
            crop: [0, x, 0, y],
            filename: None,
            scale: 1.0,
            max_sample_luminance: f32::INFINITY,
            max_component_value: f32::INFINITY,
        }
    }

    /// A sample's radiance after the film's limits: scaled down so that its luminance is at
    /// most `maxsampleluminance` and its largest component at most `maxcomponentvalue`.
    #[inline]
    pub fn clamp(&self, l: Spectrum) -> Spectrum {
        let lum = luminance(l);
        let l = if lum > self.max_sample_luminance {
            l * (self.max_sample_luminance / lum)
        } else {
            l
        };
        let m = l.max_element();
        if m > self.max_component_value {
            l * (self.max_component_value / m)
        } else {
            l
        }
    }

    /// Width and height of the rendered (cropped) image.
    pub fn size(&self) -> (u32, u32) {
        (self.crop[1] - self.crop[0], self.crop[3] - self.crop[2])
    }
}

/// The relative error `--noise-threshold` measures for a pixel or a cell: the standard error of
/// its mean luminance over (that mean + 0.01), Cycles' and LuxCore's kind of measure; the 0.01
/// keeps black pixels from dominating.
pub fn relative_error_of(mean: f64, variance_of_mean: f64) -> f64 {
    variance_of_mean.max(0.0).sqrt() / (mean.max(0.0) + 0.01)
}

/// The samples drawn for one pixel (those whose raster position lies in it), unfiltered:
/// their count, mean and sum of squared deviations (Welford's running form, stable in f32).
/// Single precision halves the film's per-pixel statistics (28 bytes a pixel, not 56: 28 MB
/// less at 1152x864); the sums a mergeable file needs are rebuilt from them in f64.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelStats {
    /// How many.
    pub count: u32,
    mean: [f32; 3],
    m2: [f32; 3],
}

impl PixelStats {
    /// Adds one sample's radiance.
    #[inline]
    pub fn add(&mut self, l: Spectrum) {
        self.count += 1;
        let inv = 1.0 / self.count as f32;
        for (c, v) in [l.x, l.y, l.z].into_iter().enumerate() {
            let delta = v - self.mean[c];
            self.mean[c] += delta * inv;
            self.m2[c] += delta * (v - self.mean[c]);
        }
    }

    /// The mean radiance (zero without samples).
    pub fn mean(&self) -> Spectrum {
        Spectrum::from_array(self.mean)
    }

    /// The sum of the samples' radiance, per channel.
    pub fn sum(&self) -> [f64; 3] {
        let n = f64::from(self.count);
        self.mean.map(|m| f64::from(m) * n)
    }

    /// The sum of the samples' squared radiance, per channel.
    pub fn sum_sq(&self) -> [f64; 3] {
        let n = f64::from(self.count);
        std::array::from_fn(|c| {
            let m = f64::from(self.mean[c]);
            f64::from(self.m2[c].max(0.0)) + n * m * m
        })
    }

    /// The variance of the mean per channel: the unbiased sample variance over the count
    /// (zero with fewer than two samples, where it cannot be estimated).
    pub fn variance_of_mean(&self) -> Spectrum {
        if self.count < 2 {
            return Spectrum::ZERO;
        }
        let n = self.count as f32;
        Spectrum::from_array(self.m2.map(|m2| m2.max(0.0) / (n - 1.0) / n))
    }
}

/// Accumulated, filtered samples.
#[derive(Clone, Debug)]
pub struct Film {
    settings: FilmSettings,
    splat: Splat,
    sums: Vec<[f64; 4]>,
    stats: Vec<PixelStats>,
    /// [`Film::add_samples`]'s prepared samples, kept to reuse the allocation.
    prepared: Vec<Prepared>,
    /// Per-cell sums over the rendering space, for a reconstruction that fits cells when the
    /// sampler keeps none ([`Film::collect_cells`]).
    cells: Option<(CellGrid, CellSums)>,
    /// The cell and offsets of each point of the batch being added (reused).
    located: Vec<(u32, [f32; MAX_DIMS])>,
    /// The two streams' films, when the samples come in two ([`Film::split_streams`]): the
    /// splats and cells go there, and this film keeps the pixel statistics of both.
    halves: Option<Box<[Film; 2]>>,
    /// The first stream's weight in the image, when split (the second's is 1 minus it).
    first_weight: f64,
}

/// Film columns a [`Prepared`] sample can reach: enough for filters of radius up to 3.5
/// pixels (wider ones splat through [`Splat::row`]).
const MAX_SPAN: usize = 8;

/// A sample ready to splat: what does not depend on the film row (the radiance, the
/// columns reached and their filter-table columns), computed once for the several rows a
/// sample reaches.
#[derive(Clone, Copy, Debug)]
struct Prepared {
    /// Raster position.
    p: Vec2,
    /// Radiance.
    l: Spectrum,
    /// First film column reached (within the crop).
    x0: i64,
    /// Number of columns reached.
    n: u8,
    /// Filter-table column of each column reached.
    fx: [u8; MAX_SPAN],
}

/// How one sample spreads over a film row: the kernel tabulated over one quadrant of its
/// support, as pbrt-v3 does (evaluating exp() or a polynomial for each of a sample's up to 25
/// pixels would cost more than tracing it), the radius and the crop's columns.
#[derive(Clone, Debug)]
struct Splat {
    table: [f32; TABLE_SIZE * TABLE_SIZE],
    radius: (f32, f32),
    columns: (i64, i64),
}

impl Splat {
    /// Adds the contributions of the sample at `p` to film row `y` (`row` is its pixels).
    #[inline]
    fn row(&self, row: &mut [[f64; 4]], y: i64, p: Vec2, l: Spectrum) {
        let (rx, ry) = self.radius;
        let (cx0, cx1) = self.columns;
        let (dx, dy) = (p.x - 0.5, p.y - 0.5);
        let ay = (y as f32 - dy).abs();
        if ay > ry {
            return;
        }
        let fy = ((ay / ry * TABLE_SIZE as f32) as usize).min(TABLE_SIZE - 1);
        let table_row = &self.table[fy * TABLE_SIZE..][..TABLE_SIZE];
        let x0 = ((dx - rx).ceil() as i64).max(cx0);
        let x1 = ((dx + rx).floor() as i64 + 1).min(cx1);
        for x in x0..x1 {
            let fx = ((x as f32 - dx).abs() / rx * TABLE_SIZE as f32) as usize;
            let weight = table_row[fx.min(TABLE_SIZE - 1)];
            if weight != 0.0 {
                let s = &mut row[(x - cx0) as usize];
                let wf = weight as f64;
                s[0] += wf * l.x as f64;
                s[1] += wf * l.y as f64;
                s[2] += wf * l.z as f64;
                s[3] += wf;
            }
        }
    }

    /// Whether to splat through [`Prepared`] samples: when a sample reaches several rows (so
    /// that preparing it pays) and every sample's columns fit one.
    fn prepare_pays(&self) -> bool {
        self.radius.1 > 0.5 && 2.0 * self.radius.0 + 1.0 <= MAX_SPAN as f32
    }

    /// The row-independent part of [`Splat::row`] for the sample at `p` (the same values);
    /// the filter must fit ([`Splat::prepare_pays`]).
    #[inline]
    fn prepare(&self, p: Vec2, l: Spectrum) -> Prepared {
        let rx = self.radius.0;
        let (cx0, cx1) = self.columns;
        let dx = p.x - 0.5;
        let x0 = ceil_i64(dx - rx).max(cx0);
        let x1 = floor_i64(dx + rx).saturating_add(1).min(cx1);
        let mut fx = [0u8; MAX_SPAN];
        let mut n = 0u8;
        for (slot, x) in fx.iter_mut().zip(x0..x1) {
            *slot = table_index((x as f32 - dx).abs() / rx);
            n += 1;
        }
        Prepared { p, l, x0, n, fx }
    }

    /// [`Splat::row`] for a prepared sample: the same contributions, in the same order.
    #[inline]
    fn row_prepared(&self, row: &mut [[f64; 4]], y: i64, s: &Prepared) {
        let ry = self.radius.1;
        let ay = (y as f32 - (s.p.y - 0.5)).abs();
        if ay > ry || s.n == 0 {
            return;
        }
        let fy = table_index(ay / ry) as usize;
        let table_row = &self.table[fy * TABLE_SIZE..][..TABLE_SIZE];
        let start = (s.x0 - self.columns.0) as usize;
        let cells = &mut row[start..start + s.n as usize];
        for (cell, &fx) in cells.iter_mut().zip(&s.fx) {
            let weight = table_row[fx as usize];
            if weight != 0.0 {
                let wf = weight as f64;
                cell[0] += wf * s.l.x as f64;
                cell[1] += wf * s.l.y as f64;
                cell[2] += wf * s.l.z as f64;
                cell[3] += wf;
            }
        }
    }
}

/// The filter-table entry for a distance `r` in units of the filter radius (r >= 0, not NaN):
/// `min(floor(r * TABLE_SIZE), TABLE_SIZE - 1)`, clamping before the conversion (the same
/// value for such `r`) so that it is one narrow conversion instead of a saturating one to usize.
#[inline]
fn table_index(r: f32) -> u8 {
    (r * TABLE_SIZE as f32).min((TABLE_SIZE - 1) as f32) as u8
}

/// `v.ceil() as i64` without a libm call (baseline x86-64 has no rounding instruction).
#[inline]
fn ceil_i64(v: f32) -> i64 {
    let t = v as i64;
    if (t as f32) < v {
        t.saturating_add(1)
    } else {
        t
    }
}

/// `v.floor() as i64` without a libm call.
#[inline]
fn floor_i64(v: f32) -> i64 {
    let t = v as i64;
    if (t as f32) > v {
        t.saturating_sub(1)
    } else {
        t
    }
}

impl Film {
    /// An empty film.
    pub fn new(settings: FilmSettings, kernel: &dyn FilterKernel) -> Self {
        let (w, h) = settings.size();
        let (rx, ry) = kernel.radius();
        let mut table = [0.0f32; TABLE_SIZE * TABLE_SIZE];
        for (i, t) in table.iter_mut().enumerate() {
            let (x, y) = (i % TABLE_SIZE, i / TABLE_SIZE);
            *t = kernel.eval(
                (x as f32 + 0.5) * rx / TABLE_SIZE as f32,
                (y as f32 + 0.5) * ry / TABLE_SIZE as f32,
            );
        }
        let [cx0, cx1, _, _] = settings.crop;
        Self {
            sums: vec![[0.0; 4]; w as usize * h as usize],
            stats: vec![PixelStats::default(); w as usize * h as usize],
            splat: Splat {
                table,
                radius: (rx, ry),
                columns: (cx0 as i64, cx1 as i64),
            },
            settings,
            prepared: Vec::new(),
            cells: None,
            located: Vec::new(),
            halves: None,
            first_weight: 0.5,
        }
    }

    /// Keeps the two sample streams of a paired sampler apart (a sample's stream is its
    /// index's parity): each gets a film of its own, and the image is their blend with the
    /// fixed weights `first_weight` and 1 minus it, so that neither stream's share of a pixel
    /// depends on the values. Called before any sample is added.
    pub fn split_streams(&mut self, first_weight: f64) {
        self.first_weight = first_weight.clamp(0.0, 1.0);
        if self.halves.is_some() {
            return;
        }
        let half = self.clone();
        // The splats and cells live in the halves only.
        self.cells = None;
        self.sums = Vec::new();
        self.halves = Some(Box::new([half.clone(), half]));
    }

    /// The two streams' films, when split.
    pub fn halves(&self) -> Option<&[Film; 2]> {
        self.halves.as_deref()
    }

    /// The image `image` makes of this film, or when it is split, the blend of the images it
    /// makes of each stream's film (`image` gets the stream's number) with the weights of
    /// [`Film::split_streams`]. A pixel one stream left without a sample (a time limit that
    /// stopped it, dropped samples) takes the other's alone.
    pub fn per_stream(&self, image: impl Fn(&Film, usize) -> Vec<Spectrum>) -> Vec<Spectrum> {
        match self.halves() {
            Some([a, b]) => {
                let w = self.first_weight as f32;
                image(a, 0)
                    .into_iter()
                    .zip(image(b, 1))
                    .zip(a.stats.iter().zip(&b.stats))
                    .map(|((x, y), (sa, sb))| match (sa.count, sb.count) {
                        (0, n) if n > 0 => y,
                        (n, 0) if n > 0 => x,
                        _ => x * w + y * (1.0 - w),
                    })
                    .collect()
            }
            None => image(self, 0),
        }
    }

    /// Adds samples of stream `stream` (raster position and radiance, sorted by row) to that
    /// stream's film, and their statistics to this one's; the same as
    /// [`Film::add_samples`] when the film is not split.
    pub fn add_stream_samples(&mut self, stream: usize, samples: &[(Vec2, Spectrum)]) {
        match self.halves.as_mut() {
            Some(h) => {
                h[stream & 1].add_samples(samples);
                self.add_stats(samples);
            }
            None => self.add_samples(samples),
        }
    }

    /// Makes the film also keep running sums per cell of `grid` ([`Film::add_points`]), with
    /// the samples' first-hit features when `features`.
    pub fn collect_cells(&mut self, grid: CellGrid, features: bool) {
        let sums = CellSums::new(&grid);
        let sums = if features { sums.with_features() } else { sums };
        self.cells = Some((grid, sums));
    }

    /// Adds each point of `batch` with its radiance (and first-hit features, when given) to
    /// its cell, when the film collects cells; NaN radiance marks a dropped sample and is
    /// skipped.
    pub fn add_points(
        &mut self,
        batch: &[SamplePoint],
        radiance: &[[f32; 3]],
        features: Option<&[Features]>,
    ) {
        if let Some(h) = self.halves.as_mut() {
            // Each stream's points to its own film's cells, in order.
            for (s, half) in h.iter_mut().enumerate() {
                let keep = |k: &usize| batch[*k].index as usize & 1 == s;
                let ks: Vec<usize> = (0..batch.len()).filter(keep).collect();
                let b: Vec<SamplePoint> = ks.iter().map(|&k| batch[k]).collect();
                let r: Vec<[f32; 3]> = ks.iter().map(|&k| radiance[k]).collect();
                let f: Option<Vec<Features>> = features.map(|f| ks.iter().map(|&k| f[k]).collect());
                half.add_points(&b, &r, f.as_deref());
            }
            return;
        }
        let Some((grid, sums)) = self.cells.as_mut() else {
            return;
        };
        grid.locate_all(batch, &mut self.located);
        sums.add_batch(&self.located, radiance, features);
    }

    /// Whether the film's cells keep the samples' first-hit features ([`Film::collect_cells`]).
    pub fn collects_features(&self) -> bool {
        if let Some(h) = &self.halves {
            return h[0].collects_features();
        }
        self.cells
            .as_ref()
            .is_some_and(|(_, sums)| sums.keeps_features())
    }

    /// The film's cells, when it collects them.
    pub fn cells(&self) -> Option<CellView<'_>> {
        self.cells.as_ref().map(|(grid, sums)| CellView {
            grid,
            sums,
            clustering: None,
        })
    }

    /// The settings it was made with.
    pub fn settings(&self) -> &FilmSettings {
        &self.settings
    }

    /// Adds a sample at raster position `p` (full-resolution pixels) with radiance `l`, into
    /// every pixel whose centre is within the filter radius (pbrt-v3's Film::AddSample, with
    /// its tabulated filter). The radiance is taken as given: the render loop applies the
    /// film's limits ([`FilmSettings::clamp`]) once, before the sampler, the cells and the film
    /// see a sample.
    pub fn add_sample(&mut self, p: Vec2, l: Spectrum) {
        let [_, _, cy0, cy1] = self.settings.crop;
        let ry = self.splat.radius.1;
        let dy = p.y - 0.5;
        let y0 = ((dy - ry).ceil() as i64).max(cy0 as i64);
        let y1 = ((dy + ry).floor() as i64 + 1).min(cy1 as i64);
        let w = self.settings.size().0 as usize;
        if let Some(i) = self.pixel_index(p) {
            self.stats[i].add(l);
        }
        for y in y0..y1 {
            let start = (y - cy0 as i64) as usize * w;
            self.splat.row(&mut self.sums[start..start + w], y, p, l);
        }
    }

    /// Adds samples in order: each pixel receives its contributions in the order given, so the
    /// result equals adding them one by one, whatever the thread count. The samples must be
    /// sorted by raster row (`floor(p.y)`), as the render loop produces them; rows are then
    /// filled in parallel, each from the samples within the filter's reach.
    pub fn add_samples(&mut self, samples: &[(Vec2, Spectrum)]) {
        use rayon::prelude::*;
        debug_assert!(samples
            .windows(2)
            .all(|w| w[0].0.y.floor() <= w[1].0.y.floor()));
        let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
            return;
        };
        self.add_stats(samples);
        let cy0 = self.settings.crop[2] as i64;
        let ry = self.splat.radius.1;
        // Sorted by whole rows only: the extreme positions are bounded by the rows' edges.
        let (lo, hi) = (first.0.y.floor() - 0.5 - ry, last.0.y.floor() + 0.5 + ry);
        let w = self.settings.size().0 as usize;
        let splat = &self.splat;
        if splat.prepare_pays() {
            samples
                .par_iter()
                .map(|&(p, l)| splat.prepare(p, l))
                .collect_into_vec(&mut self.prepared);
            let prepared = &self.prepared;
            self.sums
                .par_chunks_mut(w)
                .enumerate()
                .for_each(|(row_index, row)| {
                    let y = row_index as i64 + cy0;
                    let yf = y as f32;
                    if yf < lo || yf > hi {
                        return;
                    }
                    // As below.
                    let (top, bottom) = ((yf + 0.5 - ry).floor(), (yf + 0.5 + ry).floor());
                    let from = prepared.partition_point(|s| s.p.y.floor() < top);
                    let to = prepared.partition_point(|s| s.p.y.floor() <= bottom);
                    for s in &prepared[from..to] {
                        splat.row_prepared(row, y, s);
                    }
                });
            return;
        }
        self.sums
            .par_chunks_mut(w)
            .enumerate()
            .for_each(|(row_index, row)| {
                let y = row_index as i64 + cy0;
                let yf = y as f32;
                if yf < lo || yf > hi {
                    return;
                }
                // A superset, by whole raster rows (monotone in the sorted samples), of the
                // samples whose filter reaches row y (|y - (p.y - 0.5)| <= ry).
                let (top, bottom) = ((yf + 0.5 - ry).floor(), (yf + 0.5 + ry).floor());
                let from = samples.partition_point(|(p, _)| p.y.floor() < top);
                let to = samples.partition_point(|(p, _)| p.y.floor() <= bottom);
                for &(p, l) in &samples[from..to] {
                    splat.row(row, y, p, l);
                }
            });
    }

    /// Adds row-sorted samples to the statistics of the pixels they lie in, rows in parallel.
    fn add_stats(&mut self, samples: &[(Vec2, Spectrum)]) {
        use rayon::prelude::*;
        let [cx0, cx1, cy0, _] = self.settings.crop;
        let w = (cx1 - cx0) as usize;
        self.stats
            .par_chunks_mut(w)
            .enumerate()
            .for_each(|(row_index, row)| {
                let y = (row_index as u32 + cy0) as f32;
                let from = samples.partition_point(|(p, _)| p.y.floor() < y);
                let to = samples.partition_point(|(p, _)| p.y.floor() <= y);
                for &(p, l) in &samples[from..to] {
                    let x = p.x.floor();
                    if x >= cx0 as f32 && x < cx1 as f32 {
                        row[(x - cx0 as f32) as usize].add(l);
                    }
                }
            });
    }

    /// The index into the cropped image of the pixel holding raster position `p`, if any.
    fn pixel_index(&self, p: Vec2) -> Option<usize> {
        let [cx0, cx1, cy0, cy1] = self.settings.crop;
        let (x, y) = (p.x.floor(), p.y.floor());
        let inside = x >= cx0 as f32 && x < cx1 as f32 && y >= cy0 as f32 && y < cy1 as f32;
        inside.then(|| (y as u32 - cy0) as usize * (cx1 - cx0) as usize + (x as u32 - cx0) as usize)
    }

    /// Each pixel's own samples, row-major over the cropped image.
    pub fn pixel_stats(&self) -> &[PixelStats] {
        &self.stats
    }

    /// Each pixel's filter-weighted sums of radiance and its sum of filter weights, [r, g, b,
    /// w], row-major: what renders of different sample ranges add to merge (`None` when the
    /// streams are split: the image is then a mean of two films).
    pub fn weighted_sums(&self) -> Option<&[[f64; 4]]> {
        self.halves.is_none().then_some(self.sums.as_slice())
    }

    /// Frees the filter-weighted sums (and the streams' films), once the image is made and
    /// nothing will merge them: they are the largest part of the film (32 bytes a pixel), and
    /// the output is written after. [`Film::pixels`] and [`Film::weighted_sums`] are then empty.
    pub fn release_sums(&mut self) {
        self.sums = Vec::new();
        self.halves = None;
    }

    /// The splatted image: each pixel's weighted mean, row-major, top row first (the film's
    /// `scale` is applied on output, not here).
    pub fn pixels(&self) -> Vec<Spectrum> {
        if self.halves.is_some() {
            return self.per_stream(|f, _| f.pixels());
        }
        self.sums
            .iter()
            .map(|s| {
                if s[3] != 0.0 {
                    let inv = 1.0 / s[3];
                    // Negative lobes (Mitchell, sinc) can make a mean slightly negative.
                    Spectrum::new(
                        (s[0] * inv) as f32,
                        (s[1] * inv) as f32,
                        (s[2] * inv) as f32,
                    )
                    .max(Spectrum::ZERO)
                } else {
                    Spectrum::ZERO
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filters::{BoxFilter, GaussianFilter};

    /// The f32 running statistics agree with sums in f64, also where the mean is large against
    /// the spread (where E[x^2] - E[x]^2 in f32 would cancel to noise): the variance within
    /// 0.5% when the spread is 1e-5 of the level (pbrt-v4 keeps its variance in f32 too),
    /// 0.1% otherwise.
    #[test]
    fn pixel_statistics_keep_their_precision() {
        for (level, spread, tolerance) in [
            (1000.0f64, 0.01f64, 5e-3),
            (0.5, 0.4, 1e-3),
            (1e-3, 1e-3, 1e-3),
        ] {
            let mut stats = PixelStats::default();
            let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
            let n = 10_000;
            for i in 0..n {
                // A deterministic, irregular sequence around `level`.
                let x = (level + spread * ((i as f64 * 0.618_034).fract() - 0.5)) as f32;
                stats.add(Spectrum::new(x, x, x));
                sum += f64::from(x);
                sum_sq += f64::from(x) * f64::from(x);
            }
            let mean = sum / n as f64;
            let var_of_mean = (sum_sq / n as f64 - mean * mean) / (n as f64 - 1.0);
            let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
            assert!(rel(f64::from(stats.mean().x), mean) < 1e-6, "{level}");
            assert!(rel(stats.sum()[0], sum) < 1e-6, "{level}");
            assert!(rel(stats.sum_sq()[0], sum_sq) < 1e-6, "{level}");
            let v = f64::from(stats.variance_of_mean().x);
            assert!(
                rel(v, var_of_mean) < tolerance,
                "{level}: {v} against {var_of_mean}"
            );
        }
    }

    #[test]
    fn integer_rounding_matches_libm() {
        let values = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.5,
            -1.5,
            2.999_999_8,
            -2.999_999_8,
            1e7 + 0.5,
            3.0e9,
            -3.0e9,
            1e30,
            -1e30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        for v in values {
            assert_eq!(ceil_i64(v), v.ceil() as i64, "ceil {v}");
            assert_eq!(floor_i64(v), v.floor() as i64, "floor {v}");
        }
        for r in [
            0.0f32,
            0.03,
            0.5,
            0.937_5,
            0.999_99,
            1.0,
            1.2,
            1e9,
            f32::INFINITY,
        ] {
            let want = ((r * TABLE_SIZE as f32) as usize).min(TABLE_SIZE - 1);
            assert_eq!(table_index(r) as usize, want, "{r}");
        }
    }

    /// Releasing the sums frees them and keeps the per-pixel statistics the output still reads.
    #[test]
    fn released_sums_leave_the_statistics() {
        let mut f = Film::new(
            FilmSettings::with_resolution(2, 1),
            &BoxFilter::new(0.5, 0.5),
        );
        f.add_sample(Vec2::new(0.25, 0.5), Spectrum::splat(1.0));
        f.add_sample(Vec2::new(1.5, 0.5), Spectrum::splat(5.0));
        let stats = f.pixel_stats().to_vec();
        f.release_sums();
        assert_eq!(f.weighted_sums(), Some(&[][..]));
        assert!(f.pixels().is_empty());
        assert_eq!(f.pixel_stats(), &stats[..]);
    }

    #[test]
    fn box_filter_averages_samples_in_the_pixel() {
        let mut f = Film::new(
            FilmSettings::with_resolution(2, 1),
            &BoxFilter::new(0.5, 0.5),
        );
        f.add_sample(Vec2::new(0.25, 0.5), Spectrum::splat(1.0));
        f.add_sample(Vec2::new(0.75, 0.5), Spectrum::splat(3.0));
        f.add_sample(Vec2::new(1.5, 0.5), Spectrum::splat(5.0));
        let p = f.pixels();
        assert_eq!(p[0], Spectrum::splat(2.0));
        assert_eq!(p[1], Spectrum::splat(5.0));
        let st = f.pixel_stats();
        assert_eq!((st[0].count, st[1].count), (2, 1));
        assert_eq!(st[0].mean(), Spectrum::splat(2.0));
        // Samples 1 and 3: sample variance 2, variance of the mean 1.
        assert_eq!(st[0].variance_of_mean(), Spectrum::splat(1.0));
        assert_eq!(st[1].variance_of_mean(), Spectrum::ZERO);
    }

    #[test]
    fn batch_adding_equals_one_by_one() {
        use crate::filters::MitchellFilter;
        let kernel = MitchellFilter::new(2.0, 1.5, 1.0 / 3.0, 1.0 / 3.0);
        let mut s = FilmSettings::with_resolution(9, 7);
        s.crop = [1, 8, 1, 6];
        let mut one = Film::new(s.clone(), &kernel);
        let mut batch = Film::new(s, &kernel);
        // Row-sorted samples, several per pixel, with varied values.
        let mut samples = Vec::new();
        for py in 0..7u32 {
            for px in 0..9u32 {
                for k in 0..3u32 {
                    let u = Vec2::new(
                        (k as f32 * 0.37 + px as f32 * 0.11) % 1.0,
                        (k as f32 * 0.61) % 1.0,
                    );
                    let l = Spectrum::new(px as f32, py as f32, k as f32 + 1.0);
                    samples.push((Vec2::new(px as f32, py as f32) + u, l));
                }
            }
        }
        for &(p, l) in &samples {
            one.add_sample(p, l);
        }
        batch.add_samples(&samples[..100]);
        batch.add_samples(&samples[100..]);
        assert_eq!(one.pixels(), batch.pixels());
        assert_eq!(one.pixel_stats(), batch.pixel_stats());
        assert_eq!(batch.pixel_stats()[0].count, 3);
    }

    #[test]
    fn wide_filter_reaches_neighbours_and_crop_limits_output() {
        let mut s = FilmSettings::with_resolution(4, 4);
        s.crop = [1, 3, 1, 3];
        let mut f = Film::new(s, &GaussianFilter::new(2.0, 2.0, 2.0));
        f.add_sample(Vec2::new(1.5, 1.5), Spectrum::new(1.0, 2.0, 3.0));
        let p = f.pixels();
        assert_eq!(p.len(), 4);
        for v in p {
            assert!((v - Spectrum::new(1.0, 2.0, 3.0)).length() < 1e-6);
        }
    }
}
