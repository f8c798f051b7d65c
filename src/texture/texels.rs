//! How an image map stores its texels: as values (`Vec<T>`), or as bytes decoded through a
//! 256-entry table ([`ByteTexels`], pbrt-v4's 8-bit images), with the quantiser that turns
//! filtered values back into bytes (docs/pbrt-v3-compatibility.md, "Materials and textures").

use super::value::TexValue;
use std::fmt::Debug;

/// Texel storage: the value of texel `i` (row-major, row 0 first).
pub trait Texels<T>: Clone + Debug + Send + Sync {
    /// Texel `i`.
    fn get(&self, i: usize) -> T;
    /// Number of texels.
    fn len(&self) -> usize;
    /// Asks for texel `i`'s cache line, without waiting for it.
    #[inline(always)]
    fn prefetch(&self, _i: usize) {}
    /// Whether there are no texels.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl<T: TexValue> Texels<T> for Vec<T> {
    #[inline]
    fn get(&self, i: usize) -> T {
        self[i]
    }
    #[inline(always)]
    fn prefetch(&self, i: usize) {
        prefetch(self.as_ptr().wrapping_add(i));
    }
    fn len(&self) -> usize {
        self.as_slice().len()
    }
}

/// Asks for the cache line holding `p`, without waiting for it.
#[inline(always)]
fn prefetch<P>(p: *const P) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch reads nothing the program sees and never faults, whatever the address.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(p.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Texels of 1 or 3 bytes each, a byte's value being `lut[byte]` (grey texels of a
/// spectrum texture are the same value in all three channels).
#[derive(Clone, Debug)]
pub struct ByteTexels {
    data: Vec<u8>,
    channels: usize,
    lut: Box<[f32; 256]>,
}

impl ByteTexels {
    /// `data`, `channels` bytes a texel, decoded through `lut`.
    pub fn new(data: Vec<u8>, channels: usize, lut: [f32; 256]) -> Self {
        debug_assert!(channels == 1 || channels == 3);
        Self {
            data,
            channels,
            lut: Box::new(lut),
        }
    }

    /// Bytes the texels take.
    pub fn bytes(&self) -> usize {
        self.data.len()
    }
}

impl<T: TexValue> Texels<T> for ByteTexels {
    #[inline]
    fn get(&self, i: usize) -> T {
        let k = i * self.channels;
        T::from_bytes(&self.data[k..k + self.channels], &self.lut)
    }
    fn len(&self) -> usize {
        self.data.len() / self.channels
    }
    #[inline(always)]
    fn prefetch(&self, i: usize) {
        prefetch(self.data.as_ptr().wrapping_add(i * self.channels));
    }
}

/// Buckets of the quantiser's table: fine enough that almost every bucket holds no point
/// halfway between two table values, and so one answer.
const BUCKETS: usize = 1 << 16;

/// A bucket whose values do not all have the same nearest byte.
const MIXED: u16 = u16::MAX;

/// The byte whose table value is nearest a value, for a monotone table.
#[derive(Clone, Debug)]
pub struct Quantiser {
    /// The table in ascending order.
    asc: [f32; 256],
    /// Whether `asc` is the table reversed (a decreasing table: `invert`).
    reversed: bool,
    lo: f32,
    inv_step: f32,
    /// Per bucket, the byte nearest all its values, or [`MIXED`].
    table: Vec<u16>,
}

impl Quantiser {
    /// The quantiser of `lut`; `None` if it is not monotone or not finite.
    pub fn new(lut: &[f32; 256]) -> Option<Self> {
        let reversed = lut[255] < lut[0];
        let mut asc = *lut;
        if reversed {
            asc.reverse();
        }
        if asc.iter().any(|v| !v.is_finite()) || asc.windows(2).any(|w| w[1] < w[0]) {
            return None;
        }
        let (lo, range) = (asc[0], asc[255] - asc[0]);
        let inv_step = if range > 0.0 {
            BUCKETS as f32 / range
        } else {
            0.0
        };
        let mut q = Self {
            asc,
            reversed,
            lo,
            inv_step,
            table: Vec::new(),
        };
        let step = range / BUCKETS as f32;
        // A bucket's ends widened a little: a value rounded into it lies between them.
        q.table = (0..BUCKETS)
            .map(|k| {
                let a = q.nearest(lo + (k as f32 - 0.01) * step);
                let b = q.nearest(lo + (k as f32 + 1.01) * step);
                if a == b {
                    a as u16
                } else {
                    MIXED
                }
            })
            .collect();
        Some(q)
    }

    /// The byte whose value is nearest `v` (the lower one on a tie; NaN gives the smallest
    /// value's byte).
    #[inline]
    pub fn byte(&self, v: f32) -> u8 {
        let k = (((v - self.lo) * self.inv_step) as usize).min(BUCKETS - 1);
        match self.table[k] {
            MIXED => self.nearest(v),
            b => b as u8,
        }
    }

    /// [`Quantiser::byte`] by search.
    fn nearest(&self, v: f32) -> u8 {
        // The last value at most v (0 if none).
        let mut b = self.asc.partition_point(|&x| x <= v).saturating_sub(1);
        if b < 255 && self.asc[b + 1] - v < v - self.asc[b] {
            b += 1;
        }
        if self.reversed {
            (255 - b) as u8
        } else {
            b as u8
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn srgb_lut() -> [f32; 256] {
        std::array::from_fn(|b| crate::spectrum::srgb_to_linear(b as f32 / 255.0))
    }

    #[test]
    fn a_table_value_quantises_to_its_own_byte() {
        let up = srgb_lut();
        let down: [f32; 256] = std::array::from_fn(|b| (1.0 - 2.0 * up[b]).max(0.0));
        for lut in [up, down] {
            let q = Quantiser::new(&lut).unwrap();
            for (b, &v) in lut.iter().enumerate() {
                assert_eq!(lut[q.byte(v) as usize], v, "byte {b}");
            }
        }
    }

    #[test]
    fn quantising_picks_the_nearest_byte() {
        let lut = srgb_lut();
        let q = Quantiser::new(&lut).unwrap();
        for i in 0..=20_000 {
            let v = i as f32 / 20_000.0 * 1.2 - 0.1;
            let got = (lut[q.byte(v) as usize] - v).abs();
            let best = lut
                .iter()
                .map(|x| (x - v).abs())
                .fold(f32::INFINITY, f32::min);
            assert_eq!(got, best, "{v}");
        }
        assert_eq!(q.byte(f32::NAN), 0);
    }

    #[test]
    fn a_table_that_is_not_monotone_has_no_quantiser() {
        let mut lut = srgb_lut();
        lut[9] = 0.9;
        assert!(Quantiser::new(&lut).is_none());
        lut[9] = f32::NAN;
        assert!(Quantiser::new(&lut).is_none());
    }
}
