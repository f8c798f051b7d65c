//! Multi-channel f32 images (channels interleaved per pixel) and the filter's inputs read from
//! the film's half buffers.

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

/// What the filter reads from the half buffers: per half the mean colour and features with
/// the variances of those means, and which pixels had a first hit at all.
pub(crate) struct Inputs {
    /// Each half's mean colour (3 channels).
    pub color: [Planes; 2],
    /// The variance of one half's mean colour (both halves' estimates averaged).
    pub color_var: Planes,
    /// Each half's mean features (depth rescaled to the image's mean depth).
    pub features: [Planes; 2],
    /// The variance of one half's mean features.
    pub features_var: Planes,
    /// The pixel mean over both halves (3 channels).
    pub full: Planes,
    /// The variance of that mean.
    pub full_var: Planes,
    /// Whether some sample of the pixel met a surface (features not all zero): a pixel that
    /// sees only emitters or nothing is filtered apart from surfaces.
    pub hit: Vec<bool>,
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

impl Inputs {
    /// Reads the buffers. A half without samples takes the other half's values.
    pub fn read(b: &PixelBuffers) -> Self {
        let (w, h) = b.size();
        let (w, h) = (w as usize, h as usize);
        let n = w * h;
        let [a, bb] = [b.half(0), b.half(1)];
        // Depth on the scale of the image's mean depth, so that one ridge suits every scene.
        let (mut dsum, mut dcount) = (0.0f64, 0u64);
        for p in a.iter().chain(bb) {
            if p.count > 0 && p.features[DEPTH] > 0.0 {
                dsum += f64::from(p.features[DEPTH]);
                dcount += 1;
            }
        }
        let depth_scale = if dsum > 0.0 {
            (dcount as f64 / dsum) as f32
        } else {
            1.0
        };
        let mut inp = Inputs {
            color: [Planes::new(w, h, 3), Planes::new(w, h, 3)],
            color_var: Planes::new(w, h, 3),
            features: [Planes::new(w, h, FEATURES), Planes::new(w, h, FEATURES)],
            features_var: Planes::new(w, h, FEATURES),
            full: Planes::new(w, h, 3),
            full_var: Planes::new(w, h, 3),
            hit: vec![false; n],
        };
        for i in 0..n {
            let (pa, pb) = (&a[i], &bb[i]);
            let (pa, pb) = match (pa.count, pb.count) {
                (0, 0) => continue,
                (0, _) => (pb, pb),
                (_, 0) => (pa, pa),
                _ => (pa, pb),
            };
            inp.read_pixel(i, [pa, pb], depth_scale);
        }
        inp
    }

    /// Fills pixel `i` from its two halves (both with samples).
    fn read_pixel(&mut self, i: usize, [pa, pb]: [&HalfPixel; 2], depth_scale: f32) {
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
        let fdiff: [f32; FEATURES] = std::array::from_fn(|k| pa.features[k] - pb.features[k]);
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
            self.color_var.px_mut(i)[c] = 0.5 * (va[c] + vb[c]);
            self.full.px_mut(i)[c] = (na * pa.color[c] + nb * pb.color[c]) / t;
            self.full_var.px_mut(i)[c] = (na * na * va[c] + nb * nb * vb[c]) / (t * t);
        }
        let scale = |k: usize| if k == DEPTH { depth_scale } else { 1.0 };
        for k in 0..FEATURES {
            let s = scale(k);
            self.features[0].px_mut(i)[k] = pa.features[k] * s;
            self.features[1].px_mut(i)[k] = pb.features[k] * s;
            self.features_var.px_mut(i)[k] = 0.5 * (fa[k] + fb[k]) * s * s;
        }
        self.hit[i] = pa.features.iter().chain(&pb.features).any(|&f| f != 0.0);
    }
}
