//! Reading and writing RGB images: PNG (8 or 16 bits), OpenEXR (half or float), Radiance HDR and
//! PFM. Pixels are kept as linear RGB floats, row-major, top row first.

use crate::geometry::Spectrum;
use crate::spectrum::{linear_to_srgb, srgb_to_linear};
use std::io::Write;
use std::path::Path;

/// An RGB image: `pixels[y * width + x]`, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels, row-major, top row first.
    pub pixels: Vec<Spectrum>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            pixels: vec![Spectrum::ZERO; width * height],
        }
    }

    /// The pixel at column `x`, row `y` (from the top).
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> Spectrum {
        self.pixels[y * self.width + x]
    }

    /// Sets the pixel at column `x`, row `y` (from the top).
    #[inline]
    pub fn set(&mut self, x: usize, y: usize, c: Spectrum) {
        self.pixels[y * self.width + x] = c;
    }
}

/// Whether `path` names an EXR (by its extension, any case).
pub fn is_exr(path: &Path) -> bool {
    extension(path) == "exr"
}

/// The lower-case extension of `path`, without the dot.
fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Reads an image, choosing the format by extension: `.png`, `.exr`, `.hdr`, `.pfm`.
///
/// EXR, HDR and PFM hold linear values and are returned as they are. PNG values are scaled to
/// [0, 1]; with `srgb` they are then decoded from sRGB to linear, without it they are returned
/// as stored (what pbrt-v3's `ReadImage` does: its image textures apply their own "gamma"
/// conversion, and its environment maps use PNG values as they are).
pub fn read_image(path: &Path, srgb: bool) -> Result<RgbImage, String> {
    let format = image_format(path)?;
    decode_image(&read_image_file(path)?, format, srgb)
}

/// The bytes of an image file, through the checked reader every file a scene names goes
/// through (a regular file of bounded size).
pub(crate) fn read_image_file(path: &Path) -> Result<Vec<u8>, String> {
    acr_parser::source::read_file(path, acr_parser::source::FileKind::Image)
        .map_err(|e| acr_parser::io_message(&e))
}

/// The format of an image file, by its extension: `png`, `exr`, `hdr` or `pfm`.
fn image_format(path: &Path) -> Result<&'static str, String> {
    match extension(path).as_str() {
        "png" => Ok("png"),
        "exr" => Ok("exr"),
        "hdr" => Ok("hdr"),
        "pfm" => Ok("pfm"),
        other => Err(format!(
            "unsupported image format \"{other}\" (acr reads .png, .exr, .hdr and .pfm)"
        )),
    }
}

/// Decodes an image file's bytes in `format` (`png`, `exr`, `hdr` or `pfm`), as
/// [`read_image`] does.
pub fn decode_image(data: &[u8], format: &str, srgb: bool) -> Result<RgbImage, String> {
    let img = match format {
        "exr" => decode_exr(data)?,
        "pfm" => parse_pfm(data)?,
        _ => decode_with_image_crate(data, format)?,
    };
    Ok(if srgb && format == "png" {
        linearize(img)
    } else {
        img
    })
}

/// Decodes every channel from sRGB to linear.
pub fn linearize(mut img: RgbImage) -> RgbImage {
    for p in &mut img.pixels {
        *p = Spectrum::new(
            srgb_to_linear(p.x),
            srgb_to_linear(p.y),
            srgb_to_linear(p.z),
        );
    }
    img
}

/// PNG and Radiance HDR through the `image` crate: integer samples become [0, 1] floats
/// (v / 255 or v / 65535), HDR values stay as they are, grey becomes RGB.
fn decode_with_image_crate(data: &[u8], format: &str) -> Result<RgbImage, String> {
    let mut reader = image::ImageReader::new(std::io::Cursor::new(data));
    if let Some(f) = image::ImageFormat::from_extension(format) {
        reader.set_format(f);
    }
    let img = reader
        .with_guessed_format()
        .map_err(|e| e.to_string())?
        .decode()
        .map_err(|e| e.to_string())?;
    let rgb = img.to_rgb32f();
    let (width, height) = (rgb.width() as usize, rgb.height() as usize);
    let pixels = rgb
        .pixels()
        .map(|p| Spectrum::new(p[0], p[1], p[2]))
        .collect();
    Ok(RgbImage {
        width,
        height,
        pixels,
    })
}

