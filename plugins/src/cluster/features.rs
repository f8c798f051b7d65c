//! The feature vector F = (g, s, p) of a cell (docs/algorithm.md §3, paper eq. 2-9).

use super::grid::{CellGrid, Coords, MAX_DIMS};
use super::sums::CellSums;
use rayon::prelude::*;

/// Length of a feature vector: g, s, the level and one position per active dim.
pub const FEATURE_LEN: usize = 3 + MAX_DIMS;

/// A cell's gradient, variance and level after weighting and log-compression
/// ([`FeatureScale::squash`]).
pub type Squashed = [f32; 3];

/// A weighted, normalised feature vector `[g, s, level, p...]`; entries past `3 + dims` are 0.
pub type Feature = [f64; FEATURE_LEN];

/// The level `I` of every cell: its mean luminance, or for a cell without samples the mean of
/// its face neighbours that have some (0 when none has), so that derivatives are defined
/// everywhere while a sparse grid fills in.
pub fn level(grid: &CellGrid, sums: &CellSums, i: usize) -> f32 {
    if let Some(m) = sums.mean(i) {
        return m as f32;
    }
    let c = grid.coords(i);
    let (mut total, mut n) = (0.0, 0u32);
    for d in 0..grid.dims() {
        for up in [false, true] {
            if let Some(m) = grid.step(i, &c, d, up).and_then(|j| sums.mean(j)) {
                total += m;
                n += 1;
            }
        }
    }
    if n == 0 {
        0.0
    } else {
        (total / f64::from(n)) as f32
    }
}

/// The raw affine-invariant gradient `g` and variance `s` of cell `i`, from the levels.
pub fn raw(grid: &CellGrid, sums: &CellSums, levels: &[f32], i: usize) -> (f32, f32) {
    (raw_gradient(grid, levels, i), raw_variance(grid, sums, i))
}

/// The raw affine-invariant gradient `g` of cell `i`, from the levels.
pub fn raw_gradient(grid: &CellGrid, levels: &[f32], i: usize) -> f32 {
    let c = grid.coords(i);
    let g = interior_gradient(grid, levels, i, &c).unwrap_or_else(|| gradient(grid, levels, i, &c));
    g as f32
}

/// The raw variance `s` of cell `i`, from the sums alone.
pub fn raw_variance(grid: &CellGrid, sums: &CellSums, i: usize) -> f32 {
    variance(grid, sums, i, &grid.coords(i)) as f32
}

/// [`gradient`] for a cell with both neighbours along every dim of more than one cell (and
/// no dim of two): the same sums without the border cases, term for term, so the same value.
/// Dims of one cell contribute nothing and are skipped.
#[inline]
fn interior_gradient(grid: &CellGrid, levels: &[f32], i: usize, c: &Coords) -> Option<f64> {
    let mut live = [0usize; MAX_DIMS];
    let mut m = 0;
    for (d, (&len, &k)) in grid.shape().iter().zip(c).enumerate() {
        if len == 1 {
            continue;
        }
        if len == 2 || k == 0 || k + 1 == len {
            return None;
        }
        live[m] = grid.stride(d);
        m += 1;
    }
    let at = |j: usize| f64::from(levels[j]);
    let here = at(i);
    let mut d1 = [0.0; MAX_DIMS];
    let mut d2 = [0.0; MAX_DIMS];
    for k in 0..m {
        let (p, q) = (at(i + live[k]), at(i - live[k]));
        d1[k] = (p - q) / 2.0;
        d2[k] = p - 2.0 * here + q;
    }
    let (mut h, mut jj) = (0.0, 0.0);
    for a in 0..m {
        for b in a + 1..m {
            let (sa, sb) = (live[a], live[b]);
            let p = (at(i + sb + sa) - at(i + sb - sa)) / 2.0;
            let q = (at(i - sb + sa) - at(i - sb - sa)) / 2.0;
            let dab = (p - q) / 2.0;
            h += d2[a] * d2[b] - dab * dab;
            jj += d2[a] * d1[b] * d1[b] - 2.0 * d1[a] * d1[b] * dab + d2[b] * d1[a] * d1[a];
        }
    }
    Some((h * h / (jj * jj + 1.0)).sqrt())
}

