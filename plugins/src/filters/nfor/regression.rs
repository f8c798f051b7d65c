//! NFOR's first-order regression: each pixel's colour is the intercept of a weighted least
//! squares fit of the colours in the window around it on their features' differences from
//! the pixel's own (a plane in feature space), weighted by NL-means on a guide image. Several
//! bandwidths share the window's distances.

// Small fixed-size channel and matrix loops read clearest with indices.
#![allow(clippy::needless_range_loop)]

use super::nlmeans::{weight, Guide, Scratch};
use super::planes::{Planes, Rect, TILE};
use crate::first_hit::FEATURES;

/// Unknowns of the fit: the intercept and one slope per feature.
const D: usize = 1 + FEATURES;
/// The normal equations of one fit: rows 0..D the normal matrix (its lower triangle only:
/// the solve reads no other), rows D..D + 3 the three channels' right-hand sides.
type Normal = [[f32; D]; D + 3];

/// Weights below this add nothing measurable and are skipped.
const MIN_WEIGHT: f32 = 1e-4;

/// With a stride, a pixel the grid's fits reached with less weight than this at some
/// bandwidth gets its own fit too (its own fit predicts it with weight 1): an edge or a thin
/// object the grid's pixels do not resemble. At 1 the Cornell box after the cluster sampler
/// (8 spp) measured 10% worse than fits on every pixel, at 2 level with them
/// (docs/reconstruction.md, "Cost").
const OWN_FIT_BELOW: f32 = 2.0;

/// What one regression reads.
#[derive(Clone, Copy)]
pub(crate) struct Regression<'a> {
    /// The colours fitted (3 channels).
    pub color: &'a Planes,
    /// The features regressed on.
    pub features: &'a Planes,
    /// Whether each pixel met a surface: pixels of the other kind are left out of its fit.
    pub hit: &'a [bool],
    /// The window's radius in pixels.
    pub radius: usize,
    /// The ridge on the slopes, relative to the sum of weights.
    pub ridge: f32,
    /// Fits on every `stride`-th pixel in each direction (1: every pixel).
    pub stride: usize,
}

/// The smallest rectangle within `tile` holding its pixels marked in `fit`, from the tile's
/// first column; None if none is. The patch distances' running sums along a row start at
/// the rectangle's first column: starting at the tile's, they come out the same whichever
/// pixels are marked, so a band's fits are the whole image's, bit for bit (a pixel near a
/// band's halo edge may take an own fit that it does not in the whole image).
fn marked_box(tile: Rect, fit: &[bool], w: usize) -> Option<Rect> {
    let mut b: Option<Rect> = None;
    for y in tile.y0..tile.y1 {
        for x in tile.x0..tile.x1 {
            if fit[y * w + x] {
                let r = b.get_or_insert(Rect {
                    x0: tile.x0,
                    x1: x + 1,
                    y0: y,
                    y1: y + 1,
                });
                r.x1 = r.x1.max(x + 1);
                r.y1 = y + 1;
            }
        }
    }
    b
}

