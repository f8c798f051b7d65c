//! `volpath`: pbrt-v3's `VolPathIntegrator` (src/integrators/volpath.cpp) with its
//! `UniformSampleOneLight` and `EstimateDirect` for media (src/core/integrator.cpp), and
//! `Scene::IntersectTr` and `VisibilityTester::Tr` (transmittance along shadow rays through
//! media and through interface surfaces, `Material ""`). Every ray carries the medium it
//! travels in: the camera's first, then the medium a surface between two media
//! (`MediumInterface`) puts on the side the ray leaves by. See docs/media.md.

use super::{Radiance, MAX_PASS_THROUGH};
use crate::accel::Hit;
use crate::bsdf::Bsdf;
use crate::bssrdf::adapter_bsdf;
use crate::first_hit::FirstHitProbe;
use crate::geometry::{Ray, Spectrum, SurfaceInteraction, Vec3, SHADOW_EPSILON};
use crate::lightbvh::LightContext;
use crate::lightdistrib::LightStrategy;
use crate::medium::{HenyeyGreenstein, MediumInterface};
use crate::sampling::power_heuristic;
use crate::scene::{Scene, SceneHit, Surface};
use crate::stream::{SampleSource, SampleStream};

/// `volpath`'s settings.
#[derive(Clone, Copy, Debug)]
pub struct VolPathSettings {
    /// Longest path, in scattering events (surface or medium).
    pub max_depth: u32,
    /// Russian roulette once the throughput's largest channel is below this.
    pub rr_threshold: f32,
    /// How a light is chosen for next-event estimation.
    pub light_strategy: LightStrategy,
}

/// A ray and the medium it travels in (`None`: vacuum).
#[derive(Clone, Copy, Debug)]
pub(super) struct MediumRay {
    /// The ray.
    pub(super) ray: Ray,
    /// The medium it travels in.
    pub(super) medium: Option<u32>,
}

/// Where a path scatters: a surface with its BSDF, or a point in a medium with its phase
/// function.
enum Vertex<'a> {
    Surface {
        si: &'a SurfaceInteraction,
        bsdf: &'a Bsdf,
        /// The media on either side (both the ray's medium on a surface that is no transition).
        media: MediumInterface,
    },
    Medium {
        p: Vec3,
        wo: Vec3,
        time: f32,
        phase: HenyeyGreenstein,
        medium: Option<u32>,
    },
}

/// A scattering direction sampled at a vertex.
struct Scattered {
    wi: Vec3,
    /// The BSDF times the cosine, or the phase function's value.
    f: Spectrum,
    pdf: f32,
    specular: bool,
}

impl Vertex<'_> {
    fn p(&self) -> Vec3 {
        match self {
            Vertex::Surface { si, .. } => si.p,
            Vertex::Medium { p, .. } => *p,
        }
    }

    /// Where a light is chosen from (no normal in a medium: no cosine applies there).
    fn light_context(&self) -> LightContext {
        match self {
            Vertex::Surface { si, .. } => LightContext {
                p: si.p,
                n: si.shading_n,
            },
            Vertex::Medium { p, .. } => LightContext {
                p: *p,
                n: Vec3::ZERO,
            },
        }
    }

    /// The scattering function (times the cosine on a surface) for `wi`, and its density.
    fn f_pdf(&self, wi: Vec3) -> (Spectrum, f32) {
        match self {
            Vertex::Surface { si, bsdf, .. } => (
                bsdf.f(si.wo, wi) * wi.dot(si.shading_n).abs(),
                bsdf.pdf(si.wo, wi),
            ),
            Vertex::Medium { wo, phase, .. } => {
                let p = phase.p(*wo, wi);
                (Spectrum::splat(p), p)
            }
        }
    }

    /// Samples a direction to continue in.
    fn sample(&self, stream: &mut SampleStream) -> Option<Scattered> {
        match self {
            Vertex::Surface { si, bsdf, .. } => {
                let u_lobe = stream.next_1d();
                let u = stream.next_2d();
                let s = bsdf.sample_f(si.wo, u, u_lobe)?;
                Some(Scattered {
                    wi: s.wi,
                    f: s.f * s.wi.dot(si.shading_n).abs(),
                    pdf: s.pdf,
                    specular: s.specular,
                })
            }
            Vertex::Medium { wo, phase, .. } => {
                let (wi, p) = phase.sample_p(*wo, stream.next_2d());
                Some(Scattered {
                    wi,
                    f: Spectrum::splat(p),
                    pdf: p,
                    specular: false,
                })
            }
        }
    }

    /// The ray leaving along `d`, in the medium on that side.
    fn spawn(&self, d: Vec3) -> MediumRay {
        match self {
            Vertex::Surface { si, media, .. } => MediumRay {
                ray: si.spawn_ray(d),
                medium: media.toward(si.n, d),
            },
            Vertex::Medium {
                p, time, medium, ..
            } => MediumRay {
                ray: Ray::new(*p, d, *time),
                medium: *medium,
            },
        }
    }

    /// The shadow ray towards `target`, its end parameter, in the medium on that side.
    fn spawn_to(&self, target: Vec3) -> (MediumRay, f32) {
        match self {
            Vertex::Surface { si, media, .. } => {
                let (ray, t_max) = si.spawn_ray_to(target);
                let medium = media.toward(si.n, ray.d);
                (MediumRay { ray, medium }, t_max)
            }
            Vertex::Medium {
                p, time, medium, ..
            } => (
                MediumRay {
                    ray: Ray::new(*p, target - *p, *time),
                    medium: *medium,
                },
                1.0 - SHADOW_EPSILON,
            ),
        }
    }
}

