//! Multi-channel f32 images (channels interleaved per pixel) and the filter's inputs read from
//! the film's half buffers.

// Small fixed-size channel and matrix loops read clearest with indices.
#![allow(clippy::needless_range_loop)]

use crate::film::{HalfPixel, PixelBuffers};
use crate::first_hit::{DEPTH, FEATURES};

/// A `w` x `h` image of `c` interleaved f32 channels, row-major.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Planes {
    pub w: usize,
    pub h: usize,
    pub c: usize,
    pub data: Vec<f32>,
}

impl Planes {
    /// All zeros.
    pub fn new(w: usize, h: usize, c: usize) -> Self {
        Self {
            w,
            h,
            c,
            data: vec![0.0; w * h * c],
        }
    }

    /// Pixel `i`'s channels.
    #[inline]
    pub fn px(&self, i: usize) -> &[f32] {
        &self.data[i * self.c..(i + 1) * self.c]
    }

    /// Pixel `i`'s channels, to write.
    #[inline]
    pub fn px_mut(&mut self, i: usize) -> &mut [f32] {
        &mut self.data[i * self.c..(i + 1) * self.c]
    }

    /// A new image of `c` channels, each pixel from this one's by `f`.
    pub fn map(&self, c: usize, f: impl Fn(usize, &[f32], &mut [f32])) -> Planes {
        let mut out = Planes::new(self.w, self.h, c);
        for i in 0..self.w * self.h {
            f(i, self.px(i), out.px_mut(i));
        }
        out
    }
}

/// A rectangle of pixels, `x0..x1` by `y0..y1`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rect {
    pub x0: usize,
    pub x1: usize,
    pub y0: usize,
    pub y1: usize,
}

impl Rect {
    /// Its width.
    pub fn w(&self) -> usize {
        self.x1 - self.x0
    }

    /// Its pixel count.
    pub fn len(&self) -> usize {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }
}

/// The side of the square tiles the filter works by: small enough that a tile's regression
/// sums stay in cache.
pub(crate) const TILE: usize = 32;

/// A `w` x `h` image of `c` channels made tile by tile in parallel: `tile` returns a tile's
/// pixels (row-major over the tile, `c` channels each). Each pixel is computed within its
/// tile alone, so the result does not depend on the thread count.
pub(crate) fn by_tiles(
    w: usize,
    h: usize,
    c: usize,
    tile: impl Fn(Rect) -> Vec<f32> + Sync,
) -> Planes {
    use rayon::prelude::*;
    let (tw, th) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let mut out = Planes::new(w, h, c);
    // One row of tiles at a time, so that only that row's results are held besides the image.
    for ty in 0..th {
        let tiles: Vec<(Rect, Vec<f32>)> = (0..tw)
            .into_par_iter()
            .map(|tx| {
                let r = Rect {
                    x0: tx * TILE,
                    x1: ((tx + 1) * TILE).min(w),
                    y0: ty * TILE,
                    y1: ((ty + 1) * TILE).min(h),
                };
                (r, tile(r))
            })
            .collect();
        for (r, vals) in tiles {
            let rw = r.w() * c;
            for (j, y) in (r.y0..r.y1).enumerate() {
                out.data[(y * w + r.x0) * c..][..rw].copy_from_slice(&vals[j * rw..][..rw]);
            }
        }
    }
    out
}

/// What the filter reads from the half buffers: per half the mean colour and features with
/// the variances of those means, and which pixels had a first hit at all.
pub(crate) struct Inputs {
    /// Each half's mean colour (3 channels).
    pub color: [Planes; 2],
    /// The variance of each half's mean colour, each estimated from that half's samples
    /// alone: weights drawn from one half must not depend on the other half's noise.
    pub color_var: [Planes; 2],
    /// The pixel mean over both halves (3 channels).
    pub full: Planes,
    /// The variance of that mean.
    pub full_var: Planes,
    /// Whether some sample of the pixel met a surface (features not all zero): a pixel that
    /// sees only emitters or nothing is filtered apart from surfaces.
    pub hit: Vec<bool>,
}

/// The radius of the box that steadies the halves' variance estimates.
pub(crate) const VARIANCE_RADIUS: i64 = 1;

/// `img` averaged over each pixel's neighbours within `r` pixels of the same `group`.
fn box_in_group(img: &Planes, group: &[bool], r: i64) -> Planes {
    let (w, h, c) = (img.w as i64, img.h as i64, img.c);
    let mut out = Planes::new(img.w, img.h, c);
    for y in 0..h {
        for x in 0..w {
            let p = (y * w + x) as usize;
            let mut n = 0.0;
            for (qx, qy) in (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| (x + dx, y + dy))) {
                if qx < 0 || qy < 0 || qx >= w || qy >= h {
                    continue;
                }
                let q = (qy * w + qx) as usize;
                if group[q] != group[p] {
                    continue;
                }
                n += 1.0;
                for ch in 0..c {
                    out.data[p * c + ch] += img.data[q * c + ch];
                }
            }
            for v in out.px_mut(p) {
                *v /= n;
            }
        }
    }
    out
}

/// Each half's mean features (depth rescaled to the image's mean depth) and their variance:
/// read with [`Inputs`], and dropped once prefiltered.
pub(crate) struct FeatureHalves {
    pub features: [Planes; 2],
    pub variance: [Planes; 2],
}

