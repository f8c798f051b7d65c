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

/// Owen-scrambled radical inverse of `a` in base `B`, digits scrambled one by one down to
/// `exact` (a power of B above every index used, from [`scale_for`]). Each digit goes through
/// a random affine permutation `d -> (m d + c) mod B` chosen by a hash of `hash` and the digits
/// above it (nested, as Owen's scrambling), so every digit is uniform and the strata of all
/// levels down to `exact` are kept. Below `exact` Owen's scrambled zero digits are uniform and
/// independent per prefix, so one hash of the prefix draws them all at once (the cost is then
/// log_B(spp) hashes, not 24). The result is a multiple of 1 / top_scale(B), a step wider than
/// half an f32 ulp below 1 (top_scale < 2^25), so rounding to f32 never crosses an interval edge.
#[inline]
pub(crate) fn owen_radical_inverse<const B: u64>(mut a: u64, hash: u64, exact: u64) -> f32 {
    let top = top_scale(B);
    let mut reversed: u64 = 0;
    let mut scale: u64 = 1;
    while scale < exact && scale < top {
        let digit = a % B;
        a /= B;
        let h = mix64(hash ^ reversed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ scale);
        // B is prime, so any multiplier in 1..B is a bijection; the shift makes d uniform.
        let m = 1 + h % (B - 1);
        let c = (h >> 32) % B;
        reversed = reversed * B + (m * digit + c) % B;
        scale *= B;
    }
    let rest = top / scale;
    let fill = mix64(hash ^ reversed.wrapping_mul(0xd6e8_feb8_6659_fd93) ^ scale) % rest;
    let r = reversed * rest + fill;
    ((r as f64 / top as f64) as f32).min(ONE_MINUS_EPSILON)
}

/// Owen-scrambled Halton points per pixel.
#[derive(Clone, Debug)]
pub struct HaltonSampler {
    cursor: PixelCursor,
    seed: u64,
    /// Per base (2, 3, 5, 7, 11): the scale down to which digits are scrambled one by one.
    exact: [u64; 5],
}

impl HaltonSampler {
    /// `spp` samples in each pixel of `space`, scrambled from `seed`.
    pub fn new(space: RenderingSpace, spp: u32, seed: u64) -> Self {
        Self {
            cursor: PixelCursor::new(space, spp),
            seed,
            exact: [2, 3, 5, 7, 11].map(|b| scale_for(b, u64::from(spp))),
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
        let e = self.exact;
        for index in indices {
            let a = u64::from(index);
            let film = [
                in_pixel(p[0], owen_radical_inverse::<2>(a, h[0], e[0])),
                in_pixel(p[1], owen_radical_inverse::<3>(a, h[1], e[1])),
            ];
            // Inactive dims compute nothing: a pinhole still scene pays for x and y only.
            let time = if dims.time {
                owen_radical_inverse::<5>(a, h[2], e[2])
            } else {
                0.5
            };
            let lens = if dims.lens {
                [
                    owen_radical_inverse::<7>(a, h[3], e[3]),
                    owen_radical_inverse::<11>(a, h[4], e[4]),
                ]
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
