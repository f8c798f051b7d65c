//! sppm's photon pass (pbrt-v3's `SPPMIntegrator::Render`, its photon stage): photons leave
//! the lights (chosen by power) along `sample_le`'s rays, every hit after the first adds
//! throughput x the visible point's BSDF to each visible point within its pixel's radius, and
//! the path scatters on by BSDF sampling (importance transport) with pbrt-v3's Russian
//! roulette. A photon's dimensions are the Halton sequence at its index over all iterations,
//! each dimension shifted by the seed.
//!
//! pbrt-v3 adds the flux with atomic float adds, whose order (and so the sum's rounding)
//! depends on the threads. Here photons are traced in fixed blocks in parallel, each block
//! listing its deposits in photon order, and the lists are added in block order: the sums are
//! the same whatever the thread count.

use super::grid::Grid;
use super::visible::VisiblePoint;
use crate::bsdf::Bsdf;
use crate::geometry::{is_valid_radiance, Spectrum, Vec2, Vec3};
use crate::light::emission::sample_le;
use crate::lightdistrib::LightPmf;
use crate::scene::Scene;
use rayon::prelude::*;

/// Photons per parallel task (fixed, so that the work's split is the same on any machine).
const BLOCK: u64 = 1024;
/// Blocks traced before their deposits are added (bounds the memory of the lists).
const BLOCKS_PER_ROUND: u64 = 64;
/// Most consecutive pass-through surfaces a photon may cross.
const MAX_PASS_THROUGH: u32 = 256;

/// The first primes: the Halton bases of a photon's dimensions.
const PRIMES: [u32; 48] = [
    2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97,
    101, 103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193,
    197, 199, 211, 223,
];

/// What one iteration's photons brought to the visible points.
#[derive(Default)]
pub struct Gathered {
    /// Flux at each pixel's visible point (pbrt-v3's `Phi`).
    pub phi: Vec<[f64; 3]>,
    /// Photons that found each pixel's visible point (pbrt-v3's `M`).
    pub m: Vec<u32>,
    /// Rays traced.
    pub rays: u64,
    /// Deposits dropped for being NaN, infinite or negative.
    pub dropped: u64,
}

/// Shoots photons into a scene.
pub struct Shooter<'s> {
    scene: &'s Scene,
    /// Light choice by power (pbrt-v3's `ComputeLightPowerDistribution`).
    lights: LightPmf,
    max_depth: u32,
    /// Each dimension's shift (Cranley-Patterson rotation) under the seed.
    shifts: [f32; PRIMES.len()],
    seed: u64,
    /// The last iteration's gatherings (its buffers reused).
    gathered: Gathered,
    /// Each pixel's visible point and squared radius, for the lookups.
    near: Vec<(Vec3, f32)>,
    /// One round's blocks (their deposit lists reused).
    pool: Vec<Block>,
}

/// SplitMix64's finaliser.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A value in [0, 1) from the top 24 bits of `h`.
fn unit(h: u64) -> f32 {
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// The radical inverse of `i` in `B`, below 1 (a constant base, so that the divisions are
/// multiplications, as pbrt-v3's `RadicalInverse` specialises them).
#[inline]
fn radical_inverse<const B: u64>(mut i: u64) -> f32 {
    let inv = 1.0 / B as f64;
    let (mut reversed, mut factor) = (0u64, 1.0f64);
    // Below 2^32 (every index short of four billion photons) the digits come from 32-bit
    // divisions, cheaper than 64-bit ones; the digits and so the value are the same.
    if let Ok(mut j) = u32::try_from(i) {
        let b = B as u32;
        while j > 0 {
            let next = j / b;
            reversed = reversed * B + u64::from(j - next * b);
            factor *= inv;
            j = next;
        }
        i = 0;
    }
    while i > 0 {
        let next = i / B;
        reversed = reversed * B + (i - next * B);
        factor *= inv;
        i = next;
    }
    ((reversed as f64 * factor) as f32).min(1.0 - f32::EPSILON / 2.0)
}

/// The radical inverse of `i` in the `d`-th prime (`d` below `PRIMES.len()`).
#[inline]
fn halton(d: usize, i: u64) -> f32 {
    macro_rules! bases {
        ($($k:literal => $b:literal),*) => {
            match d {
                0 => (i.reverse_bits() >> 11) as f32 * (1.0 / (1u64 << 53) as f32),
                $($k => radical_inverse::<$b>(i),)*
                _ => unreachable!("dimension {d} has no prime"),
            }
        };
    }
    bases!(1 => 3, 2 => 5, 3 => 7, 4 => 11, 5 => 13, 6 => 17, 7 => 19, 8 => 23, 9 => 29,
        10 => 31, 11 => 37, 12 => 41, 13 => 43, 14 => 47, 15 => 53, 16 => 59, 17 => 61,
        18 => 67, 19 => 71, 20 => 73, 21 => 79, 22 => 83, 23 => 89, 24 => 97, 25 => 101,
        26 => 103, 27 => 107, 28 => 109, 29 => 113, 30 => 127, 31 => 131, 32 => 137,
        33 => 139, 34 => 149, 35 => 151, 36 => 157, 37 => 163, 38 => 167, 39 => 173,
        40 => 179, 41 => 181, 42 => 191, 43 => 193, 44 => 197, 45 => 199, 46 => 211,
        47 => 223)
}

/// A photon's dimensions: Halton at its index, shifted; past the primes, hashed.
struct Dims<'a> {
    index: u64,
    dim: usize,
    shifts: &'a [f32; PRIMES.len()],
    seed: u64,
}

