//! pbrt-v3's `SeparableBSSRDF` and `TabulatedBSSRDF` (core/bssrdf.{h,cpp}) at an entry point
//! `po`: the spatial profile Sp interpolated from a [`BssrdfTable`], its radial sampling and
//! density, and the choice of a probe segment (an axis of the shading frame, a colour channel,
//! a radius and an angle) along which the integrator looks for the exit point. Tracing the
//! probe is the integrator's (`src/integrator/subsurface.rs`), which keeps this module free of
//! the scene.

use super::table::BssrdfTable;
use crate::geometry::{Frame, Spectrum, SurfaceInteraction, Vec2, Vec3};
use crate::interpolation::{catmull_rom_weights, sample_catmull_rom_2d};
use std::f32::consts::PI;

/// A separable BSSRDF with a tabulated radial profile, at one entry point.
#[derive(Clone, Copy, Debug)]
pub struct TabulatedBssrdf<'a> {
    /// The entry point.
    pub po: Vec3,
    /// Shading frame at the entry point (z = shading normal, x = normalised shading dp/du).
    pub frame: Frame,
    /// Relative index of refraction, inside over outside.
    pub eta: f32,
    /// Extinction σa + σs per channel (mm⁻¹ or scene units, as given).
    pub sigma_t: Spectrum,
    /// Single-scattering albedo σs / σt per channel (0 where σt is 0).
    pub rho: Spectrum,
    /// The profile table.
    pub table: &'a BssrdfTable,
    /// Each channel's sampling radius bound (its 0.999 quantile), when known in advance (a
    /// material with constant coefficients computes it once): `None` computes it per sample.
    pub r_max: Option<[Option<f32>; 3]>,
}

/// A probe segment and what is left of the sample that chose it.
#[derive(Clone, Copy, Debug)]
pub struct Probe {
    /// Start of the segment.
    pub start: Vec3,
    /// End of the segment.
    pub end: Vec3,
    /// The remainder of the one-dimensional sample, uniform in [0, 1), that picks one of the
    /// surfaces found along the segment.
    pub u_choice: f32,
}

impl<'a> TabulatedBssrdf<'a> {
    /// The BSSRDF at `si` (its shading frame) with index `eta`, absorption `sigma_a` and
    /// scattering `sigma_s`; channels that are not finite and non-negative count as zero
    /// (pbrt-v3 would carry NaN into the image).
    pub fn new(
        si: &SurfaceInteraction,
        eta: f32,
        sigma_a: Spectrum,
        sigma_s: Spectrum,
        table: &'a BssrdfTable,
    ) -> Self {
        let frame = Frame::from_xz(si.shading_dpdu, si.shading_n);
        Self::with_frame(si.p, frame, eta, sigma_a, sigma_s, table)
    }

    /// [`Self::new`] at point `po` with shading frame `frame`.
    pub fn with_frame(
        po: Vec3,
        frame: Frame,
        eta: f32,
        sigma_a: Spectrum,
        sigma_s: Spectrum,
        table: &'a BssrdfTable,
    ) -> Self {
        let clean = |s: Spectrum| {
            Spectrum::from_array(
                s.to_array()
                    .map(|c| if c.is_finite() && c > 0.0 { c } else { 0.0 }),
            )
        };
        let (sigma_a, sigma_s) = (clean(sigma_a), clean(sigma_s));
        let sigma_t = sigma_a + sigma_s;
        let mut rho = Spectrum::ZERO;
        for c in 0..3 {
            // An infinite σt (from an infinite σa or σs) leaves σs / σt NaN: no albedo.
            let r = if sigma_t[c] != 0.0 {
                sigma_s[c] / sigma_t[c]
            } else {
                0.0
            };
            rho[c] = if r.is_finite() { r } else { 0.0 };
        }
        Self {
            po,
            frame,
            eta,
            sigma_t,
            rho,
            table,
            r_max: None,
        }
    }

    /// Each channel's sampling radius bound ([`Self::sample_sr`] at 0.999), for
    /// [`Self::r_max`].
    pub fn radius_bounds(&self) -> [Option<f32>; 3] {
        [0, 1, 2].map(|ch| self.sample_sr(ch, 0.999))
    }

    /// Spline weights of channel `ch` at optical radius `r_optical`, and the effective albedo
    /// interpolated by its rho weights (`None` outside the table, as pbrt-v3's weights fail).
    #[inline]
    fn interpolate(&self, ch: usize, r_optical: f32) -> Option<(f32, f32)> {
        let rho = catmull_rom_weights(&self.table.rho_samples, self.rho[ch])?;
        self.interpolate_with(rho, r_optical)
    }

    /// [`Self::interpolate`] with the channel's albedo weights already found.
    #[inline]
    fn interpolate_with(
        &self,
        (rho_off, rho_w): (isize, [f32; 4]),
        r_optical: f32,
    ) -> Option<(f32, f32)> {
        let t = self.table;
        let (rad_off, rad_w) = catmull_rom_weights(&t.radius_samples, r_optical)?;
        let (mut sr, mut rho_eff) = (0.0f32, 0.0f32);
        for (i, &wi) in rho_w.iter().enumerate() {
            if wi == 0.0 {
                continue;
            }
            let row = (rho_off + i as isize) as usize;
            rho_eff += t.rho_eff[row] * wi;
            for (j, &wj) in rad_w.iter().enumerate() {
                if wj != 0.0 {
                    sr += t.eval_profile(row, (rad_off + j as isize) as usize) * wi * wj;
                }
            }
        }
        // Cancel the 2π r the table carries for radial sampling.
        if r_optical != 0.0 {
            sr /= 2.0 * PI * r_optical;
        }
        Some((sr, rho_eff))
    }

