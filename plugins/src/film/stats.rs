//! Each pixel's own samples' statistics, for the spp and variance AOVs and the noise threshold.

use super::Spectrum;

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
    /// The statistics of two disjoint sets of one pixel's samples together, each given as its
    /// count, mean and sum of squared deviations: Chan et al.'s pairwise combination, in f64.
    pub fn combined(a: (u32, [f32; 3], [f32; 3]), b: (u32, [f32; 3], [f32; 3])) -> Self {
        let (na, nb) = (f64::from(a.0), f64::from(b.0));
        let n = na + nb;
        if a.0 == 0 || b.0 == 0 {
            let (count, mean, m2) = if a.0 == 0 { b } else { a };
            return Self { count, mean, m2 };
        }
        let mut out = Self {
            count: a.0 + b.0,
            ..Self::default()
        };
        for c in 0..3 {
            let (ma, mb) = (f64::from(a.1[c]), f64::from(b.1[c]));
            let delta = mb - ma;
            out.mean[c] = (ma + delta * nb / n) as f32;
            out.m2[c] =
                (f64::from(a.2[c]) + f64::from(b.2[c]) + delta * delta * na * nb / n) as f32;
        }
        out
    }

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

    /// The statistics of `count` samples whose values were not kept (a film that counts its
    /// pixels' samples alone, [`crate::Film::count_only`]): mean and deviations zero.
    pub fn counted(count: u32) -> Self {
        Self {
            count,
            ..Self::default()
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
