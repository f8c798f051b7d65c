//! Colour conversions for pbrt-v3's RGB mode: sRGB transfer curves, sampled spectra and
//! blackbody emitters to linear sRGB (as `RGBSpectrum::FromSampled` does), and luminance.
//!
//! pbrt-v3 integrates sampled spectra against the CIE 1931 colour-matching functions tabulated at
//! 1 nm from 360 to 830 nm. acr evaluates the same sum at the same wavelengths, but with the
//! multi-lobe analytic fit of Wyman, Sloan and Shirley ("Simple Analytic Approximations to the
//! CIE XYZ Color Matching Functions", JCGT 2(2), 2013) instead of the 471-row table. The fit is
//! within a few percent of the table; normalising by the fit's own sum of ȳ keeps a flat
//! spectrum's Y exactly where pbrt-v3 puts it.

use crate::geometry::Spectrum;
use acr_parser::{Error, Param, ParamType, Result, Values};
use std::path::Path;
use std::sync::OnceLock;

/// First wavelength (nm) of pbrt-v3's CIE table.
pub const CIE_LAMBDA_START: f64 = 360.0;
/// Last wavelength (nm) of pbrt-v3's CIE table.
pub const CIE_LAMBDA_END: f64 = 830.0;
/// Number of 1 nm samples in pbrt-v3's CIE table (360..=830).
pub const CIE_SAMPLES: usize = 471;

/// sRGB-encoded value to linear (pbrt-v3's `InverseGammaCorrect`).
#[inline]
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v * (1.0 / 12.92)
    } else {
        ((v + 0.055) * (1.0 / 1.055)).powf(2.4)
    }
}

/// Linear value to sRGB encoding (pbrt-v3's `GammaCorrect`).
#[inline]
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// [`srgb_to_linear`] per channel.
#[inline]
pub fn srgb_to_linear_rgb(c: Spectrum) -> Spectrum {
    Spectrum::new(
        srgb_to_linear(c.x),
        srgb_to_linear(c.y),
        srgb_to_linear(c.z),
    )
}

/// [`linear_to_srgb`] per channel.
#[inline]
pub fn linear_to_srgb_rgb(c: Spectrum) -> Spectrum {
    Spectrum::new(
        linear_to_srgb(c.x),
        linear_to_srgb(c.y),
        linear_to_srgb(c.z),
    )
}

/// Luminance of linear RGB (pbrt-v3's `RGBSpectrum::y()`, Rec. 709 weights).
#[inline]
pub fn luminance(c: Spectrum) -> f32 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}

/// CIE XYZ to linear sRGB (pbrt-v3's `XYZToRGB`).
#[inline]
pub fn xyz_to_linear_srgb(xyz: [f64; 3]) -> Spectrum {
    let [x, y, z] = xyz;
    Spectrum::new(
        (3.240479 * x - 1.537150 * y - 0.498535 * z) as f32,
        (-0.969256 * x + 1.875991 * y + 0.041556 * z) as f32,
        (0.055648 * x - 0.204043 * y + 1.057311 * z) as f32,
    )
}

/// The CIE 1931 2° colour-matching functions (x̄, ȳ, z̄) at `lambda` nm: the multi-lobe
/// piecewise-Gaussian fit of Wyman, Sloan and Shirley (JCGT 2013, listing 1).
pub fn cie_xyz_fit(lambda: f64) -> [f64; 3] {
    // A Gaussian lobe with different inverse widths left and right of its mean.
    let g = |mu: f64, inv_left: f64, inv_right: f64| {
        let t = (lambda - mu) * if lambda < mu { inv_left } else { inv_right };
        (-0.5 * t * t).exp()
    };
    let x = 0.362 * g(442.0, 0.0624, 0.0374) + 1.056 * g(599.8, 0.0264, 0.0323)
        - 0.065 * g(501.1, 0.0490, 0.0382);
    let y = 0.821 * g(568.8, 0.0213, 0.0247) + 0.286 * g(530.9, 0.0613, 0.0322);
    let z = 1.217 * g(437.0, 0.0845, 0.0278) + 0.681 * g(459.0, 0.0385, 0.0725);
    [x, y, z]
}

