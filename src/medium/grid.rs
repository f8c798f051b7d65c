//! pbrt-v3's `GridDensityMedium` (src/media/grid.cpp): a density grid over the box `p0`..`p1`
//! of the medium's space, trilinearly interpolated, scaling spectrally uniform coefficients;
//! distances sampled by delta tracking and transmittance estimated by ratio tracking (with
//! Russian roulette below 0.1), both against the grid's largest density as majorant.

use super::MediumSample;
use crate::geometry::{Spectrum, Vec3};
use glam::Mat4;

/// A heterogeneous medium: coefficients times a density grid.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Scattering coefficient at density 1.
    pub sigma_s: Spectrum,
    /// Extinction at density 1 (pbrt-v3 takes the first channel: it must be uniform).
    pub sigma_t: f32,
    /// Voxels along x, y, z.
    pub n: [usize; 3],
    /// The densities, x fastest, then y, then z.
    pub density: Vec<f32>,
    /// 1 / the largest density (0 when the grid is empty).
    inv_max_density: f32,
    /// The grid's unit cube from render space.
    grid_from_render: Mat4,
}

impl Grid {
    /// The grid `density` of `n` voxels (x fastest), placed so that its unit cube maps to
    /// render space by `render_from_grid`. The count must be `n[0] * n[1] * n[2]`.
    pub fn new(
        sigma_s: Spectrum,
        sigma_t: f32,
        n: [usize; 3],
        density: Vec<f32>,
        render_from_grid: Mat4,
    ) -> Self {
        debug_assert_eq!(density.len(), n[0] * n[1] * n[2]);
        let max = density.iter().copied().fold(0.0f32, f32::max);
        Self {
            sigma_s,
            sigma_t,
            n,
            density,
            inv_max_density: if max > 0.0 { 1.0 / max } else { 0.0 },
            grid_from_render: render_from_grid.inverse(),
        }
    }

    /// pbrt-v3's `D`: a voxel's density, zero outside the grid.
    #[inline]
    fn d(&self, x: i64, y: i64, z: i64) -> f32 {
        let [nx, ny, nz] = self.n.map(|v| v as i64);
        if x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz {
            return 0.0;
        }
        self.density[((z * ny + y) * nx + x) as usize]
    }

    /// pbrt-v3's `Density`: the trilinear interpolation at `p` in the unit cube (voxel
    /// centres at (i + 0.5) / n).
    pub fn density_at(&self, p: Vec3) -> f32 {
        let s = Vec3::new(
            p.x * self.n[0] as f32 - 0.5,
            p.y * self.n[1] as f32 - 0.5,
            p.z * self.n[2] as f32 - 0.5,
        );
        let f = s.floor();
        let d = s - f;
        let (x, y, z) = (f.x as i64, f.y as i64, f.z as i64);
        let c = self.corners(x, y, z);
        let lerp = |t: f32, a: f32, b: f32| (1.0 - t) * a + t * b;
        let d00 = lerp(d.x, c[0], c[1]);
        let d10 = lerp(d.x, c[2], c[3]);
        let d01 = lerp(d.x, c[4], c[5]);
        let d11 = lerp(d.x, c[6], c[7]);
        lerp(d.z, lerp(d.y, d00, d10), lerp(d.y, d01, d11))
    }

    /// The densities of the eight voxels from (x, y, z) to (x + 1, y + 1, z + 1), x fastest,
    /// then y, then z: read straight from the array where all eight lie inside the grid (the
    /// common case, one bounds test), else voxel by voxel with zeros outside.
    #[inline]
    fn corners(&self, x: i64, y: i64, z: i64) -> [f32; 8] {
        let [nx, ny, nz] = self.n.map(|v| v as i64);
        if x >= 0 && y >= 0 && z >= 0 && x + 1 < nx && y + 1 < ny && z + 1 < nz {
            let (sx, sy) = (nx as usize, (nx * ny) as usize);
            let base = ((z * ny + y) * nx + x) as usize;
            let g = &self.density[base..=base + sy + sx + 1];
            return [
                g[0],
                g[1],
                g[sx],
                g[sx + 1],
                g[sy],
                g[sy + 1],
                g[sy + sx],
                g[sy + sx + 1],
            ];
        }
        [
            self.d(x, y, z),
            self.d(x + 1, y, z),
            self.d(x, y + 1, z),
            self.d(x + 1, y + 1, z),
            self.d(x, y, z + 1),
            self.d(x + 1, y, z + 1),
            self.d(x, y + 1, z + 1),
            self.d(x + 1, y + 1, z + 1),
        ]
    }

