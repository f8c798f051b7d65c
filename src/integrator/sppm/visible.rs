//! sppm's camera pass (pbrt-v3's `SPPMIntegrator::Render`, its first stage): one camera path
//! per pixel, direct light at every vertex and emission seen directly or through specular
//! bounces added to the pixel's `ld`, the path followed through specular and glossy vertices
//! to its first diffuse one (or a glossy one at the last depth), the visible point.

use super::{Crop, PixelState};
use crate::bsdf::{Bsdf, BxdfType};
use crate::camera::CameraSample;
use crate::geometry::{Ray, RayDifferentials, Spectrum, SurfaceInteraction, Vec2, Vec3};
use crate::scene::Scene;
use crate::stream::SampleStream;
use rayon::prelude::*;

/// Most consecutive pass-through surfaces (`Material ""`) a path may cross (as the path
/// integrator's guard against a ray trapped between coincident interfaces).
const MAX_PASS_THROUGH: u32 = 256;

/// pbrt-v3's Russian roulette of camera paths: below this throughput luminance.
const RR_BELOW: f32 = 0.25;

/// Where a camera path stopped to gather photons.
#[derive(Clone, Debug)]
pub struct VisiblePoint {
    /// The point.
    pub p: Vec3,
    /// Unit direction back along the camera path.
    pub wo: Vec3,
    /// The BSDF there.
    pub bsdf: Bsdf,
    /// The camera path's throughput to it.
    pub beta: Spectrum,
}

/// One iteration's camera pass.
pub struct CameraPass<'s> {
    /// The scene.
    pub scene: &'s Scene,
    /// The pixels.
    pub crop: Crop,
    /// The iteration (the sample index of every pixel's camera sample).
    pub iteration: u32,
    /// All iterations (the ray differentials are scaled by 1 / sqrt of it, as pbrt-v3).
    pub iterations: u32,
    /// Longest camera path.
    pub max_depth: u32,
    /// The render's seed.
    pub seed: u64,
}

/// Pixels per parallel task.
const PIXELS_PER_TASK: usize = 64;

