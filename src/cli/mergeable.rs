//! Mergeable EXRs: beside the image (R, G, B), each pixel's filter-weighted radiance sums
//! (`sum.R`, `sum.G`, `sum.B`, times the film's scale), its filter-weight sum (`weight`), its
//! sample count (`count`) and the variance moments of its samples (`moment1.*`, the sum of
//! their radiance, and `moment2.*`, of its square, unweighted and unscaled), with pbrt-v4's
//! header attributes `samplesPerPixel` and `renderTimeSeconds` and acr's `sampleOffset` (and
//! `footprintSpp` for a scene whose textures read the ray differentials).
//! Renders of different sample ranges of one frame add their sums, weights and moments: the
//! merge is the image of all their samples (Cycles' `merge_images`, weighted). `Variance.*`
//! (pbrt-v4's name and meaning: the variance of a pixel's samples) is written from the moments.

use crate::exr_channels::{Attribute, Channels};
use crate::image_io::Frame;
use std::path::Path;

/// What a mergeable EXR holds, for one crop of a frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sums {
    /// Where the crop lies.
    pub frame: Frame,
    /// Crop width.
    pub width: usize,
    /// Crop height.
    pub height: usize,
    /// Per pixel: weighted radiance sums (scaled) and the weight sum.
    pub sums: Vec<[f64; 4]>,
    /// Per pixel: samples drawn in it.
    pub counts: Vec<f64>,
    /// Per pixel: the sum of its samples' radiance and of its square, per channel (absent in
    /// files written before they were).
    pub moments: Option<Vec<[f64; 6]>>,
    /// AOV channels (first-hit features, cluster ids...), each a per-pixel mean over the
    /// pixel's samples: sample ranges merge them weighted by their counts.
    pub aovs: Vec<(String, Vec<f32>)>,
    /// Samples per pixel of the render(s).
    pub spp: u32,
    /// The first sample index, when known.
    pub offset: Option<u32>,
    /// A hash of the scene's text (`sceneHash`), when known: renders of other scenes do not
    /// merge.
    pub scene: Option<i32>,
    /// The whole render's samples per pixel that set its texture footprint (`footprintSpp`,
    /// `--footprint-spp`), when the scene has textures that read it: ranges rendered with
    /// other footprints are other images and do not merge.
    pub footprint: Option<u32>,
    /// Render seconds, summed over merged renders.
    pub seconds: f64,
    /// Per pixel: the unfiltered splats' sums (bdpt's light tracing; `splat.R`, `splat.G`,
    /// `splat.B`, times the film's scale), when any landed in the crop.
    pub splats: Option<Vec<[f64; 3]>>,
    /// The light subpaths traced per full-film pixel (`splatSpp`), by which the image divides
    /// the splat sums (docs/light-transport.md), when the render said.
    pub splat_spp: Option<f64>,
}

/// The channels [`Sums`] reads and writes itself; any other is an AOV.
const OWN_CHANNELS: &[&str] = &[
    "R",
    "G",
    "B",
    "sum.R",
    "sum.G",
    "sum.B",
    "weight",
    "count",
    "moment1.R",
    "moment1.G",
    "moment1.B",
    "moment2.R",
    "moment2.G",
    "moment2.B",
    "Variance.R",
    "Variance.G",
    "Variance.B",
    "splat.R",
    "splat.G",
    "splat.B",
];

