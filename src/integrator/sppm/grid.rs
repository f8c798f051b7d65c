//! sppm's grid of visible points (pbrt-v3's hash grid): cells the size of the largest search
//! radius over the visible points' bounds, each visible point listed in every cell its search
//! sphere's box overlaps, cells hashed into as many buckets as there are pixels. pbrt-v3 links
//! the lists by atomic pushes; here the (bucket, pixel) pairs are made in parallel and laid out
//! bucket by bucket in pixel order, so the layout does not depend on the threads.

use super::visible::VisiblePoint;
use crate::geometry::Vec3;
use rayon::prelude::*;

/// The visible points of one iteration, by grid cell.
#[derive(Default)]
pub struct Grid {
    /// The grid's box, low corner.
    lo: Vec3,
    /// Its extent.
    extent: Vec3,
    /// Cells along each axis.
    res: [i32; 3],
    /// Where each bucket's pixels start in `entries` (one more than the buckets).
    starts: Vec<u32>,
    /// Pixel indices, bucket by bucket, ascending within a bucket.
    entries: Vec<u32>,
    /// The (bucket, pixel) pairs of the last build, kept for their buffer.
    pairs: Vec<(u32, u32)>,
    /// The counting sort's fill positions, kept for their buffer.
    fill: Vec<u32>,
}

/// Pixels whose (bucket, pixel) pairs one task makes.
const PIXELS_PER_CHUNK: usize = 256;

/// pbrt-v3's hash of a cell into `size` buckets.
#[inline]
fn hash(c: [i32; 3], size: usize) -> usize {
    let h = c[0].wrapping_mul(73_856_093)
        ^ c[1].wrapping_mul(19_349_663)
        ^ c[2].wrapping_mul(83_492_791);
    // A 32-bit remainder (the pixel count fits: pixels are u32), cheaper than a 64-bit one.
    (h as u32 % size as u32) as usize
}

impl Grid {
    /// [`Grid::rebuild`] with no buffers to reuse.
    #[cfg(test)]
    pub fn build(visible: &[Option<VisiblePoint>], radii: &[f32]) -> Option<Grid> {
        Self::rebuild(visible, radii, None)
    }

    /// The grid of `visible` (one entry per pixel) with each pixel's search radius in `radii`,
    /// built in the buffers of `old` (the last iteration's grid: allocating and freeing them
    /// each iteration made the kernel hand out and take back their pages); `None` when no
    /// pixel has a visible point.
    pub fn rebuild(
        visible: &[Option<VisiblePoint>],
        radii: &[f32],
        old: Option<Grid>,
    ) -> Option<Grid> {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let mut max_radius = 0.0f32;
        for (vp, &r) in visible.iter().zip(radii) {
            if let Some(vp) = vp {
                lo = lo.min(vp.p - Vec3::splat(r));
                hi = hi.max(vp.p + Vec3::splat(r));
                max_radius = max_radius.max(r);
            }
        }
        if max_radius <= 0.0 || !lo.is_finite() || !hi.is_finite() {
            return None;
        }
        let extent = hi - lo;
        let max_diag = extent.max_element();
        // pbrt-v3: cells as wide as the largest radius along the longest axis (capped here so
        // that a tiny radius in a huge scene cannot ask for more cells than an i32 holds).
        let base = (max_diag / max_radius).floor().clamp(1.0, 1_048_576.0);
        let res = [0, 1, 2].map(|i| ((base * extent[i] / max_diag) as i32).max(1));
        let mut grid = old.unwrap_or_default();
        (grid.lo, grid.extent, grid.res) = (lo, extent, res);
        let buckets = visible.len().max(1);
        // One list per chunk of pixels, not per pixel (a small allocation per pixel and
        // iteration cost more than the pairs themselves).
        let mut pairs = std::mem::take(&mut grid.pairs);
        pairs.clear();
        pairs.par_extend(
            visible
                .par_chunks(PIXELS_PER_CHUNK)
                .zip(radii.par_chunks(PIXELS_PER_CHUNK))
                .enumerate()
                .flat_map_iter(|(chunk, (vps, rs))| {
                    let mut own: Vec<(u32, u32)> = Vec::new();
                    for (k, (vp, &r)) in vps.iter().zip(rs).enumerate() {
                        let Some(vp) = vp else { continue };
                        let i = (chunk * PIXELS_PER_CHUNK + k) as u32;
                        let first = own.len();
                        let (a, _) = grid.cell(vp.p - Vec3::splat(r));
                        let (b, _) = grid.cell(vp.p + Vec3::splat(r));
                        for z in a[2]..=b[2] {
                            for y in a[1]..=b[1] {
                                for x in a[0]..=b[0] {
                                    let e = (hash([x, y, z], buckets) as u32, i);
                                    // Two of its cells in one bucket would count each photon there
                                    // twice (a point spans few cells: a scan is cheapest).
                                    if !own[first..].contains(&e) {
                                        own.push(e);
                                    }
                                }
                            }
                        }
                    }
                    own
                }),
        );
        // A counting sort by bucket, stable: each bucket's pixels stay in ascending order.
        let mut starts = std::mem::take(&mut grid.starts);
        starts.clear();
        starts.resize(buckets + 1, 0);
        for &(b, _) in &pairs {
            starts[b as usize + 1] += 1;
        }
        for b in 0..buckets {
            starts[b + 1] += starts[b];
        }
        let mut fill = std::mem::take(&mut grid.fill);
        fill.clear();
        fill.extend_from_slice(&starts);
        let mut entries = std::mem::take(&mut grid.entries);
        entries.clear();
        entries.resize(pairs.len(), 0);
        for &(b, i) in &pairs {
            entries[fill[b as usize] as usize] = i;
            fill[b as usize] += 1;
        }
        (grid.starts, grid.entries, grid.pairs, grid.fill) = (starts, entries, pairs, fill);
        Some(grid)
    }

    /// pbrt-v3's `ToGrid`: the cell holding `p` (clamped to the grid) and whether `p` is inside.
    #[inline]
    fn cell(&self, p: Vec3) -> ([i32; 3], bool) {
        let mut c = [0i32; 3];
        let mut inside = true;
        for i in 0..3 {
            let offset = if self.extent[i] > 0.0 {
                (p[i] - self.lo[i]) / self.extent[i]
            } else {
                0.0
            };
            let v = (self.res[i] as f32 * offset) as i32;
            inside &= v >= 0 && v < self.res[i];
            c[i] = v.clamp(0, self.res[i] - 1);
        }
        (c, inside)
    }

    /// The pixels whose visible points may lie within their radius of `p`: those listed in
    /// `p`'s bucket (none when `p` is outside the grid).
    #[inline]
    pub fn candidates(&self, p: Vec3) -> &[u32] {
        let (c, inside) = self.cell(p);
        if !inside {
            return &[];
        }
        let b = hash(c, self.starts.len() - 1);
        &self.entries[self.starts[b] as usize..self.starts[b + 1] as usize]
    }
}