impl CameraPass<'_> {
    /// Traces every pixel's camera path: adds its direct light to `pixels` and puts its
    /// visible point, if any, in `visible` (one entry per pixel). Returns the rays traced.
    pub fn run(&self, pixels: &mut [PixelState], visible: &mut Vec<Option<VisiblePoint>>) -> u64 {
        // The slots are kept from iteration to iteration: each pixel's BSDF is refilled in its
        // slot, where building it elsewhere and moving it in copied 0.7 kB several times.
        if visible.len() != pixels.len() {
            visible.clear();
            visible.resize(pixels.len(), None);
        }
        pixels
            .par_chunks_mut(PIXELS_PER_TASK)
            .zip(visible.par_chunks_mut(PIXELS_PER_TASK))
            .enumerate()
            .map(|(chunk, (ps, vs))| {
                let mut rays = 0u64;
                for (k, (p, v)) in ps.iter_mut().zip(vs.iter_mut()).enumerate() {
                    let (ld, r) = self.trace(chunk * PIXELS_PER_TASK + k, v);
                    p.ld += ld;
                    rays += u64::from(r);
                }
                rays
            })
            .sum()
    }

    /// The camera path of pixel `i`: its direct light and rays traced; its visible point is
    /// written to `slot`.
    fn trace(&self, i: usize, slot: &mut Option<VisiblePoint>) -> (Spectrum, u32) {
        let scene = self.scene;
        let (x, y) = self.crop.pixel(i);
        let key = u64::from(y) * u64::from(scene.film.resolution.0) + u64::from(x);
        let mut stream = SampleStream::new(key, self.iteration, self.seed, 0);
        let film = Vec2::new(x as f32, y as f32) + stream.next_2d();
        let lens = stream.next_2d();
        let sample = CameraSample {
            film,
            lens,
            time: stream.next_1d(),
        };
        let (ray, diff) = if scene.uses_differentials {
            let (ray, diff) = scene.camera.generate_ray_differential(&sample);
            let s = 1.0 / (self.iterations.max(1) as f32).sqrt();
            (ray, Some(diff.scaled(&ray, s)))
        } else {
            (scene.camera.generate_ray(&sample), None)
        };
        self.follow(ray, diff, &mut stream, slot)
    }

    /// Follows a camera ray to its visible point.
    fn follow(
        &self,
        mut ray: Ray,
        mut diff: Option<RayDifferentials>,
        stream: &mut SampleStream,
        slot: &mut Option<VisiblePoint>,
    ) -> (Spectrum, u32) {
        let scene = self.scene;
        let mut ld = Spectrum::ZERO;
        let mut beta = Spectrum::ONE;
        let mut rays = 0u32;
        let mut specular_bounce = false;
        let mut depth = 0;
        let mut pass_through = 0;
        let vp = slot.get_or_insert_with(|| VisiblePoint {
            p: Vec3::ZERO,
            wo: Vec3::ZERO,
            bsdf: Bsdf::empty(),
            beta: Spectrum::ZERO,
        });
        while depth < self.max_depth {
            rays += 1;
            let Some(hit) = scene.closest_hit(&ray) else {
                for &l in &scene.infinite_lights {
                    ld += beta * scene.lights[l as usize].le(ray.d.normalize());
                }
                break;
            };
            // Made in its local: a hit returned with its interaction was copied (180 bytes).
            let mut si = scene.interaction(&ray, &hit);
            let surface = scene.surface_of(&hit);
            if let Some(d) = diff.take() {
                si.compute_differentials(&d);
            }
            let Some(material) = surface.material else {
                pass_through += 1;
                if pass_through > MAX_PASS_THROUGH {
                    break;
                }
                ray = si.spawn_ray(ray.d);
                continue;
            };
            if depth == 0 || specular_bounce {
                if let Some(l) = surface.area_light {
                    ld += beta * scene.lights[l as usize].l(&si, si.wo);
                }
            }
            let material = &scene.materials[material as usize];
            material.shade(&mut si);
            material.bsdf_into(&si, &mut vp.bsdf);
            let bsdf = &vp.bsdf;
            ld += beta * direct(scene, &si, bsdf, stream, &mut rays);
            let has = |t: BxdfType| bsdf.lobes().iter().any(|l| l.bxdf.kind().contains(t));
            if has(BxdfType::DIFFUSE) || (has(BxdfType::GLOSSY) && depth + 1 == self.max_depth) {
                vp.p = si.p;
                vp.wo = si.wo;
                vp.beta = beta;
                return (ld, rays);
            }
            if depth + 1 >= self.max_depth {
                break;
            }
            let u_lobe = stream.next_1d();
            let u = stream.next_2d();
            let Some(s) = bsdf.sample_f(si.wo, u, u_lobe) else {
                break;
            };
            if s.pdf <= 0.0 || s.f == Spectrum::ZERO {
                break;
            }
            specular_bounce = s.specular;
            beta *= s.f * s.wi.dot(si.shading_n).abs() / s.pdf;
            if !crate::geometry::is_valid_radiance(beta) {
                break;
            }
            let y = crate::spectrum_luminance(beta);
            if y < RR_BELOW {
                let continue_prob = y.min(1.0);
                if stream.next_1d() > continue_prob {
                    break;
                }
                beta /= continue_prob;
            }
            ray = si.spawn_ray(s.wi);
            depth += 1;
        }
        *slot = None;
        (ld, rays)
    }
}

/// pbrt-v3's `UniformSampleOneLight` at `si`, by light sampling alone: one light chosen
/// uniformly, one sample of it. (pbrt-v3 adds a BSDF sample weighted by MIS; the expectation
/// is the same, as emission found after a glossy bounce is not counted either.)
fn direct(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &Bsdf,
    stream: &mut SampleStream,
    rays: &mut u32,
) -> Spectrum {
    let n = scene.lights.len();
    let u_light = stream.next_1d();
    let u = stream.next_2d();
    if n == 0 || !bsdf.has_non_specular() {
        return Spectrum::ZERO;
    }
    let index = ((u_light * n as f32) as usize).min(n - 1);
    let light = &scene.lights[index];
    let Some(ls) = light.sample_li(&scene.accel.world, si.p, u) else {
        return Spectrum::ZERO;
    };
    if ls.pdf <= 0.0 || ls.li == Spectrum::ZERO {
        return Spectrum::ZERO;
    }
    let f = bsdf.f(si.wo, ls.wi) * ls.wi.dot(si.shading_n).abs();
    if f == Spectrum::ZERO {
        return Spectrum::ZERO;
    }
    *rays += 1;
    if scene.occluded(si, ls.p) {
        return Spectrum::ZERO;
    }
    f * ls.li * (n as f32 / ls.pdf)
}
