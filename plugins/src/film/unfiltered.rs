//! Unfiltered splats: contributions that land on the film at a point of their own rather than
//! at the sample's, as light tracing's (bdpt's t = 1 strategies), mlt's and sppm's. pbrt-v3's
//! `Film::AddSplat`: each adds to the one pixel holding it, unweighted, and the image adds the
//! sums times a scale the integrator sets (1/spp for bdpt). docs/light-transport.md.

use super::Spectrum;
use glam::Vec2;

/// Per-pixel sums of unfiltered splats over the cropped film, allocated on the first splat.
#[derive(Clone, Debug, Default)]
pub struct UnfilteredSplats {
    /// The sums, row-major over the crop; empty until a splat arrives.
    sums: Vec<[f64; 3]>,
    /// What the sums are multiplied by in the image.
    scale: f64,
    /// Splats dropped because their value was not finite or negative.
    pub dropped: u64,
}

impl UnfilteredSplats {
    /// Adds `l` to the pixel at `index` of a crop of `pixels` pixels; a value that is not
    /// finite or is negative is dropped and counted.
    pub(super) fn add(&mut self, pixels: usize, index: usize, l: Spectrum) {
        if !(l.is_finite() && l.min_element() >= 0.0) {
            self.dropped += 1;
            return;
        }
        if self.sums.is_empty() {
            self.sums = vec![[0.0; 3]; pixels];
        }
        let s = &mut self.sums[index];
        s[0] += f64::from(l.x);
        s[1] += f64::from(l.y);
        s[2] += f64::from(l.z);
    }

    /// The sums, row-major over the crop (empty when nothing was splatted).
    pub fn sums(&self) -> &[[f64; 3]] {
        &self.sums
    }

    /// Adds `other`'s sums (the same crop) to these: how sample ranges merge.
    pub fn merge_sums(&mut self, other: &[[f64; 3]]) {
        if other.is_empty() {
            return;
        }
        if self.sums.is_empty() {
            self.sums = vec![[0.0; 3]; other.len()];
        }
        for (s, o) in self.sums.iter_mut().zip(other) {
            s[0] += o[0];
            s[1] += o[1];
            s[2] += o[2];
        }
    }

    /// The scale the sums take in the image.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Sets the scale the sums take in the image.
    pub fn set_scale(&mut self, scale: f64) {
        self.scale = scale;
    }

    /// Adds the scaled sums to `image` (row-major over the same crop).
    pub fn add_to(&self, image: &mut [Spectrum]) {
        for (c, s) in image.iter_mut().zip(&self.sums) {
            *c += Spectrum::new(
                (s[0] * self.scale) as f32,
                (s[1] * self.scale) as f32,
                (s[2] * self.scale) as f32,
            );
        }
    }
}

/// Where a splat at raster `p` lands in a crop `[x0, x1, y0, y1]`: its pixel's index, or
/// `None` outside the crop (dropped, as pbrt-v4 drops them).
pub(super) fn splat_index(crop: [u32; 4], p: Vec2) -> Option<usize> {
    let [cx0, cx1, cy0, cy1] = crop;
    if !(p.x.is_finite() && p.y.is_finite()) {
        return None;
    }
    let (x, y) = (p.x.floor(), p.y.floor());
    let inside = x >= cx0 as f32 && x < cx1 as f32 && y >= cy0 as f32 && y < cy1 as f32;
    inside.then(|| (y as u32 - cy0) as usize * (cx1 - cx0) as usize + (x as u32 - cx0) as usize)
}
