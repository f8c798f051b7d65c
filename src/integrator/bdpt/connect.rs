//! Connecting a light subpath's first s vertices to a camera subpath's first t (pbrt-v3's
//! `ConnectBDPT`, `G` and `MISWeight`).

use super::super::volpath::{cross_interfaces, MediumRay, Toward};
use super::vertex::{Mode, Vertex, VertexKind};
use super::LightChoice;
use crate::geometry::{Spectrum, Vec2, Vec3};
use crate::scene::Scene;
use crate::stream::SampleSource;
use std::cell::RefCell;

/// One strategy's contribution.
#[derive(Clone, Copy, Debug, Default)]
pub struct Connection {
    /// The path's contribution, MIS-weighted.
    pub l: Spectrum,
    /// Where it lands on the film when the strategy found the camera itself (t = 1).
    pub raster: Option<Vec2>,
    /// Its MIS weight.
    pub mis_weight: f32,
    /// Whether a shadow ray was traced.
    pub traced: bool,
}

/// Whether the segment between `a` and `b` is free (one of them at least is a surface, or
/// one lies at infinity).
fn unoccluded(scene: &Scene, a: &Vertex, b: &Vertex) -> bool {
    let (from, to) = if a.surface.is_some() { (a, b) } else { (b, a) };
    match &from.surface {
        Some(s) => !scene.occluded(&s.si, to.p),
        None => {
            let d = to.p - from.p;
            let ray = crate::geometry::Ray::new(from.p, d, from.time);
            !scene
                .accel
                .occluded(&ray, 1.0 - crate::geometry::SHADOW_EPSILON)
        }
    }
}

/// The transmittance from `a` to `b` (pbrt-v3's `VisibilityTester::Tr`): zero when a
/// surface with a material blocks the segment; through media and across interface surfaces
/// (`Material ""`), which may change the medium, as volpath's shadow rays. Without media in
/// the scene, plain visibility (the shadow ray of a surface-only scene, unchanged).
fn transmittance<S: SampleSource + ?Sized>(
    scene: &Scene,
    a: &Vertex,
    b: &Vertex,
    sampler: &mut S,
) -> Spectrum {
    if scene.media.is_empty() {
        return if unoccluded(scene, a, b) {
            Spectrum::ONE
        } else {
            Spectrum::ZERO
        };
    }
    // From `a`, as pbrt-v3's `VisibilityTester` (a scene's media need not agree on which
    // side a light is: the light subpath's medium, say, is its declared one).
    let (from, to) = (a, b);
    let (ray, t_max) = match &from.surface {
        Some(s) => s.si.spawn_ray_to(to.p),
        None => (
            crate::geometry::Ray::new(from.p, to.p - from.p, from.time),
            1.0 - crate::geometry::SHADOW_EPSILON,
        ),
    };
    let medium = from.medium_toward(scene, ray.d);
    let mr = MediumRay { ray, medium };
    let mut rays = 0;
    match cross_interfaces(scene, mr, t_max, Toward::Point(to.p), sampler, &mut rays) {
        (Some(_), _) => Spectrum::ZERO,
        (None, tr) => tr,
    }
}

/// pbrt-v3's `G` without visibility: the geometry term between two vertices.
fn geometry_term(a: &Vertex, b: &Vertex) -> f32 {
    let d = a.p - b.p;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        return 0.0;
    }
    let mut g = 1.0 / d2;
    let d = d * g.sqrt();
    if a.on_surface() {
        g *= a.ns.dot(d).abs();
    }
    if b.on_surface() {
        g *= b.ns.dot(d).abs();
    }
    g
}

thread_local! {
    /// The vertex a strategy samples itself (the light's for s = 1, the camera's for t = 1),
    /// rewritten field by field for each connection: a vertex is about 1 kB, and building one
    /// and moving it out cost a copy of all of it per connection.
    static SAMPLED: RefCell<Vertex> = RefCell::new(Vertex::camera(
        Vec3::ZERO,
        Vec3::ZERO,
        0.0,
        Spectrum::ZERO,
    ));
}

/// pbrt-v3's `ConnectBDPT` for strategy (s, t): `light` and `camera` hold at least s and t
/// vertices.
pub fn connect<S: SampleSource + ?Sized>(
    scene: &Scene,
    light: &[Vertex],
    camera: &[Vertex],
    s: usize,
    t: usize,
    choice: &LightChoice,
    sampler: &mut S,
) -> Connection {
    // A camera path that escaped connects to nothing.
    if t > 1 && s != 0 && camera[t - 1].kind == VertexKind::Light {
        return Connection::default();
    }
    SAMPLED.with(|v| {
        let v = &mut *v.borrow_mut();
        connect_with(scene, (light, camera), (s, t), choice, sampler, v)
    })
}