impl Regression<'_> {
    /// The fitted image for each bandwidth `k` of `ks`, the weights from `guide` (whose
    /// `k2` is ignored: each bandwidth scales the distances). Collaborative, as Tungsten's:
    /// each fit predicts every pixel of its window, and a pixel is the weighted mean of the
    /// predictions it received. Fits are made on every `stride`-th pixel in each direction,
    /// then on each pixel those reached with less than `OWN_FIT_BELOW` weight in all
    /// (docs/reconstruction.md, "Cost"). Tiles are summed in a fixed order.
    pub fn run(&self, guide: Guide<'_>, ks: &[f32]) -> Vec<Planes> {
        let (w, h) = (self.color.w, self.color.h);
        let nk = ks.len();
        let guide = Guide { k2: 1.0, ..guide };
        let inv_k2: Vec<f32> = ks.iter().map(|k| 1.0 / (k * k)).collect();
        // Per pixel, per bandwidth: the predictions' weighted sums and their weight.
        let mut sums = Planes::new(w, h, 4 * nk);
        let s = self.stride.max(1);
        let grid: Vec<bool> = (0..w * h)
            .map(|i| (i % w) % s == 0 && (i / w) % s == 0)
            .collect();
        self.add_fits(guide, &inv_k2, &grid, &mut sums);
        if s > 1 {
            let own: Vec<bool> = (0..w * h)
                .map(|i| !grid[i] && (0..nk).any(|k| sums.px(i)[4 * k + 3] < OWN_FIT_BELOW))
                .collect();
            self.add_fits(guide, &inv_k2, &own, &mut sums);
        }
        (0..nk)
            .map(|k| {
                sums.map(3, |_, v, o| {
                    let s = &v[k * 4..k * 4 + 4];
                    for c in 0..3 {
                        o[c] = if s[3] > 0.0 { s[c] / s[3] } else { 0.0 };
                    }
                })
            })
            .collect()
    }

    /// Adds to `sums` the predictions of the fits of the pixels marked in `fit`. One row of
    /// tiles at a time, so that only that row's tiles are held besides the sums; a tile
    /// fits only the bounding box of its marked pixels.
    fn add_fits(&self, guide: Guide<'_>, inv_k2: &[f32], fit: &[bool], sums: &mut Planes) {
        use rayon::prelude::*;
        let (w, h) = (self.color.w, self.color.h);
        let nk = inv_k2.len();
        let (tw, th) = (w.div_ceil(TILE), h.div_ceil(TILE));
        for ty in 0..th {
            let tiles: Vec<(Rect, Vec<f32>)> = (0..tw)
                .into_par_iter()
                .filter_map(|tx| {
                    let tile = Rect {
                        x0: tx * TILE,
                        x1: ((tx + 1) * TILE).min(w),
                        y0: ty * TILE,
                        y1: ((ty + 1) * TILE).min(h),
                    };
                    let rect = marked_box(tile, fit, w)?;
                    Some(self.tile(guide, inv_k2, rect, fit))
                })
                .collect();
            for (r, vals) in tiles {
                let rw = r.w() * 4 * nk;
                for (j, y) in (r.y0..r.y1).enumerate() {
                    let dst = &mut sums.data[(y * w + r.x0) * 4 * nk..][..rw];
                    for (d, v) in dst.iter_mut().zip(&vals[j * rw..][..rw]) {
                        *d += v;
                    }
                }
            }
        }
    }

    /// The fits of the pixels of `rect` marked in `fit` and their predictions: the rectangle
    /// grown by the window (clipped to the image) and, per pixel of it, per bandwidth, the
    /// predictions' weighted sums (3) and weight.
    fn tile(&self, guide: Guide<'_>, inv_k2: &[f32], rect: Rect, fit: &[bool]) -> (Rect, Vec<f32>) {
        let (w, h) = (self.color.w, self.color.h);
        let nk = inv_k2.len();
        let rw = rect.w();
        let r = self.radius as i64;
        // Each offset with its index step.
        let offsets: Vec<((i64, i64), i64)> = (-r..=r)
            .flat_map(|dy| (-r..=r).map(move |dx| ((dx, dy), dy * w as i64 + dx)))
            .collect();
        let mut scratch = Scratch::default();
        // The distances offset by offset, each over the rectangle.
        let no = offsets.len();
        let mut dist = vec![0.0f32; rect.len() * no];
        let mut row = Vec::new();
        for (o, &(off, _)) in offsets.iter().enumerate() {
            guide.patch_distances(off, rect, &mut scratch, &mut row);
            dist[o * rect.len()..(o + 1) * rect.len()].copy_from_slice(&row);
        }
        let x_of = |p: usize, q: usize| {
            let (fp, fq) = (self.features.px(p), self.features.px(q));
            let mut x = [1.0f32; D];
            for k in 0..FEATURES {
                x[k + 1] = fq[k] - fp[k];
            }
            x
        };
        let out_rect = Rect {
            x0: rect.x0.saturating_sub(self.radius),
            x1: (rect.x1 + self.radius).min(w),
            y0: rect.y0.saturating_sub(self.radius),
            y1: (rect.y1 + self.radius).min(h),
        };
        let ow = out_rect.w();
        let mut out = vec![0.0f32; out_rect.len() * 4 * nk];
        // The marked pixels (index in the rectangle, in the image), LANES fits at a time:
        // per offset, each lane's neighbour's features' differences and colour, and its
        // distance (infinite where the neighbour is outside or of the other kind).
        let fits: Vec<(usize, usize)> = (0..rect.len())
            .map(|j| (j, (rect.y0 + j / rw) * w + rect.x0 + j % rw))
            .filter(|&(_, p)| fit[p])
            .collect();
        let mut xs = vec![[[0.0f32; LANES]; D + 3]; no];
        let mut ds = vec![[f32::INFINITY; LANES]; no];
        let mut wts = vec![[0.0f32; LANES]; no];
        let mut preds = vec![[[0.0f32; LANES]; 3]; no];
        for chunk in fits.chunks(LANES) {
            for (o, &(_, step)) in offsets.iter().enumerate() {
                let (x, d) = (&mut xs[o], &mut ds[o]);
                for l in 0..LANES {
                    let near = chunk.get(l).and_then(|&(j, p)| {
                        let dj = dist[o * rect.len() + j];
                        let q = (p as i64 + step) as usize;
                        (dj != f32::INFINITY && self.hit[q] == self.hit[p])
                            .then(|| (dj, x_of(p, q), q))
                    });
                    let Some((dj, xq, q)) = near else {
                        d[l] = f32::INFINITY;
                        for v in x.iter_mut() {
                            v[l] = 0.0;
                        }
                        continue;
                    };
                    d[l] = dj;
                    for i in 0..D {
                        x[i][l] = xq[i];
                    }
                    for c in 0..3 {
                        x[D + c][l] = self.color.px(q)[c];
                    }
                }
            }
            for (k, &s) in inv_k2.iter().enumerate() {
                let mut a = [[0.0f32; LANES]; LANE_SUMS];
                for o in 0..no {
                    let (d, wt) = (&ds[o], &mut wts[o]);
                    for l in 0..LANES {
                        let v = if d[l] == f32::INFINITY {
                            0.0
                        } else {
                            weight(d[l] * s)
                        };
                        wt[l] = if v >= MIN_WEIGHT { v } else { 0.0 };
                    }
                    accumulate_lanes(&mut a, &xs[o], wt);
                }
                // Each lane's fit, then its predictions at every offset in lanes.
                let mut beta = [[[0.0f32; LANES]; D]; 3];
                for l in 0..chunk.len() {
                    let b = solve(&lane_normal(&a, l), self.ridge);
                    for c in 0..3 {
                        for i in 0..D {
                            beta[c][i][l] = b[c][i];
                        }
                    }
                }
                for (o, pred) in preds.iter_mut().enumerate() {
                    for c in 0..3 {
                        // Summed in the order of the features from -0 (as `Iterator::sum`).
                        let mut v = [-0.0f32; LANES];
                        for i in 0..D {
                            for l in 0..LANES {
                                v[l] += beta[c][i][l] * xs[o][i][l];
                            }
                        }
                        pred[c] = v;
                    }
                }
                for (l, &(_, p)) in chunk.iter().enumerate() {
                    for (o, &(_, step)) in offsets.iter().enumerate() {
                        let wt = wts[o][l];
                        if wt == 0.0 {
                            continue;
                        }
                        let q = (p as i64 + step) as usize;
                        let local = (q / w - out_rect.y0) * ow + q % w - out_rect.x0;
                        let dst = &mut out[(local * nk + k) * 4..][..4];
                        for c in 0..3 {
                            dst[c] += wt * preds[o][c][l];
                        }
                        dst[3] += wt;
                    }
                }
            }
        }
        (out_rect, out)
    }
}