/// The surface's media as seen by a ray in `medium`: its own where it is a transition, else
/// `medium` on both sides (pbrt-v3's `GeometricPrimitive::Intersect`).
#[inline]
pub(super) fn media_at(surface: &Surface, medium: Option<u32>) -> MediumInterface {
    surface.media.unwrap_or(MediumInterface {
        inside: medium,
        outside: medium,
    })
}

/// At a surface vertex: one light sampled (when `light`: the BSDF has a non-specular part),
/// then the direction that continues the path. Adds the light to `l` and multiplies `beta` by
/// f / pdf (`step` holds beta, l and the rays traced); `None` ends the path.
fn continue_from(
    scene: &Scene,
    v: &Vertex,
    light: bool,
    strategy: LightStrategy,
    stream: &mut SampleStream,
    (beta, l, rays): (&mut Spectrum, &mut Spectrum, &mut u32),
) -> Option<Scattered> {
    if light {
        *l += *beta * sample_one_light(scene, v, strategy, stream, rays);
    }
    let s = v.sample(stream)?;
    if s.pdf <= 0.0 || s.f == Spectrum::ZERO {
        return None;
    }
    *beta *= s.f / s.pdf;
    Some(s)
}

/// A ray's closest hit before its interaction is computed (which a path that scatters in a
/// medium first, or a shadow ray that is blocked, never needs).
#[derive(Clone, Copy)]
pub(super) struct RawHit {
    hit: Hit,
    surface: Surface,
}

impl RawHit {
    /// The hit, resolved for `ray` (the ray that found it).
    #[inline]
    fn resolve(&self, scene: &Scene, ray: &Ray) -> SceneHit {
        SceneHit {
            si: scene.accel.interaction(ray, &self.hit),
            surface: self.surface,
        }
    }
}

/// The closest hit along `ray` before parameter `t_max`.
#[inline]
fn intersect(scene: &Scene, ray: &Ray, t_max: f32) -> Option<RawHit> {
    let hit = scene.accel.intersect(ray, t_max)?;
    Some(RawHit {
        hit,
        surface: scene.surfaces[hit.prim.surface as usize],
    })
}

/// Transmittance through `medium` along `ray` up to `t_max`.
#[inline]
fn medium_tr<S: SampleSource + ?Sized>(
    scene: &Scene,
    medium: Option<u32>,
    ray: &Ray,
    t_max: f32,
    stream: &mut S,
) -> Spectrum {
    match medium {
        Some(m) => scene.media[m as usize].tr(ray, t_max, &mut || stream.next_1d()),
        None => Spectrum::ONE,
    }
}

/// Where a ray that crosses interface surfaces goes on from each: along its own direction, or
/// (a shadow ray) towards a fixed point.
#[derive(Clone, Copy)]
pub(super) enum Toward {
    /// Along the ray's direction.
    Along,
    /// Towards this point (a shadow ray).
    Point(Vec3),
}

