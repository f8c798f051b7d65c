//! First-hit features of a camera path: the albedo, shading normal and distance of the first
//! surface it meets that is not a perfect mirror or glass (pbrt-v4's `GBufferFilm` and Open
//! Image Denoise take them through specular surfaces), and their per-pixel means (`--aov
//! albedo=...,normal=...,depth=...`).

use crate::bsdf::Bsdf;
use crate::geometry::{Spectrum, SurfaceInteraction, Vec2, Vec3};

/// What a camera path saw first: zeros when it met no such surface (it escaped, or only met
/// specular ones).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FirstHit {
    /// The surface's albedo: the sum of its lobes' reflectances and transmittances, in [0, 1].
    pub albedo: Spectrum,
    /// Its unit shading normal (world space), turned towards the side the path came from.
    pub normal: Vec3,
    /// The length of the path from the camera to it (through mirrors and glass).
    pub depth: f32,
}

impl FirstHit {
    /// The features as the film's cells take them: albedo, normal, depth.
    pub fn to_array(&self) -> acr_plugins::first_hit::Features {
        let (a, n) = (self.albedo, self.normal);
        [a.x, a.y, a.z, n.x, n.y, n.z, self.depth]
    }

    /// Whether every value is finite.
    pub fn is_finite(&self) -> bool {
        self.albedo.is_finite() && self.normal.is_finite() && self.depth.is_finite()
    }
}

/// Follows a camera path for its first-hit features: call [`FirstHitProbe::travel`] at every
/// intersection and [`FirstHitProbe::surface`] with each BSDF.
#[derive(Clone, Copy, Debug, Default)]
pub struct FirstHitProbe {
    /// The features, once found.
    pub hit: Option<FirstHit>,
    travelled: f32,
}

impl FirstHitProbe {
    /// The path went from `from` to `to`.
    #[inline]
    pub fn travel(&mut self, from: Vec3, to: Vec3) {
        if self.hit.is_none() {
            self.travelled += from.distance(to);
        }
    }

    /// The path scatters at `si` with `bsdf`: the first surface with a non-specular lobe, or
    /// with none at all (black), gives the features.
    #[inline]
    pub fn surface(&mut self, si: &SurfaceInteraction, bsdf: &Bsdf) {
        if self.hit.is_some() || (bsdf.num_lobes() > 0 && !bsdf.has_non_specular()) {
            return;
        }
        let n = si.shading_n.normalize_or_zero();
        self.hit = Some(FirstHit {
            albedo: bsdf.albedo(),
            normal: if n.dot(si.wo) < 0.0 { -n } else { n },
            depth: self.travelled,
        });
    }

    /// The path scatters in a medium of single-scattering albedo `albedo` at the end of the
    /// last travel: the features are that albedo, a zero normal (a medium has no surface) and
    /// the distance (docs/media.md).
    #[inline]
    pub fn medium(&mut self, albedo: Spectrum) {
        if self.hit.is_none() {
            self.hit = Some(FirstHit {
                albedo,
                normal: Vec3::ZERO,
                depth: self.travelled,
            });
        }
    }

    /// The features (zeros when none were found).
    pub fn features(&self) -> FirstHit {
        self.hit.unwrap_or_default()
    }
}

/// Per-pixel sums of first-hit features over a film's crop, for their means.
#[derive(Clone, Debug)]
pub struct FeatureImage {
    x0: u32,
    y0: u32,
    width: usize,
    height: usize,
    /// Albedo (3), normal (3), depth (1) per pixel.
    sums: Vec<[f64; 7]>,
    counts: Vec<u32>,
    /// Samples whose features were not finite (left out, counted).
    pub non_finite: u64,
}

impl FeatureImage {
    /// Empty sums over pixels `x0..x1` x `y0..y1`.
    pub fn new(x0: u32, x1: u32, y0: u32, y1: u32) -> Self {
        let (width, height) = ((x1 - x0) as usize, (y1 - y0) as usize);
        Self {
            x0,
            y0,
            width,
            height,
            sums: vec![[0.0; 7]; width * height],
            counts: vec![0; width * height],
            non_finite: 0,
        }
    }

    /// Adds the features of a sample at raster position `film`.
    pub fn add(&mut self, film: Vec2, hit: &FirstHit) {
        if !hit.is_finite() {
            self.non_finite += 1;
            return;
        }
        let (x, y) = (film.x.floor() as i64, film.y.floor() as i64);
        let (x, y) = (x - i64::from(self.x0), y - i64::from(self.y0));
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return;
        }
        let i = y as usize * self.width + x as usize;
        for (s, v) in self.sums[i].iter_mut().zip(hit.to_array()) {
            *s += f64::from(v);
        }
        self.counts[i] += 1;
    }

    /// The mean of channels `c..c + 3` of each pixel (zero where no sample landed).
    fn means(&self, c: usize) -> Vec<Spectrum> {
        self.sums
            .iter()
            .zip(&self.counts)
            .map(|(s, &n)| {
                let k = f64::from(n.max(1));
                let at = |j: usize| {
                    if c + j < 7 {
                        (s[c + j] / k) as f32
                    } else {
                        0.0
                    }
                };
                Spectrum::new(at(0), at(1), at(2))
            })
            .collect()
    }

    /// The named feature's per-pixel means: `albedo`, `normal` (RGB = XYZ, not renormalised,
    /// as Open Image Denoise takes it) or `depth` (the same value in the three channels).
    pub fn image(&self, name: &str) -> Vec<Spectrum> {
        match name {
            "albedo" => self.means(0),
            "normal" => self.means(3),
            _ => self.means(6).iter().map(|d| Spectrum::splat(d.x)).collect(),
        }
    }

    /// Width and height in pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_means_skip_non_finite_samples_and_stay_inside() {
        let mut img = FeatureImage::new(2, 4, 1, 2);
        let a = FirstHit {
            albedo: Spectrum::new(0.2, 0.4, 0.6),
            normal: Vec3::Z,
            depth: 2.0,
        };
        let b = FirstHit {
            albedo: Spectrum::new(0.4, 0.4, 0.4),
            normal: Vec3::X,
            depth: 4.0,
        };
        img.add(Vec2::new(2.5, 1.5), &a);
        img.add(Vec2::new(2.9, 1.1), &b);
        img.add(
            Vec2::new(3.5, 1.5),
            &FirstHit {
                depth: f32::NAN,
                ..a
            },
        );
        img.add(Vec2::new(0.5, 0.5), &a); // outside the crop: ignored
        assert_eq!(img.non_finite, 1);
        let albedo = img.image("albedo");
        assert_eq!(albedo.len(), 2);
        assert!(
            (albedo[0] - Spectrum::new(0.3, 0.4, 0.5))
                .abs()
                .max_element()
                < 1e-6
        );
        assert_eq!(albedo[1], Spectrum::ZERO);
        assert_eq!(img.image("normal")[0], Spectrum::new(0.5, 0.0, 0.5));
        assert_eq!(img.image("depth")[0], Spectrum::splat(3.0));
    }
}
