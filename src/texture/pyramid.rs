//! Building a MIP map's levels as pbrt-v3 does (core/mipmap.h): an image whose sides are not
//! powers of two is resampled up to them (a Lanczos-windowed sinc, 4 taps, clamped at 0), and
//! each level halves the one below by a box filter. Rows are built in parallel; each texel's
//! arithmetic is the same whatever the thread count, so the levels are too.

use super::image_map::{ImageMap, Wrap};
#[cfg(test)]
use super::texels::{ByteTexels, Quantiser};
use super::value::TexValue;
use rayon::prelude::*;

/// pbrt-v3's `Lanczos(x, tau = 2)`.
fn lanczos(x: f32) -> f32 {
    let x = x.abs();
    if x < 1e-5 {
        return 1.0;
    }
    if x > 1.0 {
        return 0.0;
    }
    let x = x * std::f32::consts::PI;
    let tau = 2.0;
    ((x * tau).sin() / (x * tau)) * (x.sin() / x)
}

/// pbrt-v3's `resampleWeights`: per new texel, its first old texel and four weights.
pub(super) fn resample_weights(old: usize, new: usize) -> Vec<(i64, [f32; 4])> {
    let filter_width = 2.0f32;
    (0..new)
        .map(|i| {
            let center = (i as f32 + 0.5) * old as f32 / new as f32;
            let first = ((center - filter_width) + 0.5).floor() as i64;
            let mut w: [f32; 4] = std::array::from_fn(|j| {
                lanczos((first as f32 + j as f32 + 0.5 - center) / filter_width)
            });
            let inv = 1.0 / (w[0] + w[1] + w[2] + w[3]);
            for v in &mut w {
                *v *= inv;
            }
            (first, w)
        })
        .collect()
}

/// Where texel `i` of a `size`-texel row lies after wrapping (`None`: black, outside).
pub(super) fn wrap_index(i: i64, size: usize, wrap: Wrap) -> Option<usize> {
    let n = size as i64;
    match wrap {
        Wrap::Repeat => Some(i.rem_euclid(n) as usize),
        Wrap::Clamp => Some(i.clamp(0, n - 1) as usize),
        Wrap::Black => (0..n).contains(&i).then_some(i as usize),
    }
}

/// `image` resampled up to powers of two: along s row by row, then along t, each new texel
/// the sum, tap after tap, of pbrt-v3's four weighted texels, kept non-negative (pbrt-v3
/// clamps what the Lanczos lobes make negative).
pub fn resample_up<T: TexValue>(image: &ImageMap<T>) -> ImageMap<T> {
    let wrap = image.wrap();
    let (w, h) = (image.width(), image.height());
    let (w2, h2) = (w.next_power_of_two(), h.next_power_of_two());
    let texels = image.texels();
    // Each new texel's four old ones, wrapped once for all rows (`None`: black).
    let along_s: Vec<([Option<usize>; 4], [f32; 4])> = resample_weights(w, w2)
        .into_iter()
        .map(|(first, wts)| {
            let taps = std::array::from_fn(|j| wrap_index(first + j as i64, w, wrap));
            (taps, wts)
        })
        .collect();
    let mut wide = vec![T::ZERO; w2 * h];
    wide.par_chunks_mut(w2).enumerate().for_each(|(t, row)| {
        let line = &texels[t * w..(t + 1) * w];
        for (out, (taps, wts)) in row.iter_mut().zip(&along_s) {
            let mut v = T::ZERO;
            for (tap, &wt) in taps.iter().zip(wts) {
                if let Some(o) = *tap {
                    v = v + line[o] * wt;
                }
            }
            *out = v;
        }
    });
    let along_t = resample_weights(h, h2);
    let mut out = vec![T::ZERO; w2 * h2];
    out.par_chunks_mut(w2)
        .zip(along_t.par_iter())
        .for_each(|(row, (first, wts))| {
            for (j, &wt) in wts.iter().enumerate() {
                if let Some(o) = wrap_index(first + j as i64, h, wrap) {
                    let src = &wide[o * w2..(o + 1) * w2];
                    for (v, &x) in row.iter_mut().zip(src) {
                        *v = *v + x * wt;
                    }
                }
            }
            for v in row.iter_mut() {
                *v = v.clamp_nonneg();
            }
        });
    ImageMap::from_rows(w2, h2, out, wrap)
}

/// The level above `below`: each texel the mean of the 2 x 2 below it (wrapped as lookups
/// wrap, for a side of 1).
fn downsample<T: TexValue>(below: &ImageMap<T>) -> ImageMap<T> {
    let (sw, th) = ((below.width() / 2).max(1), (below.height() / 2).max(1));
    let mut texels = vec![T::ZERO; sw * th];
    let (w, h) = (below.width(), below.height());
    if w >= 2 && h >= 2 {
        // Both sides even: no texel read wraps.
        let src = below.texels();
        texels.par_chunks_mut(sw).enumerate().for_each(|(t, row)| {
            let (r0, r1) = (
                &src[2 * t * w..(2 * t + 1) * w],
                &src[(2 * t + 1) * w..(2 * t + 2) * w],
            );
            for (s, out) in row.iter_mut().enumerate() {
                let sum = r0[2 * s] + r0[2 * s + 1] + r1[2 * s] + r1[2 * s + 1];
                *out = sum * 0.25;
            }
        });
    } else {
        for (t, row) in texels.chunks_mut(sw).enumerate() {
            let t = t as i64;
            for (s, out) in row.iter_mut().enumerate() {
                let s = s as i64;
                let sum = below.texel(2 * s, 2 * t)
                    + below.texel(2 * s + 1, 2 * t)
                    + below.texel(2 * s, 2 * t + 1)
                    + below.texel(2 * s + 1, 2 * t + 1);
                *out = sum * 0.25;
            }
        }
    }
    ImageMap::from_rows(sw, th, texels, below.wrap())
}

/// Hands `keep` every level of the pyramid whose finest level is `base` (sides powers of
/// two), finest first; each level is built from the one below before that one is kept.
pub fn build_levels<T: TexValue>(base: ImageMap<T>, mut keep: impl FnMut(ImageMap<T>)) {
    let count = 1 + base.width().max(base.height()).ilog2() as usize;
    let mut level = base;
    for _ in 1..count {
        let next = downsample(&level);
        keep(level);
        level = next;
    }
    keep(level);
}

/// `level` stored in bytes: each channel of each texel the byte `quantiser` finds nearest
/// (`channels` of them: 1 keeps a grey colour's first channel). The whole-level reference that
/// [`super::byte_pyramid`]'s bands are tested against.
#[cfg(test)]
pub fn quantise<T: TexValue>(
    level: &ImageMap<T>,
    channels: usize,
    quantiser: &Quantiser,
    lut: &[f32; 256],
) -> ImageMap<T, ByteTexels> {
    let w = level.width();
    let mut data = vec![0u8; w * level.height() * channels];
    for (out, row) in data.chunks_mut(w * channels).zip(level.texels().chunks(w)) {
        for (bytes, v) in out.chunks_exact_mut(channels).zip(row) {
            for (c, b) in bytes.iter_mut().enumerate() {
                *b = quantiser.byte(v.channel(c));
            }
        }
    }
    let texels = ByteTexels::new(data, channels, *lut);
    ImageMap::from_rows(w, level.height(), texels, level.wrap())
}