/// Follows `mr` up to `t_max` through interface surfaces (`Material ""`), each of which may
/// change the medium, and gives the first surface with a material (with the ray that found
/// it) and the transmittance up to it, or up to `t_max` when there is none. A shadow ray
/// (`Toward::Point`) stops with zero transmittance at a blocking surface, before measuring the
/// medium, and as soon as the transmittance is zero (pbrt-v3's `VisibilityTester::Tr`); a
/// ray `Toward::Along` measures on (pbrt-v3's `Scene::IntersectTr`). The crossings need only
/// the point and normal ([`crate::accel::Accel::crossing`]).
pub(super) fn cross_interfaces<S: SampleSource + ?Sized>(
    scene: &Scene,
    mut mr: MediumRay,
    mut t_max: f32,
    toward: Toward,
    stream: &mut S,
    rays: &mut u32,
) -> (Option<(RawHit, Ray)>, Spectrum) {
    let shadow = matches!(toward, Toward::Point(_));
    let mut tr = Spectrum::ONE;
    for _ in 0..MAX_PASS_THROUGH {
        *rays += 1;
        let hit = intersect(scene, &mr.ray, t_max);
        if let Some(h) = hit.filter(|h| shadow && h.surface.material.is_some()) {
            return (Some((h, mr.ray)), Spectrum::ZERO);
        }
        let t_end = hit.map_or(t_max, |h| h.hit.t);
        tr *= medium_tr(scene, mr.medium, &mr.ray, t_end, stream);
        let Some(h) = hit else {
            return (None, tr);
        };
        if h.surface.material.is_some() {
            return (Some((h, mr.ray)), tr);
        }
        if shadow && tr == Spectrum::ZERO {
            return (None, tr);
        }
        let c = scene.accel.crossing(&mr.ray, &h.hit);
        let media = media_at(&h.surface, mr.medium);
        (mr, t_max) = match toward {
            Toward::Along => {
                let d = mr.ray.d;
                let medium = media.toward(c.n, d);
                let ray = c.spawn_ray(d);
                (MediumRay { ray, medium }, f32::INFINITY)
            }
            Toward::Point(target) => {
                let (ray, t) = c.spawn_ray_to(target);
                let medium = media.toward(c.n, ray.d);
                (MediumRay { ray, medium }, t)
            }
        };
    }
    (None, Spectrum::ZERO)
}

/// pbrt-v3's `VisibilityTester::Tr`: the transmittance from `from` to `target`, zero when a
/// surface with a material blocks it; interface surfaces are crossed, changing the medium.
fn transmittance_to(
    scene: &Scene,
    from: &Vertex,
    target: Vec3,
    stream: &mut SampleStream,
    rays: &mut u32,
) -> Spectrum {
    let (mr, t_max) = from.spawn_to(target);
    match cross_interfaces(scene, mr, t_max, Toward::Point(target), stream, rays) {
        (Some(_), _) => Spectrum::ZERO,
        (None, tr) => tr,
    }
}

/// pbrt-v3's `Scene::IntersectTr`: the first surface with a material along `mr`, crossing
/// interfaces (with the ray that found it), and the transmittance up to it (or to infinity
/// when none is found).
fn intersect_tr(
    scene: &Scene,
    mr: MediumRay,
    stream: &mut SampleStream,
    rays: &mut u32,
) -> (Option<(RawHit, Ray)>, Spectrum) {
    cross_interfaces(scene, mr, f32::INFINITY, Toward::Along, stream, rays)
}

