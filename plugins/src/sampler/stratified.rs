//! `stratified`: pbrt-v3's StratifiedSampler. The film offset takes one sample in each of
//! xsamples x ysamples strata (jittered, or at the stratum centre with jitter off); time takes
//! one in each of spp 1D strata and the lens one in each of xsamples x ysamples 2D strata.
//! Each dim's strata are permuted separately, from the seed and pixel, so that sample i's
//! film stratum says nothing of its time or lens stratum (pbrt-v3 shuffles for the same reason).
//! The permutation is evaluated per sample (pbrt-v4's PermutationElement), not stored, so a
//! pass of a few samples costs a few samples' work however many strata the pixel has.

use super::{mix64, pixel_key, PixelCursor, PixelPattern, Sampler};
use super::{SamplerBuild, SamplerSetup};
use crate::registry::{Choice, Entry, Kind, ParamSpec, PluginInfo};
use crate::space::{in_stratum, RenderingSpace, SamplePoint};
use acr_parser::{ParamType, Result};

/// Salt of this sampler's per-pixel keys.
const SALT: u64 = 0x7374_7261;

/// Jittered stratified points over the active dims.
#[derive(Clone, Debug)]
pub struct StratifiedSampler {
    cursor: PixelCursor,
    xsamples: u32,
    ysamples: u32,
    jitter: bool,
    seed: u64,
}

/// Element `i` of a pseudo-random permutation of `0..l` chosen by `p` (Kensler's hashed
/// permutation, as pbrt-v4's PermutationElement): a bijection of `0..l`, in O(1) expected time.
pub(crate) fn permutation_element(mut i: u32, l: u32, p: u32) -> u32 {
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < l {
            break;
        }
    }
    if l.is_power_of_two() {
        // The sum's low bits: the remainder below, without a 64-bit division.
        return i.wrapping_add(p) & (l - 1);
    }
    ((u64::from(i) + u64::from(p)) % u64::from(l)) as u32
}

/// `(k % n, k / n)` for n >= 1, by a mask and a shift where n is a power of two (the common
/// strata counts), else by division: the same values either way.
#[inline]
fn split(k: u32, n: u32) -> (u32, u32) {
    if n.is_power_of_two() {
        (k & (n - 1), k >> n.trailing_zeros())
    } else {
        (k % n, k / n)
    }
}

/// `x / n` for n >= 1, bit for bit: a product where n is a power of two (its reciprocal is
/// exact and the product of x >= 2^-24 by it is far above the subnormals), else a division.
#[inline]
fn div(x: f64, n: u32) -> f64 {
    if n.is_power_of_two() {
        x * f64::from_bits((1023 - u64::from(n.trailing_zeros())) << 52)
    } else {
        x / f64::from(n)
    }
}

/// A uniform value in [0, 1) from a 64-bit hash (24 bits, so it never rounds to 1).
#[inline]
fn unit(h: u64) -> f32 {
    (h >> 40) as f32 * (1.0 / (1u32 << 24) as f32)
}

impl StratifiedSampler {
    /// `xsamples` x `ysamples` samples in each pixel of `space` (each at least 1), jittered
    /// inside their strata when `jitter`, drawn from `seed`.
    pub fn new(
        space: RenderingSpace,
        xsamples: u32,
        ysamples: u32,
        jitter: bool,
        seed: u64,
    ) -> Self {
        let (xsamples, ysamples) = (xsamples.max(1), ysamples.max(1));
        Self {
            cursor: PixelCursor::new(space, xsamples * ysamples),
            xsamples,
            ysamples,
            jitter,
            seed,
        }
    }
}

impl PixelPattern for StratifiedSampler {
    const NAME: &'static str = "stratified";
    const PROGRESSIVE: bool = false;

    fn cursor(&self) -> &PixelCursor {
        &self.cursor
    }

    fn cursor_mut(&mut self) -> &mut PixelCursor {
        &mut self.cursor
    }

