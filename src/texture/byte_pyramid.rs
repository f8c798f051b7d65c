//! The pyramid of an 8-bit image kept in bytes, built in bands: level 0 is cut into bands of
//! [`BAND_ROWS`] rows, and each band is resampled, halved up its own levels until one row is
//! left and quantised row by row, in a few rows of floats that each worker thread keeps from
//! band to band and from image to image. Each texel's arithmetic is the one
//! [`super::pyramid`] does on whole levels of values (the same taps, sums and products in the
//! same order, channel by channel), so the bytes are the same; but no level is ever held whole
//! in floats, which saves the memory, the passes over it and the page faults of mapping it
//! (docs/BENCHMARKS.md, "San Miguel's start-up").

use super::image_map::{ImageMap, Wrap};
use super::pyramid::{resample_weights, wrap_index};
use super::source::ByteImage;
use super::texels::{ByteTexels, Quantiser};
use super::value::TexValue;
use rayon::prelude::*;
use std::cell::RefCell;

/// Rows of level 0 in a band (a power of two).
const BAND_ROWS: usize = 32;

/// How level 0's rows come from the image's bytes: `channels` floats a texel (a grey image's
/// one float stands for every channel of a colour texel).
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

/// The floats a worker builds its bands in.
#[derive(Default)]
struct Scratch {
    /// The image's row being resampled along s.
    line: Vec<f32>,
    /// The rows resampled along s that the band's rows read.
    wide: Vec<f32>,
    /// The band's rows at the level being halved, and at the level above.
    cur: Vec<f32>,
    next: Vec<f32>,
}

thread_local! {
    /// Each thread's scratch, kept so that its pages are mapped once, not once an image.
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// What a band writes: its rows' bytes at each banded level it quantises (level 0 first,
/// unless level 0 is the image's own bytes), and its one row at the last banded level.
struct BandOut<'a> {
    bytes: Vec<&'a mut [u8]>,
    top: &'a mut [f32],
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
    let ch = image.channels;
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
        .map(|k| vec![0u8; width_at(k) * (h2 >> k) * ch])
        .collect();
    if own {
        let mut level0 = Vec::with_capacity(image.data.len());
        for t in 0..h {
            level0.extend_from_slice(image.row_from_bottom(t));
        }
        data[0] = level0;
    }
    let w_top = width_at(banded);
    let mut top = vec![0.0f32; w_top * ch * bands];
    {
        let mut outs: Vec<BandOut> = top
            .chunks_mut(w_top * ch)
            .map(|top| BandOut {
                bytes: Vec::with_capacity(banded + 1),
                top,
            })
            .collect();
        let first = usize::from(own);
        for (k, level) in data.iter_mut().enumerate().skip(first) {
            let chunk = (band >> k) * width_at(k) * ch;
            for (out, rows) in outs.iter_mut().zip(level.chunks_mut(chunk)) {
                out.bytes.push(rows);
            }
        }
        outs.into_par_iter().enumerate().for_each(|(b, out)| {
            SCRATCH.with_borrow_mut(|scratch| {
                let shape = Shape {
                    rows: band,
                    width: w2,
                    wrap,
                };
                // Channels known when compiled: the loops over a texel's floats unrolled.
                if ch == 1 {
                    base.rows::<1>(b * band, band, scratch);
                    build_band::<1>(scratch, out, shape, (banded, first), quantiser);
                } else {
                    base.rows::<3>(b * band, band, scratch);
                    build_band::<3>(scratch, out, shape, (banded, first), quantiser);
                }
            })
        });
    }
    let mut levels: Vec<ImageMap<T, ByteTexels>> = data
        .into_iter()
        .enumerate()
        .map(|(k, bytes)| {
            let texels = ByteTexels::new(bytes, ch, *lut);
            ImageMap::from_rows(width_at(k), h2 >> k, texels, wrap)
        })
        .collect();
    // The levels above the bands, small, built whole from the bands' top rows.
    let (mut level, mut lw, mut lh) = (top, w_top, bands);
    while lw > 1 || lh > 1 {
        let (sw, sh) = ((lw / 2).max(1), (lh / 2).max(1));
        level = halve_level(&level, (lw, lh), ch, wrap);
        (lw, lh) = (sw, sh);
        let mut bytes = vec![0u8; level.len()];
        quantise_row(&level, &mut bytes, quantiser);
        let texels = ByteTexels::new(bytes, ch, *lut);
        levels.push(ImageMap::from_rows(lw, lh, texels, wrap));
    }
    levels
}

/// A band's rows: how many, how wide, the wrap.
#[derive(Clone, Copy)]
struct Shape {
    rows: usize,
    width: usize,
    wrap: Wrap,
}

/// Halves `scratch.cur` (the band's rows of level 0) up to level `banded`, quantising each
/// level from `first` on into `out.bytes` and leaving the last one's row in `out.top`.
fn build_band<const CH: usize>(
    scratch: &mut Scratch,
    out: BandOut,
    shape: Shape,
    (banded, first): (usize, usize),
    quantiser: &Quantiser,
) {
    let Shape {
        mut rows,
        mut width,
        wrap,
    } = shape;
    let ch = CH;
    let mut bytes = out.bytes.into_iter();
    for k in 0..=banded {
        if k >= first {
            let dst = bytes.next().expect("one slice a quantised level");
            quantise_row(&scratch.cur[..rows * width * ch], dst, quantiser);
        }
        if k == banded {
            break;
        }
        let half = (width / 2).max(1);
        scratch.next.clear();
        scratch.next.resize(half * ch * rows / 2, 0.0);
        for (pair, o) in scratch
            .cur
            .chunks_exact(2 * width * ch)
            .zip(scratch.next.chunks_exact_mut(half * ch))
        {
            let (r0, r1) = pair.split_at(width * ch);
            halve_rows::<CH>(r0, r1, o, wrap);
        }
        std::mem::swap(&mut scratch.cur, &mut scratch.next);
        rows /= 2;
        width = half;
    }
    out.top.copy_from_slice(&scratch.cur[..width * ch]);
}

