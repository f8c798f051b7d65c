//! The cell grid over the active dims (docs/algorithm.md §2); each cell's running sums are
//! in `sums.rs`. Image dims are cut every `cellsize` pixels, each non-image dim into `bins`
//! intervals; the non-image dims are innermost in the cell index, so a pixel's cells lie
//! together in memory.

use crate::space::{in_pixel, RenderingSpace, SamplePoint};
use rayon::prelude::*;

/// Most active dims: x, y, t, u, v.
pub const MAX_DIMS: usize = 5;

/// Integer coordinates of a cell, one per active dim (unused entries 0).
pub type Coords = [u32; MAX_DIMS];

/// The grid of cells over a rendering space.
#[derive(Clone, Debug)]
pub struct CellGrid {
    space: RenderingSpace,
    cell_size: f64,
    n: usize,
    shape: Coords,
    stride: [usize; MAX_DIMS],
    len: usize,
    /// Whether cells are whole pixels (cell size 1) with one interval along every other dim.
    pixel_cells: bool,
}

impl CellGrid {
    /// Cells of `cell_size` pixels in x and y and `bins` intervals per non-image dim.
    pub fn new(space: RenderingSpace, cell_size: f64, bins: u32) -> Self {
        let n = space.dims.count();
        let along = |w: u32| ((f64::from(w) / cell_size).ceil() as u32).max(1);
        let mut shape = [1; MAX_DIMS];
        shape[0] = along(space.width());
        shape[1] = along(space.height());
        for s in &mut shape[2..n] {
            *s = bins.max(1);
        }
        let inner: usize = shape[2..n].iter().map(|&b| b as usize).product();
        let mut stride = [0; MAX_DIMS];
        stride[0] = inner;
        stride[1] = inner * shape[0] as usize;
        let mut s = 1;
        for d in 2..n {
            stride[d] = s;
            s *= shape[d] as usize;
        }
        Self {
            space,
            cell_size,
            n,
            shape,
            stride,
            len: stride[1] * shape[1] as usize,
            pixel_cells: cell_size == 1.0 && inner == 1,
        }
    }

    /// The space the grid covers.
    pub fn space(&self) -> &RenderingSpace {
        &self.space
    }

    /// How many cells.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the grid has no cell (never: an empty space still has one).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Active dims.
    pub fn dims(&self) -> usize {
        self.n
    }

    /// Cells along each active dim.
    pub fn shape(&self) -> &[u32] {
        &self.shape[..self.n]
    }

    /// Cells that share one image cell (the product of the non-image bins).
    pub fn cells_per_image_cell(&self) -> usize {
        self.stride[0]
    }

    /// Pixels per image cell side.
    pub fn cell_size(&self) -> f64 {
        self.cell_size
    }

    /// How far apart in index two cells one step apart along `dim` are.
    #[inline]
    pub fn stride(&self, dim: usize) -> usize {
        self.stride[dim]
    }

    /// The coordinates of cell `i`.
    #[inline]
    pub fn coords(&self, i: usize) -> Coords {
        // In u32 (cell ids are u32 throughout), and no division for dims of one cell: this
        // runs for every cell a round touches, and 64-bit divisions dominated it.
        let mut c = [0; MAX_DIMS];
        let (i, inner_len, width) = (i as u32, self.stride[0] as u32, self.shape[0]);
        let (image, mut inner) = if inner_len == 1 {
            (i, 0)
        } else {
            (i / inner_len, i % inner_len)
        };
        c[0] = image % width;
        c[1] = image / width;
        for (cd, &len) in c[2..self.n].iter_mut().zip(&self.shape[2..self.n]) {
            if len > 1 {
                *cd = inner % len;
                inner /= len;
            }
        }
        c
    }

    /// The index of the cell at `c`.
    #[inline]
    pub fn index(&self, c: &Coords) -> usize {
        (0..self.n).map(|d| c[d] as usize * self.stride[d]).sum()
    }

    /// The neighbour of cell `i` one step along `dim` (`up` or down), if inside the grid.
    #[inline]
    pub fn step(&self, i: usize, c: &Coords, dim: usize, up: bool) -> Option<usize> {
        if up {
            (c[dim] + 1 < self.shape[dim]).then(|| i + self.stride[dim])
        } else {
            (c[dim] > 0).then(|| i - self.stride[dim])
        }
    }

    /// Appends the face neighbours of cell `i` (two per dim, fewer at the border).
    pub fn neighbours(&self, i: usize, out: &mut Vec<usize>) {
        let c = self.coords(i);
        for d in 0..self.n {
            for up in [false, true] {
                if let Some(j) = self.step(i, &c, d, up) {
                    out.push(j);
                }
            }
        }
    }

