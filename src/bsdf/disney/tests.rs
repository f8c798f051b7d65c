//! Tests of the Disney BSDF against pbrt-v3's values, energy and sampling, its lobes built by
//! the `disney` material from scene text as pbrt-v3 builds them.

use super::*;
use crate::bsdf::check::*;
use crate::bsdf::{Bsdf, Bxdf};
use crate::geometry::SurfaceInteraction;
use crate::material::{build_materials, Material};
use crate::sampling::uniform_sample_sphere;
use acr_parser::parse_str;
use std::path::Path;

/// pbrt-v3's `OneMinusEpsilon`.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// The material of one `Material "disney" ...` line (no warnings allowed).
fn material(params: &str) -> Material {
    let text = format!("WorldBegin\nMaterial \"disney\" {params}\nShape \"sphere\"\nWorldEnd\n");
    let desc = parse_str(&text, Path::new("/tmp/scene.pbrt")).unwrap();
    let mut w = Vec::new();
    let m = build_materials(&desc, Path::new("/tmp"), glam::DMat4::IDENTITY, &mut w).unwrap();
    assert!(w.is_empty(), "{params}: {w:?}");
    m.last().unwrap().clone()
}

/// A hit whose shading frame is the local frame (normal z, tangent x).
fn flat_hit() -> SurfaceInteraction {
    SurfaceInteraction::flat(Vec3::ZERO, Vec2::new(0.3, 0.6))
}

fn close(got: f32, want: f32, rel: f32) -> bool {
    (got - want).abs() <= rel * got.abs().max(want.abs()) + 1e-6
}

fn close_s(got: Spectrum, want: Spectrum, rel: f32) -> bool {
    (0..3).all(|c| close(got[c], want[c], rel))
}

/// pbrt-v3's `BxDFType` bits (the same as acr's) of a kind.
fn bits(k: BxdfType) -> u32 {
    use BxdfType as T;
    [
        T::REFLECTION,
        T::TRANSMISSION,
        T::DIFFUSE,
        T::GLOSSY,
        T::SPECULAR,
    ]
    .iter()
    .enumerate()
    .map(|(i, t)| if k.contains(*t) { 1 << i } else { 0 })
    .sum()
}

/// The pbrt-v3 class a lobe is.
fn pbrt_name(b: &Bxdf) -> &'static str {
    match b {
        Bxdf::Disney(DisneyBxdf::Diffuse { .. }) => "DisneyDiffuse",
        Bxdf::Disney(DisneyBxdf::FakeSs { .. }) => "DisneyFakeSS",
        Bxdf::Disney(DisneyBxdf::Retro { .. }) => "DisneyRetro",
        Bxdf::Disney(DisneyBxdf::Sheen { .. }) => "DisneySheen",
        Bxdf::Disney(DisneyBxdf::Clearcoat { .. }) => "DisneyClearcoat",
        Bxdf::Disney(DisneyBxdf::Specular { .. }) => "MicrofacetReflection",
        Bxdf::Disney(DisneyBxdf::Transmission { .. }) | Bxdf::MicrofacetTransmission { .. } => {
            "MicrofacetTransmission"
        }
        Bxdf::LambertianTransmission { .. } => "LambertianTransmission",
        _ => "other",
    }
}

