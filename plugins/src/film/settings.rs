//! The `Film` directive's settings: resolution, crop, clamp, checked before allocation.

use super::{luminance, Spectrum};
use acr_parser::{Error, PluginDesc, Result};

/// Largest accepted resolution per axis: keeps a typo from allocating terabytes.
pub const MAX_RESOLUTION: u32 = 1 << 15;

/// Largest accepted number of rendered (cropped) pixels, 8192 x 8192: the film keeps about
/// 100 bytes per pixel, so this bounds it near 7 GiB before anything is allocated.
pub const MAX_PIXELS: u64 = 1 << 26;

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
    /// Samples whose largest RGB component exceeds this are scaled down to it (pbrt-v4's
    /// maxcomponentvalue); infinite by default.
    pub max_component_value: f32,
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
            let window = <[f64; 4]>::try_from(c)
                .map_err(|_| Error::at(&loc, "\"cropwindow\" needs four values"))?;
            s.set_crop_window(window)
                .map_err(|e| Error::at(&loc, format!("\"cropwindow\" {e}")))?;
        }
        s.filename = params.string("filename")?.map(str::to_owned);
        s.scale = params.float_or("scale", 1.0)? as f32;
        let positive = |name: &str| -> Result<f32> {
            let v = params.float_or(name, f64::INFINITY)?;
            if v.is_nan() || v <= 0.0 {
                let loc = params.get(name).map_or(&p.loc, |x| &x.loc);
                return Err(Error::at(loc, format!("{name} must be positive, not {v}")));
            }
            Ok(v as f32)
        };
        s.max_sample_luminance = positive("maxsampleluminance")?;
        s.max_component_value = positive("maxcomponentvalue")?;
        let (w, h) = s.size();
        if u64::from(w) * u64::from(h) > MAX_PIXELS {
            let loc = params.get("xresolution").map_or(&p.loc, |x| &x.loc);
            return Err(Error::at(
                loc,
                format!(
                    "{w}x{h} = {} pixels to render is more than {MAX_PIXELS} (8192x8192); \
                     lower the resolution or set a cropwindow",
                    u64::from(w) * u64::from(h)
                ),
            ));
        }
        // Accepted, and meaningless for an RGB film.
        let _ = params.float("diagonal")?;
        Ok(s)
    }

    /// Crops to a window given in fractions of the image, [x0, x1, y0, y1] (pbrt-v3's
    /// `cropwindow`: the ceiling of each edge in raster space; values clamped to [0, 1]).
    /// The products are in f32 as pbrt-v3's (its `Float`): 0.6 of 800 is then 481, not 480,
    /// so that a crop has pbrt-v3's pixels.
    pub fn set_crop_window(&mut self, window: [f64; 4]) -> std::result::Result<(), String> {
        let [x0, x1, y0, y1] = window.map(|v| {
            if v.is_nan() {
                0.0
            } else {
                v.clamp(0.0, 1.0) as f32
            }
        });
        let (w, h) = (self.resolution.0 as f32, self.resolution.1 as f32);
        self.set_pixel_bounds([
            (w * x0.min(x1)).ceil() as u32,
            (w * x0.max(x1)).ceil() as u32,
            (h * y0.min(y1)).ceil() as u32,
            (h * y0.max(y1)).ceil() as u32,
        ])
    }

    /// Crops to the pixels [x0, x1) x [y0, y1) (pbrt-v4's `--pixelbounds`), which must lie in
    /// the image and hold at least one pixel.
    pub fn set_pixel_bounds(&mut self, bounds: [u32; 4]) -> std::result::Result<(), String> {
        let [x0, x1, y0, y1] = bounds;
        let (w, h) = self.resolution;
        if x0 >= x1 || y0 >= y1 {
            return Err(format!("{x0},{x1},{y0},{y1} contains no pixel"));
        }
        if x1 > w || y1 > h {
            return Err(format!(
                "{x0},{x1},{y0},{y1} reaches beyond the {w}x{h} image"
            ));
        }
        if u64::from(x1 - x0) * u64::from(y1 - y0) > MAX_PIXELS {
            return Err(format!(
                "{x0},{x1},{y0},{y1} holds more than {MAX_PIXELS} pixels (8192x8192)"
            ));
        }
        self.crop = bounds;
        Ok(())
    }

    /// The defaults at a given resolution.
    pub fn with_resolution(x: u32, y: u32) -> Self {
        Self {
            resolution: (x, y),
            crop: [0, x, 0, y],
            filename: None,
            scale: 1.0,
            max_sample_luminance: f32::INFINITY,
            max_component_value: f32::INFINITY,
        }
    }

    /// A sample's radiance after the film's limits: scaled down so that its luminance is at
    /// most `maxsampleluminance` and its largest component at most `maxcomponentvalue`.
    #[inline]
    pub fn clamp(&self, l: Spectrum) -> Spectrum {
        let lum = luminance(l);
        let l = if lum > self.max_sample_luminance {
            l * (self.max_sample_luminance / lum)
        } else {
            l
        };
        let m = l.max_element();
        if m > self.max_component_value {
            l * (self.max_component_value / m)
        } else {
            l
        }
    }

    /// Width and height of the rendered (cropped) image.
    pub fn size(&self) -> (u32, u32) {
        (self.crop[1] - self.crop[0], self.crop[3] - self.crop[2])
    }
}
