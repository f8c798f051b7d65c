//! pbrt-v3's `fourier` material: a measured or simulated isotropic BSDF tabulated in a spline
//! (over the cosines of the two zenith angles) times Fourier (over the azimuth difference)
//! basis, read from a `.bsdf` file (the `SCATFUN` format of Jakob et al. 2014's layerlab), and
//! pbrt-v3's `FourierBSDF` evaluating, sampling and giving the density of it.

use crate::geometry::{Spectrum, Vec3};
use crate::interpolation::{catmull_rom_weights, fourier, sample_catmull_rom_2d, sample_fourier};
use std::collections::HashMap;
use std::f32::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// A `.bsdf` file's table, as pbrt-v3's `FourierBSDFTable` holds it.
#[derive(Debug, PartialEq)]
pub struct FourierTable {
    /// Relative index of refraction (bottom over top).
    pub eta: f32,
    /// The longest series' coefficient count.
    pub m_max: usize,
    /// 1 (luminance) or 3 (luminance, red, blue).
    pub channels: usize,
    /// The zenith cosines of the spline nodes, ascending.
    pub mu: Vec<f32>,
    /// Per (mu_o, mu_i) node pair: its series' length.
    m: Vec<u32>,
    /// Per node pair: where its coefficients start in `a`.
    a_offset: Vec<u32>,
    /// Every series' coefficients, channel after channel.
    a: Vec<f32>,
    /// Per node pair: the luminance series' constant term.
    a0: Vec<f32>,
    /// Per mu_o node: the running integral of `a0` over mu_i.
    cdf: Vec<f32>,
    /// 1 / k for k < m_max.
    recip: Vec<f32>,
}

/// Tables read so far, by path: a scene's materials share one (pbrt-v3 caches them alike).
/// They live as long as the process, as pbrt-v3's do.
static TABLES: Mutex<Option<HashMap<PathBuf, &'static FourierTable>>> = Mutex::new(None);