/// Each float the byte `quantiser` finds nearest.
fn quantise_row(values: &[f32], out: &mut [u8], quantiser: &Quantiser) {
    for (b, &v) in out.iter_mut().zip(values) {
        *b = quantiser.byte(v);
    }
}

/// The row above rows `r0` and `r1` (`ch` floats a texel): each texel the mean of the 2 x 2
/// below it, summed in [`super::pyramid`]'s order; a row one texel wide reads its second
/// column as the lookups' wrap does (the first column again, or black).
fn halve_rows<const CH: usize>(r0: &[f32], r1: &[f32], out: &mut [f32], wrap: Wrap) {
    if r0.len() >= 2 * CH {
        let pairs = r0.chunks_exact(2 * CH).zip(r1.chunks_exact(2 * CH));
        for (o, (a, b)) in out.chunks_exact_mut(CH).zip(pairs) {
            for (c, v) in o.iter_mut().enumerate() {
                *v = (a[c] + a[CH + c] + b[c] + b[CH + c]) * 0.25;
            }
        }
    } else {
        let beyond = |r: &[f32], c: usize| if wrap == Wrap::Black { 0.0 } else { r[c] };
        for (c, v) in out.iter_mut().enumerate() {
            *v = (r0[c] + beyond(r0, c) + r1[c] + beyond(r1, c)) * 0.25;
        }
    }
}

/// The level above `below` (`w` x `h`, sides powers of two, `ch` floats a texel), reading
/// texels past a side of 1 as the lookups' wrap does ([`super::pyramid`]'s halving): row pairs
/// halved by [`halve_rows`], as the bands are.
fn halve_level(below: &[f32], (w, h): (usize, usize), ch: usize, wrap: Wrap) -> Vec<f32> {
    let (sw, sh) = ((w / 2).max(1), (h / 2).max(1));
    let row = w * ch;
    let black = vec![0.0f32; row];
    let mut out = vec![0.0f32; sw * sh * ch];
    for (t, o) in out.chunks_exact_mut(sw * ch).enumerate() {
        let r0 = &below[2 * t * row..][..row];
        // The row above the only one: itself when wrapped or clamped, black otherwise.
        let r1 = match (h > 1, wrap) {
            (true, _) => &below[(2 * t + 1) * row..][..row],
            (false, Wrap::Black) => &black[..],
            (false, _) => r0,
        };
        if ch == 1 {
            halve_rows::<1>(r0, r1, o, wrap);
        } else {
            halve_rows::<3>(r0, r1, o, wrap);
        }
    }
    out
}

impl Base<'_> {
    /// Level 0's rows `t0` to `t0 + n` into `scratch.cur`.
    fn rows<const CH: usize>(&self, t0: usize, n: usize, scratch: &mut Scratch) {
        let ch = CH;
        let wc = self.width * ch;
        let cur = &mut scratch.cur;
        cur.clear();
        cur.resize(n * wc, 0.0);
        let Some(re) = &self.resample else {
            for (t, row) in cur.chunks_exact_mut(wc).enumerate() {
                self.convert(t0 + t, row);
            }
            return;
        };
        // The rows along s that the band reads, by their unwrapped index from `lo` on.
        let lo = re.along_t[t0].0;
        let hi = re.along_t[t0 + n - 1].0 + 3;
        let h = self.image.height;
        scratch.wide.clear();
        scratch.wide.resize((hi - lo + 1) as usize * wc, 0.0);
        scratch.line.resize(self.image.width * ch, 0.0);
        for (i, wide) in (lo..=hi).zip(scratch.wide.chunks_exact_mut(wc)) {
            let Some(o) = wrap_index(i, h, self.wrap) else {
                continue;
            };
            self.convert(o, &mut scratch.line);
            let line = &scratch.line;
            for (v, (taps, wts)) in wide.chunks_exact_mut(CH).zip(&re.along_s) {
                let mut sum = [0.0f32; CH];
                for (tap, &wt) in taps.iter().zip(wts) {
                    if let Some(o) = *tap {
                        let x = &line[o * CH..o * CH + CH];
                        for c in 0..CH {
                            sum[c] += x[c] * wt;
                        }
                    }
                }
                v.copy_from_slice(&sum);
            }
        }
        for (t, row) in cur.chunks_exact_mut(wc).enumerate() {
            let (first, wts) = re.along_t[t0 + t];
            for (j, &wt) in wts.iter().enumerate() {
                let i = first + j as i64;
                if wrap_index(i, h, self.wrap).is_some() {
                    let at = (i - lo) as usize * wc;
                    for (v, &x) in row.iter_mut().zip(&scratch.wide[at..at + wc]) {
                        *v += x * wt;
                    }
                }
            }
            for v in row.iter_mut() {
                *v = v.max(0.0);
            }
        }
    }

    /// The image's row `t` (from the bottom) as floats.
    fn convert(&self, t: usize, out: &mut [f32]) {
        for (v, &b) in out.iter_mut().zip(self.image.row_from_bottom(t)) {
            *v = self.lut[b as usize];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::pyramid::{build_levels, quantise, resample_up};
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
