//! `sobol`: Owen-scrambled Sobol points per pixel (as pbrt-v4's padded Sobol sampler), through
//! `sobol_burley`: dims 0, 1 the film offset, 2 time, 3, 4 the lens, scrambled from a hash of
//! (pixel, seed). The first 2^k points of a pixel form a (0, k, 1)-net in each dim, so spp = 16
//! puts one point in each 1/16 of every 1D projection.

use super::IndexStream;
use super::{pixel_key, Pcg32, PixelCursor, PixelPattern, Sampler};
use super::{SamplerBuild, SamplerSetup};
use crate::registry::{Choice, Entry, Kind, ParamSpec, PluginInfo};
use crate::space::{in_pixel, RenderingSpace, SamplePoint};
use acr_parser::{ParamType, Result};
use sobol_burley::parts;

/// Salt of this sampler's per-pixel keys.
const SALT: u64 = 0x736f_626c;

/// Samples per pixel that the Sobol sequence covers (sobol_burley's limit); later samples of a
/// pixel come from a hashed random stream.
pub const SOBOL_SAMPLES: u32 = 1 << 16;

/// The integrator's per-sample stream must start past these Sobol dims, or its first
/// dimensions would repeat the sampler's.
pub const SOBOL_DIMS_USED: u32 = 5;

/// Owen-scrambled Sobol points per pixel.
#[derive(Clone, Debug)]
pub struct SobolSampler {
    cursor: PixelCursor,
    seed: u64,
    stream: IndexStream,
}

impl SobolSampler {
    /// `spp` samples in each pixel of `space`, scrambled from `seed`.
    pub fn new(space: RenderingSpace, spp: u32, seed: u64) -> Self {
        Self {
            cursor: PixelCursor::new(space, spp),
            seed,
            stream: IndexStream::ALL,
        }
    }

    /// The same sampler labelling its samples with stream `stream`'s indices: a pixel's points
    /// are still its sequence's first ones (the even points alone of a Sobol sequence would
    /// all lie in one half of the pixel), and only the index that keys the integrator's stream
    /// and tells the film the stream changes.
    pub fn with_stream(mut self, stream: IndexStream) -> Self {
        self.stream = stream;
        self
    }
}

impl PixelPattern for SobolSampler {
    const NAME: &'static str = "sobol";
    const PROGRESSIVE: bool = true;

    fn cursor(&self) -> &PixelCursor {
        &self.cursor
    }

    fn cursor_mut(&mut self) -> &mut PixelCursor {
        &mut self.cursor
    }

    fn pixel(&self, p: [u32; 2], indices: std::ops::Range<u32>, out: &mut Vec<SamplePoint>) {
        let scramble = Scramble::of(p, self.seed);
        let stream = self.stream;
        out.extend(indices.map(|i| SamplePoint {
            index: stream.index(i),
            ..self.point(p, i, scramble)
        }));
    }
}

/// The per-pixel key and Sobol scrambles of one pixel, computed once for its points.
#[derive(Clone, Copy, Debug)]
pub struct Scramble {
    key: u64,
    /// The hashed seed that shuffles the pixel's sample indices.
    shuffle: u32,
    /// The hashed seed of each dim's Owen scramble.
    dims: [u32; MAX_SOBOL_DIMS],
}

/// The Sobol dims a point takes: film x, y, time, lens u, v.
const MAX_SOBOL_DIMS: usize = 5;

impl Scramble {
    /// The scramble of pixel `p` under `seed`.
    pub fn of(p: [u32; 2], seed: u64) -> Self {
        let key = pixel_key(p, seed, SALT);
        let bits = (key ^ (key >> 32)) as u32;
        // sobol_burley's own seeds for the index shuffle and each dim's scramble
        // (`sobol_burley::sample`), hashed once here rather than once per point.
        let base = bits.wrapping_mul(0x9c8f_2d3b);
        let per_dim = [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8];
        Self {
            key,
            shuffle: parts::hash(bits ^ 0x79c6_8e4a),
            dims: std::array::from_fn(|d| parts::hash(base ^ (d as u32 >> 2) ^ per_dim[d & 3])),
        }
    }
}