/// The BSDF of every parameter set of tests/data/pbrt-v3/disneycheck.cpp (pbrt-v3's own
/// DisneyMaterial on a hit with tilted geometric and shading frames): the same lobes, the
/// same f and pdf, whole and lobe by lobe, for 49 pairs of directions (some below the
/// surface), and the same samples for 12 sample values from each of 7 directions.
#[test]
fn bsdf_matches_pbrt_v3() {
    let data = include_str!("../../../tests/data/pbrt-v3/disney-bsdf.txt");
    let num = |w: &[&str], i: usize| -> f32 { w[i].parse().unwrap() };
    let v3 = |w: &[&str], i: usize| Vec3::new(num(w, i), num(w, i + 1), num(w, i + 2));
    let mut si = flat_hit();
    let mut dirs = Vec::new();
    let mut bsdf = None;
    let (mut cases, mut values, mut samples, mut lobe_values) = (0, 0, 0, 0);
    let (mut nones, mut one_lobe_below) = (0, 0);
    let mut pair = (0, 0);
    for line in data.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w[0] {
            "frame" => {
                si.n = v3(&w, 2);
                si.shading_n = v3(&w, 6);
                si.shading_dpdu = v3(&w, 10);
                si.shading_dpdv = v3(&w, 14);
            }
            "dir" => dirs.push(v3(&w, 2)),
            "case" => {
                // "case NAME color r g b metallic m ... lobes N": the same Material line.
                let mut params = format!("\"rgb color\" [{} {} {}]", w[3], w[4], w[5]);
                let mut i = 6;
                while w[i] != "lobes" {
                    params += &match w[i] {
                        "thin" => format!(" \"bool thin\" \"{}\"", w[i + 1] == "1"),
                        name => format!(" \"float {name}\" {}", w[i + 1]),
                    };
                    i += 2;
                }
                let b = material(&params).bsdf(&si);
                assert_eq!(b.num_lobes(), w[i + 1].parse::<usize>().unwrap(), "{line}");
                bsdf = Some(b);
                cases += 1;
            }
            "lobe" => {
                let b = bsdf.as_ref().unwrap();
                let k: usize = w[1].parse().unwrap();
                assert_eq!(pbrt_name(&b.lobes()[k].bxdf), w[3], "{line}");
            }
            "f" => {
                let b = bsdf.as_ref().unwrap();
                let (o, i): (usize, usize) = (w[1].parse().unwrap(), w[2].parse().unwrap());
                let f = b.f(dirs[o], dirs[i]);
                let pdf = b.pdf(dirs[o], dirs[i]);
                assert!(close_s(f, v3(&w, 4), 1e-4), "f {f}\n{line}");
                assert!(close(pdf, num(&w, 8), 1e-4), "pdf {pdf}\n{line}");
                (pair, values, lobe_values) = ((o, i), values + 1, 0);
            }
            "l" => {
                let b = bsdf.as_ref().unwrap();
                let k: usize = w[1].parse().unwrap();
                // The pair is the previous "f" line's.
                let (o, i) = pair;
                let (lo, li) = (b.frame().to_local(dirs[o]), b.frame().to_local(dirs[i]));
                let lobe = &b.lobes()[k];
                let f = lobe.scale * lobe.bxdf.f(lo, li);
                let pdf = lobe.bxdf.pdf(lo, li);
                assert!(close_s(f, v3(&w, 3), 1e-4), "lobe {k} f {f}\n{line}");
                assert!(close(pdf, num(&w, 7), 1e-4), "lobe {k} pdf {pdf}\n{line}");
                lobe_values += 1;
                assert!(lobe_values <= b.num_lobes());
            }
            "s" => {
                let b = bsdf.as_ref().unwrap();
                let o: usize = w[1].parse().unwrap();
                let (u0, u1) = (num(&w, 2), num(&w, 3));
                // pbrt-v3 picks the lobe with u0 and reuses what is left of it.
                let n = b.num_lobes();
                let comp = ((u0 * n as f32).floor() as usize).min(n - 1);
                let u = Vec2::new((u0 * n as f32 - comp as f32).min(ONE_MINUS_EPSILON), u1);
                let got = b.sample_f(dirs[o], u, u0);
                if w[4] == "none" {
                    assert!(
                        got.is_none(),
                        "acr samples {got:?} where pbrt-v3 does not:\n{line}"
                    );
                    nones += 1;
                    continue;
                }
                let s = got.unwrap_or_else(|| panic!("no sample where pbrt-v3 has:\n{line}"));
                let kind: u32 = w[15].parse().unwrap();
                assert_eq!(bits(b.lobes()[comp].bxdf.kind()), kind, "{line}");
                let want_wi = v3(&w, 5);
                assert!((s.wi - want_wi).length() < 1e-4, "wi {}\n{line}", s.wi);
                let reflect = s.wi.dot(si.n) * dirs[o].dot(si.n) > 0.0;
                let lobe_kind = b.lobes()[comp].bxdf.kind();
                if n == 1 && !reflect && !lobe_kind.contains(BxdfType::TRANSMISSION) {
                    // A known difference (src/bsdf/mod.rs): with one lobe pbrt-v3 keeps the
                    // lobe's value below the geometric surface; acr applies its test.
                    assert_eq!(s.f, Spectrum::ZERO, "{line}");
                    one_lobe_below += 1;
                } else {
                    assert!(close_s(s.f, v3(&w, 9), 1e-3), "f {}\n{line}", s.f);
                }
                assert!(close(s.pdf, num(&w, 13), 1e-3), "pdf {}\n{line}", s.pdf);
                samples += 1;
            }
            _ => panic!("unexpected line {line}"),
        }
    }
    assert_eq!((cases, values), (10, 10 * 49));
    assert_eq!((samples, nones), (10 * 7 * 12 - 26, 26));
    assert!(one_lobe_below <= 2, "{one_lobe_below}");
}

