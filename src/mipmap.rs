//! pbrt-v3's `MIPMap` (core/mipmap.h) for image textures: an image whose sides are not powers
//! of two is resampled up to them (a Lanczos-windowed sinc, 4 taps, clamped at 0), each level
//! halves the one below by a box filter ([`crate::texture::pyramid`]), and lookups filter over
//! the hit's footprint, EWA (a Gaussian over the footprint's ellipse, its eccentricity capped at
//! `maxanisotropy`) by default or trilinear on request. Without a footprint (rays after the
//! first bounce) a lookup is bilinear in the first level, as pbrt-v3's. The levels of an 8-bit
//! image are kept in bytes, as pbrt-v4 keeps them (docs/pbrt-v3-compatibility.md, "Materials
//! and textures"). EWA sums the texels pbrt-v3's loop sums, in its order, only faster
//! (docs/BENCHMARKS.md, "Texture lookups' speed").

use crate::texture::byte_pyramid::byte_levels;
use crate::texture::image_map::{ImageMap, Wrap};
use crate::texture::pyramid::{build_levels, resample_up};
use crate::texture::source::ByteImage;
use crate::texture::texels::{ByteTexels, Quantiser, Texels};
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

/// A pyramid's levels, finest first, in the storage they were built in.
#[derive(Clone, Debug)]
enum Pyramid<T> {
    /// Texels as values.
    Values(Vec<ImageMap<T>>),
    /// Texels as bytes through a table.
    Bytes(Vec<ImageMap<T, ByteTexels>>),
}

/// How a pyramid filters, and what its texels allow.
#[derive(Clone, Copy, Debug)]
struct Filter {
    /// Trilinear filtering instead of EWA.
    trilinear: bool,
    /// The largest ratio of the footprint's axes EWA keeps.
    max_anisotropy: f32,
    /// Every texel [`plain`]: a filtered value is then finite and not negative, and weighted
    /// by 0 it is +0.
    plain: bool,
}

/// The largest texel [`plain`] allows: no sum of a level's weighted texels, scaled by the
/// weights' inverse sum, can overflow.
const PLAIN_MAX: f32 = 1e20;

/// Whether `v` is finite, not negative (its sign bit clear: not -0) and at most [`PLAIN_MAX`].
fn plain(v: f32) -> bool {
    v.is_sign_positive() && v <= PLAIN_MAX
}

/// An image pyramid with pbrt-v3's lookups.
#[derive(Clone, Debug)]
pub struct MipMap<T> {
    /// Level 0 (the image, resampled to powers of two) up to 1 x 1.
    levels: Pyramid<T>,
    /// How lookups filter.
    filter: Filter,
}

impl<T: TexValue> MipMap<T> {
    /// The pyramid of `image`, its texels kept as values.
    pub fn new(image: &ImageMap<T>, trilinear: bool, max_anisotropy: f32) -> Self {
        Self::from_image(image.clone(), trilinear, max_anisotropy)
    }

    /// [`MipMap::new`], taking the image.
    pub fn from_image(image: ImageMap<T>, trilinear: bool, max_anisotropy: f32) -> Self {
        let base = if image.width().is_power_of_two() && image.height().is_power_of_two() {
            image
        } else {
            resample_up(&image)
        };
        let mut levels = Vec::new();
        build_levels(base, |level| levels.push(level));
        let plain = levels.iter().all(|m| {
            m.texels()
                .iter()
                .all(|&v| (0..3).all(|c| plain(v.channel(c))))
        });
        Self {
            levels: Pyramid::Values(levels),
            filter: Filter {
                trilinear,
                max_anisotropy,
                plain,
            },
        }
    }

    /// The pyramid of an 8-bit image whose byte `b` is worth `lut[b]`, kept in bytes: levels
    /// are built in floats exactly as [`MipMap::new`] builds them (band by band,
    /// [`crate::texture::byte_pyramid`]), each stored as the bytes `quantiser` finds nearest, but for a level 0 that is the image's own pixels, kept
    /// as they are. A grey image's bytes make every channel of a colour texel.
    pub fn from_bytes(
        image: &ByteImage,
        lut: &[f32; 256],
        quantiser: &Quantiser,
        wrap: Wrap,
        trilinear: bool,
        max_anisotropy: f32,
    ) -> Self {
        let levels = byte_levels(image, lut, quantiser, wrap);
        Self {
            levels: Pyramid::Bytes(levels),
            // Every texel is a table value.
            filter: Filter {
                trilinear,
                max_anisotropy,
                plain: lut.iter().all(|&v| plain(v)),
            },
        }
    }

