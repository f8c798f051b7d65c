//! The output file of `acr render`: the image alone, or a mergeable EXR (`mergeable.rs`), with
//! AOVs as channels beside R, G, B (pbrt-v4's GBuffer names), written through a temporary file
//! and a rename so that no reader sees half a file, at the end and as partial images.

use crate::cli::aov::AovRequest;
use crate::cli::mergeable::Sums;
use crate::exr_channels::{Attribute, Channels};
use crate::first_hit::FeatureImage;
use crate::geometry::Spectrum;
use crate::image_io::{is_exr, write_image_in_frame, Frame, RgbImage};
use acr_plugins::{Film, PixelStats};
use std::path::{Path, PathBuf};

/// The AOVs that can be channels of the output EXR, and their channel names (pbrt-v4's
/// `GBufferFilm` names where it has the quantity; `Z` is OpenEXR's depth channel).
pub const CHANNEL_AOVS: &[(&str, [&str; 3])] = &[
    ("albedo", ["Albedo.R", "Albedo.G", "Albedo.B"]),
    ("normal", ["Ns.X", "Ns.Y", "Ns.Z"]),
    ("depth", ["Z", "", ""]),
    ("spp", ["count", "", ""]),
    ("variance", ["Variance.R", "Variance.G", "Variance.B"]),
];

/// Where and how the render's image is written.
pub struct Output {
    /// The file.
    pub path: PathBuf,
    /// Where the film's crop lies in the frame.
    pub frame: Frame,
    /// The film's crop size.
    pub size: (usize, usize),
    /// The film's scale, applied on output.
    pub scale: f32,
    /// Whether the final file is mergeable (`--mergeable`).
    pub mergeable: bool,
    /// Whether the film's sums can be merged at all: a splatting filter, one sample stream,
    /// an EXR output. Partial images and a render stopped by a signal are then mergeable.
    pub can_merge: bool,
    /// The first sample index (`--sample-offset`).
    pub offset: u32,
    /// AOVs written as channels of this file.
    pub channel_aovs: Vec<String>,
    /// [`scene_hash`] of the scene rendered, written as the `sceneHash` attribute of an EXR.
    pub scene: i32,
    /// The whole render's samples per pixel that set the texture footprint, written as the
    /// `footprintSpp` attribute of a mergeable EXR when the scene's textures read it.
    pub footprint: Option<u32>,
}

/// A hash of the scene's text (its .pbrt files, FNV-1a folded to 32 bits), so that `acr
/// merge` can tell renders of different scenes apart.
pub fn scene_hash(desc: &acr_parser::SceneDescription) -> i32 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for f in &desc.files {
        for &b in f.text().as_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    ((h >> 32) ^ h) as u32 as i32
}

impl Output {
    /// Whether `aov` goes into this file as channels (no file of its own, or this file).
    pub fn holds(&self, aov: &AovRequest) -> bool {
        aov.path.as_os_str().is_empty() || aov.path == self.path
    }

    /// The film's sums as a mergeable file holds them, `spp` samples per pixel.
    pub fn sums(&self, film: &Film, spp: u32, seconds: f64) -> Result<Sums, String> {
        let scale = f64::from(self.scale);
        let sums = film
            .weighted_sums()
            .ok_or("the film has no sums to merge")?;
        // A film that counts its pixels' samples alone has no moments to write.
        let stats = film.keeps_moments().then(|| film.pixel_stats());
        Ok(Sums {
            frame: self.frame,
            width: self.size.0,
            height: self.size.1,
            sums: sums
                .iter()
                .map(|s| [s[0] * scale, s[1] * scale, s[2] * scale, s[3]])
                .collect(),
            counts: film.pixel_counts().iter().map(|&n| f64::from(n)).collect(),
            moments: stats.map(|stats| {
                stats
                    .iter()
                    .map(|p| {
                        let (m, q) = (p.sum(), p.sum_sq());
                        let s2 = scale * scale;
                        [
                            m[0] * scale,
                            m[1] * scale,
                            m[2] * scale,
                            q[0] * s2,
                            q[1] * s2,
                            q[2] * s2,
                        ]
                    })
                    .collect()
            }),
            aovs: Vec::new(),
            spp,
            offset: Some(self.offset),
            scene: Some(self.scene),
            footprint: self.footprint,
            seconds,
            splats: (!film.unfiltered().sums().is_empty()).then(|| {
                film.unfiltered()
                    .sums()
                    .iter()
                    .map(|s| s.map(|v| v * scale))
                    .collect()
            }),
            // The film scales its splats by full-film pixels over light subpaths traced; written
            // with the splats only, so that other integrators' files stay as they were.
            splat_spp: (!film.unfiltered().sums().is_empty() && film.unfiltered().scale() > 0.0)
                .then(|| 1.0 / film.unfiltered().scale()),
        })
    }

    /// The image so far, mid-render: a mergeable EXR of the passes done when the sums can be
    /// merged (samplesPerPixel: the fewest samples any pixel has), else the splatted image.
    pub fn write_partial(&self, film: &Film, seconds: f64) -> Result<(), String> {
        let spp = reached_spp(&film.pixel_counts());
        if self.can_merge {
            let sums = self.sums(film, spp, seconds)?;
            return self.atomically(|temp| sums.write(temp));
        }
        let image: Vec<Spectrum> = film
            .with_splats(film.pixels())
            .into_iter()
            .map(|c| c * self.scale)
            .collect();
        self.write_image(&image, Vec::new(), spp)
    }

