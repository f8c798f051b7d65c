//! pbrt-v3's `MIPMap` (core/mipmap.h) for image textures: an image whose sides are not powers
//! of two is resampled up to them (a Lanczos-windowed sinc, 4 taps, clamped at 0), each level
//! halves the one below by a box filter, and lookups filter over the hit's footprint, EWA
//! (a Gaussian over the footprint's ellipse, its eccentricity capped at `maxanisotropy`) by
//! default or trilinear on request. Without a footprint (rays after the first bounce) a lookup
//! is bilinear in the first level, as pbrt-v3's.

use crate::texture::image_map::{ImageMap, Wrap};
use crate::texture::value::TexValue;
use glam::Vec2;

/// Entries of pbrt-v3's Gaussian weight table.
const WEIGHT_LUT_SIZE: usize = 128;

/// pbrt-v3's EWA weights: exp(-2 r^2) - exp(-2) at r^2 = i / 127.
fn weight_lut() -> &'static [f32; WEIGHT_LUT_SIZE] {
    static LUT: std::sync::OnceLock<[f32; WEIGHT_LUT_SIZE]> = std::sync::OnceLock::new();
    LUT.get_or_init(|| {
        std::array::from_fn(|i| {
            let r2 = i as f32 / (WEIGHT_LUT_SIZE - 1) as f32;
            (-2.0 * r2).exp() - (-2.0f32).exp()
        })
    })
}

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
fn resample_weights(old: usize, new: usize) -> Vec<(i64, [f32; 4])> {
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

/// `lines` lines of `old` texels each (texel i of line l is `at(l, i)`) resampled to `new`
/// texels with pbrt-v3's weights, line after line.
fn resample_lines<T: TexValue>(
    at: impl Fn(usize, usize) -> T,
    lines: usize,
    old: usize,
    new: usize,
    wrap: Wrap,
) -> Vec<T> {
    let weights = resample_weights(old, new);
    let mut out = Vec::with_capacity(lines * new);
    for l in 0..lines {
        for (first, w) in &weights {
            let mut v = T::ZERO;
            for (j, &wt) in w.iter().enumerate() {
                if let Some(o) = wrap_index(first + j as i64, old, wrap) {
                    v = v + at(l, o) * wt;
                }
            }
            out.push(v);
        }
    }
    out
}

/// Where texel `i` of a `size`-texel row lies after wrapping (`None`: black, outside).
fn wrap_index(i: i64, size: usize, wrap: Wrap) -> Option<usize> {
    let n = size as i64;
    match wrap {
        Wrap::Repeat => Some(i.rem_euclid(n) as usize),
        Wrap::Clamp => Some(i.clamp(0, n - 1) as usize),
        Wrap::Black => (0..n).contains(&i).then_some(i as usize),
    }
}

/// An image pyramid with pbrt-v3's lookups.
#[derive(Clone, Debug)]
pub struct MipMap<T> {
    /// Level 0 (the image, resampled to powers of two) up to 1 x 1.
    levels: Vec<ImageMap<T>>,
    /// Trilinear filtering instead of EWA.
    trilinear: bool,
    /// The largest ratio of the footprint's axes EWA keeps.
    max_anisotropy: f32,
}

impl<T: TexValue> MipMap<T> {
    /// The pyramid of `image` (a resampled texel is kept non-negative: pbrt-v3 clamps what the
    /// Lanczos lobes make negative).
    pub fn new(image: &ImageMap<T>, trilinear: bool, max_anisotropy: f32) -> Self {
        let wrap = image.wrap();
        let (w, h) = (image.width(), image.height());
        let base = if w.is_power_of_two() && h.is_power_of_two() {
            image.clone()
        } else {
            let (w2, h2) = (w.next_power_of_two(), h.next_power_of_two());
            let texels = image.texels();
            // Along s, row by row; then along t, column by column, clamped.
            let wide = resample_lines(|t, s| texels[t * w + s], h, w, w2, wrap);
            let tall = resample_lines(|s, t| wide[t * w2 + s], w2, h, h2, wrap);
            let mut out = vec![T::ZERO; w2 * h2];
            for s in 0..w2 {
                for t in 0..h2 {
                    out[t * w2 + s] = tall[s * h2 + t].clamp_nonneg();
                }
            }
            ImageMap::from_rows(w2, h2, out, wrap)
        };
        let count = 1 + base.width().max(base.height()).ilog2() as usize;
        let mut levels = vec![base];
        for _ in 1..count {
            let below = levels.last().expect("level 0 is there");
            let (sw, th) = ((below.width() / 2).max(1), (below.height() / 2).max(1));
            let mut texels = Vec::with_capacity(sw * th);
            for t in 0..th as i64 {
                for s in 0..sw as i64 {
                    let sum = below.texel(2 * s, 2 * t)
                        + below.texel(2 * s + 1, 2 * t)
                        + below.texel(2 * s, 2 * t + 1)
                        + below.texel(2 * s + 1, 2 * t + 1);
                    texels.push(sum * 0.25);
                }
            }
            levels.push(ImageMap::from_rows(sw, th, texels, wrap));
        }
        Self {
            levels,
            trilinear,
            max_anisotropy,
        }
    }

    /// The finest level's width and height (the image's, raised to powers of two).
    pub fn size(&self) -> (usize, usize) {
        (self.levels[0].width(), self.levels[0].height())
    }

    /// The number of levels.
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// Bilinear lookup in `level` (pbrt-v3's `triangle`).
    fn triangle(&self, level: usize, st: Vec2) -> T {
        self.levels[level.min(self.levels.len() - 1)].bilerp(st)
    }

    /// The texel that stands for the whole image: the top level's.
    fn top(&self) -> T {
        self.levels[self.levels.len() - 1].texel(0, 0)
    }

    /// pbrt-v3's trilinear lookup over a square footprint `width` wide (its
    /// `MIPMap::Lookup(st, width)`).
    pub fn lookup_width(&self, st: Vec2, width: f32) -> T {
        let n = self.levels.len();
        let level = n as f32 - 1.0 + width.max(1e-8).log2();
        if level < 0.0 {
            self.triangle(0, st)
        } else if level >= (n - 1) as f32 {
            self.top()
        } else {
            let i = level.floor() as usize;
            let d = level - i as f32;
            self.triangle(i, st) * (1.0 - d) + self.triangle(i + 1, st) * d
        }
    }

    /// The filtered value at `st` over the footprint `dst0`, `dst1` (pbrt-v3's
    /// `MIPMap::Lookup(st, dstdx, dstdy)`).
    pub fn lookup(&self, st: Vec2, dst0: Vec2, dst1: Vec2) -> T {
        if !(dst0.is_finite() && dst1.is_finite()) {
            return self.triangle(0, st);
        }
        if self.trilinear {
            let width = dst0.abs().max_element().max(dst1.abs().max_element());
            return self.lookup_width(st, width);
        }
        let (mut major, mut minor) = (dst0, dst1);
        if major.length_squared() < minor.length_squared() {
            std::mem::swap(&mut major, &mut minor);
        }
        let major_length = major.length();
        let mut minor_length = minor.length();
        if minor_length * self.max_anisotropy < major_length && minor_length > 0.0 {
            let scale = major_length / (minor_length * self.max_anisotropy);
            minor *= scale;
            minor_length *= scale;
        }
        if minor_length == 0.0 {
            return self.triangle(0, st);
        }
        let lod = (self.levels.len() as f32 - 1.0 + minor_length.log2()).max(0.0);
        let i = lod.floor() as usize;
        let d = lod - i as f32;
        self.ewa(i, st, major, minor) * (1.0 - d) + self.ewa(i + 1, st, major, minor) * d
    }

    /// pbrt-v3's EWA filter at one level.
    fn ewa(&self, level: usize, st: Vec2, dst0: Vec2, dst1: Vec2) -> T {
        let Some(map) = self.levels.get(level) else {
            return self.top();
        };
        let size = Vec2::new(map.width() as f32, map.height() as f32);
        let st = st * size - Vec2::splat(0.5);
        let (d0, d1) = (dst0 * size, dst1 * size);
        let mut a = d0.y * d0.y + d1.y * d1.y + 1.0;
        let mut b = -2.0 * (d0.x * d0.y + d1.x * d1.y);
        let mut c = d0.x * d0.x + d1.x * d1.x + 1.0;
        let inv_f = 1.0 / (a * c - b * b * 0.25);
        a *= inv_f;
        b *= inv_f;
        c *= inv_f;
        let det = -b * b + 4.0 * a * c;
        let inv_det = 1.0 / det;
        let (u_sqrt, v_sqrt) = ((det * c).sqrt(), (a * det).sqrt());
        let s0 = (st.x - 2.0 * inv_det * u_sqrt).ceil();
        let s1 = (st.x + 2.0 * inv_det * u_sqrt).floor();
        let t0 = (st.y - 2.0 * inv_det * v_sqrt).ceil();
        let t1 = (st.y + 2.0 * inv_det * v_sqrt).floor();
        // A footprint that is not finite, or wider than any capped one can be: bilinear.
        let span = (s1 - s0).max(t1 - t0);
        if !(span.is_finite() && s0.is_finite() && t0.is_finite()) || span > 4096.0 {
            return map.bilerp((st + Vec2::splat(0.5)) / size);
        }
        let lut = weight_lut();
        let (mut sum, mut sum_weights) = (T::ZERO, 0.0f32);
        for it in t0 as i64..=t1 as i64 {
            let tt = it as f32 - st.y;
            for is in s0 as i64..=s1 as i64 {
                let ss = is as f32 - st.x;
                let r2 = a * ss * ss + b * ss * tt + c * tt * tt;
                if r2 < 1.0 {
                    let index = ((r2 * WEIGHT_LUT_SIZE as f32) as usize).min(WEIGHT_LUT_SIZE - 1);
                    let weight = lut[index];
                    sum = sum + map.texel(is, it) * weight;
                    sum_weights += weight;
                }
            }
        }
        if sum_weights > 0.0 {
            sum * (1.0 / sum_weights)
        } else {
            map.bilerp((st + Vec2::splat(0.5)) / size)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The image of `tests/data/pbrt-v3/mipmapcheck.cpp`.
    fn image(w: usize, h: usize, wrap: Wrap) -> ImageMap<f32> {
        let texels = (0..h)
            .flat_map(|t| {
                (0..w).map(move |s| 0.1 + ((3 * s + 5 * t) % 7) as f32 / 7.0 + 0.02 * s as f32)
            })
            .collect();
        ImageMap::from_rows(w, h, texels, wrap)
    }

    #[test]
    fn lookups_match_pbrt_v3() {
        let data = include_str!("../tests/data/pbrt-v3/mipmap.txt");
        let mut worst = 0.0f32;
        for line in data.lines() {
            let v: Vec<f32> = line
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            let wrap = [Wrap::Repeat, Wrap::Black, Wrap::Clamp][v[2] as usize];
            let mip = MipMap::new(&image(v[0] as usize, v[1] as usize, wrap), v[3] == 1.0, 8.0);
            let got = mip.lookup(
                Vec2::new(v[4], v[5]),
                Vec2::new(v[6], v[7]),
                Vec2::new(v[8], v[9]),
            );
            let err = (got - v[10]).abs() / v[10].abs().max(0.1);
            worst = worst.max(err);
            assert!(err < 1e-4, "{line}: {got}");
        }
        eprintln!("largest relative difference {worst:.1e}");
    }

    #[test]
    fn a_constant_image_stays_constant_at_every_footprint() {
        let map = ImageMap::from_rows(5, 3, vec![0.7f32; 15], Wrap::Repeat);
        for trilinear in [false, true] {
            let mip = MipMap::new(&map, trilinear, 8.0);
            assert_eq!(mip.levels(), 4, "8 x 4 after resampling: 4 levels");
            for scale in [0.0, 1e-3, 0.1, 1.0, 10.0] {
                let v = mip.lookup(
                    Vec2::new(0.3, 0.6),
                    Vec2::new(scale, 0.2 * scale),
                    Vec2::new(-0.1 * scale, scale),
                );
                assert!((v - 0.7).abs() < 1e-5, "{scale}: {v}");
            }
        }
    }
}
