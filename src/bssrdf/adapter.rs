//! pbrt-v3's `SeparableBSSRDFAdapter` (core/bssrdf.h): the BSDF at the point where a
//! subsurface path leaves the surface. Its one diffuse reflection lobe is the BSSRDF's
//! directional term Sw(wi) = (1 - Fr(cos θi)) / (c π), times η² for radiance transport.

use super::fresnel_moment1;
use crate::bsdf::{Bsdf, Bxdf};
use crate::geometry::SurfaceInteraction;

/// The BSDF at exit point `pi` for index `eta`: its shading frame, relative index 1 (as pbrt-v3,
/// whose adapter BSDF is built with the default), one `BssrdfAdapter` lobe.
pub fn adapter_bsdf(pi: &SurfaceInteraction, eta: f32) -> Bsdf {
    let mut b = Bsdf::new(pi, 1.0);
    b.add(Bxdf::BssrdfAdapter {
        eta,
        scale: adapter_scale(eta),
    });
    b
}

/// η² / (c π) with c = 1 - 2 FresnelMoment1(1 / η): the factor of Sw, with the η² of
/// radiance transport (pbrt-v3's adapter in `TransportMode::Radiance`).
pub fn adapter_scale(eta: f32) -> f32 {
    let c = 1.0 - 2.0 * fresnel_moment1(1.0 / eta);
    eta * eta / (c * std::f32::consts::PI)
}