/// Most pixels an image read from disk may have (16384 x 16384): a corrupt or hostile header
/// fails here instead of sizing an allocation.
pub const MAX_IMAGE_PIXELS: usize = 1 << 28;

/// The most an EXR's raw samples may outweigh its file: deflate (the ZIP compressions) gains
/// at most about 1032:1, the others less; a header claiming more is corrupt or hostile, and is
/// refused before its pixels are allocated (a 1 KB file made `acr merge` allocate 1.9 GB).
const MAX_EXR_RATIO: usize = 1100;

/// An EXR's header, read before its pixels: every layer's size and the display window
/// (which `acr merge` allocates) must be sane first.
pub fn exr_header(data: &[u8]) -> Result<exr::meta::MetaData, String> {
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(data), false).map_err(
        |e| match e {
            exr::error::Error::Io(io) => acr_parser::io_message(&io),
            other => other.to_string(),
        },
    )?;
    for h in meta.headers.iter() {
        let display = h.shared_attributes.display_window.size;
        let (w, ht) = (h.layer_size.width(), h.layer_size.height());
        for (w, ht) in [(w, ht), (display.width(), display.height())] {
            if w.checked_mul(ht).is_none_or(|n| n > MAX_IMAGE_PIXELS) {
                return Err(format!(
                    "the image is {w}x{ht}, more than {MAX_IMAGE_PIXELS} pixels"
                ));
            }
        }
        // Its samples at 2 bytes each at least, and one block of them (which the reader
        // allocates whole), against what the file could hold compressed.
        let channels = h.channels.list.len().max(1);
        let raw = w * ht * channels * 2;
        if raw / MAX_EXR_RATIO > data.len() {
            return Err(format!(
                "its header claims {w}x{ht} pixels of {channels} channels, more than a file of \
                 {} bytes can hold",
                data.len()
            ));
        }
        let block_pixels = match h.blocks {
            exr::meta::BlockDescription::Tiles(t) => t.tile_size.area(),
            exr::meta::BlockDescription::ScanLines => {
                h.compression.scan_lines_per_block().saturating_mul(w)
            }
        };
        let block = block_pixels.saturating_mul(h.channels.bytes_per_pixel);
        if block / MAX_EXR_RATIO > data.len() {
            return Err(format!(
                "its header claims blocks of {block} bytes, more than a file of {} bytes can hold",
                data.len()
            ));
        }
    }
    Ok(meta)
}

fn decode_exr(data: &[u8]) -> Result<RgbImage, String> {
    use exr::prelude::*;
    exr_header(data)?;
    let rgba = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size: Vec2<usize>, _: &RgbaChannels| RgbImage::new(size.width(), size.height()),
            |img: &mut RgbImage, pos: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
                img.set(pos.x(), pos.y(), Spectrum::new(r, g, b));
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(data));
    match rgba {
        Ok(image) => Ok(image.layer_data.channel_data.pixels),
        Err(rgb_error) => {
            // A luminance-only file ("Y"), as OpenEXR's RGBA interface reads it: grey.
            let grey = read()
                .no_deep_data()
                .largest_resolution_level()
                .specific_channels()
                .required("Y")
                .collect_pixels(
                    |size: Vec2<usize>, _: &(ChannelDescription,)| {
                        RgbImage::new(size.width(), size.height())
                    },
                    |img: &mut RgbImage, pos: Vec2<usize>, (y,): (f32,)| {
                        img.set(pos.x(), pos.y(), Spectrum::splat(y));
                    },
                )
                .first_valid_layer()
                .all_attributes()
                .from_buffered(std::io::Cursor::new(data));
            match grey {
                Ok(image) => Ok(image.layer_data.channel_data.pixels),
                Err(_) => Err(rgb_error.to_string()),
            }
        }
    }
}