    /// A point's coordinates in the active dims: pixels from the space's corner in x and y,
    /// then t, u, v in [0, 1).
    #[inline]
    fn position(&self, q: &SamplePoint) -> [f64; MAX_DIMS] {
        let mut p = [0.0; MAX_DIMS];
        p[0] = f64::from(q.film[0]) - f64::from(self.space.x0);
        p[1] = f64::from(q.film[1]) - f64::from(self.space.y0);
        let mut d = 2;
        if self.space.dims.time {
            p[d] = f64::from(q.time);
            d += 1;
        }
        if self.space.dims.lens {
            p[d] = f64::from(q.lens[0]);
            p[d + 1] = f64::from(q.lens[1]);
        }
        p
    }

    /// The extent of cell coordinate `k` along `dim`, in the units of [`Self::position`].
    #[inline]
    fn extent(&self, dim: usize, k: u32) -> (f64, f64) {
        if dim < 2 {
            let limit = f64::from(if dim == 0 {
                self.space.width()
            } else {
                self.space.height()
            });
            let lo = f64::from(k) * self.cell_size;
            (lo, (lo + self.cell_size).min(limit))
        } else {
            let b = f64::from(self.shape[dim]);
            (f64::from(k) / b, f64::from(k + 1) / b)
        }
    }

    /// The box of cell `i`: pixels from the space's corner in x and y, [0, 1] in the others.
    pub fn bounds(&self, i: usize) -> ([f64; MAX_DIMS], [f64; MAX_DIMS]) {
        let c = self.coords(i);
        let mut lo = [0.0; MAX_DIMS];
        let mut hi = [0.0; MAX_DIMS];
        for d in 0..self.n {
            (lo[d], hi[d]) = self.extent(d, c[d]);
        }
        (lo, hi)
    }

    /// The cell coordinate along `dim` of position `v` (in the units of [`Self::position`]).
    #[inline]
    fn coord(&self, dim: usize, v: f64) -> u32 {
        let unit = if dim < 2 {
            self.cell_size
        } else {
            1.0 / f64::from(self.shape[dim])
        };
        // `as` truncates, which is floor for the non-negative values `max` leaves (and costs
        // no call to libm's floor on targets without SSE4.1).
        ((v / unit).max(0.0) as u32).min(self.shape[dim] - 1)
    }

    /// The cell a point lies in and its offsets inside the cell, each in [0, 1).
    #[inline]
    pub fn locate(&self, q: &SamplePoint) -> (usize, [f32; MAX_DIMS]) {
        let p = self.position(q);
        if self.pixel_cells {
            self.locate_in_pixel_cells(&p)
        } else {
            self.locate_at(&p)
        }
    }

    /// The cell of position `p` (in the units of [`Self::position`]) and the offsets in it.
    #[inline]
    fn locate_at(&self, p: &[f64; MAX_DIMS]) -> (usize, [f32; MAX_DIMS]) {
        let mut c = [0; MAX_DIMS];
        let mut off = [0.0; MAX_DIMS];
        for d in 0..self.n {
            let k = self.coord(d, p[d]);
            let (lo, hi) = self.extent(d, k);
            c[d] = k;
            off[d] = (((p[d] - lo) / (hi - lo)) as f32).clamp(0.0, crate::space::ONE_MINUS_EPSILON);
        }
        (self.index(&c), off)
    }

    /// [`Self::locate`] for every point of `batch`, in parallel, into `out` (cell, offsets).
    pub fn locate_all(&self, batch: &[SamplePoint], out: &mut Vec<(u32, [f32; MAX_DIMS])>) {
        batch
            .par_iter()
            .with_min_len(256)
            .map(|q| {
                let (cell, off) = self.locate(q);
                (cell as u32, off)
            })
            .collect_into_vec(out);
    }

    /// [`Self::locate`] when cells are whole pixels with one interval along every other dim:
    /// the same arithmetic without the divisions by a unit of 1.
    #[inline]
    fn locate_in_pixel_cells(&self, p: &[f64; MAX_DIMS]) -> (usize, [f32; MAX_DIMS]) {
        let mut off = [0.0; MAX_DIMS];
        let one = crate::space::ONE_MINUS_EPSILON;
        let kx = (p[0].max(0.0) as u32).min(self.shape[0] - 1);
        let ky = (p[1].max(0.0) as u32).min(self.shape[1] - 1);
        off[0] = ((p[0] - f64::from(kx)) as f32).clamp(0.0, one);
        off[1] = ((p[1] - f64::from(ky)) as f32).clamp(0.0, one);
        for d in 2..self.n {
            off[d] = (p[d] as f32).clamp(0.0, one);
        }
        (
            kx as usize * self.stride[0] + ky as usize * self.stride[1],
            off,
        )
    }