/// The colour-matching functions at pbrt-v3's 471 wavelengths, and the sum of ȳ over them.
struct CieTable {
    xyz: Vec<[f64; 3]>,
    y_sum: f64,
}

fn cie_table() -> &'static CieTable {
    static TABLE: OnceLock<CieTable> = OnceLock::new();
    TABLE.get_or_init(|| {
        let xyz: Vec<[f64; 3]> = (0..CIE_SAMPLES)
            .map(|i| cie_xyz_fit(CIE_LAMBDA_START + i as f64))
            .collect();
        let y_sum = xyz.iter().map(|c| c[1]).sum();
        CieTable { xyz, y_sum }
    })
}

/// Value of the piecewise-linear spectrum through (`lambda`, `values`) (sorted by wavelength) at
/// `l`, held constant beyond its ends (pbrt-v3's `InterpolateSpectrumSamples`).
fn interpolate_samples(lambda: &[f64], values: &[f64], l: f64) -> f64 {
    let n = lambda.len();
    if l <= lambda[0] {
        return values[0];
    }
    if l >= lambda[n - 1] {
        return values[n - 1];
    }
    // The last i with lambda[i] <= l.
    let i = lambda.partition_point(|&x| x <= l).clamp(1, n - 1) - 1;
    let span = lambda[i + 1] - lambda[i];
    let t = if span > 0.0 {
        (l - lambda[i]) / span
    } else {
        0.0
    };
    values[i] + t * (values[i + 1] - values[i])
}

/// CIE XYZ of a piecewise-linear spectrum given by samples, normalised as pbrt-v3 does (a flat
/// spectrum of 1 has Y = 470/471). Empty or mismatched input gives black.
pub fn sampled_to_xyz(lambda: &[f64], values: &[f64]) -> [f64; 3] {
    let n = lambda.len().min(values.len());
    if n == 0 {
        return [0.0; 3];
    }
    let mut pairs: Vec<(f64, f64)> = lambda[..n]
        .iter()
        .copied()
        .zip(values[..n].iter().copied())
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (l, v): (Vec<f64>, Vec<f64>) = pairs.into_iter().unzip();
    let table = cie_table();
    let mut xyz = [0.0f64; 3];
    for (i, cmf) in table.xyz.iter().enumerate() {
        let val = interpolate_samples(&l, &v, CIE_LAMBDA_START + i as f64);
        for c in 0..3 {
            xyz[c] += val * cmf[c];
        }
    }
    let scale = (CIE_LAMBDA_END - CIE_LAMBDA_START) / (table.y_sum * CIE_SAMPLES as f64);
    xyz.map(|c| c * scale)
}

/// Linear sRGB of a piecewise-linear spectrum given by samples (pbrt-v3's
/// `RGBSpectrum::FromSampled`). Note that, as in pbrt-v3, a flat spectrum of 1 (CIE illuminant
/// E) is not (1, 1, 1) but about (1.205, 0.948, 0.909): sRGB's white is D65.
pub fn sampled_to_rgb(lambda: &[f64], values: &[f64]) -> Spectrum {
    xyz_to_linear_srgb(sampled_to_xyz(lambda, values))
}

/// Planck's law: emitted radiance at `lambda_nm` nm of a blackbody at `t` kelvin (pbrt-v3's
/// `Blackbody`, in W/(m² sr m)).
pub fn blackbody(lambda_nm: f64, t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    const C: f64 = 299_792_458.0;
    const H: f64 = 6.626_069_57e-34;
    const KB: f64 = 1.380_648_8e-23;
    let l = lambda_nm * 1e-9;
    let l5 = (l * l) * (l * l) * l;
    (2.0 * H * C * C) / (l5 * (((H * C) / (l * KB * t)).exp() - 1.0))
}

/// Linear sRGB of a blackbody at `temperature_k` kelvin whose spectrum is normalised to a peak
/// of 1 (pbrt-v3's `BlackbodyNormalized`), times `scale`: what pbrt-v3 makes of a
/// `"blackbody" [T scale]` parameter. A non-positive temperature gives black.
pub fn blackbody_rgb(temperature_k: f64, scale: f64) -> Spectrum {
    if temperature_k.is_nan() || temperature_k <= 0.0 {
        return Spectrum::ZERO;
    }
    // Wien's displacement law gives the peak wavelength.
    let lambda_max = 2.897_772_1e-3 / temperature_k * 1e9;
    let max_l = blackbody(lambda_max, temperature_k);
    let lambda: Vec<f64> = (0..CIE_SAMPLES)
        .map(|i| CIE_LAMBDA_START + i as f64)
        .collect();
    let values: Vec<f64> = lambda
        .iter()
        .map(|&l| blackbody(l, temperature_k) / max_l)
        .collect();
    sampled_to_rgb(&lambda, &values) * scale as f32
}