/// A white material's BSDF in the local frame.
fn white(params: &str) -> Bsdf {
    material(&format!("\"rgb color\" [1 1 1] {params}")).bsdf(&flat_hit())
}

/// Outgoing directions from normal incidence to grazing (cosines 1 to 0.08).
fn elevations() -> impl Iterator<Item = Vec3> {
    [1.0f32, 0.7, 0.4, 0.2, 0.08]
        .into_iter()
        .map(|c| Vec3::new((1.0 - c * c).sqrt(), 0.0, c))
}

/// White furnace: the directional albedo of white materials. Where the model conserves
/// energy (metals, specular transmission) the albedo stays at most 1, a physical bound
/// checked independently of any measurement. Its diffuse part does not (Burley's model, as
/// pbrt-v3's `DisneyMaterial` codes it, adds the diffuse and retro-reflection lobes to the
/// specular one without a 1 - F weight, the retro-reflection grows toward grazing, and the thin
/// fake subsurface lobe's 1 / (cos θo + cos θi) does more so): for those the ranges below are
/// acr's own measurement, kept as a regression check (pbrt-v3 computes no such figures; that
/// the gains are the model's and not acr's rests on reading its code, not on its numbers).
#[test]
fn white_furnace_conserves_where_the_model_does_and_keeps_its_measured_gains() {
    let conserving = [
        "\"float roughness\" 0.3 \"float metallic\" 1",
        "\"float roughness\" 1 \"float metallic\" 1",
        "\"float roughness\" 0.5 \"float metallic\" 0.5 \"float speculartint\" 1",
        "\"float roughness\" 0.4 \"float anisotropic\" 0.9 \"float metallic\" 1",
        "\"float roughness\" 0.3 \"float spectrans\" 1",
        "\"float roughness\" 0.3 \"float spectrans\" 0.5",
    ];
    for (k, p) in conserving.iter().enumerate() {
        let b = white(p);
        for wo in elevations() {
            let (a, se) = albedo(&b, wo, 40_000, 3 + k as u64);
            assert!(
                a.max_element() <= 1.0 + 3.0 * se + 1e-3,
                "{p} {wo}: {a} ± {se}"
            );
        }
    }
    // (parameters, albedo range at normal incidence, at cos θo = 0.2): acr's measurement with
    // 100,000 samples (a regression range, not pbrt-v3's figures), 1.018-1.326 for roughness
    // 0.05 across the elevations, 1.05-1.45 for roughness 1, 0.96-2.05 for the thin fake
    // subsurface.
    let gaining = [
        ("\"float roughness\" 0.05", (1.0, 1.05), (1.12, 1.22)),
        ("\"float roughness\" 0.5", (1.02, 1.07), (1.12, 1.2)),
        (
            "\"float roughness\" 1 \"float sheen\" 1",
            (1.02, 1.08),
            (1.28, 1.37),
        ),
        (
            "\"float roughness\" 0.5 \"float clearcoat\" 1",
            (1.02, 1.08),
            (1.15, 1.25),
        ),
        (
            "\"float roughness\" 1 \"bool thin\" \"true\" \"float flatness\" 1",
            (0.93, 0.98),
            (1.62, 1.72),
        ),
    ];
    for (k, (p, normal, grazing)) in gaining.iter().enumerate() {
        let b = white(p);
        for (c, (lo, hi)) in [(1.0f32, normal), (0.2, grazing)] {
            let wo = Vec3::new((1.0 - c * c).sqrt(), 0.0, c);
            let (a, se) = albedo(&b, wo, 40_000, 7 + k as u64);
            let a = a.max_element();
            assert!(
                *lo <= a + 3.0 * se && a - 3.0 * se <= *hi,
                "{p} {wo}: {a} ± {se}"
            );
        }
    }
}

