//! pbrt's transform constructors (Translate, Scale, Rotate, LookAt) and animated transforms.

use glam::{DMat4, DVec3};

/// A transform that may change during the shutter: `start` at `start_time`, `end` at `end_time`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnimatedTransform {
    /// The transform at `start_time`.
    pub start: DMat4,
    /// The transform at `end_time`.
    pub end: DMat4,
    /// Time of `start` (TransformTimes' first value).
    pub start_time: f64,
    /// Time of `end`.
    pub end_time: f64,
}

impl AnimatedTransform {
    /// A transform that does not move.
    pub fn fixed(m: DMat4) -> Self {
        Self {
            start: m,
            end: m,
            start_time: 0.0,
            end_time: 1.0,
        }
    }

    /// True when the start and end differ (and so the shape or camera moves).
    pub fn is_animated(&self) -> bool {
        self.start != self.end
    }
}

/// pbrt's `Translate`.
pub fn translate(d: DVec3) -> DMat4 {
    DMat4::from_translation(d)
}

/// pbrt's `Scale`.
pub fn scale(s: DVec3) -> DMat4 {
    DMat4::from_scale(s)
}

/// pbrt's `Rotate`: `degrees` about `axis` (normalised here); `None` for a zero axis.
pub fn rotate(degrees: f64, axis: DVec3) -> Option<DMat4> {
    let a = axis.try_normalize()?;
    Some(DMat4::from_axis_angle(a, degrees.to_radians()))
}

/// pbrt's `LookAt`: the camera-from-world transform of a camera at `pos` looking at `look`.
/// pbrt's camera space is left-handed: x = up × dir, y = dir × x, z = dir.
/// `None` when `up` is parallel to the viewing direction or `pos == look`.
pub fn look_at(pos: DVec3, look: DVec3, up: DVec3) -> Option<DMat4> {
    let dir = (look - pos).try_normalize()?;
    let right = up.try_normalize()?.cross(dir).try_normalize()?;
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        pos.extend(1.0),
    );
    Some(world_from_camera.inverse())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotate_matches_pbrt_formula() {
        // pbrt-v3 Rotate(90, z) maps x to y.
        let m = rotate(90.0, DVec3::Z).unwrap();
        let p = m.transform_point3(DVec3::X);
        assert!((p - DVec3::Y).length() < 1e-12, "{p}");
        assert!(rotate(10.0, DVec3::ZERO).is_none());
    }

    #[test]
    fn look_at_puts_target_on_plus_z() {
        let m = look_at(
            DVec3::new(0.0, 1.0, 5.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::Y,
        )
        .unwrap();
        let t = m.transform_point3(DVec3::new(0.0, 1.0, 0.0));
        assert!((t - DVec3::new(0.0, 0.0, 5.0)).length() < 1e-12, "{t}");
        // Left-handed camera space: world +x (to the camera's left when it looks down -z)
        // maps to camera -x.
        let x = m.transform_point3(DVec3::new(1.0, 1.0, 5.0));
        assert!((x - DVec3::new(-1.0, 0.0, 0.0)).length() < 1e-12, "{x}");
        assert!(look_at(DVec3::ZERO, DVec3::Y, DVec3::Y).is_none());
    }
}
