//! Standard normal deviates for mlt's small steps: Marsaglia and Tsang's ziggurat (128
//! layers), an exact sampler of the Gaussian that mostly costs one 32-bit draw, a table
//! look-up and an integer compare (docs/light-transport.md, `## mlt`). pbrt-v3 inverts
//! `erf` with a logarithm and a polynomial for each deviate, which was the sampler's main cost.

use crate::stream::Pcg32;
use std::sync::LazyLock;

/// Layers of the ziggurat (a power of two: the layer is the draw's low bits).
const LAYERS: usize = 128;
/// The start of the tail (the base layer's right edge), for 128 layers of equal area.
const R: f64 = 3.442_619_855_899;
/// Each layer's area under the unnormalised density exp(-x^2 / 2).
const V: f64 = 9.912_563_035_262_17e-3;
/// 2^24: a draw's odd 25-bit numerator over it is a uniform in (-1, 1), symmetric about 0.
const SCALE: f64 = (1u32 << 24) as f64;

/// The ziggurat's tables (built once, [`Ziggurat::get`]).
#[derive(Debug)]
pub struct Ziggurat {
    /// Layer i's fast acceptance bound: |numerator| below it lies under the curve
    /// (2^24 x[i + 1] / x[i]).
    k: [u32; LAYERS],
    /// Layer i's width over 2^24 (a numerator times it is the deviate).
    w: [f32; LAYERS],
    /// The unnormalised density at the layers' edges x[0] .. x[128] (x[128] = 0).
    f: [f32; LAYERS + 1],
}

/// The unnormalised standard normal density.
fn density(x: f64) -> f64 {
    (-0.5 * x * x).exp()
}

static TABLES: LazyLock<Ziggurat> = LazyLock::new(Ziggurat::build);

