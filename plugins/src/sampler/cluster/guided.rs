//! The cluster sampler guided by the reconstruction's estimated error (`guide
//! "reconstruction"`, docs/cluster-sampler.md): at the end of the first stage it asks the
//! render loop for each pixel's estimated squared error of the reconstructed image (the
//! filter's, or each pixel's variance of the mean), and its rounds then go to the clusters of
//! largest summed error per sample, as that error would fall with more samples (one over
//! the count). The map is read once: a sampler that re-read it after its own rounds would
//! decide a pixel's count from that pixel's later values (docs/algorithm.md §8). In an
//! unbiased pair (the default) each half weighs a cell by the other colour's pixels alone: an
//! other-colour pixel by its own estimate, an own-colour one by the mean of its four
//! neighbours' (all of the other colour), so that no pixel's count reads its own samples where
//! the estimate is per pixel (the variance of the mean). Samples go in pairs of consecutive
//! indices from an even first stage, so that each pixel's two halves (index parities, which
//! a reconstruction such as NFOR keeps apart) have equal counts.

use super::{ClusterSampler, Phase, PixelPattern, Priority};
use crate::cells::grid::MAX_DIMS;
use crate::sampler::ErrorMap;

/// The guided first stage's least count per pixel: two samples in each half (index parity),
/// so that each half has a variance of its own when the estimate is read (from a budget of
/// twice this on).
pub(super) const FIRST_STAGE_MIN: u32 = 4;

/// `v` rounded up to an even count, at most `spp` (an odd budget keeps an odd first stage
/// only when it is the whole budget).
pub(super) fn even_up(v: u32, spp: u32) -> u32 {
    let even = v + (v & 1);
    if even <= spp {
        even
    } else {
        v
    }
}

impl ClusterSampler {
    /// Whether it waits for the map before it clusters: guided, its first stage given and not
    /// halted, no map yet.
    pub(super) fn awaits_guide(&self) -> bool {
        self.settings.guided
            && self.state.phase == Phase::Init
            && !self.state.halted
            && !self.state.init.cursor().has_next()
            && self.state.guide.is_none()
            && self.space.pixels() > 0
    }

    /// Keeps the map for the clustering, when it waits for one.
    pub(super) fn take_guide(&mut self, error: &ErrorMap) {
        if self.awaits_guide() {
            self.state.guide = Some(error.clone());
        }
    }

    /// Guided with a map: each cell's error, the first stage's samples per cell, and the
    /// guided priority. Without a map (a caller that never answered) the priority stays the
    /// features' one.
    pub(super) fn weigh_by_guide(&mut self) {
        let Some(map) = self.state.guide.take() else {
            return;
        };
        self.state.cell_error = self.cell_errors(&map);
        let cells = self.state.grid.len().max(1) as f64;
        let share = self.own_pixels() as f64 / self.space.pixels().max(1) as f64;
        let per_cell = self.space.pixels() as f64 / cells * f64::from(self.settings.init_spp);
        self.state.first_per_cell = per_cell * share;
        self.settings.priority = Priority::Guided;
    }

    /// Each cell's estimated error, read from pixels whose samples this sampler's decisions
    /// may read (see the module's comment).
    fn cell_errors(&self, map: &ErrorMap) -> Vec<f64> {
        let grid = &self.state.grid;
        let per_pixel = grid.cells_per_pixel();
        let space = &self.space;
        let (w, h) = (space.width(), space.height());
        (0..grid.len())
            .map(|cell| {
                let p = match per_pixel {
                    Some(per) => grid.pixel_of_cell(cell, per),
                    None => grid.pixel(cell, &[0.5; MAX_DIMS]),
                };
                let (col, row) = (p[0] - space.x0, p[1] - space.y0);
                let own = self.settings.colour.is_some_and(|c| (col + row) & 1 == c);
                if !own {
                    return f64::from(map.at(p));
                }
                let mut sum = 0.0;
                let mut n = 0;
                let near = [
                    (col.wrapping_sub(1), row),
                    (col + 1, row),
                    (col, row.wrapping_sub(1)),
                    (col, row + 1),
                ];
                for (x, y) in near {
                    if x < w && y < h {
                        sum += f64::from(map.at([space.x0 + x, space.y0 + y]));
                        n += 1;
                    }
                }
                if n > 0 {
                    sum / f64::from(n)
                } else {
                    0.0
                }
            })
            .collect()
    }
}