impl Dims<'_> {
    #[inline]
    fn next(&mut self) -> f32 {
        let d = self.dim;
        self.dim += 1;
        match self.shifts.get(d) {
            Some(&shift) => {
                let v = halton(d, self.index) + shift;
                let v = if v >= 1.0 { v - 1.0 } else { v };
                v.min(1.0 - f32::EPSILON / 2.0)
            }
            None => unit(mix64(self.index ^ mix64(self.seed ^ mix64(d as u64)))),
        }
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next();
        Vec2::new(x, self.next())
    }
}

/// One block's deposits in photon order, with its rays and drops.
#[derive(Default)]
struct Block {
    deposits: Vec<(u32, Spectrum)>,
    rays: u64,
    dropped: u64,
}

impl<'s> Shooter<'s> {
    /// A shooter for `scene` with paths of at most `max_depth` bounces, under `seed`.
    pub fn new(scene: &'s Scene, max_depth: u32, seed: u64) -> Self {
        let power: Vec<f32> = scene
            .lights
            .iter()
            .map(|l| crate::spectrum_luminance(l.power()))
            .collect();
        let mut shifts = [0.0; PRIMES.len()];
        for (d, s) in shifts.iter_mut().enumerate() {
            *s = unit(mix64(seed ^ mix64(0x5151 + d as u64)));
        }
        Self {
            scene,
            lights: LightPmf::new(&power),
            max_depth,
            shifts,
            seed,
            gathered: Gathered::default(),
            near: Vec::new(),
            pool: Vec::new(),
        }
    }

    /// Shoots iteration `iter`'s `count` photons at the visible points in `grid` (`visible`
    /// and `radii` by pixel).
    pub fn shoot(
        &mut self,
        grid: &Grid,
        visible: &[Option<VisiblePoint>],
        radii: &[f32],
        iter: u32,
        count: u64,
    ) -> &Gathered {
        // The buffers are kept from iteration to iteration: allocating, growing and freeing
        // them each time cost about 3% of a render (perf).
        let g = &mut self.gathered;
        g.phi.clear();
        g.phi.resize(visible.len(), [0.0; 3]);
        g.m.clear();
        g.m.resize(visible.len(), 0);
        (g.rays, g.dropped) = (0, 0);
        if self.scene.lights.is_empty() {
            return &self.gathered;
        }
        // Each pixel's visible point and squared radius packed in 16 bytes: the lookups test
        // distances here instead of in the visible points (about 0.8 kB each, with their
        // BSDFs), which cache misses made slow. No visible point: a radius that takes nothing.
        let mut near = std::mem::take(&mut self.near);
        near.clear();
        near.extend(visible.iter().zip(radii).map(|(vp, &r)| match vp {
            Some(vp) => (vp.p, r * r),
            None => (Vec3::ZERO, f32::NEG_INFINITY),
        }));
        let mut pool = std::mem::take(&mut self.pool);
        pool.resize_with(BLOCKS_PER_ROUND as usize, Block::default);
        let mut g = std::mem::take(&mut self.gathered);
        let first = u64::from(iter) * count;
        let blocks = count.div_ceil(BLOCK);
        let mut round = 0;
        while round < blocks {
            let end = (round + BLOCKS_PER_ROUND).min(blocks);
            let traced = &mut pool[..(end - round) as usize];
            traced.par_iter_mut().enumerate().for_each(|(k, block)| {
                block.deposits.clear();
                (block.rays, block.dropped) = (0, 0);
                let b = round + k as u64;
                let mut bsdf = Bsdf::empty();
                for i in b * BLOCK..((b + 1) * BLOCK).min(count) {
                    self.trace(first + i, grid, visible, &near, &mut bsdf, block);
                }
            });
            for block in traced.iter() {
                g.rays += block.rays;
                g.dropped += block.dropped;
                for &(pixel, phi) in &block.deposits {
                    let (s, m) = (&mut g.phi[pixel as usize], &mut g.m[pixel as usize]);
                    s[0] += f64::from(phi.x);
                    s[1] += f64::from(phi.y);
                    s[2] += f64::from(phi.z);
                    *m += 1;
                }
            }
            round = end;
        }
        (self.near, self.pool, self.gathered) = (near, pool, g);
        &self.gathered
    }

