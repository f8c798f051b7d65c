//! IEEE 754 half precision (binary16) by hand, for the half buffers' features: 11 significant
//! bits (relative error at most 2^-11 when rounded to nearest even), normal from 6.1e-5 to
//! 65504. Values beyond the largest finite one are stored as it, so that sums never become
//! infinite.

/// The binary16 nearest `x` (ties to even), its magnitude at most 65504; NaN stays NaN.
pub fn to_half(x: f32) -> u16 {
    let b = x.to_bits();
    let sign = ((b >> 16) & 0x8000) as u16;
    let a = b & 0x7fff_ffff;
    if a > 0x7f80_0000 {
        return sign | 0x7e00;
    }
    if a >= 0x4780_0000 {
        // 65536 or more, infinity included.
        return sign | 0x7bff;
    }
    if a < 0x3880_0000 {
        // Below 2^-14: a subnormal half, in units of 2^-24 (the scaling is exact).
        let units = f32::from_bits(a) * (1u32 << 24) as f32;
        return sign | units.round_ties_even() as u16;
    }
    // Rebias the exponent (127 to 15) and round the significand from 23 to 10 bits.
    let a = a - 0x3800_0000;
    let rounded = (a + 0x0fff + ((a >> 13) & 1)) >> 13;
    sign | rounded.min(0x7bff) as u16
}

/// The value of binary16 `h`.
pub fn from_half(h: u16) -> f32 {
    let (e, m) = (u32::from(h >> 10) & 0x1f, u32::from(h & 0x3ff));
    let v = match e {
        0 => m as f32 / (1u32 << 24) as f32,
        31 if m == 0 => f32::INFINITY,
        31 => f32::NAN,
        _ => f32::from_bits(((e + 112) << 23) | (m << 13)),
    };
    if h & 0x8000 != 0 {
        -v
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_finite_half_round_trips() {
        for h in 0..=u16::MAX {
            let v = from_half(h);
            if v.is_nan() {
                assert!(from_half(to_half(v)).is_nan());
            } else if v.is_finite() {
                assert_eq!(to_half(v), h, "{h:#x} {v}");
            }
        }
        assert_eq!(from_half(to_half(1.0)), 1.0);
        assert_eq!(from_half(to_half(65504.0)), 65504.0);
        assert_eq!(from_half(to_half(1e9)), 65504.0);
        assert_eq!(from_half(to_half(f32::INFINITY)), 65504.0);
        assert_eq!(from_half(to_half(-3.0e-8)), -5.960_464_5e-8);
    }

    #[test]
    fn rounding_is_to_the_nearest_half() {
        let mut x = 1.234_567e-7f32;
        while x < 60000.0 {
            for v in [x, -x] {
                let r = from_half(to_half(v));
                let tolerance = (v.abs() * 2f32.powi(-11)).max(2f32.powi(-25));
                assert!((r - v).abs() <= tolerance, "{v} -> {r}");
            }
            x *= 1.37;
        }
        // A tie between two halves goes to the even one: 1 + 2^-11 lies between 1 and
        // 1 + 2^-10.
        assert_eq!(from_half(to_half(1.0 + 2f32.powi(-11))), 1.0);
        assert_eq!(
            from_half(to_half(1.0 + 3.0 * 2f32.powi(-11))),
            1.0 + 2.0 * 2f32.powi(-10)
        );
    }
}
