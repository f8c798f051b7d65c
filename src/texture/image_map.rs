//! Image maps: converted texels with pbrt-v3's wrap modes and bilinear lookup.

use super::texels::Texels;
use super::value::TexValue;
use crate::geometry::{Spectrum, Vec2};
use crate::image_io::RgbImage;
use std::fmt::Debug;
use std::marker::PhantomData;

/// What an image lookup outside [0, 1]² gives (pbrt-v3's `ImageWrap`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// Tile the image.
    Repeat,
    /// Black outside.
    Black,
    /// The nearest edge texel.
    Clamp,
}

/// An image ready for lookups: texels already converted (gamma, scale, invert), bottom row
/// first, so that t = 0 is the bottom of the picture as in pbrt-v3. The texels are stored as
/// `S`: `T`s, or bytes decoded through a table ([`super::texels::ByteTexels`]).
#[derive(Clone, Debug)]
pub struct ImageMap<T, S = Vec<T>> {
    width: usize,
    height: usize,
    texels: S,
    wrap: Wrap,
    /// Both sides powers of two (every MIP level's): repeating is a mask.
    pow2: bool,
    value: PhantomData<fn() -> T>,
}

impl<T: TexValue> ImageMap<T> {
    /// From an image (top row first) and the conversion of each texel.
    pub fn new(img: &RgbImage, wrap: Wrap, convert: impl Fn(Spectrum) -> T) -> Self {
        let (width, height) = (img.width.max(1), img.height.max(1));
        let mut texels = Vec::with_capacity(width * height);
        for t in 0..height {
            for s in 0..width {
                let c = if img.width == 0 || img.height == 0 {
                    Spectrum::ZERO
                } else {
                    img.get(s, img.height - 1 - t)
                };
                texels.push(convert(c));
            }
        }
        Self::from_rows(width, height, texels, wrap)
    }

    /// The texels, row 0 first.
    pub fn texels(&self) -> &[T] {
        &self.texels
    }
}

impl<T: TexValue, S: Texels<T>> ImageMap<T, S> {
    /// From texels already in lookup order (row 0 at t = 0), `width` x `height` of them.
    pub fn from_rows(width: usize, height: usize, texels: S, wrap: Wrap) -> Self {
        debug_assert_eq!(texels.len(), width * height);
        Self {
            width,
            height,
            texels,
            wrap,
            pow2: width.is_power_of_two() && height.is_power_of_two(),
            value: PhantomData,
        }
    }

    /// What a lookup outside [0, 1]² gives.
    pub fn wrap(&self) -> Wrap {
        self.wrap
    }

    /// The stored texels.
    pub fn storage(&self) -> &S {
        &self.texels
    }

    /// Width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Coordinate `v` of a side `n` texels long, wrapped: `None` where the wrap gives black.
    #[inline(always)]
    fn wrap_coord(&self, v: i64, n: usize) -> Option<usize> {
        let n = n as i64;
        match self.wrap {
            // The mask is the Euclidean remainder by a power of two, without a division.
            Wrap::Repeat if self.pow2 => Some((v & (n - 1)) as usize),
            Wrap::Repeat => Some(v.rem_euclid(n) as usize),
            Wrap::Clamp => Some(v.clamp(0, n - 1) as usize),
            Wrap::Black => (0..n).contains(&v).then_some(v as usize),
        }
    }

    /// Column `s` wrapped: `None` where the wrap gives black.
    #[inline(always)]
    pub fn column(&self, s: i64) -> Option<usize> {
        self.wrap_coord(s, self.width)
    }

    /// The index of row `t`'s first texel, the row wrapped: `None` where the wrap gives black.
    #[inline(always)]
    pub fn row_start(&self, t: i64) -> Option<usize> {
        self.wrap_coord(t, self.height).map(|t| t * self.width)
    }

    /// The texel at `index` (a [`ImageMap::row_start`] plus a [`ImageMap::column`]).
    #[inline(always)]
    pub fn at(&self, index: usize) -> T {
        self.texels.get(index)
    }

    /// The texel at column `s` (wrapped here) of the row starting at `row` (from
    /// [`ImageMap::row_start`]), black where either is.
    #[inline(always)]
    pub fn texel_in_row(&self, row: Option<usize>, s: i64) -> T {
        self.at_wrapped(row, self.column(s))
    }

    /// The texel at row start `row`, column `s` (both wrapped already), black where either is.
    #[inline(always)]
    fn at_wrapped(&self, row: Option<usize>, s: Option<usize>) -> T {
        match (row, s) {
            (Some(row), Some(s)) => self.texels.get(row + s),
            _ => T::ZERO,
        }
    }

    /// Asks for the cache line of the texel at column `s`, row `t` (wrapped), without waiting.
    #[inline(always)]
    pub fn prefetch(&self, s: i64, t: i64) {
        if let (Some(row), Some(s)) = (self.row_start(t), self.column(s)) {
            self.texels.prefetch(row + s);
        }
    }

    /// The texel at column `s`, row `t` counted from the bottom, wrapped.
    #[inline]
    pub fn texel(&self, s: i64, t: i64) -> T {
        self.at_wrapped(self.row_start(t), self.column(s))
    }

    /// Bilinear interpolation at (s, t) in [0, 1]² (pbrt-v3's `MIPMap::triangle` at level 0).
    #[inline]
    pub fn bilerp(&self, st: Vec2) -> T {
        // Keep the integer arithmetic far from overflow; NaN becomes 0.
        let fix = |v: f32| {
            if v.is_finite() {
                v.clamp(-1e9, 1e9)
            } else {
                0.0
            }
        };
        let s = fix(st.x * self.width as f32 - 0.5);
        let t = fix(st.y * self.height as f32 - 0.5);
        let (s0, t0) = (s.floor(), t.floor());
        let (ds, dt) = (s - s0, t - t0);
        let (s0, t0) = (s0 as i64, t0 as i64);
        // Each coordinate wrapped once, not once a texel.
        let (c0, c1) = (self.column(s0), self.column(s0 + 1));
        let (r0, r1) = (self.row_start(t0), self.row_start(t0 + 1));
        self.at_wrapped(r0, c0) * ((1.0 - ds) * (1.0 - dt))
            + self.at_wrapped(r1, c0) * ((1.0 - ds) * dt)
            + self.at_wrapped(r0, c1) * (ds * (1.0 - dt))
            + self.at_wrapped(r1, c1) * (ds * dt)
    }
}
