//! The pyramid of an 8-bit image kept in bytes, built in bands: level 0 is cut into bands of
//! [`BAND_ROWS`] rows, and each band is resampled, halved up its own levels until one row is
//! left and quantised row by row, in a few rows of floats that a worker keeps from band to band.
//! Each texel's arithmetic is the one [`super::pyramid`] does on whole levels (the same taps,
//! sums and products in the same order), so the bytes are the same; but no level is ever held
//! whole in floats, which saves the memory, the passes over it and the page faults of mapping
//! it (docs/BENCHMARKS.md, "San Miguel's start-up").

use super::image_map::{ImageMap, Wrap};
use super::pyramid::{build_levels, quantise, quantise_row, resample_weights, wrap_index};
use super::source::ByteImage;
use super::texels::{ByteTexels, Quantiser};
use super::value::TexValue;
use rayon::prelude::*;

/// Rows of level 0 in a band (a power of two).
const BAND_ROWS: usize = 32;

/// How level 0's rows come from the image's bytes.
struct Base<'a> {
    image: &'a ByteImage,
    lut: &'a [f32; 256],
    wrap: Wrap,
    /// Level 0's width (a power of two).
    width: usize,
    /// Resampling up to powers of two, or `None` where the sides already are.
    resample: Option<Resample>,
}

/// pbrt-v3's resampling weights ([`super::pyramid::resample_up`]).
struct Resample {
    /// Per new column, its four old columns (`None`: black) and their weights.
    along_s: Vec<([Option<usize>; 4], [f32; 4])>,
    /// Per new row, its first old row (unwrapped) and its four weights.
    along_t: Vec<(i64, [f32; 4])>,
}

/// The floats a worker builds its bands in, kept from band to band.
struct Scratch<T> {
    /// The image's row being resampled along s.
    line: Vec<T>,
    /// The rows resampled along s that the band's rows read.
    wide: Vec<T>,
    /// The band's rows at the level being halved, and at the level above.
    cur: Vec<T>,
    next: Vec<T>,
}

/// What a band writes: its rows' bytes at each banded level it quantises (level 0 first,
/// unless level 0 is the image's own bytes), and its one row at the last banded level.
struct BandOut<'a, T> {
    bytes: Vec<&'a mut [u8]>,
    top: &'a mut [T],
}

/// Every level of the pyramid of `image` (each byte worth `lut[byte]`), finest first, stored
/// as the bytes `quantiser` finds nearest the levels pbrt-v3 builds in floats; a level 0 that
/// is the image's own pixels (sides powers of two) keeps them as they are.
pub fn byte_levels<T: TexValue>(
    image: &ByteImage,
    lut: &[f32; 256],
    quantiser: &Quantiser,
    wrap: Wrap,
) -> Vec<ImageMap<T, ByteTexels>> {
    let (w, h) = (image.width, image.height);
    let (w2, h2) = (w.next_power_of_two(), h.next_power_of_two());
    let own = w == w2 && h == h2;
    let channels = image.channels;
    let base = Base {
        image,
        lut,
        wrap,
        width: w2,
        resample: (!own).then(|| Resample {
            along_s: resample_weights(w, w2)
                .into_iter()
                .map(|(first, wts)| {
                    let taps = std::array::from_fn(|j| wrap_index(first + j as i64, w, wrap));
                    (taps, wts)
                })
                .collect(),
            along_t: resample_weights(h, h2),
        }),
    };
    let band = BAND_ROWS.min(h2);
    let banded = band.ilog2() as usize;
    let bands = h2 / band;
    let width_at = |k: usize| (w2 >> k).max(1);
    let mut data: Vec<Vec<u8>> = (0..=banded)
        .map(|k| vec![0u8; width_at(k) * (h2 >> k) * channels])
        .collect();
    if own {
        let mut level0 = Vec::with_capacity(image.data.len());
        for t in 0..h {
            level0.extend_from_slice(image.row_from_bottom(t));
        }
        data[0] = level0;
    }
    let w_top = width_at(banded);
    let mut top = vec![T::ZERO; w_top * bands];
    {
        let mut outs: Vec<BandOut<T>> = top
            .chunks_mut(w_top)
            .map(|top| BandOut {
                bytes: Vec::with_capacity(banded + 1),
                top,
            })
            .collect();
        let first = usize::from(own);
        for (k, level) in data.iter_mut().enumerate().skip(first) {
            let chunk = (band >> k) * width_at(k) * channels;
            for (out, rows) in outs.iter_mut().zip(level.chunks_mut(chunk)) {
                out.bytes.push(rows);
            }
        }
        outs.into_par_iter().enumerate().for_each_init(
            || Scratch {
                line: Vec::new(),
                wide: Vec::new(),
                cur: Vec::new(),
                next: Vec::new(),
            },
            |scratch, (b, out)| {
                base.rows(b * band, band, scratch);
                build_band(
                    scratch,
                    out,
                    (band, banded, first),
                    channels,
                    quantiser,
                    wrap,
                    w2,
                );
            },
        );
    }
    let mut levels: Vec<ImageMap<T, ByteTexels>> = data
        .into_iter()
        .enumerate()
        .map(|(k, bytes)| {
            let texels = ByteTexels::new(bytes, channels, *lut);
            ImageMap::from_rows(width_at(k), h2 >> k, texels, wrap)
        })
        .collect();
    // The levels above the bands, small, built whole from the bands' top rows.
    let mut first_above = true;
    build_levels(ImageMap::from_rows(w_top, bands, top, wrap), |level| {
        if !std::mem::take(&mut first_above) {
            levels.push(quantise(&level, channels, quantiser, lut));
        }
    });
    levels
}