impl Ziggurat {
    /// The shared tables.
    pub fn get() -> &'static Self {
        &TABLES
    }

    /// The layers' edges x[0] (the base layer's pseudo-width V / f(R)) > x[1] = R > ... >
    /// x[128] = 0, each layer of area V.
    fn build() -> Self {
        let mut x = [0.0f64; LAYERS + 1];
        x[0] = V / density(R);
        x[1] = R;
        for i in 1..LAYERS - 1 {
            x[i + 1] = (-2.0 * (V / x[i] + density(x[i])).ln()).sqrt();
        }
        x[LAYERS] = 0.0;
        let mut z = Self {
            k: [0; LAYERS],
            w: [0.0; LAYERS],
            f: [0.0; LAYERS + 1],
        };
        for i in 0..LAYERS {
            z.k[i] = (SCALE * x[i + 1] / x[i]) as u32;
            z.w[i] = (x[i] / SCALE) as f32;
        }
        for (f, &x) in z.f.iter_mut().zip(&x) {
            *f = density(x) as f32;
        }
        z
    }

    /// One standard normal deviate from `rng`.
    #[inline]
    pub fn sample(&self, rng: &mut Pcg32) -> f32 {
        let bits = rng.next_u32();
        match self.in_box(bits) {
            Some(x) => x,
            None => self.finish(bits, rng),
        }
    }

    /// The deviate of the generator's draw `bits` when it falls in its layer's box (the
    /// common case: a table look-up and a compare), else `None` ([`Ziggurat::finish`]).
    #[inline(always)]
    pub fn in_box(&self, bits: u32) -> Option<f32> {
        let i = bits as usize & (LAYERS - 1);
        // Bits 8..31 as a signed number j; 2j + 1 is odd, in (-2^24, 2^24), exact in f32.
        let m = ((bits as i32) >> 8) * 2 + 1;
        (m.unsigned_abs() < self.k[i]).then(|| m as f32 * self.w[i])
    }

    /// The deviate of a draw `bits` outside its layer's box: the tail or the wedge, drawing
    /// more from `rng` as needed.
    #[inline(never)]
    pub fn finish(&self, mut bits: u32, rng: &mut Pcg32) -> f32 {
        loop {
            let i = bits as usize & (LAYERS - 1);
            let m = ((bits as i32) >> 8) * 2 + 1;
            let x = m as f32 * self.w[i];
            if m.unsigned_abs() < self.k[i] {
                return x;
            }
            if i == 0 {
                return Self::tail(rng, m < 0);
            }
            // The wedge between the layer's inner edge and the curve.
            let y = self.f[i] + rng.next_f32() * (self.f[i + 1] - self.f[i]);
            if y < (-0.5 * x * x).exp() {
                return x;
            }
            bits = rng.next_u32();
        }
    }

    /// A deviate beyond R (Marsaglia's tail method), negative when asked.
    #[cold]
    fn tail(rng: &mut Pcg32, negative: bool) -> f32 {
        let r = R as f32;
        loop {
            // 1 - u is in (0, 1]: its logarithm is finite.
            let x = -(1.0 - rng.next_f32()).ln() / r;
            let y = -(1.0 - rng.next_f32()).ln();
            if 2.0 * y >= x * x {
                return if negative { -(r + x) } else { r + x };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The standard normal CDF by Simpson's rule over the density (f64, fine steps).
    fn phi(x: f64) -> f64 {
        let n = 20_000;
        let h = x.abs() / n as f64;
        let mut s = density(0.0) + density(x.abs());
        for k in 1..n {
            s += density(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
        }
        let half = s * h / 3.0 / (2.0 * std::f64::consts::PI).sqrt();
        if x >= 0.0 {
            0.5 + half
        } else {
            0.5 - half
        }
    }

    #[test]
    fn the_layers_close_at_the_peak() {
        // The last layer's top, f(x[127]) + V / x[127], must come out at the density's peak,
        // else the recurrence (or R and V) is wrong.
        let z = Ziggurat::get();
        let x127 = f64::from(z.w[LAYERS - 1]) * SCALE;
        let top = density(x127) + V / x127;
        assert!((top - 1.0).abs() < 1e-6, "{top}");
        assert_eq!(z.f[LAYERS], 1.0);
    }

    /// The deviates' histogram over 80 bins of [-4, 4] and the two tails beyond agree with
    /// the normal distribution (chi-square), and their mean and variance are 0 and 1.
    #[test]
    fn deviates_are_standard_normal() {
        let z = Ziggurat::get();
        let mut rng = Pcg32::new(12345, 678);
        let n = 4_000_000usize;
        let bins = 80usize;
        let mut counts = vec![0u64; bins + 2];
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let x = z.sample(&mut rng);
            assert!(x.is_finite());
            let xf = f64::from(x);
            sum += xf;
            sum2 += xf * xf;
            let b = if xf < -4.0 {
                0
            } else if xf >= 4.0 {
                bins + 1
            } else {
                1 + (((xf + 4.0) / 8.0 * bins as f64) as usize).min(bins - 1)
            };
            counts[b] += 1;
        }
        let mean = sum / n as f64;
        let var = sum2 / n as f64 - mean * mean;
        assert!(mean.abs() < 2e-3, "mean {mean}");
        assert!((var - 1.0).abs() < 4e-3, "variance {var}");
        let edge = |b: usize| -4.0 + 8.0 * b as f64 / bins as f64;
        let mut chi2 = 0.0;
        for (b, &c) in counts.iter().enumerate() {
            let p = match b {
                0 => phi(-4.0),
                _ if b == bins + 1 => phi(-4.0),
                _ => phi(edge(b)) - phi(edge(b - 1)),
            };
            let expected = p * n as f64;
            chi2 += (c as f64 - expected).powi(2) / expected;
        }
        // 81 degrees of freedom: 140 is beyond the 0.9999 quantile.
        assert!(chi2 < 140.0, "chi-square {chi2}");
    }

    #[test]
    fn the_same_generator_gives_the_same_deviates() {
        let z = Ziggurat::get();
        let (mut a, mut b) = (Pcg32::new(9, 1), Pcg32::new(9, 1));
        for _ in 0..1000 {
            assert_eq!(z.sample(&mut a).to_bits(), z.sample(&mut b).to_bits());
        }
    }
}
