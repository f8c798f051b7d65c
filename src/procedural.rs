//! pbrt-v3's procedural textures (textures/fbm, wrinkled, windy, marble, dots), on the Perlin
//! noise of [`crate::noise`], with pbrt-v3's parameters and defaults.

use crate::geometry::{Spectrum, Vec2, Vec3};
use crate::noise::{fbm, noise, turbulence};

/// A 3D noise pattern, evaluated at the texture-space point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NoisePattern {
    /// `fbm`: fractional Brownian motion.
    Fbm {
        /// `roughness`: each octave's amplitude over the one before's.
        omega: f32,
        /// `octaves`.
        octaves: u32,
    },
    /// `wrinkled`: turbulence (the octaves' absolute values).
    Wrinkled {
        /// `roughness`.
        omega: f32,
        /// `octaves`.
        octaves: u32,
    },
    /// `windy`: waves (6 octaves) scaled by a slower wind (3 octaves at a tenth the frequency).
    Windy,
    /// `marble` (spectrum only): a sine of the height perturbed by fbm, through pbrt-v3's
    /// colour spline.
    Marble {
        /// `roughness`.
        omega: f32,
        /// `octaves`.
        octaves: u32,
        /// `scale`: of the point before everything else.
        scale: f32,
        /// `variation`: of the fbm's perturbation.
        variation: f32,
    },
}

/// pbrt-v3's marble colour spline's control points.
const MARBLE: [[f32; 3]; 9] = [
    [0.58, 0.58, 0.6],
    [0.58, 0.58, 0.6],
    [0.58, 0.58, 0.6],
    [0.5, 0.5, 0.5],
    [0.6, 0.59, 0.58],
    [0.58, 0.58, 0.6],
    [0.58, 0.58, 0.6],
    [0.2, 0.2, 0.33],
    [0.58, 0.58, 0.6],
];

impl NoisePattern {
    /// The scalar value of a grey pattern (all but marble) at texture-space point `p` whose
    /// footprint is `dpdx`, `dpdy` (zero: none, every octave).
    pub fn scalar(&self, p: Vec3, dpdx: Vec3, dpdy: Vec3) -> f32 {
        match *self {
            NoisePattern::Fbm { omega, octaves } => fbm(p, dpdx, dpdy, omega, octaves),
            NoisePattern::Wrinkled { omega, octaves } => turbulence(p, dpdx, dpdy, omega, octaves),
            NoisePattern::Windy => {
                let wind = fbm(0.1 * p, 0.1 * dpdx, 0.1 * dpdy, 0.5, 3);
                let wave = fbm(p, dpdx, dpdy, 0.5, 6);
                wind.abs() * wave
            }
            NoisePattern::Marble { .. } => self.colour(p, dpdx, dpdy).x,
        }
    }

    /// The pattern's colour: marble's spline, or the scalar in every channel.
    pub fn colour(&self, p: Vec3, dpdx: Vec3, dpdy: Vec3) -> Spectrum {
        let NoisePattern::Marble {
            omega,
            octaves,
            scale,
            variation,
        } = *self
        else {
            return Spectrum::splat(self.scalar(p, dpdx, dpdy));
        };
        let p = p * scale;
        let marble = p.y + variation * fbm(p, scale * dpdx, scale * dpdy, omega, octaves);
        let t = 0.5 + 0.5 * marble.sin();
        let segments = (MARBLE.len() - 3) as f32;
        // pbrt-v3 writes `std::min(1, int(std::floor(t * NSEG)))` (its own slip for
        // `min(floor(t * NSEG), NSEG - 1)`): kept, so that images match; only the first two
        // segments are used.
        // The spline is then extrapolated past its segment, as in pbrt-v3 (values of 10 and
        // more are pbrt-v3's own).
        let first = ((t * segments).floor() as i32).clamp(0, 1) as usize;
        let t = t * segments - first as f32;
        let c = |k: usize| Spectrum::from_array(MARBLE[first + k]);
        let (c0, c1, c2, c3) = (c(0), c(1), c(2), c(3));
        // Bézier by de Casteljau, as pbrt-v3.
        let s0 = (1.0 - t) * c0 + t * c1;
        let s1 = (1.0 - t) * c1 + t * c2;
        let s2 = (1.0 - t) * c2 + t * c3;
        let s0 = (1.0 - t) * s0 + t * s1;
        let s1 = (1.0 - t) * s1 + t * s2;
        1.5 * ((1.0 - t) * s0 + t * s1)
    }
}

