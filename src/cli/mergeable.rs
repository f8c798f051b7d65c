//! Mergeable EXRs: beside the image (R, G, B), each pixel's filter-weighted radiance sums
//! (`sum.R`, `sum.G`, `sum.B`, times the film's scale), its filter-weight sum (`weight`) and its
//! sample count (`count`), with pbrt-v4's header attributes `samplesPerPixel` and
//! `renderTimeSeconds`. Renders of different sample ranges of one frame add their sums and
//! weights: the merge is the image of all their samples (Cycles' `merge_images`, weighted).

use crate::image_io::Frame;
use exr::prelude::*;
use std::path::Path;

/// What a mergeable EXR holds, for one crop of a frame.
#[derive(Clone, Debug, PartialEq)]
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
    /// Samples per pixel of the render(s).
    pub spp: u32,
    /// Render seconds, summed over merged renders.
    pub seconds: f64,
}

impl Sums {
    /// The image: each pixel's weighted mean (0 where no weight, and never negative, as the
    /// film makes it).
    pub fn image(&self) -> Vec<[f32; 3]> {
        self.sums
            .iter()
            .map(|s| {
                if s[3] == 0.0 {
                    return [0.0; 3];
                }
                let inv = 1.0 / s[3];
                [0, 1, 2].map(|c| ((s[c] * inv) as f32).max(0.0))
            })
            .collect()
    }

    /// Adds `other`'s samples (another sample range of the same crop).
    pub fn add(&mut self, other: &Sums) -> std::result::Result<(), String> {
        if (self.frame, self.width, self.height) != (other.frame, other.width, other.height) {
            return Err("not the same crop of the same frame".to_owned());
        }
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            for c in 0..4 {
                a[c] += b[c];
            }
        }
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
        self.spp += other.spp;
        self.seconds += other.seconds;
        Ok(())
    }

    /// Writes the EXR: R, G, B, the sums, weight and count, and the attributes.
    pub fn write(&self, path: &Path) -> std::result::Result<(), String> {
        let n = self.width * self.height;
        let image = self.image();
        let channel =
            |name: &str, values: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(values));
        let pick = |f: &dyn Fn(usize) -> f32| (0..n).map(f).collect::<Vec<f32>>();
        let channels = AnyChannels::sort(SmallVec::from_vec(vec![
            channel("R", pick(&|i| image[i][0])),
            channel("G", pick(&|i| image[i][1])),
            channel("B", pick(&|i| image[i][2])),
            channel("sum.R", pick(&|i| self.sums[i][0] as f32)),
            channel("sum.G", pick(&|i| self.sums[i][1] as f32)),
            channel("sum.B", pick(&|i| self.sums[i][2] as f32)),
            channel("weight", pick(&|i| self.sums[i][3] as f32)),
            channel("count", pick(&|i| self.counts[i] as f32)),
        ]));
        let mut attributes = LayerAttributes {
            layer_position: Vec2(self.frame.x0 as i32, self.frame.y0 as i32),
            ..LayerAttributes::default()
        };
        attributes.other.insert(
            Text::from("samplesPerPixel"),
            AttributeValue::I32(self.spp.min(i32::MAX as u32) as i32),
        );
        attributes.other.insert(
            Text::from("renderTimeSeconds"),
            AttributeValue::F32(self.seconds as f32),
        );
        let encoding = Encoding {
            line_order: LineOrder::Increasing,
            ..Encoding::FAST_LOSSLESS
        };
        let layer = Layer::new((self.width, self.height), attributes, encoding, channels);
        let display = IntegerBounds::new((0, 0), (self.frame.width, self.frame.height));
        Image::new(ImageAttributes::new(display), layer)
            .write()
            .to_file(path)
            .map_err(|e| e.to_string())
    }

    /// Reads a mergeable EXR; `None` when the file lacks the sums (a plain image).
    pub fn read(path: &Path) -> std::result::Result<Option<Sums>, String> {
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(path)
            .map_err(|e| e.to_string())?;
        let layer = &image.layer_data;
        let find = |name: &str| {
            layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name.to_string() == name)
                .map(|c| {
                    c.sample_data
                        .values_as_f32()
                        .map(f64::from)
                        .collect::<Vec<f64>>()
                })
        };
        let (Some(r), Some(g), Some(b), Some(w), Some(count)) = (
            find("sum.R"),
            find("sum.G"),
            find("sum.B"),
            find("weight"),
            find("count"),
        ) else {
            return Ok(None);
        };
        let display = image.attributes.display_window;
        let pos = layer.attributes.layer_position;
        let (dx, dy) = (
            pos.x() - display.position.x(),
            pos.y() - display.position.y(),
        );
        let (width, height) = (layer.size.width(), layer.size.height());
        if dx < 0
            || dy < 0
            || dx as usize + width > display.size.width()
            || dy as usize + height > display.size.height()
        {
            return Err("its data window is not within its display window".to_owned());
        }
        let spp = match layer.attributes.other.get(&Text::from("samplesPerPixel")) {
            Some(AttributeValue::I32(v)) => (*v).max(0) as u32,
            _ => 0,
        };
        let seconds = match layer.attributes.other.get(&Text::from("renderTimeSeconds")) {
            Some(AttributeValue::F32(v)) => f64::from(*v),
            _ => 0.0,
        };
        Ok(Some(Sums {
            frame: Frame {
                width: display.size.width(),
                height: display.size.height(),
                x0: dx as usize,
                y0: dy as usize,
            },
            width,
            height,
            sums: (0..r.len()).map(|i| [r[i], g[i], b[i], w[i]]).collect(),
            counts: count,
            spp,
            seconds,
        }))
    }
}
