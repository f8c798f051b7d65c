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
    /// Rows walked at a time ([`Sampler::walk_by_rows`]; 0: the whole space): every sample of
    /// a chunk of rows is given before the next chunk's.
    chunk_rows: u32,
    /// The chunk under way.
    chunk: u32,
    /// Rows, from the space's top, whose every sample has been given.
    rows_given: u32,
}

impl PixelCursor {
    /// A cursor at the first pixel, for `spp` samples per pixel.
    pub(crate) fn new(space: RenderingSpace, spp: u32) -> Self {
        let pixels = space.pixels().max(1);
        Self {
            space,
            spp,
            offset: 0,
            pass_len: Self::pass_len(pixels, spp),
            pass_start: 0,
            next_pixel: 0,
            halted: false,
            chunk_rows: 0,
            chunk: 0,
            rows_given: 0,
        }
    }

    /// Walks the space `rows` rows at a time (0: all at once), from the first pixel.
    pub(crate) fn walk_by_rows(&mut self, rows: u32) {
        self.chunk_rows = rows;
        self.chunk = 0;
        self.next_pixel = 0;
        self.pass_start = 0;
        self.pass_len = Self::pass_len(self.chunk_pixels().end, self.spp);
    }

    /// Samples a pixel gets in each pass over `pixels` pixels: as many as keep a pass near a
    /// batch.
    fn pass_len(pixels: u64, spp: u32) -> u32 {
        (BATCH_SAMPLES / pixels.max(1)).clamp(1, u64::from(spp.max(1))) as u32
    }

    /// The row-major pixel indices of the chunk under way.
    fn chunk_pixels(&self) -> Range<u64> {
        let total = self.space.pixels();
        if self.chunk_rows == 0 {
            return 0..total;
        }
        let w = u64::from(self.space.x1 - self.space.x0);
        let rows = u64::from(self.chunk_rows) * w;
        let start = (u64::from(self.chunk) * rows).min(total);
        start..(start + rows).min(total)
    }

    /// Rows, from the space's top, whose every sample the batches given so far hold.
    pub(crate) fn rows_given(&self) -> u32 {
        self.rows_given
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
        let chunk = self.chunk_pixels();
        let n = self.pass_len.min(self.spp - self.pass_start);
        // A pixel with more than a batch's samples forms a batch alone.
        let per_batch = (BATCH_SAMPLES / u64::from(n)).max(1);
        let end = (self.next_pixel + per_batch).min(chunk.end);
        let first = self.pass_start.saturating_add(self.offset);
        let batch = (self.next_pixel..end, first..first.saturating_add(n));
        self.next_pixel = end;
        if end == chunk.end {
            self.next_pixel = chunk.start;
            self.pass_start = if self.halted {
                self.spp
            } else {
                self.pass_start + n
            };
            if self.pass_start >= self.spp && !self.halted {
                self.next_chunk(chunk.end);
            }
        }
        Some(batch)
    }

    /// The chunk ending at pixel `end` is given whole: on to the next one, if any.
    fn next_chunk(&mut self, end: u64) {
        let w = u64::from(self.space.x1 - self.space.x0).max(1);
        self.rows_given = (end.div_ceil(w)).min(u64::from(u32::MAX)) as u32;
        if end < self.space.pixels() {
            self.chunk += 1;
            self.pass_start = 0;
            let chunk = self.chunk_pixels();
            self.next_pixel = chunk.start;
            self.pass_len = Self::pass_len(chunk.end - chunk.start, self.spp);
        }
    }

    /// The fewest samples per pixel the walk can still end at: the passes given and the one
    /// under way (at least 1).
    pub(crate) fn floor(&self) -> u32 {
        let under_way = if self.next_pixel > self.chunk_pixels().start {
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
        let at_start = self.next_pixel == self.chunk_pixels().start;
        // Between passes, or before a chunk's first pass once an earlier chunk is whole.
        if at_start && (self.pass_start > 0 || self.chunk > 0) {
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

    fn walk_by_rows(&mut self, rows: u32) -> bool {
        // Its points depend on the pixel and index alone, not on the order of the walk.
        self.cursor_mut().walk_by_rows(rows);
        true
    }

    fn rows_given(&self) -> u32 {
        self.cursor().rows_given()
    }

    fn set_sample_offset(&mut self, offset: u32) -> bool {
        if offset != 0 && !T::PROGRESSIVE {
            return false;
        }
        self.cursor_mut().offset = offset;
        true
    }
}
