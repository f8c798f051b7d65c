//! Each cell's running sums (never its samples): count, radiance and luminance moments, the
//! samples' offsets inside the cell and, for the polynomial fit, their first-hit features.
//! Batches are summed in parallel by bands of cells, each cell's samples in batch order.

use super::grid::{CellGrid, MAX_DIMS};
use crate::color::{luminance, Spectrum};
use crate::first_hit::Features;
use rayon::prelude::*;

/// Fewest samples in a batch worth summing in parallel.
const PARALLEL_BATCH: usize = 4096;

/// A contiguous run of cells' sums, borrowed for adding samples.
struct Band<'a> {
    count: &'a mut [u32],
    rgb: &'a mut [[f32; 3]],
    rgb_sq: &'a mut [[f32; 3]],
    lum: &'a mut [f64],
    lum_sq: &'a mut [f64],
    offset: &'a mut [f32],
    offset_sq: &'a mut [f32],
    features: &'a mut [Features],
    features_sq: &'a mut [Features],
    dims: usize,
}

impl Band<'_> {
    /// Adds one sample of radiance `l` at offsets `off`, with first-hit features `f`, to cell
    /// `i` of the band (the features only when the sums keep them).
    #[inline]
    fn add(&mut self, i: usize, off: &[f32; MAX_DIMS], l: Spectrum, f: Option<&Features>) {
        self.count[i] += 1;
        if let (Some(sum), Some(f)) = (self.features.get_mut(i), f) {
            for (s, v) in sum.iter_mut().zip(f) {
                *s += v;
            }
            for (s, v) in self.features_sq[i].iter_mut().zip(f) {
                *s += v * v;
            }
        }
        let y = f64::from(luminance(l));
        self.lum[i] += y;
        self.lum_sq[i] += y * y;
        if self.rgb.is_empty() {
            // Luminance-only sums ([`CellSums::luminance_only`]).
            return;
        }
        for (c, v) in [l.x, l.y, l.z].into_iter().enumerate() {
            self.rgb[i][c] += v;
            self.rgb_sq[i][c] += v * v;
        }
        let at = i * self.dims..(i + 1) * self.dims;
        for ((s, s2), o) in self.offset[at.clone()]
            .iter_mut()
            .zip(&mut self.offset_sq[at])
            .zip(off)
        {
            *s += o;
            *s2 += o * o;
        }
    }
}

/// Each cell's running sums (never its samples), structure of arrays.
#[derive(Clone, Debug, Default)]
pub struct CellSums {
    /// Samples in the cell.
    pub count: Vec<u32>,
    /// Sum of radiance per channel.
    pub rgb: Vec<[f32; 3]>,
    /// Sum of squared radiance per channel.
    pub rgb_sq: Vec<[f32; 3]>,
    /// Sum of luminance (f64: the variance subtracts squares of it).
    pub lum: Vec<f64>,
    /// Sum of squared luminance.
    pub lum_sq: Vec<f64>,
    /// Sum of the samples' offsets inside the cell, `dims` per cell, for their centroid.
    pub offset: Vec<f32>,
    /// Sum of the squared offsets, `dims` per cell: with `offset`, the mean of any quadratic
    /// over the cell's samples (the polynomial fit's rows).
    pub offset_sq: Vec<f32>,
    /// Sum of the samples' first-hit features; empty unless made [`CellSums::with_features`].
    pub features: Vec<Features>,
    /// Sum of the squares of the samples' first-hit features, beside `features`: each
    /// feature's own noise, for the fit's feature prefilter.
    pub features_sq: Vec<Features>,
    dims: usize,
}

impl CellSums {
    /// Zeroed sums for every cell of `grid`.
    pub fn new(grid: &CellGrid) -> Self {
        let n = grid.len();
        Self {
            rgb: vec![[0.0; 3]; n],
            rgb_sq: vec![[0.0; 3]; n],
            offset: vec![0.0; n * grid.dims()],
            offset_sq: vec![0.0; n * grid.dims()],
            ..Self::luminance_only(grid)
        }
    }

    /// Zeroed sums of count and luminance only, for when nothing reads the cells' radiance
    /// and positions (the cluster sampler's features need neither): `rgb`, `rgb_sq`,
    /// `offset` and `offset_sq` stay empty, and adding a sample touches three arrays, not
    /// seven.
    pub fn luminance_only(grid: &CellGrid) -> Self {
        let n = grid.len();
        Self {
            count: vec![0; n],
            rgb: Vec::new(),
            rgb_sq: Vec::new(),
            lum: vec![0.0; n],
            lum_sq: vec![0.0; n],
            offset: Vec::new(),
            offset_sq: Vec::new(),
            features: Vec::new(),
            features_sq: Vec::new(),
            dims: grid.dims(),
        }
    }

