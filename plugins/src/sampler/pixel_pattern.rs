//! Samplers whose points in a pixel depend only on the pixel, the sample index and the seed
//! (random, stratified, halton, sobol, and the first stages of the adaptive ones): the walk
//! over the image in passes ([`PixelCursor`]), the pattern a sampler implements
//! ([`PixelPattern`]) and the batches made from it, in parallel.

use super::{Sampler, BATCH_SAMPLES};
use crate::space::{RenderingSpace, SamplePoint};
use rayon::prelude::*;
use std::ops::Range;

/// Walks a space's pixels in passes: each pass gives every pixel the next few sample indices
/// (as many as keep a pass near a batch), in batches of whole pixels, row-major. Between
/// passes every pixel has the same count, which is where a halted sampler stops.
#[derive(Clone, Debug)]
pub(crate) struct PixelCursor {
    space: RenderingSpace,
    spp: u32,
    /// The first sample index given ([`Sampler::set_sample_offset`]).
    offset: u32,
    pass_len: u32,
    pass_start: u32,
    next_pixel: u64,
    halted: bool,
}

impl PixelCursor {
    /// A cursor at the first pixel, for `spp` samples per pixel.
    pub(crate) fn new(space: RenderingSpace, spp: u32) -> Self {
        let pixels = space.pixels().max(1);
        Self {
            space,
            spp,
            offset: 0,
            pass_len: (BATCH_SAMPLES / pixels).clamp(1, u64::from(spp.max(1))) as u32,
            pass_start: 0,
            next_pixel: 0,
            halted: false,
        }
    }

    /// The space walked.
    pub(crate) fn space(&self) -> &RenderingSpace {
        &self.space
    }

    /// Samples per pixel, unless halted.
    pub(crate) fn spp(&self) -> u32 {
        self.spp
    }

    /// Whether [`Self::next`] has another batch to give.
    pub(crate) fn has_next(&self) -> bool {
        self.space.pixels() > 0 && self.pass_start < self.spp
    }

    /// The next batch: row-major pixel indices and the sample indices each of them gets, or
    /// None when every pixel is done.
    pub(crate) fn next(&mut self) -> Option<(Range<u64>, Range<u32>)> {
        if !self.has_next() {
            return None;
        }
        let total = self.space.pixels();
        let n = self.pass_len.min(self.spp - self.pass_start);
        // A pixel with more than a batch's samples forms a batch alone.
        let per_batch = (BATCH_SAMPLES / u64::from(n)).max(1);
        let end = (self.next_pixel + per_batch).min(total);
        let first = self.pass_start.saturating_add(self.offset);
        let batch = (self.next_pixel..end, first..first.saturating_add(n));
        self.next_pixel = end;
        if end == total {
            self.next_pixel = 0;
            self.pass_start = if self.halted {
                self.spp
            } else {
                self.pass_start + n
            };
        }
        Some(batch)
    }

    /// The fewest samples per pixel the walk can still end at: the passes given and the one
    /// under way (at least 1).
    pub(crate) fn floor(&self) -> u32 {
        let under_way = if self.next_pixel > 0 {
            self.pass_len.min(self.spp - self.pass_start)
        } else {
            0
        };
        (self.pass_start + under_way).clamp(1, self.spp.max(1))
    }

    /// Lowers the walk's samples per pixel to `spp`, but not below [`Self::floor`] (so that
    /// every pixel still ends with as many samples); returns the count in force.
    pub(crate) fn shorten(&mut self, spp: u32) -> u32 {
        self.spp = spp.clamp(self.floor(), self.spp.max(1));
        self.spp
    }

    /// Ends the walk after the current pass (after the first pass, if none is complete yet).
    pub(crate) fn halt(&mut self) {
        self.halted = true;
        if self.next_pixel == 0 && self.pass_start > 0 {
            self.pass_start = self.spp;
        }
    }
}

/// Pixels whose points one task makes: enough to outweigh the task's cost.
const PIXELS_PER_TASK: usize = 64;

/// A sampler whose points in a pixel depend only on the pixel, the sample index and the seed.
/// It walks the image with a [`PixelCursor`]; the walk, the budget and halting are the same for
/// every such sampler, so implementing this trait gives [`Sampler`].
pub(crate) trait PixelPattern: Send + Sync {
    /// The plugin's name.
    const NAME: &'static str;

    /// The walk over the image.
    fn cursor(&self) -> &PixelCursor;

    /// The walk, to advance or halt it.
    fn cursor_mut(&mut self) -> &mut PixelCursor;

    /// Appends the points with sample indices `indices` of pixel `p` to `out`.
    fn pixel(&self, p: [u32; 2], indices: Range<u32>, out: &mut Vec<SamplePoint>);

    /// Whether a point depends on its index alone, not on the pixel's sample count (so that a
    /// range of indices can start anywhere: [`Sampler::set_sample_offset`]).
    const PROGRESSIVE: bool;
}

/// The next batch of `pattern`'s walk, with points made only for the pixels `keep` accepts
/// (the others' are skipped, not made and dropped): what [`Sampler::next_batch`] gives, less
/// the pixels left out. False once the walk is over.
pub(crate) fn next_batch_where<T: PixelPattern>(
    pattern: &mut T,
    out: &mut Vec<SamplePoint>,
    keep: impl Fn([u32; 2]) -> bool + Sync,
) -> bool {
    out.clear();
    let Some((pixels, indices)) = pattern.cursor_mut().next() else {
        return false;
    };
    let space = *pattern.cursor().space();
    let kept: Vec<[u32; 2]> = (pixels.start..pixels.end)
        .map(|i| space.pixel(i))
        .filter(|&p| keep(p))
        .collect();
    make_points(&*pattern, &kept, indices, out);
    true
}

/// The points with sample indices `indices` of each of `pixels`, in order, made in parallel.
fn make_points<T: PixelPattern>(
    pattern: &T,
    pixels: &[[u32; 2]],
    indices: Range<u32>,
    out: &mut Vec<SamplePoint>,
) {
    let per_pixel = indices.len();
    out.resize(pixels.len() * per_pixel, SamplePoint::UNMADE);
    out.par_chunks_mut(PIXELS_PER_TASK * per_pixel)
        .zip(pixels.par_chunks(PIXELS_PER_TASK))
        .for_each_init(Vec::new, |points, (chunk, pixels)| {
            for (slot, &p) in chunk.chunks_mut(per_pixel).zip(pixels) {
                points.clear();
                pattern.pixel(p, indices.clone(), points);
                slot.copy_from_slice(points);
            }
        });
}

impl<T: PixelPattern> Sampler for T {
    fn name(&self) -> &'static str {
        T::NAME
    }

    fn spp(&self) -> u32 {
        self.cursor().spp()
    }

    fn next_batch(&mut self, out: &mut Vec<SamplePoint>) -> bool {
        next_batch_where(self, out, |_| true)
    }

    fn halt(&mut self) {
        self.cursor_mut().halt();
    }

    fn plans_ahead(&self) -> bool {
        // Its points depend on nothing it observes.
        true
    }

    fn reads_film(&self) -> bool {
        false
    }

    fn whole_passes(&self) -> bool {
        true
    }

    fn set_sample_offset(&mut self, offset: u32) -> bool {
        if offset != 0 && !T::PROGRESSIVE {
            return false;
        }
        self.cursor_mut().offset = offset;
        true
    }
}
