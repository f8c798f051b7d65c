//! Arbitrary output variables (`--aov NAME=FILE`): per-pixel images beside the render. `spp` is
//! the number of samples each pixel received, `variance` the variance of each pixel's mean.
//! An `.exr` (or `.pfm`) holds the values themselves; a `.png` a false-colour picture scaled
//! by the largest value, which is written into the PNG (a tEXt chunk) and printed. `clusters`
//! is the cluster sampler's final partition: in a PNG each cluster a colour with its borders
//! drawn dark (the paper's figures 2 and 4), in an EXR each pixel's cluster id. `albedo`,
//! `normal` and `depth` are the means of each pixel's first-hit features (`first_hit.rs`), linear
//! in an EXR or PFM, as Open Image Denoise's tools read them.

use crate::first_hit::FeatureImage;
use crate::geometry::Spectrum;
use crate::image_io::{write_image, RgbImage};
use acr_plugins::{Partition, PixelStats};
use std::path::{Path, PathBuf};

/// The AOVs acr writes.
pub const AOV_NAMES: &[&str] = &[
    "spp",
    "variance",
    "clusters",
    "fitclusters",
    "albedo",
    "normal",
    "depth",
];

/// The AOVs made of first-hit features (the render collects them only when one is asked for).
pub const FEATURE_AOVS: &[&str] = &["albedo", "normal", "depth"];

/// One requested AOV.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AovRequest {
    /// Which (`spp`, `variance`, `clusters`).
    pub name: String,
    /// Where to write it.
    pub path: PathBuf,
}

impl AovRequest {
    /// Whether this AOV is made of first-hit features.
    pub fn is_feature(&self) -> bool {
        FEATURE_AOVS.contains(&self.name.as_str())
    }

    /// The file's extension, lower case ("" when none): it picks the format.
    fn extension(&self) -> String {
        self.path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase()
    }
}

/// Parses `NAME[=FILE][,NAME[=FILE]...]` as `--aov` takes it; a NAME without a file (an
/// empty path) goes into the output EXR as channels.
pub fn parse_aovs(arg: &str) -> Result<Vec<AovRequest>, String> {
    arg.split(',')
        .map(|part| {
            // A NAME alone is a channel of the output EXR.
            let (name, file) = part.split_once('=').unwrap_or((part, ""));
            let name = name.trim();
            if !AOV_NAMES.contains(&name) {
                let hint = acr_parser::closest(name, AOV_NAMES.iter().copied())
                    .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
                return Err(format!(
                    "--aov: unknown AOV \"{name}\"{hint}; known: {}",
                    AOV_NAMES.join(", ")
                ));
            }
            if file.is_empty() && part.contains('=') {
                return Err(format!("--aov {name}: the file name is empty"));
            }
            let req = AovRequest {
                name: name.to_owned(),
                path: PathBuf::from(file),
            };
            if req.is_feature()
                && !file.is_empty()
                && !matches!(req.extension().as_str(), "exr" | "pfm")
            {
                return Err(format!(
                    "--aov {name}: \"{file}\" must be an .exr or .pfm (linear values, as \
                     denoisers read them)"
                ));
            }
            Ok(req)
        })
        .collect()
}

/// The per-pixel values of AOV `name` (one value per channel for `variance`).
pub fn aov_values(name: &str, stats: &[PixelStats]) -> Vec<Spectrum> {
    match name {
        "spp" => stats
            .iter()
            .map(|s| Spectrum::splat(s.count as f32))
            .collect(),
        _ => stats.iter().map(PixelStats::variance_of_mean).collect(),
    }
}

/// Writes AOV `name` of a `width` x `height` film; returns a line saying what was written
/// (with the false-colour scale for a PNG).
pub fn write_aov(
    req: &AovRequest,
    width: usize,
    height: usize,
    stats: &[PixelStats],
    partition: Option<&Partition>,
    fit_partition: Option<&Partition>,
    features: Option<&FeatureImage>,
) -> Result<String, String> {
    if req.name == "clusters" {
        let p = partition.ok_or("--aov clusters: the sampler made no clusters")?;
        return write_clusters(req, p);
    }
    if req.name == "fitclusters" {
        let p = fit_partition.ok_or("--aov fitclusters: the filter fitted no clusters")?;
        return write_clusters(req, p);
    }
    let values = if req.is_feature() {
        let f =
            features.ok_or_else(|| format!("--aov {}: no features were collected", req.name))?;
        f.image(&req.name)
    } else {
        aov_values(&req.name, stats)
    };
    let ext = req.extension();
    if ext != "png" {
        write_image(
            &req.path,
            &RgbImage {
                width,
                height,
                pixels: values,
            },
        )
        .map_err(|e| format!("{}: {e}", req.path.display()))?;
        return Ok(format!("{} AOV -> {}", req.name, req.path.display()));
    }
    // A scalar per pixel: the count, or the luminance of the variance.
    let scalar: Vec<f32> = values
        .iter()
        .map(|v| {
            if req.name == "spp" {
                v.x
            } else {
                crate::spectrum_luminance(*v)
            }
        })
        .collect();
    let max = scalar.iter().copied().fold(0.0f32, f32::max);
    let unit = if req.name == "spp" {
        "samples per pixel"
    } else {
        "variance of the pixel mean (luminance)"
    };
    let scale = format!("false colour from black (0) to white ({max} {unit})");
    write_false_colour(&req.path, width, height, &scalar, max, &scale)
        .map_err(|e| format!("{}: {e}", req.path.display()))?;
    Ok(format!(
        "{} AOV -> {}: {scale}",
        req.name,
        req.path.display()
    ))
}

