//! NL-means weights (Rousselle et al. 2012's variance-cancelling patch distance, as NFOR and
//! Tungsten's denoiser use it): for each offset of the window, the per-pixel distances between
//! a pixel and its neighbour at that offset, box-filtered over the patch (separably, so the
//! patch size costs little per offset), then `exp(-max(0, d))`. Work goes by tiles, each
//! computed alone, so the result does not depend on the thread count.

// Small fixed-size channel and matrix loops read clearest with indices.
#![allow(clippy::needless_range_loop)]

use super::planes::{by_tiles, Planes, Rect};

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

/// Reused buffers of one tile.
#[derive(Default)]
pub(crate) struct Scratch {
    raw: Vec<f32>,
    rows: Vec<f32>,
}

impl Guide<'_> {
    /// The channel-averaged distances between the pixels of `p` (`n` of them from pixel
    /// index `p0`) and those `q0 - p0` further, into `out`.
    #[inline]
    fn pixel_distances<const C: usize>(&self, p0: usize, q0: usize, out: &mut [f32]) {
        let n = out.len();
        let gp = &self.image.data[p0 * C..(p0 + n) * C];
        let gq = &self.image.data[q0 * C..(q0 + n) * C];
        let vp = &self.variance.data[p0 * C..(p0 + n) * C];
        let vq = &self.variance.data[q0 * C..(q0 + n) * C];
        let k2 = self.k2;
        for (i, o) in out.iter_mut().enumerate() {
            let mut d = 0.0;
            for c in 0..C {
                let j = i * C + c;
                let diff = gp[j] - gq[j];
                let num = diff * diff - (vp[j] + vp[j].min(vq[j]));
                d += (num / (EPSILON + k2 * (vp[j] + vq[j]))).min(DISTANCE_CLAMP);
            }
            *o = d * (1.0 / C as f32);
        }
    }

    /// The channel-averaged distances, whatever the channel count.
    fn row_distances(&self, p0: usize, q0: usize, out: &mut [f32]) {
        match self.image.c {
            1 => self.pixel_distances::<1>(p0, q0, out),
            2 => self.pixel_distances::<2>(p0, q0, out),
            3 => self.pixel_distances::<3>(p0, q0, out),
            7 => self.pixel_distances::<7>(p0, q0, out),
            c => {
                for (i, o) in out.iter_mut().enumerate() {
                    let mut d = 0.0;
                    for ch in 0..c {
                        let (jp, jq) = ((p0 + i) * c + ch, (q0 + i) * c + ch);
                        let (g, v) = (&self.image.data, &self.variance.data);
                        let diff = g[jp] - g[jq];
                        let num = diff * diff - (v[jp] + v[jp].min(v[jq]));
                        d += (num / (EPSILON + self.k2 * (v[jp] + v[jq]))).min(DISTANCE_CLAMP);
                    }
                    *o = d / c as f32;
                }
            }
        }
    }

    /// The patch distances of the pixels of `rect` to their neighbours at `(dx, dy)`, into
    /// `out` (row-major over the rectangle): infinite where the neighbour is outside.
    pub fn patch_distances(
        &self,
        (dx, dy): (i64, i64),
        rect: Rect,
        scratch: &mut Scratch,
        out: &mut Vec<f32>,
    ) {
        let (w, h) = (self.image.w as i64, self.image.h as i64);
        let f = self.patch as i64;
        // The padded rectangle, clipped to the image.
        let (px0, px1) = ((rect.x0 as i64 - f).max(0), (rect.x1 as i64 + f).min(w));
        let (py0, py1) = ((rect.y0 as i64 - f).max(0), (rect.y1 as i64 + f).min(h));
        let pw = (px1 - px0) as usize;
        let rows = (py1 - py0) as usize;
        scratch.raw.clear();
        scratch.raw.resize(rows * pw, DISTANCE_CLAMP);
        // Columns whose neighbour is inside the image.
        let (qx0, qx1) = (px0.max(-dx), px1.min(w - dx));
        for y in py0..py1 {
            let qy = y + dy;
            if qy < 0 || qy >= h || qx0 >= qx1 {
                continue;
            }
            let row = &mut scratch.raw[(y - py0) as usize * pw..][..pw];
            let p0 = (y * w + qx0) as usize;
            let q0 = (qy * w + qx0 + dx) as usize;
            let seg = &mut row[(qx0 - px0) as usize..(qx1 - px0) as usize];
            self.row_distances(p0, q0, seg);
        }
        // Horizontal box (the mean over the columns inside the image), then vertical.
        let rw = rect.w();
        let off = rect.x0 - px0 as usize;
        scratch.rows.clear();
        scratch.rows.resize(rows * rw, 0.0);
        for (src, dst) in scratch.raw.chunks(pw).zip(scratch.rows.chunks_mut(rw)) {
            box_row(src, dst, off, self.patch);
        }
        out.clear();
        out.resize(rect.len(), 0.0);
        for (j, y) in (rect.y0 as i64..rect.y1 as i64).enumerate() {
            let (a, b) = ((y - f).max(py0), (y + f + 1).min(py1));
            let o = &mut out[j * rw..][..rw];
            for r in a..b {
                let src = &scratch.rows[(r - py0) as usize * rw..][..rw];
                for (o, s) in o.iter_mut().zip(src) {
                    *o += s;
                }
            }
            let inv = 1.0 / (b - a) as f32;
            let qy = y + dy;
            for (i, o) in o.iter_mut().enumerate() {
                let qx = (rect.x0 + i) as i64 + dx;
                *o = if qy < 0 || qy >= h || qx < 0 || qx >= w {
                    f32::INFINITY
                } else {
                    *o * inv
                };
            }
        }
    }
}

