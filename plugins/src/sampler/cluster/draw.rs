//! Where a round's samples go: each chosen cluster's samples spread systematically over its
//! cells, to the pixels of those cells (`evenpixels`, each pixel's next point of its
//! sequence) or to uniform points inside the cells; sorted by row for the film.

use super::crossed::own_colour;
use super::{ClusterSampler, SALT};
use crate::cells::grid::MAX_DIMS;
use crate::sampler::{mix64, Pcg32};
use crate::space::SamplePoint;
use rayon::prelude::*;

/// Picks one task draws the pixels of, in a round.
const PICKS_PER_TASK: usize = 64;

impl ClusterSampler {
    /// The systematic sample of `k` slots over `m` cells from a random start: `k` samples
    /// cover a cluster's cells evenly rather than by chance.
    #[inline]
    fn slots(rng: &mut Pcg32, m: usize, k: u64) -> impl Iterator<Item = usize> {
        let start = f64::from(rng.next_f32()) * m as f64;
        let step = m as f64 / k as f64;
        // start < m and j * step < m: one subtraction wraps it (no division per slot).
        (0..k).map(move |j| {
            let s = (start + j as f64 * step) as usize;
            if s >= m {
                s - m
            } else {
                s
            }
        })
    }

    /// Draws the round's pixels (evenpixels): each pick's samples go to pixels of its cells,
    /// and each gets the pixel's next index; `out` holds them sorted by row, the rest of each
    /// point left to be made.
    pub(super) fn draw_pixels(&mut self, picks: &[(u32, u64)], out: &mut Vec<SamplePoint>) {
        let clustering = self.state.clustering.as_ref().expect("clustered");
        let per_pixel = self.state.grid.cells_per_pixel();
        let width = self.space.width() as usize;
        let rows = self.space.height() as usize;
        // Each pick draws from its own stream, so that picks are drawn in parallel and the
        // pixels do not depend on the thread count.
        let round_key = mix64(self.seed ^ SALT ^ mix64(self.state.rounds));
        let (grid, space) = (&self.state.grid, &self.space);
        let colour = self.settings.colour;
        let pairs = self.settings.guided;
        let groups: Vec<Vec<u64>> = picks
            .par_chunks(PICKS_PER_TASK)
            .enumerate()
            .map(|(g, group)| {
                let mut drawn = Vec::new();
                // Every pick's cell list, then its first cell, before drawing: independent
                // reads whose cache misses overlap, where drawing pick after pick waited on
                // two misses each (the clusters are cold after tracing).
                let lists: Vec<&[u32]> = group
                    .iter()
                    .map(|&(id, _)| clustering.clusters[id as usize].cells.as_slice())
                    .collect();
                let first = lists.iter().filter_map(|l| l.first());
                std::hint::black_box(first.fold(0u32, |a, &c| a ^ c));
                for (n, (&(_, k), cells)) in group.iter().zip(&lists).enumerate() {
                    let stream = (g * PICKS_PER_TASK + n) as u64;
                    let mut rng = Pcg32::new(round_key, stream);
                    // Guided, each pixel drawn takes two consecutive indices.
                    let copies = if pairs { 2 } else { 1 };
                    for slot in Self::slots(&mut rng, cells.len(), k / copies) {
                        let cell = cells[slot] as usize;
                        let pixel = match per_pixel {
                            Some(per) => grid.pixel_of_cell(cell, per),
                            None => {
                                let mut u = [0.5f32; MAX_DIMS];
                                u[0] = rng.next_f32();
                                u[1] = rng.next_f32();
                                grid.pixel(cell, &u)
                            }
                        };
                        let (col, row) = (pixel[0] - space.x0, pixel[1] - space.y0);
                        let (col, row) = match colour {
                            Some(c) => own_colour(col, row, c, space.width(), space.height()),
                            None => (col, row),
                        };
                        // Row and column packed, so that sorting needs no division.
                        for _ in 0..copies {
                            drawn.push(u64::from(row) << 32 | u64::from(col));
                        }
                    }
                }
                drawn
            })
            .collect();
        let mut drawn = std::mem::take(&mut self.scratch.drawn);
        drawn.clear();
        drawn.extend(groups.into_iter().flatten());
        let mut start = vec![0usize; rows + 1];
        for &p in &drawn {
            start[(p >> 32) as usize + 1] += 1;
        }
        // The film takes samples sorted by row: a stable counting sort, O(n). A pixel's
        // indices follow the draw order, as the sort is stable.
        for r in 0..rows {
            start[r + 1] += start[r];
        }
        out.clear();
        out.resize(drawn.len(), SamplePoint::UNMADE);
        let (x0, y0) = (self.space.x0, self.space.y0);
        for &p in &drawn {
            let (row, col) = ((p >> 32) as u32, p as u32);
            let r = &mut start[row as usize];
            out[*r].pixel = [x0 + col, y0 + row];
            *r += 1;
        }
        // The indices after the sort, in row order: pixel counts read a row at a time rather
        // than at random (each read missed the cache: 18% of the planning's time). A pixel's
        // points keep their draw order, so they get the same indices either way.
        for q in out.iter_mut() {
            let p = (q.pixel[1] - y0) as usize * width + (q.pixel[0] - x0) as usize;
            q.index = self.state.pixel_count[p];
            self.state.pixel_count[p] += 1;
        }
        self.scratch.drawn = drawn;
    }

    /// Draws the round's points inside the chosen cells themselves (evenpixels false): each a
    /// uniform point in its cell; `out` holds them sorted by row and `round_cells` their cells.
    pub(super) fn draw_cells(
        &mut self,
        picks: &[(u32, u64)],
        rng: &mut Pcg32,
        out: &mut Vec<SamplePoint>,
    ) {
        let clustering = self.state.clustering.as_ref().expect("clustered");
        let n = self.state.grid.dims();
        let mut points: Vec<(SamplePoint, u32, [f32; MAX_DIMS])> = Vec::new();
        for &(id, k) in picks {
            let cells = &clustering.clusters[id as usize].cells;
            for slot in Self::slots(rng, cells.len(), k) {
                let mut u = [0.5f32; MAX_DIMS];
                for v in &mut u[..n] {
                    *v = rng.next_f32();
                }
                let cell = cells[slot];
                let mut q = self.state.grid.point(cell as usize, &u);
                let p = self.space.index_of(q.pixel);
                q.index = self.settings.stream.index(self.state.pixel_count[p]);
                self.state.pixel_count[p] += 1;
                points.push((q, cell, u));
            }
        }
        // Sorted by row for the film: a stable counting sort, O(n).
        let (y0, rows) = (self.space.y0, self.space.height() as usize);
        let mut start = vec![0usize; rows + 1];
        for (q, _, _) in &points {
            start[(q.pixel[1] - y0) as usize + 1] += 1;
        }
        for r in 0..rows {
            start[r + 1] += start[r];
        }
        out.clear();
        self.scratch.round_cells.clear();
        if let Some(first) = points.first() {
            out.resize(points.len(), first.0);
            self.scratch
                .round_cells
                .resize(points.len(), (first.1, first.2));
        }
        for (q, cell, u) in points {
            let r = &mut start[(q.pixel[1] - y0) as usize];
            out[*r] = q;
            self.scratch.round_cells[*r] = (cell, u);
            *r += 1;
        }
    }
}
