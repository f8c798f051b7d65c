//! NFOR's first-order regression: each pixel's colour is the intercept of a weighted least
//! squares fit of the colours in the window around it on their features' differences from
//! the pixel's own (a plane in feature space), weighted by NL-means on a guide image. Several
//! bandwidths share the window's distances.

use super::nlmeans::{weight, Guide, Scratch, BAND};
use super::planes::Planes;
use crate::first_hit::FEATURES;
use rayon::prelude::*;

/// Unknowns of the fit: the intercept and one slope per feature.
const D: usize = 1 + FEATURES;
/// Entries of the upper triangle of the normal matrix.
const TRI: usize = D * (D + 1) / 2;
/// Accumulators per pixel and bandwidth: the normal matrix and three right-hand sides.
const ACC: usize = TRI + 3 * D;

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
    /// `k2` is ignored: each bandwidth scales the distances).
    pub fn run(&self, guide: Guide<'_>, ks: &[f32]) -> Vec<Planes> {
        let (w, h) = (self.color.w, self.color.h);
        let nk = ks.len();
        let guide = Guide { k2: 1.0, ..guide };
        let inv_k2: Vec<f32> = ks.iter().map(|k| 1.0 / (k * k)).collect();
        let bands: Vec<Vec<f32>> = (0..h.div_ceil(BAND))
            .into_par_iter()
            .map(|band| {
                let (y0, y1) = (band * BAND, ((band + 1) * BAND).min(h));
                self.band(guide, &inv_k2, (y0, y1))
            })
            .collect();
        (0..nk)
            .map(|k| {
                let mut out = Planes::new(w, h, 3);
                for (band, vals) in bands.iter().enumerate() {
                    let y0 = band * BAND;
                    let n = vals.len() / (3 * nk);
                    for j in 0..n {
                        let o = (y0 * w + j) * 3;
                        out.data[o..o + 3].copy_from_slice(&vals[(j * nk + k) * 3..][..3]);
                    }
                }
                out
            })
            .collect()
    }

    /// The fits of rows `y0..y1`: per pixel, per bandwidth, three channels.
    fn band(&self, guide: Guide<'_>, inv_k2: &[f32], (y0, y1): (usize, usize)) -> Vec<f32> {
        let w = self.color.w;
        let nk = inv_k2.len();
        let n = (y1 - y0) * w;
        let mut acc = vec![0.0f32; n * nk * ACC];
        let mut scratch = Scratch::default();
        let mut dist = Vec::new();
        let r = self.radius as i64;
        for dy in -r..=r {
            for dx in -r..=r {
                guide.patch_distances((dx, dy), (y0, y1), &mut scratch, &mut dist);
                for (j, &d) in dist.iter().enumerate() {
                    if d == f32::INFINITY {
                        continue;
                    }
                    let p = y0 * w + j;
                    let q = (p as i64 + dy * w as i64 + dx) as usize;
                    if self.hit[p] != self.hit[q] {
                        continue;
                    }
                    let (fp, fq) = (self.features.px(p), self.features.px(q));
                    let mut x = [1.0f32; D];
                    for k in 0..FEATURES {
                        x[k + 1] = fq[k] - fp[k];
                    }
                    let y = self.color.px(q);
                    for (k, &s) in inv_k2.iter().enumerate() {
                        let wt = weight(d * s);
                        if wt < MIN_WEIGHT {
                            continue;
                        }
                        let a = &mut acc[(j * nk + k) * ACC..][..ACC];
                        accumulate(a, &x, y, wt);
                    }
                }
            }
        }
        let mut out = vec![0.0f32; n * nk * 3];
        for (a, o) in acc.chunks(ACC).zip(out.chunks_mut(3)) {
            o.copy_from_slice(&solve(a, self.ridge));
        }
        out
    }
}

/// Adds one neighbour (features `x`, colour `y`, weight `wt`) to the normal equations.
#[inline]
fn accumulate(a: &mut [f32], x: &[f32; D], y: &[f32], wt: f32) {
    let mut t = 0;
    for i in 0..D {
        let wx = wt * x[i];
        for xj in &x[i..] {
            a[t] += wx * xj;
            t += 1;
        }
    }
    for c in 0..3 {
        let wy = wt * y[c];
        for i in 0..D {
            a[TRI + c * D + i] += wy * x[i];
        }
    }
}

/// The intercepts of the three channels' fits from the normal equations `a`, with a ridge
/// on the slopes of `ridge` times the sum of weights; the weighted mean where the system is
/// singular.
fn solve(a: &[f32], ridge: f32) -> [f32; 3] {
    let sw = f64::from(a[0]);
    if sw <= 0.0 {
        return [0.0; 3];
    }
    let mean = [0, 1, 2].map(|c| (f64::from(a[TRI + c * D]) / sw) as f32);
    let mut m = [[0.0f64; D]; D];
    let mut t = 0;
    for i in 0..D {
        for j in i..D {
            m[i][j] = f64::from(a[t]);
            m[j][i] = m[i][j];
            t += 1;
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
    let mut out = [0.0f32; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut z = [0.0f64; D];
        for i in 0..D {
            let mut s = f64::from(a[TRI + c * D + i]);
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
        *o = if b[0].is_finite() {
            b[0] as f32
        } else {
            mean[c]
        };
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
