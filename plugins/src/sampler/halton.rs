//! `halton`: pbrt-v3's HaltonSampler in spirit. Sample i of a pixel is the i-th Halton point,
//! radical inverse in base 2 and 3 for the film offset, 5 for time, 7 and 11 for the lens,
//! Owen-scrambled (as pbrt-v4's OwenScrambledRadicalInverse) with a hash of (pixel, seed, dim),
//! so pixels are independent while each keeps the sequence's stratification: among the first
//! n points the base-b digits of i, hence the intervals of width b^-m, are balanced.

use super::{mix64, pixel_key, PixelCursor, PixelPattern, Sampler};
use super::{SamplerBuild, SamplerSetup};
use crate::registry::{Choice, Entry, Kind, ParamSpec, PluginInfo};
use crate::space::{in_pixel, RenderingSpace, SamplePoint, ONE_MINUS_EPSILON};
use acr_parser::{ParamType, Result};

/// Salt of this sampler's per-pixel keys.
const SALT: u64 = 0x6861_6c74;

/// The largest power of `b` below 2^25: digits past it are below f32 precision.
const fn top_scale(b: u64) -> u64 {
    let mut s = 1;
    while s * b < 1 << 25 {
        s *= b;
    }
    s
}

/// The least power of `b` at least `n` (at most [`top_scale`]): the digits of every index
/// below `n` lie above it.
pub(crate) fn scale_for(b: u64, n: u64) -> u64 {
    let mut s = 1;
    while s < n && s < top_scale(b) {
        s *= b;
    }
    s
}

/// The random affine permutation `d -> (m d + c) mod B` of the digit at `scale` under the
/// scrambled digits `reversed` above it (nested, as Owen's scrambling).
#[inline]
fn digit_permutation<const B: u64>(hash: u64, reversed: u64, scale: u64) -> (u64, u64) {
    let h = mix64(hash ^ reversed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ scale);
    // B is prime, so any multiplier in 1..B is a bijection; the shift makes d uniform.
    (1 + h % (B - 1), (h >> 32) % B)
}

/// The point of the scrambled digits `reversed` (down to `scale`), their prefix's random fill
/// below added. [`Fill::point`] gives the same values faster.
#[cfg(test)]
fn filled<const B: u64>(hash: u64, reversed: u64, scale: u64) -> f32 {
    let top = top_scale(B);
    let rest = top / scale;
    let fill = mix64(hash ^ reversed.wrapping_mul(0xd6e8_feb8_6659_fd93) ^ scale) % rest;
    let r = reversed * rest + fill;
    ((r as f64 / top as f64) as f32).min(ONE_MINUS_EPSILON)
}

/// Owen-scrambled radical inverse of `a` in base `B`, digits scrambled one by one down to
/// `exact` (a power of B above every index used, from [`scale_for`]). Each digit goes through
/// a random affine permutation `d -> (m d + c) mod B` chosen by a hash of `hash` and the digits
/// above it (nested, as Owen's scrambling), so every digit is uniform and the strata of all
/// levels down to `exact` are kept. Below `exact` Owen's scrambled zero digits are uniform and
/// independent per prefix, so one hash of the prefix draws them all at once (the cost is then
/// log_B(spp) hashes, not 24). The result is a multiple of 1 / top_scale(B), a step wider than
/// half an f32 ulp below 1 (top_scale < 2^25), so rounding to f32 never crosses an interval edge.
/// The sampler scrambles with [`Scrambling`] and [`Fill`], which give the same values.
#[cfg(test)]
pub(crate) fn owen_radical_inverse<const B: u64>(mut a: u64, hash: u64, exact: u64) -> f32 {
    let top = top_scale(B);
    let mut reversed: u64 = 0;
    let mut scale: u64 = 1;
    while scale < exact && scale < top {
        let digit = a % B;
        a /= B;
        let (m, c) = digit_permutation::<B>(hash, reversed, scale);
        reversed = reversed * B + (m * digit + c) % B;
        scale *= B;
    }
    filled::<B>(hash, reversed, scale)
}

/// The fill below the digits scrambled one by one, for base `B` down to a given `exact`: its
/// constants are computed once, so that a point costs no division (a hash's remainder by
/// Lemire, Kaser and Kurz's direct computation, the scaling by a reciprocal), with the values
/// of the divisions bit for bit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fill {
    /// The scale the one-by-one digits end at (the first power of B at least `exact`, at
    /// most top_scale(B)).
    scale: u64,
    /// top_scale(B) / scale: the fill's range.
    rest: u64,
    /// ceil(2^128 / rest) (0 for rest = 1): `x % rest` is the high part of
    /// `(magic * x mod 2^128) * rest`.
    magic: u128,
    /// 1 / top_scale(B).
    inv_top: f64,
}

