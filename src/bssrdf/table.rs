//! pbrt-v3's `BSSRDFTable` and `ComputeBeamDiffusionBSSRDF` (core/bssrdf.cpp): the radial
//! scattering profile of photon beam diffusion (multiple scattering, Habel et al. 2013) plus
//! single scattering, tabulated over 100 albedos and 64 optical radii for unit extinction,
//! with each albedo's effective albedo and the running integrals that sampling inverts. A
//! table depends only on the phase asymmetry `g` and the index `eta`; [`table_for`] builds
//! each (g, eta) once per process.

use super::{fresnel_moment1, fresnel_moment2};
use crate::bsdf::fr_dielectric;
use crate::geometry::Spectrum;
use crate::interpolation::{integrate_catmull_rom, invert_catmull_rom};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Albedo samples of pbrt-v3's tables.
pub const RHO_SAMPLES: usize = 100;
/// Optical radius samples of pbrt-v3's tables.
pub const RADIUS_SAMPLES: usize = 64;

/// A tabulated radial profile: `profile[i * radius_samples.len() + j]` is 2π r Sr(r) at albedo
/// `rho_samples[i]` and optical radius `radius_samples[j]` (unit extinction).
#[derive(Debug)]
pub struct BssrdfTable {
    /// The albedos, denser near 1.
    pub rho_samples: Vec<f32>,
    /// The optical radii: 0, then 2.5e-3 growing by 1.2 each.
    pub radius_samples: Vec<f32>,
    /// 2π r times the profile, row per albedo.
    pub profile: Vec<f32>,
    /// Each albedo's effective albedo: the profile's integral over the plane.
    pub rho_eff: Vec<f32>,
    /// Each row's running integral at each radius node.
    pub profile_cdf: Vec<f32>,
}

/// pbrt-v3's `PhaseHG`: the Henyey-Greenstein phase function at `cos_theta`.
fn phase_hg(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g + 2.0 * g * cos_theta;
    std::f32::consts::FRAC_1_PI * 0.25 * (1.0 - g * g) / (denom * denom.sqrt())
}

/// pbrt-v3's `BeamDiffusionMS`: multiply scattered exitance at radius `r` from a beam entering
/// a medium (σs, σa, `g`, index `eta`), by 100 dipoles along the beam.
pub fn beam_diffusion_ms(sigma_s: f32, sigma_a: f32, g: f32, eta: f32, r: f32) -> f32 {
    const N: usize = 100;
    let sigmap_s = sigma_s * (1.0 - g);
    let sigmap_t = sigma_a + sigmap_s;
    let rhop = sigmap_s / sigmap_t;
    // Grosjean's non-classical diffusion coefficient and the effective transport coefficient.
    let d_g = (2.0 * sigma_a + sigmap_s) / (3.0 * sigmap_t * sigmap_t);
    let sigma_tr = (sigma_a / d_g).sqrt();
    let (fm1, fm2) = (fresnel_moment1(eta), fresnel_moment2(eta));
    // Linear extrapolation distance, and the exitance scale factors.
    let ze = -2.0 * d_g * (1.0 + 3.0 * fm2) / (1.0 - 2.0 * fm1);
    let (c_phi, c_e) = (0.25 * (1.0 - 2.0 * fm1), 0.5 * (1.0 - 3.0 * fm2));
    let inv4pi = 0.25 * std::f32::consts::FRAC_1_PI;
    let mut ed = 0.0f32;
    for i in 0..N {
        let zr = -(1.0 - (i as f32 + 0.5) / N as f32).ln() / sigmap_t;
        let zv = -zr + 2.0 * ze;
        let dr = (r * r + zr * zr).sqrt();
        let dv = (r * r + zv * zv).sqrt();
        let phi_d = inv4pi / d_g * ((-sigma_tr * dr).exp() / dr - (-sigma_tr * dv).exp() / dv);
        let ed_n = inv4pi
            * (zr * (1.0 + sigma_tr * dr) * (-sigma_tr * dr).exp() / (dr * dr * dr)
                - zv * (1.0 + sigma_tr * dv) * (-sigma_tr * dv).exp() / (dv * dv * dv));
        let e = phi_d * c_phi + ed_n * c_e;
        let kappa = 1.0 - (-2.0 * sigmap_t * (dr + zr)).exp();
        ed += kappa * rhop * rhop * e;
    }
    ed / N as f32
}

/// pbrt-v3's `BeamDiffusionSS`: singly scattered exitance at radius `r`, sampled along the
/// refracted beam below the critical angle.
pub fn beam_diffusion_ss(sigma_s: f32, sigma_a: f32, g: f32, eta: f32, r: f32) -> f32 {
    const N: usize = 100;
    let sigma_t = sigma_a + sigma_s;
    let rho = sigma_s / sigma_t;
    let t_crit = r * (eta * eta - 1.0).sqrt();
    let mut ess = 0.0f32;
    for i in 0..N {
        let ti = t_crit - (1.0 - (i as f32 + 0.5) / N as f32).ln() / sigma_t;
        let d = (r * r + ti * ti).sqrt();
        let cos_o = ti / d;
        ess += rho * (-sigma_t * (d + t_crit)).exp() / (d * d)
            * phase_hg(cos_o, g)
            * (1.0 - fr_dielectric(-cos_o, 1.0, eta))
            * cos_o.abs();
    }
    ess / N as f32
}

