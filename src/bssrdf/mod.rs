//! Subsurface scattering as pbrt-v3 does it (core/bssrdf.{h,cpp}; docs/subsurface.md): a
//! separable BSSRDF whose radial profile comes from photon beam diffusion tables
//! ([`table`]), sampled by probe rays around the entry point ([`tabulated`]), with the BSDF of
//! the exit point ([`adapter`]) and pbrt-v3's named measurements ([`measured`]). The
//! `subsurface` and `kdsubsurface` materials make a [`TabulatedBssrdf`]; the path integrator's
//! step that uses it is `src/integrator/subsurface.rs`.

pub mod adapter;
pub mod table;
pub mod tabulated;

pub use adapter::adapter_bsdf;
pub use table::{table_for, BssrdfTable};
pub use tabulated::{Probe, TabulatedBssrdf};

/// eta², eta³, eta⁴ and eta⁵, multiplied in pbrt-v3's order (so that values match).
fn powers(eta: f32) -> (f32, f32, f32, f32) {
    let eta2 = eta * eta;
    let eta3 = eta2 * eta;
    let eta4 = eta3 * eta;
    (eta2, eta3, eta4, eta4 * eta)
}

/// pbrt-v3's `FresnelMoment1`: the first moment of the dielectric Fresnel reflectance for
/// relative index `eta` (a polynomial fit).
pub fn fresnel_moment1(eta: f32) -> f32 {
    let (eta2, eta3, eta4, eta5) = powers(eta);
    if eta < 1.0 {
        // pbrt-v3 writes one constant as a double, so the sum from it on is in double.
        let head = 0.45966 - 1.73965 * eta + 3.37668 * eta2;
        (f64::from(head) - 3.904945 * f64::from(eta3) + f64::from(2.49277 * eta4)
            - f64::from(0.68441 * eta5)) as f32
    } else {
        -4.61686 + 11.1136 * eta - 10.4646 * eta2 + 5.11455 * eta3 - 1.27198 * eta4 + 0.12746 * eta5
    }
}

/// pbrt-v3's `FresnelMoment2`: the second moment (a polynomial fit).
pub fn fresnel_moment2(eta: f32) -> f32 {
    let (eta2, eta3, eta4, eta5) = powers(eta);
    if eta < 1.0 {
        0.27614 - 0.87350 * eta + 1.12077 * eta2 - 0.65095 * eta3 + 0.07883 * eta4 + 0.04860 * eta5
    } else {
        let r = 1.0 / eta;
        let (r2, r3) = (r * r, r * r * r);
        -547.033 + 45.3087 * r3 - 218.725 * r2 + 458.843 * r + 404.557 * eta - 189.519 * eta2
            + 54.9327 * eta3
            - 9.00603 * eta4
            + 0.63942 * eta5
    }
}

#[cfg(test)]
mod tests;
