//! EXR files of named channels: one layer of 32-bit float channels (R, G, B and whatever lies
//! beside them: sums, AOVs), a crop placed in its frame by the data and display windows, and
//! header attributes (pbrt-v4's `samplesPerPixel`, `renderTimeSeconds`).

use crate::image_io::Frame;
use exr::prelude::*;
use std::collections::HashMap;
use std::path::Path;

/// A header attribute's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Attribute {
    /// A 32-bit integer.
    Int(i32),
    /// A 32-bit float.
    Float(f32),
}

/// One layer of named channels of a crop of a frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Channels {
    /// Where the crop lies.
    pub frame: Frame,
    /// Crop width.
    pub width: usize,
    /// Crop height.
    pub height: usize,
    /// Each channel's name and its values, row-major over the crop.
    pub channels: Vec<(String, Vec<f32>)>,
    /// Header attributes by name.
    pub attributes: Vec<(String, Attribute)>,
}

impl Channels {
    /// An empty layer of a `width` x `height` crop placed in `frame`.
    pub fn new(frame: Frame, width: usize, height: usize) -> Self {
        Self {
            frame,
            width,
            height,
            ..Self::default()
        }
    }

    /// Adds a channel.
    pub fn push(&mut self, name: &str, values: Vec<f32>) {
        self.channels.push((name.to_owned(), values));
    }

    /// The channel called `name`.
    pub fn get(&self, name: &str) -> Option<&[f32]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }

    /// The attribute called `name`.
    pub fn attribute(&self, name: &str) -> Option<Attribute> {
        self.attributes
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
    }

    /// Writes the layer (lossless compression).
    pub fn write(self, path: &Path) -> std::result::Result<(), String> {
        let n = self.width * self.height;
        if let Some((name, v)) = self.channels.iter().find(|(_, v)| v.len() != n) {
            return Err(format!(
                "channel {name} has {} values for {}x{} pixels",
                v.len(),
                self.width,
                self.height
            ));
        }
        let list = self
            .channels
            .into_iter()
            .map(|(name, v)| AnyChannel::new(name.as_str(), FlatSamples::F32(v)))
            .collect::<Vec<_>>();
        let channels = AnyChannels::sort(SmallVec::from_vec(list));
        let mut attributes = LayerAttributes {
            layer_position: Vec2(self.frame.x0 as i32, self.frame.y0 as i32),
            ..LayerAttributes::default()
        };
        // The exr crate keeps custom attributes in hash maps, written in an order that changes
        // from run to run: the first goes into the layer's map, the second into the image's,
        // so that a file of at most two is the same bytes every run (the rest follow the
        // first, in any order).
        let mut shared = HashMap::new();
        for (k, (name, value)) in self.attributes.iter().enumerate() {
            let value = match *value {
                Attribute::Int(v) => AttributeValue::I32(v),
                Attribute::Float(v) => AttributeValue::F32(v),
            };
            let map = if k == 1 {
                &mut shared
            } else {
                &mut attributes.other
            };
            map.insert(Text::from(name.as_str()), value);
        }
        let encoding = Encoding {
            line_order: LineOrder::Increasing,
            ..Encoding::FAST_LOSSLESS
        };
        let layer = Layer::new((self.width, self.height), attributes, encoding, channels);
        let display = IntegerBounds::new((0, 0), (self.frame.width, self.frame.height));
        let mut image_attributes = ImageAttributes::new(display);
        image_attributes.other = shared;
        Image::new(image_attributes, layer)
            .write()
            .to_file(path)
            .map_err(|e| e.to_string())
    }

    /// Reads the first layer of an EXR: every channel as f32, the integer and float
    /// attributes, and the crop's place in its display window.
    pub fn read(path: &Path) -> std::result::Result<Channels, String> {
        let data = acr_parser::source::read_file(path, acr_parser::source::FileKind::Image)
            .map_err(|e| acr_parser::io_message(&e))?;
        Self::decode(&data)
    }

    /// The first layer of an EXR file's bytes, as [`Channels::read`] gives it.
    pub fn decode(data: &[u8]) -> std::result::Result<Channels, String> {
        crate::image_io::exr_header(data)?;
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_buffered(std::io::Cursor::new(data))
            .map_err(|e| e.to_string())?;
        let layer = &image.layer_data;
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
        let channels = layer
            .channel_data
            .list
            .iter()
            .map(|c| {
                let values = c.sample_data.values_as_f32().collect::<Vec<f32>>();
                (c.name.to_string(), values)
            })
            .collect();
        let attributes = layer
            .attributes
            .other
            .iter()
            .chain(image.attributes.other.iter())
            .filter_map(|(name, value)| {
                let v = match value {
                    AttributeValue::I32(v) => Attribute::Int(*v),
                    AttributeValue::F32(v) => Attribute::Float(*v),
                    _ => return None,
                };
                Some((name.to_string(), v))
            })
            .collect();
        Ok(Channels {
            frame: Frame {
                width: display.size.width(),
                height: display.size.height(),
                x0: dx as usize,
                y0: dy as usize,
            },
            width,
            height,
            channels,
            attributes,
        })
    }
}

/// The integer or float attribute `name` of an EXR's first layer, read from its header alone
/// (`None` when the file has none, or is no EXR).
pub fn read_attribute(path: &Path, name: &str) -> Option<Attribute> {
    let (file, _) =
        acr_parser::source::open_file(path, acr_parser::source::FileKind::Image).ok()?;
    let meta =
        exr::meta::MetaData::read_from_buffered(std::io::BufReader::new(file), false).ok()?;
    let header = meta.headers.first()?;
    let key = Text::from(name);
    let own = header.own_attributes.other.get(&key);
    match own.or_else(|| header.shared_attributes.other.get(&key))? {
        AttributeValue::I32(v) => Some(Attribute::Int(*v)),
        AttributeValue::F32(v) => Some(Attribute::Float(*v)),
        _ => None,
    }
}