    /// The finest level's width and height (the image's, raised to powers of two).
    pub fn size(&self) -> (usize, usize) {
        match &self.levels {
            Pyramid::Values(l) => (l[0].width(), l[0].height()),
            Pyramid::Bytes(l) => (l[0].width(), l[0].height()),
        }
    }

    /// The number of levels.
    pub fn levels(&self) -> usize {
        match &self.levels {
            Pyramid::Values(l) => l.len(),
            Pyramid::Bytes(l) => l.len(),
        }
    }

    /// Whether the texels are kept in bytes.
    pub fn in_bytes(&self) -> bool {
        matches!(self.levels, Pyramid::Bytes(_))
    }

    /// Bytes the texels take.
    pub fn texel_bytes(&self) -> usize {
        match &self.levels {
            Pyramid::Values(l) => {
                l.iter().map(|m| m.texels().len()).sum::<usize>() * size_of::<T>()
            }
            Pyramid::Bytes(l) => l.iter().map(|m| m.storage().bytes()).sum(),
        }
    }

    /// pbrt-v3's trilinear lookup over a square footprint `width` wide (its
    /// `MIPMap::Lookup(st, width)`).
    pub fn lookup_width(&self, st: Vec2, width: f32) -> T {
        match &self.levels {
            Pyramid::Values(l) => Levels(l).lookup_width(st, width),
            Pyramid::Bytes(l) => Levels(l).lookup_width(st, width),
        }
    }

    /// The filtered value at `st` over the footprint `dst0`, `dst1` (pbrt-v3's
    /// `MIPMap::Lookup(st, dstdx, dstdy)`).
    pub fn lookup(&self, st: Vec2, dst0: Vec2, dst1: Vec2) -> T {
        match &self.levels {
            Pyramid::Values(l) => Levels(l).lookup(st, dst0, dst1, self.filter),
            Pyramid::Bytes(l) => Levels(l).lookup(st, dst0, dst1, self.filter),
        }
    }
}

/// A pyramid's levels in one storage, with the lookups.
struct Levels<'a, T, S>(&'a [ImageMap<T, S>]);