/// Halves `scratch.cur` (the band's `rows` rows of level 0, `width` wide) up to the last
/// banded level, quantising each level from `first` on into `out.bytes` and leaving the last
/// one's row in `out.top`.
fn build_band<T: TexValue>(
    scratch: &mut Scratch<T>,
    out: BandOut<T>,
    (rows, banded, first): (usize, usize, usize),
    channels: usize,
    quantiser: &Quantiser,
    wrap: Wrap,
    width: usize,
) {
    let mut bytes = out.bytes.into_iter();
    let (mut rows, mut width) = (rows, width);
    for k in 0..=banded {
        if k >= first {
            let dst = bytes.next().expect("one slice a quantised level");
            for (row, o) in scratch
                .cur
                .chunks_exact(width)
                .zip(dst.chunks_exact_mut(width * channels))
            {
                quantise_row(row, o, channels, quantiser);
            }
        }
        if k == banded {
            break;
        }
        let half = (width / 2).max(1);
        scratch.next.clear();
        scratch.next.resize(half * rows / 2, T::ZERO);
        for (pair, o) in scratch
            .cur
            .chunks_exact(2 * width)
            .zip(scratch.next.chunks_exact_mut(half))
        {
            let (r0, r1) = pair.split_at(width);
            halve_rows(r0, r1, o, wrap);
        }
        std::mem::swap(&mut scratch.cur, &mut scratch.next);
        rows /= 2;
        width = half;
    }
    out.top.copy_from_slice(&scratch.cur[..width]);
}

/// Row `t` of the level above rows `2t` and `2t + 1`: each texel the mean of the 2 x 2 below
/// it, summed in [`super::pyramid`]'s order; a row 1 wide reads its second column as the
/// lookups' wrap does (the first column again, or black).
fn halve_rows<T: TexValue>(r0: &[T], r1: &[T], out: &mut [T], wrap: Wrap) {
    if r0.len() >= 2 {
        for (s, o) in out.iter_mut().enumerate() {
            let sum = r0[2 * s] + r0[2 * s + 1] + r1[2 * s] + r1[2 * s + 1];
            *o = sum * 0.25;
        }
    } else {
        let beyond = |r: &[T]| if wrap == Wrap::Black { T::ZERO } else { r[0] };
        out[0] = (r0[0] + beyond(r0) + r1[0] + beyond(r1)) * 0.25;
    }
}

