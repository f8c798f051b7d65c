//! `triangle`: a tent falling linearly to zero at the radius (pbrt-v3 default radius 2).

use super::FilterKernel;
use super::{radius, Filter, FilterBuild, Splatting, XWIDTH, YWIDTH};
use crate::registry::{Choice, Entry, Kind, ParamSpec, PluginInfo};
use acr_parser::{ParamType, Result};

/// The triangle (tent) filter.
#[derive(Clone, Debug)]
pub struct TriangleFilter {
    rx: f32,
    ry: f32,
}

impl TriangleFilter {
    /// A tent of half-widths `rx`, `ry`.
    pub fn new(rx: f32, ry: f32) -> Self {
        Self { rx, ry }
    }
}

impl FilterKernel for TriangleFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        (self.rx - x.abs()).max(0.0) * (self.ry - y.abs()).max(0.0)
    }
}

/// The registry's entry.
pub(super) const ENTRY: Entry<FilterBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Filter,
        name: "triangle",
        doc: "pbrt-v3 triangle: a tent falling linearly to zero at the radius",
        params: &[
            ParamSpec::new("xwidth", ParamType::Float, "2", XWIDTH),
            ParamSpec::new("ywidth", ParamType::Float, "2", YWIDTH),
        ],
    },
    build,
};

fn build(c: &Choice) -> Result<Box<dyn Filter>> {
    let (rx, ry) = radius(&c.params, 2.0)?;
    Ok(Box::new(Splatting::new(
        "triangle",
        TriangleFilter::new(rx, ry),
    )))
}
