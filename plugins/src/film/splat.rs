//! Splatting a sample into the pixels its filter reaches, through pbrt-v3's filter table.

use super::Spectrum;
use glam::Vec2;

/// Entries per axis of the filter table (pbrt-v3's filterTableWidth).
pub(super) const TABLE_SIZE: usize = 16;

/// Film columns a [`Prepared`] sample can reach: enough for filters of radius up to 3.5
/// pixels (wider ones splat through [`Splat::row`]).
pub(super) const MAX_SPAN: usize = 8;

/// A sample ready to splat: what does not depend on the film row (the radiance, the
/// columns reached and their filter-table columns), computed once for the several rows a
/// sample reaches.
#[derive(Clone, Copy, Debug)]
pub(super) struct Prepared {
    /// Raster position.
    pub(super) p: Vec2,
    /// Radiance.
    pub(super) l: Spectrum,
    /// First film column reached (within the crop).
    pub(super) x0: i64,
    /// Number of columns reached.
    pub(super) n: u8,
    /// Filter-table column of each column reached.
    pub(super) fx: [u8; MAX_SPAN],
}

/// How one sample spreads over a film row: the kernel tabulated over one quadrant of its
/// support, as pbrt-v3 does (evaluating exp() or a polynomial for each of a sample's up to 25
/// pixels would cost more than tracing it), the radius and the crop's columns.
#[derive(Clone, Debug)]
pub(super) struct Splat {
    pub(super) table: [f32; TABLE_SIZE * TABLE_SIZE],
    pub(super) radius: (f32, f32),
    pub(super) columns: (i64, i64),
}

impl Splat {
    /// Adds the contributions of the sample at `p` to film row `y` (`row` is its pixels).
    #[inline]
    pub(super) fn row(&self, row: &mut [[f64; 4]], y: i64, p: Vec2, l: Spectrum) {
        let (rx, ry) = self.radius;
        let (cx0, cx1) = self.columns;
        let (dx, dy) = (p.x - 0.5, p.y - 0.5);
        let ay = (y as f32 - dy).abs();
        if ay > ry {
            return;
        }
        let fy = ((ay / ry * TABLE_SIZE as f32) as usize).min(TABLE_SIZE - 1);
        let table_row = &self.table[fy * TABLE_SIZE..][..TABLE_SIZE];
        let x0 = ((dx - rx).ceil() as i64).max(cx0);
        let x1 = ((dx + rx).floor() as i64 + 1).min(cx1);
        for x in x0..x1 {
            let fx = ((x as f32 - dx).abs() / rx * TABLE_SIZE as f32) as usize;
            let weight = table_row[fx.min(TABLE_SIZE - 1)];
            if weight != 0.0 {
                let s = &mut row[(x - cx0) as usize];
                let wf = weight as f64;
                s[0] += wf * l.x as f64;
                s[1] += wf * l.y as f64;
                s[2] += wf * l.z as f64;
                s[3] += wf;
            }
        }
    }

    /// Whether to splat through [`Prepared`] samples: when a sample reaches several rows (so
    /// that preparing it pays) and every sample's columns fit one.
    pub(super) fn prepare_pays(&self) -> bool {
        self.radius.1 > 0.5 && 2.0 * self.radius.0 + 1.0 <= MAX_SPAN as f32
    }

    /// The row-independent part of [`Splat::row`] for the sample at `p` (the same values);
    /// the filter must fit ([`Splat::prepare_pays`]).
    #[inline]
    pub(super) fn prepare(&self, p: Vec2, l: Spectrum) -> Prepared {
        let rx = self.radius.0;
        let (cx0, cx1) = self.columns;
        let dx = p.x - 0.5;
        let x0 = ceil_i64(dx - rx).max(cx0);
        let x1 = floor_i64(dx + rx).saturating_add(1).min(cx1);
        let mut fx = [0u8; MAX_SPAN];
        let mut n = 0u8;
        for (slot, x) in fx.iter_mut().zip(x0..x1) {
            *slot = table_index((x as f32 - dx).abs() / rx);
            n += 1;
        }
        Prepared { p, l, x0, n, fx }
    }

    /// [`Splat::row`] for a prepared sample: the same contributions, in the same order.
    #[inline]
    pub(super) fn row_prepared(&self, row: &mut [[f64; 4]], y: i64, s: &Prepared) {
        let ry = self.radius.1;
        let ay = (y as f32 - (s.p.y - 0.5)).abs();
        if ay > ry || s.n == 0 {
            return;
        }
        let fy = table_index(ay / ry) as usize;
        let table_row = &self.table[fy * TABLE_SIZE..][..TABLE_SIZE];
        let start = (s.x0 - self.columns.0) as usize;
        let cells = &mut row[start..start + s.n as usize];
        for (cell, &fx) in cells.iter_mut().zip(&s.fx) {
            let weight = table_row[fx as usize];
            if weight != 0.0 {
                let wf = weight as f64;
                cell[0] += wf * s.l.x as f64;
                cell[1] += wf * s.l.y as f64;
                cell[2] += wf * s.l.z as f64;
                cell[3] += wf;
            }
        }
    }
}

/// The filter-table entry for a distance `r` in units of the filter radius (r >= 0, not NaN):
/// `min(floor(r * TABLE_SIZE), TABLE_SIZE - 1)`, clamping before the conversion (the same
/// value for such `r`) so that it is one narrow conversion instead of a saturating one to usize.
#[inline]
pub(super) fn table_index(r: f32) -> u8 {
    (r * TABLE_SIZE as f32).min((TABLE_SIZE - 1) as f32) as u8
}

/// `v.ceil() as i64` without a libm call (baseline x86-64 has no rounding instruction).
#[inline]
pub(super) fn ceil_i64(v: f32) -> i64 {
    let t = v as i64;
    if (t as f32) < v {
        t.saturating_add(1)
    } else {
        t
    }
}

/// `v.floor() as i64` without a libm call.
#[inline]
pub(super) fn floor_i64(v: f32) -> i64 {
    let t = v as i64;
    if (t as f32) > v {
        t.saturating_sub(1)
    } else {
        t
    }
}
