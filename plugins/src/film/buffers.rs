//! Per-pixel half buffers for a reconstruction that estimates its own error from two
//! independent halves of the samples (NFOR, docs/reconstruction.md): a sample's half is its
//! index's parity. Each half keeps, per pixel, the count, the running mean and sum of squared
//! deviations of the colour and of the first-hit features (Welford's form, stable in f32): the
//! colour and depth in f32, the albedo and normal in half precision (60 bytes a half, not 88).

// Small fixed-size channel and matrix loops read clearest with indices.
#![allow(clippy::needless_range_loop)]

use super::half_float::{from_half, to_half};
use super::stats::PixelStats;
use crate::first_hit::{Features, DEPTH, FEATURES};
use crate::space::SamplePoint;

/// The features kept in half precision: the albedo and the normal, each channel within
/// [-1, 1] or near it (depth, on the scene's scale, stays f32).
const PACKED: usize = DEPTH;

/// One half's statistics for one pixel: 60 bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HalfPixel {
    /// Samples in this half.
    pub count: u32,
    /// Mean colour.
    pub color: [f32; 3],
    /// Sum of squared deviations of the colour from its mean.
    pub color_m2: [f32; 3],
    /// The depth's mean and sum of squared deviations.
    depth: [f32; 2],
    /// The other features' means, binary16 ([`to_half`]): 11 significant bits are far below
    /// their sampling noise, and they take half the memory.
    packed: [u16; PACKED],
    /// Their sums of squared deviations, binary16.
    packed_m2: [u16; PACKED],
}

impl HalfPixel {
    /// Adds one sample.
    #[inline]
    fn add(&mut self, l: [f32; 3], f: &Features) {
        self.count += 1;
        let inv = 1.0 / self.count as f32;
        for c in 0..3 {
            let delta = l[c] - self.color[c];
            self.color[c] += delta * inv;
            self.color_m2[c] += delta * (l[c] - self.color[c]);
        }
        let (mut mean, mut m2) = (self.features(), self.features_m2());
        for k in 0..FEATURES {
            let delta = f[k] - mean[k];
            mean[k] += delta * inv;
            m2[k] += delta * (f[k] - mean[k]);
        }
        self.depth = [mean[DEPTH], m2[DEPTH]];
        for k in 0..PACKED {
            self.packed[k] = to_half(mean[k]);
            self.packed_m2[k] = to_half(m2[k]);
        }
    }

    /// The mean first-hit features.
    #[inline]
    pub fn features(&self) -> Features {
        std::array::from_fn(|k| match k {
            DEPTH => self.depth[0],
            k => from_half(self.packed[k]),
        })
    }

    /// The features' sums of squared deviations from their mean.
    #[inline]
    pub fn features_m2(&self) -> Features {
        std::array::from_fn(|k| match k {
            DEPTH => self.depth[1],
            k => from_half(self.packed_m2[k]),
        })
    }

    /// The variance of this half's mean colour, per channel: the sample variance over the
    /// count (None with fewer than two samples).
    pub fn color_variance_of_mean(&self) -> Option<[f32; 3]> {
        (self.count >= 2).then(|| {
            let n = self.count as f32;
            self.color_m2.map(|m2| m2.max(0.0) / ((n - 1.0) * n))
        })
    }

    /// The variance of this half's mean features (None with fewer than two samples).
    pub fn features_variance_of_mean(&self) -> Option<Features> {
        (self.count >= 2).then(|| {
            let n = self.count as f32;
            self.features_m2().map(|m2| m2.max(0.0) / ((n - 1.0) * n))
        })
    }
}

/// Both halves of every pixel of the cropped film, row-major; in a render by bands, of the
/// rows under way only ([`PixelBuffers::hold_rows`]).
#[derive(Clone, Debug)]
pub struct PixelBuffers {
    width: u32,
    height: u32,
    /// The raster origin of the crop.
    origin: [u32; 2],
    /// The halves of rows `first_row..`, as many as they hold.
    halves: [Vec<HalfPixel>; 2],
    /// The first row the halves hold (0 but in a render by bands).
    first_row: usize,
    /// In a render by bands, what is kept of the rows above `first_row`, released.
    released: Option<Released>,
    /// The factor that brings the depth feature to a common scale, when the render set one
    /// (else the filter computes it from the halves).
    depth_scale: Option<f32>,
}

