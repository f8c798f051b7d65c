//! The rendering space (docs/algorithm.md §1): image dims `x`, `y` in pixels always, time `t`
//! only when something moves during the shutter, lens `u`, `v` only with a lens; non-image dims
//! normalised to [0, 1). Samplers produce points of this space and know nothing of the scene.

/// Which dimensions beyond the image plane the scene needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Dims {
    /// Something moves while the shutter is open: sample time.
    pub time: bool,
    /// The camera has a lens: sample the lens.
    pub lens: bool,
}

impl Dims {
    /// The names of the active dimensions, as the stats file reports them.
    pub fn names(&self) -> Vec<&'static str> {
        let mut v = vec!["x", "y"];
        if self.time {
            v.push("t");
        }
        if self.lens {
            v.extend(["u", "v"]);
        }
        v
    }

    /// How many dimensions are active (2 to 5).
    pub fn count(&self) -> usize {
        2 + usize::from(self.time) + 2 * usize::from(self.lens)
    }
}

/// The part of the rendering space one render covers: a half-open pixel rectangle and its dims.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderingSpace {
    /// First pixel column rendered.
    pub x0: u32,
    /// One past the last pixel column rendered.
    pub x1: u32,
    /// First pixel row rendered.
    pub y0: u32,
    /// One past the last pixel row rendered.
    pub y1: u32,
    /// The active dimensions beyond x and y.
    pub dims: Dims,
}

impl RenderingSpace {
    /// The whole of a `width` x `height` image, no crop, with `dims` beyond x and y.
    pub fn whole(width: u32, height: u32, dims: Dims) -> Self {
        Self {
            x0: 0,
            x1: width,
            y0: 0,
            y1: height,
            dims,
        }
    }

    /// Pixel columns rendered.
    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    /// Pixel rows rendered.
    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    /// How many pixels are rendered.
    pub fn pixels(&self) -> u64 {
        u64::from(self.width()) * u64::from(self.height())
    }

    /// The row-major index of pixel `p` (which must lie in the space): [`Self::pixel`]'s inverse.
    #[inline]
    pub fn index_of(&self, p: [u32; 2]) -> usize {
        (p[1] - self.y0) as usize * self.width() as usize + (p[0] - self.x0) as usize
    }

    /// The `i`-th pixel in row-major order, as `[x, y]`.
    #[inline]
    pub fn pixel(&self, i: u64) -> [u32; 2] {
        let w = u64::from(self.width());
        [self.x0 + (i % w) as u32, self.y0 + (i / w) as u32]
    }
}

/// One point of the rendering space, with what the renderer needs to trace it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplePoint {
    /// The pixel the point was drawn for, `[x, y]`.
    pub pixel: [u32; 2],
    /// The sample's index within its pixel (0, 1, 2, ... in the order drawn; below spp except
    /// for adaptive samplers, which give some pixels more): with `pixel` and the seed it keys
    /// the integrator's per-sample random stream.
    pub index: u32,
    /// Raster position, inside `[pixel, pixel + 1)` in both axes.
    pub film: [f32; 2],
    /// Shutter time in [0, 1); 0.5 when the time dim is inactive.
    pub time: f32,
    /// Lens position in [0, 1)^2; `[0.5, 0.5]` when the lens dims are inactive.
    pub lens: [f32; 2],
}

impl SamplePoint {
    /// A point not made yet: pixel 0, index 0, inactive time and lens; what a buffer is
    /// filled with before its points are written in place.
    pub const UNMADE: Self = Self {
        pixel: [0; 2],
        index: 0,
        film: [0.0; 2],
        time: 0.5,
        lens: [0.5; 2],
    };
}

/// The largest f32 below 1, so that a value meant to lie in [0, 1) never rounds up to 1.
pub const ONE_MINUS_EPSILON: f32 = f32::from_bits(0x3f7f_ffff);

/// The raster coordinate `p + offset` for `offset` in [0, 1), kept inside `[p, p + 1)`:
/// rounding would otherwise carry it to `p + 1` (from coordinate 1024 on, say) and the sample
/// would land in the next pixel, unsorting the batch's rows.
#[inline]
pub fn in_pixel(p: u32, offset: f32) -> f32 {
    in_stratum(p, 0, 1, offset as f64)
}

/// An f32 `f` nearest to `base + v` with `k / n <= f - base < (k + 1) / n` exactly, for `v` in
/// that stratum: the nearest float can fall across the stratum's edge, which would break the
/// stratification samplers promise. Exact while `base` < 2^24 and the stratum holds a float.
#[inline]
pub(crate) fn in_stratum(base: u32, k: u32, n: u32, v: f64) -> f32 {
    let b = f64::from(base);
    let (k, n) = (f64::from(k), f64::from(n));
    let mut f = (b + v) as f32;
    // `(f - b) * n` is exact in f64 (f has 24 significant bits, n < 2^29), so this test is the
    // same one a caller makes; a few steps suffice since rounding moves f by half an ulp.
    for _ in 0..8 {
        let d = (f64::from(f) - b) * n;
        if d < k {
            f = f32::from_bits(f.to_bits() + 1);
        } else if d >= k + 1.0 {
            f = f32::from_bits(f.to_bits() - 1);
        } else {
            break;
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dims_names_and_counts() {
        let d = |time, lens| Dims { time, lens };
        assert_eq!(d(false, false).names(), ["x", "y"]);
        assert_eq!(d(true, false).names(), ["x", "y", "t"]);
        assert_eq!(d(false, true).names(), ["x", "y", "u", "v"]);
        assert_eq!(d(true, true).names(), ["x", "y", "t", "u", "v"]);
        for (t, l) in [(false, false), (true, false), (false, true), (true, true)] {
            assert_eq!(d(t, l).count(), d(t, l).names().len());
        }
    }

    #[test]
    fn pixels_row_major() {
        let s = RenderingSpace {
            x0: 3,
            x1: 6,
            y0: 10,
            y1: 12,
            dims: Dims::default(),
        };
        assert_eq!(s.pixels(), 6);
        assert_eq!(s.pixel(0), [3, 10]);
        assert_eq!(s.pixel(2), [5, 10]);
        assert_eq!(s.pixel(3), [3, 11]);
        let empty = RenderingSpace { x1: 2, ..s };
        assert_eq!(empty.pixels(), 0);
    }

    #[test]
    fn in_pixel_stays_inside() {
        // 1024 + (1 - 2^-24) rounds to 1025 in f32: it must stay below.
        for p in [0u32, 1, 1023, 1024, 4095, 1 << 20] {
            let f = in_pixel(p, ONE_MINUS_EPSILON);
            assert!(f >= p as f32 && (f as f64) < p as f64 + 1.0, "{p}: {f}");
            assert_eq!(in_pixel(p, 0.0), p as f32);
        }
        // A value just below a stratum edge stays in its stratum.
        let f = in_stratum(3, 1, 4, 0.5 - 1e-9);
        assert!((f as f64 - 3.0) * 4.0 < 2.0 && (f as f64 - 3.0) * 4.0 >= 1.0);
    }
}