impl Fill {
    /// The fill of base `B` below `exact`.
    pub(crate) fn new<const B: u64>(exact: u64) -> Self {
        let top = top_scale(B);
        let mut scale = 1;
        while scale < exact && scale < top {
            scale *= B;
        }
        let rest = top / scale;
        Self {
            scale,
            rest,
            magic: (u128::MAX / u128::from(rest)).wrapping_add(1),
            inv_top: 1.0 / top as f64,
        }
    }

    /// `x % self.rest`, by multiplication (exact for every 64-bit `x`: the 128-bit magic
    /// carries twice the bits of the operands).
    #[inline]
    fn rem(&self, x: u64) -> u64 {
        let low = self.magic.wrapping_mul(u128::from(x));
        let rest = u128::from(self.rest);
        let lo = u128::from(low as u64) * rest;
        let hi = (low >> 64) * rest;
        ((hi + (lo >> 64)) >> 64) as u64
    }

    /// The point of the scrambled digits `reversed` with the fill below them: `filled`'s
    /// value. The product by 1 / top in place of the division rounds to the same f32: top is
    /// odd (or a power of two, where both are exact), so r / top lies at least 2^-50 (relative)
    /// from every f32 rounding boundary, and the two f64 values are within 2^-52 of it.
    #[inline]
    fn point(&self, hash: u64, reversed: u64) -> f32 {
        let fill = self.rem(mix64(
            hash ^ reversed.wrapping_mul(0xd6e8_feb8_6659_fd93) ^ self.scale,
        ));
        let r = reversed * self.rest + fill;
        ((r as f64 * self.inv_top) as f32).min(ONE_MINUS_EPSILON)
    }
}

/// One dim's scrambled radical inverse under way: the digits of the index not yet scrambled,
/// the scrambled ones, and the scale of the next.
#[derive(Clone, Copy, Debug)]
struct Scrambling {
    a: u64,
    reversed: u64,
    scale: u64,
}

impl Scrambling {
    /// The scrambling of index `a`, no digit done.
    fn new(a: u64) -> Self {
        Self {
            a,
            reversed: 0,
            scale: 1,
        }
    }

    /// Scrambles the next digit in base `B`; false (and nothing done) once the digits down to
    /// the fill's scale are. The digits' remainders are by the constant B.
    #[inline(always)]
    fn step<const B: u64>(&mut self, hash: u64, fill: &Fill) -> bool {
        if self.scale >= fill.scale {
            return false;
        }
        let digit = self.a % B;
        self.a /= B;
        let (m, c) = digit_permutation::<B>(hash, self.reversed, self.scale);
        self.reversed = self.reversed * B + (m * digit + c) % B;
        self.scale *= B;
        true
    }
}

/// [`owen_radical_inverse`] of `a` for the `exact` of `fill`, bit for bit, without a
/// division ([`Scrambling`], [`Fill`]).
#[cfg(test)]
fn owen_radical_inverse_fast<const B: u64>(a: u64, hash: u64, fill: &Fill) -> f32 {
    let mut s = Scrambling::new(a);
    while s.step::<B>(hash, fill) {}
    fill.point(hash, s.reversed)
}

/// Owen-scrambled Halton points per pixel.
#[derive(Clone, Debug)]
pub struct HaltonSampler {
    cursor: PixelCursor,
    seed: u64,
    /// Per base (2, 3, 5, 7, 11): the fill below the scale down to which digits are
    /// scrambled one by one.
    fills: [Fill; 5],
}

impl HaltonSampler {
    /// `spp` samples in each pixel of `space`, scrambled from `seed`.
    pub fn new(space: RenderingSpace, spp: u32, seed: u64) -> Self {
        Self {
            cursor: PixelCursor::new(space, spp),
            seed,
            fills: {
                let n = u64::from(spp);
                [
                    Fill::new::<2>(scale_for(2, n)),
                    Fill::new::<3>(scale_for(3, n)),
                    Fill::new::<5>(scale_for(5, n)),
                    Fill::new::<7>(scale_for(7, n)),
                    Fill::new::<11>(scale_for(11, n)),
                ]
            },
        }
    }
}

impl PixelPattern for HaltonSampler {
    const NAME: &'static str = "halton";
    // Its scramble keeps as many exact digits as the sample count needs: index i's point
    // depends on spp, so a range of indices is not a slice of a longer render.
    const PROGRESSIVE: bool = false;

    fn cursor(&self) -> &PixelCursor {
        &self.cursor
    }

    fn cursor_mut(&mut self) -> &mut PixelCursor {
        &mut self.cursor
    }

