//! `directlighting`: pbrt-v3's DirectLightingIntegrator, and the specular differentials
//! `whitted` shares.

use super::light_sample::sample_light;
use super::{DirectStrategy, MAX_PASS_THROUGH};
use crate::bsdf::Bsdf;
use crate::first_hit::FirstHitProbe;
use crate::geometry::{Ray, RayDifferentials, Spectrum, SurfaceInteraction};
use crate::lightbvh::LightContext;
use crate::lightdistrib::LightStrategy;
use crate::sampling::power_heuristic;
use crate::scene::{Scene, SceneHit};
use crate::stream::SampleStream;

/// What a recursive estimate counts on its way: rays traced and the first-hit features.
#[derive(Default)]
pub(super) struct Tally {
    pub(super) rays: u32,
    pub(super) probe: FirstHitProbe,
}

/// pbrt-v3's DirectLightingIntegrator: emission, direct light at the first non-specular hit
/// (MIS of light and BSDF sampling), and specular reflection and transmission recursively,
/// every specular lobe followed as pbrt-v3 does, the camera ray's differentials carried
/// through them.
#[allow(clippy::too_many_arguments)]
pub(super) fn direct_li(
    scene: &Scene,
    ray: Ray,
    diff: Option<&RayDifferentials>,
    stream: &mut SampleStream,
    max_depth: u32,
    depth: u32,
    strategy: DirectStrategy,
    tally: &mut Tally,
) -> Spectrum {
    let (hit, pass_through) = match first_surface(scene, ray, tally) {
        Ok(h) => h,
        Err(sky) => return sky,
    };
    let mut si = hit.si;
    // The differentials hold for the ray as it left the camera (or a specular bounce), not
    // through an interface.
    let camera_diff = diff.filter(|_| pass_through == 0);
    if let Some(d) = camera_diff {
        si.compute_differentials(d);
    }
    let mut l = Spectrum::ZERO;
    if let Some(li) = hit.surface.area_light {
        l += scene.lights[li as usize].l(&si, si.wo);
    }
    let Some(material) = hit.surface.material else {
        return l;
    };
    let material = &scene.materials[material as usize];
    material.shade(&mut si);
    // pbrt-v3's DirectLightingIntegrator asks for separate lobes (a glass's reflection and
    // transmission apart), and follows each.
    let mut bsdf = Bsdf::empty();
    material.bsdf_into_with(&si, false, &mut bsdf);
    tally.probe.surface(&si, &bsdf);
    if bsdf.has_non_specular() && !scene.lights.is_empty() {
        match strategy {
            DirectStrategy::All => {
                // pbrt-v3's UniformSampleAllLights: each light's `nsamples`, averaged.
                for (i, &n) in scene.light_samples.iter().enumerate() {
                    let mut sum = Spectrum::ZERO;
                    for _ in 0..n {
                        sum += estimate_direct(
                            scene,
                            &si,
                            &bsdf,
                            i as u32,
                            1.0,
                            stream,
                            &mut tally.rays,
                        );
                    }
                    l += sum / n as f32;
                }
            }
            DirectStrategy::One => {
                let ctx = LightContext {
                    p: si.p,
                    n: si.shading_n,
                };
                if let Some((i, pdf)) =
                    scene.choose_light(LightStrategy::Uniform, ctx, stream.next_1d())
                {
                    l += estimate_direct(scene, &si, &bsdf, i as u32, pdf, stream, &mut tally.rays);
                }
            }
        }
    }
    if depth + 1 < max_depth {
        l += follow_specular_lobes(&si, &bsdf, camera_diff, stream, |next, d, stream| {
            direct_li(
                scene,
                next,
                d,
                stream,
                max_depth,
                depth + 1,
                strategy,
                tally,
            )
        });
    }
    l
}

/// The differentials of the ray leaving `si` along `wi` by specular reflection or transmission,
/// from those of the ray that arrived (`d`): pbrt-v3's `SpecularReflect` and
/// `SpecularTransmit`, which follow the footprint through mirrors and glass (with the normal's
/// change across it, from dn/du and dn/dv).
pub(super) fn specular_differentials(
    d: &RayDifferentials,
    si: &SurfaceInteraction,
    wi: crate::geometry::Vec3,
    transmitted: bool,
    bsdf_eta: f32,
) -> RayDifferentials {
    let wo = si.wo;
    let mut ns = si.shading_n;
    let f = &si.diff;
    let mut dndx = si.dndu * f.dudx + si.dndv * f.dvdx;
    let mut dndy = si.dndu * f.dudy + si.dndv * f.dvdy;
    let (rx_o, ry_o) = (si.p + f.dpdx, si.p + f.dpdy);
    let (dwodx, dwody) = (-d.rx_d - wo, -d.ry_d - wo);
    if !transmitted {
        let ddndx = dwodx.dot(ns) + wo.dot(dndx);
        let ddndy = dwody.dot(ns) + wo.dot(dndy);
        return RayDifferentials {
            rx_o,
            ry_o,
            rx_d: wi - dwodx + 2.0 * (wo.dot(ns) * dndx + ddndx * ns),
            ry_d: wi - dwody + 2.0 * (wo.dot(ns) * dndy + ddndy * ns),
        };
    }
    let mut eta = 1.0 / bsdf_eta;
    if wo.dot(ns) < 0.0 {
        eta = 1.0 / eta;
        ns = -ns;
        dndx = -dndx;
        dndy = -dndy;
    }
    let ddndx = dwodx.dot(ns) + wo.dot(dndx);
    let ddndy = dwody.dot(ns) + wo.dot(dndy);
    let mu = eta * wo.dot(ns) - wi.dot(ns).abs();
    let k = eta - (eta * eta * wo.dot(ns)) / wi.dot(ns).abs();
    RayDifferentials {
        rx_o,
        ry_o,
        rx_d: wi - eta * dwodx + (mu * dndx + k * ddndx * ns),
        ry_d: wi - eta * dwody + (mu * dndy + k * ddndy * ns),
    }
}