impl<T: TexValue, S: Texels<T>> Levels<'_, T, S> {
    /// Bilinear lookup in `level` (pbrt-v3's `triangle`).
    fn triangle(&self, level: usize, st: Vec2) -> T {
        self.0[level.min(self.0.len() - 1)].bilerp(st)
    }

    /// The texel that stands for the whole image: the top level's.
    fn top(&self) -> T {
        self.0[self.0.len() - 1].texel(0, 0)
    }

    /// See [`MipMap::lookup_width`].
    fn lookup_width(&self, st: Vec2, width: f32) -> T {
        let n = self.0.len();
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

    /// See [`MipMap::lookup`].
    fn lookup(&self, st: Vec2, dst0: Vec2, dst1: Vec2, filter: Filter) -> T {
        let Filter {
            trilinear,
            max_anisotropy,
            plain,
        } = filter;
        if !(dst0.is_finite() && dst1.is_finite()) {
            return self.triangle(0, st);
        }
        if trilinear {
            let width = dst0.abs().max_element().max(dst1.abs().max_element());
            return self.lookup_width(st, width);
        }
        let (mut major, mut minor) = (dst0, dst1);
        if major.length_squared() < minor.length_squared() {
            std::mem::swap(&mut major, &mut minor);
        }
        let major_length = major.length();
        let mut minor_length = minor.length();
        if minor_length * max_anisotropy < major_length && minor_length > 0.0 {
            let scale = major_length / (minor_length * max_anisotropy);
            minor *= scale;
            minor_length *= scale;
        }
        if minor_length == 0.0 {
            return self.triangle(0, st);
        }
        let lod = (self.0.len() as f32 - 1.0 + minor_length.log2()).max(0.0);
        let i = lod.floor() as usize;
        let d = lod - i as f32;
        // Weighted by 0 (a footprint at or under a level-0 texel, clamped to level 0), the
        // coarser level's value would add +0: zero in its place keeps the same bits.
        let skip = d == 0.0 && plain;
        let fine = self.ellipse(i, st, major, minor);
        let coarse = (!skip).then(|| self.ellipse(i + 1, st, major, minor));
        // Both levels' rows asked for before either sum waits on them.
        self.prefetch(i, &fine);
        if let Some(e) = &coarse {
            self.prefetch(i + 1, e);
        }
        let coarser = coarse.map_or(T::ZERO, |e| self.ewa_sum(i + 1, e));
        self.ewa_sum(i, fine) * (1.0 - d) + coarser * d
    }

    /// pbrt-v3's EWA filter at one level.
    #[cfg(test)]
    fn ewa(&self, level: usize, st: Vec2, dst0: Vec2, dst1: Vec2) -> T {
        self.ewa_sum(level, self.ellipse(level, st, dst0, dst1))
    }

    /// pbrt-v3's EWA ellipse at `level`: its coefficients and bounding box in texels.
    fn ellipse(&self, level: usize, st: Vec2, dst0: Vec2, dst1: Vec2) -> Ellipse {
        let Some(map) = self.0.get(level) else {
            return Ellipse::Top;
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
            return Ellipse::Bilinear((st + Vec2::splat(0.5)) / size);
        }
        Ellipse::Box {
            abc: [a, b, c],
            st,
            s: [s0, s1],
            t: [t0 as i64, t1 as i64],
        }
    }

    /// Asks for the cache lines of `ellipse`'s rows at `level` ahead of [`Levels::ewa_sum`].
    fn prefetch(&self, level: usize, ellipse: &Ellipse) {
        if let (Some(map), Ellipse::Box { s, t, .. }) = (self.0.get(level), ellipse) {
            for it in t[0]..=t[1] {
                map.prefetch(s[0] as i64, it);
                map.prefetch(s[1] as i64, it);
            }
        }
    }

    /// The EWA sum over `ellipse` at `level`.
    fn ewa_sum(&self, level: usize, ellipse: Ellipse) -> T {
        let (map, (abc, st, [s0, s1], [t0, t1])) = match (self.0.get(level), ellipse) {
            (Some(map), Ellipse::Box { abc, st, s, t }) => (map, (abc, st, s, t)),
            (Some(map), Ellipse::Bilinear(st)) => return map.bilerp(st),
            _ => return self.top(),
        };
        let size = Vec2::new(map.width() as f32, map.height() as f32);
        let (mut sum, mut sum_weights) = (T::ZERO, 0.0f32);
        // Every column of the box inside the level: a column needs no wrapping.
        let inside = s0 >= 0.0 && s1 < size.x;
        let lut = weight_lut();
        let columns = s0 as i64..=s1 as i64;
        for it in t0..=t1 {
            let tt = it as f32 - st.y;
            let acc = (&mut sum, &mut sum_weights);
            let row = map.row_start(it);
            match (inside, row) {
                (true, Some(row)) => scan_row(abc, st.x, tt, columns.clone(), acc, lut, |is| {
                    map.at(row + is as usize)
                }),
                _ => scan_row(abc, st.x, tt, columns.clone(), acc, lut, |is| {
                    map.texel_in_row(row, is)
                }),
            }
        }
        if sum_weights > 0.0 {
            sum * (1.0 / sum_weights)
        } else {
            map.bilerp((st + Vec2::splat(0.5)) / size)
        }
    }
}

/// pbrt-v3's EWA footprint at one level.
enum Ellipse {
    /// Past the last level: the top texel.
    Top,
    /// Not finite, or too wide: bilinear at (s, t).
    Bilinear(Vec2),
    /// The ellipse's `A`, `B`, `C` about `st` (in texels), and its bounding box's columns
    /// (as floats) and rows.
    Box {
        abc: [f32; 3],
        st: Vec2,
        s: [f32; 2],
        t: [i64; 2],
    },
}