/// The affine-invariant gradient of cell `i` at coordinates `c` (eq. 3-8), any cell.
fn gradient(grid: &CellGrid, levels: &[f32], i: usize, c: &Coords) -> f64 {
    let c = *c;
    let n = grid.dims();
    let at = |j: usize| f64::from(levels[j]);
    // First derivative along `d` at cell `j` (coords `cj`): central, one-sided at the border.
    let first = |j: usize, cj: &Coords, d: usize| -> f64 {
        match (grid.step(j, cj, d, true), grid.step(j, cj, d, false)) {
            (Some(p), Some(m)) => (at(p) - at(m)) / 2.0,
            (Some(p), None) => at(p) - at(j),
            (None, Some(m)) => at(j) - at(m),
            (None, None) => 0.0,
        }
    };
    let mut d1 = [0.0; MAX_DIMS];
    let mut d2 = [0.0; MAX_DIMS];
    for d in 0..n {
        d1[d] = first(i, &c, d);
        d2[d] = match (grid.step(i, &c, d, true), grid.step(i, &c, d, false)) {
            (Some(p), Some(m)) => at(p) - 2.0 * at(i) + at(m),
            // Two cells along a dim (bins = 2) carry no curvature.
            _ => 0.0,
        };
    }
    let (mut h, mut jj) = (0.0, 0.0);
    for a in 0..n {
        for b in a + 1..n {
            // I_ab: the derivative along b of I_a (eq. 6).
            let shifted = |up: bool| {
                grid.step(i, &c, b, up).map(|j| {
                    let mut cj = c;
                    cj[b] = if up { c[b] + 1 } else { c[b] - 1 };
                    first(j, &cj, a)
                })
            };
            let dab = match (shifted(true), shifted(false)) {
                (Some(p), Some(m)) => (p - m) / 2.0,
                (Some(p), None) => p - d1[a],
                (None, Some(m)) => d1[a] - m,
                (None, None) => 0.0,
            };
            // Eq. 3-4 for the pair, summed over pairs (eq. 8).
            h += d2[a] * d2[b] - dab * dab;
            jj += d2[a] * d1[b] * d1[b] - 2.0 * d1[a] * d1[b] * dab + d2[b] * d1[a] * d1[a];
        }
    }
    // Eq. 7.
    (h * h / (jj * jj + 1.0)).sqrt()
}

/// The variance `s` of cell `i` (eq. 9). A cell with fewer than two samples has no variance
/// of its own; it takes the mean of its face neighbours' that have one (0 when none has).
/// Eq. 9's 0 would make every such cell look noise-free: with 2 to 4 samples per pixel over
/// 4 to 8 cells most cells hold one sample, and the clusters would follow who got two.
fn variance(grid: &CellGrid, sums: &CellSums, i: usize, c: &Coords) -> f64 {
    if sums.count[i] >= 2 {
        return sums.variance(i);
    }
    let (mut total, mut n) = (0.0, 0u32);
    for d in 0..grid.dims() {
        for up in [false, true] {
            if let Some(j) = grid.step(i, c, d, up).filter(|&j| sums.count[j] >= 2) {
                total += sums.variance(j);
                n += 1;
            }
        }
    }
    if n == 0 {
        0.0
    } else {
        total / f64::from(n)
    }
}

/// How the raw features become one weighted vector: robust scales for g and s, the weights,
/// and the position unit.
#[derive(Clone, Copy, Debug)]
pub struct FeatureScale {
    /// sqrt(gradweight) / (the median non-zero g).
    pub g: f64,
    /// sqrt(varweight) / (the median non-zero s).
    pub s: f64,
    /// sqrt(posweight) / L, with L the side in cells of a cube of `maxclustercells` cells.
    pub p: f64,
    /// sqrt(levelweight) / (the median non-zero level).
    pub level: f64,
    /// Whether g and s are log-compressed (ln(1 + x)) after scaling.
    pub log: bool,
}

impl FeatureScale {
    /// Scales for the current raw features: the median of the non-zero values of g and of s
    /// over the cells that have samples, so that their units do not matter.
    pub fn measure(
        sums: &CellSums,
        g: &[f32],
        s: &[f32],
        levels: &[f32],
        weights: [f64; 4],
        position_unit: f64,
        log: bool,
    ) -> Self {
        let median = |v: &[f32]| -> f64 {
            let mut nz: Vec<f32> = v
                .par_iter()
                .zip(&sums.count)
                .filter(|(x, &n)| n > 0 && **x > 0.0 && x.is_finite())
                .map(|(x, _)| *x)
                .collect();
            if nz.is_empty() {
                return 1.0;
            }
            let k = nz.len() / 2;
            let (_, m, _) = nz.select_nth_unstable_by(k, f32::total_cmp);
            f64::from(*m)
        };
        Self {
            g: weights[0].sqrt() / median(g),
            s: weights[1].sqrt() / median(s),
            p: weights[2].sqrt() / position_unit.max(1e-9),
            level: weights[3].sqrt() / median(levels),
            log,
        }
    }