impl FourierTable {
    /// The table in `path`, read once per process.
    pub fn load(path: &Path) -> Result<&'static FourierTable, String> {
        let mut tables = TABLES.lock().unwrap_or_else(|e| e.into_inner());
        let tables = tables.get_or_insert_with(HashMap::new);
        if let Some(t) = tables.get(path) {
            return Ok(t);
        }
        let bytes = acr_parser::source::read_file(path, acr_parser::source::FileKind::BsdfTable)
            .map_err(|e| {
                format!(
                    "cannot read {}: {}",
                    path.display(),
                    acr_parser::io_message(&e)
                )
            })?;
        let table: &'static FourierTable = Box::leak(Box::new(
            Self::parse(&bytes).map_err(|e| format!("{}: {e}", path.display()))?,
        ));
        tables.insert(path.to_path_buf(), table);
        Ok(table)
    }

    /// Parses a `.bsdf` file (little-endian): the 64-byte header, the nodes, the CDF, the
    /// offsets and lengths, the coefficients. As pbrt-v3, only untextured (one basis) BSDFs of
    /// 1 or 3 channels are read; every count and offset is checked against the file.
    pub fn parse(bytes: &[u8]) -> Result<FourierTable, String> {
        let mut words = Words { bytes, at: 0 };
        if bytes.get(..8) != Some(b"SCATFUN\x01") {
            return Err("not a pbrt-v3 .bsdf file (no SCATFUN version 1 header)".to_owned());
        }
        words.at = 8;
        let flags = words.int()?;
        let n_mu = words.int()?;
        let n_coeffs = words.int()?;
        let m_max = words.int()?;
        let channels = words.int()?;
        let bases = words.int()?;
        words.at += 12;
        let eta = words.float()?;
        words.at += 16;
        if flags != 1 || !(channels == 1 || channels == 3) || bases != 1 {
            return Err(format!(
                "a .bsdf file pbrt-v3 cannot read either: flags {flags} (1 wanted), {channels} \
                 channels (1 or 3), {bases} bases (1: no textured parameters)"
            ));
        }
        let count = |v: i32, what: &str| {
            usize::try_from(v)
                .ok()
                .filter(|&n| n <= bytes.len())
                .ok_or_else(|| format!("bad {what} {v}"))
        };
        let (n_mu, n_coeffs, m_max, channels) = (
            count(n_mu, "node count")?,
            count(n_coeffs, "coefficient count")?,
            count(m_max, "series length")?,
            channels as usize,
        );
        if n_mu < 2 || m_max == 0 {
            return Err(format!("{n_mu} nodes and series of {m_max}: too few"));
        }
        let pairs = n_mu * n_mu;
        let mu = words.floats(n_mu)?;
        let ascending = |w: &[f32]| w[0].partial_cmp(&w[1]) == Some(std::cmp::Ordering::Less);
        if !mu.windows(2).all(ascending) || mu[0] < -1.0 || mu[n_mu - 1] > 1.0 {
            return Err("its zenith cosines are not ascending within [-1, 1]".to_owned());
        }
        let cdf = words.floats(pairs)?;
        let offset_and_length = words.ints(2 * pairs)?;
        let a = words.floats(n_coeffs)?;
        let (mut m, mut a_offset, mut a0) = (Vec::new(), Vec::new(), Vec::new());
        for pair in offset_and_length.chunks(2) {
            let (offset, length) = (pair[0], pair[1]);
            let fits = offset >= 0
                && length >= 0
                && length as usize <= m_max
                && offset as usize + length as usize * channels <= n_coeffs;
            if !fits {
                return Err(format!(
                    "a series at {offset} of length {length} does not fit {n_coeffs} \
                     coefficients"
                ));
            }
            m.push(length as u32);
            a_offset.push(offset as u32);
            a0.push(if length > 0 { a[offset as usize] } else { 0.0 });
        }
        let recip = (0..m_max).map(|i| 1.0 / i as f32).collect();
        Ok(FourierTable {
            eta,
            m_max,
            channels,
            mu,
            m,
            a_offset,
            a,
            a0,
            cdf,
            recip,
        })
    }

    /// The coefficients of node pair (i, o): `m` per channel, channel after channel.
    fn ak(&self, i: usize, o: usize) -> (&[f32], usize) {
        let k = o * self.mu.len() + i;
        let (start, m) = (self.a_offset[k] as usize, self.m[k] as usize);
        (&self.a[start..start + m * self.channels], m)
    }

    /// The series at (mu_i, mu_o), interpolated over the 4 x 4 nearest node pairs: `m_max`
    /// coefficients per channel (the first `channels_used` channels), and the longest length.
    fn series(&self, mu_i: f32, mu_o: f32, channels_used: usize) -> Option<(Vec<f32>, usize)> {
        let (offset_i, wi) = catmull_rom_weights(&self.mu, mu_i)?;
        let (offset_o, wo) = catmull_rom_weights(&self.mu, mu_o)?;
        let mut ak = vec![0.0f32; self.m_max * channels_used];
        let mut longest = 0;
        for (b, &w_o) in wo.iter().enumerate() {
            for (a, &w_i) in wi.iter().enumerate() {
                let weight = w_i * w_o;
                if weight == 0.0 {
                    continue;
                }
                let i = (offset_i + a as isize) as usize;
                let o = (offset_o + b as isize) as usize;
                let (ap, m) = self.ak(i, o);
                longest = longest.max(m);
                for c in 0..channels_used {
                    for k in 0..m {
                        ak[c * self.m_max + k] += weight * ap[c * m + k];
                    }
                }
            }
        }
        Some((ak, longest))
    }

    /// The grey albedo for first-hit features: the table's integral at normal incidence
    /// (what the density normalises by), kept in [0, 1].
    pub fn albedo(&self) -> Spectrum {
        let n = self.mu.len();
        let rho = self.cdf[(n - 1) * n + n - 1] * 2.0 * PI;
        Spectrum::splat(rho.clamp(0.0, 1.0))
    }
}

/// Little-endian 32-bit words of a file, each read checked.
struct Words<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Words<'_> {
    fn word(&mut self) -> Result<[u8; 4], String> {
        let w = self
            .bytes
            .get(self.at..self.at + 4)
            .ok_or("the file ends early")?;
        self.at += 4;
        Ok([w[0], w[1], w[2], w[3]])
    }
    fn int(&mut self) -> Result<i32, String> {
        self.word().map(i32::from_le_bytes)
    }
    fn float(&mut self) -> Result<f32, String> {
        self.word().map(f32::from_le_bytes)
    }
    fn ints(&mut self, n: usize) -> Result<Vec<i32>, String> {
        (0..n).map(|_| self.int()).collect()
    }
    fn floats(&mut self, n: usize) -> Result<Vec<f32>, String> {
        (0..n).map(|_| self.float()).collect()
    }
}

/// pbrt-v3's `FourierBSDF` for radiance transport, over a table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FourierBsdf {
    /// The table.
    pub table: &'static FourierTable,
}

/// pbrt-v3's `CosDPhi`: the cosine of the azimuth between `wa` and `wb`.
fn cos_d_phi(wa: Vec3, wb: Vec3) -> f32 {
    let waxy = wa.x * wa.x + wa.y * wa.y;
    let wbxy = wb.x * wb.x + wb.y * wb.y;
    if waxy == 0.0 || wbxy == 0.0 {
        return 1.0;
    }
    ((wa.x * wb.x + wa.y * wb.y) / (waxy * wbxy).sqrt()).clamp(-1.0, 1.0)
}