/// ∫ f |cos θi| dωi over the sphere with stratified uniform directions, and its standard
/// error (that of independent samples, an overestimate).
fn uniform_albedo(b: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (Spectrum, f32) {
    let mut rng = Rng::new(seed);
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    for j in 0..n {
        for i in 0..n {
            let u = Vec2::new(
                (i as f32 + rng.next_f32()) / n as f32,
                (j as f32 + rng.next_f32()) / n as f32,
            );
            let wi = uniform_sample_sphere(u);
            let v = b.f(wo, wi) * wi.z.abs() * (4.0 * PI);
            for c in 0..3 {
                sum[c] += v[c] as f64;
                sum2[c] += (v[c] as f64).powi(2);
            }
        }
    }
    let m = (n * n) as f64;
    let mean = sum.map(|s| s / m);
    let se = (0..3)
        .map(|c| ((sum2[c] / m - mean[c] * mean[c]).max(0.0) / m).sqrt())
        .fold(0.0, f64::max);
    (
        Spectrum::new(mean[0] as f32, mean[1] as f32, mean[2] as f32),
        se as f32,
    )
}

/// Sampling agrees with evaluation: each sample's f and pdf are `f()` and `pdf()`, the pdf
/// integrates to the rate at which sampling succeeds, and ∫ f cos estimated by sampling
/// (E[f cos / pdf]) equals the estimate over uniform directions.
#[test]
fn sampling_agrees_with_evaluation() {
    let sets = [
            "\"rgb color\" [0.8 0.5 0.3]",
            "\"rgb color\" [0.9 0.6 0.3] \"float metallic\" 1 \"float roughness\" 0.4",
            "\"rgb color\" [0.7 0.7 0.7] \"float metallic\" 0.6 \"float anisotropic\" 0.8 \"float roughness\" 0.6 \"float speculartint\" 0.5",
            "\"rgb color\" [0.1 0.3 0.6] \"float clearcoat\" 1 \"float clearcoatgloss\" 0",
            "\"rgb color\" [0.6 0.2 0.4] \"float sheen\" 1 \"float roughness\" 0.8",
            "\"rgb color\" [0.9 0.9 0.7] \"float spectrans\" 0.7 \"float roughness\" 0.5 \"float eta\" 1.33",
            "\"rgb color\" [0.5 0.8 0.3] \"bool thin\" \"true\" \"float spectrans\" 0.6 \"float flatness\" 0.4 \"float difftrans\" 0.8 \"float roughness\" 0.6",
            "\"rgb color\" [0.7 0.4 0.3] \"bool thin\" \"true\" \"float spectrans\" 0.5 \"float flatness\" 0.7 \"float sheen\" 0.6 \"float clearcoat\" 0.5 \"float clearcoatgloss\" 0 \"float metallic\" 0.2 \"float roughness\" 0.7 \"float anisotropic\" 0.5",
        ];
    for (k, p) in sets.iter().enumerate() {
        let b = material(p).bsdf(&flat_hit());
        for (j, wo) in test_directions().into_iter().enumerate() {
            let seed = (10 * k + j) as u64;
            sample_matches_eval(&b, wo, 2000, seed);
            let (integral, se, success) = pdf_integral(&b, wo, 200, seed);
            let transmits = b.lobes().iter().any(|l| {
                l.bxdf.kind().contains(BxdfType::TRANSMISSION)
                    && l.bxdf.kind().contains(BxdfType::GLOSSY)
            });
            if transmits && wo.z.abs() < 0.2 {
                // pbrt-v3's rough transmission pdf also counts microfacets facing away from
                // a grazing wo, which its sampler never picks (see src/bsdf/tests.rs).
                assert!(
                    integral < 1.1 && integral + 4.0 * se + 0.01 > success,
                    "{p} {wo}"
                );
            } else {
                assert!(
                    (integral - success).abs() < 4.0 * se + 0.01,
                    "{p} {wo}: ∫pdf {integral} ± {se}, success {success}"
                );
            }
            let (a, se_a) = albedo(&b, wo, 100_000, seed);
            let (u, se_u) = uniform_albedo(&b, wo, 400, seed);
            for c in 0..3 {
                assert!(
                    (a[c] - u[c]).abs() <= 4.0 * (se_a + se_u) + 0.005,
                    "{p} {wo}: sampled {a} ± {se_a}, uniform {u} ± {se_u}"
                );
            }
        }
    }
}

/// The reflection lobes are symmetric in wo and wi, as pbrt-v3's.
#[test]
fn reflection_lobes_are_reciprocal() {
    let b = material(
            "\"rgb color\" [0.7 0.4 0.3] \"bool thin\" \"true\" \"float spectrans\" 0.5 \"float flatness\" 0.7 \"float sheen\" 0.6 \"float clearcoat\" 0.5 \"float metallic\" 0.2 \"float anisotropic\" 0.5",
        )
        .bsdf(&flat_hit());
    assert_eq!(b.num_lobes(), 8);
    let mut rng = Rng::new(5);
    for _ in 0..500 {
        let x = cosine_sample_hemisphere(rng.next_2d());
        let y = cosine_sample_hemisphere(rng.next_2d());
        for l in b.lobes() {
            if l.bxdf.kind().contains(BxdfType::REFLECTION) {
                let (fxy, fyx) = (l.bxdf.f(x, y), l.bxdf.f(y, x));
                assert!(close_s(fxy, fyx, 1e-4), "{:?}: {fxy} vs {fyx}", l.bxdf);
            }
        }
    }
}

/// Defaults are pbrt-v3's (colour 0.5, roughness 0.5, eta 1.5: three lobes), a non-zero
/// `scatterdistance` warns, and degenerate directions give finite values.
#[test]
fn defaults_warnings_and_degenerate_directions() {
    let b = material("").bsdf(&flat_hit());
    let names: Vec<_> = b.lobes().iter().map(|l| pbrt_name(&l.bxdf)).collect();
    assert_eq!(
        names,
        ["DisneyDiffuse", "DisneyRetro", "MicrofacetReflection"]
    );
    let Bxdf::Disney(DisneyBxdf::Specular {
        distribution,
        r0,
        metallic,
        eta,
    }) = b.lobes()[2].bxdf
    else {
        panic!()
    };
    assert_eq!(
        (distribution.alpha_x, distribution.alpha_y, metallic, eta),
        (0.25, 0.25, 0.0, 1.5)
    );
    assert!((r0 - Spectrum::splat(0.04)).abs().max_element() < 1e-7);

    let text = "WorldBegin\nMaterial \"disney\" \"rgb scatterdistance\" [1 1 1]\nShape \"sphere\"\nWorldEnd\n";
    let desc = parse_str(text, Path::new("/tmp/scene.pbrt")).unwrap();
    let mut w = Vec::new();
    let m = build_materials(&desc, Path::new("/tmp"), glam::DMat4::IDENTITY, &mut w).unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].message.contains("scatterdistance") && w[0].loc.is_some());
    assert_eq!(m.last().unwrap().bsdf(&flat_hit()).num_lobes(), 3);

    let b = material(
            "\"bool thin\" \"true\" \"float spectrans\" 0.5 \"float flatness\" 0.7 \"float sheen\" 0.6 \"float clearcoat\" 0.5 \"float anisotropic\" 0.5 \"float roughness\" 0",
        )
        .bsdf(&flat_hit());
    let mut lobes: Vec<Bxdf> = b.lobes().iter().map(|l| l.bxdf).collect();
    lobes.push(Bxdf::Disney(DisneyBxdf::Transmission {
        t: Spectrum::ONE,
        distribution: TrowbridgeReitz::new(0.001, 0.001),
        eta: 1.5,
    }));
    let dirs = degenerate_directions();
    let us = edge_samples();
    for l in lobes {
        for wo in dirs {
            for wi in dirs {
                assert!(
                    l.f(wo, wi).is_finite() && l.pdf(wo, wi).is_finite(),
                    "{l:?} {wo} {wi}"
                );
            }
            for u in us {
                if let Some(s) = l.sample_f(wo, u) {
                    assert!(
                        s.f.is_finite() && s.pdf > 0.0 && s.pdf.is_finite() && s.wi.is_finite()
                    );
                }
            }
        }
    }
}

/// The Disney lobes fit in the space of the largest other lobes.
#[test]
fn lobes_stay_small() {
    assert!(std::mem::size_of::<DisneyBxdf>() <= 32);
    println!("Bxdf: {} bytes", std::mem::size_of::<Bxdf>());
}