/// The mean of `src` over `[x - r, x + r]` (clipped to the row) for the `dst.len()` columns
/// from `off` on, into `dst`.
fn box_row(src: &[f32], dst: &mut [f32], off: usize, r: usize) {
    let n = src.len();
    let x0 = off;
    let (a0, b0) = (x0.saturating_sub(r), (x0 + r + 1).min(n));
    let mut sum: f32 = src[a0..b0].iter().sum();
    // The running sums first, then the divisions by the counts (a loop apart, so that they
    // go in vector lanes).
    for (i, d) in dst.iter_mut().enumerate() {
        let x = x0 + i;
        *d = sum;
        if x + r + 1 < n {
            sum += src[x + r + 1];
        }
        if x >= r {
            sum -= src[x - r];
        }
    }
    // Columns whose window lies inside the row have the full count.
    let full = (2 * r + 1) as f32;
    let lo = r.saturating_sub(x0).min(dst.len());
    let hi = (n.saturating_sub(r + x0)).clamp(lo, dst.len());
    for (i, d) in dst.iter_mut().enumerate() {
        if i < lo || i >= hi {
            let x = x0 + i;
            *d /= ((x + r + 1).min(n) - x.saturating_sub(r)) as f32;
        }
    }
    for d in &mut dst[lo..hi] {
        *d /= full;
    }
}

/// The weight of a patch distance: `exp(-max(0, d))`, by a degree-6 polynomial for the
/// fraction of a power of two (relative error below 2e-5; the weights need no more, and
/// the library's exp is a call the loops cannot vectorise).
#[inline]
pub(crate) fn weight(d: f32) -> f32 {
    let t = (d.max(0.0) * std::f32::consts::LOG2_E).min(126.0);
    let i = t.floor();
    let g = i - t;
    // 2^g for g in (-1, 0]: its Taylor series in g ln 2.
    let p = 1.0
        + g * (std::f32::consts::LN_2
            + g * (0.240_226_5
                + g * (0.055_504_1 + g * (0.009_618_13 + g * (0.001_333_36 + g * 0.000_154_04)))));
    f32::from_bits(((127 - i as i32) as u32) << 23) * p
}

/// NL-means: each pixel of `image` the weighted mean of the pixels in its window of radius
/// `radius`, weighted by the patch distances of `guide`. Pixels whose `group` differs (a
/// surface against an emitter or the background) never mix.
pub(crate) fn nl_means(image: &Planes, guide: Guide<'_>, radius: usize, group: &[bool]) -> Planes {
    match image.c {
        1 => nl_means_c::<1>(image, guide, radius, group),
        3 => nl_means_c::<3>(image, guide, radius, group),
        7 => nl_means_c::<7>(image, guide, radius, group),
        _ => nl_means_c::<0>(image, guide, radius, group),
    }
}

