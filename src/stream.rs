//! The per-sample random stream the integrator draws its decisions from (light choice, BSDF
//! lobes, bounce directions, Russian roulette). It depends only on (pixel, sample index, seed),
//! so an image does not depend on the thread count or the order samples are traced in.
//!
//! Dimensions below [`sobol_burley::NUM_DIMENSIONS`] come from an Owen-scrambled Sobol sequence
//! indexed by the sample's index within its pixel (as pbrt-v4's padded Sobol sampler), so the
//! samples of one pixel are stratified in every dimension; later dimensions from a PCG stream.

use sobol_burley::parts::{hash, hash_int4, owen_scramble_int4_rev, owen_scramble_rev, Int4};

pub use acr_plugins::rng::{mix64, Pcg32};

/// Samples per pixel that the Sobol sequence covers (sobol_burley's limit).
const SOBOL_SAMPLES: u32 = 1 << 16;

/// Dimension sets (of four dimensions) served from [`SobolTables`]; later sets (past the
/// 64th dimension) are computed by `sobol_burley::sample_4d` directly.
const TABLE_SETS: u32 = 16;

/// The unscrambled Sobol points of the first [`TABLE_SETS`] dimension sets, by nibble of the
/// (16-bit) index: a point is the XOR of the direction vectors of its index's bits, so the
/// XOR of four nibble entries equals sobol_burley's loop over up to 16 bits, bit for bit.
#[derive(Debug)]
struct SobolTables(Vec<[[Int4; 16]; 4]>);

impl SobolTables {
    fn get() -> &'static Self {
        static TABLES: std::sync::OnceLock<SobolTables> = std::sync::OnceLock::new();
        TABLES.get_or_init(|| {
            Self(
                (0..TABLE_SETS)
                    .map(|set| {
                        std::array::from_fn(|nibble| {
                            std::array::from_fn(|v| {
                                // The index's top 16 bits, most significant nibble first.
                                let bits = (v as u32) << (28 - 4 * nibble);
                                sobol_burley::parts::sobol_int4_rev(bits, set)
                            })
                        })
                    })
                    .collect(),
            )
        })
    }

    /// `sobol_burley::sample_4d(index, set, seed)` for a set below [`TABLE_SETS`], given
    /// `shuffled` (the index as it scrambles it, see [`shuffled_index`]).
    #[inline]
    fn sample_4d(&self, shuffled: u32, set: u32, seed: u32) -> [f32; 4] {
        let t = &self.0[set as usize];
        let nib = |k: usize| ((shuffled >> (28 - 4 * k)) & 0xf) as usize;
        let sobol = t[0][nib(0)] ^ t[1][nib(1)] ^ t[2][nib(2)] ^ t[3][nib(3)];
        // As sobol_burley::sample_4d from here on.
        let scramble = {
            let seed: Int4 = [seed.wrapping_mul(0x9c8f2d3b); 4].into();
            let ds: Int4 = [set; 4].into();
            seed ^ ds ^ [0x912f69ba, 0x174f18ab, 0x691e72ca, 0xb40cc1b8].into()
        };
        owen_scramble_int4_rev(sobol, hash_int4(scramble))
            .reverse_bits()
            .to_f32_norm()
    }
}

/// The sample index as sobol_burley's `sample_4d` scrambles it for `seed` (the same for every
/// dimension set).
#[inline]
fn shuffled_index(index: u32, seed: u32) -> u32 {
    owen_scramble_rev(index.reverse_bits(), hash(seed ^ 0x79c68e4a))
}

/// The random numbers of one sample.
#[derive(Clone, Debug)]
pub struct SampleStream {
    index: u32,
    scramble: u32,
    dim: u32,
    /// The four Sobol dimensions of the set `dim / 4`, computed together (SIMD) on first use:
    /// the same values `sobol_burley::sample` gives one at a time, at about a quarter the cost.
    block: [f32; 4],
    /// The set `block` holds, or `u32::MAX` for none.
    block_set: u32,
    /// The sample index as the Sobol scrambling shuffles it ([`shuffled_index`]).
    shuffled: u32,
    tables: &'static SobolTables,
    rng: Pcg32,
}