/// Reads a pbrt-v3 `.spd` file: whitespace-separated wavelength/value pairs, `#` comments.
fn read_spd_file(path: &Path) -> std::result::Result<(Vec<f64>, Vec<f64>), String> {
    let bytes = acr_parser::source::read_file(path, acr_parser::source::FileKind::Spectrum)
        .map_err(|e| e.to_string())?;
    let text = String::from_utf8(bytes).map_err(|_| "not a text file".to_owned())?;
    let mut numbers = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("");
        for word in line.split(|c: char| c.is_whitespace() || c == ',') {
            if word.is_empty() {
                continue;
            }
            numbers.push(
                word.parse::<f64>()
                    .map_err(|_| format!("\"{word}\" is not a number"))?,
            );
        }
    }
    pairs_of(&numbers)
}

fn pairs_of(numbers: &[f64]) -> std::result::Result<(Vec<f64>, Vec<f64>), String> {
    if numbers.is_empty() || numbers.len() % 2 != 0 {
        return Err(format!(
            "a sampled spectrum needs wavelength/value pairs, found {} number(s)",
            numbers.len()
        ));
    }
    Ok(numbers.chunks_exact(2).map(|p| (p[0], p[1])).unzip())
}

/// Linear RGB of an `rgb`, `spectrum` or `blackbody` parameter, as pbrt-v3 reads it in RGB
/// mode: `rgb` as is; `spectrum` as wavelength/value pairs (or the name of an `.spd` file
/// relative to the scene file that names it) through [`sampled_to_rgb`]; `blackbody` as
/// `[T scale]` through [`blackbody_rgb`] (a single value `[T]` takes scale 1). Only the first
/// value of an array is used, as pbrt-v3's single-valued lookups do.
pub fn spectrum_param_to_rgb(param: &Param) -> Result<Spectrum> {
    let err = |msg: String| Error::at(&param.loc, msg);
    match (param.ty, &param.values) {
        (ParamType::Rgb, Values::Floats(v)) => {
            if v.len() < 3 || v.len() % 3 != 0 {
                return Err(err(format!(
                    "parameter \"{}\" needs r g b values, found {} number(s)",
                    param.name,
                    v.len()
                )));
            }
            Ok(Spectrum::new(v[0] as f32, v[1] as f32, v[2] as f32))
        }
        (ParamType::Spectrum, Values::Floats(v)) => {
            let (l, s) =
                pairs_of(v).map_err(|m| err(format!("parameter \"{}\": {m}", param.name)))?;
            Ok(sampled_to_rgb(&l, &s))
        }
        (ParamType::Spectrum, Values::Strings(names)) => {
            let Some(name) = names.first() else {
                return Err(err(format!("parameter \"{}\" has no value", param.name)));
            };
            let path = param.loc.file.dir().join(name);
            let (l, s) = read_spd_file(&path)
                .map_err(|m| err(format!("cannot read spectrum \"{}\": {m}", path.display())))?;
            Ok(sampled_to_rgb(&l, &s))
        }
        (ParamType::Blackbody, Values::Floats(v)) => match v.as_slice() {
            [] => Err(err(format!("parameter \"{}\" has no value", param.name))),
            [t] => Ok(blackbody_rgb(*t, 1.0)),
            [t, scale, ..] => Ok(blackbody_rgb(*t, *scale)),
        },
        _ => Err(err(format!(
            "parameter \"{}\" is declared {}, but rgb, spectrum or blackbody is expected here",
            param.name,
            param.ty.name()
        ))),
    }
}