/// Parses a PFM file: `PF` (RGB) or `Pf` (grey), width, height and a scale whose sign gives the
/// byte order (negative: little-endian), then rows of 32-bit floats from the bottom up.
fn parse_pfm(data: &[u8]) -> Result<RgbImage, String> {
    // Four whitespace-separated words, then exactly one whitespace byte before the raster.
    let mut pos = 0usize;
    let mut words: Vec<&str> = Vec::with_capacity(4);
    while words.len() < 4 {
        while pos < data.len() && data[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < data.len() && !data[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err("truncated PFM header".into());
        }
        words.push(std::str::from_utf8(&data[start..pos]).map_err(|_| "bad PFM header")?);
    }
    pos += 1; // the single whitespace byte after the scale
    let channels = match words[0] {
        "PF" => 3,
        "Pf" => 1,
        other => return Err(format!("not a PFM file (magic \"{other}\")")),
    };
    let parse_dim = |s: &str| -> Result<usize, String> {
        s.parse::<usize>()
            .ok()
            .filter(|&v| v > 0)
            .ok_or_else(|| format!("bad PFM size \"{s}\""))
    };
    let width = parse_dim(words[1])?;
    let height = parse_dim(words[2])?;
    let scale: f32 = words[3]
        .parse()
        .map_err(|_| format!("bad PFM scale \"{}\"", words[3]))?;
    let little_endian = scale < 0.0;
    let abs_scale = scale.abs();
    let n = width
        .checked_mul(height)
        .and_then(|v| v.checked_mul(channels))
        .filter(|&n| n <= 3 * MAX_IMAGE_PIXELS)
        .ok_or("PFM too large")?;
    let raster = data.get(pos..).unwrap_or(&[]);
    // n <= 3 * 2^28, so 4 * n cannot overflow.
    if raster.len() < 4 * n {
        return Err(format!(
            "truncated PFM raster: {} bytes for {width}x{height}x{channels} floats",
            raster.len()
        ));
    }
    let value = |i: usize| -> f32 {
        let b = [
            raster[4 * i],
            raster[4 * i + 1],
            raster[4 * i + 2],
            raster[4 * i + 3],
        ];
        let v = if little_endian {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        };
        if abs_scale != 1.0 && abs_scale != 0.0 {
            v * abs_scale
        } else {
            v
        }
    };
    let mut img = RgbImage::new(width, height);
    for file_row in 0..height {
        // The file's first row is the image's bottom row.
        let y = height - 1 - file_row;
        for x in 0..width {
            let i = (file_row * width + x) * channels;
            let c = if channels == 3 {
                Spectrum::new(value(i), value(i + 1), value(i + 2))
            } else {
                Spectrum::splat(value(i))
            };
            img.set(x, y, c);
        }
    }
    Ok(img)
}

/// Where an image lies in a larger frame: a crop of a `width` x `height` image whose top-left
/// pixel is (`x0`, `y0`). An EXR carries it as its display window (the frame) and data window
/// (the crop), as OpenEXR and pbrt-v4 do, so that an assembler can place the crop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Frame {
    /// The whole image's width.
    pub width: usize,
    /// The whole image's height.
    pub height: usize,
    /// The crop's first column.
    pub x0: usize,
    /// The crop's first row.
    pub y0: usize,
}

/// Writes `img`, a crop placed in `frame` (EXR keeps the placement; PNG and PFM hold the crop
/// alone).
pub fn write_image_in_frame(path: &Path, img: &RgbImage, frame: Frame) -> Result<(), String> {
    if is_exr(path) && img.pixels.len() == img.width * img.height {
        return write_exr_in(path, img, Some(frame));
    }
    write_image(path, img)
}

/// Reads an EXR and where it lies in its frame (its data window within its display window);
/// other formats are their own frame.
pub fn read_image_with_frame(path: &Path) -> Result<(RgbImage, Frame), String> {
    let format = image_format(path)?;
    decode_image_with_frame(&read_image_file(path)?, format)
}