    /// Whether the final file holds the film's sums (a mergeable file): when asked, or when a
    /// signal stopped a render whose sums can be merged.
    pub fn writes_sums(&self, signalled: bool) -> bool {
        self.mergeable || (signalled && self.can_merge)
    }

    /// The final file: `image` (the reconstruction, scaled) and, in an EXR, the channel AOVs;
    /// mergeable when asked or when the render was stopped by a signal and can be merged.
    /// `spp` is what each pixel was planned to get; a halted render records what it reached.
    pub fn write_final(&self, image: &[Spectrum], film: &Film, end: &End) -> Result<(), String> {
        let mut aovs = Vec::new();
        if !self.channel_aovs.is_empty() {
            // Computed once: with half buffers every call makes the whole image's statistics.
            let stats = film.pixel_stats();
            for name in &self.channel_aovs {
                aovs.extend(channel_values(name, &stats, self.scale, end.features)?);
            }
        }
        let spp = if end.halted {
            reached_spp(&film.pixel_counts())
        } else {
            end.spp
        };
        if self.writes_sums(end.signalled) {
            let mut sums = self.sums(film, spp, end.seconds)?;
            // What the sums already hold is not written twice.
            aovs.retain(|(n, _)| {
                !matches!(
                    n.as_str(),
                    "count" | "Variance.R" | "Variance.G" | "Variance.B"
                )
            });
            sums.aovs = aovs;
            return self.atomically(|temp| sums.write(temp));
        }
        self.write_image(image, aovs, spp)
    }

    /// Writes `image`: in an EXR with the channel AOVs and the attributes, else alone.
    fn write_image(
        &self,
        image: &[Spectrum],
        aovs: Vec<(String, Vec<f32>)>,
        spp: u32,
    ) -> Result<(), String> {
        if !is_exr(&self.path) {
            let rgb = RgbImage {
                width: self.size.0,
                height: self.size.1,
                pixels: image.to_vec(),
            };
            return self.atomically(|temp| write_image_in_frame(temp, &rgb, self.frame));
        }
        let mut layer = Channels::new(self.frame, self.size.0, self.size.1);
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            layer.push(name, image.iter().map(|p| p[c]).collect());
        }
        layer.channels.extend(aovs);
        // No render time here: the same scene, seed and budget give the same file, byte for
        // byte (a mergeable file, which needs it, has it).
        layer.attributes = vec![
            (
                "samplesPerPixel".into(),
                Attribute::Int(spp.min(i32::MAX as u32) as i32),
            ),
            ("sceneHash".into(), Attribute::Int(self.scene)),
        ];
        self.atomically(|temp| layer.write(temp))
    }

    /// Writes through a temporary file in the same folder and a rename, so that a reader (or a
    /// kill mid-write) never sees half a file.
    fn atomically(&self, write: impl FnOnce(&Path) -> Result<(), String>) -> Result<(), String> {
        let output = &self.path;
        let name = output
            .file_name()
            .map_or_else(|| "image".into(), |n| n.to_string_lossy().into_owned());
        let ext = output
            .extension()
            .map_or_else(String::new, |e| e.to_string_lossy().into_owned());
        let temp = output.with_file_name(format!(".{name}.{}.partial.{ext}", std::process::id()));
        write(&temp).map_err(|e| format!("{}: {e}", temp.display()))?;
        std::fs::rename(&temp, output).map_err(|e| {
            let _ = std::fs::remove_file(&temp);
            format!("{}: cannot write: {e}", output.display())
        })
    }
}

/// How the render ended, for the final file.
pub struct End<'a> {
    /// Samples per pixel planned.
    pub spp: u32,
    /// Whether the render stopped before its budget.
    pub halted: bool,
    /// Whether a signal stopped it.
    pub signalled: bool,
    /// Render seconds.
    pub seconds: f64,
    /// The first-hit features, when collected.
    pub features: Option<&'a FeatureImage>,
}

/// The samples every pixel has: the fewest any pixel has.
pub fn reached_spp(counts: &[u32]) -> u32 {
    counts.iter().copied().min().unwrap_or(0)
}

/// The channels of AOV `name`, by [`CHANNEL_AOVS`]'s names (the variance in the units of the
/// image, scaled by the film's `scale` squared).
fn channel_values(
    name: &str,
    stats: &[PixelStats],
    scale: f32,
    features: Option<&FeatureImage>,
) -> Result<Vec<(String, Vec<f32>)>, String> {
    let Some((_, names)) = CHANNEL_AOVS.iter().find(|(n, _)| *n == name) else {
        return Err(format!(
            "--aov {name}: cannot be a channel of the output (give it a file of its own)"
        ));
    };
    let values: Vec<Spectrum> = match name {
        "spp" => stats
            .iter()
            .map(|s| Spectrum::splat(s.count as f32))
            .collect(),
        "variance" => stats
            .iter()
            .map(|p| sample_variance(p) * (scale * scale))
            .collect(),
        _ => features
            .ok_or_else(|| format!("--aov {name}: no features were collected"))?
            .image(name),
    };
    Ok(names
        .iter()
        .enumerate()
        .filter(|(_, n)| !n.is_empty())
        .map(|(c, n)| ((*n).to_owned(), values.iter().map(|v| v[c]).collect()))
        .collect())
}

/// The variance of a pixel's samples (pbrt-v4's `Variance` channel), 0 below two samples.
fn sample_variance(p: &PixelStats) -> Spectrum {
    p.variance_of_mean() * p.count as f32
}