    /// These sums, also keeping each cell's sum of first-hit features.
    pub fn with_features(mut self) -> Self {
        self.features = vec![[0.0; crate::first_hit::FEATURES]; self.count.len()];
        self.features_sq = vec![[0.0; crate::first_hit::FEATURES]; self.count.len()];
        self
    }

    /// Whether the sums keep first-hit features.
    pub fn keeps_features(&self) -> bool {
        !self.features.is_empty()
    }

    /// The mean first-hit features of cell `i` from feature sums `features` in place of the
    /// cells' own (a prefiltered copy); None without samples or without features.
    pub fn mean_features_of(
        &self,
        features: &[Features],
        i: usize,
    ) -> Option<[f64; crate::first_hit::FEATURES]> {
        let n = *self.count.get(i)?;
        let f = features.get(i)?;
        (n > 0).then(|| f.map(|v| f64::from(v) / f64::from(n)))
    }

    /// The mean first-hit features of cell `i`; None without samples or without features.
    pub fn mean_features(&self, i: usize) -> Option<[f64; crate::first_hit::FEATURES]> {
        self.mean_features_of(&self.features, i)
    }

    /// Whether the sums hold radiance and positions, not only luminance.
    pub fn keeps_radiance(&self) -> bool {
        !self.rgb.is_empty() || self.count.is_empty()
    }

    /// Adds one sample of radiance `l` at offsets `off` to cell `i`.
    #[inline]
    pub fn add(&mut self, i: usize, off: &[f32; MAX_DIMS], l: Spectrum) {
        self.band(0, self.count.len()).add(i, off, l, None);
    }

