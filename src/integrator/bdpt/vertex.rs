//! A subpath vertex (pbrt-v3's `Vertex`): a camera or light endpoint or a surface point, with
//! the densities with which each direction of travel generates it, for the MIS weights.

use super::LightChoice;
use crate::bsdf::{Bsdf, Bxdf};
use crate::geometry::{Spectrum, SurfaceInteraction, Vec3};
use crate::light::{Light, WorldSphere};
use crate::material::Material;
use crate::medium::{HenyeyGreenstein, MediumInterface};
use crate::scene::Scene;

/// Which way a subpath carries light (pbrt-v3's `TransportMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// From the camera: radiance.
    Radiance,
    /// From a light: importance.
    Importance,
}

/// What a vertex is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// The camera's lens.
    Camera,
    /// A light's emitting point, or where a camera ray left the scene (infinite lights).
    Light,
    /// A surface.
    Surface,
    /// A scattering point in a participating medium.
    Medium,
}

/// A surface vertex's scattering.
#[derive(Clone, Debug)]
pub struct SurfacePoint {
    /// The (shading) interaction.
    pub si: SurfaceInteraction,
    /// Its BSDF.
    pub bsdf: Bsdf,
}

/// A vertex of a camera or light subpath.
#[derive(Clone, Debug)]
pub struct Vertex {
    /// What it is.
    pub kind: VertexKind,
    /// The subpath's throughput up to it.
    pub beta: Spectrum,
    /// Position.
    pub p: Vec3,
    /// Geometric normal (zero for a point not on a surface).
    pub ng: Vec3,
    /// Shading normal (`ng` but on surfaces).
    pub ns: Vec3,
    /// The ray's time.
    pub time: f32,
    /// Scattered by a specular lobe.
    pub delta: bool,
    /// Area density of generating it from the previous vertex of its subpath.
    pub pdf_fwd: f32,
    /// Area density of generating it from the next vertex (the other direction).
    pub pdf_rev: f32,
    /// The light: a light endpoint's (`None` where a camera ray escaped: the infinite
    /// lights), or a surface's area light.
    pub light: Option<u32>,
    /// A surface's scattering.
    pub surface: Option<SurfacePoint>,
    /// A medium vertex's phase function and the direction it was reached from (pointing back).
    pub phase: Option<(HenyeyGreenstein, Vec3)>,
    /// The media on either side: a surface's (both the ray's medium on a surface that is no
    /// transition), a medium vertex's medium on both; unused by the endpoints, whose media are
    /// the camera's and the lights' ([`Vertex::medium_toward`]).
    pub media: MediumInterface,
}

/// pbrt-v3's `CorrectShadingNormal`: the adjoint BSDF's correction for shading normals in
/// importance transport.
pub fn correct_shading_normal(si: &SurfaceInteraction, wo: Vec3, wi: Vec3, mode: Mode) -> f32 {
    if mode == Mode::Radiance {
        return 1.0;
    }
    let num = wo.dot(si.shading_n).abs() * wi.dot(si.n).abs();
    let denom = wo.dot(si.n).abs() * wi.dot(si.shading_n).abs();
    if denom == 0.0 {
        0.0
    } else {
        num / denom
    }
}

/// Whether a lobe scales transmitted radiance by (eta_i / eta_t)^2 (the dielectric ones).
fn scales_radiance(bxdf: &Bxdf) -> bool {
    matches!(
        bxdf,
        Bxdf::SpecularTransmission { .. }
            | Bxdf::FresnelSpecular { .. }
            | Bxdf::MicrofacetTransmission { .. }
    )
}

/// The factor that undoes radiance's (eta_i / eta_t)^2 across the interface for (wo, wi),
/// or 1 when they are on one side.
fn eta_undo(bsdf: &Bsdf, si: &SurfaceInteraction, wo: Vec3) -> f32 {
    let eta = bsdf.eta();
    // Entering (wo outside): radiance was scaled by 1 / eta^2, importance is not.
    if wo.dot(si.n) > 0.0 {
        eta * eta
    } else {
        1.0 / (eta * eta)
    }
}