impl Sums {
    /// The image: each pixel's weighted mean (0 where no weight, and never negative, as the
    /// film makes it), plus its splat sum over the light subpaths per full-film pixel.
    pub fn image(&self) -> Vec<[f32; 3]> {
        let splat_scale = match self.splat_spp {
            Some(n) if n > 0.0 => 1.0 / n,
            _ => 0.0,
        };
        self.sums
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let splat = self
                    .splats
                    .as_ref()
                    .map_or([0.0; 3], |p| p[i].map(|v| v * splat_scale));
                if s[3] == 0.0 {
                    return splat.map(|v| v as f32);
                }
                let inv = 1.0 / s[3];
                [0, 1, 2].map(|c| ((s[c] * inv) as f32).max(0.0) + splat[c] as f32)
            })
            .collect()
    }

    /// Each pixel's sample variance per channel (pbrt-v4's `Variance`), 0 below two samples.
    pub fn variance(&self) -> Option<Vec<[f32; 3]>> {
        let moments = self.moments.as_ref()?;
        Some(
            moments
                .iter()
                .zip(&self.counts)
                .map(|(m, &n)| {
                    if n < 2.0 {
                        return [0.0; 3];
                    }
                    [0, 1, 2].map(|c| ((m[3 + c] - m[c] * m[c] / n) / (n - 1.0)).max(0.0) as f32)
                })
                .collect(),
        )
    }

    /// The sample indices it holds, when known: [offset, offset + spp).
    pub fn range(&self) -> Option<std::ops::Range<u64>> {
        self.offset
            .map(|o| u64::from(o)..u64::from(o) + u64::from(self.spp))
    }

    /// Adds `other`'s samples (another sample range of the same crop). AOV channels both hold
    /// become their count-weighted mean; the others are dropped.
    pub fn add(&mut self, other: &Sums) -> std::result::Result<(), String> {
        if (self.frame, self.width, self.height) != (other.frame, other.width, other.height) {
            return Err("not the same crop of the same frame".to_owned());
        }
        if let (Some(a), Some(b)) = (self.scene, other.scene) {
            if a != b {
                return Err("rendered from another scene (its sceneHash differs)".to_owned());
            }
        }
        if self.footprint != other.footprint {
            let said = |f: Option<u32>| f.map_or("none".to_owned(), |n| n.to_string());
            return Err(format!(
                "rendered with another texture footprint (footprintSpp {} against {}): render \
                 every sample range with the same --footprint-spp, the whole render's spp",
                said(other.footprint),
                said(self.footprint)
            ));
        }
        self.aovs
            .retain(|(name, _)| other.aovs.iter().any(|(n, _)| n == name));
        for (name, values) in &mut self.aovs {
            let Some((_, theirs)) = other.aovs.iter().find(|(n, _)| n == name) else {
                continue;
            };
            for (i, v) in values.iter_mut().enumerate() {
                let (a, b) = (self.counts[i], other.counts[i]);
                if a + b > 0.0 {
                    *v = ((f64::from(*v) * a + f64::from(theirs[i]) * b) / (a + b)) as f32;
                }
            }
        }
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            for c in 0..4 {
                a[c] += b[c];
            }
        }
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
        self.moments = match (self.moments.take(), &other.moments) {
            (Some(mut m), Some(o)) => {
                for (a, b) in m.iter_mut().zip(o) {
                    for c in 0..6 {
                        a[c] += b[c];
                    }
                }
                Some(m)
            }
            _ => None,
        };
        self.add_splats(other)?;
        self.offset = match (self.range(), other.range()) {
            (Some(a), Some(b)) => Some(a.start.min(b.start) as u32),
            _ => None,
        };
        self.spp += other.spp;
        self.seconds += other.seconds;
        Ok(())
    }

    /// Adds `other`'s splat sums and light subpaths; a file without splat channels adds none
    /// but its subpaths still count.
    fn add_splats(&mut self, other: &Sums) -> std::result::Result<(), String> {
        let any = self.splats.is_some() || other.splats.is_some();
        self.splat_spp = match (self.splat_spp, other.splat_spp) {
            (Some(a), Some(b)) => Some(a + b),
            (None, None) => None,
            _ if any => {
                return Err(
                    "one file lacks splatSpp, the light subpaths behind its splats".to_owned(),
                )
            }
            _ => None,
        };
        self.splats = match (self.splats.take(), &other.splats) {
            (Some(mut a), Some(b)) => {
                for (x, y) in a.iter_mut().zip(b) {
                    for c in 0..3 {
                        x[c] += y[c];
                    }
                }
                Some(a)
            }
            (Some(a), None) => Some(a),
            (None, b) => b.clone(),
        };
        Ok(())
    }

    /// Writes the EXR: R, G, B, the sums, weight, count, moments and variance, the AOVs, and
    /// the attributes.
    pub fn write(&self, path: &Path) -> std::result::Result<(), String> {
        let n = self.width * self.height;
        let image = self.image();
        let mut layer = Channels::new(self.frame, self.width, self.height);
        let pick = |f: &dyn Fn(usize) -> f32| (0..n).map(f).collect::<Vec<f32>>();
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            layer.push(name, pick(&|i| image[i][c]));
        }
        for (c, name) in ["sum.R", "sum.G", "sum.B", "weight"]
            .into_iter()
            .enumerate()
        {
            layer.push(name, pick(&|i| self.sums[i][c] as f32));
        }
        layer.push("count", pick(&|i| self.counts[i] as f32));
        if let (Some(m), Some(var)) = (&self.moments, self.variance()) {
            for (c, rgb) in ["R", "G", "B"].into_iter().enumerate() {
                layer.push(&format!("moment1.{rgb}"), pick(&|i| m[i][c] as f32));
                layer.push(&format!("moment2.{rgb}"), pick(&|i| m[i][3 + c] as f32));
                layer.push(&format!("Variance.{rgb}"), pick(&|i| var[i][c]));
            }
        }
        if let Some(splats) = &self.splats {
            for (c, name) in ["splat.R", "splat.G", "splat.B"].into_iter().enumerate() {
                layer.push(name, pick(&|i| splats[i][c] as f32));
            }
        }
        for (name, values) in &self.aovs {
            layer.push(name, values.clone());
        }
        if let Some(n) = self.splat_spp {
            layer
                .attributes
                .push(("splatSpp".into(), Attribute::Float(n as f32)));
        }
        let spp = self.spp.min(i32::MAX as u32) as i32;
        layer
            .attributes
            .push(("samplesPerPixel".into(), Attribute::Int(spp)));
        layer.attributes.push((
            "renderTimeSeconds".into(),
            Attribute::Float(self.seconds as f32),
        ));
        if let Some(h) = self.scene {
            layer
                .attributes
                .push(("sceneHash".into(), Attribute::Int(h)));
        }
        if let Some(o) = self.offset {
            let o = o.min(i32::MAX as u32) as i32;
            layer
                .attributes
                .push(("sampleOffset".into(), Attribute::Int(o)));
        }
        if let Some(f) = self.footprint {
            let f = f.min(i32::MAX as u32) as i32;
            layer
                .attributes
                .push(("footprintSpp".into(), Attribute::Int(f)));
        }
        layer.write(path)
    }

    /// Reads a mergeable EXR; `None` when the file lacks the sums (a plain image).
    pub fn read(path: &Path) -> std::result::Result<Option<Sums>, String> {
        Ok(Self::from_channels(Channels::read(path)?))
    }

    /// The sums a mergeable EXR's first layer holds; `None` when it lacks them.
    pub fn from_channels(layer: Channels) -> Option<Sums> {
        let find = |name: &str| {
            layer
                .get(name)
                .map(|v| v.iter().copied().map(f64::from).collect::<Vec<f64>>())
        };
        let (Some(r), Some(g), Some(b), Some(w), Some(count)) = (
            find("sum.R"),
            find("sum.G"),
            find("sum.B"),
            find("weight"),
            find("count"),
        ) else {
            return None;
        };
        let moment_channels = ["moment1.R", "moment1.G", "moment1.B"]
            .into_iter()
            .chain(["moment2.R", "moment2.G", "moment2.B"])
            .map(find)
            .collect::<Option<Vec<Vec<f64>>>>();
        let moments = moment_channels.map(|m| {
            (0..r.len())
                .map(|i| std::array::from_fn(|c| m[c][i]))
                .collect()
        });
        let int = |name: &str| match layer.attribute(name) {
            Some(Attribute::Int(v)) => Some(v.max(0) as u32),
            _ => None,
        };
        let seconds = match layer.attribute("renderTimeSeconds") {
            Some(Attribute::Float(v)) => f64::from(v),
            _ => 0.0,
        };
        let splats = match (find("splat.R"), find("splat.G"), find("splat.B")) {
            (Some(r), Some(g), Some(b)) => Some((0..r.len()).map(|i| [r[i], g[i], b[i]]).collect()),
            _ => None,
        };
        let splat_spp = match layer.attribute("splatSpp") {
            Some(Attribute::Float(v)) => Some(f64::from(v)),
            _ => None,
        };
        let aovs = layer
            .channels
            .iter()
            .filter(|(name, _)| !OWN_CHANNELS.contains(&name.as_str()))
            .cloned()
            .collect();
        Some(Sums {
            frame: layer.frame,
            width: layer.width,
            height: layer.height,
            sums: (0..r.len()).map(|i| [r[i], g[i], b[i], w[i]]).collect(),
            counts: count,
            moments,
            aovs,
            spp: int("samplesPerPixel").unwrap_or(0),
            offset: int("sampleOffset"),
            footprint: int("footprintSpp"),
            scene: match layer.attribute("sceneHash") {
                Some(Attribute::Int(h)) => Some(h),
                _ => None,
            },
            seconds,
            splats,
            splat_spp,
        })
    }
}