    /// Adds a batch of samples: the sample in cell `located[k].0` at offsets `located[k].1`
    /// with radiance `radiance[k]` (and first-hit features `features[k]`, when given and
    /// kept), skipping radiance that is not finite (a dropped sample). Bands of cells are
    /// summed in parallel, each cell's samples in batch order, so the sums do not depend on
    /// the thread count.
    pub fn add_batch(
        &mut self,
        located: &[(u32, [f32; MAX_DIMS])],
        radiance: &[[f32; 3]],
        features: Option<&[Features]>,
    ) {
        let cells = self.count.len();
        let bands = if located.len() < PARALLEL_BATCH {
            1
        } else {
            (4 * rayon::current_num_threads()).min(cells.max(1))
        };
        let band_len = cells.div_ceil(bands).max(1);
        // Each band's samples, in batch order: one pass, then the bands in parallel.
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); bands];
        for (k, ((cell, _), l)) in located.iter().zip(radiance).enumerate() {
            if l.iter().all(|v| v.is_finite()) {
                members[*cell as usize / band_len].push(k as u32);
            }
        }
        let add_band = |b: usize, mut band: Band<'_>, members: &[u32]| {
            for &k in members {
                let (cell, off) = &located[k as usize];
                let i = *cell as usize - b * band_len;
                let f = features.and_then(|f| f.get(k as usize));
                band.add(i, off, Spectrum::from_array(radiance[k as usize]), f);
            }
        };
        if bands == 1 {
            add_band(0, self.band(0, cells), &members[0]);
            return;
        }
        self.bands(band_len)
            .into_par_iter()
            .zip(&members)
            .enumerate()
            .for_each(|(b, (band, members))| add_band(b, band, members));
    }

    /// The sums of cells `start..end` as one band.
    fn band(&mut self, start: usize, end: usize) -> Band<'_> {
        let d = self.dims;
        // Luminance-only sums have empty radiance arrays: their bands' are empty too.
        let (r, o) = if self.rgb.is_empty() {
            (0..0, 0..0)
        } else {
            (start..end, start * d..end * d)
        };
        let f = if self.features.is_empty() {
            0..0
        } else {
            start..end
        };
        Band {
            count: &mut self.count[start..end],
            rgb: &mut self.rgb[r.clone()],
            rgb_sq: &mut self.rgb_sq[r],
            lum: &mut self.lum[start..end],
            lum_sq: &mut self.lum_sq[start..end],
            offset: &mut self.offset[o.clone()],
            offset_sq: &mut self.offset_sq[o],
            features: &mut self.features[f.clone()],
            features_sq: &mut self.features_sq[f],
            dims: d,
        }
    }

    /// The sums split into bands of `band_len` cells, in order.
    fn bands(&mut self, band_len: usize) -> Vec<Band<'_>> {
        let d = self.dims;
        // Chunks of an array, then empty ones: luminance-only sums' radiance arrays are empty.
        fn chunks<T>(v: &mut [T], len: usize) -> impl Iterator<Item = &mut [T]> {
            v.chunks_mut(len)
                .chain(std::iter::repeat_with(|| &mut [][..]))
        }
        self.count
            .chunks_mut(band_len)
            .zip(chunks(&mut self.rgb, band_len))
            .zip(chunks(&mut self.rgb_sq, band_len))
            .zip(self.lum.chunks_mut(band_len))
            .zip(self.lum_sq.chunks_mut(band_len))
            .zip(chunks(&mut self.offset, band_len * d))
            .zip(chunks(&mut self.offset_sq, band_len * d))
            .zip(chunks(&mut self.features, band_len))
            .zip(chunks(&mut self.features_sq, band_len))
            .map(
                |(
                    (((((((count, rgb), rgb_sq), lum), lum_sq), offset), offset_sq), features),
                    features_sq,
                )| Band {
                    count,
                    rgb,
                    rgb_sq,
                    lum,
                    lum_sq,
                    offset,
                    offset_sq,
                    features,
                    features_sq,
                    dims: d,
                },
            )
            .collect()
    }

    /// The mean luminance of cell `i`, if it has samples.
    #[inline]
    pub fn mean(&self, i: usize) -> Option<f64> {
        let n = self.count[i];
        (n > 0).then(|| self.lum[i] / f64::from(n))
    }

    /// The sample variance of luminance in cell `i` (N - 1 in the denominator; 0 when N < 2).
    #[inline]
    pub fn variance(&self, i: usize) -> f64 {
        let n = f64::from(self.count[i]);
        if n < 2.0 {
            return 0.0;
        }
        ((self.lum_sq[i] - self.lum[i] * self.lum[i] / n) / (n - 1.0)).max(0.0)
    }

    /// Bytes held, for the memory budget.
    pub fn bytes(&self) -> usize {
        self.count.capacity() * 4
            + self.rgb.capacity() * 12
            + self.rgb_sq.capacity() * 12
            + self.lum.capacity() * 8
            + self.lum_sq.capacity() * 8
            + self.offset.capacity() * 4
            + self.offset_sq.capacity() * 4
            + self.features.capacity() * std::mem::size_of::<Features>()
            + self.features_sq.capacity() * std::mem::size_of::<Features>()
    }

    /// Active dims (offsets per cell).
    pub fn dims(&self) -> usize {
        self.dims
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cells::grid::tests::space;

    #[test]
    fn luminance_only_sums_agree_with_full_ones() {
        let g = CellGrid::new(space(40, 30, true, true), 1.0, 2);
        let mut rng = crate::rng::Pcg32::new(5, 1);
        // More samples than PARALLEL_BATCH, so that the bands are summed in parallel.
        let n = 3 * PARALLEL_BATCH;
        let located: Vec<(u32, [f32; MAX_DIMS])> = (0..n)
            .map(|_| {
                let cell = (rng.next_f32() * g.len() as f32) as u32 % g.len() as u32;
                (cell, [rng.next_f32(); MAX_DIMS])
            })
            .collect();
        let radiance: Vec<[f32; 3]> = (0..n)
            .map(|k| {
                let v = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
                // A dropped sample now and then.
                if k % 97 == 0 {
                    [f32::NAN; 3]
                } else {
                    v
                }
            })
            .collect();
        let (mut full, mut lum) = (CellSums::new(&g), CellSums::luminance_only(&g));
        full.add_batch(&located, &radiance, None);
        lum.add_batch(&located, &radiance, None);
        assert!(full.keeps_radiance() && !lum.keeps_radiance());
        assert_eq!(full.count, lum.count);
        assert_eq!(full.lum, lum.lum);
        assert_eq!(full.lum_sq, lum.lum_sq);
        assert!(lum.rgb.is_empty() && lum.offset.is_empty() && lum.offset_sq.is_empty());
        assert_eq!(full.count.iter().sum::<u32>(), (n - n.div_ceil(97)) as u32);
        // 20 bytes a cell rather than 20 + 24 + 8 per active dim.
        assert_eq!(lum.bytes(), 20 * g.len());
        assert!(lum.bytes() * 3 < full.bytes());
    }

    #[test]
    fn variance_of_known_samples() {
        let g = CellGrid::new(space(1, 1, false, false), 1.0, 2);
        let mut s = CellSums::new(&g);
        assert_eq!(s.mean(0), None);
        for v in [1.0f32, 2.0, 3.0] {
            s.add(0, &[0.5; 5], Spectrum::splat(v));
        }
        assert!((s.mean(0).unwrap() - 2.0).abs() < 1e-6);
        assert!((s.variance(0) - 1.0).abs() < 1e-5);
    }
}
