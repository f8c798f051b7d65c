//! `path`: pbrt-v3's PathIntegrator (light and BSDF sampling combined by MIS, Russian
//! roulette), with the BSDF sample that continues the path serving as the BSDF half of the MIS
//! pair for the emission it finds (as pbrt-v4). Also what mlt's interim path function traces.

use super::light_sample::{next_event, LastScatter};
use super::{subsurface, Radiance, MAX_PASS_THROUGH};
use crate::bsdf::Bsdf;
use crate::first_hit::FirstHitProbe;
use crate::geometry::{Ray, RayDifferentials, Spectrum};
use crate::lightbvh::LightContext;
use crate::lightdistrib::LightStrategy;
use crate::scene::Scene;
use crate::stream::SampleSource;

/// The longest path `path_li` traces, in scattering vertices (0: emission the camera ray
/// finds; a light sample at the first hit makes a path of length 1), and how it ends.
#[derive(Clone, Copy)]
pub(super) struct PathRange {
    /// Longest path, in bounces.
    pub(super) max_depth: u32,
    /// Russian roulette below this throughput (0: never).
    pub(super) rr_threshold: f32,
}

/// The path integrator's estimate of the radiance along `ray`: at each scattering a light
/// sample and a BSDF sample, emission found weighted by MIS, Russian roulette after depth 3.
pub(super) fn path_li(
    scene: &Scene,
    mut ray: Ray,
    mut diff: Option<&RayDifferentials>,
    stream: &mut impl SampleSource,
    range: PathRange,
    light_strategy: LightStrategy,
) -> Radiance {
    let PathRange {
        max_depth,
        rr_threshold,
    } = range;
    let mut l = Spectrum::ZERO;
    let mut beta = Spectrum::ONE;
    let mut rays = 0u32;
    let mut depth = 0u32;
    let mut eta_scale = 1.0f32;
    let mut last = LastScatter {
        whole: true,
        p: ray.o,
        bsdf_pdf: 0.0,
        ctx: None,
    };
    let mut pass_through = 0u32;
    let have_lights = !scene.lights.is_empty();
    let mut probe = FirstHitProbe::default();
    // One BSDF for the whole path, refilled in place at each hit.
    let mut bsdf = Bsdf::empty();
    loop {
        rays += 1;
        // Borrowed where it was returned: moving it out copied it, reading back the stores
        // just made in other widths (a stalled load).
        let found = scene.closest_hit(&ray);
        let Some(hit) = &found else {
            for &i in &scene.infinite_lights {
                let light = &scene.lights[i as usize];
                let le = light.le(ray.d.normalize());
                l += last.weigh(scene, light_strategy, i as usize, beta, le, || {
                    light.pdf_le(ray.d.normalize())
                });
            }
            break;
        };
        let surface = scene.surface_of(hit);
        let mut si = scene.interaction(&ray, hit);
        // Only the camera ray has differentials (pbrt-v3's path integrator spawns every later
        // ray, and the one through an interface, without them).
        if let Some(d) = diff.take() {
            si.compute_differentials(d);
        }
        probe.travel(ray.o, si.p);
        if let Some(li) = surface.area_light {
            let light = &scene.lights[li as usize];
            let le = light.l(&si, si.wo);
            if le != Spectrum::ZERO {
                l += last.weigh(scene, light_strategy, li as usize, beta, le, || {
                    light.pdf_area_hit(&scene.accel.world, last.p, si.p, si.n)
                });
            }
        }
        let Some(material) = surface.material else {
            // An interface between media: continue in the same direction, same depth.
            pass_through += 1;
            if pass_through > MAX_PASS_THROUGH {
                break;
            }
            ray = si.spawn_ray(ray.d);
            continue;
        };
        if depth >= max_depth {
            break;
        }
        let material_index = material;
        let material = &scene.materials[material as usize];
        material.shade(&mut si);
        material.bsdf_into(&si, &mut bsdf);
        probe.surface(&si, &bsdf);
        last.ctx = None;
        if have_lights && bsdf.has_non_specular() {
            let ctx = LightContext {
                p: si.p,
                n: si.shading_n,
            };
            let direct = next_event(scene, &si, &bsdf, &ctx, light_strategy, stream, &mut rays);
            // Kept after the light sample: copied at once, the context's fresh narrow stores
            // were reloaded in wider pieces, which stalls.
            last.ctx = Some(ctx);
            if let Some(direct) = direct {
                l += beta * direct;
            }
        }
        let u_lobe = stream.next_1d();
        let u = stream.next_2d();
        let Some(s) = bsdf.sample_f(si.wo, u, u_lobe) else {
            break;
        };
        if s.pdf <= 0.0 || s.f == Spectrum::ZERO {
            break;
        }
        beta *= s.f * s.wi.dot(si.shading_n).abs() / s.pdf;
        if !crate::geometry::is_valid_radiance(beta) {
            break;
        }
        let transmitted = s.wi.dot(si.n) * si.wo.dot(si.n) < 0.0;
        if s.specular && transmitted {
            let eta = bsdf.eta();
            eta_scale *= if si.wo.dot(si.n) > 0.0 {
                eta * eta
            } else {
                1.0 / (eta * eta)
            };
        }
        last.whole = s.specular;
        last.p = si.p;
        last.bsdf_pdf = if s.specular { 0.0 } else { s.pdf };
        ray = si.spawn_ray(s.wi);
        // Transmitted into a subsurface material: the path leaves from an exit point instead.
        if let Some(bssrdf) = transmitted.then(|| material.bssrdf(&si)).flatten() {
            // The light sampled at the exit point counts as a path one longer than this one.
            let mut at_exit = Spectrum::ZERO;
            let exit = subsurface::scatter(
                scene,
                &bssrdf,
                material_index,
                si.time,
                light_strategy,
                stream,
                &mut beta,
                &mut at_exit,
                &mut last,
                &mut rays,
            );
            l += at_exit;
            let Some(next) = exit else { break };
            ray = next;
        }
        depth += 1;
        let rr_beta = beta * eta_scale;
        let m = rr_beta.max_element();
        if m < rr_threshold && depth > 3 {
            let q = (1.0 - m).max(0.05);
            if stream.next_1d() < q {
                break;
            }
            beta /= 1.0 - q;
        }
    }
    Radiance {
        l,
        rays,
        first_hit: probe.features(),
    }
}