    fn pixel(&self, p: [u32; 2], indices: std::ops::Range<u32>, out: &mut Vec<SamplePoint>) {
        let dims = self.cursor.space().dims;
        let key = pixel_key(p, self.seed, SALT);
        // One independent scramble per dim.
        let h: [u64; 5] = std::array::from_fn(|d| mix64(key ^ (d as u64 + 1)));
        let e = &self.fills;
        for index in indices {
            let mut s = [Scrambling::new(u64::from(index)); 5];
            // Each dim's digits are a chain of hashes, each on the digits above it; the dims'
            // chains are independent, so they advance a level at a time together, for the
            // processor to overlap them. Inactive dims compute nothing: a pinhole still scene
            // pays for x and y only.
            loop {
                let mut more = s[0].step::<2>(h[0], &e[0]);
                more |= s[1].step::<3>(h[1], &e[1]);
                if dims.time {
                    more |= s[2].step::<5>(h[2], &e[2]);
                }
                if dims.lens {
                    more |= s[3].step::<7>(h[3], &e[3]);
                    more |= s[4].step::<11>(h[4], &e[4]);
                }
                if !more {
                    break;
                }
            }
            let point = |d: usize| e[d].point(h[d], s[d].reversed);
            let film = [in_pixel(p[0], point(0)), in_pixel(p[1], point(1))];
            let time = if dims.time { point(2) } else { 0.5 };
            let lens = if dims.lens {
                [point(3), point(4)]
            } else {
                [0.5; 2]
            };
            out.push(SamplePoint {
                pixel: p,
                index,
                film,
                time,
                lens,
            });
        }
    }
}

/// The registry's entry.
pub(super) const ENTRY: Entry<SamplerBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Sampler,
        name: "halton",
        doc: "Owen-scrambled Halton points per pixel (pbrt-v3 halton, pbrt-v4 scrambling)",
        params: &[
            ParamSpec::new(
                "pixelsamples",
                ParamType::Integer,
                "16",
                super::PIXELSAMPLES,
            ),
            ParamSpec::new(
                "samplepixelcenter",
                ParamType::Bool,
                "false",
                "accepted for pbrt-v3 scenes; ignored",
            ),
        ],
    },
    build,
};

