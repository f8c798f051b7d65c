//! First-hit features as the cells and the fit see them: per sample, the albedo (3), shading
//! normal (3) and depth (1) of the first non-specular surface the camera path met, as the
//! renderer's integrator records them (zeros where it met none).

/// Features per sample.
pub const FEATURES: usize = 7;

/// One sample's first-hit features: albedo r, g, b, normal x, y, z, depth.
pub type Features = [f32; FEATURES];

/// Index of the normal's x.
pub const NORMAL: usize = 3;
/// Index of the depth.
pub const DEPTH: usize = 6;

/// `f` with every value that is not finite replaced by 0, and whether any was.
pub fn sanitized(f: Features) -> (Features, bool) {
    let bad = f.iter().any(|v| !v.is_finite());
    (f.map(|v| if v.is_finite() { v } else { 0.0 }), bad)
}

/// The scale of feature `k` when two groups' values `a`, `b` are compared: 1 for albedo, 2 for
/// the normal (its components span [-1, 1]), the larger depth for depth.
fn scale(k: usize, a: f64, b: f64) -> f64 {
    match k {
        k if k < NORMAL => 1.0,
        k if k < DEPTH => 2.0,
        _ => a.abs().max(b.abs()),
    }
}

/// Whether two groups' mean features `a` and `b` agree within `tolerance`: per feature,
/// |a - b| <= tolerance × scale (1 for albedo, 2 for the normal, the larger depth for depth).
/// NaN never agrees.
pub fn agree(a: &[f64; FEATURES], b: &[f64; FEATURES], tolerance: f64) -> bool {
    (0..FEATURES).all(|k| (a[k] - b[k]).abs() <= tolerance * scale(k, a[k], b[k]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn features_agree_within_the_tolerance() {
        let wall = [0.5, 0.5, 0.5, 0.0, 0.0, 1.0, 4.0];
        assert!(agree(&wall, &wall, 0.0));
        let mut brighter = wall;
        brighter[0] = 0.7;
        assert!(!agree(&wall, &brighter, 0.1));
        assert!(agree(&wall, &brighter, 0.25));
        // A normal turned by 90 degrees differs by 1 on two axes: half of its scale of 2.
        let floor = [0.5, 0.5, 0.5, 0.0, 1.0, 0.0, 4.0];
        assert!(!agree(&wall, &floor, 0.4));
        assert!(agree(&wall, &floor, 0.5));
        // Depth relative to the larger: 4 against 8 differs by half.
        let behind = [0.5, 0.5, 0.5, 0.0, 0.0, 1.0, 8.0];
        assert!(!agree(&wall, &behind, 0.4));
        assert!(agree(&wall, &behind, 0.5));
        let nan = [f64::NAN; FEATURES];
        assert!(!agree(&wall, &nan, 10.0));
    }

    #[test]
    fn sanitized_zeroes_what_is_not_finite() {
        let (f, bad) = sanitized([1.0, f32::NAN, 0.5, f32::INFINITY, 0.0, 1.0, 2.0]);
        assert!(bad);
        assert_eq!(f, [1.0, 0.0, 0.5, 0.0, 0.0, 1.0, 2.0]);
        assert!(!sanitized([0.0; FEATURES]).1);
    }
}