/// One row of pbrt-v3's EWA sum: each texel `is` of `columns` whose squared radius in the
/// ellipse `abc` (`A`, `B`, `C`) about `s` is under 1, at `tt` from the centre's row, adds
/// its `texel(is)`, weighted from `lut`, to `acc` (the sum and the weights' sum), in order.
#[inline(always)]
fn scan_row<T: TexValue>(
    abc: [f32; 3],
    s: f32,
    tt: f32,
    columns: std::ops::RangeInclusive<i64>,
    acc: (&mut T, &mut f32),
    lut: &[f32; WEIGHT_LUT_SIZE],
    texel: impl Fn(i64) -> T,
) {
    let [a, b, c] = abc;
    let (sum, sum_weights) = acc;
    for is in columns {
        let ss = is as f32 - s;
        let r2 = a * ss * ss + b * ss * tt + c * tt * tt;
        if r2 < 1.0 {
            let index = ((r2 * WEIGHT_LUT_SIZE as f32) as usize).min(WEIGHT_LUT_SIZE - 1);
            let weight = lut[index];
            *sum = *sum + texel(is) * weight;
            *sum_weights += weight;
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

    /// pbrt-v3's EWA loop as written over `ellipse` (from [`Levels::ellipse`] at `map`'s
    /// level): every texel of the bounding box tested, each wrapped.
    fn ewa_every_texel<T: TexValue, S: Texels<T>>(
        map: &ImageMap<T, S>,
        ellipse: &Ellipse,
    ) -> Option<T> {
        let &Ellipse::Box {
            abc: [a, b, c],
            st,
            s: [s0, s1],
            t: [t0, t1],
        } = ellipse
        else {
            return None;
        };
        let lut = weight_lut();
        let (mut sum, mut sum_weights) = (T::ZERO, 0.0f32);
        for it in t0..=t1 {
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
        (sum_weights > 0.0).then(|| sum * (1.0 / sum_weights))
    }

    /// Lookups at random points with random footprints, thin ellipses at every angle (no
    /// anisotropy cap) and boxes that cross the edges included, against the loop over every
    /// texel of the box: the same bits.
    fn check_rows_against_every_texel<T: TexValue, S: Texels<T>>(map: &ImageMap<T, S>) {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let levels = Levels(std::slice::from_ref(map));
        let mut compared = 0;
        for k in 0..40_000 {
            let st = Vec2::new(uniform() * 1.4 - 0.2, uniform() * 1.4 - 0.2);
            let scale = [0.002, 0.02, 0.2, 2.0][k % 4];
            let angle = uniform() * std::f32::consts::TAU;
            let major = Vec2::new(angle.cos(), angle.sin()) * scale * uniform();
            let minor = Vec2::new(-major.y, major.x) * [1.0, 0.3, 0.01, 1e-4, 0.0][k % 5];
            let ellipse = levels.ellipse(0, st, major, minor);
            let Some(want) = ewa_every_texel(map, &ellipse) else {
                continue;
            };
            let got = levels.ewa(0, st, major, minor);
            for ch in 0..3 {
                assert_eq!(
                    got.channel(ch).to_bits(),
                    want.channel(ch).to_bits(),
                    "{st} {major} {minor}: {got:?} against {want:?}"
                );
            }
            compared += 1;
        }
        assert!(compared > 30_000, "{compared}");
    }

    #[test]
    fn ewa_row_by_row_gives_the_bits_of_pbrt_v3s_loop() {
        for (w, h) in [(64, 32), (48, 20)] {
            for wrap in [Wrap::Repeat, Wrap::Black, Wrap::Clamp] {
                check_rows_against_every_texel(&image(w, h, wrap));
                let bytes = (0..w * h * 3).map(|i| (i * 37 % 251) as u8).collect();
                let lut =
                    std::array::from_fn(|b| crate::spectrum::srgb_to_linear(b as f32 / 255.0));
                let texels = ByteTexels::new(bytes, 3, lut);
                let map: ImageMap<crate::geometry::Spectrum, _> =
                    ImageMap::from_rows(w, h, texels, wrap);
                check_rows_against_every_texel(&map);
            }
        }
    }

    #[test]
    fn a_footprint_under_a_texel_skips_the_coarser_level_and_keeps_the_bits() {
        let mip = MipMap::new(&image(64, 32, Wrap::Repeat), false, 8.0);
        assert!(mip.filter.plain);
        let Pyramid::Values(levels) = &mip.levels else {
            panic!("values");
        };
        let levels = Levels(levels);
        for k in 0..2000 {
            let st = Vec2::new(k as f32 * 0.0137 % 1.0, k as f32 * 0.0291 % 1.0);
            // Under a level-0 texel (1/64 wide): the level is clamped to 0.
            let major = Vec2::new(0.004, 0.001 * (k % 7) as f32);
            let minor = Vec2::new(-major.y, major.x) * 0.5;
            let both =
                levels.ewa(0, st, major, minor) * 1.0 + levels.ewa(1, st, major, minor) * 0.0;
            assert_eq!(
                mip.lookup(st, major, minor).to_bits(),
                both.to_bits(),
                "{st}"
            );
        }
        for bad in [-0.0, -1e-3, f32::INFINITY, f32::NAN, 1e21] {
            let mut texels = vec![0.5f32; 16];
            texels[5] = bad;
            let map = ImageMap::from_rows(4, 4, texels, Wrap::Clamp);
            assert!(!MipMap::new(&map, false, 8.0).filter.plain, "{bad}");
        }
    }
}