impl BssrdfTable {
    /// pbrt-v3's `ComputeBeamDiffusionBSSRDF` for asymmetry `g` and index `eta` (pbrt-v3's
    /// 100 albedos by 64 radii). `eta` must be at least 1 (below, single scattering has no
    /// critical angle: pbrt-v3's table is NaN); the material builders check it.
    pub fn beam_diffusion(g: f32, eta: f32) -> Self {
        let (nr, nrho) = (RADIUS_SAMPLES, RHO_SAMPLES);
        let mut radius_samples = vec![0.0f32; nr];
        radius_samples[1] = 2.5e-3;
        for i in 2..nr {
            radius_samples[i] = radius_samples[i - 1] * 1.2;
        }
        let rho_samples: Vec<f32> = (0..nrho)
            .map(|i| (1.0 - (-8.0 * i as f32 / (nrho - 1) as f32).exp()) / (1.0 - (-8.0f32).exp()))
            .collect();
        let mut profile = vec![0.0f32; nr * nrho];
        let mut profile_cdf = vec![0.0f32; nr * nrho];
        let mut rho_eff = vec![0.0f32; nrho];
        // Rows are independent (pbrt-v3 builds them in parallel); two threads halve the
        // few tens of milliseconds a table takes.
        let rows = |profile: &mut [f32], cdf: &mut [f32], eff: &mut [f32], first: usize| {
            for (k, ((row, cdf_row), e)) in profile
                .chunks_mut(nr)
                .zip(cdf.chunks_mut(nr))
                .zip(eff.iter_mut())
                .enumerate()
            {
                let rho = rho_samples[first + k];
                for (j, v) in row.iter_mut().enumerate() {
                    let r = radius_samples[j];
                    *v = 2.0
                        * std::f32::consts::PI
                        * r
                        * (beam_diffusion_ss(rho, 1.0 - rho, g, eta, r)
                            + beam_diffusion_ms(rho, 1.0 - rho, g, eta, r));
                }
                *e = integrate_catmull_rom(&radius_samples, row, cdf_row);
            }
        };
        let half = nrho / 2;
        let (p0, p1) = profile.split_at_mut(half * nr);
        let (c0, c1) = profile_cdf.split_at_mut(half * nr);
        let (e0, e1) = rho_eff.split_at_mut(half);
        std::thread::scope(|s| {
            s.spawn(|| rows(p1, c1, e1, half));
            rows(p0, c0, e0, 0);
        });
        Self {
            rho_samples,
            radius_samples,
            profile,
            rho_eff,
            profile_cdf,
        }
    }

    /// Row `rho_index`'s profile at radius node `radius_index` (pbrt-v3's `EvalProfile`).
    #[inline]
    pub fn eval_profile(&self, rho_index: usize, radius_index: usize) -> f32 {
        self.profile[rho_index * self.radius_samples.len() + radius_index]
    }

    /// pbrt-v3's `SubsurfaceFromDiffuse`: the σa and σs, per channel, whose effective albedo
    /// is `rho_eff` with mean free path `mfp` (σt = 1 / mfp).
    pub fn subsurface_from_diffuse(
        &self,
        rho_eff: Spectrum,
        mfp: Spectrum,
    ) -> (Spectrum, Spectrum) {
        let mut sigma_a = Spectrum::ZERO;
        let mut sigma_s = Spectrum::ZERO;
        for c in 0..3 {
            let rho = invert_catmull_rom(&self.rho_samples, &self.rho_eff, rho_eff[c]);
            sigma_s[c] = rho / mfp[c];
            sigma_a[c] = (1.0 - rho) / mfp[c];
        }
        (sigma_a, sigma_s)
    }
}

/// The tables built so far, by the bits of (g, eta).
type Tables = HashMap<(u32, u32), Arc<BssrdfTable>>;

/// The table for (`g`, `eta`), built on first request and shared after (several materials
/// with the same g and eta share one; pbrt-v3 builds one per material).
pub fn table_for(g: f32, eta: f32) -> Arc<BssrdfTable> {
    static CACHE: OnceLock<Mutex<Tables>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    let key = (g.to_bits(), eta.to_bits());
    if let Some(t) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return Arc::clone(t);
    }
    // Built outside the lock: two threads asking at once at worst both build it.
    let t = Arc::new(BssrdfTable::beam_diffusion(g, eta));
    let mut map = cache.lock().unwrap_or_else(|e| e.into_inner());
    Arc::clone(map.entry(key).or_insert(t))
}
