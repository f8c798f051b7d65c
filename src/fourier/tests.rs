//! Tests of the fourier BSDF against pbrt-v3's values (`tests/data/pbrt-v3/fouriercheck.cpp`
//! over `scenes/pbrt-v3/textures/tabulated.bsdf`), its density, and bad files.

use super::*;
use crate::sampling::uniform_sample_sphere;
use glam::Vec2;

const FILE: &[u8] = include_bytes!("../../scenes/pbrt-v3/textures/tabulated.bsdf");

fn bsdf() -> FourierBsdf {
    let table: &'static FourierTable = Box::leak(Box::new(FourierTable::parse(FILE).unwrap()));
    FourierBsdf { table }
}

fn close(got: f32, want: f32, rel: f32) -> bool {
    (got - want).abs() <= rel * got.abs().max(want.abs()) + 1e-6
}

#[test]
fn fourier_bsdf_matches_pbrt_v3() {
    let b = bsdf();
    let data = include_str!("../../tests/data/pbrt-v3/fourier-values.txt");
    let (mut evaluated, mut sampled) = (0, 0);
    for line in data.lines() {
        let mut parts = line.split_whitespace();
        let kind = parts.next().unwrap();
        let v: Vec<f32> = parts.map(|x| x.parse().unwrap()).collect();
        let wo = Vec3::new(v[0], v[1], v[2]);
        if kind == "f" {
            let wi = Vec3::new(v[3], v[4], v[5]);
            let f = b.f(wo, wi);
            for c in 0..3 {
                assert!(close(f[c], v[6 + c], 1e-4), "{line}: f {f:?}");
            }
            let pdf = b.pdf(wo, wi);
            assert!(close(pdf, v[9], 1e-4), "{line}: pdf {pdf}");
            evaluated += 1;
        } else {
            let want_f = Spectrum::new(v[8], v[9], v[10]);
            match b.sample_f(wo, [v[3], v[4]]) {
                Some((wi, f, pdf)) => {
                    let want_wi = Vec3::new(v[5], v[6], v[7]);
                    assert!((wi - want_wi).abs().max_element() < 1e-4, "{line}: wi {wi}");
                    for c in 0..3 {
                        assert!(close(f[c], want_f[c], 1e-4), "{line}: f {f:?}");
                    }
                    assert!(close(pdf, v[11], 1e-4), "{line}: pdf {pdf}");
                    sampled += 1;
                }
                None => assert!(v[11] == 0.0 || want_f == Spectrum::ZERO, "{line}"),
            }
        }
    }
    assert_eq!(evaluated, 400);
    assert!(sampled > 380, "{sampled}");
}

/// The density of the sampled directions integrates to one over the sphere, and what
/// sampling gives is what evaluating gives.
#[test]
fn density_integrates_to_one_and_sampling_agrees_with_evaluation() {
    let b = bsdf();
    let mut rng = crate::stream::Pcg32::new(3, 1);
    for wo in [
        Vec3::new(0.3, 0.2, 0.93),
        Vec3::new(-0.8, 0.1, 0.2),
        Vec3::new(0.1, 0.5, -0.7),
    ] {
        let wo = wo.normalize();
        let n = 200_000;
        let sum: f64 = (0..n)
            .map(|_| {
                let wi = uniform_sample_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
                f64::from(b.pdf(wo, wi)) * 4.0 * std::f64::consts::PI
            })
            .sum();
        let integral = sum / f64::from(n);
        assert!((integral - 1.0).abs() < 0.02, "{wo}: {integral}");
        for _ in 0..200 {
            let Some((wi, f, pdf)) = b.sample_f(wo, [rng.next_f32(), rng.next_f32()]) else {
                continue;
            };
            assert!(close(pdf, b.pdf(wo, wi), 1e-3), "{wo} {wi}");
            let e = b.f(wo, wi);
            for c in 0..3 {
                assert!(close(f[c], e[c], 1e-3), "{wo} {wi}: {f:?} {e:?}");
            }
        }
    }
}