/// The BSDF for (wo, wi) in transport `mode`, given its radiance value `f` (the whole BSDF's,
/// or with `specular` a specular lobe's sample): acr's lobes are radiance's, whose dielectric
/// transmission is scaled by (eta_i / eta_t)^2; importance transport leaves that out (pbrt-v3's
/// `TransportMode::Importance`), lobe by lobe, so that a translucent surface's Lambertian
/// transmission beside its microfacet one keeps its value.
pub fn adjoint_f(
    bsdf: &Bsdf,
    si: &SurfaceInteraction,
    (wo, wi): (Vec3, Vec3),
    f: Spectrum,
    specular: bool,
    mode: Mode,
) -> Spectrum {
    let transmitted = wo.dot(si.n) * wi.dot(si.n) < 0.0;
    if mode == Mode::Radiance || !transmitted || bsdf.eta() == 1.0 {
        return f;
    }
    let undo = eta_undo(bsdf, si, wo);
    if specular {
        // Specular transmission lobes are all dielectric.
        return f * undo;
    }
    let frame = bsdf.frame();
    let (lo, li) = (frame.to_local(wo), frame.to_local(wi));
    let dielectric: Spectrum = bsdf
        .lobes()
        .iter()
        .filter(|l| scales_radiance(&l.bxdf))
        .map(|l| l.scale * l.bxdf.f(lo, li))
        .sum();
    let g = f + dielectric * (undo - 1.0);
    if g.is_finite() {
        g.max(Spectrum::ZERO)
    } else {
        Spectrum::ZERO
    }
}

impl Vertex {
    /// The camera endpoint at `p` (pbrt-v3's `CreateCamera`); `n` the lens normal or zero.
    pub fn camera(p: Vec3, n: Vec3, time: f32, beta: Spectrum) -> Self {
        Self::endpoint(VertexKind::Camera, p, n, time, beta, None)
    }

    /// A light endpoint.
    pub fn endpoint(
        kind: VertexKind,
        p: Vec3,
        n: Vec3,
        time: f32,
        beta: Spectrum,
        light: Option<u32>,
    ) -> Self {
        Self {
            kind,
            beta,
            p,
            ng: n,
            ns: n,
            time,
            delta: false,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            light,
            surface: None,
            phase: None,
            media: MediumInterface::default(),
        }
    }

    /// Makes this vertex [`Vertex::endpoint`]'s, field by field (a kept slot of a
    /// [`super::Subpath`]: no 1 kB vertex built and copied in).
    pub fn make_endpoint(
        &mut self,
        kind: VertexKind,
        (p, n, time): (Vec3, Vec3, f32),
        beta: Spectrum,
        light: Option<u32>,
    ) {
        self.kind = kind;
        self.beta = beta;
        self.p = p;
        self.ng = n;
        self.ns = n;
        self.time = time;
        self.delta = false;
        self.pdf_fwd = 0.0;
        self.pdf_rev = 0.0;
        self.light = light;
        self.surface = None;
        self.phase = None;
        self.media = MediumInterface::default();
    }

    /// Makes this vertex a surface vertex at the (shaded) interaction it holds (see
    /// [`super::Subpath::next_interaction`]) with `material`'s BSDF refilled in place (no
    /// lobes without one: nothing will read its scattering), reached from `prev` with
    /// solid-angle density `pdf`.
    pub fn make_surface(
        &mut self,
        material: Option<&Material>,
        (light, media): (Option<u32>, MediumInterface),
        beta: Spectrum,
        pdf: f32,
        prev: &Vertex,
    ) {
        let point = self
            .surface
            .as_mut()
            .expect("Subpath::next_interaction gives the slot an interaction");
        match material {
            Some(m) => m.bsdf_into(&point.si, &mut point.bsdf),
            None => point.bsdf.clear(),
        }
        let si = &point.si;
        let (p, ng) = (si.p, si.n);
        (self.p, self.ng, self.ns, self.time) = (p, ng, si.shading_n, si.time);
        self.kind = VertexKind::Surface;
        self.beta = beta;
        self.delta = false;
        self.pdf_fwd = 0.0;
        self.pdf_rev = 0.0;
        self.light = light;
        self.phase = None;
        self.media = media;
        // From the values in hand: reading the vertex's fields just written stalled.
        self.pdf_fwd = prev.area_density(pdf, p, ng);
    }