/// [`connect`] with the vertex its strategy samples written into `v`.
fn connect_with<S: SampleSource + ?Sized>(
    scene: &Scene,
    (light, camera): (&[Vertex], &[Vertex]),
    (s, t): (usize, usize),
    choice: &LightChoice,
    sampler: &mut S,
    v: &mut Vertex,
) -> Connection {
    let mut c = Connection::default();
    let mut sampled = false;
    let mut l = Spectrum::ZERO;
    if s == 0 {
        let pt = &camera[t - 1];
        if pt.is_light() {
            l = pt.le(scene, &camera[t - 2]) * pt.beta;
        }
    } else if t == 1 {
        let qs = &light[s - 1];
        let u = sampler.next_2d();
        if qs.connectible(scene) {
            if let Some(i) = scene.camera.sample_wi(qs.p, qs.time, u) {
                if i.pdf > 0.0 && i.we != Spectrum::ZERO {
                    let at = (i.p, i.n, qs.time);
                    v.make_endpoint(VertexKind::Camera, at, i.we / i.pdf, None);
                    l = qs.beta * qs.f(v, Mode::Importance) * v.beta;
                    if qs.on_surface() {
                        l *= i.wi.dot(qs.ns).abs();
                    }
                    if l != Spectrum::ZERO {
                        c.traced = true;
                        l *= transmittance(scene, qs, v, sampler);
                    }
                    c.raster = Some(i.raster);
                    sampled = true;
                }
            }
        }
    } else if s == 1 {
        let pt = &camera[t - 1];
        let u_light = sampler.next_1d();
        let u = sampler.next_2d();
        if pt.connectible(scene) {
            if let Some(weight) = sample_light_vertex(scene, pt, choice, (u_light, u), v) {
                l = pt.beta * pt.f(v, Mode::Radiance) * weight;
                if pt.on_surface() {
                    l *= (v.p - pt.p).normalize_or_zero().dot(pt.ns).abs();
                }
                if l != Spectrum::ZERO {
                    c.traced = true;
                    l *= transmittance(scene, pt, v, sampler);
                }
                sampled = true;
            }
        }
    } else {
        let (qs, pt) = (&light[s - 1], &camera[t - 1]);
        if qs.connectible(scene) && pt.connectible(scene) {
            l = qs.beta * qs.f(pt, Mode::Importance) * pt.f(qs, Mode::Radiance) * pt.beta;
            if l != Spectrum::ZERO {
                l *= geometry_term(qs, pt);
                c.traced = true;
                if l != Spectrum::ZERO {
                    l *= transmittance(scene, qs, pt, sampler);
                }
            }
        }
    }
    if l == Spectrum::ZERO {
        return c;
    }
    let sampled = sampled.then_some(&*v);
    let w = super::mis::mis_weight(scene, light, camera, sampled, s, t, choice);
    c.mis_weight = w;
    c.l = l * w;
    c
}

/// The s = 1 strategy's light vertex seen from `pt`, written into `v`: a light chosen at `pt`
/// as `path` chooses one (the strategy's choice) with `u_light`, a point on it by
/// `Light::sample_li` with `u`; returns the weight Le / (pdf of the point and of the choice),
/// `None` (and `v` not a light vertex) when it sends nothing.
fn sample_light_vertex(
    scene: &Scene,
    pt: &Vertex,
    choice: &LightChoice,
    (u_light, u): (f32, Vec2),
    v: &mut Vertex,
) -> Option<Spectrum> {
    let (index, choice_pdf) = choice.sample_at(scene, pt, u_light)?;
    let light = &scene.lights[index];
    let (ls, n) = light.sample_li_with_normal(&scene.accel.world, pt.p, u)?;
    if ls.pdf <= 0.0 || ls.li == Spectrum::ZERO {
        return None;
    }
    let weight = ls.li / (ls.pdf * choice_pdf);
    let at = (ls.p, n, pt.time);
    v.make_endpoint(VertexKind::Light, at, weight, Some(index as u32));
    v.pdf_fwd = v.pdf_light_origin(scene, pt, choice);
    Some(weight)
}
