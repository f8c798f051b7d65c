//! Image files as image textures read them: an 8-bit PNG kept in its bytes ([`ByteImage`]),
//! anything else (16-bit PNG, EXR, HDR, PFM) as linear floats.

use super::image_map::{ImageMap, Wrap};
use super::value::TexValue;
use crate::geometry::Spectrum;
use crate::image_io::{decode_image, read_image, read_image_file, RgbImage};
use std::path::Path;

/// An 8-bit image: `channels` (1: grey, 3: RGB) bytes a pixel, top row first.
#[derive(Clone, Debug)]
pub struct ByteImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Bytes a pixel: 1 or 3.
    pub channels: usize,
    /// The pixels' bytes, row-major, top row first.
    pub data: Vec<u8>,
    /// The value of a byte, as [`read_image`] reads it from this file.
    pub unit: &'static [f32; 256],
}

/// An image file's pixels as an image texture reads them.
#[derive(Clone, Debug)]
pub enum Source {
    /// An 8-bit PNG (grey or colour; alpha dropped).
    Bytes(ByteImage),
    /// Anything else, as [`read_image`] reads it.
    Values(RgbImage),
}

/// The layouts of 8-bit PNG pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Grey.
    L,
    /// Grey and alpha.
    La,
    /// RGB.
    Rgb,
    /// RGB and alpha.
    Rgba,
}

/// The value [`read_image`] gives a byte of an 8-bit PNG of `layout` (the `image` crate's
/// conversion, which differs by layout in the last bit, asked of the crate itself so that both
/// paths agree to the bit).
pub fn unit_lut(layout: Layout) -> &'static [f32; 256] {
    type Lut = std::sync::OnceLock<[f32; 256]>;
    static LUTS: [Lut; 4] = [Lut::new(), Lut::new(), Lut::new(), Lut::new()];
    LUTS[layout as usize].get_or_init(|| {
        use image::DynamicImage as D;
        let n = layout_channels(layout);
        let raw: Vec<u8> = (0..256)
            .flat_map(|x| {
                (0..n).map(move |c| {
                    if c == 3 || (c == 1 && n == 2) {
                        255
                    } else {
                        x as u8
                    }
                })
            })
            .collect();
        let img = match layout {
            Layout::L => D::ImageLuma8(image::GrayImage::from_raw(256, 1, raw).expect("sized")),
            Layout::La => {
                D::ImageLumaA8(image::GrayAlphaImage::from_raw(256, 1, raw).expect("sized"))
            }
            Layout::Rgb => D::ImageRgb8(image::RgbImage::from_raw(256, 1, raw).expect("sized")),
            Layout::Rgba => D::ImageRgba8(image::RgbaImage::from_raw(256, 1, raw).expect("sized")),
        };
        let rgb = img.to_rgb32f();
        std::array::from_fn(|i| rgb.get_pixel(i as u32, 0)[0])
    })
}

/// Channels a pixel of `layout` has in the file.
fn layout_channels(layout: Layout) -> usize {
    match layout {
        Layout::L => 1,
        Layout::La => 2,
        Layout::Rgb => 3,
        Layout::Rgba => 4,
    }
}

/// Reads `path` for an image texture: as [`read_image`] does (no sRGB decoding), but an
/// 8-bit PNG stays in bytes.
pub fn read_source(path: &Path) -> Result<Source, String> {
    let is_png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return read_image(path, false).map(Source::Values);
    }
    let data = read_image_file(path)?;
    let mut reader = image::ImageReader::new(std::io::Cursor::new(&data));
    reader.set_format(image::ImageFormat::Png);
    let img = reader.decode().map_err(|e| e.to_string())?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    let (layout, bytes) = match img {
        image::DynamicImage::ImageLuma8(g) => (Layout::L, g.into_raw()),
        image::DynamicImage::ImageLumaA8(g) => (Layout::La, g.into_raw()),
        image::DynamicImage::ImageRgb8(c) => (Layout::Rgb, c.into_raw()),
        image::DynamicImage::ImageRgba8(c) => (Layout::Rgba, c.into_raw()),
        _ => return decode_image(&data, "png", false).map(Source::Values),
    };
    // Alpha is dropped, as read_image drops it.
    let (channels, data) = match layout {
        Layout::La => (1, bytes.chunks_exact(2).map(|p| p[0]).collect()),
        Layout::Rgba => (
            3,
            bytes
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect(),
        ),
        Layout::L => (1, bytes),
        Layout::Rgb => (3, bytes),
    };
    Ok(Source::Bytes(ByteImage {
        width,
        height,
        channels,
        data,
        unit: unit_lut(layout),
    }))
}

impl ByteImage {
    /// The bytes of row `t` counted from the bottom.
    pub fn row_from_bottom(&self, t: usize) -> &[u8] {
        let n = self.width * self.channels;
        let y = self.height - 1 - t;
        &self.data[y * n..(y + 1) * n]
    }

    /// The image map of these pixels, each pixel's bytes converted by `convert`.
    pub fn to_map<T: TexValue>(&self, wrap: Wrap, convert: impl Fn(&[u8]) -> T) -> ImageMap<T> {
        let mut texels = Vec::with_capacity(self.width * self.height);
        for t in 0..self.height {
            texels.extend(
                self.row_from_bottom(t)
                    .chunks_exact(self.channels)
                    .map(&convert),
            );
        }
        ImageMap::from_rows(self.width, self.height, texels, wrap)
    }

    /// A pixel's bytes as [`read_image`] reads them: linear floats, grey as RGB.
    pub fn rgb(&self, bytes: &[u8]) -> Spectrum {
        let unit = self.unit;
        match bytes {
            [r, g, b] => Spectrum::new(unit[*r as usize], unit[*g as usize], unit[*b as usize]),
            _ => Spectrum::splat(unit[bytes[0] as usize]),
        }
    }
}
