//! pbrt-v3's Perlin noise (core/texture.cpp): its permutation table, gradient choice and
//! quintic weights, and the fractional Brownian motion and turbulence sums built on it, so that
//! the procedural textures match pbrt-v3's images.
//!
//! As pbrt-v3, the octaves stop at the footprint of the hit (`dpdx`, `dpdy`, from the camera
//! ray's differentials): finer octaves would alias; the last one fades in. Without
//! differentials (later bounces) every octave is summed.

use crate::geometry::Vec3;

/// pbrt-v3's `NoisePerm` (its first 256 entries; the second half repeats them).
const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219,
    203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175,
    74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230,
    220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76,
    132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173,
    186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163,
    70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232,
    178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162,
    241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204,
    176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141,
    128, 195, 78, 66, 215, 61, 156, 180,
];

#[inline]
fn perm(i: i32) -> i32 {
    i32::from(PERM[(i & 255) as usize])
}

/// pbrt-v3's `Grad`: the dot product of one of 12 (16, four repeated) gradients, chosen by
/// hashing the lattice point, with the offset from it.
#[inline]
fn grad(x: i32, y: i32, z: i32, dx: f32, dy: f32, dz: f32) -> f32 {
    let h = perm(perm(perm(x) + y) + z) & 15;
    let u = if h < 8 || h == 12 || h == 13 { dx } else { dy };
    let v = if h < 4 || h == 12 || h == 13 { dy } else { dz };
    (if h & 1 != 0 { -u } else { u }) + (if h & 2 != 0 { -v } else { v })
}

/// pbrt-v3's `NoiseWeight`: 6t^5 - 15t^4 + 10t^3.
#[inline]
fn weight(t: f32) -> f32 {
    let t3 = t * t * t;
    let t4 = t3 * t;
    6.0 * t4 * t - 15.0 * t4 + 10.0 * t3
}

#[inline]
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// pbrt-v3's `SmoothStep`.
#[inline]
pub fn smooth_step(min: f32, max: f32, value: f32) -> f32 {
    let v = ((value - min) / (max - min)).clamp(0.0, 1.0);
    v * v * (-2.0 * v + 3.0)
}

/// Perlin noise at (x, y, z): in [-1, 1], 0 at every lattice point.
pub fn noise(x: f32, y: f32, z: f32) -> f32 {
    let (fx, fy, fz) = (x.floor(), y.floor(), z.floor());
    let (dx, dy, dz) = (x - fx, y - fy, z - fz);
    // As pbrt-v3's int conversion and mask (a saturating cast keeps huge inputs defined).
    let (ix, iy, iz) = ((fx as i32) & 255, (fy as i32) & 255, (fz as i32) & 255);
    let w000 = grad(ix, iy, iz, dx, dy, dz);
    let w100 = grad(ix + 1, iy, iz, dx - 1.0, dy, dz);
    let w010 = grad(ix, iy + 1, iz, dx, dy - 1.0, dz);
    let w110 = grad(ix + 1, iy + 1, iz, dx - 1.0, dy - 1.0, dz);
    let w001 = grad(ix, iy, iz + 1, dx, dy, dz - 1.0);
    let w101 = grad(ix + 1, iy, iz + 1, dx - 1.0, dy, dz - 1.0);
    let w011 = grad(ix, iy + 1, iz + 1, dx, dy - 1.0, dz - 1.0);
    let w111 = grad(ix + 1, iy + 1, iz + 1, dx - 1.0, dy - 1.0, dz - 1.0);
    let (wx, wy, wz) = (weight(dx), weight(dy), weight(dz));
    let x00 = lerp(wx, w000, w100);
    let x10 = lerp(wx, w010, w110);
    let x01 = lerp(wx, w001, w101);
    let x11 = lerp(wx, w011, w111);
    let y0 = lerp(wy, x00, x10);
    let y1 = lerp(wy, x01, x11);
    lerp(wz, y0, y1)
}

/// Noise at a point.
#[inline]
pub fn noise3(p: Vec3) -> f32 {
    noise(p.x, p.y, p.z)
}

/// The octaves pbrt-v3 sums for a footprint: `-1 - log2(|dp|^2) / 2`, within [0, `max`]
/// (`max` for no footprint).
fn octave_count(dpdx: Vec3, dpdy: Vec3, max: u32) -> f32 {
    let len2 = dpdx.length_squared().max(dpdy.length_squared());
    let n = -1.0 - 0.5 * (len2.ln() * std::f32::consts::LOG2_E);
    if n.is_nan() {
        return 0.0;
    }
    n.clamp(0.0, max as f32)
}

