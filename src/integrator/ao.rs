//! `ambientocclusion`: pbrt-v3's AOIntegrator. At the first surface with a material, `nsamples`
//! directions over the hemisphere of the geometric normal turned towards the camera (cosine-
//! weighted with `cossample`, else uniform), each unoccluded one adding cos / (pdf nsamples):
//! pi times the unoccluded fraction with cosine sampling (docs/light-transport.md).

use super::{Radiance, MAX_PASS_THROUGH};
use crate::first_hit::FirstHit;
use crate::geometry::{Ray, Spectrum, Vec3};
use crate::sampling::cosine_sample_hemisphere;
use crate::scene::Scene;
use crate::stream::SampleStream;

/// `ambientocclusion`'s settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AoSettings {
    /// Directions sampled at the hit (pbrt-v3's `nsamples`, default 64).
    pub samples: u32,
    /// Cosine-weighted directions (pbrt-v3's `cossample`, default true), else uniform.
    pub cos_sample: bool,
}

/// The ambient occlusion seen along `ray`.
pub fn ao_li(scene: &Scene, mut ray: Ray, stream: &mut SampleStream, s: AoSettings) -> Radiance {
    let mut rays = 0u32;
    let mut travelled = 0.0f32;
    let mut pass_through = 0u32;
    let hit = loop {
        rays += 1;
        let Some(hit) = scene.intersect(&ray) else {
            return Radiance {
                rays,
                ..Default::default()
            };
        };
        travelled += ray.o.distance(hit.si.p);
        if hit.surface.material.is_some() {
            break hit;
        }
        // No material: an interface between media, which pbrt-v3 skips.
        pass_through += 1;
        if pass_through > MAX_PASS_THROUGH {
            return Radiance {
                rays,
                ..Default::default()
            };
        }
        ray = hit.si.spawn_ray(ray.d);
    };
    let si = &hit.si;
    // The frame of the true geometry, not the shading's, as pbrt-v3.
    let n = if si.n.dot(-ray.d) < 0.0 { -si.n } else { si.n };
    let mut sx = si.dpdu.normalize_or_zero();
    let mut ty = si.n.cross(sx);
    if sx == Vec3::ZERO || !ty.is_finite() {
        // A surface without dp/du: any frame around the normal samples the same hemisphere.
        let f = crate::geometry::Frame::from_z(n);
        (sx, ty) = (f.s, f.t);
    }
    let count = s.samples as f32;
    let mut l = 0.0f32;
    // pbrt-v3 draws the directions as one array from its sampler, stratified over the pixel's
    // samples together; here a Hammersley set of `nsamples` points shifted (mod 1) by one
    // stream point: each direction still uniform, the set stratified, the shift stratified
    // across the pixel's samples.
    let shift = stream.next_2d();
    let inv_count = 1.0 / count;
    for i in 0..s.samples {
        // The base-2 radical inverse is i's bits reversed.
        let h = glam::Vec2::new(
            (i as f32 + 0.5) * inv_count,
            i.reverse_bits() as f32 * (1.0 / 4_294_967_296.0),
        );
        let u = (h + shift).fract();
        let (w, pdf) = if s.cos_sample {
            let w = cosine_sample_hemisphere(u);
            (w, w.z.abs() * std::f32::consts::FRAC_1_PI)
        } else {
            let z = u.x;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * u.y;
            (
                Vec3::new(r * phi.cos(), r * phi.sin(), z),
                0.5 * std::f32::consts::FRAC_1_PI,
            )
        };
        // A grazing cosine sample has pdf 0 and adds nothing (pbrt-v3's would be 0/0).
        if pdf <= 0.0 {
            continue;
        }
        let wi = sx * w.x + ty * w.y + n * w.z;
        rays += 1;
        if !scene.accel.occluded(&si.spawn_ray(wi), f32::INFINITY) {
            l += wi.dot(n) / (pdf * count);
        }
    }
    Radiance {
        l: Spectrum::splat(l),
        rays,
        first_hit: FirstHit {
            // What the occlusion is relative to: a white surface.
            albedo: Spectrum::ONE,
            normal: n,
            depth: travelled,
        },
    }
}