impl Base<'_> {
    /// Level 0's rows `t0` to `t0 + n` into `scratch.cur`.
    fn rows<T: TexValue>(&self, t0: usize, n: usize, scratch: &mut Scratch<T>) {
        let w2 = self.width;
        let cur = &mut scratch.cur;
        cur.clear();
        cur.resize(n * w2, T::ZERO);
        let Some(re) = &self.resample else {
            for (t, row) in cur.chunks_exact_mut(w2).enumerate() {
                self.convert(t0 + t, row);
            }
            return;
        };
        // The rows along s that the band reads, by their unwrapped index from `lo` on.
        let lo = re.along_t[t0].0;
        let hi = re.along_t[t0 + n - 1].0 + 3;
        let h = self.image.height;
        scratch.wide.clear();
        scratch.wide.resize((hi - lo + 1) as usize * w2, T::ZERO);
        scratch.line.resize(self.image.width, T::ZERO);
        for (i, wide) in (lo..=hi).zip(scratch.wide.chunks_exact_mut(w2)) {
            let Some(o) = wrap_index(i, h, self.wrap) else {
                continue;
            };
            self.convert(o, &mut scratch.line);
            for (v, (taps, wts)) in wide.iter_mut().zip(&re.along_s) {
                let mut sum = T::ZERO;
                for (tap, &wt) in taps.iter().zip(wts) {
                    if let Some(o) = *tap {
                        sum = sum + scratch.line[o] * wt;
                    }
                }
                *v = sum;
            }
        }
        for (t, row) in cur.chunks_exact_mut(w2).enumerate() {
            let (first, wts) = re.along_t[t0 + t];
            for (j, &wt) in wts.iter().enumerate() {
                let i = first + j as i64;
                if wrap_index(i, h, self.wrap).is_some() {
                    let at = (i - lo) as usize * w2;
                    for (v, &x) in row.iter_mut().zip(&scratch.wide[at..at + w2]) {
                        *v = *v + x * wt;
                    }
                }
            }
            for v in row.iter_mut() {
                *v = v.clamp_nonneg();
            }
        }
    }

    /// The image's row `t` (from the bottom) as values.
    fn convert<T: TexValue>(&self, t: usize, out: &mut [T]) {
        let c = self.image.channels;
        for (v, px) in out
            .iter_mut()
            .zip(self.image.row_from_bottom(t).chunks_exact(c))
        {
            *v = T::from_bytes(px, self.lut);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::pyramid::resample_up;
    use super::super::texels::Texels;
    use super::*;
    use crate::geometry::Spectrum;

    /// The pyramid as whole levels: built in floats, then quantised level by level.
    fn whole<T: TexValue>(
        image: &ByteImage,
        lut: &[f32; 256],
        q: &Quantiser,
        wrap: Wrap,
    ) -> Vec<Vec<T>> {
        let values = image.to_map(wrap, |b| T::from_bytes(b, lut));
        let own = image.width.is_power_of_two() && image.height.is_power_of_two();
        let base = if own { values } else { resample_up(&values) };
        let mut levels = Vec::new();
        build_levels(base, |level| {
            let bytes = quantise(&level, image.channels, q, lut);
            let n = bytes.width() * bytes.height();
            levels.push((0..n).map(|i| bytes.storage().get(i)).collect());
        });
        levels
    }

    fn image(width: usize, height: usize, channels: usize) -> ByteImage {
        let data = (0..width * height * channels)
            .map(|i| ((i * 97 + i / 3 * 31 + i * i % 13) % 256) as u8)
            .collect();
        ByteImage {
            width,
            height,
            channels,
            data,
            unit: super::super::source::unit_lut(super::super::source::Layout::Rgb),
        }
    }

    fn check<T: TexValue>(img: &ByteImage, wrap: Wrap) {
        let lut: [f32; 256] =
            std::array::from_fn(|b| crate::spectrum::srgb_to_linear(img.unit[b]) * 0.9);
        let q = Quantiser::new(&lut).unwrap();
        let want = whole::<T>(img, &lut, &q, wrap);
        let got = byte_levels::<T>(img, &lut, &q, wrap);
        assert_eq!(got.len(), want.len());
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            let g: Vec<T> = (0..g.width() * g.height())
                .map(|i| g.storage().get(i))
                .collect();
            assert_eq!(&g, w, "{}x{} level {k} {wrap:?}", img.width, img.height);
        }
    }

    /// Bands give every level's bytes as whole levels do: sides powers of two or not, taller
    /// or wider (columns of one texel halved), more bands than one, every wrap.
    #[test]
    fn bands_build_the_bytes_whole_levels_build() {
        let sizes = [
            (8, 4),
            (7, 5),
            (3, 70),
            (64, 64),
            (100, 33),
            (1, 50),
            (130, 1),
            (2, 128),
        ];
        for (w, h) in sizes {
            for wrap in [Wrap::Repeat, Wrap::Black, Wrap::Clamp] {
                check::<Spectrum>(&image(w, h, 3), wrap);
                check::<Spectrum>(&image(w, h, 1), wrap);
                check::<f32>(&image(w, h, 1), wrap);
            }
        }
    }
}