    /// pbrt-v3's `TabulatedBSSRDF::Sr`: the radial profile at distance `r`, per channel,
    /// in world units (non-negative).
    pub fn sr(&self, r: f32) -> Spectrum {
        let mut out = Spectrum::ZERO;
        for ch in 0..3 {
            if let Some((sr, _)) = self.interpolate(ch, r * self.sigma_t[ch]) {
                out[ch] = sr;
            }
        }
        (out * self.sigma_t * self.sigma_t).max(Spectrum::ZERO)
    }

    /// pbrt-v3's `Sp`: the profile at the distance from the entry point to `pi`.
    pub fn sp(&self, pi: Vec3) -> Spectrum {
        self.sr(self.po.distance(pi))
    }

    /// pbrt-v3's `Sample_Sr`: a radius for channel `ch` distributed as its profile (`None`
    /// where the channel does not scatter or the table gives nothing to sample).
    pub fn sample_sr(&self, ch: usize, u: f32) -> Option<f32> {
        if self.sigma_t[ch] == 0.0 {
            return None;
        }
        let t = self.table;
        let (r, _, _) = sample_catmull_rom_2d(
            &t.rho_samples,
            &t.radius_samples,
            &t.profile,
            &t.profile_cdf,
            self.rho[ch],
            u,
        )?;
        let r = r / self.sigma_t[ch];
        (r >= 0.0 && r.is_finite()).then_some(r)
    }

    /// pbrt-v3's `Pdf_Sr`: the density of radius `r` under [`Self::sample_sr`] for channel
    /// `ch`, per unit area of the plane.
    pub fn pdf_sr(&self, ch: usize, r: f32) -> f32 {
        match catmull_rom_weights(&self.table.rho_samples, self.rho[ch]) {
            Some(rho) => self.pdf_sr_with(ch, rho, r),
            None => 0.0,
        }
    }

    /// [`Self::pdf_sr`] with the channel's albedo weights already found.
    #[inline]
    fn pdf_sr_with(&self, ch: usize, rho: (isize, [f32; 4]), r: f32) -> f32 {
        let st = self.sigma_t[ch];
        match self.interpolate_with(rho, r * st) {
            Some((sr, rho_eff)) => {
                let p = sr * st * st / rho_eff;
                if p.is_finite() {
                    p.max(0.0)
                } else {
                    0.0
                }
            }
            None => 0.0,
        }
    }

    /// pbrt-v3's `Sample_Sp` up to its tracing: from `u1` a projection axis (the normal half
    /// the time, each tangent a quarter) and a channel, from `u2` a radius and an angle; the
    /// probe segment through the sphere of radius rMax (the channel's 0.999 quantile) that
    /// holds the exit points this sample can reach. `None`: nothing to sample.
    pub fn probe(&self, u1: f32, u2: Vec2) -> Option<Probe> {
        let f = &self.frame;
        let (vx, vy, vz, mut u1) = if u1 < 0.5 {
            (f.s, f.t, f.n, u1 * 2.0)
        } else if u1 < 0.75 {
            (f.t, f.n, f.s, (u1 - 0.5) * 4.0)
        } else {
            (f.n, f.s, f.t, (u1 - 0.75) * 4.0)
        };
        let ch = ((u1 * 3.0) as usize).min(2);
        u1 = u1 * 3.0 - ch as f32;
        let r = self.sample_sr(ch, u2.x)?;
        let phi = 2.0 * PI * u2.y;
        let r_max = match self.r_max {
            Some(bounds) => bounds[ch]?,
            None => self.sample_sr(ch, 0.999)?,
        };
        if r >= r_max {
            return None;
        }
        let l = 2.0 * (r_max * r_max - r * r).sqrt();
        let start = self.po + r * (vx * phi.cos() + vy * phi.sin()) - l * vz * 0.5;
        Some(Probe {
            start,
            end: start + l * vz,
            u_choice: u1,
        })
    }

    /// pbrt-v3's `Pdf_Sp`: the density, per unit area, with which [`Self::probe`] and a choice
    /// among one surface reach exit point `pi` of geometric normal `ni` (every axis and
    /// channel's strategy combined).
    pub fn pdf_sp(&self, pi: Vec3, ni: Vec3) -> f32 {
        let d = self.frame.to_local(self.po - pi);
        let n = self.frame.to_local(ni);
        let r_proj = [
            (d.y * d.y + d.z * d.z).sqrt(),
            (d.z * d.z + d.x * d.x).sqrt(),
            (d.x * d.x + d.y * d.y).sqrt(),
        ];
        let axis_prob = [0.25f32, 0.25, 0.5];
        let n_local = [n.x, n.y, n.z];
        let mut pdf = 0.0f32;
        // Channel-major: each channel's albedo weights found once for the three axes.
        for ch in 0..3 {
            let Some(rho) = catmull_rom_weights(&self.table.rho_samples, self.rho[ch]) else {
                continue;
            };
            for axis in 0..3 {
                pdf +=
                    self.pdf_sr_with(ch, rho, r_proj[axis]) * n_local[axis].abs() * axis_prob[axis]
                        / 3.0;
            }
        }
        pdf
    }
}