    /// The sample point at offsets `u` (each in [0, 1)) inside cell `i`; its pixel is where it
    /// falls, its index is left 0 for the caller.
    pub fn point(&self, i: usize, u: &[f32; MAX_DIMS]) -> SamplePoint {
        let c = self.coords(i);
        let mut p = [0.5f64; MAX_DIMS];
        for d in 0..self.n {
            let (lo, hi) = self.extent(d, c[d]);
            p[d] = lo + f64::from(u[d]) * (hi - lo);
        }
        // The raster coordinate in f32, nudged by ulps where rounding carried it out of the
        // cell (10 + 0.49999997 rounds to 10.5): a point lies in the cell it was drawn for, as
        // `locate` sees it.
        let film_axis = |d: usize, origin: u32, limit: u32| {
            let v = p[d];
            let k = (v.max(0.0) as u32).min(limit.saturating_sub(1));
            let px = origin + k;
            let mut f = in_pixel(px, (v - f64::from(k)).clamp(0.0, 1.0) as f32);
            for _ in 0..8 {
                let got = self.coord(d, f64::from(f) - f64::from(origin));
                let up = f32::from_bits(f.to_bits() + 1);
                if got > c[d] && f > px as f32 {
                    f = f32::from_bits(f.to_bits() - 1);
                } else if got < c[d] && f64::from(up) < f64::from(px) + 1.0 {
                    f = up;
                } else {
                    break;
                }
            }
            (px, f)
        };
        let (px, fx) = film_axis(0, self.space.x0, self.space.width());
        let (py, fy) = film_axis(1, self.space.y0, self.space.height());
        let clamp01 = |v: f64| (v as f32).min(crate::space::ONE_MINUS_EPSILON);
        let mut d = 2;
        let time = if self.space.dims.time {
            d += 1;
            clamp01(p[2])
        } else {
            0.5
        };
        let lens = if self.space.dims.lens {
            [clamp01(p[d]), clamp01(p[d + 1])]
        } else {
            [0.5; 2]
        };
        SamplePoint {
            pixel: [px, py],
            index: 0,
            film: [fx, fy],
            time,
            lens,
        }
    }

    /// The pixel of the point at offsets `u` inside cell `i` (what [`Self::point`] would give,
    /// without the rest of the point).
    #[inline]
    pub fn pixel(&self, i: usize, u: &[f32; MAX_DIMS]) -> [u32; 2] {
        let image = i / self.stride[0];
        let c = [
            image % self.shape[0] as usize,
            image / self.shape[0] as usize,
        ];
        let limit = [self.space.width(), self.space.height()];
        let origin = [self.space.x0, self.space.y0];
        std::array::from_fn(|d| {
            let (lo, hi) = self.extent(d, c[d] as u32);
            let v = lo + f64::from(u[d]) * (hi - lo);
            origin[d] + (v.max(0.0) as u32).min(limit[d].saturating_sub(1))
        })
    }

    /// Cells per pixel side when a pixel holds a whole number of cells (cellsize 1, 1/2,
    /// 1/3...): then a cell lies in one pixel and [`Self::pixel_of_cell`] needs no offsets.
    pub fn cells_per_pixel(&self) -> Option<u32> {
        let k = 1.0 / self.cell_size;
        (self.cell_size <= 1.0 && k.fract() == 0.0).then_some(k as u32)
    }

    /// The pixel holding cell `i` when a pixel holds `per_pixel` cells per side (from
    /// [`Self::cells_per_pixel`]).
    #[inline]
    pub fn pixel_of_cell(&self, i: usize, per_pixel: u32) -> [u32; 2] {
        let c = self.coords(i);
        // Whole-pixel cells (the default) need no division here: this runs once per adaptive
        // sample.
        let (px, py) = if per_pixel == 1 {
            (c[0], c[1])
        } else {
            (c[0] / per_pixel, c[1] / per_pixel)
        };
        [self.space.x0 + px, self.space.y0 + py]
    }