/// Each dim's Sobol matrix applied to a byte of the (bit-reversed) index: the top two bytes,
/// 256 entries each, so that a point's dim is two lookups rather than a loop over the index's
/// bits (`sobol_burley::parts::sobol_rev`, which the tables are made from and agree with).
struct SobolTables([[[u32; 256]; 2]; MAX_SOBOL_DIMS]);

impl SobolTables {
    fn get() -> &'static Self {
        static TABLES: std::sync::OnceLock<Box<SobolTables>> = std::sync::OnceLock::new();
        TABLES.get_or_init(|| {
            Box::new(SobolTables(std::array::from_fn(|d| {
                std::array::from_fn(|byte| {
                    let shift = 24 - 8 * byte as u32;
                    std::array::from_fn(|v| parts::sobol_rev((v as u32) << shift, d as u32))
                })
            })))
        })
    }

    /// Dim `d` of the Sobol point with bit-reversed index `rev`, bit-reversed.
    #[inline]
    fn rev(&self, rev: u32, d: usize) -> u32 {
        let t = &self.0[d];
        t[0][(rev >> 24) as usize] ^ t[1][((rev >> 16) & 0xff) as usize]
    }
}

/// The coordinate in [0, 1) of a scrambled, bit-reversed Sobol value (`sobol_burley::sample`'s
/// last steps).
#[inline]
fn to_unit(sobol_rev: u32, scramble: u32) -> f32 {
    parts::u32_to_f32_norm(parts::owen_scramble_rev(sobol_rev, scramble).reverse_bits())
}

impl SobolSampler {
    /// The `index`th point of pixel `p` (`scramble` from `Scramble::of(p, seed)`): any number
    /// of a pixel's points, made in any order, form the same sequence.
    pub fn point(&self, p: [u32; 2], index: u32, scramble: Scramble) -> SamplePoint {
        let dims = self.cursor.space().dims;
        let (off, time, lens) = if index < SOBOL_SAMPLES {
            // As `sobol_burley::sample(index, d, seed)` for each dim, bit for bit, with the
            // index shuffled once for all dims; inactive dims draw nothing.
            let tables = SobolTables::get();
            let rev = parts::owen_scramble_rev(index.reverse_bits(), scramble.shuffle);
            let dim = |d: usize| to_unit(tables.rev(rev, d), scramble.dims[d]);
            let time = if dims.time { dim(2) } else { 0.5 };
            let lens = if dims.lens {
                [dim(3), dim(4)]
            } else {
                [0.5; 2]
            };
            ([dim(0), dim(1)], time, lens)
        } else {
            let mut rng = Pcg32::new(
                super::mix64(scramble.key ^ super::mix64(u64::from(index))),
                u64::from(index),
            );
            let off = [rng.next_f32(), rng.next_f32()];
            let time = if dims.time { rng.next_f32() } else { 0.5 };
            let lens = if dims.lens {
                [rng.next_f32(), rng.next_f32()]
            } else {
                [0.5; 2]
            };
            (off, time, lens)
        };
        SamplePoint {
            pixel: p,
            index,
            film: [in_pixel(p[0], off[0]), in_pixel(p[1], off[1])],
            time,
            lens,
        }
    }

    /// The seed the points are scrambled from.
    pub fn seed(&self) -> u64 {
        self.seed
    }
}

/// The registry's entry.
pub(super) const ENTRY: Entry<SamplerBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Sampler,
        name: "sobol",
        doc: "Owen-scrambled Sobol points per pixel (pbrt-v4 padded Sobol, via sobol_burley)",
        params: &[ParamSpec::new(
            "pixelsamples",
            ParamType::Integer,
            "16",
            super::PIXELSAMPLES,
        )],
    },
    build,
};

fn build(c: &Choice, setup: &SamplerSetup) -> Result<Box<dyn Sampler>> {
    let spp = super::pixel_samples(&c.params, setup)?;
    Ok(Box::new(SobolSampler::new(setup.space, spp, setup.seed)))
}

#[cfg(test)]
mod tests {
    use super::super::tests::{batches, space, star_discrepancy, ALL_DIMS};
    use super::*;