    /// The weighted and compressed `(g, s, level)` of a cell: the part of its feature vector
    /// that depends on its samples. Kept per cell, it spares recomputing the logarithms of a
    /// cell's old feature when the cell changes.
    #[inline]
    pub fn squash(&self, g: f32, s: f32, level: f32) -> Squashed {
        let squash = |x: f64| {
            if self.log {
                // ln(1 + x) in f32 (the features are f32 wherever they are kept) by `ln`, not
                // `ln_1p`: glibc's log1pf took 16.7 ns a call against 5.0 ns (1% of a render's
                // cycles); for x >= 0 they differ by at most 2.4e-7, two ulps at the features'
                // typical size of 1 (no image changed).
                (1.0 + (x.max(0.0).min(f64::from(f32::MAX)) as f32)).ln()
            } else {
                x as f32
            }
        };
        [
            squash(f64::from(g) * self.g),
            squash(f64::from(s) * self.s),
            squash(f64::from(level) * self.level),
        ]
    }

    /// The feature vector of a cell with coordinates `c` and squashed values `q`.
    #[inline]
    pub fn feature_of(&self, dims: usize, c: &Coords, q: Squashed) -> Feature {
        let mut f = [0.0; FEATURE_LEN];
        f[0] = f64::from(q[0]);
        f[1] = f64::from(q[1]);
        f[2] = f64::from(q[2]);
        for d in 0..dims {
            f[3 + d] = (f64::from(c[d]) + 0.5) * self.p;
        }
        f
    }

    /// The distance between the features of two face-neighbour cells that agree in g and s:
    /// one cell step. The membership test's absolute tolerance.
    pub fn cell_step(&self) -> f64 {
        self.p
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Spectrum;
    use crate::space::{Dims, RenderingSpace};

    fn grid(w: u32, h: u32) -> CellGrid {
        let sp = RenderingSpace::whole(w, h, Dims::default());
        CellGrid::new(sp, 1.0, 2)
    }

    fn filled(g: &CellGrid, f: impl Fn(u32, u32) -> f32) -> (CellSums, Vec<f32>) {
        let mut s = CellSums::new(g);
        for i in 0..g.len() {
            let c = g.coords(i);
            s.add(i, &[0.5; 5], Spectrum::splat(f(c[0], c[1])));
        }
        let levels = (0..g.len()).map(|i| level(g, &s, i)).collect();
        (s, levels)
    }

    #[test]
    fn straight_edges_and_planes_have_no_affine_gradient() {
        // H and J vanish wherever the level depends on one direction only: a ramp, a step
        // along x, a slanted plane. The affine-invariant gradient sees corners, not lines.
        let g = grid(8, 8);
        for f in [
            (|x: u32, _y: u32| x as f32 * 0.1) as fn(u32, u32) -> f32,
            |x, _| if x < 4 { 0.0 } else { 1.0 },
            |x, y| 0.1 * x as f32 + 0.2 * y as f32,
        ] {
            let (s, lv) = filled(&g, f);
            for i in 0..g.len() {
                assert!(raw(&g, &s, &lv, i).0.abs() < 1e-5);
            }
        }
    }

    #[test]
    fn a_corner_has_an_affine_gradient() {
        let g = grid(8, 8);
        let (s, lv) = filled(&g, |x, y| if x >= 4 && y >= 4 { 1.0 } else { 0.0 });
        let at = |x, y| raw(&g, &s, &lv, g.index(&[x, y, 0, 0, 0])).0;
        assert!(at(4, 4) > 0.1, "{}", at(4, 4));
        assert_eq!(at(0, 0), 0.0);
    }

    #[test]
    fn the_interior_shortcut_gives_the_same_gradient_bit_for_bit() {
        // Every combination of active dims and bins 1 (dims of one cell), 2 (no shortcut)
        // and 3, over random levels.
        let mut rng = crate::rng::Pcg32::new(7, 0);
        let mut next = || rng.next_f32();
        let mut checked = 0;
        for (time, lens) in [(false, false), (true, false), (false, true), (true, true)] {
            for bins in [1, 2, 3] {
                let sp = RenderingSpace::whole(6, 5, Dims { time, lens });
                let g = CellGrid::new(sp, 1.0, bins);
                let levels: Vec<f32> = (0..g.len()).map(|_| next() * 4.0).collect();
                for i in 0..g.len() {
                    let c = g.coords(i);
                    if let Some(fast) = interior_gradient(&g, &levels, i, &c) {
                        assert_eq!(fast.to_bits(), gradient(&g, &levels, i, &c).to_bits());
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 100, "{checked}");
    }

    #[test]
    fn empty_cells_take_their_neighbours_level() {
        let g = grid(3, 1);
        let mut s = CellSums::new(&g);
        s.add(0, &[0.5; 5], Spectrum::splat(1.0));
        s.add(2, &[0.5; 5], Spectrum::splat(3.0));
        assert_eq!(level(&g, &s, 1), 2.0);
    }
}