/// Decodes an image file's bytes in `format` and where it lies in its frame, as
/// [`read_image_with_frame`] does.
pub fn decode_image_with_frame(data: &[u8], format: &str) -> Result<(RgbImage, Frame), String> {
    let img = decode_image(data, format, false)?;
    let mut frame = Frame {
        width: img.width,
        height: img.height,
        x0: 0,
        y0: 0,
    };
    if format == "exr" {
        let meta = exr_header(data)?;
        if let Some(h) = meta.headers.first() {
            let display = h.shared_attributes.display_window;
            let pos = h.own_attributes.layer_position;
            let (dx, dy) = (
                pos.x() - display.position.x(),
                pos.y() - display.position.y(),
            );
            if dx < 0 || dy < 0 {
                return Err(format!(
                    "its data window starts outside its display window ({dx}, {dy})"
                ));
            }
            frame = Frame {
                width: display.size.width(),
                height: display.size.height(),
                x0: dx as usize,
                y0: dy as usize,
            };
        }
    }
    if frame.x0 + img.width > frame.width || frame.y0 + img.height > frame.height {
        return Err("its data window reaches beyond its display window".to_owned());
    }
    Ok((img, frame))
}

/// Writes an image, choosing the format by extension: `.exr` (linear 32-bit float RGB), `.png`
/// (8-bit sRGB: clamped to [0, 1], encoded, rounded, as pbrt-v3 writes it) or `.pfm` (linear
/// 32-bit float RGB, little-endian).
pub fn write_image(path: &Path, img: &RgbImage) -> Result<(), String> {
    if img.pixels.len() != img.width * img.height {
        return Err(format!(
            "image has {} pixels, not {}x{}",
            img.pixels.len(),
            img.width,
            img.height
        ));
    }
    match extension(path).as_str() {
        "exr" => write_exr(path, img),
        "png" => write_png(path, img),
        "pfm" => write_pfm(path, img),
        other => Err(format!(
            "cannot write image format \"{other}\" (acr writes .exr, .png and .pfm)"
        )),
    }
}

fn write_exr(path: &Path, img: &RgbImage) -> Result<(), String> {
    write_exr_in(path, img, None)
}

/// An EXR of `img`, placed in `frame` when given (display window the frame, data window the
/// crop).
fn write_exr_in(path: &Path, img: &RgbImage, frame: Option<Frame>) -> Result<(), String> {
    use exr::prelude::*;
    // Tiles are compressed on several threads; an increasing line order makes the writer put
    // them in the file in order, so the bytes do not depend on which thread finishes first
    // (exr's default, unspecified order, writes them as they come).
    let encoding = Encoding {
        line_order: LineOrder::Increasing,
        ..Encoding::FAST_LOSSLESS
    };
    let channels = SpecificChannels::rgb(|Vec2(x, y)| {
        let c = img.get(x, y);
        (c.x, c.y, c.z)
    });
    let Some(f) = frame else {
        return Image::from_encoded_channels((img.width, img.height), encoding, channels)
            .write()
            .to_file(path)
            .map_err(|e| e.to_string());
    };
    let attributes = LayerAttributes {
        layer_position: Vec2(f.x0 as i32, f.y0 as i32),
        ..LayerAttributes::default()
    };
    let layer = Layer::new((img.width, img.height), attributes, encoding, channels);
    let display = IntegerBounds::new((0, 0), (f.width, f.height));
    Image::new(ImageAttributes::new(display), layer)
        .write()
        .to_file(path)
        .map_err(|e| e.to_string())
}

/// pbrt-v3's 8-bit conversion: `Clamp(255 * GammaCorrect(v) + 0.5, 0, 255)`, truncated.
#[inline]
pub fn to_srgb8(v: f32) -> u8 {
    (255.0 * linear_to_srgb(v) + 0.5).clamp(0.0, 255.0) as u8
}

fn write_png(path: &Path, img: &RgbImage) -> Result<(), String> {
    let mut bytes = Vec::with_capacity(3 * img.pixels.len());
    for c in &img.pixels {
        bytes.extend_from_slice(&[to_srgb8(c.x), to_srgb8(c.y), to_srgb8(c.z)]);
    }
    let buf = image::RgbImage::from_raw(img.width as u32, img.height as u32, bytes)
        .ok_or("image size mismatch")?;
    buf.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| e.to_string())
}