/// pbrt-v3's EstimateDirect: a light sample and a BSDF sample, combined by MIS.
pub(super) fn estimate_direct(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &crate::bsdf::Bsdf,
    light_index: u32,
    choice_pdf: f32,
    stream: &mut SampleStream,
    rays: &mut u32,
) -> Spectrum {
    let light = &scene.lights[light_index as usize];
    let mut ld = sample_light(scene, si, bsdf, light_index, choice_pdf, stream, rays);
    if light.is_delta() {
        return ld;
    }
    let u_lobe = stream.next_1d();
    let u = stream.next_2d();
    let Some(s) = bsdf.sample_f(si.wo, u, u_lobe) else {
        return ld;
    };
    if s.specular || s.pdf <= 0.0 {
        return ld;
    }
    let f = s.f * s.wi.dot(si.shading_n).abs();
    if f == Spectrum::ZERO {
        return ld;
    }
    let ray = si.spawn_ray(s.wi);
    *rays += 1;
    let (li, light_pdf) = match scene.intersect(&ray) {
        Some(h) if h.surface.area_light == Some(light_index) => (
            light.l(&h.si, -s.wi),
            light.pdf_area_hit(&scene.accel.world, si.p, h.si.p, h.si.n),
        ),
        Some(_) => return ld,
        None => (light.le(s.wi), light.pdf_le(s.wi)),
    };
    if light_pdf <= 0.0 || li == Spectrum::ZERO {
        return ld;
    }
    let w = power_heuristic(1.0, s.pdf, 1.0, light_pdf * choice_pdf);
    ld += f * li * w / (s.pdf * choice_pdf);
    ld
}

/// The first surface along `ray` that has a material, passing through interfaces (`Material
/// ""`, at most [`MAX_PASS_THROUGH`] of them; the one after is taken as the surface), with the
/// number passed; `Err` with the infinite lights' radiance when the ray leaves the scene.
/// Shared by `directlighting` and `whitted`.
pub(super) fn first_surface(
    scene: &Scene,
    mut ray: Ray,
    tally: &mut Tally,
) -> Result<(SceneHit, u32), Spectrum> {
    let mut pass_through = 0;
    loop {
        tally.rays += 1;
        let hit = scene.intersect(&ray);
        if let Some(h) = &hit {
            tally.probe.travel(ray.o, h.si.p);
        }
        match hit {
            None => {
                return Err(scene
                    .infinite_lights
                    .iter()
                    .map(|&i| scene.lights[i as usize].le(ray.d.normalize()))
                    .sum());
            }
            Some(h) if h.surface.material.is_none() && pass_through < MAX_PASS_THROUGH => {
                pass_through += 1;
                ray = h.si.spawn_ray(ray.d);
            }
            Some(h) => return Ok((h, pass_through)),
        }
    }
}

/// pbrt-v3's SpecularReflect and SpecularTransmit: every specular lobe of `bsdf` at `si` is
/// followed (a glass's reflection and its transmission both), each with its own sample, the
/// camera ray's differentials carried through; `trace` gives the radiance along each spawned
/// ray. Shared by `directlighting` and `whitted`.
pub(super) fn follow_specular_lobes(
    si: &SurfaceInteraction,
    bsdf: &crate::bsdf::Bsdf,
    camera_diff: Option<&RayDifferentials>,
    stream: &mut SampleStream,
    mut trace: impl FnMut(Ray, Option<&RayDifferentials>, &mut SampleStream) -> Spectrum,
) -> Spectrum {
    let mut l = Spectrum::ZERO;
    for index in 0..bsdf.num_lobes() {
        let u = stream.next_2d();
        let Some(s) = bsdf.sample_specular_lobe(si.wo, u, index) else {
            continue;
        };
        let cos = s.wi.dot(si.shading_n).abs();
        let weight = s.f * cos / s.pdf;
        if cos == 0.0 || weight == Spectrum::ZERO || !crate::geometry::is_valid_radiance(weight) {
            continue;
        }
        let next = si.spawn_ray(s.wi);
        let transmitted = s.wi.dot(si.n) * si.wo.dot(si.n) < 0.0;
        let next_diff =
            camera_diff.map(|d| specular_differentials(d, si, s.wi, transmitted, bsdf.eta()));
        l += weight * trace(next, next_diff.as_ref(), stream);
    }
    l
}
