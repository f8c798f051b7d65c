//! The film: pbrt-v3's image film. Each sample is splatted into every pixel within the filter's
//! radius, weighted; a pixel's value is its weighted mean.

use crate::geometry::{Spectrum, Vec2};
use acr_parser::{Error, PluginDesc, Result};
use acr_plugins::{FilterKernel, Kernel};

/// Largest accepted resolution per axis: keeps a typo from allocating terabytes.
pub const MAX_RESOLUTION: u32 = 1 << 15;

/// Film settings from the `Film` directive.
#[derive(Clone, Debug)]
pub struct FilmSettings {
    /// Full image resolution.
    pub resolution: (u32, u32),
    /// Pixel bounds actually rendered: [x0, x1) x [y0, y1).
    pub crop: [u32; 4],
    /// Output file name from the scene ("string filename").
    pub filename: Option<String>,
    /// Scale applied to pixel values on output.
    pub scale: f32,
    /// Samples whose luminance exceeds this are scaled down to it (pbrt-v3's
    /// maxsampleluminance); infinite by default.
    pub max_sample_luminance: f32,
}

impl FilmSettings {
    /// Reads the `Film` directive (pbrt-v3's defaults when absent).
    pub fn new(desc: Option<&PluginDesc>) -> Result<Self> {
        let Some(p) = desc else {
            return Ok(Self::with_resolution(1280, 720));
        };
        if p.kind != "image" {
            return Err(Error::at(
                &p.loc,
                format!("film \"{}\" is not supported (only \"image\")", p.kind),
            ));
        }
        let params = &p.params;
        let res = |name: &str, default: i32| -> Result<u32> {
            let v = params.int_or(name, default)?;
            if v < 1 || v as u32 > MAX_RESOLUTION {
                let loc = params.get(name).map_or(&p.loc, |x| &x.loc).clone();
                return Err(Error::at(
                    &loc,
                    format!("{name} {v} is out of range (1 to {MAX_RESOLUTION})"),
                ));
            }
            Ok(v as u32)
        };
        let mut s = Self::with_resolution(res("xresolution", 1280)?, res("yresolution", 720)?);
        if let Some(c) = params.floats("cropwindow")? {
            let loc = params.get("cropwindow").map_or(&p.loc, |x| &x.loc).clone();
            let [x0, x1, y0, y1] = <[f64; 4]>::try_from(c)
                .map_err(|_| Error::at(&loc, "\"cropwindow\" needs four values"))?;
            let (x0, x1) = (x0.clamp(0.0, 1.0), x1.clamp(0.0, 1.0));
            let (y0, y1) = (y0.clamp(0.0, 1.0), y1.clamp(0.0, 1.0));
            let (w, h) = (s.resolution.0 as f64, s.resolution.1 as f64);
            // pbrt-v3: ceil of the crop window in raster space.
            s.crop = [
                (w * x0.min(x1)).ceil() as u32,
                (w * x0.max(x1)).ceil() as u32,
                (h * y0.min(y1)).ceil() as u32,
                (h * y0.max(y1)).ceil() as u32,
            ];
            if s.crop[0] >= s.crop[1] || s.crop[2] >= s.crop[3] {
                return Err(Error::at(&loc, "\"cropwindow\" contains no pixel"));
            }
        }
        s.filename = params.string("filename")?.map(str::to_owned);
        s.scale = params.float_or("scale", 1.0)? as f32;
        s.max_sample_luminance = params.float_or("maxsampleluminance", f64::INFINITY)? as f32;
        // Accepted, and meaningless for an RGB film.
        let _ = params.float("diagonal")?;
        Ok(s)
    }

    /// The defaults at a given resolution.
    pub fn with_resolution(x: u32, y: u32) -> Self {
        Self {
            resolution: (x, y),
            crop: [0, x, 0, y],
            filename: None,
            scale: 1.0,
            max_sample_luminance: f32::INFINITY,
        }
    }

    /// Width and height of the rendered (cropped) image.
    pub fn size(&self) -> (u32, u32) {
        (self.crop[1] - self.crop[0], self.crop[3] - self.crop[2])
    }
}

