//! mlt's path function over bdpt: pbrt-v3's `MLTIntegrator::L` (docs/light-transport.md,
//! `## mlt`). One connection strategy (s, t) of the path length asked for, chosen uniformly
//! from the camera stream, its camera subpath from a raster position over the rendering
//! space, its light subpath, and bdpt's `connect`, times the number of strategies.

use super::contribution::{raster_position, Contribution, PathContribution};
use super::sampler::{MltSampler, CAMERA_STREAM, CONNECTION_STREAM, LIGHT_STREAM};
use crate::camera::CameraSample;
use crate::geometry::Vec3;
use crate::integrator::bdpt::{
    connect, generate_camera_subpath_on_film, generate_light_subpath, LightChoice, Subpath,
};
use crate::lightdistrib::LightStrategy;
use crate::scene::Scene;
use crate::stream::SampleSource;
use acr_plugins::RenderingSpace;
use std::cell::RefCell;

thread_local! {
    /// The camera and light subpaths, reused from evaluation to evaluation.
    static PATHS: RefCell<(Subpath, Subpath)> = const { RefCell::new((Subpath::new(), Subpath::new())) };
}

/// bdpt's paths as mlt's path function (pbrt-v3's `MLTIntegrator::L`).
#[derive(Clone, Copy, Debug)]
pub struct BdptContribution {
    /// The longest path, in bounces.
    pub max_depth: u32,
    /// How lights are chosen ([`LightChoice`]): mlt passes `Power`, pbrt-v3's mlt's light
    /// distribution, for the light subpath's light and the s = 1 strategy's alike.
    pub light_strategy: LightStrategy,
    /// The camera ray's differentials' scale: 1/sqrt(mutations per pixel), as pbrt-v3's
    /// `GenerateCameraSubpath` scales them by its sampler's samples per pixel (the MLT
    /// sampler's are its mutations).
    pub differential_scale: f32,
}

impl BdptContribution {
    /// The strategy for `depth` from `sampler`'s camera stream: (s, t, number of strategies).
    fn strategy(sampler: &mut MltSampler, depth: u32) -> (usize, usize, usize) {
        if depth == 0 {
            return (0, 2, 1);
        }
        let n = depth as usize + 2;
        let s = ((sampler.next_1d() * n as f32) as usize).min(n - 1);
        (s, n - s, n)
    }
}

impl PathContribution for BdptContribution {
    fn max_depth(&self) -> u32 {
        self.max_depth
    }

    fn l(
        &self,
        scene: &Scene,
        space: &RenderingSpace,
        sampler: &mut MltSampler,
        depth: u32,
    ) -> Contribution {
        sampler.start_stream(CAMERA_STREAM);
        let (s, t, n_strategies) = Self::strategy(sampler, depth);
        let raster = raster_position(space, sampler.next_2d());
        let mut c = Contribution {
            raster,
            ..Contribution::default()
        };
        let time = sampler.next_1d();
        let lens = sampler.next_2d();
        let sample = CameraSample {
            film: raster,
            lens,
            time,
        };
        PATHS.with(|paths| {
            let (camera, light) = &mut *paths.borrow_mut();
            let (origin, time) = if t == 1 && self.light_strategy != LightStrategy::Spatial {
                // Light tracing (t = 1) connects to a lens point of its own: the camera ray
                // would go unused but for its time (and its origin, for a light choice that
                // depends on where it is looked up: only `spatial`'s does).
                camera.clear();
                (Vec3::ZERO, scene.camera.sample_time(&sample))
            } else {
                // The s = 0 strategy reads its last vertex's emission, not its scattering.
                let depth = (t, s != 0);
                let (ray, made) = if scene.uses_differentials {
                    let (ray, diff) = scene.camera.generate_ray_differential(&sample);
                    let diff = diff.scaled(&ray, self.differential_scale);
                    let at = (ray, Some(&diff));
                    let n = generate_camera_subpath_on_film(scene, at, sampler, depth, camera);
                    (ray, n)
                } else {
                    let ray = scene.camera.generate_ray(&sample);
                    let n =
                        generate_camera_subpath_on_film(scene, (ray, None), sampler, depth, camera);
                    (ray, n)
                };
                c.rays = made as u32;
                if made != t {
                    return c;
                }
                (ray.o, ray.time)
            };
            sampler.start_stream(LIGHT_STREAM);
            let choice = LightChoice::new(scene, self.light_strategy, origin);
            // The s = 1 strategy samples its light vertex itself (`connect`), and its MIS
            // weight reads that vertex: a light subpath's would go unused. pbrt-v3 makes it
            // and returns zero where its emission sample fails, which loses that share of
            // s = 1's light (bdpt runs s = 1 regardless, docs/light-transport.md).
            if s > 1 {
                let made = generate_light_subpath(scene, sampler, s, time, &choice, light);
                c.rays += made as u32;
                if made != s {
                    return c;
                }
            } else {
                light.clear();
            }
            sampler.start_stream(CONNECTION_STREAM);
            let k = connect(scene, light, camera, s, t, &choice, sampler);
            c.rays += u32::from(k.traced);
            c.l = k.l * n_strategies as f32;
            if t == 1 {
                // Light tracing found the camera: the path lands where it says.
                match k.raster {
                    Some(r) => c.raster = r,
                    None => c.l = crate::geometry::Spectrum::ZERO,
                }
            }
            c
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Depth 0 has the one strategy s = 0, t = 2; depth d chooses each of its d + 2 (s, t)
    /// with s + t = d + 2, about uniformly.
    #[test]
    fn strategies_cover_each_depth_uniformly() {
        for _ in 0..4 {
            let mut sampler = MltSampler::new(1, 0, 0.01, 0.3);
            sampler.start_stream(CAMERA_STREAM);
            assert_eq!(BdptContribution::strategy(&mut sampler, 0), (0, 2, 1));
        }
        for depth in 1..6u32 {
            let n = depth as usize + 2;
            let mut counts = vec![0u32; n];
            for i in 0..4000 {
                let mut sampler = MltSampler::new(7, i, 0.01, 0.3);
                sampler.start_stream(CAMERA_STREAM);
                let (s, t, k) = BdptContribution::strategy(&mut sampler, depth);
                assert_eq!((s + t, k), (n, n));
                counts[s] += 1;
            }
            let expected = 4000.0 / n as f64;
            for c in counts {
                assert!((f64::from(c) / expected - 1.0).abs() < 0.2, "{depth}: {c}");
            }
        }
    }
}