#[test]
fn bad_files_are_errors_not_panics() {
    assert!(FourierTable::parse(b"SCATFUN").is_err());
    assert!(FourierTable::parse(&FILE[..FILE.len() / 2])
        .unwrap_err()
        .contains("ends early"));
    let mut wrong = FILE.to_vec();
    wrong[7] = 2;
    assert!(FourierTable::parse(&wrong).unwrap_err().contains("SCATFUN"));
    // A node count far beyond the file.
    let mut big = FILE.to_vec();
    big[12..16].copy_from_slice(&i32::MAX.to_le_bytes());
    assert!(FourierTable::parse(&big).is_err());
    // Every single-byte corruption of the header and the offsets is refused or read.
    let mut rng = crate::stream::Pcg32::new(9, 1);
    for _ in 0..2000 {
        let mut bytes = FILE.to_vec();
        let at = (rng.next_f32() * bytes.len() as f32) as usize % bytes.len();
        bytes[at] = (rng.next_f32() * 256.0) as u8;
        if let Ok(t) = FourierTable::parse(&bytes) {
            let b = FourierBsdf {
                table: Box::leak(Box::new(t)),
            };
            let (wo, wi) = (Vec3::new(0.0, 0.6, 0.8), Vec3::new(0.6, 0.0, 0.8));
            let _ = (b.f(wo, wi), b.pdf(wo, wi), b.sample_f(wo, [0.3, 0.7]));
        }
    }
}

/// A `bsdffile` that cannot be read is an error at the parameter's location.
#[test]
fn a_missing_bsdf_file_is_a_located_error() {
    use acr_parser::parse_str;
    use std::path::Path;
    let text = "WorldBegin\nMaterial \"fourier\" \"string bsdffile\" \"nowhere.bsdf\"\nShape \"sphere\"\nWorldEnd\n";
    let desc = parse_str(text, Path::new("/tmp/acr-fourier-scene.pbrt")).unwrap();
    let mut w = Vec::new();
    let e =
        crate::material::build_materials(&desc, Path::new("/tmp"), glam::DMat4::IDENTITY, &mut w)
            .unwrap_err()
            .to_string();
    assert!(
        e.contains("acr-fourier-scene.pbrt:2:") && e.contains("nowhere.bsdf"),
        "{e}"
    );
    let text = "WorldBegin\nMaterial \"fourier\"\nShape \"sphere\"\nWorldEnd\n";
    let desc = parse_str(text, Path::new("/tmp/acr-fourier-scene.pbrt")).unwrap();
    let e =
        crate::material::build_materials(&desc, Path::new("/tmp"), glam::DMat4::IDENTITY, &mut w)
            .unwrap_err()
            .to_string();
    assert!(e.contains("needs \"string bsdffile\""), "{e}");
}

/// Along the normal wo has no azimuth: the sampled wi keeps its sampled zenith (pbrt-v3's
/// formula put every such wi on the normal) and agrees with evaluation there.
#[test]
fn sampling_at_normal_incidence_agrees_with_evaluation() {
    let b = bsdf();
    let wo = Vec3::new(0.0, 0.0, 1.0);
    for u in [[0.1, 0.2], [0.5, 0.5], [0.9, 0.7], [0.3, 0.95]] {
        let (wi, f, pdf) = b.sample_f(wo, u).expect("a sample");
        assert!((wi.length() - 1.0).abs() < 1e-5, "{u:?}: {wi}");
        assert!(wi.z.abs() < 0.9999, "{u:?}: {wi} lies on the normal");
        let (f2, pdf2) = (b.f(wo, wi), b.pdf(wo, wi));
        assert!(close(pdf, pdf2, 2e-3), "{u:?}: pdf {pdf} vs {pdf2}");
        for c in 0..3 {
            assert!(close(f[c], f2[c], 2e-3), "{u:?}: f {f} vs {f2}");
        }
    }
}