    /// Counts per interval of width 1/n of each 1D projection of one pixel's points.
    fn projections(px: &[SamplePoint], n: usize) -> [Vec<u32>; 5] {
        let mut c: [Vec<u32>; 5] = std::array::from_fn(|_| vec![0; n]);
        for q in px {
            let v = [
                f64::from(q.film[0]) - f64::from(q.pixel[0]),
                f64::from(q.film[1]) - f64::from(q.pixel[1]),
                f64::from(q.time),
                f64::from(q.lens[0]),
                f64::from(q.lens[1]),
            ];
            for d in 0..5 {
                c[d][(v[d] * n as f64).floor() as usize] += 1;
            }
        }
        c
    }

    #[test]
    fn one_point_per_interval_in_each_projection() {
        for spp in [16, 64] {
            let mut worst = 0.0f64;
            let sp = space(0, 0, 4, 4, ALL_DIMS[3]);
            let mut s = SobolSampler::new(sp, spp, 8);
            for px in batches(&mut s).concat().chunks(spp as usize) {
                for (d, c) in projections(px, spp as usize).iter().enumerate() {
                    assert!(c.iter().all(|&k| k == 1), "spp {spp} dim {d}: {c:?}");
                }
                // One point per 1/n interval bounds the star discrepancy by 1/n: [0, x) with
                // x in [k/n, (k+1)/n) holds k or k + 1 points against n x in [k, k + 1).
                let v: [Vec<f64>; 5] = std::array::from_fn(|d| {
                    px.iter()
                        .map(|q| match d {
                            0 => f64::from(q.film[0]) - f64::from(q.pixel[0]),
                            1 => f64::from(q.film[1]) - f64::from(q.pixel[1]),
                            2 => f64::from(q.time),
                            3 => f64::from(q.lens[0]),
                            _ => f64::from(q.lens[1]),
                        })
                        .collect()
                });
                for vals in &v {
                    let d = star_discrepancy(vals);
                    assert!(d <= 1.0 / f64::from(spp) + 1e-9);
                    worst = worst.max(d);
                }
            }
            eprintln!("sobol spp {spp}: worst 1D star discrepancy {worst:.4} (1/spp bound)");
        }
    }

    #[test]
    fn the_tables_give_sobol_burleys_points_bit_for_bit() {
        let sp = space(0, 0, 1, 1, ALL_DIMS[3]);
        let s = SobolSampler::new(sp, 16, 0);
        for p in [[0, 0], [7, 3], [1000, 20]] {
            for seed in [0, 5, u64::MAX] {
                let scramble = Scramble::of(p, seed);
                let bits = (scramble.key ^ (scramble.key >> 32)) as u32;
                for index in (0..SOBOL_SAMPLES)
                    .step_by(7)
                    .chain([1, 2, 3, SOBOL_SAMPLES - 1])
                {
                    let q = s.point(p, index, scramble);
                    let want = sobol_burley::sample_4d(index, 0, bits);
                    let film = [in_pixel(p[0], want[0]), in_pixel(p[1], want[1])];
                    assert_eq!(q.film, film, "{p:?} {index}");
                    assert_eq!([q.time, q.lens[0]], [want[2], want[3]]);
                    let v = sobol_burley::sample(index, 4, bits);
                    assert_eq!(q.lens[1].to_bits(), v.to_bits());
                }
            }
        }
    }

    #[test]
    fn past_the_sobol_limit_points_stay_in_range() {
        let sp = space(3, 4, 1, 1, ALL_DIMS[3]);
        let mut s = SobolSampler::new(sp, SOBOL_SAMPLES + 300, 1);
        let pts = batches(&mut s).concat();
        assert_eq!(pts.len(), SOBOL_SAMPLES as usize + 300);
        let late = &pts[SOBOL_SAMPLES as usize..];
        assert!(late.iter().all(|q| (0.0..1.0).contains(&q.time)
            && q.lens.iter().all(|l| (0.0..1.0).contains(l))
            && q.film[0] >= 3.0
            && q.film[0] < 4.0));
        // Random, not a repeat of the first points.
        assert_ne!(late[0].film, pts[0].film);
        assert_ne!(late[0].time, late[1].time);
    }
}