/// `nl_means` for `C` channels (0: whatever `image` has). Per offset and row of the tile,
/// the weights of the columns whose neighbour is inside are made first (zero where the
/// groups differ: such a neighbour is skipped), then added in.
fn nl_means_c<const C: usize>(
    image: &Planes,
    guide: Guide<'_>,
    radius: usize,
    group: &[bool],
) -> Planes {
    let (w, h, c) = (image.w, image.h, image.c);
    let r = radius as i64;
    by_tiles(w, h, c, |rect| {
        let mut scratch = Scratch::default();
        let mut dist = Vec::new();
        let mut acc = vec![0.0f32; rect.len() * c];
        let mut wsum = vec![0.0f32; rect.len()];
        let rw = rect.w();
        let mut wts = vec![0.0f32; rw];
        for dy in -r..=r {
            for dx in -r..=r {
                guide.patch_distances((dx, dy), rect, &mut scratch, &mut dist);
                // The columns whose neighbour is inside the image (the distance elsewhere
                // is infinite).
                let xa = (rect.x0 as i64).max(-dx);
                let xb = (rect.x1 as i64).min(w as i64 - dx);
                if xa >= xb {
                    continue;
                }
                let (ja, n) = ((xa - rect.x0 as i64) as usize, (xb - xa) as usize);
                for (jr, y) in (rect.y0..rect.y1).enumerate() {
                    let qy = y as i64 + dy;
                    if qy < 0 || qy >= h as i64 {
                        continue;
                    }
                    let p0 = y * w + xa as usize;
                    let q0 = (qy * w as i64 + xa + dx) as usize;
                    let j0 = jr * rw + ja;
                    let (gp, gq) = (&group[p0..p0 + n], &group[q0..q0 + n]);
                    let wts = &mut wts[..n];
                    for (i, (o, d)) in wts.iter_mut().zip(&dist[j0..j0 + n]).enumerate() {
                        let v = weight(*d);
                        *o = if gp[i] == gq[i] { v } else { 0.0 };
                    }
                    for (s, &wt) in wsum[j0..j0 + n].iter_mut().zip(wts.iter()) {
                        *s += wt;
                    }
                    let src = &image.data[q0 * c..(q0 + n) * c];
                    let dst = &mut acc[j0 * c..(j0 + n) * c];
                    if C == 0 {
                        add_weighted(dst, src, wts, c);
                    } else {
                        add_weighted(dst, src, wts, C);
                    }
                }
            }
        }
        for (j, ws) in wsum.iter().enumerate() {
            // The centre's own weight is 1, so ws >= 1.
            for o in &mut acc[j * c..(j + 1) * c] {
                *o /= ws;
            }
        }
        acc
    })
}

/// Adds each pixel of `src` (`c` channels) times its weight to `dst`; zero weights add
/// nothing.
#[inline(always)]
fn add_weighted(dst: &mut [f32], src: &[f32], wts: &[f32], c: usize) {
    for ((d, s), &wt) in dst.chunks_exact_mut(c).zip(src.chunks_exact(c)).zip(wts) {
        if wt != 0.0 {
            for ch in 0..c {
                d[ch] += wt * s[ch];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weight_is_exp_of_minus_the_distance() {
        for d in [-1.0f32, 0.0, 0.3, 1.0, 2.5, 7.0, 30.0, 200.0] {
            let e = (-d.max(0.0)).exp();
            assert!(
                (weight(d) - e).abs() <= 2e-5 * e + 1e-30,
                "{d}: {} vs {e}",
                weight(d)
            );
        }
    }

    #[test]
    fn box_row_is_the_clipped_mean() {
        let src = [1.0, 2.0, 3.0, 4.0, 5.0];
        let mut dst = [0.0; 5];
        box_row(&src, &mut dst, 0, 1);
        assert_eq!(dst, [1.5, 2.0, 3.0, 4.0, 4.5]);
        box_row(&src, &mut dst, 0, 0);
        assert_eq!(dst, src);
        let mut two = [0.0; 2];
        box_row(&src, &mut two, 2, 1);
        assert_eq!(two, [3.0, 4.0]);
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