/// Accumulated, filtered samples.
#[derive(Clone, Debug)]
pub struct Film {
    settings: FilmSettings,
    kernel: Kernel,
    sums: Vec<[f64; 4]>,
}

impl Film {
    /// An empty film.
    pub fn new(settings: FilmSettings, kernel: Kernel) -> Self {
        let (w, h) = settings.size();
        Self {
            sums: vec![[0.0; 4]; w as usize * h as usize],
            settings,
            kernel,
        }
    }

    /// The settings it was made with.
    pub fn settings(&self) -> &FilmSettings {
        &self.settings
    }

    /// Adds a sample at raster position `p` (full-resolution pixels) with radiance `l`, into
    /// every pixel whose centre is within the filter radius (pbrt-v3's Film::AddSample).
    #[inline]
    pub fn add_sample(&mut self, p: Vec2, l: Spectrum) {
        let (rx, ry) = self.kernel.radius();
        let [cx0, cx1, cy0, cy1] = self.settings.crop;
        let (dx, dy) = (p.x - 0.5, p.y - 0.5);
        let x0 = ((dx - rx).ceil() as i64).max(cx0 as i64);
        let x1 = ((dx + rx).floor() as i64 + 1).min(cx1 as i64);
        let y0 = ((dy - ry).ceil() as i64).max(cy0 as i64);
        let y1 = ((dy + ry).floor() as i64 + 1).min(cy1 as i64);
        let w = (cx1 - cx0) as i64;
        let lum = crate::spectrum_luminance(l);
        let l = if lum > self.settings.max_sample_luminance {
            l * (self.settings.max_sample_luminance / lum)
        } else {
            l
        };
        for y in y0..y1 {
            let fy = y as f32 - dy;
            for x in x0..x1 {
                let weight = self.kernel.eval(x as f32 - dx, fy);
                if weight != 0.0 {
                    let i = ((y - cy0 as i64) * w + (x - cx0 as i64)) as usize;
                    let s = &mut self.sums[i];
                    let wf = weight as f64;
                    s[0] += wf * l.x as f64;
                    s[1] += wf * l.y as f64;
                    s[2] += wf * l.z as f64;
                    s[3] += wf;
                }
            }
        }
    }

    /// The image: each pixel's weighted mean times the film scale, row-major, top row first.
    pub fn pixels(&self) -> Vec<Spectrum> {
        let scale = self.settings.scale;
        self.sums
            .iter()
            .map(|s| {
                if s[3] != 0.0 {
                    let inv = 1.0 / s[3];
                    // Negative lobes (Mitchell, sinc) can make a mean slightly negative.
                    Spectrum::new(
                        (s[0] * inv) as f32,
                        (s[1] * inv) as f32,
                        (s[2] * inv) as f32,
                    )
                    .max(Spectrum::ZERO)
                        * scale
                } else {
                    Spectrum::ZERO
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use acr_plugins::filters::{BoxFilter, GaussianFilter};

    #[test]
    fn box_filter_averages_samples_in_the_pixel() {
        let mut f = Film::new(
            FilmSettings::with_resolution(2, 1),
            Kernel::Box(BoxFilter::new(0.5, 0.5)),
        );
        f.add_sample(Vec2::new(0.25, 0.5), Spectrum::splat(1.0));
        f.add_sample(Vec2::new(0.75, 0.5), Spectrum::splat(3.0));
        f.add_sample(Vec2::new(1.5, 0.5), Spectrum::splat(5.0));
        let p = f.pixels();
        assert_eq!(p[0], Spectrum::splat(2.0));
        assert_eq!(p[1], Spectrum::splat(5.0));
    }

    #[test]
    fn wide_filter_reaches_neighbours_and_crop_limits_output() {
        let mut s = FilmSettings::with_resolution(4, 4);
        s.crop = [1, 3, 1, 3];
        let mut f = Film::new(s, Kernel::Gaussian(GaussianFilter::new(2.0, 2.0, 2.0)));
        f.add_sample(Vec2::new(1.5, 1.5), Spectrum::new(1.0, 2.0, 3.0));
        let p = f.pixels();
        assert_eq!(p.len(), 4);
        for v in p {
            assert!((v - Spectrum::new(1.0, 2.0, 3.0)).length() < 1e-6);
        }
    }
}
