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
}

impl Regression<'_> {
    /// The fitted image for each bandwidth `k` of `ks`, the weights from `guide` (whose
    /// `k2` is ignored: each bandwidth scales the distances). Collaborative, as Tungsten's:
    /// each pixel's fit predicts every pixel of its window, and a pixel is the weighted mean
    /// of the predictions it received. Tiles are summed in a fixed order.
    pub fn run(&self, guide: Guide<'_>, ks: &[f32]) -> Vec<Planes> {
        use rayon::prelude::*;
        let (w, h) = (self.color.w, self.color.h);
        let nk = ks.len();
        let guide = Guide { k2: 1.0, ..guide };
        let inv_k2: Vec<f32> = ks.iter().map(|k| 1.0 / (k * k)).collect();
        let (tw, th) = (w.div_ceil(TILE), h.div_ceil(TILE));
        // Per pixel, per bandwidth: the predictions' weighted sums and their weight. One row
        // of tiles at a time, so that only that row's tiles are held besides the sums.
        let mut sums = Planes::new(w, h, 4 * nk);
        for ty in 0..th {
            let tiles: Vec<(Rect, Vec<f32>)> = (0..tw)
                .into_par_iter()
                .map(|tx| {
                    let rect = Rect {
                        x0: tx * TILE,
                        x1: ((tx + 1) * TILE).min(w),
                        y0: ty * TILE,
                        y1: ((ty + 1) * TILE).min(h),
                    };
                    self.tile(guide, &inv_k2, rect)
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

    /// The fits of the pixels of `rect` and their predictions: the rectangle grown by the
    /// window (clipped to the image) and, per pixel of it, per bandwidth, the predictions'
    /// weighted sums (3) and weight.
    fn tile(&self, guide: Guide<'_>, inv_k2: &[f32], rect: Rect) -> (Rect, Vec<f32>) {
        let (w, h) = (self.color.w, self.color.h);
        let nk = inv_k2.len();
        let rw = rect.w();
        let r = self.radius as i64;
        // Each offset with its index step.
        let offsets: Vec<((i64, i64), i64)> = (-r..=r)
            .flat_map(|dy| (-r..=r).map(move |dx| ((dx, dy), dy * w as i64 + dx)))
            .collect();
        let mut scratch = Scratch::default();
        // The distances pixel by pixel (each pixel's offsets together), as they are read.
        let no = offsets.len();
        let mut dist = vec![0.0f32; rect.len() * no];
        let mut row = Vec::new();
        for (o, &(off, _)) in offsets.iter().enumerate() {
            guide.patch_distances(off, rect, &mut scratch, &mut row);
            for (j, d) in row.iter().enumerate() {
                dist[j * no + o] = *d;
            }
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
        // A pixel's neighbours that may weigh in (index, distance, features, colour), and
        // their weights at the current bandwidth.
        let mut near: Vec<(usize, f32, [f32; D], [f32; 3])> = Vec::with_capacity(no);
        let mut wts: Vec<f32> = Vec::with_capacity(no);
        for j in 0..rect.len() {
            let p = (rect.y0 + j / rw) * w + rect.x0 + j % rw;
            let hit = self.hit[p];
            let dist = &dist[j * no..(j + 1) * no];
            near.clear();
            for (o, &(_, step)) in offsets.iter().enumerate() {
                let d = dist[o];
                let q = (p as i64 + step) as usize;
                if d != f32::INFINITY && self.hit[q] == hit {
                    let y = self.color.px(q);
                    near.push((q, d, x_of(p, q), [y[0], y[1], y[2]]));
                }
            }
            for (k, &s) in inv_k2.iter().enumerate() {
                wts.clear();
                wts.extend(near.iter().map(|n| weight(n.1 * s)));
                let mut a: Normal = [[0.0; D]; D + 3];
                for (n, &wt) in near.iter().zip(&wts) {
                    if wt >= MIN_WEIGHT {
                        accumulate(&mut a, &n.2, &n.3, wt);
                    }
                }
                let beta = solve(&a, self.ridge);
                for (n, &wt) in near.iter().zip(&wts) {
                    if wt < MIN_WEIGHT {
                        continue;
                    }
                    let (q, x) = (n.0, &n.2);
                    let local = (q / w - out_rect.y0) * ow + q % w - out_rect.x0;
                    let dst = &mut out[(local * nk + k) * 4..][..4];
                    for c in 0..3 {
                        let pred: f32 = beta[c].iter().zip(x).map(|(b, x)| b * x).sum();
                        dst[c] += wt * pred;
                    }
                    dst[3] += wt;
                }
            }
        }
        (out_rect, out)
    }
}

/// Adds one neighbour (features `x`, colour `y`, weight `wt`) to the normal equations.
#[inline]
fn accumulate(a: &mut Normal, x: &[f32; D], y: &[f32; 3], wt: f32) {
    let (gram, rhs) = a.split_at_mut(D);
    for i in 0..D {
        let wx = wt * x[i];
        for j in 0..=i {
            gram[i][j] += wx * x[j];
        }
    }
    for c in 0..3 {
        let wy = wt * y[c];
        for i in 0..D {
            rhs[c][i] += wy * x[i];
        }
    }
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

    #[test]
    fn an_image_linear_in_a_feature_is_reproduced() {
        // Colour = 0.2 + 3 * albedo_r, the albedo a ramp with a jump: the fit is exact.
        let (w, h) = (24, 12);
        let mut features = Planes::new(w, h, FEATURES);
        let mut color = Planes::new(w, h, 3);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let a = (x as f32 * 0.03) + if x > 11 { 0.4 } else { 0.0 } + y as f32 * 0.01;
                features.px_mut(i)[0] = a;
                features.px_mut(i)[6] = 1.0;
                color.px_mut(i).fill(0.2 + 3.0 * a);
            }
        }
        let var = Planes::new(w, h, 3);
        let hit = vec![true; w * h];
        let reg = Regression {
            color: &color,
            features: &features,
            hit: &hit,
            radius: 3,
            ridge: 0.0,
        };
        // A guide that weighs every neighbour alike: a constant image.
        let flat = Planes::new(w, h, 3);
        let guide = Guide {
            image: &flat,
            variance: &var,
            patch: 1,
            k2: 1.0,
        };
        let out = reg.run(guide, &[1.0]);
        for (o, c) in out[0].data.iter().zip(&color.data) {
            assert!((o - c).abs() < 1e-4, "{o} vs {c}");
        }
    }
}