    /// The ray (origin `o`, direction `d`, ending at parameter `t_max`) in the grid's space
    /// with a unit-length world direction, and the distances over which it crosses the unit
    /// cube; `None` when it misses it, or the medium cannot interact.
    fn overlap(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(Vec3, Vec3, f32, f32, f32)> {
        if self.inv_max_density == 0.0 || self.sigma_t <= 0.0 {
            return None;
        }
        let len = d.length();
        let om = self.grid_from_render.transform_point3(o);
        let dm = self.grid_from_render.transform_vector3(d / len);
        let (mut t0, mut t1) = (0.0f32, t_max * len);
        for a in 0..3 {
            let inv = 1.0 / dm[a];
            let (mut near, mut far) = ((0.0 - om[a]) * inv, (1.0 - om[a]) * inv);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            // NaN (a ray in the slab's plane) keeps the interval as it is.
            t0 = if near > t0 { near } else { t0 };
            t1 = if far < t1 { far } else { t1 };
            if t0 > t1 {
                return None;
            }
        }
        Some((om, dm, t0, t1, len))
    }

    /// pbrt-v3's delta tracking: a scattering point (as a parameter of the ray given) with
    /// weight sigma_s / sigma_t, or none with weight one.
    pub fn sample(
        &self,
        o: Vec3,
        d: Vec3,
        t_max: f32,
        u: &mut impl FnMut() -> f32,
    ) -> MediumSample {
        let none = MediumSample {
            weight: Spectrum::ONE,
            t: None,
        };
        let Some((om, dm, t_min, t_far, len)) = self.overlap(o, d, t_max) else {
            return none;
        };
        let step = self.inv_max_density / self.sigma_t;
        let mut t = t_min;
        loop {
            t -= (1.0 - u()).ln() * step;
            if t >= t_far {
                return none;
            }
            if self.density_at(om + dm * t) * self.inv_max_density > u() {
                return MediumSample {
                    weight: self.sigma_s / self.sigma_t,
                    t: Some(t / len),
                };
            }
        }
    }

    /// pbrt-v3's ratio tracking with Russian roulette: an unbiased estimate of the
    /// transmittance along the ray up to parameter `t_max`.
    pub fn tr(&self, o: Vec3, d: Vec3, t_max: f32, u: &mut impl FnMut() -> f32) -> Spectrum {
        let Some((om, dm, t_min, t_far, _)) = self.overlap(o, d, t_max) else {
            return Spectrum::ONE;
        };
        let step = self.inv_max_density / self.sigma_t;
        let (mut tr, mut t) = (1.0f32, t_min);
        loop {
            t -= (1.0 - u()).ln() * step;
            if t >= t_far {
                return Spectrum::splat(tr);
            }
            let density = self.density_at(om + dm * t);
            tr *= 1.0 - (density * self.inv_max_density).max(0.0);
            if tr < 0.1 {
                let q = (1.0 - tr).max(0.05);
                if u() < q {
                    return Spectrum::ZERO;
                }
                tr /= 1.0 - q;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rng(seed: u64) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        }
    }

    /// Trilinear lookups reproduce voxel values at their centres and interpolate between.
    #[test]
    fn trilinear_lookup_as_pbrt_v3() {
        let density: Vec<f32> = (0..8).map(|i| i as f32).collect();
        let g = Grid::new(Spectrum::ONE, 1.0, [2, 2, 2], density, Mat4::IDENTITY);
        assert_eq!(g.density_at(Vec3::new(0.25, 0.25, 0.25)), 0.0);
        assert_eq!(g.density_at(Vec3::new(0.75, 0.25, 0.25)), 1.0);
        assert_eq!(g.density_at(Vec3::new(0.75, 0.75, 0.75)), 7.0);
        assert!((g.density_at(Vec3::new(0.5, 0.5, 0.5)) - 3.5).abs() < 1e-6);
        // Half a voxel beyond the centres the grid fades towards zero outside.
        assert!((g.density_at(Vec3::new(1.0, 0.75, 0.75)) - 3.5).abs() < 1e-6);
    }

    /// The eight corners read straight from the array (inside) are those read voxel by voxel
    /// (with zeros outside), over points inside, on the rim and outside the unit cube.
    #[test]
    fn corner_fast_path_reads_the_same_voxels() {
        let n = [5, 3, 4];
        let density: Vec<f32> = (0..60).map(|i| (i * 7 % 13) as f32 + 0.5).collect();
        let g = Grid::new(Spectrum::ONE, 1.0, n, density, Mat4::IDENTITY);
        let mut u = rng(3);
        let mut inside = 0;
        for _ in 0..2000 {
            let (x, y, z) = (
                (u() * 8.0) as i64 - 2,
                (u() * 6.0) as i64 - 2,
                (u() * 7.0) as i64 - 2,
            );
            let slow = [
                g.d(x, y, z),
                g.d(x + 1, y, z),
                g.d(x, y + 1, z),
                g.d(x + 1, y + 1, z),
                g.d(x, y, z + 1),
                g.d(x + 1, y, z + 1),
                g.d(x, y + 1, z + 1),
                g.d(x + 1, y + 1, z + 1),
            ];
            assert_eq!(g.corners(x, y, z), slow, "{x} {y} {z}");
            inside += usize::from(slow.iter().all(|&v| v > 0.0));
        }
        assert!(inside > 100, "{inside}");
    }

    /// Ratio tracking and delta tracking agree with the transmittance of a constant grid
    /// away from its faded rim: exp(-sigma_t * density * distance).
    #[test]
    fn tracking_estimates_are_unbiased() {
        // A 4^3 grid of density 2 scaled to [-2, 2]^3: the ray along x through the middle
        // from x = -1 to 1 stays in the constant part (the rim fades in the outer half voxel).
        let n = [4, 4, 4];
        let render_from_grid =
            Mat4::from_translation(Vec3::splat(-2.0)) * Mat4::from_scale(Vec3::splat(4.0));
        let g = Grid::new(
            Spectrum::splat(0.5),
            0.6,
            n,
            vec![2.0; 64],
            render_from_grid,
        );
        let (o, d) = (Vec3::new(-1.0, 0.1, -0.2), Vec3::new(2.0, 0.0, 0.0));
        let expected = (-0.6f32 * 2.0 * 2.0).exp();
        let mut u = rng(7);
        let runs = 100_000;
        let mut ratio = 0.0f64;
        let mut passed = 0usize;
        for _ in 0..runs {
            ratio += f64::from(g.tr(o, d, 1.0, &mut u).x);
            let s = g.sample(o, d, 1.0, &mut u);
            if s.t.is_none() {
                passed += 1;
            } else {
                assert!((s.weight.x - 0.5 / 0.6).abs() < 1e-6);
            }
        }
        let ratio = ratio / runs as f64;
        let delta = passed as f64 / runs as f64;
        assert!(
            (ratio - f64::from(expected)).abs() < 0.005,
            "{ratio} {expected}"
        );
        assert!(
            (delta - f64::from(expected)).abs() < 0.005,
            "{delta} {expected}"
        );
        // A grid of two halves, density 0.1 and 3, crossed along x: both estimators give
        // exp(-sigma_t * (0.1 + 3) * half length) against the grid's majorant.
        let mut two = vec![0.1f32; 64 * 64 * 4];
        for z in 0..4 {
            for y in 0..64 {
                for x in 32..64 {
                    two[(z * 64 + y) * 64 + x] = 3.0;
                }
            }
        }
        let g2 = Grid::new(
            Spectrum::splat(0.5),
            0.6,
            [64, 64, 4],
            two,
            render_from_grid,
        );
        let half = 1.5f32;
        let expected2 = (-0.6f32 * (0.1 + 3.0) * half).exp();
        let (o2, d2) = (Vec3::new(-1.5, 0.1, 0.0), Vec3::new(3.0, 0.0, 0.0));
        let (mut ratio2, mut passed2) = (0.0f64, 0usize);
        for _ in 0..runs {
            ratio2 += f64::from(g2.tr(o2, d2, 1.0, &mut u).x);
            if g2.sample(o2, d2, 1.0, &mut u).t.is_none() {
                passed2 += 1;
            }
        }
        let (ratio2, delta2) = (ratio2 / runs as f64, passed2 as f64 / runs as f64);
        assert!(
            (ratio2 - f64::from(expected2)).abs() < 0.004,
            "{ratio2} {expected2}"
        );
        assert!(
            (delta2 - f64::from(expected2)).abs() < 0.004,
            "{delta2} {expected2}"
        );
        // A ray that misses the box passes whole.
        let far = Vec3::new(0.0, 5.0, 0.0);
        assert_eq!(g.tr(far, d, 1.0, &mut u), Spectrum::ONE);
    }
}
