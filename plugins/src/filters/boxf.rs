//! `box`: constant weight over the radius (pbrt-v3 default radius 0.5).

use super::FilterKernel;
use super::{radius, Filter, FilterBuild, Splatting, XWIDTH, YWIDTH};
use crate::registry::{Choice, Entry, Kind, ParamSpec, PluginInfo};
use acr_parser::{ParamType, Result};

/// The box filter.
#[derive(Clone, Debug)]
pub struct BoxFilter {
    rx: f32,
    ry: f32,
}

impl BoxFilter {
    /// A box of half-widths `rx`, `ry`.
    pub fn new(rx: f32, ry: f32) -> Self {
        Self { rx, ry }
    }
}

impl FilterKernel for BoxFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        if x.abs() <= self.rx && y.abs() <= self.ry {
            1.0
        } else {
            0.0
        }
    }
}

/// The registry's entry.
pub(super) const ENTRY: Entry<FilterBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Filter,
        name: "box",
        doc: "pbrt-v3 box: every sample within the radius weighs the same",
        params: &[
            ParamSpec::new("xwidth", ParamType::Float, "0.5", XWIDTH),
            ParamSpec::new("ywidth", ParamType::Float, "0.5", YWIDTH),
        ],
    },
    build,
};

fn build(c: &Choice) -> Result<Box<dyn Filter>> {
    let (rx, ry) = radius(&c.params, 0.5)?;
    Ok(Box::new(Splatting::new("box", BoxFilter::new(rx, ry))))
}