/// pbrt-v3's `EstimateDirect` with media: a light sample with the transmittance to it, and
/// (for lights that are not delta) a BSDF or phase sample that finds the light through
/// media and interfaces, combined by the power heuristic.
fn estimate_direct(
    scene: &Scene,
    v: &Vertex,
    light_index: usize,
    stream: &mut SampleStream,
    rays: &mut u32,
) -> Spectrum {
    let light = &scene.lights[light_index];
    let mut ld = Spectrum::ZERO;
    let p = v.p();
    if let Some(ls) = light.sample_li(&scene.accel.world, p, stream.next_2d()) {
        if ls.pdf > 0.0 && ls.li != Spectrum::ZERO {
            let (f, scattering_pdf) = v.f_pdf(ls.wi);
            if f != Spectrum::ZERO {
                let li = ls.li * transmittance_to(scene, v, ls.p, stream, rays);
                if li != Spectrum::ZERO {
                    ld += if light.is_delta() {
                        f * li / ls.pdf
                    } else {
                        f * li * power_heuristic(1.0, ls.pdf, 1.0, scattering_pdf) / ls.pdf
                    };
                }
            }
        }
    }
    if light.is_delta() {
        return ld;
    }
    let Some(s) = v.sample(stream) else {
        return ld;
    };
    if s.specular || s.pdf <= 0.0 || s.f == Spectrum::ZERO {
        return ld;
    }
    let (hit, tr) = intersect_tr(scene, v.spawn(s.wi), stream, rays);
    let (li, light_pdf) = match hit {
        Some((h, ray)) if h.surface.area_light == Some(light_index as u32) => {
            let si = scene.accel.interaction(&ray, &h.hit);
            (
                light.l(&si, -s.wi),
                light.pdf_area_hit(&scene.accel.world, p, si.p, si.n),
            )
        }
        Some(_) => return ld,
        None => (light.le(s.wi), light.pdf_le(s.wi)),
    };
    if light_pdf <= 0.0 || li == Spectrum::ZERO {
        return ld;
    }
    let w = power_heuristic(1.0, s.pdf, 1.0, light_pdf);
    ld + s.f * li * tr * w / s.pdf
}

/// pbrt-v3's `UniformSampleOneLight` with media, the light chosen by `strategy` at `v`.
fn sample_one_light(
    scene: &Scene,
    v: &Vertex,
    strategy: LightStrategy,
    stream: &mut SampleStream,
    rays: &mut u32,
) -> Spectrum {
    if scene.lights.is_empty() {
        return Spectrum::ZERO;
    }
    let u = stream.next_1d();
    match scene.choose_light(strategy, v.light_context(), u) {
        Some((i, pdf)) if pdf > 0.0 => estimate_direct(scene, v, i, stream, rays) / pdf,
        _ => Spectrum::ZERO,
    }
}

/// Emission the path finds on a surface or, escaping, from the infinite lights.
fn emission(scene: &Scene, hit: Option<&SceneHit>, d: Vec3) -> Spectrum {
    match hit {
        Some(h) => h.surface.area_light.map_or(Spectrum::ZERO, |li| {
            scene.lights[li as usize].l(&h.si, h.si.wo)
        }),
        None => scene
            .infinite_lights
            .iter()
            .map(|&i| scene.lights[i as usize].le(d.normalize()))
            .sum(),
    }
}

