//! What the render loop hands a sampler that places samples by the reconstruction's estimated
//! error (docs/cluster-sampler.md, "Guided by the reconstruction's error"): a per-pixel map of
//! the estimated squared error, from the filter when it makes one
//! ([`crate::filters::Filter::estimated_error`]) floored at the film's own statistics (the
//! variance of each pixel's mean luminance), else from those statistics alone.

use crate::film::{luminance, Film};

/// A per-pixel estimate of the squared error, over a rectangle of raster pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorMap {
    /// The rectangle's first column.
    pub x0: u32,
    /// The rectangle's first row.
    pub y0: u32,
    /// Its width in pixels.
    pub width: u32,
    /// Its height in pixels.
    pub height: u32,
    /// The estimate of each pixel, row-major (never negative nor NaN).
    pub error: Vec<f32>,
}

impl ErrorMap {
    /// The map of `film`'s cropped pixels: the variance of each pixel's mean luminance, raised
    /// to `estimate` (a filter's, row-major over the cropped film, when it has one value per
    /// pixel) where that is larger.
    pub fn of(film: &Film, estimate: Option<Vec<f32>>) -> Self {
        let [x0, x1, y0, y1] = film.settings().crop;
        let pixels = (x1 - x0) as usize * (y1 - y0) as usize;
        let stats = film.pixel_stats();
        let own = stats.iter().map(|s| luminance(s.variance_of_mean()));
        // A filter's estimate of its error (NFOR's: the halves' differences less their
        // variances, clamped) is zero wherever its own noise swamps it, most pixels after a
        // short first stage, and those pixels would get no rounds; the variance of the mean,
        // what their samples would take off, is the floor (docs/cluster-sampler.md).
        let error: Vec<f32> = match estimate {
            Some(e) if e.len() == pixels => own.zip(e).map(|(v, e)| v.max(e)).collect(),
            _ => own.collect(),
        };
        Self {
            x0,
            y0,
            width: x1 - x0,
            height: y1 - y0,
            // A NaN or negative estimate says nothing: no error.
            error: error
                .into_iter()
                .map(|e| if e > 0.0 { e } else { 0.0 })
                .collect(),
        }
    }

    /// The estimate at raster pixel `p`, or at the map's nearest pixel when `p` lies outside
    /// it (a sampler's space reaches beyond a crop by the filter's radius); 0 for an empty map.
    pub fn at(&self, p: [u32; 2]) -> f32 {
        if self.width == 0 || self.height == 0 {
            return 0.0;
        }
        let x = p[0].clamp(self.x0, self.x0 + self.width - 1) - self.x0;
        let y = p[1].clamp(self.y0, self.y0 + self.height - 1) - self.y0;
        self.error[y as usize * self.width as usize + x as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_filters_estimate_is_floored_at_each_pixels_variance_of_the_mean() {
        use crate::film::{FilmSettings, Spectrum};
        use crate::filters::BoxFilter;
        use glam::Vec2;
        let mut f = Film::new(
            FilmSettings::with_resolution(2, 1),
            &BoxFilter::new(0.5, 0.5),
        );
        // Pixel 0: samples 1 and 3 (variance 2, of the mean 1); pixel 1: one sample.
        f.add_sample(Vec2::new(0.25, 0.5), Spectrum::splat(1.0));
        f.add_sample(Vec2::new(0.75, 0.5), Spectrum::splat(3.0));
        f.add_sample(Vec2::new(1.5, 0.5), Spectrum::splat(5.0));
        let own = ErrorMap::of(&f, None);
        assert_eq!((own.width, own.height), (2, 1));
        assert!((own.error[0] - 1.0).abs() < 1e-6, "{:?}", own.error);
        assert_eq!(own.error[1], 0.0);
        // The filter's where larger, NaN and negatives cleaned; the variance of the mean
        // where the filter's is smaller (pixel 0) or says nothing.
        let given = ErrorMap::of(&f, Some(vec![0.25, 0.5]));
        assert_eq!(given.error, [1.0, 0.5]);
        assert_eq!(
            ErrorMap::of(&f, Some(vec![f32::NAN, -1.0])).error,
            [1.0, 0.0]
        );
        assert_eq!(
            ErrorMap::of(&f, Some(vec![3.0, f32::NAN])).error,
            [3.0, 0.0]
        );
        // One of the wrong size is not the film's: the film's own instead.
        assert_eq!(ErrorMap::of(&f, Some(vec![7.0])), own);
    }

    #[test]
    fn outside_pixels_take_the_nearest_estimate() {
        let m = ErrorMap {
            x0: 2,
            y0: 3,
            width: 2,
            height: 2,
            error: vec![1.0, 2.0, 3.0, 4.0],
        };
        assert_eq!(m.at([2, 3]), 1.0);
        assert_eq!(m.at([3, 4]), 4.0);
        assert_eq!(m.at([0, 0]), 1.0);
        assert_eq!(m.at([9, 3]), 2.0);
        assert_eq!(m.at([2, 9]), 3.0);
    }
}