impl SampleStream {
    /// The stream of sample `index` of pixel `pixel` under `seed`. `first_dim` skips the
    /// dimensions the sampler already used for the rendering space (film, time, lens).
    pub fn new(pixel: u64, index: u32, seed: u64, first_dim: u32) -> Self {
        let key = mix64(pixel ^ mix64(seed.wrapping_add(0x9e37_79b9_7f4a_7c15)));
        Self {
            index,
            scramble: key as u32,
            dim: first_dim,
            block: [0.0; 4],
            block_set: u32::MAX,
            shuffled: shuffled_index(index, key as u32),
            tables: SobolTables::get(),
            // The index is hashed into the seed: PCG streams whose seeds and increments differ
            // by small steps start out correlated.
            rng: Pcg32::new(
                mix64(key ^ mix64(u64::from(index))),
                mix64(key).wrapping_add(u64::from(index)),
            ),
        }
    }

    /// The next value in [0, 1).
    // Always inlined: called a few dozen times per sample, and the call cost rivals the work.
    #[inline(always)]
    pub fn next_1d(&mut self) -> f32 {
        let d = self.dim;
        self.dim += 1;
        // sobol_burley's sequences hold 2^16 samples: a pixel's later samples are random.
        if d < sobol_burley::NUM_DIMENSIONS && self.index < SOBOL_SAMPLES {
            let set = d / 4;
            if set != self.block_set {
                self.block = if set < TABLE_SETS {
                    self.tables.sample_4d(self.shuffled, set, self.scramble)
                } else {
                    sobol_burley::sample_4d(self.index, set, self.scramble)
                };
                self.block_set = set;
            }
            self.block[(d % 4) as usize]
        } else {
            self.rng.next_f32()
        }
    }

    /// The next pair of values in [0, 1)^2.
    #[inline(always)]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        glam::Vec2::new(self.next_1d(), self.next_1d())
    }
}

/// Where an estimator draws its random decisions: a pixel sample's [`SampleStream`], or a
/// sampler that drives its own (mlt's primary sample space). Estimators shared by both (bdpt's
/// subpaths) are generic over it.
pub trait SampleSource {
    /// The next value in [0, 1).
    fn next_1d(&mut self) -> f32;
    /// The next pair of values in [0, 1)^2.
    fn next_2d(&mut self) -> glam::Vec2 {
        let u = self.next_1d();
        glam::Vec2::new(u, self.next_1d())
    }
}

impl SampleSource for SampleStream {
    #[inline(always)]
    fn next_1d(&mut self) -> f32 {
        SampleStream::next_1d(self)
    }

    #[inline(always)]
    fn next_2d(&mut self) -> glam::Vec2 {
        SampleStream::next_2d(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_inputs_same_stream_and_values_in_range() {
        let mut a = SampleStream::new(17, 3, 42, 5);
        let mut b = SampleStream::new(17, 3, 42, 5);
        for _ in 0..400 {
            let x = a.next_1d();
            assert_eq!(x, b.next_1d());
            assert!((0.0..1.0).contains(&x));
        }
        // The same values as one dimension at a time.
        let mut d = SampleStream::new(17, 3, 42, 5);
        for dim in 5..(4 * TABLE_SETS + 40) {
            assert_eq!(d.next_1d(), sobol_burley::sample(3, dim, d.scramble));
        }
        // The tables give sobol_burley's values, whatever the index and seed.
        let tables = SobolTables::get();
        for (index, seed) in [(0, 0), (1, 7), (5, 0xdead_beef), (65_535, 3), (40_000, 99)] {
            for set in 0..TABLE_SETS {
                assert_eq!(
                    tables.sample_4d(shuffled_index(index, seed), set, seed),
                    sobol_burley::sample_4d(index, set, seed)
                );
            }
        }
        // Past the Sobol sequence's 2^16 samples, values are still in range.
        let mut late = SampleStream::new(17, 1 << 17, 42, 0);
        assert!((0..300).all(|_| (0.0..1.0).contains(&late.next_1d())));
        let mut c = SampleStream::new(18, 3, 42, 5);
        assert_ne!(SampleStream::new(17, 3, 42, 5).next_1d(), c.next_1d());
    }

    #[test]
    fn samples_of_one_pixel_are_stratified() {
        // 16 samples of one pixel in one dimension: one per stratum of width 1/16.
        let mut strata = [0; 16];
        for i in 0..16 {
            let mut s = SampleStream::new(7, i, 1, 9);
            strata[(s.next_1d() * 16.0) as usize] += 1;
        }
        assert_eq!(strata, [1; 16]);
    }
}
