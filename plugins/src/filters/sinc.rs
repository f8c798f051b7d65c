//! `sinc`: sinc windowed by a Lanczos lobe of width tau (pbrt-v3: radius 4, tau 3).

use super::FilterKernel;
use super::{finite, radius, Filter, FilterBuild, Splatting, XWIDTH, YWIDTH};
use crate::registry::{Choice, Entry, Kind, ParamSpec, PluginInfo};
use acr_parser::{ParamType, Result};
use std::f32::consts::PI;

/// The Lanczos-windowed sinc filter.
#[derive(Clone, Debug)]
pub struct LanczosSincFilter {
    rx: f32,
    ry: f32,
    tau: f32,
}

/// sin(pi x) / (pi x).
#[inline]
fn sinc(x: f32) -> f32 {
    let x = x.abs();
    if x < 1e-5 {
        1.0
    } else {
        (PI * x).sin() / (PI * x)
    }
}

impl LanczosSincFilter {
    /// A windowed sinc of half-widths `rx`, `ry` and window `tau`.
    pub fn new(rx: f32, ry: f32, tau: f32) -> Self {
        Self { rx, ry, tau }
    }

    #[inline]
    fn windowed(&self, x: f32, radius: f32) -> f32 {
        if x.abs() > radius {
            0.0
        } else {
            sinc(x) * sinc(x / self.tau)
        }
    }
}

impl FilterKernel for LanczosSincFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        self.windowed(x, self.rx) * self.windowed(y, self.ry)
    }
}

/// The registry's entry.
pub(super) const ENTRY: Entry<FilterBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Filter,
        name: "sinc",
        doc: "pbrt-v3 sinc: a sinc windowed by a Lanczos sinc of tau cycles",
        params: &[
            ParamSpec::new("xwidth", ParamType::Float, "4", XWIDTH),
            ParamSpec::new("ywidth", ParamType::Float, "4", YWIDTH),
            ParamSpec::new(
                "tau",
                ParamType::Float,
                "3",
                "cycles of the sinc inside the window",
            ),
        ],
    },
    build,
};

fn build(c: &Choice) -> Result<Box<dyn Filter>> {
    let (rx, ry) = radius(&c.params, 4.0)?;
    let tau = finite(&c.params, "tau", 3.0)?;
    Ok(Box::new(Splatting::new(
        "sinc",
        LanczosSincFilter::new(rx, ry, tau),
    )))
}