    /// The image cell (x, y cell coordinates) holding the centre of pixel `(px, py)`, given
    /// relative to the space's corner.
    pub fn image_cell_of_pixel(&self, px: u32, py: u32) -> (u32, u32) {
        let at = |p: u32, d: usize| {
            ((((f64::from(p) + 0.5) / self.cell_size).floor()) as u32).min(self.shape[d] - 1)
        };
        (at(px, 0), at(py, 1))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::space::Dims;

    /// A space of `w` x `h` pixels from (10, 20), with time and lens dims as asked.
    pub(crate) fn space(w: u32, h: u32, time: bool, lens: bool) -> RenderingSpace {
        RenderingSpace {
            x0: 10,
            x1: 10 + w,
            y0: 20,
            y1: 20 + h,
            dims: Dims { time, lens },
        }
    }

    #[test]
    fn indices_and_coords_round_trip() {
        let g = CellGrid::new(space(7, 5, true, true), 1.0, 3);
        assert_eq!(g.shape(), [7, 5, 3, 3, 3]);
        assert_eq!(g.len(), 7 * 5 * 27);
        for i in 0..g.len() {
            assert_eq!(g.index(&g.coords(i)), i);
        }
        // Dims of one interval (bins 1) and of two, and half-pixel cells.
        for (cs, bins) in [(1.0, 1), (1.0, 2), (0.5, 1)] {
            let g = CellGrid::new(space(7, 5, true, true), cs, bins);
            for i in 0..g.len() {
                let c = g.coords(i);
                assert_eq!(g.index(&c), i);
                assert!((0..5).all(|d| c[d] < g.shape()[d]));
            }
        }
        // A pixel's cells are consecutive.
        assert_eq!(g.coords(26)[..2], [0, 0]);
        assert_eq!(g.coords(27)[..2], [1, 0]);
    }

    #[test]
    fn points_fall_in_their_cells() {
        for (cs, (w, h)) in [(1.0, (7, 5)), (0.5, (3, 3)), (2.0, (5, 3)), (1.5, (4, 4))] {
            let g = CellGrid::new(space(w, h, true, false), cs, 2);
            for i in 0..g.len() {
                for u in [[0.0; 5], [0.5; 5], [crate::space::ONE_MINUS_EPSILON; 5]] {
                    let q = g.point(i, &u);
                    let (j, off) = g.locate(&q);
                    assert_eq!(j, i, "cellsize {cs} cell {i} u {u:?} -> {q:?}");
                    assert!(off.iter().all(|o| (0.0..1.0).contains(o)));
                    for a in 0..2 {
                        let f = f64::from(q.film[a]);
                        assert!(f >= f64::from(q.pixel[a]) && f < f64::from(q.pixel[a]) + 1.0);
                    }
                    assert!(q.pixel[0] < 10 + w && q.pixel[1] < 20 + h);
                    assert_eq!(g.pixel(i, &u), q.pixel);
                }
            }
        }
    }

    #[test]
    fn pixel_cells_locate_as_the_general_rule_does() {
        let mut rng = crate::rng::Pcg32::new(3, 0);
        let mut next = || f64::from(rng.next_f32());
        for (time, lens) in [(false, false), (true, false), (true, true)] {
            let g = CellGrid::new(space(7, 5, time, lens), 1.0, 1);
            assert!(g.pixel_cells);
            for _ in 0..2000 {
                // Inside the space, on its edges and a little outside.
                let mut p = [0.0; MAX_DIMS];
                p[0] = next() * 9.0 - 1.0;
                p[1] = next() * 7.0 - 1.0;
                for v in &mut p[2..] {
                    *v = (next() * 1.2 - 0.1) as f32 as f64;
                }
                p[0] = (p[0] as f32).floor() as f64 + [0.0, 0.5, next()][(next() * 3.0) as usize];
                assert_eq!(g.locate_in_pixel_cells(&p), g.locate_at(&p), "{p:?}");
            }
        }
    }

    #[test]
    fn a_cell_inside_one_pixel_knows_its_pixel() {
        for (cs, per) in [
            (1.0, Some(1)),
            (0.5, Some(2)),
            (0.25, Some(4)),
            (1.5, None),
            (0.75, None),
        ] {
            // Cells cut in time, and whole-pixel cells (the shortcut) when cellsize is 1.
            for (time, bins) in [(true, 2), (false, 1)] {
                let g = CellGrid::new(space(6, 4, time, false), cs, bins);
                assert_eq!(g.cells_per_pixel(), per, "cellsize {cs}");
                let Some(per) = per else { continue };
                for i in 0..g.len() {
                    for u in [[0.0; MAX_DIMS], [0.999; MAX_DIMS]] {
                        assert_eq!(g.pixel_of_cell(i, per), g.pixel(i, &u), "cell {i}");
                    }
                }
            }
        }
    }

    #[test]
    fn neighbours_stay_inside() {
        let g = CellGrid::new(space(3, 2, false, true), 1.0, 2);
        let mut v = Vec::new();
        g.neighbours(0, &mut v);
        // Corner cell: one neighbour per dim.
        assert_eq!(v.len(), 4);
        v.clear();
        let mid = g.index(&[1, 0, 1, 0, 0]);
        g.neighbours(mid, &mut v);
        assert_eq!(v.len(), 5);
    }
}
