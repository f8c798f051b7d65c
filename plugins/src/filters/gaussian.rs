//! `gaussian`: exp(-alpha d^2) shifted to reach zero at the radius (pbrt-v3: radius 2, alpha 2).

use super::FilterKernel;
use super::{finite, radius, Filter, FilterBuild, Splatting, XWIDTH, YWIDTH};
use crate::registry::{Choice, Entry, Kind, ParamSpec, PluginInfo};
use acr_parser::{ParamType, Result};

/// The truncated Gaussian filter.
#[derive(Clone, Debug)]
pub struct GaussianFilter {
    rx: f32,
    ry: f32,
    alpha: f32,
    exp_x: f32,
    exp_y: f32,
}

impl GaussianFilter {
    /// A Gaussian of falloff `alpha` truncated at half-widths `rx`, `ry`.
    pub fn new(rx: f32, ry: f32, alpha: f32) -> Self {
        Self {
            rx,
            ry,
            alpha,
            exp_x: (-alpha * rx * rx).exp(),
            exp_y: (-alpha * ry * ry).exp(),
        }
    }

    #[inline]
    fn gaussian(&self, d: f32, expv: f32) -> f32 {
        ((-self.alpha * d * d).exp() - expv).max(0.0)
    }
}

impl FilterKernel for GaussianFilter {
    fn radius(&self) -> (f32, f32) {
        (self.rx, self.ry)
    }

    #[inline]
    fn eval(&self, x: f32, y: f32) -> f32 {
        if x.abs() > self.rx || y.abs() > self.ry {
            return 0.0;
        }
        self.gaussian(x, self.exp_x) * self.gaussian(y, self.exp_y)
    }
}

/// The registry's entry.
pub(super) const ENTRY: Entry<FilterBuild> = Entry {
    info: PluginInfo {
        kind: Kind::Filter,
        name: "gaussian",
        doc: "pbrt-v3 gaussian: exp(-alpha d^2), shifted to reach zero at the radius",
        params: &[
            ParamSpec::new("xwidth", ParamType::Float, "2", XWIDTH),
            ParamSpec::new("ywidth", ParamType::Float, "2", YWIDTH),
            ParamSpec::new(
                "alpha",
                ParamType::Float,
                "2",
                "falloff: larger is narrower",
            ),
        ],
    },
    build,
};

fn build(c: &Choice) -> Result<Box<dyn Filter>> {
    let (rx, ry) = radius(&c.params, 2.0)?;
    let alpha = finite(&c.params, "alpha", 2.0)?;
    Ok(Box::new(Splatting::new(
        "gaussian",
        GaussianFilter::new(rx, ry, alpha),
    )))
}
