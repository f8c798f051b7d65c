//! NL-means weights (Rousselle et al. 2012's variance-cancelling patch distance, as NFOR and
//! Tungsten's denoiser use it): for each offset of the window, the per-pixel distances between
//! a pixel and its neighbour at that offset, box-filtered over the patch (separably, so the
//! patch size costs nothing per offset), then `exp(-max(0, d))`. Work goes by bands of rows,
//! each band computed alone, so the result does not depend on the thread count.

use super::planes::Planes;
use rayon::prelude::*;

/// Rows per band: enough to amortise the patch's padding rows.
pub(crate) const BAND: usize = 32;

/// A single pixel distance beyond this is clamped (Tungsten's), so one channel cannot make
/// the sum overflow.
const DISTANCE_CLAMP: f32 = 1e4;

/// Keeps the distance of noise-free, equal values finite.
const EPSILON: f32 = 1e-7;

/// What the patch distances are computed from: the guide image and the variance of its
/// values, the patch radius and the bandwidth squared.
#[derive(Clone, Copy)]
pub(crate) struct Guide<'a> {
    pub image: &'a Planes,
    pub variance: &'a Planes,
    pub patch: usize,
    pub k2: f32,
}

/// Reused buffers of one band.
#[derive(Default)]
pub(crate) struct Scratch {
    raw: Vec<f32>,
    rows: Vec<f32>,
}

impl Guide<'_> {
    /// The channel-averaged distance between pixels `p` and `q`.
    #[inline]
    fn pixel_distance(&self, p: usize, q: usize) -> f32 {
        let (gp, gq) = (self.image.px(p), self.image.px(q));
        let (vp, vq) = (self.variance.px(p), self.variance.px(q));
        let mut d = 0.0;
        for c in 0..gp.len() {
            let diff = gp[c] - gq[c];
            let num = diff * diff - (vp[c] + vp[c].min(vq[c]));
            d += (num / (EPSILON + self.k2 * (vp[c] + vq[c]))).min(DISTANCE_CLAMP);
        }
        d / gp.len() as f32
    }

    /// The patch distances of rows `y0..y1` (all columns) to their neighbours at `(dx, dy)`,
    /// into `out` (row-major over the band): infinite where the neighbour is outside.
    pub fn patch_distances(
        &self,
        (dx, dy): (i64, i64),
        (y0, y1): (usize, usize),
        scratch: &mut Scratch,
        out: &mut Vec<f32>,
    ) {
        let (w, h) = (self.image.w as i64, self.image.h as i64);
        let f = self.patch as i64;
        let (py0, py1) = ((y0 as i64 - f).max(0), (y1 as i64 + f).min(h));
        let rows = (py1 - py0) as usize;
        let wu = w as usize;
        scratch.raw.clear();
        scratch.raw.resize(rows * wu, DISTANCE_CLAMP);
        for y in py0..py1 {
            let qy = y + dy;
            if qy < 0 || qy >= h {
                continue;
            }
            let row = &mut scratch.raw[(y - py0) as usize * wu..][..wu];
            let (x0, x1) = ((-dx).max(0), (w - dx).min(w));
            for x in x0..x1 {
                let p = (y * w + x) as usize;
                let q = (qy * w + x + dx) as usize;
                row[x as usize] = self.pixel_distance(p, q);
            }
        }
        // Horizontal box (the mean over the columns inside the image), then vertical.
        scratch.rows.clear();
        scratch.rows.resize(rows * wu, 0.0);
        for (src, dst) in scratch.raw.chunks(wu).zip(scratch.rows.chunks_mut(wu)) {
            box_row(src, dst, self.patch);
        }
        out.clear();
        out.resize((y1 - y0) * wu, f32::INFINITY);
        for y in y0 as i64..y1 as i64 {
            let (a, b) = ((y - f).max(py0), (y + f + 1).min(py1));
            let o = &mut out[(y as usize - y0) * wu..][..wu];
            o.fill(0.0);
            for r in a..b {
                let src = &scratch.rows[(r - py0) as usize * wu..][..wu];
                for (o, s) in o.iter_mut().zip(src) {
                    *o += s;
                }
            }
            let inv = 1.0 / (b - a) as f32;
            let qy = y + dy;
            for (x, o) in o.iter_mut().enumerate() {
                let qx = x as i64 + dx;
                *o = if qy < 0 || qy >= h || qx < 0 || qx >= w {
                    f32::INFINITY
                } else {
                    *o * inv
                };
            }
        }
    }
}