/// Whether a parameter of this type holds a colour that [`spectrum_param_to_rgb`] reads.
pub fn is_spectrum_type(ty: ParamType) -> bool {
    matches!(
        ty,
        ParamType::Rgb | ParamType::Spectrum | ParamType::Blackbody
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use acr_parser::{Loc, SourceFile};

    fn param(ty: ParamType, values: Values) -> Param {
        let file = SourceFile::new("test.pbrt", "");
        Param::new(ty, "Kd", values, Loc::new(&file, 0))
    }

    #[test]
    fn srgb_curves_invert_each_other() {
        for i in 0..=255 {
            let v = i as f32 / 255.0;
            let back = linear_to_srgb(srgb_to_linear(v));
            assert!((back - v).abs() < 1e-5, "{v} {back}");
        }
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn luminance_weights_sum_to_one() {
        assert!((luminance(Spectrum::ONE) - 1.0).abs() < 1e-5);
        assert!(
            (crate::spectrum_luminance(Spectrum::new(0.2, 0.5, 0.9))
                - luminance(Spectrum::new(0.2, 0.5, 0.9)))
            .abs()
                < 1e-7
        );
    }

    #[test]
    fn flat_spectrum_is_equal_energy_white() {
        // A flat spectrum of 1 is CIE illuminant E: X = Y = Z = 1 (pbrt-v3: Y = 470/471).
        let xyz = sampled_to_xyz(&[400.0, 700.0], &[1.0, 1.0]);
        for c in xyz {
            assert!((c - 1.0).abs() < 0.02, "{xyz:?}");
        }
        assert!((xyz[1] - 470.0 / 471.0).abs() < 1e-9);
        // ... which in linear sRGB (white = D65) is pinkish, as in pbrt-v3.
        let rgb = sampled_to_rgb(&[400.0, 700.0], &[1.0, 1.0]);
        let e_white = xyz_to_linear_srgb([1.0; 3]) * (470.0 / 471.0);
        assert!(
            (rgb - e_white).abs().max_element() < 0.03,
            "{rgb} {e_white}"
        );
        assert!((luminance(rgb) - 1.0).abs() < 0.02, "{rgb}");
        // Unsorted samples are sorted first; values are held beyond the ends.
        let a = sampled_to_rgb(&[700.0, 400.0], &[0.2, 0.8]);
        let b = sampled_to_rgb(&[400.0, 700.0], &[0.8, 0.2]);
        assert!((a - b).abs().max_element() < 1e-6);
    }

    #[test]
    fn copper_matches_pbrt_v3_tables() {
        // pbrt-v3's metal.cpp copper samples; converted with the CIE table they give eta
        // (0.200438, 0.924033, 1.10221) and k (3.91295, 2.45285, 2.14219).
        let lambda = [
            298.7570554,
            302.4004341,
            306.1337728,
            309.960445,
            313.8839949,
            317.9081487,
            322.036826,
            326.2741526,
            330.6244747,
            335.092373,
            339.6826795,
            344.4004944,
            349.2512056,
            354.2405086,
            359.374429,
            364.6593471,
            370.1020239,
            375.7096303,
            381.4897785,
            387.4505563,
            393.6005651,
            399.9489613,
            406.5055016,
            413.2805933,
            420.2853492,
            427.5316483,
            435.0322035,
            442.8006357,
            450.8515564,
            459.2006593,
            467.8648226,
            476.8622231,
            486.2124627,
            495.936712,
            506.0578694,
            516.6007417,
            527.5922468,
            539.0616435,
            551.0407911,
            563.5644455,
            576.6705953,
            590.4008476,
            604.8008683,
            619.92089,
            635.8162974,
            652.5483053,
            670.1847459,
            688.8009889,
            708.4810171,
            729.3186941,
            751.4192606,
            774.9011125,
            799.8979226,
            826.5611867,
            855.0632966,
            885.6012714,
        ];
        let n = [
            1.400313, 1.38, 1.358438, 1.34, 1.329063, 1.325, 1.3325, 1.34, 1.334375, 1.325,
            1.317812, 1.31, 1.300313, 1.29, 1.281563, 1.27, 1.249062, 1.225, 1.2, 1.18, 1.174375,
            1.175, 1.1775, 1.18, 1.178125, 1.175, 1.172812, 1.17, 1.165312, 1.16, 1.155312, 1.15,
            1.142812, 1.135, 1.131562, 1.12, 1.092437, 1.04, 0.950375, 0.826, 0.645875, 0.468,
            0.35125, 0.272, 0.230813, 0.214, 0.20925, 0.213, 0.21625, 0.223, 0.2365, 0.25,
            0.254188, 0.26, 0.28, 0.3,
        ];
        let k = [
            1.662125, 1.687, 1.703313, 1.72, 1.744563, 1.77, 1.791625, 1.81, 1.822125, 1.834,
            1.85175, 1.872, 1.89425, 1.916, 1.931688, 1.95, 1.972438, 2.015, 2.121562, 2.21,
            2.177188, 2.13, 2.160063, 2.21, 2.249938, 2.289, 2.326, 2.362, 2.397625, 2.433,
            2.469187, 2.504, 2.535875, 2.564, 2.589625, 2.605, 2.595562, 2.583, 2.5765, 2.599,
            2.678062, 2.809, 3.01075, 3.24, 3.458187, 3.67, 3.863125, 4.05, 4.239563, 4.43,
            4.619563, 4.817, 5.034125, 5.26, 5.485625, 5.717,
        ];
        let eta = sampled_to_rgb(&lambda, &n);
        let kk = sampled_to_rgb(&lambda, &k);
        let want_eta = Spectrum::new(0.200438, 0.924033, 1.10221);
        let want_k = Spectrum::new(3.91295, 2.45285, 2.14219);
        assert!((eta - want_eta).abs().max_element() < 0.03, "{eta}");
        assert!((kk - want_k).abs().max_element() < 0.05, "{kk}");
    }

    #[test]
    fn blackbody_6500k_is_near_white() {
        let c = blackbody_rgb(6500.0, 1.0);
        let n = c / c.max_element();
        assert!(n.min_element() > 0.85, "{c}");
        // Warmer is redder, hotter is bluer.
        let warm = blackbody_rgb(2700.0, 1.0);
        assert!(warm.x > warm.y && warm.y > warm.z, "{warm}");
        let cold = blackbody_rgb(12000.0, 1.0);
        assert!(cold.z > cold.x, "{cold}");
        // Scale multiplies; zero temperature is black.
        assert!((blackbody_rgb(6500.0, 3.0) - 3.0 * c).abs().max_element() < 1e-5);
        assert_eq!(blackbody_rgb(0.0, 1.0), Spectrum::ZERO);
    }

    #[test]
    fn params_convert_by_type() {
        let rgb = param(ParamType::Rgb, Values::Floats(vec![0.1, 0.2, 0.3]));
        assert_eq!(
            spectrum_param_to_rgb(&rgb).unwrap(),
            Spectrum::new(0.1, 0.2, 0.3)
        );
        let bb = param(ParamType::Blackbody, Values::Floats(vec![6500.0, 2.0]));
        assert!(
            (spectrum_param_to_rgb(&bb).unwrap() - blackbody_rgb(6500.0, 2.0))
                .abs()
                .max_element()
                < 1e-6
        );
        let flat = param(
            ParamType::Spectrum,
            Values::Floats(vec![300.0, 0.5, 800.0, 0.5]),
        );
        let s = spectrum_param_to_rgb(&flat).unwrap();
        assert!((luminance(s) - 0.5).abs() < 0.01, "{s}");
        let odd = param(ParamType::Spectrum, Values::Floats(vec![300.0, 0.5, 800.0]));
        assert!(spectrum_param_to_rgb(&odd).is_err());
        let wrong = param(ParamType::Float, Values::Floats(vec![0.5]));
        assert!(spectrum_param_to_rgb(&wrong).is_err());
    }

    #[test]
    fn spd_files_are_read_relative_to_the_scene() {
        let dir = std::env::temp_dir().join(format!("acr-spectrum-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("flat.spd"), "# flat\n400 0.25\n700 0.25\n").unwrap();
        let file = SourceFile::new(dir.join("scene.pbrt"), "");
        let p = Param::new(
            ParamType::Spectrum,
            "Kd",
            Values::Strings(vec!["flat.spd".into()]),
            Loc::new(&file, 0),
        );
        let s = spectrum_param_to_rgb(&p).unwrap();
        assert!((luminance(s) - 0.25).abs() < 0.01, "{s}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