/// pbrt-v3's `FBm`: octaves of noise, each at 1.99 times the frequency and `omega` times the
/// amplitude of the one before, as many as the footprint (`dpdx`, `dpdy`) allows up to
/// `max_octaves`, the last partial one faded in.
pub fn fbm(p: Vec3, dpdx: Vec3, dpdy: Vec3, omega: f32, max_octaves: u32) -> f32 {
    let n = octave_count(dpdx, dpdy, max_octaves);
    let whole = n.floor() as u32;
    let (mut sum, mut lambda, mut o) = (0.0, 1.0f32, 1.0);
    for _ in 0..whole {
        sum += o * noise3(lambda * p);
        lambda *= 1.99;
        o *= omega;
    }
    sum + o * smooth_step(0.3, 0.7, n - whole as f32) * noise3(lambda * p)
}

/// pbrt-v3's `Turbulence`: as [`fbm`] with the absolute value of each octave, and the octaves
/// the footprint leaves out counted at their mean, 0.2 times their amplitude.
pub fn turbulence(p: Vec3, dpdx: Vec3, dpdy: Vec3, omega: f32, max_octaves: u32) -> f32 {
    let n = octave_count(dpdx, dpdy, max_octaves);
    let whole = n.floor() as u32;
    let (mut sum, mut lambda, mut o) = (0.0, 1.0f32, 1.0);
    for _ in 0..whole {
        sum += o * noise3(lambda * p).abs();
        lambda *= 1.99;
        o *= omega;
    }
    let partial = smooth_step(0.3, 0.7, n - whole as f32);
    sum += o * (0.2 + partial * (noise3(lambda * p).abs() - 0.2));
    for _ in whole..max_octaves {
        sum += o * 0.2;
        o *= omega;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_zero_on_the_lattice_and_bounded_between() {
        for (x, y, z) in [(0.0, 0.0, 0.0), (3.0, -7.0, 12.0), (255.0, 256.0, -1.0)] {
            assert_eq!(noise(x, y, z), 0.0);
        }
        let mut k = 0u32;
        for i in 0..2000 {
            let t = i as f32 * 0.137;
            let v = noise(t, t * 0.71 + 3.3, -t * 1.37);
            assert!(v.is_finite() && v.abs() <= 1.0, "{v}");
            k += u32::from(v != 0.0);
        }
        assert!(k > 1900);
    }

    #[test]
    // The values as pbrt-v3 printed them (%.9g).
    #[allow(clippy::excessive_precision)]
    fn noise_fbm_and_turbulence_match_pbrt_v3() {
        // Printed by pbrt-v3 itself: Noise, FBm and Turbulence (omega 0.5, 8 octaves, zero
        // differentials) at these points, from a program linked with pbrt-v3's libpbrt
        // (core/texture.h's functions; tests/data/pbrt-v3/noisecheck.cpp).
        let cases = [
            ([0.5, 0.5, 0.5], [-0.125, -0.118037626, 0.188432008]),
            ([1.3, 2.7, 0.4], [0.571163952, 0.890168071, 0.891302645]),
            ([-3.21, 7.7, 12.05], [0.343819857, 0.320599794, 0.502978921]),
            (
                [100.25, -40.5, 3.125],
                [0.150135666, 0.105533428, 0.203138635],
            ),
        ];
        for (p, want) in cases {
            let p = Vec3::from_array(p);
            let got = [
                noise3(p),
                fbm(p, Vec3::ZERO, Vec3::ZERO, 0.5, 8),
                turbulence(p, Vec3::ZERO, Vec3::ZERO, 0.5, 8),
            ];
            for (g, w) in got.iter().zip(want) {
                assert!((g - w).abs() < 2e-6, "{p}: {got:?} against {want:?}");
            }
        }
        // Periodic over 256 in every axis, as pbrt-v3's masked lattice is.
        let (a, b) = (noise(1.3, 2.7, 0.4), noise(257.3, 2.7 - 256.0, 512.4));
        assert!((a - b).abs() < 1e-4, "{a} {b}");
    }

    #[test]
    fn fbm_and_turbulence_sum_their_octaves() {
        let p = Vec3::new(0.3, 1.7, -2.2);
        assert_eq!(fbm(p, Vec3::ZERO, Vec3::ZERO, 0.5, 1), noise3(p));
        let two = noise3(p) + 0.5 * noise3(1.99 * p);
        assert!((fbm(p, Vec3::ZERO, Vec3::ZERO, 0.5, 2) - two).abs() < 1e-6);
        let t = noise3(p).abs() + 0.5 * 0.2;
        assert!((turbulence(p, Vec3::ZERO, Vec3::ZERO, 0.5, 1) - t).abs() < 1e-6);
        assert!(turbulence(p, Vec3::ZERO, Vec3::ZERO, 0.5, 8) > 0.0);
    }
}