impl FourierBsdf {
    /// The value for local `wo` and `wi`.
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Spectrum {
        let (mu_i, mu_o) = (-wi.z, wo.z);
        let cos_phi = f64::from(cos_d_phi(-wi, wo));
        let t = self.table;
        let Some((ak, m)) = t.series(mu_i, mu_o, t.channels) else {
            return Spectrum::ZERO;
        };
        let y = fourier(&ak[..m], cos_phi).max(0.0);
        self.colour(&ak, m, y, cos_phi, mu_i, mu_o)
    }

    /// The series' colour at `cos_phi` given its luminance `y`, scaled by 1 / |mu_i| (and by
    /// the relative index squared through the boundary, for radiance), as pbrt-v3.
    fn colour(&self, ak: &[f32], m: usize, y: f32, cos_phi: f64, mu_i: f32, mu_o: f32) -> Spectrum {
        let t = self.table;
        let mut scale = if mu_i != 0.0 { 1.0 / mu_i.abs() } else { 0.0 };
        if mu_i * mu_o > 0.0 {
            let eta = if mu_i > 0.0 { 1.0 / t.eta } else { t.eta };
            scale *= eta * eta;
        }
        if t.channels == 1 {
            return Spectrum::splat(y * scale);
        }
        let r = fourier(&ak[t.m_max..t.m_max + m], cos_phi);
        let b = fourier(&ak[2 * t.m_max..2 * t.m_max + m], cos_phi);
        let g = 1.39829 * y - 0.100913 * b - 0.297375 * r;
        Spectrum::new(r * scale, g * scale, b * scale).max(Spectrum::ZERO)
    }

    /// Samples `wi` for `wo` by `u`: mu_i from the spline table, the azimuth from the
    /// luminance series. Returns wi, the value and the density.
    pub fn sample_f(&self, wo: Vec3, u: [f32; 2]) -> Option<(Vec3, Spectrum, f32)> {
        let t = self.table;
        let mu_o = wo.z;
        let (mu_i, _, pdf_mu) = sample_catmull_rom_2d(&t.mu, &t.mu, &t.a0, &t.cdf, mu_o, u[1])?;
        let (ak, m) = t.series(mu_i, mu_o, t.channels)?;
        if m == 0 {
            return None;
        }
        let (y, pdf_phi, phi) = sample_fourier(&ak[..m], &t.recip, u[0]);
        let pdf = (pdf_phi * pdf_mu).max(0.0);
        let sin2_theta_i = (1.0 - mu_i * mu_i).max(0.0);
        let sin2_theta_o = (1.0 - wo.z * wo.z).max(0.0);
        // The azimuth is measured from wo's; along the normal wo has none, and pbrt-v3's
        // sqrt(sin2_theta_i / 0), taken as 0 (or NaN when both are 0), put wi on the normal
        // whatever mu_i was sampled: measured from the x axis there instead.
        let (wo_x, wo_y, norm) = if sin2_theta_o > 0.0 {
            let norm = (sin2_theta_i / sin2_theta_o).sqrt();
            (wo.x, wo.y, if norm.is_infinite() { 0.0 } else { norm })
        } else {
            (1.0, 0.0, sin2_theta_i.sqrt())
        };
        let (sin_phi, cos_phi) = phi.sin_cos();
        let wi = -Vec3::new(
            norm * (cos_phi * wo_x - sin_phi * wo_y),
            norm * (sin_phi * wo_x + cos_phi * wo_y),
            mu_i,
        );
        // pbrt-v3 normalises again: rounding would otherwise grow over bounces.
        let wi = wi.normalize();
        let f = self.colour(&ak, m, y, f64::from(cos_phi), mu_i, mu_o);
        Some((wi, f, pdf))
    }

    /// The density of [`FourierBsdf::sample_f`] picking `wi` for `wo`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (mu_i, mu_o) = (-wi.z, wo.z);
        let cos_phi = f64::from(cos_d_phi(-wi, wo));
        let t = self.table;
        let Some((ak, m)) = t.series(mu_i, mu_o, 1) else {
            return 0.0;
        };
        let Some((offset_o, wo_weights)) = catmull_rom_weights(&t.mu, mu_o) else {
            return 0.0;
        };
        let n = t.mu.len();
        let mut rho = 0.0f32;
        for (o, &w) in wo_weights.iter().enumerate() {
            if w != 0.0 {
                let row = (offset_o + o as isize) as usize;
                rho += w * t.cdf[row * n + n - 1] * (2.0 * PI);
            }
        }
        let y = fourier(&ak[..m], cos_phi);
        if rho > 0.0 && y > 0.0 {
            y / rho
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests;