fn build(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn Sampler>> {
    let spp = super::pixel_samples(&c.params, setup)?;
    let _ = c.params.bool_or("samplepixelcenter", false)?;
    Ok(Box::new(HaltonSampler::new(setup.space, spp, setup.seed)))
}

#[cfg(test)]
mod tests {
    use super::super::tests::{batches, space, star_discrepancy, ALL_DIMS};
    use super::*;

    /// Counts of `vals` in `n` equal intervals of [0, 1).
    fn counts(vals: &[f64], n: u64) -> Vec<u64> {
        let mut c = vec![0; n as usize];
        for &v in vals {
            c[(v * n as f64).floor() as usize] += 1;
        }
        c
    }

    #[test]
    fn radical_inverse_balances_every_level() {
        // For i in 0..n the interval of width b^-m holding RI_b(i) is fixed by i mod b^m, so
        // each interval holds floor(n / b^m) or ceil(n / b^m) points, whatever the scramble.
        let check = |b: u64, vals: &[f64]| {
            let n = vals.len() as u64;
            let mut bm = b;
            while bm <= 4 * n {
                let (lo, hi) = (n / bm, n.div_ceil(bm));
                let c = counts(vals, bm);
                assert!(
                    c.iter().all(|&k| k == lo || k == hi),
                    "b {b} b^m {bm}: {c:?}"
                );
                bm *= b;
            }
        };
        for n in [16u64, 27, 100] {
            for hash in [0u64, 1, 0xdead_beef] {
                let ri = |b: u64, f: fn(u64, u64, u64) -> f32| -> Vec<f64> {
                    let e = scale_for(b, n);
                    (0..n).map(|a| f64::from(f(a, hash, e))).collect()
                };
                check(2, &ri(2, owen_radical_inverse::<2>));
                check(3, &ri(3, owen_radical_inverse::<3>));
                check(5, &ri(5, owen_radical_inverse::<5>));
                check(7, &ri(7, owen_radical_inverse::<7>));
                check(11, &ri(11, owen_radical_inverse::<11>));
            }
        }
        // Unscrambled digits would give the plain radical inverse; scrambled ones differ.
        assert_ne!(
            owen_radical_inverse::<2>(1, 5, 16),
            owen_radical_inverse::<2>(1, 6, 16)
        );
        // The fill below `exact` is spread: values of one index under many hashes are not
        // stuck on the level-`exact` grid.
        let off_grid = (0..64u64)
            .filter(|&h| (owen_radical_inverse::<3>(4, h, 9) * 9.0).fract() != 0.0)
            .count();
        assert!(off_grid > 60, "{off_grid}");
    }

    #[test]
    fn fast_radical_inverse_is_the_divisions_one() {
        fn check<const B: u64>() {
            for exact in [
                1,
                scale_for(B, 16),
                scale_for(B, 100),
                scale_for(B, 1 << 30),
            ] {
                let fill = Fill::new::<B>(exact);
                for a in (0..2000).chain([1 << 20, (1 << 32) - 1, u64::MAX / 3]) {
                    for hash in [0u64, 0xdead_beef, mix64(a)] {
                        let fast = owen_radical_inverse_fast::<B>(a, hash, &fill);
                        let slow = owen_radical_inverse::<B>(a, hash, exact);
                        assert_eq!(fast.to_bits(), slow.to_bits(), "b {B} a {a} e {exact}");
                    }
                }
            }
        }
        check::<2>();
        check::<3>();
        check::<5>();
        check::<7>();
        check::<11>();
    }

    #[test]
    fn fill_divides_without_dividing() {
        fn check<const B: u64>() {
            let top = top_scale(B);
            let inv = 1.0 / top as f64;
            // Every point the fill can give: the product rounds to the quotient's f32.
            for r in 0..top {
                let (q, p) = (r as f64 / top as f64, r as f64 * inv);
                assert_eq!((q as f32).to_bits(), (p as f32).to_bits(), "b {B} r {r}");
            }
            // The remainder of every rest (each power of B) for hashes all over 64 bits.
            let mut exact = 1;
            loop {
                let f = Fill::new::<B>(exact);
                for i in 0..20_000u64 {
                    for x in [mix64(i), i, u64::MAX - i, (f.rest * i).wrapping_sub(1)] {
                        assert_eq!(f.rem(x), x % f.rest, "b {B} rest {} x {x}", f.rest);
                    }
                }
                if f.rest == 1 {
                    break;
                }
                exact *= B;
            }
        }
        check::<2>();
        check::<3>();
        check::<5>();
        check::<7>();
        check::<11>();
    }

    #[test]
    fn spp_16_stratified_in_each_projection() {
        // 16 points per pixel: film x (base 2) holds one per 1/16; the other bases hold at
        // most one per interval of width b^-m with b^m >= 16 (1/27, 1/25, 1/49, 1/121) and
        // floor or ceil of 16 / b^m per interval below that (1/3, 1/9; 1/5; 1/7; 1/11).
        let sp = space(0, 0, 4, 4, ALL_DIMS[3]);
        let mut s = HaltonSampler::new(sp, 16, 21);
        let mut worst_16 = 0;
        let mut worst_d = [0.0f64; 5];
        for px in batches(&mut s).concat().chunks(16) {
            let dims: [(u64, Vec<f64>); 5] = [
                (
                    2,
                    px.iter()
                        .map(|q| f64::from(q.film[0]) - f64::from(q.pixel[0]))
                        .collect(),
                ),
                (
                    3,
                    px.iter()
                        .map(|q| f64::from(q.film[1]) - f64::from(q.pixel[1]))
                        .collect(),
                ),
                (5, px.iter().map(|q| f64::from(q.time)).collect()),
                (7, px.iter().map(|q| f64::from(q.lens[0])).collect()),
                (11, px.iter().map(|q| f64::from(q.lens[1])).collect()),
            ];
            for (di, (b, v)) in dims.iter().enumerate() {
                let mut bm = *b;
                loop {
                    let c = counts(v, bm);
                    let (lo, hi) = (16 / bm, 16u64.div_ceil(bm));
                    assert!(c.iter().all(|&k| k == lo || k == hi), "b {b}: {c:?}");
                    if bm >= 16 {
                        break;
                    }
                    bm *= b;
                }
                worst_16 = worst_16.max(*counts(v, 16).iter().max().unwrap());
                // Bound: [0, x) splits into at most b - 1 whole intervals per level j = 1..M
                // (b^M >= n), each off its share n / b^j by < 1 and by 0 where b^j divides n,
                // plus a part of one level-M interval, off by <= 1. So n D* <= 1 + that sum.
                let (mut bj, mut off) = (1u64, 1.0);
                while bj < 16 {
                    bj *= b;
                    if 16 % bj != 0 {
                        off += (b - 1) as f64;
                    }
                }
                let d = star_discrepancy(v);
                assert!(d <= off / 16.0 + 1e-9, "b {b}: D* {d} > {}", off / 16.0);
                worst_d[di] = worst_d[di].max(d);
            }
            assert_eq!(counts(&dims[0].1, 16), vec![1; 16]);
        }
        eprintln!("halton spp 16: most points in one 1/16 interval of any dim: {worst_16}");
        eprintln!("halton spp 16: worst star discrepancy per dim (x y t u v): {worst_d:.4?}");
    }
}
