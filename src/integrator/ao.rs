//! `ambientocclusion`: pbrt-v3's AOIntegrator. At the first surface with a material, `nsamples`
//! directions over the hemisphere of the geometric normal turned towards the camera (cosine-
//! weighted with `cossample`, else uniform), each unoccluded one adding cos / (pdf nsamples):
//! pi times the unoccluded fraction with cosine sampling (docs/light-transport.md).

use super::{Radiance, MAX_PASS_THROUGH};
use crate::first_hit::FirstHit;
use crate::geometry::{Ray, Spectrum, Vec3};
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
        // Polar mappings (the stratified set keeps its spread) with an inline sin/cos: the
        // library's was a sixth of the integrator's time.
        let (sin, cos) = sin_cos_2pi(u.y);
        let (w, pdf) = if s.cos_sample {
            // Malley's method: r = sqrt(u), z = sqrt(1 - u) > 0.
            let r = u.x.sqrt();
            let z = (1.0 - u.x).sqrt();
            (
                Vec3::new(r * cos, r * sin, z),
                z * std::f32::consts::FRAC_1_PI,
            )
        } else {
            let z = u.x;
            let r = (1.0 - z * z).max(0.0).sqrt();
            (
                Vec3::new(r * cos, r * sin, z),
                0.5 * std::f32::consts::FRAC_1_PI,
            )
        };
        // A direction at the horizon would have pdf 0 (0/0 in pbrt-v3): never drawn here, as
        // u.x < 1; kept as a guard.
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

/// sin and cos of 2 pi t (t in [0, 1]): the angle reduced to a quarter turn's nearest multiple
/// and a remainder within pi/4, whose Taylor series to the 7th and 8th powers are exact to
/// 3e-7.
#[inline]
fn sin_cos_2pi(t: f32) -> (f32, f32) {
    let q4 = t * 4.0;
    let q = q4.round();
    let a = (q4 - q) * std::f32::consts::FRAC_PI_2;
    let a2 = a * a;
    let s = a * (1.0 - a2 / 6.0 * (1.0 - a2 / 20.0 * (1.0 - a2 / 42.0)));
    let c = 1.0 - a2 / 2.0 * (1.0 - a2 / 12.0 * (1.0 - a2 / 30.0 * (1.0 - a2 / 56.0)));
    match (q as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn sin_cos_2pi_is_accurate() {
        for i in 0..=4096 {
            let t = i as f32 / 4096.0;
            let (s, c) = super::sin_cos_2pi(t);
            let a = 2.0 * std::f64::consts::PI * f64::from(t);
            assert!((f64::from(s) - a.sin()).abs() < 1e-6, "{t}: {s}");
            assert!((f64::from(c) - a.cos()).abs() < 1e-6, "{t}: {c}");
        }
    }
}
