//! Bands of rows for a reconstruction that reads each pixel's neighbours within a fixed reach:
//! the image is made a band at a time, each band from its rows and a halo of rows around them
//! (docs/reconstruction.md, "NFOR", bands; "Rendering by bands").

use std::ops::Range;

/// How a filter cuts the image into bands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BandPlan {
    /// Rows of a band (0: the whole image is one band).
    pub rows: usize,
    /// Rows read above and below a band besides its own.
    pub halo: usize,
}

impl BandPlan {
    /// The bands of an image of `height` rows, top first. A last band within the halo of the
    /// one before joins it: those rows are read anyway.
    pub fn layout(&self, height: usize) -> Vec<Range<usize>> {
        let band = if self.rows == 0 {
            height.max(1)
        } else {
            self.rows
        };
        let mut out = Vec::new();
        let mut y = 0;
        while y < height {
            let end = if y + band + self.halo >= height {
                height
            } else {
                y + band
            };
            out.push(y..end);
            y = end;
        }
        out
    }

    /// The rows band `rows` is made from: its own and the halo's, within the image's `height`.
    pub fn read(&self, rows: &Range<usize>, height: usize) -> Range<usize> {
        rows.start.saturating_sub(self.halo)..(rows.end + self.halo).min(height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_the_image_and_a_short_last_band_joins_the_one_before() {
        let plan = BandPlan { rows: 64, halo: 32 };
        assert_eq!(plan.layout(200), vec![0..64, 64..128, 128..200]);
        assert_eq!(plan.layout(64), vec![0..64]);
        assert_eq!(plan.layout(0), Vec::<Range<usize>>::new());
        assert_eq!(BandPlan { rows: 0, halo: 32 }.layout(300), vec![0..300]);
        assert_eq!(plan.read(&(64..128), 200), 32..160);
        assert_eq!(plan.read(&(128..200), 200), 96..200);
    }
}
