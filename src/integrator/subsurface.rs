//! The path integrator's subsurface step (pbrt-v3's `PathIntegrator::Li`, its BSSRDF block;
//! docs/subsurface.md): when a path is transmitted into a subsurface material, an exit point is
//! found by a probe segment around the entry point (pbrt-v3's `Sample_Sp`: every surface of
//! the same material along it, one chosen uniformly), the throughput takes Sp / pdf, light is
//! sampled at the exit point through the adapter BSDF, and the path continues from there by a
//! sample of that BSDF. Kept apart from `path` so that `volpath` can call it too.

use super::light_sample::{next_event, LastScatter};
use super::MAX_PASS_THROUGH;
use crate::accel::Hit;
use crate::bssrdf::{adapter_bsdf, TabulatedBssrdf};
use crate::geometry::{is_valid_radiance, Ray, Spectrum, SurfaceInteraction, Vec3};
use crate::lightbvh::LightContext;
use crate::lightdistrib::LightStrategy;
use crate::scene::Scene;
use crate::stream::SampleSource;

/// An exit point found by [`find_exit`]: its interaction (looking out along its shading
/// normal, pbrt-v3's `Sample_S`) and the index of its surface in the scene.
pub(super) struct Exit {
    /// The exit point, `wo` its shading normal.
    pub si: SurfaceInteraction,
    /// Its surface (`Scene::surfaces`), whose media the path leaves into.
    pub surface: u32,
}

/// Finds where a path that entered material `material` (whose BSSRDF at the entry point is
/// `bssrdf`, at time `time`) leaves it, and multiplies `beta` by Sp / pdf: pbrt-v3's
/// `SeparableBSSRDF::Sample_S`, shared by `path` and `volpath`. `None` ends the path (no exit
/// point found), as pbrt-v3's `break`. Every probe ray is counted in `rays`.
pub(super) fn find_exit(
    scene: &Scene,
    bssrdf: &TabulatedBssrdf,
    material: u32,
    time: f32,
    stream: &mut impl SampleSource,
    beta: &mut Spectrum,
    rays: &mut u32,
) -> Option<Exit> {
    let u1 = stream.next_1d();
    let u2 = stream.next_2d();
    let probe = bssrdf.probe(u1, u2)?;
    // Every surface of the same material along the segment (pbrt-v3 compares material
    // pointers; acr's materials are indices). Other surfaces are crossed. Only the chosen
    // one's full interaction is computed; the probe needs just each hit's point and normal.
    let mut found = Candidates::default();
    let mut ray = Ray::new(probe.start, probe.end - probe.start, time);
    let mut t_max = 1.0 - crate::geometry::SHADOW_EPSILON;
    for _ in 0..MAX_PASS_THROUGH {
        if ray.d == Vec3::ZERO {
            break;
        }
        *rays += 1;
        let Some(hit) = scene.accel.intersect(&ray, t_max) else {
            break;
        };
        let c = scene.accel.crossing(&ray, &hit);
        if scene.surfaces[hit.prim.surface as usize].material == Some(material) {
            found.push(Candidate {
                hit,
                ray,
                p: c.p,
                n: c.n,
            });
        }
        (ray, t_max) = c.spawn_ray_to(probe.end);
    }
    let n = found.len();
    let chosen = found.get(((probe.u_choice * n as f32) as usize).min(n.max(1) - 1))?;
    let pdf = bssrdf.pdf_sp(chosen.p, chosen.n) / n as f32;
    let sp = bssrdf.sp(chosen.p);
    if sp == Spectrum::ZERO || pdf.is_nan() || pdf <= 0.0 {
        return None;
    }
    *beta *= sp / pdf;
    if !is_valid_radiance(*beta) {
        return None;
    }
    let mut si = scene.accel.interaction(&chosen.ray, &chosen.hit);
    // pbrt-v3's `Sample_S`: the exit point looks out along its shading normal.
    si.wo = si.shading_n;
    Some(Exit {
        si,
        surface: chosen.hit.prim.surface,
    })
}

/// A probe segment's hit on the entry's material: the hit and the ray that found it (for the
/// full interaction, computed for the chosen one only), its point and geometric normal.
#[derive(Clone, Copy)]
struct Candidate {
    hit: Hit,
    ray: Ray,
    p: Vec3,
    n: Vec3,
}

/// How many candidates [`Candidates`] keeps without allocating: a convex surface gives two.
const INLINE_CANDIDATES: usize = 8;

/// The candidates along one probe segment: the first few in place, the rest (a segment through
/// a folded surface) on the heap, so that the common case allocates nothing.
#[derive(Default)]
struct Candidates {
    inline: [Option<Candidate>; INLINE_CANDIDATES],
    len: usize,
    spill: Vec<Candidate>,
}

impl Candidates {
    fn push(&mut self, c: Candidate) {
        match self.inline.get_mut(self.len) {
            Some(slot) => *slot = Some(c),
            None => self.spill.push(c),
        }
        self.len += 1;
    }

    fn len(&self) -> usize {
        self.len
    }

    fn get(&self, i: usize) -> Option<Candidate> {
        if i >= self.len {
            return None;
        }
        match self.inline.get(i) {
            Some(slot) => *slot,
            None => self.spill.get(i - INLINE_CANDIDATES).copied(),
        }
    }
}

/// Follows a path that entered material `material` (whose BSSRDF at the entry point is
/// `bssrdf`, at time `time`) to its exit point ([`find_exit`]), adds the light sampled there
/// to `l`, multiplies `beta` by the adapter BSDF's sample and records that scattering in
/// `last` (for the MIS weight of the emission the next ray finds). Returns the ray that
/// continues the path; `None` ends it, as pbrt-v3's `break`. Every probe and shadow ray is
/// counted in `rays`.
#[allow(clippy::too_many_arguments)]
pub(super) fn scatter(
    scene: &Scene,
    bssrdf: &TabulatedBssrdf,
    material: u32,
    time: f32,
    strategy: LightStrategy,
    stream: &mut impl SampleSource,
    beta: &mut Spectrum,
    l: &mut Spectrum,
    last: &mut LastScatter,
    rays: &mut u32,
) -> Option<Ray> {
    let pi = find_exit(scene, bssrdf, material, time, stream, beta, rays)?.si;
    let bsdf = adapter_bsdf(&pi, bssrdf.eta);
    last.ctx = None;
    if !scene.lights.is_empty() {
        let ctx = LightContext {
            p: pi.p,
            n: pi.shading_n,
        };
        last.ctx = Some(ctx);
        if let Some(direct) = next_event(scene, &pi, &bsdf, &ctx, strategy, stream, rays) {
            *l += *beta * direct;
        }
    }
    let u_lobe = stream.next_1d();
    let u = stream.next_2d();
    let s = bsdf.sample_f(pi.wo, u, u_lobe)?;
    if s.pdf <= 0.0 || s.f == Spectrum::ZERO {
        return None;
    }
    *beta *= s.f * s.wi.dot(pi.shading_n).abs() / s.pdf;
    if !is_valid_radiance(*beta) {
        return None;
    }
    last.whole = false;
    last.p = pi.p;
    last.bsdf_pdf = s.pdf;
    Some(pi.spawn_ray(s.wi))
}
