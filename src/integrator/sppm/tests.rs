//! sppm's own parts: the per-pixel update, the grid, the photons' Halton dimensions.

use super::grid::Grid;
use super::visible::VisiblePoint;
use super::PixelState;
use crate::bsdf::Bsdf;
use crate::geometry::{Frame, Spectrum, Vec3};

#[test]
fn the_update_shrinks_the_radius_as_pbrt_v3() {
    let mut p = PixelState {
        radius: 1.0,
        ld: Spectrum::ZERO,
        n: 0.0,
        tau: Spectrum::ZERO,
    };
    // No photon: nothing changes.
    p.update(Spectrum::ONE, Spectrum::splat(5.0), 0);
    assert_eq!(p.radius, 1.0);
    assert_eq!(p.tau, Spectrum::ZERO);
    // 3 photons: N = 2, r = sqrt(2/3), tau = beta * phi * r^2.
    p.update(Spectrum::splat(0.5), Spectrum::splat(6.0), 3);
    assert!((p.n - 2.0).abs() < 1e-6);
    assert!((p.radius - (2.0f32 / 3.0).sqrt()).abs() < 1e-6);
    assert!((p.tau.x - 3.0 * 2.0 / 3.0).abs() < 1e-5);
    // The value: Ld / iterations + tau / (Np pi r^2).
    p.ld = Spectrum::splat(4.0);
    let v = p.value(2, 10);
    let want = 2.0 + 2.0 / (20.0 * std::f32::consts::PI * (2.0 / 3.0));
    assert!((v.x - want).abs() < 1e-5, "{v} vs {want}");
}

fn vp(p: Vec3) -> Option<VisiblePoint> {
    Some(VisiblePoint {
        p,
        wo: Vec3::Z,
        bsdf: Bsdf::from_frame(Frame::from_z(Vec3::Z), Vec3::Z, 1.0),
        beta: Spectrum::ONE,
    })
}

/// Every visible point within its radius of a query point is among the candidates there, once.
#[test]
fn the_grid_finds_every_visible_point_in_reach() {
    let mut visible = Vec::new();
    let mut radii = Vec::new();
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    for i in 0..400 {
        let p = Vec3::new(next() * 4.0, next() * 2.0, next());
        visible.push(if i % 7 == 0 { None } else { vp(p) });
        radii.push(0.05 + 0.2 * next());
    }
    let grid = Grid::build(&visible, &radii).unwrap();
    for _ in 0..2000 {
        let q = Vec3::new(next() * 4.4 - 0.2, next() * 2.4 - 0.2, next() * 1.4 - 0.2);
        let found = grid.candidates(q);
        for (i, v) in visible.iter().enumerate() {
            if let Some(v) = v {
                if v.p.distance(q) <= radii[i] {
                    let times = found.iter().filter(|&&f| f as usize == i).count();
                    assert_eq!(times, 1, "point {i} at {q}");
                }
            }
        }
    }
    assert!(Grid::build(&[None, None], &[1.0, 1.0]).is_none());
}
