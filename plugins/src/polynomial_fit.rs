//! The polynomial reconstruction's model of one cluster (docs/algorithm.md §5, the paper's
//! eq. 12-16): one additive Legendre polynomial over the cluster's dims,
//! `l(u) = a0 + Σ_d Σ_{k=1..deg_d} a_dk P_k(ũ_d)`, with `ũ_d` the coordinate mapped from the
//! cluster's extent to [-1, 1], fitted by weighted least squares over its cells (value: the
//! cell's mean radiance, weight: its sample count), and integrated in closed form over any box.
//!
//! A cell's row is the mean of each basis function over the cell's own samples, computed
//! exactly from the cell's first two moments of the sample offsets (degree <= 2). For linear
//! terms that is the basis at the samples' centroid, as docs/algorithm.md §5 first read it; for the
//! quadratic term it also counts the spread of the samples, so a noise-free quadratic field is
//! fitted exactly from any number of samples per cell (at the centroid alone it is off by the
//! samples' variance times the curvature).
//!
//! With features on, the model also has a linear term per first-hit feature (albedo, normal,
//! depth: `crate::first_hit`) that varies over the cluster, `+ Σ_j b_j (f_j - μ_j) / σ_j`,
//! the cell's row holding its mean features: a first-order feature regression per cluster,
//! so that a texture or an edge inside the cluster is explained by the albedo or the normal
//! instead of smoothed away. A feature term is used only where the cluster has at least twice
//! as many sampled cells as the model has terms.
//!
//! Stability: coordinates centred and scaled to the cluster; a ridge scaled to the normal
//! matrix's trace (never on the constant); a dim with fewer distinct cell positions than its
//! degree needs loses degree; a failed or ill-conditioned Cholesky falls back one degree at a
//! time down to the weighted mean; values clamped to the range of the cluster's cell means,
//! never negative, never NaN.

// The solver's loops index several small arrays at once, as the formulas do.
#![allow(clippy::needless_range_loop)]

use crate::cells::grid::MAX_DIMS;
use crate::first_hit::FEATURES;

/// Highest degree of the model.
pub const MAX_DEGREE: u32 = 2;

/// Coefficients of one fit: the constant, up to `MAX_DEGREE` per dim, and one per feature.
const MAX_TERMS: usize = 1 + MAX_DIMS * MAX_DEGREE as usize + FEATURES;

/// A feature's term in the model: `b (f - centre) / scale`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FeatureTerm {
    feature: usize,
    centre: f64,
    scale: f64,
}

/// A feature whose weighted standard deviation over the cluster is below this (relative to
/// its scale: 1 for albedo and normal, the mean for depth) has no term.
const FEATURE_SPREAD_FLOOR: f64 = 1e-3;

/// A pivot below this fraction of the largest diagonal entry means the system is singular
/// for the degree tried.
const PIVOT_FLOOR: f64 = 1e-12;

/// One cell as the fit sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitCell {
    /// The cell's lower corner per dim (pixels for x and y, [0, 1] for time and lens).
    pub lo: [f64; MAX_DIMS],
    /// The cell's upper corner.
    pub hi: [f64; MAX_DIMS],
    /// Mean offset of its samples inside the cell per dim, in [0, 1].
    pub m1: [f64; MAX_DIMS],
    /// Mean squared offset of its samples per dim.
    pub m2: [f64; MAX_DIMS],
    /// Mean radiance of its samples.
    pub mean: [f64; 3],
    /// Mean first-hit features of its samples (zeros when not kept).
    pub features: [f64; FEATURES],
    /// Its weight (sample count); 0 for a cell without samples, which only needs a value.
    pub weight: f64,
}

/// How to fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitSettings {
    /// Degree per dim (0: the cluster's weighted mean), at most `MAX_DEGREE`.
    pub degree: u32,
    /// Ridge, relative to the mean diagonal of the normal matrix.
    pub ridge: f64,
    /// Clamp values to the range of the cluster's cell means.
    pub clamp: bool,
    /// Regress on the cells' first-hit features too.
    pub features: bool,
}

/// One cluster's fitted model.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    dims: usize,
    centre: [f64; MAX_DIMS],
    half: [f64; MAX_DIMS],
    degree: [u32; MAX_DIMS],
    /// The features with a term: each one's index, centre and scale.
    feature_terms: Vec<FeatureTerm>,
    /// a0, then each dim's a_d1..a_d(deg_d), then each feature term's, per channel.
    coeffs: Vec<[f64; 3]>,
    lo: [f64; 3],
    hi: [f64; 3],
    clamp: bool,
    empty: bool,
}