    fn pixel(&self, p: [u32; 2], indices: std::ops::Range<u32>, out: &mut Vec<SamplePoint>) {
        let dims = self.cursor.space().dims;
        let (nx, ny, jitter) = (self.xsamples, self.ysamples, self.jitter);
        let spp = nx * ny;
        let key = pixel_key(p, self.seed, SALT);
        // One permutation and one jitter stream per dim group: film, time, lens.
        let perm: [u32; 3] = std::array::from_fn(|d| mix64(key ^ (d as u64 + 1)) as u32);
        // The stratum of sample `index` in group `d` and its jitter within it.
        let cell = |index: u32, d: usize| -> (u32, [f32; 2]) {
            let k = permutation_element(index, spp, perm[d]);
            let j = if jitter {
                let h = mix64(key ^ mix64((u64::from(index) << 2) | d as u64));
                [unit(h), unit(mix64(h))]
            } else {
                [0.5; 2]
            };
            (k, j)
        };
        // Position `j` within stratum `k` of `n`, as an f32 kept inside that stratum.
        let at = |base: u32, k: u32, n: u32, j: f32| {
            in_stratum(base, k, n, div(f64::from(k) + f64::from(j), n))
        };
        for index in indices {
            let (k, j) = cell(index, 0);
            let (kx, ky) = split(k, nx);
            let film = [at(p[0], kx, nx, j[0]), at(p[1], ky, ny, j[1])];
            // Inactive dims draw nothing: a pinhole still scene pays for x and y only.
            let time = if dims.time {
                let (k, j) = cell(index, 1);
                at(0, k, spp, j[0])
            } else {
                0.5
            };
            let lens = if dims.lens {
                let (k, j) = cell(index, 2);
                let (kx, ky) = split(k, nx);
                [at(0, kx, nx, j[0]), at(0, ky, ny, j[1])]
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
        name: "stratified",
        doc: "jittered strata per pixel: xsamples x ysamples (pbrt-v3 stratified)",
        params: &[
            ParamSpec::new("xsamples", ParamType::Integer, "4", "strata across a pixel"),
            ParamSpec::new("ysamples", ParamType::Integer, "4", "strata down a pixel"),
            ParamSpec::new(
                "jitter",
                ParamType::Bool,
                "true",
                "jitter inside each stratum (false: its centre)",
            ),
            ParamSpec::new(
                "dimensions",
                ParamType::Integer,
                "4",
                "accepted for pbrt-v3 scenes; acr's per-sample streams have no dimension limit",
            ),
        ],
    },
    build,
};

fn build(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn Sampler>> {
    let xs = super::check_count(
        &c.params,
        "xsamples",
        i64::from(c.params.int_or("xsamples", 4)?),
    )?;
    let ys = super::check_count(
        &c.params,
        "ysamples",
        i64::from(c.params.int_or("ysamples", 4)?),
    )?;
    let jitter = c.params.bool_or("jitter", true)?;
    let _ = c.params.int_or("dimensions", 4)?;
    // --spp N: the most nearly square grid of N strata (pbrt-v4's rule).
    let (xs, ys) = match setup.spp {
        Some(n) => square_grid(n),
        None => (xs, ys),
    };
    if u64::from(xs) * u64::from(ys) > u64::from(super::MAX_SPP) {
        let message = format!(
            "xsamples x ysamples = {} is over {}",
            u64::from(xs) * u64::from(ys),
            super::MAX_SPP
        );
        return Err(crate::registry::error_at_param(
            &c.params,
            &["xsamples"],
            "--spp",
            message,
        ));
    }
    Ok(Box::new(StratifiedSampler::new(
        setup.space,
        xs,
        ys,
        jitter,
        setup.seed,
    )))
}

/// The `xs` x `ys` grid of `n` strata closest to square (xs <= ys).
pub fn square_grid(n: u32) -> (u32, u32) {
    let n = n.max(1);
    let mut xs = (f64::from(n).sqrt()) as u32;
    while n % xs != 0 {
        xs -= 1;
    }
    (xs, n / xs)
}

#[cfg(test)]
mod permutation_tests {
    use super::{div, permutation_element, split};

    #[test]
    fn power_of_two_shortcuts_match_the_divisions() {
        for n in (0..31).map(|e| 1u32 << e).chain([3, 5, 6, 7, 12, 100]) {
            for k in [
                0u32,
                1,
                2,
                3,
                5,
                15,
                16,
                17,
                255,
                1 << 20,
                u32::MAX - 1,
                u32::MAX,
            ] {
                assert_eq!(split(k, n), (k % n, k / n), "k {k} n {n}");
                for j in [0.0f32, 1.0 / (1 << 24) as f32, 0.3, 0.999_999_94] {
                    let x = f64::from(k) + f64::from(j);
                    assert_eq!(
                        div(x, n).to_bits(),
                        (x / f64::from(n)).to_bits(),
                        "{x} / {n}"
                    );
                }
            }
            if !n.is_power_of_two() {
                continue;
            }
            for (i, p) in [(0u32, 0u32), (3, u32::MAX), (7, 0xdead_beef), (1, 1 << 31)] {
                let i = i % n;
                let general = ((u64::from(i) + u64::from(p)) % u64::from(n)) as u32;
                assert_eq!(i.wrapping_add(p) & (n - 1), general);
            }
        }
    }

    #[test]
    fn permutation_element_is_a_bijection() {
        for l in [1u32, 2, 3, 16, 17, 100, 1024] {
            for p in [0u32, 1, 0xdead_beef, 12345] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let k = permutation_element(i, l, p);
                    assert!(k < l && !seen[k as usize], "l {l} p {p} i {i}");
                    seen[k as usize] = true;
                }
            }
        }
        // Different keys, different orders.
        let a: Vec<u32> = (0..16).map(|i| permutation_element(i, 16, 1)).collect();
        let b: Vec<u32> = (0..16).map(|i| permutation_element(i, 16, 2)).collect();
        assert_ne!(a, b);
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{batches, space, ALL_DIMS};
    use super::*;

    /// The stratum of `v` in [0, 1) among `n`, computed exactly.
    fn stratum(v: f64, n: u32) -> usize {
        (v * f64::from(n)).floor() as usize
    }

    #[test]
    fn one_point_per_stratum_in_every_pixel() {
        for jitter in [true, false] {
            for (xs, ys) in [(4, 4), (3, 5), (1, 1), (7, 2)] {
                let spp = (xs * ys) as usize;
                // A far-off origin too, where px + offset rounds.
                for (x0, y0) in [(0, 0), (16380, 4090)] {
                    let sp = space(x0, y0, 5, 4, ALL_DIMS[3]);
                    let mut s = StratifiedSampler::new(sp, xs, ys, jitter, 11);
                    assert_eq!(s.spp() as usize, spp);
                    for px in batches(&mut s).concat().chunks(spp) {
                        let (mut film, mut time, mut lens) =
                            (vec![0; spp], vec![0; spp], vec![0; spp]);
                        for q in px {
                            let fx = f64::from(q.film[0]) - f64::from(q.pixel[0]);
                            let fy = f64::from(q.film[1]) - f64::from(q.pixel[1]);
                            film[stratum(fy, ys) * xs as usize + stratum(fx, xs)] += 1;
                            time[stratum(f64::from(q.time), xs * ys)] += 1;
                            let (u, v) = (f64::from(q.lens[0]), f64::from(q.lens[1]));
                            lens[stratum(v, ys) * xs as usize + stratum(u, xs)] += 1;
                        }
                        assert_eq!(film, vec![1; spp], "{xs}x{ys} jitter {jitter} film");
                        assert_eq!(time, vec![1; spp], "{xs}x{ys} jitter {jitter} time");
                        assert_eq!(lens, vec![1; spp], "{xs}x{ys} jitter {jitter} lens");
                    }
                }
            }
        }
    }

    #[test]
    fn no_jitter_means_stratum_centres() {
        let sp = space(0, 0, 2, 2, ALL_DIMS[1]);
        let mut s = StratifiedSampler::new(sp, 2, 2, false, 3);
        for q in batches(&mut s).concat() {
            for a in 0..2 {
                let f = q.film[a] - q.pixel[a] as f32;
                assert!(f == 0.25 || f == 0.75, "{f}");
            }
            assert!([0.125, 0.375, 0.625, 0.875].contains(&q.time));
        }
    }

    #[test]
    fn dims_are_shuffled_apart() {
        // Were the strata not shuffled separately, sample i's time stratum would follow its
        // film stratum. Over 256 pixels of 4x4 samples, count how often the film stratum
        // index equals the time stratum: 1/16 of the samples by chance (256 expected).
        let sp = space(0, 0, 16, 16, ALL_DIMS[3]);
        let mut s = StratifiedSampler::new(sp, 4, 4, true, 9);
        let pts = batches(&mut s).concat();
        let same = pts
            .iter()
            .filter(|q| {
                let fx = stratum(f64::from(q.film[0] - q.pixel[0] as f32), 4);
                let fy = stratum(f64::from(q.film[1] - q.pixel[1] as f32), 4);
                fy * 4 + fx == stratum(f64::from(q.time), 16)
            })
            .count();
        // Binomial(4096, 1/16): mean 256, sd 15.5; 6 sd either side.
        assert!((163..=349).contains(&same), "{same}");
        eprintln!("stratified film/time same-stratum count: {same} of 4096 (256 expected)");
    }
}