    /// A scattering point `p` in `medium` (phase function `phase`), reached along `-wo` from
    /// `prev` with solid-angle density `pdf` (pbrt-v3's `CreateMedium`).
    pub fn medium(
        (p, wo, time): (Vec3, Vec3, f32),
        phase: HenyeyGreenstein,
        medium: Option<u32>,
        beta: Spectrum,
        pdf: f32,
        prev: &Vertex,
        scene: &Scene,
    ) -> Self {
        let mut v = Self {
            kind: VertexKind::Medium,
            beta,
            p,
            ng: Vec3::ZERO,
            ns: Vec3::ZERO,
            time,
            delta: false,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            light: None,
            surface: None,
            phase: Some((phase, wo)),
            media: MediumInterface {
                inside: medium,
                outside: medium,
            },
        };
        v.pdf_fwd = prev.convert_density(pdf, &v, scene);
        v
    }

    /// The medium a ray leaving this vertex along `d` travels in (pbrt-v3's
    /// `Interaction::GetMedium`): the camera's, a light's, or the vertex's own.
    pub fn medium_toward(&self, scene: &Scene, d: Vec3) -> Option<u32> {
        match self.kind {
            VertexKind::Camera => scene.camera_medium,
            VertexKind::Light => self
                .light
                .and_then(|i| scene.light_media.get(i as usize))
                .and_then(|m| m.toward(self.ng, d)),
            VertexKind::Surface | VertexKind::Medium => self.media.toward(self.ng, d),
        }
    }

    /// Whether it lies on a surface (a non-zero normal).
    pub fn on_surface(&self) -> bool {
        self.ng != Vec3::ZERO
    }

    /// Whether it emits: a light endpoint or an area light's surface.
    pub fn is_light(&self) -> bool {
        self.kind == VertexKind::Light || (self.kind == VertexKind::Surface && self.light.is_some())
    }

