//! Light sampling at a scattering point, shared by `path`, its subsurface step and
//! `directlighting`: one light sample with MIS against the BSDF, next-event estimation for the
//! lights chosen at a point, and the last scattering's record that the MIS weight of emission
//! found later needs.

use crate::geometry::{Spectrum, SurfaceInteraction, Vec3};
use crate::lightbvh::LightContext;
use crate::lightdistrib::LightStrategy;
use crate::sampling::power_heuristic;
use crate::scene::Scene;
use crate::stream::SampleSource;

/// One light sample at `si` with MIS against the BSDF (for non-delta lights): pbrt-v3's
/// EstimateDirect without its BSDF-sampling half, which the caller's next ray provides.
#[inline]
pub(super) fn sample_light(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &crate::bsdf::Bsdf,
    light_index: u32,
    choice_pdf: f32,
    stream: &mut impl SampleSource,
    rays: &mut u32,
) -> Spectrum {
    let light = &scene.lights[light_index as usize];
    let u = stream.next_2d();
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
    let light_pdf = ls.pdf * choice_pdf;
    if light.is_delta() {
        f * ls.li / light_pdf
    } else {
        let w = power_heuristic(1.0, light_pdf, 1.0, bsdf.pdf(si.wo, ls.wi));
        f * ls.li * w / light_pdf
    }
}

/// The path's last scattering, as the MIS weight of the emission its next ray finds needs it.
#[derive(Clone, Copy)]
pub(super) struct LastScatter {
    /// Whether the next ray is the camera ray or leaves a specular bounce: no light sample
    /// could have found what it finds, so its emission counts whole.
    pub(super) whole: bool,
    /// The scattering point.
    pub(super) p: Vec3,
    /// The BSDF density of the direction taken from it.
    pub(super) bsdf_pdf: f32,
    /// Where the light for next-event estimation was chosen there (`None`: none was).
    pub(super) ctx: Option<LightContext>,
}

impl LastScatter {
    /// Emission `le` of light `light` found by the path of throughput `beta`, weighted against
    /// the light sample at the last scattering, whose density of it `pdf_of_light` gives
    /// (times the chance of choosing the light).
    pub(super) fn weigh(
        &self,
        scene: &Scene,
        strategy: LightStrategy,
        light: usize,
        beta: Spectrum,
        le: Spectrum,
        pdf_of_light: impl FnOnce() -> f32,
    ) -> Spectrum {
        if self.whole {
            return beta * le;
        }
        let choice = self
            .ctx
            .map_or(0.0, |ctx| scene.light_choice_pdf(strategy, ctx, light));
        let light_pdf = choice * pdf_of_light();
        beta * le * power_heuristic(1.0, self.bsdf_pdf, 1.0, light_pdf)
    }
}

/// Next-event estimation at `si` for the lights chosen at `ctx`: a light's sampled direct
/// radiance; `None` when no light can reach the point (its sample's dimensions are spent all
/// the same, so that later decisions keep their place in the stream). `ctx` by reference: by
/// value, its fields were stored and at once reloaded in wider pieces, which stalls.
pub(super) fn next_event(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &crate::bsdf::Bsdf,
    ctx: &LightContext,
    strategy: LightStrategy,
    stream: &mut impl SampleSource,
    rays: &mut u32,
) -> Option<Spectrum> {
    match scene.choose_light(strategy, *ctx, stream.next_1d()) {
        Some((light_index, choice_pdf)) => Some(sample_light(
            scene,
            si,
            bsdf,
            light_index as u32,
            choice_pdf,
            stream,
            rays,
        )),
        None => {
            stream.next_2d();
            None
        }
    }
}