/// The mean of `src` over `[x - r, x + r]` (clipped to the row), into `dst`.
fn box_row(src: &[f32], dst: &mut [f32], r: usize) {
    let n = src.len();
    let mut sum: f32 = src[..(r + 1).min(n)].iter().sum();
    for x in 0..n {
        let (a, b) = (x.saturating_sub(r), (x + r + 1).min(n));
        dst[x] = sum / (b - a) as f32;
        if x + r + 1 < n {
            sum += src[x + r + 1];
        }
        if x >= r {
            sum -= src[x - r];
        }
    }
}

/// The weight of a patch distance.
#[inline]
pub(crate) fn weight(d: f32) -> f32 {
    (-d.max(0.0)).exp()
}

/// NL-means: each pixel of `image` the weighted mean of the pixels in its window of radius
/// `radius`, weighted by the patch distances of `guide`. Pixels whose `group` differs (a
/// surface against an emitter or the background) never mix.
pub(crate) fn nl_means(image: &Planes, guide: Guide<'_>, radius: usize, group: &[bool]) -> Planes {
    let (w, h, c) = (image.w, image.h, image.c);
    let mut out = Planes::new(w, h, c);
    let r = radius as i64;
    out.data
        .par_chunks_mut(BAND * w * c)
        .enumerate()
        .for_each(|(band, chunk)| {
            let y0 = band * BAND;
            let y1 = (y0 + BAND).min(h);
            let mut scratch = Scratch::default();
            let mut dist = Vec::new();
            let mut wsum = vec![0.0f32; (y1 - y0) * w];
            for dy in -r..=r {
                for dx in -r..=r {
                    guide.patch_distances((dx, dy), (y0, y1), &mut scratch, &mut dist);
                    for (j, &d) in dist.iter().enumerate() {
                        if d == f32::INFINITY {
                            continue;
                        }
                        let p = y0 * w + j;
                        let q = (p as i64 + dy * w as i64 + dx) as usize;
                        if group[p] != group[q] {
                            continue;
                        }
                        let wt = weight(d);
                        wsum[j] += wt;
                        let (src, dst) = (image.px(q), &mut chunk[j * c..(j + 1) * c]);
                        for (o, s) in dst.iter_mut().zip(src) {
                            *o += wt * s;
                        }
                    }
                }
            }
            for (j, ws) in wsum.iter().enumerate() {
                // The centre's own weight is 1, so ws >= 1.
                for o in &mut chunk[j * c..(j + 1) * c] {
                    *o /= ws;
                }
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_row_is_the_clipped_mean() {
        let src = [1.0, 2.0, 3.0, 4.0, 5.0];
        let mut dst = [0.0; 5];
        box_row(&src, &mut dst, 1);
        assert_eq!(dst, [1.5, 2.0, 3.0, 4.0, 4.5]);
        box_row(&src, &mut dst, 0);
        assert_eq!(dst, src);
    }

    #[test]
    fn nl_means_keeps_a_step_and_smooths_noise() {
        // Left half 0, right half 10, variance 1: the step is far beyond the noise.
        let (w, h) = (16, 8);
        let mut img = Planes::new(w, h, 1);
        for y in 0..h {
            for x in 0..w {
                let noise = if (x + y) % 2 == 0 { 0.5 } else { -0.5 };
                img.data[y * w + x] = if x < 8 { noise } else { 10.0 + noise };
            }
        }
        let var = Planes {
            data: vec![0.25; w * h],
            ..img.clone()
        };
        let g = Guide {
            image: &img,
            variance: &var,
            patch: 1,
            k2: 1.0,
        };
        let out = nl_means(&img, g, 2, &vec![true; w * h]);
        for y in 0..h {
            assert!(out.data[y * w + 3].abs() < 0.3, "{}", out.data[y * w + 3]);
            assert!((out.data[y * w + 12] - 10.0).abs() < 0.3);
        }
    }
}