/// Legendre polynomials P_0..P_(MAX_DEGREE + 1) at `x`.
#[inline]
fn legendre(x: f64) -> [f64; MAX_DEGREE as usize + 2] {
    let mut p = [0.0; MAX_DEGREE as usize + 2];
    p[0] = 1.0;
    p[1] = x;
    for k in 1..=MAX_DEGREE as usize {
        let kf = k as f64;
        p[k + 1] = ((2.0 * kf + 1.0) * x * p[k] - kf * p[k - 1]) / (kf + 1.0);
    }
    p
}

/// The mean of P_k over [a, b] for k = 1..=MAX_DEGREE (index k - 1), through the
/// antiderivative (P_(k+1) - P_(k-1)) / (2k + 1); the value at the midpoint when the interval
/// is (numerically) a point.
#[inline]
fn legendre_means(a: f64, b: f64) -> [f64; MAX_DEGREE as usize] {
    let mut out = [0.0; MAX_DEGREE as usize];
    if (b - a).abs() < 1e-9 {
        let p = legendre(0.5 * (a + b));
        out.copy_from_slice(&p[1..=MAX_DEGREE as usize]);
        return out;
    }
    let (pa, pb) = (legendre(a), legendre(b));
    for k in 1..=MAX_DEGREE as usize {
        let q = |p: &[f64; MAX_DEGREE as usize + 2]| (p[k + 1] - p[k - 1]) / (2 * k + 1) as f64;
        out[k - 1] = (q(&pb) - q(&pa)) / (b - a);
    }
    out
}

/// The features that vary over the usable cells, with their weighted mean and standard
/// deviation: each becomes a term `(f - mean) / sd`.
fn feature_terms(cells: &[FitCell], usable: &dyn Fn(&FitCell) -> bool) -> Vec<FeatureTerm> {
    let (mut w, mut s1, mut s2) = (0.0, [0.0f64; FEATURES], [0.0f64; FEATURES]);
    for c in cells.iter().filter(|c| usable(c)) {
        if c.features.iter().any(|v| !v.is_finite()) {
            return Vec::new();
        }
        w += c.weight;
        for f in 0..FEATURES {
            s1[f] += c.weight * c.features[f];
            s2[f] += c.weight * c.features[f] * c.features[f];
        }
    }
    if w <= 0.0 {
        return Vec::new();
    }
    (0..FEATURES)
        .filter_map(|f| {
            let mean = s1[f] / w;
            let sd = (s2[f] / w - mean * mean).max(0.0).sqrt();
            let scale = if f == crate::first_hit::DEPTH {
                mean.abs()
            } else {
                1.0
            };
            (sd > FEATURE_SPREAD_FLOOR * scale && sd.is_finite()).then_some(FeatureTerm {
                feature: f,
                centre: mean,
                scale: sd,
            })
        })
        .collect()
}