    /// The light object, when there is one.
    fn light_of<'s>(&self, scene: &'s Scene) -> Option<&'s Light> {
        self.light.map(|i| &scene.lights[i as usize])
    }

    /// A light endpoint of a light that no ray can hit.
    pub fn is_delta_light(&self, scene: &Scene) -> bool {
        self.kind == VertexKind::Light && self.light_of(scene).is_some_and(Light::is_delta)
    }

    /// A light endpoint at infinity: an escaped camera ray, an infinite or a distant light.
    pub fn is_infinite_light(&self, scene: &Scene) -> bool {
        self.kind == VertexKind::Light
            && match self.light_of(scene) {
                None => true,
                Some(l) => matches!(l, Light::Infinite { .. } | Light::Distant { .. }),
            }
    }

    /// Whether a connection can end here (not a specular surface nor a distant light).
    pub fn connectible(&self, scene: &Scene) -> bool {
        match self.kind {
            VertexKind::Camera => true,
            VertexKind::Light => !matches!(self.light_of(scene), Some(Light::Distant { .. })),
            VertexKind::Surface => self
                .surface
                .as_ref()
                .is_some_and(|s| s.bsdf.has_non_specular()),
            VertexKind::Medium => true,
        }
    }

    /// The BSDF towards `next` (pbrt-v3's `Vertex::f`), for transport `mode`.
    pub fn f(&self, next: &Vertex, mode: Mode) -> Spectrum {
        let wi = (next.p - self.p).normalize_or_zero();
        if wi == Vec3::ZERO {
            return Spectrum::ZERO;
        }
        if let Some((phase, wo)) = &self.phase {
            return Spectrum::splat(phase.p(*wo, wi));
        }
        let Some(s) = &self.surface else {
            return Spectrum::ZERO;
        };
        let wo = s.si.wo;
        let f = s.bsdf.f(wo, wi);
        adjoint_f(&s.bsdf, &s.si, (wo, wi), f, false, mode)
            * correct_shading_normal(&s.si, wo, wi, mode)
    }

    /// A solid-angle density at this vertex towards `next` as an area density there.
    pub fn convert_density(&self, pdf: f32, next: &Vertex, scene: &Scene) -> f32 {
        if next.is_infinite_light(scene) {
            return pdf;
        }
        self.area_density(pdf, next.p, next.ng)
    }

    /// [`Vertex::convert_density`] towards a point `p` at finite distance, of geometric
    /// normal `ng` (zero off surfaces).
    #[inline]
    fn area_density(&self, pdf: f32, p: Vec3, ng: Vec3) -> f32 {
        let w = p - self.p;
        let d2 = w.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let inv = 1.0 / d2;
        let cos = if ng != Vec3::ZERO {
            ng.dot(w * inv.sqrt()).abs()
        } else {
            1.0
        };
        pdf * cos * inv
    }

    /// The area density of generating `next` from this vertex, reached from `prev`
    /// (pbrt-v3's `Vertex::Pdf`).
    pub fn pdf(&self, scene: &Scene, prev: Option<&Vertex>, next: &Vertex) -> f32 {
        if self.kind == VertexKind::Light {
            return self.pdf_light(scene, next);
        }
        let wn = (next.p - self.p).normalize_or_zero();
        if wn == Vec3::ZERO {
            return 0.0;
        }
        let pdf = match (self.kind, &self.surface) {
            (VertexKind::Camera, _) => scene.camera.pdf_we(self.p, wn, self.time).1,
            (VertexKind::Surface, Some(s)) => {
                let Some(prev) = prev else { return 0.0 };
                let wp = (prev.p - self.p).normalize_or_zero();
                if wp == Vec3::ZERO {
                    return 0.0;
                }
                s.bsdf.pdf(wp, wn)
            }
            (VertexKind::Medium, _) => {
                let (Some(prev), Some((phase, _))) = (prev, &self.phase) else {
                    return 0.0;
                };
                let wp = (prev.p - self.p).normalize_or_zero();
                if wp == Vec3::ZERO {
                    return 0.0;
                }
                phase.p(wp, wn)
            }
            _ => 0.0,
        };
        self.convert_density(pdf, next, scene)
    }

    /// The world's bounding sphere.
    fn sphere(scene: &Scene) -> WorldSphere {
        WorldSphere {
            center: scene.world_center,
            radius: scene.world_radius,
        }
    }

    /// The area density with which this light vertex emits towards `v` (pbrt-v3's
    /// `PdfLight`).
    pub fn pdf_light(&self, scene: &Scene, v: &Vertex) -> f32 {
        let w = v.p - self.p;
        let d2 = w.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let inv = 1.0 / d2;
        let w = w * inv.sqrt();
        let mut pdf = if self.is_infinite_light(scene) {
            let r = scene.world_radius;
            1.0 / (std::f32::consts::PI * r * r)
        } else {
            let Some(light) = self.light_of(scene) else {
                return 0.0;
            };
            light.pdf_emission(Self::sphere(scene), self.ng, w).1 * inv
        };
        if v.on_surface() {
            pdf *= v.ng.dot(w).abs();
        }
        pdf
    }

    /// The density of this light vertex as a light subpath's origin when the path goes on to
    /// `v` (pbrt-v3's `PdfLightOrigin`): the light's choice times its position's density, or
    /// for infinite lights the density of the direction.
    pub fn pdf_light_origin(&self, scene: &Scene, v: &Vertex, choice: &LightChoice) -> f32 {
        let w = (v.p - self.p).normalize_or_zero();
        if w == Vec3::ZERO {
            return 0.0;
        }
        if self.is_infinite_light(scene) {
            return infinite_light_density(scene, w, |i| choice.origin_pdf(scene, i));
        }
        let Some(i) = self.light else { return 0.0 };
        let pos = scene.lights[i as usize]
            .pdf_emission(Self::sphere(scene), self.ng, w)
            .0;
        pos * choice.origin_pdf(scene, i as usize)
    }

    /// The radiance this light vertex emits towards `v` (pbrt-v3's `Vertex::Le`).
    pub fn le(&self, scene: &Scene, v: &Vertex) -> Spectrum {
        if !self.is_light() {
            return Spectrum::ZERO;
        }
        let w = (v.p - self.p).normalize_or_zero();
        if w == Vec3::ZERO {
            return Spectrum::ZERO;
        }
        if self.is_infinite_light(scene) {
            return scene
                .infinite_lights
                .iter()
                .map(|&i| scene.lights[i as usize].le(-w))
                .sum();
        }
        match (&self.surface, self.light_of(scene)) {
            (Some(s), Some(light)) => light.l(&s.si, w),
            _ => Spectrum::ZERO,
        }
    }
}

/// pbrt-v3's `InfiniteLightDensity`: the density of the infinite lights sending light along
/// `-w` (w points away from them), each weighted by its choice probability `choice`.
pub fn infinite_light_density(scene: &Scene, w: Vec3, choice: impl Fn(usize) -> f32) -> f32 {
    scene
        .infinite_lights
        .iter()
        .map(|&i| {
            let light = &scene.lights[i as usize];
            if matches!(light, Light::Infinite { .. }) {
                light.pdf_le(-w) * choice(i as usize)
            } else {
                0.0
            }
        })
        .sum()
}
