//! The film: pbrt-v3's image film. Each sample is splatted into every pixel within the filter's
//! radius, weighted; a pixel's value is its weighted mean. Beside the splats it keeps each
//! pixel's own samples' count, sum and sum of squares, for the spp and variance AOVs and for
//! filters that reconstruct from per-pixel statistics. A film that keeps half buffers for its
//! filter keeps neither: the pixel statistics, the image and the sums are read from the halves.

use crate::cells::grid::MAX_DIMS;
use crate::cells::{CellGrid, CellSums, CellView};
use crate::first_hit::Features;
use crate::kernel::FilterKernel;
use crate::space::SamplePoint;
use glam::Vec2;
use std::borrow::Cow;

pub use crate::color::{luminance, Spectrum};
pub use buffers::{HalfPixel, PixelBuffers};
pub use settings::{FilmSettings, MAX_PIXELS, MAX_RESOLUTION};
use splat::{Prepared, Splat, TABLE_SIZE};
pub use stats::{relative_error_of, PixelStats};
pub use unfiltered::UnfilteredSplats;

mod buffers;
mod half_float;
mod settings;
mod splat;
mod stats;
mod unfiltered;

/// Accumulated, filtered samples.
#[derive(Clone, Debug)]
pub struct Film {
    settings: FilmSettings,
    splat: Splat,
    sums: Vec<[f64; 4]>,
    stats: Vec<PixelStats>,
    /// Each pixel's own samples' count alone, when the film keeps no means nor deviations
    /// ([`Film::count_only`]); `stats` is then empty.
    counts: Option<Vec<u32>>,
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
    /// Per-pixel half buffers, for a filter that reads them ([`Film::keep_pixel_buffers`]).
    buffers: Option<Box<PixelBuffers>>,
    /// Unfiltered splats (light tracing, mlt, sppm), added to the reconstructed image.
    unfiltered: UnfilteredSplats,
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
            counts: None,
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
            buffers: None,
            unfiltered: UnfilteredSplats::default(),
        }
    }

    /// Adds unfiltered splats, each to the one pixel holding its raster position (pbrt-v3's
    /// `Film::AddSplat`); those outside the crop are dropped, those not finite or negative
    /// dropped and counted. In the order given, so the sums do not depend on thread count.
    pub fn add_splats(&mut self, splats: &[(Vec2, Spectrum)]) {
        let crop = self.settings.crop;
        let (w, h) = self.settings.size();
        let pixels = w as usize * h as usize;
        for &(p, l) in splats {
            if let Some(i) = unfiltered::splat_index(crop, p) {
                self.unfiltered.add(pixels, i, l);
            }
        }
    }

    /// The unfiltered splats: their sums and scale.
    pub fn unfiltered(&self) -> &UnfilteredSplats {
        &self.unfiltered
    }

    /// The unfiltered splats, to set their scale or merge sums into them.
    pub fn unfiltered_mut(&mut self) -> &mut UnfilteredSplats {
        &mut self.unfiltered
    }

    /// `image` (a reconstruction of this film, row-major over the crop, before the film's
    /// `scale`) with the unfiltered splats added.
    pub fn with_splats(&self, mut image: Vec<Spectrum>) -> Vec<Spectrum> {
        self.unfiltered.add_to(&mut image);
        image
    }

    /// Makes the film keep each pixel's two halves of samples (by index parity) with their
    /// colour and first-hit features ([`PixelBuffers`]); the render loop then computes the
    /// features of every sample. The halves hold all the film would: it keeps no splats nor
    /// pixel statistics of its own (60 bytes a pixel), and [`Film::pixel_stats`],
    /// [`Film::pixels`] and [`Film::weighted_sums`] are computed from the halves (the kernel
    /// is then a box of one pixel). Called before any sample is added.
    pub fn keep_pixel_buffers(&mut self) {
        // Freed before the buffers are made, so that the peak holds one or the other.
        self.sums = Vec::new();
        self.stats = Vec::new();
        self.counts = None;
        let [cx0, _, cy0, _] = self.settings.crop;
        let (w, h) = self.settings.size();
        self.buffers = Some(Box::new(PixelBuffers::new(w, h, [cx0, cy0])));
    }

    /// Makes the film count each pixel's own samples alone, without their mean and squared
    /// deviations (4 bytes a pixel, not 28: 16 MiB less at 1000x676), for a render where
    /// nothing reads those: no variance AOV, noise threshold, adaptive sampler, filter of
    /// pixel means, nor file of mergeable sums (a render stopped by a signal then writes its
    /// sums without the moments). [`Film::pixel_stats`] then gives the counts with zero
    /// moments. Called before any sample is added; a film with half buffers or split streams
    /// keeps what it has.
    pub fn count_only(&mut self) {
        if self.buffers.is_some() || self.halves.is_some() {
            return;
        }
        let n = self.stats.len();
        self.stats = Vec::new();
        self.counts = Some(vec![0; n]);
    }

    /// Whether the film keeps its pixels' sample means and deviations (not only their counts,
    /// [`Film::count_only`]).
    pub fn keeps_moments(&self) -> bool {
        self.counts.is_none()
    }

    /// The per-pixel half buffers, when kept.
    pub fn pixel_buffers(&self) -> Option<&PixelBuffers> {
        self.buffers.as_deref()
    }

    /// Sets the half buffers' depth scale ([`PixelBuffers::set_depth_scale`]), when kept.
    pub fn set_depth_scale(&mut self, scale: f32) {
        if let Some(b) = self.buffers.as_mut() {
            b.set_depth_scale(scale);
        }
    }

    /// A render by bands (docs/reconstruction.md, "Rendering by bands"): the half buffers hold
    /// the rows under way only, room made for `window` rows, and of the rows released each
    /// pixel's statistics when `keep_stats` (the variance AOV reads them), else its
    /// count ([`PixelBuffers::hold_rows`]). Called before any sample is added.
    pub fn hold_rows(&mut self, keep_stats: bool, window: usize) {
        if let Some(b) = self.buffers.as_mut() {
            b.hold_rows(keep_stats, window);
        }
    }

    /// [`Film::keep_pixel_buffers`] for a render by bands ([`Film::hold_rows`]), the whole
    /// image's halves never made.
    pub fn keep_pixel_buffers_by_rows(&mut self, keep_stats: bool, window: usize) {
        self.sums = Vec::new();
        self.stats = Vec::new();
        let [cx0, _, cy0, _] = self.settings.crop;
        let (w, h) = self.settings.size();
        self.buffers = Some(Box::new(PixelBuffers::by_rows_of(
            w,
            h,
            [cx0, cy0],
            keep_stats,
            window,
        )));
    }

    /// In a render by bands, makes the half buffers hold every row above crop row `row`
    /// ([`PixelBuffers::hold_through`]).
    pub fn hold_through(&mut self, row: usize) {
        if let Some(b) = self.buffers.as_mut() {
            b.hold_through(row);
        }
    }

    /// In a render by bands, frees the half buffers' rows above crop row `row`.
    pub fn release_rows(&mut self, row: usize) {
        if let Some(b) = self.buffers.as_mut() {
            b.release_rows(row);
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
        if let Some(c) = self.counts.take() {
            // Each stream's film keeps its own statistics, which the blend reads.
            self.stats = vec![PixelStats::default(); c.len()];
        }
        // The half buffers stay here: they hold both streams already.
        let buffers = self.buffers.take();
        let half = self.clone();
        self.buffers = buffers;
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
        if self.buffers.is_some() {
            // The half buffers took them in [`Film::add_points`].
            return;
        }
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
        if let Some(b) = self.buffers.as_mut() {
            b.add(batch, radiance, features);
        }
        // The cells see features only when they keep them.
        let features = features.filter(|_| self.cells_keep_features());
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

    /// Whether the film needs the samples' first-hit features: its cells keep them
    /// ([`Film::collect_cells`]) or it keeps half buffers ([`Film::keep_pixel_buffers`]).
    pub fn collects_features(&self) -> bool {
        self.buffers.is_some() || self.cells_keep_features()
    }

    /// Whether the film's cells (or its streams' cells) keep first-hit features.
    fn cells_keep_features(&self) -> bool {
        if let Some(h) = &self.halves {
            return h[0].cells_keep_features();
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
        if self.buffers.is_some() {
            // With half buffers, samples come in with their index through add_points.
            return;
        }
        let [_, _, cy0, cy1] = self.settings.crop;
        let ry = self.splat.radius.1;
        let dy = p.y - 0.5;
        let y0 = ((dy - ry).ceil() as i64).max(cy0 as i64);
        let y1 = ((dy + ry).floor() as i64 + 1).min(cy1 as i64);
        let w = self.settings.size().0 as usize;
        if let Some(i) = self.pixel_index(p) {
            match &mut self.counts {
                Some(c) => c[i] += 1,
                None => self.stats[i].add(l),
            }
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
        if self.buffers.is_some() {
            // The half buffers took them in [`Film::add_points`].
            return;
        }
        self.add_stats(samples);
        let cy0 = self.settings.crop[2] as i64;
        let ry = self.splat.radius.1;
        // Sorted by whole rows only: the extreme positions are bounded by the rows' edges.
        let (lo, hi) = (first.0.y.floor() - 0.5 - ry, last.0.y.floor() + 0.5 + ry);
        let w = self.settings.size().0 as usize;
        let splat = &self.splat;
        let rows = RowSplat {
            width: w,
            first_row: cy0,
            reach: (lo, hi),
            radius: ry,
        };
        if splat.prepare_pays() {
            samples
                .par_iter()
                .map(|&(p, l)| splat.prepare(p, l))
                .collect_into_vec(&mut self.prepared);
            rows.splat(
                &mut self.sums,
                &self.prepared,
                |s| s.p.y,
                |row, y, s| splat.row_prepared(row, y, s),
            );
        } else {
            rows.splat(
                &mut self.sums,
                samples,
                |&(p, _)| p.y,
                |row, y, &(p, l)| splat.row(row, y, p, l),
            );
        }
    }

    /// Adds row-sorted samples to the statistics (or the counts) of the pixels they lie in,
    /// rows in parallel.
    fn add_stats(&mut self, samples: &[(Vec2, Spectrum)]) {
        let crop = self.settings.crop;
        match &mut self.counts {
            Some(c) => add_by_row(c, crop, samples, |n, _| *n += 1),
            None => add_by_row(&mut self.stats, crop, samples, |s, l| s.add(l)),
        }
    }

    /// The index into the cropped image of the pixel holding raster position `p`, if any.
    fn pixel_index(&self, p: Vec2) -> Option<usize> {
        let [cx0, cx1, cy0, cy1] = self.settings.crop;
        let (x, y) = (p.x.floor(), p.y.floor());
        let inside = x >= cx0 as f32 && x < cx1 as f32 && y >= cy0 as f32 && y < cy1 as f32;
        inside.then(|| (y as u32 - cy0) as usize * (cx1 - cx0) as usize + (x as u32 - cx0) as usize)
    }

    /// Each pixel's own samples, row-major over the cropped image: computed from the half
    /// buffers when the film keeps them; their counts alone, moments zero, when it counts
    /// them only ([`Film::count_only`]).
    pub fn pixel_stats(&self) -> Cow<'_, [PixelStats]> {
        match (&self.buffers, &self.counts) {
            (Some(b), _) => Cow::Owned(b.pixel_stats()),
            (None, Some(c)) => Cow::Owned(c.iter().map(|&n| PixelStats::counted(n)).collect()),
            (None, None) => Cow::Borrowed(&self.stats),
        }
    }

    /// How many of its own samples each pixel has, row-major over the cropped image (what
    /// [`Film::pixel_stats`] counts, without making the statistics of a film that counts
    /// them only).
    pub fn pixel_counts(&self) -> Cow<'_, [u32]> {
        match &self.counts {
            Some(c) if self.buffers.is_none() => Cow::Borrowed(c),
            _ => Cow::Owned(self.pixel_stats().iter().map(|s| s.count).collect()),
        }
    }

    /// Each pixel's filter-weighted sums of radiance and its sum of filter weights, [r, g, b,
    /// w], row-major: what renders of different sample ranges add to merge (`None` when the
    /// streams are split: the image is then a mean of two films). With half buffers, the
    /// pixel's own samples' sums and count (a box of one pixel).
    pub fn weighted_sums(&self) -> Option<Cow<'_, [[f64; 4]]>> {
        if self.halves.is_some() || self.buffers.as_ref().is_some_and(|b| b.by_rows()) {
            // Split streams make the image a mean of two films; a render by bands keeps no
            // sums of the rows it released.
            return None;
        }
        Some(match &self.buffers {
            Some(b) => Cow::Owned(
                b.pixel_stats()
                    .iter()
                    .map(|s| {
                        let m = s.sum();
                        [m[0], m[1], m[2], f64::from(s.count)]
                    })
                    .collect(),
            ),
            None => Cow::Borrowed(&self.sums),
        })
    }

    /// Frees the filter-weighted sums (and the streams' films and the half buffers, keeping
    /// their pixel statistics), once the image is made and nothing will merge them: they are
    /// the largest part of the film (32 bytes a pixel; the halves 176), and the output is
    /// written after. [`Film::pixels`] and [`Film::weighted_sums`] are then empty.
    pub fn release_sums(&mut self) {
        // A render by bands holds no halves by now, only what it kept of each pixel.
        if let Some(b) = self.buffers.take_if(|b| !b.by_rows()) {
            self.stats = b.pixel_stats();
        }
        self.sums = Vec::new();
        self.halves = None;
    }

    /// The splatted image: each pixel's weighted mean, row-major, top row first (the film's
    /// `scale` is applied on output, not here). With half buffers, each pixel's mean.
    pub fn pixels(&self) -> Vec<Spectrum> {
        if let Some(b) = &self.buffers {
            return b.pixel_stats().iter().map(PixelStats::mean).collect();
        }
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

/// Where [`Film::add_samples`] splats a batch: the film's rows, `width` pixels each, the first
/// at raster row `first_row`; the rows the batch can reach (`reach`, raster y); the filter's
/// radius in y.
struct RowSplat {
    width: usize,
    first_row: i64,
    reach: (f32, f32),
    radius: f32,
}

impl RowSplat {
    /// Splats `items`, sorted by raster row (`floor(y_of)`), into the rows of `sums` in
    /// parallel: each row takes, in order, the items whose filter may reach it (`put`).
    fn splat<T: Sync>(
        &self,
        sums: &mut [[f64; 4]],
        items: &[T],
        y_of: impl Fn(&T) -> f32 + Sync,
        put: impl Fn(&mut [[f64; 4]], i64, &T) + Sync,
    ) {
        use rayon::prelude::*;
        let (lo, hi) = self.reach;
        sums.par_chunks_mut(self.width)
            .enumerate()
            .for_each(|(row_index, row)| {
                let y = row_index as i64 + self.first_row;
                let yf = y as f32;
                if yf < lo || yf > hi {
                    return;
                }
                // A superset, by whole raster rows (monotone in the sorted items), of the items
                // whose filter reaches row y (|y - (p.y - 0.5)| <= radius).
                let (top, bottom) = (
                    (yf + 0.5 - self.radius).floor(),
                    (yf + 0.5 + self.radius).floor(),
                );
                let from = items.partition_point(|t| y_of(t).floor() < top);
                let to = items.partition_point(|t| y_of(t).floor() <= bottom);
                for t in &items[from..to] {
                    put(row, y, t);
                }
            });
    }
}

#[cfg(test)]
mod tests;

/// Adds row-sorted samples to `per_pixel` (row-major over `crop`), each to the item of the
/// pixel it lies in with `add`, rows in parallel.
fn add_by_row<T: Send>(
    per_pixel: &mut [T],
    crop: [u32; 4],
    samples: &[(Vec2, Spectrum)],
    add: impl Fn(&mut T, Spectrum) + Sync,
) {
    use rayon::prelude::*;
    let [cx0, cx1, cy0, _] = crop;
    let w = (cx1 - cx0) as usize;
    per_pixel
        .par_chunks_mut(w)
        .enumerate()
        .for_each(|(row_index, row)| {
            let y = (row_index as u32 + cy0) as f32;
            let from = samples.partition_point(|(p, _)| p.y.floor() < y);
            let to = samples.partition_point(|(p, _)| p.y.floor() <= y);
            for &(p, l) in &samples[from..to] {
                let x = p.x.floor();
                if x >= cx0 as f32 && x < cx1 as f32 {
                    add(&mut row[(x - cx0 as f32) as usize], l);
                }
            }
        });
}