/// The variance of a half's mean: its own estimate, else the other half's scaled by the
/// counts, else from the halves' difference (one sample each).
fn half_variance<const N: usize>(
    own: (u32, Option<[f32; N]>),
    other: (u32, Option<[f32; N]>),
    diff: [f32; N],
) -> [f32; N] {
    match (own.1, other.1) {
        (Some(v), _) => v,
        (None, Some(v)) if own.0 > 0 => v.map(|v| v * other.0 as f32 / own.0 as f32),
        _ => diff.map(|d| d * d * 0.5),
    }
}

/// The factor that brings depth to the scale of the image's mean depth, so that one ridge
/// suits every scene: the render's ([`PixelBuffers::set_depth_scale`], known before any sample,
/// so the same whether the image is filtered whole or by bands), else over both halves of
/// every pixel with a first hit that the buffers hold (the whole image but in a render by
/// bands), whatever part of it is filtered.
pub(crate) fn depth_scale(b: &PixelBuffers) -> f32 {
    if let Some(s) = b.depth_scale() {
        return s;
    }
    let (mut dsum, mut dcount) = (0.0f64, 0u64);
    for p in b.half(0).iter().chain(b.half(1)) {
        let depth = p.features()[DEPTH];
        if p.count > 0 && depth > 0.0 {
            dsum += f64::from(depth);
            dcount += 1;
        }
    }
    if dsum > 0.0 {
        (dcount as f64 / dsum) as f32
    } else {
        1.0
    }
}

impl Inputs {
    /// Reads the buffers' rows `rows` (an image of their full width and `rows.len()` rows),
    /// with depth times `depth_scale` ([`depth_scale`]). A half without samples takes the
    /// other half's values.
    pub fn read(
        b: &PixelBuffers,
        rows: std::ops::Range<usize>,
        depth_scale: f32,
    ) -> (Self, FeatureHalves) {
        let w = b.size().0 as usize;
        let h = rows.len();
        let n = w * h;
        let [a, bb] = [b.rows_of(0, rows.clone()), b.rows_of(1, rows)];
        let mut inp = Inputs {
            color: [Planes::new(w, h, 3), Planes::new(w, h, 3)],
            color_var: [Planes::new(w, h, 3), Planes::new(w, h, 3)],
            full: Planes::new(w, h, 3),
            full_var: Planes::new(w, h, 3),
            hit: vec![false; n],
        };
        let mut feats = FeatureHalves {
            features: [Planes::new(w, h, FEATURES), Planes::new(w, h, FEATURES)],
            variance: [Planes::new(w, h, FEATURES), Planes::new(w, h, FEATURES)],
        };
        for i in 0..n {
            let (pa, pb) = (&a[i], &bb[i]);
            let (pa, pb) = match (pa.count, pb.count) {
                (0, 0) => continue,
                (0, _) => (pb, pb),
                (_, 0) => (pa, pa),
                _ => (pa, pb),
            };
            inp.read_pixel(i, [pa, pb], depth_scale, &mut feats);
        }
        // A half's variance from a few samples is itself noisy: averaged over 3x3 pixels of
        // the same kind it steadies the NL-means distances.
        for h in 0..2 {
            inp.color_var[h] = box_in_group(&inp.color_var[h], &inp.hit, VARIANCE_RADIUS);
        }
        (inp, feats)
    }

    /// Fills pixel `i` from its two halves (both with samples).
    fn read_pixel(
        &mut self,
        i: usize,
        [pa, pb]: [&HalfPixel; 2],
        depth_scale: f32,
        feats: &mut FeatureHalves,
    ) {
        let cdiff: [f32; 3] = std::array::from_fn(|c| pa.color[c] - pb.color[c]);
        let va = half_variance(
            (pa.count, pa.color_variance_of_mean()),
            (pb.count, pb.color_variance_of_mean()),
            cdiff,
        );
        let vb = half_variance(
            (pb.count, pb.color_variance_of_mean()),
            (pa.count, pa.color_variance_of_mean()),
            cdiff,
        );
        let (ma, mb) = (pa.features(), pb.features());
        let fdiff: [f32; FEATURES] = std::array::from_fn(|k| ma[k] - mb[k]);
        let fa = half_variance(
            (pa.count, pa.features_variance_of_mean()),
            (pb.count, pb.features_variance_of_mean()),
            fdiff,
        );
        let fb = half_variance(
            (pb.count, pb.features_variance_of_mean()),
            (pa.count, pa.features_variance_of_mean()),
            fdiff,
        );
        let same = std::ptr::eq(pa, pb);
        let (na, nb) = if same {
            (pa.count as f32, 0.0)
        } else {
            (pa.count as f32, pb.count as f32)
        };
        let t = na + nb;
        for c in 0..3 {
            self.color[0].px_mut(i)[c] = pa.color[c];
            self.color[1].px_mut(i)[c] = pb.color[c];
            self.color_var[0].px_mut(i)[c] = va[c];
            self.color_var[1].px_mut(i)[c] = vb[c];
            self.full.px_mut(i)[c] = (na * pa.color[c] + nb * pb.color[c]) / t;
            self.full_var.px_mut(i)[c] = (na * na * va[c] + nb * nb * vb[c]) / (t * t);
        }
        let scale = |k: usize| if k == DEPTH { depth_scale } else { 1.0 };
        for k in 0..FEATURES {
            let s = scale(k);
            feats.features[0].px_mut(i)[k] = ma[k] * s;
            feats.features[1].px_mut(i)[k] = mb[k] * s;
            feats.variance[0].px_mut(i)[k] = fa[k] * s * s;
            feats.variance[1].px_mut(i)[k] = fb[k] * s * s;
        }
        self.hit[i] = ma.iter().chain(&mb).any(|&f| f != 0.0);
    }
}