impl Fit {
    /// Fits the cluster made of `cells` over the first `dims` dims.
    pub fn new(cells: &[FitCell], dims: usize, settings: &FitSettings) -> Self {
        let dims = dims.min(MAX_DIMS);
        let mut fit = Self {
            dims,
            centre: [0.0; MAX_DIMS],
            half: [1.0; MAX_DIMS],
            degree: [0; MAX_DIMS],
            feature_terms: Vec::new(),
            coeffs: vec![[0.0; 3]],
            lo: [f64::INFINITY; 3],
            hi: [0.0; 3],
            clamp: settings.clamp,
            empty: false,
        };
        let usable = |c: &FitCell| {
            c.weight > 0.0 && c.weight.is_finite() && c.mean.iter().all(|v| v.is_finite())
        };
        // The range of the cell means, and the extent of every cell (also the empty ones,
        // which are evaluated too and must not be extrapolated to).
        let mut lo = [f64::INFINITY; MAX_DIMS];
        let mut hi = [f64::NEG_INFINITY; MAX_DIMS];
        let mut total = 0.0;
        let mut mean = [0.0; 3];
        for c in cells {
            for d in 0..dims {
                lo[d] = lo[d].min(c.lo[d]);
                hi[d] = hi[d].max(c.hi[d]);
            }
            if usable(c) {
                total += c.weight;
                for k in 0..3 {
                    let v = c.mean[k].max(0.0);
                    mean[k] += c.weight * v;
                    fit.lo[k] = fit.lo[k].min(v);
                    fit.hi[k] = fit.hi[k].max(v);
                }
            }
        }
        if total <= 0.0 {
            fit.lo = [0.0; 3];
            fit.empty = true;
            return fit;
        }
        fit.coeffs[0] = mean.map(|m| m / total);
        for d in 0..dims {
            if hi[d] > lo[d] {
                fit.centre[d] = 0.5 * (lo[d] + hi[d]);
                fit.half[d] = 0.5 * (hi[d] - lo[d]);
            }
        }
        // A dim's degree is at most its distinct cell positions (among sampled cells) - 1.
        let want = settings.degree.min(MAX_DEGREE);
        let mut degree = [0u32; MAX_DIMS];
        let mut starts: Vec<f64> = Vec::with_capacity(cells.len());
        for d in 0..dims {
            starts.clear();
            starts.extend(cells.iter().filter(|c| usable(c)).map(|c| c.lo[d]));
            starts.sort_unstable_by(f64::total_cmp);
            starts.dedup();
            degree[d] = want.min(starts.len().saturating_sub(1) as u32);
        }
        let features = if settings.features {
            feature_terms(cells, &usable)
        } else {
            Vec::new()
        };
        let sampled = cells.iter().filter(|c| usable(c)).count();
        // Fall back one degree at a time until the system is well posed, at each degree first
        // with the feature terms (when the cluster has cells enough for them), then without.
        for cap in (0..=want).rev() {
            fit.degree = degree.map(|g| g.min(cap));
            let poly_terms = fit.terms();
            let with = (!features.is_empty() && sampled >= 2 * (poly_terms + features.len()))
                .then_some(features.clone());
            for terms in with.into_iter().chain([Vec::new()]) {
                if terms.is_empty() && poly_terms == 1 {
                    continue; // the weighted mean, below
                }
                fit.feature_terms = terms;
                loop {
                    match fit.solve(cells, settings.ridge, &usable) {
                        Ok(coeffs) => {
                            fit.coeffs = coeffs;
                            return fit;
                        }
                        // A feature term that repeats another (grey albedo: three equal
                        // channels) or a coordinate: drop that term, keep the others.
                        Err(Some(j)) if j >= poly_terms && !fit.feature_terms.is_empty() => {
                            fit.feature_terms.remove(j - poly_terms);
                        }
                        Err(_) => break,
                    }
                }
            }
        }
        fit.degree = [0; MAX_DIMS];
        fit.feature_terms.clear();
        fit
    }

