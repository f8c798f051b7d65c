//! `mitchell`: the Mitchell-Netravali cubic with parameters B and C (pbrt-v3: radius 2, 1/3, 1/3).

use super::FilterKernel;
use super::{finite, radius, Filter, FilterBuild, Splatting, XWIDTH, YWIDTH};
use crate::registry::{Choice, Entry, Kind, ParamSpec, PluginInfo};
use acr_parser::{ParamType, Result};

/// The Mitchell-Netravali filter.
#[derive(Clone, Debug)]
pub struct MitchellFilter {
    rx: f32,
    ry: f32,
    b: f32,
    c: f32,
}

impl MitchellFilter {
    /// A Mitchell filter of half-widths `rx`, `ry` and parameters `b`, `c`.
    pub fn new(rx: f32, ry: f32, b: f32, c: f32) -> Self {
        Self { rx, ry, b, c }
    }

    /// pbrt-v3's Mitchell1D on x in [-1, 1].
    #[inline]
    fn mitchell_1d(&self, x: f32) -> f32 {
        let (b, c) = (self.b, self.c);
        let x = (2.0 * x).abs();
        if x > 2.0 {
            0.0
        } else if x > 1.0 {
            ((-b - 6.0 * c) * x * x * x
                + (6.0 * b + 30.0 * c) * x * x
                + (-12.0 * b - 48.0 * c) * x
                + (8.0 * b + 24.0 * c))
                * (1.0 / 6.0)
        } else {
            ((12.0 - 9.0 * b - 6.0 * c) * x * x * x
                + (-18.0 + 12.0 * b + 6.0 * c) * x * x
                + (6.0 - 2.0 * b))
                * (1.0 / 6.0)
        }
    }
}

impl FilterKernel for MitchellFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        if x.abs() > self.rx || y.abs() > self.ry {
            return 0.0;
        }
        self.mitchell_1d(x / self.rx) * self.mitchell_1d(y / self.ry)
    }
}

/// The registry's entry.
pub(super) const ENTRY: Entry<FilterBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Filter,
        name: "mitchell",
        doc: "pbrt-v3 mitchell: the Mitchell-Netravali cubic with parameters B and C",
        params: &[
            ParamSpec::new("xwidth", ParamType::Float, "2", XWIDTH),
            ParamSpec::new("ywidth", ParamType::Float, "2", YWIDTH),
            ParamSpec::new("B", ParamType::Float, "0.333333", "blur: the cubic's B"),
            ParamSpec::new("C", ParamType::Float, "0.333333", "ringing: the cubic's C"),
        ],
    },
    build,
};

fn build(c: &Choice) -> Result<Box<dyn Filter>> {
    let (rx, ry) = radius(&c.params, 2.0)?;
    let b = finite(&c.params, "B", 1.0 / 3.0)?;
    let cc = finite(&c.params, "C", 1.0 / 3.0)?;
    Ok(Box::new(Splatting::new(
        "mitchell",
        MitchellFilter::new(rx, ry, b, cc),
    )))
}