    /// Traces photon `index` (over all iterations), its deposits added to `block`; `near` is
    /// each pixel's visible point and squared radius, `bsdf` a BSDF refilled at each hit.
    fn trace(
        &self,
        index: u64,
        grid: &Grid,
        visible: &[Option<VisiblePoint>],
        near: &[(Vec3, f32)],
        bsdf: &mut Bsdf,
        block: &mut Block,
    ) {
        let scene = self.scene;
        let mut dims = Dims {
            index,
            dim: 0,
            shifts: &self.shifts,
            seed: self.seed,
        };
        let (light, light_pdf) = self.lights.sample(dims.next());
        let u1 = dims.next_2d();
        let u2 = dims.next_2d();
        let cam = &scene.camera;
        let time = cam.shutter_open + dims.next() * (cam.shutter_close - cam.shutter_open);
        let Some(s) = sample_le(scene, &scene.lights[light], u1, u2, time) else {
            return;
        };
        let mut beta = s.le * (s.n.dot(s.ray.d).abs() / (light_pdf * s.pdf_pos * s.pdf_dir));
        if !is_valid_radiance(beta) || beta == Spectrum::ZERO {
            return;
        }
        let mut ray = s.ray;
        let mut depth = 0;
        let mut pass_through = 0;
        while depth < self.max_depth {
            block.rays += 1;
            let Some(hit) = scene.closest_hit(&ray) else {
                break;
            };
            // Made in its local: a hit returned with its interaction was copied (180 bytes).
            let mut si = scene.interaction(&ray, &hit);
            let surface = scene.surface_of(&hit);
            if depth > 0 {
                let wi = -ray.d.normalize();
                for &pixel in grid.candidates(si.p) {
                    let (p, r2) = near[pixel as usize];
                    if p.distance_squared(si.p) > r2 {
                        continue;
                    }
                    let Some(vp) = &visible[pixel as usize] else {
                        continue;
                    };
                    let phi = beta * vp.bsdf.f(vp.wo, wi);
                    if is_valid_radiance(phi) {
                        block.deposits.push((pixel, phi));
                    } else {
                        block.dropped += 1;
                    }
                }
            }
            let Some(material) = surface.material else {
                pass_through += 1;
                if pass_through > MAX_PASS_THROUGH {
                    break;
                }
                ray = si.spawn_ray(ray.d);
                continue;
            };
            let material = &scene.materials[material as usize];
            material.shade(&mut si);
            material.bsdf_into(&si, bsdf);
            let u = dims.next_2d();
            let u_lobe = dims.next();
            let Some(bs) = bsdf.sample_f(si.wo, u, u_lobe) else {
                break;
            };
            if bs.pdf <= 0.0 || bs.f == Spectrum::ZERO {
                break;
            }
            let mut bnew = beta * bs.f * (bs.wi.dot(si.shading_n).abs() / bs.pdf);
            // The BSDFs scale radiance by (eta_i / eta_t)^2 across a refraction; photons carry
            // flux, which pbrt-v3's importance transport leaves unscaled: undo it.
            let eta = bsdf.eta();
            if eta != 1.0 && bs.wi.dot(si.n) * si.wo.dot(si.n) < 0.0 {
                bnew *= if si.wo.dot(si.n) > 0.0 {
                    eta * eta
                } else {
                    1.0 / (eta * eta)
                };
            }
            if !is_valid_radiance(bnew) {
                break;
            }
            let y_old = crate::spectrum_luminance(beta);
            let q = if y_old > 0.0 {
                (1.0 - crate::spectrum_luminance(bnew) / y_old).max(0.0)
            } else {
                1.0
            };
            if dims.next() < q {
                break;
            }
            beta = bnew / (1.0 - q);
            ray = si.spawn_ray(bs.wi);
            depth += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{halton, PRIMES};

    /// The specialised radical inverses are the plain one of each prime.
    #[test]
    fn halton_dimensions_are_the_radical_inverses_of_the_primes() {
        for (d, &p) in PRIMES.iter().enumerate() {
            for i in [0u32, 1, 2, 7, 100, 12345, 987_654_321] {
                let want = crate::lightdistrib::radical_inverse(p, i);
                let got = halton(d, u64::from(i));
                assert!(
                    (got - want).abs() < 1e-6,
                    "base {p}, index {i}: {got} vs {want}"
                );
            }
        }
    }
}
