//! The transform directives: the current transform matrices (two, for motion), their
//! times, named coordinate systems, and the orientation flag.

use super::Builder;
use crate::error::{Error, Result};
use crate::source::Loc;
use crate::suggest::did_you_mean;
use crate::transform::AnimatedTransform;
use glam::DMat4;

impl Builder {
    pub(super) fn animated(&self) -> AnimatedTransform {
        AnimatedTransform {
            start: self.ctm[0],
            end: self.ctm[1],
            start_time: self.scene.transform_times.0,
            end_time: self.scene.transform_times.1,
        }
    }

    /// Multiplies the active transforms by `m` on the right (pbrt's order).
    pub fn concat(&mut self, m: DMat4) {
        for i in 0..2 {
            if self.active[i] {
                self.ctm[i] *= m;
            }
        }
    }

    /// Replaces the active transforms by `m`.
    pub fn set_transform(&mut self, m: DMat4) {
        for i in 0..2 {
            if self.active[i] {
                self.ctm[i] = m;
            }
        }
    }

    /// `CoordinateSystem`: names the current transforms.
    pub fn coordinate_system(&mut self, name: String) {
        self.named_coordinate_systems.insert(name, self.ctm);
    }

    /// `CoordSysTransform`: restores named transforms.
    pub fn coord_sys_transform(&mut self, name: &str, loc: &Loc) -> Result<()> {
        let Some(saved) = self.named_coordinate_systems.get(name).copied() else {
            let known: Vec<&str> = self
                .named_coordinate_systems
                .keys()
                .map(String::as_str)
                .collect();
            return Err(Error::at(
                loc,
                format!(
                    "no coordinate system named \"{name}\"{}",
                    did_you_mean(name, known)
                ),
            ));
        };
        for ((ctm, saved), active) in self.ctm.iter_mut().zip(saved).zip(self.active) {
            if active {
                *ctm = saved;
            }
        }
        Ok(())
    }

    /// `TransformTimes`.
    pub fn transform_times(&mut self, start: f64, end: f64, loc: &Loc) -> Result<()> {
        self.require_options("TransformTimes", loc)?;
        if end < start {
            return Err(Error::at(
                loc,
                format!("TransformTimes: end time {end} is before start time {start}"),
            ));
        }
        self.scene.transform_times = (start, end);
        Ok(())
    }

    /// `ActiveTransform StartTime|EndTime|All`.
    pub fn active_transform(&mut self, which: &str, loc: &Loc) -> Result<()> {
        self.active = match which {
            "StartTime" => [true, false],
            "EndTime" => [false, true],
            "All" => [true, true],
            _ => {
                return Err(Error::at(
                    loc,
                    format!(
                        "ActiveTransform needs StartTime, EndTime or All, not '{which}'{}",
                        did_you_mean(which, ["StartTime", "EndTime", "All"])
                    ),
                ))
            }
        };
        Ok(())
    }

    /// `ReverseOrientation`.
    pub fn reverse_orientation(&mut self, loc: &Loc) -> Result<()> {
        self.require_world("ReverseOrientation", loc)?;
        self.graphics.reverse_orientation = !self.graphics.reverse_orientation;
        Ok(())
    }
}