    /// Features with a term in the last fit (indices into the cell's features).
    pub fn feature_terms(&self) -> impl Iterator<Item = usize> + '_ {
        self.feature_terms.iter().map(|t| t.feature)
    }

    /// Terms of the model (the constant included).
    fn terms(&self) -> usize {
        1 + self.degree[..self.dims]
            .iter()
            .map(|&g| g as usize)
            .sum::<usize>()
            + self.feature_terms.len()
    }

    /// The row of cell `c`: the mean of each basis function over its samples.
    fn row(&self, c: &FitCell, row: &mut [f64; MAX_TERMS]) {
        row[0] = 1.0;
        let mut t = 1;
        for d in 0..self.dims {
            if self.degree[d] == 0 {
                continue;
            }
            // ũ = alpha + beta × offset; its first two moments from the offsets'.
            let alpha = (c.lo[d] - self.centre[d]) / self.half[d];
            let beta = (c.hi[d] - c.lo[d]) / self.half[d];
            let e1 = alpha + beta * c.m1[d];
            let e2 = alpha * alpha + 2.0 * alpha * beta * c.m1[d] + beta * beta * c.m2[d];
            row[t] = e1;
            if self.degree[d] >= 2 {
                row[t + 1] = 0.5 * (3.0 * e2 - 1.0);
            }
            t += self.degree[d] as usize;
        }
        for (k, term) in self.feature_terms.iter().enumerate() {
            row[t + k] = (c.features[term.feature] - term.centre) / term.scale;
        }
    }

    /// Weighted least squares with a ridge by Cholesky; the term whose pivot collapses when
    /// one does (None: the solution was not finite).
    fn solve(
        &self,
        cells: &[FitCell],
        ridge: f64,
        usable: &dyn Fn(&FitCell) -> bool,
    ) -> Result<Vec<[f64; 3]>, Option<usize>> {
        let m = self.terms();
        let mut a = [[0.0f64; MAX_TERMS]; MAX_TERMS];
        let mut b = [[0.0f64; 3]; MAX_TERMS];
        let mut row = [0.0; MAX_TERMS];
        for c in cells.iter().filter(|c| usable(c)) {
            self.row(c, &mut row);
            for i in 0..m {
                let wi = c.weight * row[i];
                for j in 0..=i {
                    a[i][j] += wi * row[j];
                }
                for k in 0..3 {
                    b[i][k] += wi * c.mean[k].max(0.0);
                }
            }
        }
        let trace: f64 = (0..m).map(|i| a[i][i]).sum();
        let lambda = ridge.max(0.0) * trace / m as f64;
        for (i, r) in a.iter_mut().enumerate().take(m).skip(1) {
            r[i] += lambda;
        }
        let largest = (0..m).map(|i| a[i][i]).fold(0.0, f64::max);
        // Cholesky, lower triangle in place.
        for j in 0..m {
            let mut d = a[j][j];
            for k in 0..j {
                d -= a[j][k] * a[j][k];
            }
            if d.is_nan() || d <= PIVOT_FLOOR * largest {
                return Err(Some(j));
            }
            let d = d.sqrt();
            a[j][j] = d;
            for i in j + 1..m {
                let mut s = a[i][j];
                for k in 0..j {
                    s -= a[i][k] * a[j][k];
                }
                a[i][j] = s / d;
            }
        }
        // Forward then back substitution, three right-hand sides.
        let mut y = [[0.0f64; 3]; MAX_TERMS];
        for i in 0..m {
            for ch in 0..3 {
                let mut s = b[i][ch];
                for k in 0..i {
                    s -= a[i][k] * y[k][ch];
                }
                y[i][ch] = s / a[i][i];
            }
        }
        let mut x = vec![[0.0f64; 3]; m];
        for i in (0..m).rev() {
            for ch in 0..3 {
                let mut s = y[i][ch];
                for k in i + 1..m {
                    s -= a[k][i] * x[k][ch];
                }
                x[i][ch] = s / a[i][i];
            }
        }
        if x.iter().flatten().all(|v| v.is_finite()) {
            Ok(x)
        } else {
            Err(None)
        }
    }

    /// Whether the cluster had no usable sample (its values are then 0 and mean nothing).
    pub fn is_empty(&self) -> bool {
        self.empty
    }

    /// The degree used, the largest over the dims (0: the weighted mean).
    pub fn degree(&self) -> u32 {
        self.degree.iter().copied().max().unwrap_or(0)
    }

    /// The coefficients: a0, then each dim's a_d1..a_d(deg_d), per channel.
    pub fn coefficients(&self) -> &[[f64; 3]] {
        &self.coeffs
    }

    /// The model's mean over the box `[lo, hi]` of a cell whose mean features are `features`
    /// (closed form; None: the cluster's mean features), clamped as set, never negative,
    /// never NaN.
    pub fn mean_over(
        &self,
        lo: &[f64; MAX_DIMS],
        hi: &[f64; MAX_DIMS],
        features: Option<&[f64; FEATURES]>,
    ) -> [f64; 3] {
        let mut v = self.coeffs[0];
        let mut t = 1;
        for d in 0..self.dims {
            let g = self.degree[d] as usize;
            if g == 0 {
                continue;
            }
            let a = (lo[d] - self.centre[d]) / self.half[d];
            let b = (hi[d] - self.centre[d]) / self.half[d];
            let means = legendre_means(a, b);
            for (k, pm) in means.iter().enumerate().take(g) {
                for (ch, out) in v.iter_mut().enumerate() {
                    *out += self.coeffs[t + k][ch] * pm;
                }
            }
            t += g;
        }
        for (k, term) in self.feature_terms.iter().enumerate() {
            // No features: the cluster's mean features, where every term is 0.
            let x = features.map_or(0.0, |fs| (fs[term.feature] - term.centre) / term.scale);
            if x.is_finite() {
                for (ch, out) in v.iter_mut().enumerate() {
                    *out += self.coeffs[t + k][ch] * x;
                }
            }
        }
        std::array::from_fn(|ch| self.limit(ch, v[ch]))
    }

    /// `x` clamped to the cell means' range when set, else to >= 0; the weighted mean for NaN.
    fn limit(&self, ch: usize, x: f64) -> f64 {
        let x = if x.is_finite() { x } else { self.coeffs[0][ch] };
        let x = if self.clamp {
            x.clamp(self.lo[ch], self.hi[ch].max(self.lo[ch]))
        } else {
            x
        };
        if x.is_finite() {
            x.max(0.0)
        } else {
            0.0
        }
    }
}