/// pbrt-v3's `dots`: whether texture coordinates `st` fall inside a dot. Each unit cell around
/// an integer point holds a dot of radius 0.35 where the noise at its centre is positive,
/// shifted by up to 0.15 by two more noise lookups.
pub fn in_dot(st: Vec2) -> bool {
    let s_cell = (st.x + 0.5).floor();
    let t_cell = (st.y + 0.5).floor();
    if noise(s_cell + 0.5, t_cell + 0.5, 0.5) <= 0.0 {
        return false;
    }
    const RADIUS: f32 = 0.35;
    let max_shift = 0.5 - RADIUS;
    let s_center = s_cell + max_shift * noise(s_cell + 1.5, t_cell + 2.8, 0.5);
    let t_center = t_cell + max_shift * noise(s_cell + 4.5, t_cell + 9.8, 0.5);
    let d = st - Vec2::new(s_center, t_center);
    d.length_squared() < RADIUS * RADIUS
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grey_patterns_are_their_noise_sums() {
        let p = Vec3::new(0.3, 1.7, -2.2);
        let f = NoisePattern::Fbm {
            omega: 0.5,
            octaves: 8,
        };
        assert_eq!(
            f.scalar(p, Vec3::ZERO, Vec3::ZERO),
            fbm(p, Vec3::ZERO, Vec3::ZERO, 0.5, 8)
        );
        assert_eq!(
            f.colour(p, Vec3::ZERO, Vec3::ZERO),
            Spectrum::splat(fbm(p, Vec3::ZERO, Vec3::ZERO, 0.5, 8))
        );
        let w = NoisePattern::Wrinkled {
            omega: 0.7,
            octaves: 3,
        };
        assert_eq!(
            w.scalar(p, Vec3::ZERO, Vec3::ZERO),
            turbulence(p, Vec3::ZERO, Vec3::ZERO, 0.7, 3)
        );
        let windy = NoisePattern::Windy.scalar(p, Vec3::ZERO, Vec3::ZERO);
        assert_eq!(
            windy,
            fbm(0.1 * p, Vec3::ZERO, Vec3::ZERO, 0.5, 3).abs()
                * fbm(p, Vec3::ZERO, Vec3::ZERO, 0.5, 6)
        );
    }

    #[test]
    // The values as pbrt-v3 printed them (%.9g).
    #[allow(clippy::excessive_precision)]
    fn marble_windy_and_wrinkled_match_pbrt_v3() {
        // Printed by pbrt-v3's own MarbleTexture (octaves 8, roughness 0.5, scale 1, variation
        // 0.2), WindyTexture and WrinkledTexture (8, 0.5) at these points, with zero
        // differentials: tests/data/pbrt-v3/texcheck.cpp, linked with pbrt-v3's libpbrt.
        let cases = [
            (
                [0.5, 0.5, 0.5],
                [11.7702312, 11.1932049, 11.9286804],
                -0.0308828894,
                0.188432008,
            ),
            (
                [1.3, 2.7, 0.4],
                [6.4778614, 6.15504456, 6.45715857],
                0.0255227014,
                0.891302645,
            ),
            (
                [-3.21, 7.7, 12.05],
                [40.310318, 38.4488945, 41.8240395],
                0.110328883,
                0.502978921,
            ),
            (
                [100.25, -40.5, 3.125],
                [0.875153899, 0.862770677, 0.85071826],
                0.00560348807,
                0.203138635,
            ),
            (
                [0.1, -1.2, 2.3],
                [0.869338095, 0.869338095, 0.899172783],
                -0.0798446611,
                0.431348413,
            ),
        ];
        let marble = NoisePattern::Marble {
            omega: 0.5,
            octaves: 8,
            scale: 1.0,
            variation: 0.2,
        };
        let wrinkled = NoisePattern::Wrinkled {
            omega: 0.5,
            octaves: 8,
        };
        for (p, rgb, windy, wr) in cases {
            let p = Vec3::from_array(p);
            let m = marble.colour(p, Vec3::ZERO, Vec3::ZERO).to_array();
            for (g, w) in m.iter().zip(rgb) {
                assert!(
                    (g - w).abs() <= 2e-6 * w.abs().max(1.0),
                    "{p}: {m:?} against {rgb:?}"
                );
            }
            assert!(
                (NoisePattern::Windy.scalar(p, Vec3::ZERO, Vec3::ZERO) - windy).abs() < 2e-6,
                "{p}"
            );
            assert!(
                (wrinkled.scalar(p, Vec3::ZERO, Vec3::ZERO) - wr).abs() < 2e-6,
                "{p}"
            );
        }
    }

    #[test]
    fn dots_match_pbrt_v3_on_a_grid() {
        // pbrt-v3's DotsTexture (inside 1, outside 0, uv mapping) on a 64 x 24 grid from
        // (-3.1, -2.05) in steps of 0.25: tests/data/pbrt-v3/dotscheck.cpp.
        let want = include_str!("../tests/data/pbrt-v3/dots-grid.txt");
        for (j, row) in want.lines().enumerate() {
            for (i, c) in row.chars().enumerate() {
                let st = Vec2::new(i as f32 * 0.25 - 3.1, j as f32 * 0.25 - 2.05);
                assert_eq!(in_dot(st), c == '1', "({}, {})", st.x, st.y);
            }
        }
    }

    #[test]
    fn dots_lie_on_some_cells_only() {
        let mut inside = 0;
        let n = 200;
        for i in 0..n {
            for j in 0..n {
                let st = Vec2::new(i as f32 * 0.1, j as f32 * 0.1);
                inside += usize::from(in_dot(st));
            }
        }
        // A dot covers pi 0.35^2 = 0.385 of its cell; about half the cells have one.
        let share = inside as f64 / (n * n) as f64;
        assert!((0.1..0.3).contains(&share), "{share}");
    }
}