/// Fits made together, one per vector lane.
const LANES: usize = 16;
/// The normal equations' sums in lanes: the normal matrix's lower triangle row by row, then
/// the three channels' right-hand sides.
const LANE_SUMS: usize = D * (D + 1) / 2 + 3 * D;

/// Adds one neighbour per lane (features' differences and colours `x`, weights `wt`, zero
/// where a lane has none) to the lanes' normal equations: the weight times one factor,
/// times the other.
#[inline]
fn accumulate_lanes(
    a: &mut [[f32; LANES]; LANE_SUMS],
    x: &[[f32; LANES]; D + 3],
    wt: &[f32; LANES],
) {
    let mut m = 0;
    for i in 0..D {
        let wx: [f32; LANES] = std::array::from_fn(|l| wt[l] * x[i][l]);
        for j in 0..=i {
            for l in 0..LANES {
                a[m][l] += wx[l] * x[j][l];
            }
            m += 1;
        }
    }
    for c in 0..3 {
        let wy: [f32; LANES] = std::array::from_fn(|l| wt[l] * x[D + c][l]);
        for i in 0..D {
            for l in 0..LANES {
                a[m][l] += wy[l] * x[i][l];
            }
            m += 1;
        }
    }
}

/// Lane `l`'s normal equations.
fn lane_normal(a: &[[f32; LANES]; LANE_SUMS], l: usize) -> Normal {
    let mut n: Normal = [[0.0; D]; D + 3];
    let mut m = 0;
    for i in 0..D {
        for j in 0..=i {
            n[i][j] = a[m][l];
            m += 1;
        }
    }
    for c in 0..3 {
        for i in 0..D {
            n[D + c][i] = a[m][l];
            m += 1;
        }
    }
    n
}