fn write_pfm(path: &Path, img: &RgbImage) -> Result<(), String> {
    let mut out = Vec::with_capacity(32 + 12 * img.pixels.len());
    write!(out, "PF\n{} {}\n-1.000000\n", img.width, img.height).map_err(|e| e.to_string())?;
    for y in (0..img.height).rev() {
        for x in 0..img.width {
            let c = img.get(x, y);
            for v in [c.x, c.y, c.z] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, out).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// A fresh directory under the system's temporary one, removed when dropped.
    struct TempDir(PathBuf);

    impl TempDir {
        fn new(tag: &str) -> Self {
            let dir = std::env::temp_dir().join(format!(
                "acr-image-io-{tag}-{}-{:?}",
                std::process::id(),
                std::thread::current().id()
            ));
            std::fs::create_dir_all(&dir).unwrap();
            Self(dir)
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            std::fs::remove_dir_all(&self.0).ok();
        }
    }

    fn gradient(w: usize, h: usize) -> RgbImage {
        let mut img = RgbImage::new(w, h);
        for y in 0..h {
            for x in 0..w {
                img.set(
                    x,
                    y,
                    Spectrum::new(
                        x as f32 * 0.37 + 0.01,
                        y as f32 * 1.5 + 0.25,
                        (x * 7 + y * 3) as f32 * 0.013,
                    ),
                );
            }
        }
        img
    }

    /// A 1 KB EXR (found by the `merge` fuzz target) whose header claims a 1 GB image: refused
    /// from its header, before the pixels are allocated.
    #[test]
    fn an_exr_claiming_more_than_its_file_can_hold_is_refused_before_allocating() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fuzz/regressions/merge/huge-claimed-size.exr");
        let data = std::fs::read(path).unwrap();
        assert!(data.len() < 10_000);
        let e = decode_image(&data, "exr", false).unwrap_err();
        assert!(e.contains("more than a file of"), "{e}");
    }

    /// A 918-byte EXR (found by the `merge` fuzz target) whose header claims blocks of 2 GB,
    /// which the EXR reader allocates whole: refused from its header.
    #[test]
    fn an_exr_claiming_huge_blocks_is_refused_before_allocating() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fuzz/regressions/merge/huge-claimed-block.exr");
        let data = std::fs::read(path).unwrap();
        let e = decode_image(&data, "exr", false).unwrap_err();
        assert!(e.contains("more than a file of"), "{e}");
    }

    #[test]
    fn exr_round_trips_exactly() {
        let dir = TempDir::new("exr");
        let img = gradient(5, 3);
        let path = dir.0.join("a.exr");
        write_image(&path, &img).unwrap();
        assert_eq!(read_image(&path, true).unwrap(), img);
    }

    /// The same image gives the same bytes: tiles are compressed on several threads, and the
    /// file must not depend on which finishes first (a 320x240 render's EXR differed from run
    /// to run in its tile order before).
    #[test]
    fn exr_files_are_the_same_bytes_every_time() {
        let dir = TempDir::new("exr-same");
        let mut img = gradient(700, 500);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            // Noise makes the tiles' compression times differ.
            let h = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
            *p += Spectrum::splat(h as f32 / (1u64 << 24) as f32);
        }
        let first = dir.0.join("0.exr");
        write_image(&first, &img).unwrap();
        let want = std::fs::read(&first).unwrap();
        for k in 1..8 {
            let path = dir.0.join(format!("{k}.exr"));
            write_image(&path, &img).unwrap();
            assert!(std::fs::read(&path).unwrap() == want, "write {k} differs");
        }
        assert_eq!(read_image(&first, false).unwrap(), img);
    }

    #[test]
    fn exr_half_rgba_reads_as_linear_rgb() {
        use exr::prelude::*;
        let dir = TempDir::new("exr-half");
        let path = dir.0.join("h.exr");
        write_rgba_file(&path, 2, 2, |x, y| {
            (
                f16::from_f32(x as f32 + 0.5),
                f16::from_f32(y as f32),
                f16::from_f32(0.25),
                f16::from_f32(1.0),
            )
        })
        .unwrap();
        let img = read_image(&path, false).unwrap();
        assert_eq!((img.width, img.height), (2, 2));
        assert_eq!(img.get(1, 0), Spectrum::new(1.5, 0.0, 0.25));
        assert_eq!(img.get(0, 1), Spectrum::new(0.5, 1.0, 0.25));
    }

    #[test]
    fn pfm_round_trips_and_reads_both_byte_orders() {
        let dir = TempDir::new("pfm");
        let img = gradient(4, 3);
        let path = dir.0.join("a.pfm");
        write_image(&path, &img).unwrap();
        assert_eq!(read_image(&path, false).unwrap(), img);

        // Big-endian grey, scale 2, rows bottom to top.
        let mut data = b"Pf\n2 2\n2.0\n".to_vec();
        for v in [1.0f32, 2.0, 3.0, 4.0] {
            data.extend_from_slice(&v.to_be_bytes());
        }
        let grey = parse_pfm(&data).unwrap();
        assert_eq!(grey.get(0, 1), Spectrum::splat(2.0));
        assert_eq!(grey.get(1, 1), Spectrum::splat(4.0));
        assert_eq!(grey.get(0, 0), Spectrum::splat(6.0));
        assert_eq!(grey.get(1, 0), Spectrum::splat(8.0));
        assert!(parse_pfm(b"PF\n2 2\n-1.0\n\0\0").is_err());
        assert!(parse_pfm(b"P6\n2 2\n255\n").is_err());
    }

    #[test]
    fn png_round_trips_8_bit_srgb() {
        let dir = TempDir::new("png");
        let mut img = RgbImage::new(16, 16);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            let v = |k: usize| srgb_to_linear(((i * k) % 256) as f32 / 255.0);
            *p = Spectrum::new(v(1), v(3), v(7));
        }
        let path = dir.0.join("a.png");
        write_image(&path, &img).unwrap();
        let back = read_image(&path, true).unwrap();
        assert_eq!((back.width, back.height), (16, 16));
        for (a, b) in img.pixels.iter().zip(&back.pixels) {
            assert!((*a - *b).abs().max_element() < 1e-5, "{a} {b}");
        }
        // Without decoding, the stored sRGB values come back.
        let raw = read_image(&path, false).unwrap();
        assert!((raw.get(1, 0).y - 3.0 / 255.0).abs() < 1e-6);
        // Out-of-range values clamp; NaN writes as 0.
        let mut hot = RgbImage::new(1, 1);
        hot.set(0, 0, Spectrum::new(7.0, -1.0, f32::NAN));
        write_image(&path, &hot).unwrap();
        assert_eq!(
            read_image(&path, false).unwrap().get(0, 0),
            Spectrum::new(1.0, 0.0, 0.0)
        );
    }

    #[test]
    fn png_16_bit_and_grey_read() {
        let dir = TempDir::new("png16");
        let path = dir.0.join("g.png");
        let buf = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(2, 1, vec![0, 65535])
            .unwrap();
        buf.save(&path).unwrap();
        let img = read_image(&path, true).unwrap();
        assert_eq!(img.get(0, 0), Spectrum::ZERO);
        assert!((img.get(1, 0) - Spectrum::ONE).abs().max_element() < 1e-6);
    }

    #[test]
    fn hdr_reads() {
        let dir = TempDir::new("hdr");
        let path = dir.0.join("a.hdr");
        let buf =
            image::Rgb32FImage::from_raw(2, 1, vec![0.5, 1.0, 2.0, 4.0, 0.25, 0.125]).unwrap();
        image::DynamicImage::ImageRgb32F(buf).save(&path).unwrap();
        let img = read_image(&path, true).unwrap();
        // RGBE keeps 8 bits of mantissa per channel.
        assert!(
            (img.get(0, 0) - Spectrum::new(0.5, 1.0, 2.0))
                .abs()
                .max_element()
                < 0.02
        );
        assert!(
            (img.get(1, 0) - Spectrum::new(4.0, 0.25, 0.125))
                .abs()
                .max_element()
                < 0.05
        );
    }

    #[test]
    fn unknown_formats_are_errors() {
        let img = RgbImage::new(1, 1);
        assert!(write_image(Path::new("/nonexistent/a.tga"), &img).is_err());
        assert!(read_image(Path::new("/nonexistent/a.tga"), false).is_err());
        assert!(read_image(Path::new("/nonexistent/a.exr"), false).is_err());
    }
}