/// What a render by bands keeps of the rows it released: each pixel's statistics, or only its
/// count (4 bytes a pixel, not 28) when nothing reads the rest.
#[derive(Clone, Debug)]
enum Released {
    Stats(Vec<PixelStats>),
    Counts(Vec<u32>),
}

/// The statistics of a pixel's two halves together.
fn combined(a: &HalfPixel, b: &HalfPixel) -> PixelStats {
    let part = |p: &HalfPixel| (p.count, p.color, p.color_m2);
    PixelStats::combined(part(a), part(b))
}

impl PixelBuffers {
    /// Empty buffers for a `width` x `height` crop starting at raster `origin`.
    pub fn new(width: u32, height: u32, origin: [u32; 2]) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            origin,
            halves: [vec![HalfPixel::default(); n], vec![HalfPixel::default(); n]],
            first_row: 0,
            released: None,
            depth_scale: None,
        }
    }

    /// Buffers for a render by bands ([`PixelBuffers::hold_rows`]): no row held yet, room for
    /// `window` rows.
    pub fn by_rows_of(
        width: u32,
        height: u32,
        origin: [u32; 2],
        keep_stats: bool,
        window: usize,
    ) -> Self {
        let mut b = Self {
            width,
            height,
            origin,
            halves: [Vec::new(), Vec::new()],
            first_row: 0,
            released: None,
            depth_scale: None,
        };
        b.hold_rows(keep_stats, window);
        b
    }

    /// The crop's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Half `h`'s pixels (0 or 1), row-major: of the rows held ([`PixelBuffers::held_rows`]).
    pub fn half(&self, h: usize) -> &[HalfPixel] {
        &self.halves[h & 1]
    }

    /// Half `h`'s pixels of rows `rows` (crop rows, held).
    pub fn rows_of(&self, h: usize, rows: std::ops::Range<usize>) -> &[HalfPixel] {
        let w = self.width as usize;
        &self.halves[h & 1][(rows.start - self.first_row) * w..(rows.end - self.first_row) * w]
    }

    /// The crop rows the halves hold: all of them, but in a render by bands.
    pub fn held_rows(&self) -> std::ops::Range<usize> {
        let held = self.halves[0].len() / (self.width as usize).max(1);
        self.first_row..self.first_row + held
    }

    /// Makes the buffers hold only the rows under way of a render by bands, from none: a
    /// sample's row is added when its first sample comes, [`PixelBuffers::release_rows`] frees
    /// the rows above a row. Of the rows released each pixel's statistics are kept when
    /// `keep_stats`, else its count. Room for `window` rows is made at once.
    pub fn hold_rows(&mut self, keep_stats: bool, window: usize) {
        let n = window.min(self.height as usize) * self.width as usize;
        self.halves = [Vec::with_capacity(n), Vec::with_capacity(n)];
        self.first_row = 0;
        self.released = Some(if keep_stats {
            Released::Stats(Vec::new())
        } else {
            Released::Counts(Vec::new())
        });
    }

    /// Whether the buffers hold the rows under way only ([`PixelBuffers::hold_rows`]).
    pub fn by_rows(&self) -> bool {
        self.released.is_some()
    }

    /// Frees the halves of the rows above crop row `row`, keeping what
    /// [`PixelBuffers::hold_rows`] asked of them (rows never sampled count none).
    pub fn release_rows(&mut self, row: usize) {
        let Some(released) = self.released.as_mut() else {
            return;
        };
        let w = self.width as usize;
        let row = row.min(self.height as usize).max(self.first_row);
        let held = (row - self.first_row).min(self.halves[0].len() / w.max(1)) * w;
        let unsampled = (row - self.first_row) * w - held;
        let [a, b] = &self.halves;
        match released {
            Released::Stats(s) => {
                s.extend(
                    a[..held]
                        .iter()
                        .zip(&b[..held])
                        .map(|(a, b)| combined(a, b)),
                );
                s.resize(s.len() + unsampled, PixelStats::default());
            }
            Released::Counts(c) => {
                c.extend(
                    a[..held]
                        .iter()
                        .zip(&b[..held])
                        .map(|(a, b)| a.count + b.count),
                );
                c.resize(c.len() + unsampled, 0);
            }
        }
        for h in &mut self.halves {
            h.drain(..held);
            if h.is_empty() {
                // The last rows: their room goes too.
                *h = Vec::new();
            }
        }
        self.first_row = row;
    }

    /// In a render by bands, makes the halves hold every row above crop row `row`, those
    /// not sampled empty (a halted render's rows below the last it reached).
    pub fn hold_through(&mut self, row: usize) {
        if self.released.is_none() {
            return;
        }
        let n =
            (row.min(self.height as usize).saturating_sub(self.first_row)) * self.width as usize;
        for h in &mut self.halves {
            if h.len() < n {
                h.resize(n, HalfPixel::default());
            }
        }
    }

    /// The depth scale the render set ([`PixelBuffers::set_depth_scale`]).
    pub fn depth_scale(&self) -> Option<f32> {
        self.depth_scale
    }

    /// Sets the factor that brings the depth feature to a common scale: known before any
    /// sample, it is the same whether the image is filtered whole or by bands.
    pub fn set_depth_scale(&mut self, scale: f32) {
        self.depth_scale = Some(scale);
    }

    /// Each pixel's statistics over both halves, row-major: what the film's own pixel
    /// statistics would hold, combined from the halves ([`PixelStats::combined`]). In a render
    /// by bands, the rows released as kept (a count alone: zero mean and variance), the rows
    /// not yet sampled empty.
    pub fn pixel_stats(&self) -> Vec<PixelStats> {
        let held = self.halves[0].iter().zip(&self.halves[1]);
        let Some(released) = &self.released else {
            return held.map(|(a, b)| combined(a, b)).collect();
        };
        let mut out = match released {
            Released::Stats(s) => s.clone(),
            Released::Counts(c) => c
                .iter()
                .map(|&count| {
                    let mut s = PixelStats::default();
                    s.count = count;
                    s
                })
                .collect(),
        };
        out.extend(held.map(|(a, b)| combined(a, b)));
        out.resize(
            self.width as usize * self.height as usize,
            PixelStats::default(),
        );
        out
    }

    /// Adds the samples of a batch: each point's radiance (NaN: dropped, skipped) and
    /// first-hit features (zeros when not given) to its pixel's half, in order.
    pub fn add(
        &mut self,
        batch: &[SamplePoint],
        radiance: &[[f32; 3]],
        features: Option<&[Features]>,
    ) {
        let (w, h) = (self.width as i64, self.height as i64);
        for (k, (q, l)) in batch.iter().zip(radiance).enumerate() {
            if l[0].is_nan() {
                continue;
            }
            let x = q.film[0].floor() as i64 - i64::from(self.origin[0]);
            let y = q.film[1].floor() as i64 - i64::from(self.origin[1]);
            if x < 0 || y < 0 || x >= w || y >= h {
                continue;
            }
            let f = features.map_or([0.0; FEATURES], |f| f[k]);
            let Some(i) =
                (y as usize * w as usize + x as usize).checked_sub(self.first_row * w as usize)
            else {
                // A row already released: a render by bands gives none.
                debug_assert!(false, "a sample in a released row");
                continue;
            };
            if i >= self.halves[0].len() {
                // A render by bands: the sample's row and those above it come in.
                let rows = i / w as usize + 1;
                for h in &mut self.halves {
                    h.resize(rows * w as usize, HalfPixel::default());
                }
            }
            self.halves[q.index as usize & 1][i].add(*l, &f);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_go_to_their_index_parity() {
        let mut b = PixelBuffers::new(2, 1, [10, 5]);
        let mut batch = Vec::new();
        for i in 0..4 {
            batch.push(SamplePoint {
                index: i,
                film: [11.5, 5.5],
                pixel: [11, 5],
                ..SamplePoint::UNMADE
            });
        }
        let radiance = [[1.0; 3], [2.0; 3], [3.0; 3], [f32::NAN; 3]];
        let features = [[0.5; FEATURES]; 4];
        b.add(&batch, &radiance, Some(&features));
        assert_eq!(b.half(0)[1].count, 2);
        assert_eq!(b.half(0)[1].color, [2.0; 3]);
        assert_eq!(b.half(1)[1].count, 1);
        assert_eq!(b.half(1)[1].color, [2.0; 3]);
        assert_eq!(b.half(0)[0].count, 0);
        let v = b.half(0)[1].color_variance_of_mean().expect("two samples");
        assert!((v[0] - 1.0).abs() < 1e-6, "{v:?}");
        assert_eq!(b.half(0)[1].features(), [0.5; FEATURES]);
        assert_eq!(std::mem::size_of::<HalfPixel>(), 60);
    }
}