/// The three channels' fits (intercept and slopes) from the normal equations `a`, with a
/// ridge on the slopes of `ridge` times the sum of weights; the weighted mean where the
/// system is singular.
fn solve(a: &Normal, ridge: f32) -> [[f32; D]; 3] {
    let sw = f64::from(a[0][0]);
    if sw <= 0.0 {
        return [[0.0; D]; 3];
    }
    let mean = [0, 1, 2].map(|c| {
        let mut b = [0.0f32; D];
        b[0] = (f64::from(a[D + c][0]) / sw) as f32;
        b
    });
    let mut m = [[0.0f64; D]; D];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate().take(i + 1) {
            *v = f64::from(a[i][j]);
        }
    }
    for (i, row) in m.iter_mut().enumerate().skip(1) {
        row[i] += f64::from(ridge) * sw + 1e-12;
    }
    // Cholesky: m = L L^T, L in the lower triangle.
    for j in 0..D {
        let mut s = m[j][j];
        for k in 0..j {
            s -= m[j][k] * m[j][k];
        }
        if s <= 0.0 || !s.is_finite() {
            return mean;
        }
        let l = s.sqrt();
        m[j][j] = l;
        for i in j + 1..D {
            let mut s = m[i][j];
            for k in 0..j {
                s -= m[i][k] * m[j][k];
            }
            m[i][j] = s / l;
        }
    }
    let mut out = [[0.0f32; D]; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut z = [0.0f64; D];
        for i in 0..D {
            let mut s = f64::from(a[D + c][i]);
            for k in 0..i {
                s -= m[i][k] * z[k];
            }
            z[i] = s / m[i][i];
        }
        let mut b = [0.0f64; D];
        for i in (0..D).rev() {
            let mut s = z[i];
            for k in i + 1..D {
                s -= m[k][i] * b[k];
            }
            b[i] = s / m[i][i];
        }
        if !b.iter().all(|v| v.is_finite()) {
            return mean;
        }
        *o = b.map(|v| v as f32);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Colour = 0.2 + 3 * albedo_r, the albedo a ramp with a jump, every pixel a surface but
    /// `other` (none of its kind near it, its colour 5): the regression with `stride`, its
    /// guide a constant image (every neighbour weighs alike).
    fn linear_image(stride: usize, other: Option<(usize, usize)>) -> (Planes, Planes) {
        let (w, h) = (24, 12);
        let mut features = Planes::new(w, h, FEATURES);
        let mut color = Planes::new(w, h, 3);
        let mut hit = vec![true; w * h];
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let a = (x as f32 * 0.03) + if x > 11 { 0.4 } else { 0.0 } + y as f32 * 0.01;
                features.px_mut(i)[0] = a;
                features.px_mut(i)[6] = 1.0;
                color.px_mut(i).fill(0.2 + 3.0 * a);
            }
        }
        if let Some((x, y)) = other {
            hit[y * w + x] = false;
            color.px_mut(y * w + x).fill(5.0);
        }
        let var = Planes::new(w, h, 3);
        let reg = Regression {
            color: &color,
            features: &features,
            hit: &hit,
            radius: 3,
            ridge: 0.0,
            stride,
        };
        let flat = Planes::new(w, h, 3);
        let guide = Guide {
            image: &flat,
            variance: &var,
            patch: 1,
            k2: 1.0,
        };
        let out = reg.run(guide, &[1.0]).remove(0);
        (out, color)
    }

    #[test]
    fn an_image_linear_in_a_feature_is_reproduced() {
        for stride in [1, 2, 3] {
            let (out, color) = linear_image(stride, None);
            for (o, c) in out.data.iter().zip(&color.data) {
                assert!((o - c).abs() < 1e-4, "stride {stride}: {o} vs {c}");
            }
        }
    }

    #[test]
    fn a_pixel_no_grid_fit_reaches_gets_its_own() {
        // At odd coordinates, of its own kind: no fit on the grid of stride 2 predicts it.
        let (out, color) = linear_image(2, Some((7, 5)));
        for (o, c) in out.data.iter().zip(&color.data) {
            assert!((o - c).abs() < 1e-4, "{o} vs {c}");
        }
    }
}