/// A colour for cluster `id`: hue from a hash of the id, bright enough to show dark borders.
pub fn cluster_colour(id: u32) -> [u8; 3] {
    let h = acr_plugins::rng::mix64(u64::from(id) ^ 0x5eed);
    let hue = (h % 3600) as f32 / 600.0;
    let (sat, val) = (
        0.45 + (h >> 20 & 0xff) as f32 / 255.0 * 0.5,
        0.75 + (h >> 28 & 0xff) as f32 / 255.0 * 0.25,
    );
    let c = val * sat;
    let x = c * (1.0 - (hue % 2.0 - 1.0).abs());
    let (r, g, b) = match hue as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = val - c;
    [r, g, b].map(|v| ((v + m) * 255.0 + 0.5) as u8)
}

/// Writes the partition: a PNG of cluster colours with borders, or the ids as values.
fn write_clusters(req: &AovRequest, p: &Partition) -> Result<String, String> {
    let (w, h) = (p.width as usize, p.height as usize);
    let ext = req.extension();
    let count = p.clusters();
    if ext != "png" {
        let pixels = p
            .cluster
            .iter()
            .map(|&c| Spectrum::splat(c as f32))
            .collect();
        write_image(
            &req.path,
            &RgbImage {
                width: w,
                height: h,
                pixels,
            },
        )
        .map_err(|e| format!("{}: {e}", req.path.display()))?;
        return Ok(format!(
            "clusters AOV -> {}: {count} cluster ids",
            req.path.display()
        ));
    }
    let mut bytes = Vec::with_capacity(3 * w * h);
    for y in 0..h {
        for x in 0..w {
            let c = p.cluster[y * w + x];
            // A pixel on a border with its right or lower neighbour is drawn dark.
            let border = (x + 1 < w && p.cluster[y * w + x + 1] != c)
                || (y + 1 < h && p.cluster[(y + 1) * w + x] != c);
            let rgb = if border {
                cluster_colour(c).map(|v| v / 4)
            } else {
                cluster_colour(c)
            };
            bytes.extend_from_slice(&rgb);
        }
    }
    let text = format!("{count} clusters, borders dark");
    write_png(&req.path, w, h, &bytes, &text)
        .map_err(|e| format!("{}: {e}", req.path.display()))?;
    Ok(format!("clusters AOV -> {}: {text}", req.path.display()))
}

/// The false-colour map: black, blue, magenta, orange, yellow, white (like "inferno"), at
/// `t` in [0, 1].
pub fn false_colour(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 6] = [
        [0.0, 0.0, 0.0],
        [0.12, 0.05, 0.45],
        [0.55, 0.1, 0.5],
        [0.9, 0.35, 0.1],
        [0.98, 0.8, 0.15],
        [1.0, 1.0, 1.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f32;
    let i = (x as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    std::array::from_fn(|c| ((a[c] + (b[c] - a[c]) * f) * 255.0 + 0.5) as u8)
}

fn write_false_colour(
    path: &Path,
    width: usize,
    height: usize,
    values: &[f32],
    max: f32,
    scale: &str,
) -> Result<(), String> {
    let mut bytes = Vec::with_capacity(3 * values.len());
    for &v in values {
        let t = if max > 0.0 { v / max } else { 0.0 };
        bytes.extend_from_slice(&false_colour(t));
    }
    write_png(path, width, height, &bytes, scale)
}

/// An 8-bit RGB PNG with an `acr-scale` tEXt chunk saying what the colours mean.
fn write_png(
    path: &Path,
    width: usize,
    height: usize,
    bytes: &[u8],
    scale: &str,
) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width as u32, height as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.add_text_chunk("acr-scale".to_owned(), scale.to_owned())
        .map_err(|e| e.to_string())?;
    let mut w = enc.write_header().map_err(|e| e.to_string())?;
    w.write_image_data(bytes).map_err(|e| e.to_string())?;
    w.finish().map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_requests() {
        let r = parse_aovs("spp=a.png,variance=b.exr").unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[1].name, "variance");
        assert_eq!(r[1].path, PathBuf::from("b.exr"));
        let e = parse_aovs("sp=a.png").unwrap_err();
        assert!(e.contains("did you mean \"spp\""), "{e}");
        // A name alone is a channel of the output: an empty path.
        let r = parse_aovs("spp,albedo").unwrap();
        assert!(r.iter().all(|a| a.path.as_os_str().is_empty()));
        assert!(parse_aovs("spp=").is_err());
        assert!(parse_aovs("albedo=a.png").is_err());
    }

    #[test]
    fn cluster_colours_differ_and_show_borders() {
        let colours: std::collections::HashSet<[u8; 3]> = (0..64).map(cluster_colour).collect();
        assert!(colours.len() >= 60);
        for id in 0..64 {
            let c = cluster_colour(id);
            // Bright: a border at a quarter of it stands out.
            assert!(c.iter().copied().max().unwrap_or(0) >= 180, "{id}: {c:?}");
        }
    }

    #[test]
    fn false_colour_runs_black_to_white() {
        assert_eq!(false_colour(0.0), [0, 0, 0]);
        assert_eq!(false_colour(1.0), [255, 255, 255]);
        assert_eq!(false_colour(f32::NAN), [0, 0, 0]);
        // Brighter with the value.
        let lum = |c: [u8; 3]| c.iter().map(|&v| u32::from(v)).sum::<u32>();
        let mut last = 0;
        for i in 0..=20 {
            let l = lum(false_colour(i as f32 / 20.0));
            assert!(l >= last, "{i}");
            last = l;
        }
    }
}