/// The volumetric path tracer's estimate of the radiance along `ray`, which starts in the
/// camera's medium.
pub(super) fn volpath_li(
    scene: &Scene,
    ray: Ray,
    mut diff: Option<&crate::geometry::RayDifferentials>,
    stream: &mut SampleStream,
    settings: VolPathSettings,
) -> Radiance {
    let mut l = Spectrum::ZERO;
    let mut beta = Spectrum::ONE;
    let mut rays = 0u32;
    let mut specular_bounce = false;
    let mut eta_scale = 1.0f32;
    let mut probe = FirstHitProbe::default();
    let mut mr = MediumRay {
        ray,
        medium: scene.camera_medium,
    };
    let mut bounces = 0u32;
    let mut pass_through = 0u32;
    // One BSDF for the whole path, refilled in place at each surface.
    let mut bsdf = Bsdf::empty();
    loop {
        rays += 1;
        let hit = intersect(scene, &mr.ray, f32::INFINITY);
        let t_hit = hit.map_or(f32::INFINITY, |h| h.hit.t);
        let mut scatter_t = None;
        if let Some(m) = mr.medium {
            let medium = &scene.media[m as usize];
            let s = medium.sample(&mr.ray, t_hit, &mut || stream.next_1d());
            beta *= s.weight;
            scatter_t = s.t;
        }
        if beta == Spectrum::ZERO || !crate::geometry::is_valid_radiance(beta) {
            break;
        }
        if let (Some(t), Some(m)) = (scatter_t, mr.medium) {
            // Scattering in the medium.
            if bounces >= settings.max_depth {
                break;
            }
            let medium = &scene.media[m as usize];
            let p = mr.ray.at(t);
            probe.travel(mr.ray.o, p);
            probe.medium(medium.albedo());
            let v = Vertex::Medium {
                p,
                wo: -mr.ray.d.normalize(),
                time: mr.ray.time,
                phase: medium.phase,
                medium: mr.medium,
            };
            l += beta * sample_one_light(scene, &v, settings.light_strategy, stream, &mut rays);
            let Some(s) = v.sample(stream) else {
                break;
            };
            mr = v.spawn(s.wi);
            specular_bounce = false;
        } else {
            // An interface that emits nothing: the ray goes on in the same direction (not a
            // bounce), from the point and normal alone.
            if let Some(h) = hit
                .filter(|h| h.surface.material.is_none())
                .filter(|h| h.surface.area_light.is_none())
            {
                if bounces >= settings.max_depth {
                    break;
                }
                // The camera ray's differentials end at the first surface, as below.
                diff = None;
                let c = scene.accel.crossing(&mr.ray, &h.hit);
                probe.travel(mr.ray.o, c.p);
                pass_through += 1;
                if pass_through > MAX_PASS_THROUGH {
                    break;
                }
                mr = MediumRay {
                    medium: media_at(&h.surface, mr.medium).toward(c.n, mr.ray.d),
                    ray: c.spawn_ray(mr.ray.d),
                };
                continue;
            }
            let hit = hit.map(|h| h.resolve(scene, &mr.ray));
            if bounces == 0 || specular_bounce {
                l += beta * emission(scene, hit.as_ref(), mr.ray.d);
            }
            let Some(hit) = hit else {
                break;
            };
            if bounces >= settings.max_depth {
                break;
            }
            let mut si = hit.si;
            if let Some(d) = diff.take() {
                si.compute_differentials(d);
            }
            probe.travel(mr.ray.o, si.p);
            let media = media_at(&hit.surface, mr.medium);
            let Some(material) = hit.surface.material else {
                // An interface: the ray goes on in the same direction (not a bounce).
                pass_through += 1;
                if pass_through > MAX_PASS_THROUGH {
                    break;
                }
                mr = MediumRay {
                    medium: media.toward(si.n, mr.ray.d),
                    ray: si.spawn_ray(mr.ray.d),
                };
                continue;
            };
            let material_index = material;
            let material = &scene.materials[material as usize];
            material.shade(&mut si);
            material.bsdf_into(&si, &mut bsdf);
            probe.surface(&si, &bsdf);
            let v = Vertex::Surface {
                si: &si,
                bsdf: &bsdf,
                media,
            };
            let light = bsdf.has_non_specular();
            let strategy = settings.light_strategy;
            let step = (&mut beta, &mut l, &mut rays);
            let Some(s) = continue_from(scene, &v, light, strategy, stream, step) else {
                break;
            };
            specular_bounce = s.specular;
            let transmitted = s.wi.dot(si.n) * si.wo.dot(si.n) < 0.0;
            if s.specular && transmitted {
                let eta = bsdf.eta();
                eta_scale *= if si.wo.dot(si.n) > 0.0 {
                    eta * eta
                } else {
                    1.0 / (eta * eta)
                };
            }
            mr = v.spawn(s.wi);
            // Transmitted into a subsurface material: the path leaves from an exit point, as
            // pbrt-v3's volpath (docs/subsurface.md).
            if let Some(bssrdf) = transmitted.then(|| material.bssrdf(&si)).flatten() {
                let Some(exit) = super::subsurface::find_exit(
                    scene,
                    &bssrdf,
                    material_index,
                    si.time,
                    stream,
                    &mut beta,
                    &mut rays,
                ) else {
                    break;
                };
                let adapter = adapter_bsdf(&exit.si, bssrdf.eta);
                // The exit surface's media, or, on a surface that is no transition, those
                // the path entered by.
                let v = Vertex::Surface {
                    si: &exit.si,
                    bsdf: &adapter,
                    media: scene.surfaces[exit.surface as usize].media.unwrap_or(media),
                };
                let step = (&mut beta, &mut l, &mut rays);
                let Some(s) = continue_from(scene, &v, true, strategy, stream, step) else {
                    break;
                };
                specular_bounce = s.specular;
                mr = v.spawn(s.wi);
            }
        }
        pass_through = 0;
        if !crate::geometry::is_valid_radiance(beta) {
            break;
        }
        let rr_beta = beta * eta_scale;
        let m = rr_beta.max_element();
        if m < settings.rr_threshold && bounces > 3 {
            let q = (1.0 - m).max(0.05);
            if stream.next_1d() < q {
                break;
            }
            beta /= 1.0 - q;
        }
        bounces += 1;
    }
    Radiance {
        l,
        rays,
        first_hit: probe.features(),
    }
}
