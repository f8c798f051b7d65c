//! Tests of the hair BSDF and material against pbrt-v3's values and its own hair tests. The
//! material's tests are here too: they read the lobe it builds, down to its private fields.

use super::*;
use crate::bsdf::check::Rng;
use crate::bsdf::{Bsdf, Bxdf};
use crate::geometry::SurfaceInteraction;
use crate::material::{build_materials, HairMaterial, Material};
use crate::sampling::uniform_sample_sphere;
use crate::texture::Texture;
use acr_parser::{parse_str, Error, Result, Warning};
use std::path::Path;

/// 1 / (4 pi), pbrt-v3's `UniformSpherePdf`.
const UNIFORM_SPHERE_PDF: f32 = std::f32::consts::FRAC_1_PI / 4.0;

/// `f`, `Pdf`, `Sample_f`, `DemuxFloat` and the two absorption conversions against the
/// values pbrt-v3's own code printed for 30 hairs (h from -1 to 1, beta_m from 0.05 to 1,
/// both branches of M_p, tilts of -3 to 5 degrees, absorption none, from melanins and from
/// colours), 300 pairs of directions and 300 samples (tests/data/pbrt-v3/haircheck.cpp).
/// Built without fused multiply-adds, pbrt-v3 gives the same floats as acr on this machine;
/// the margin is for other platforms' libm. (pbrt-v3's own -march=native build fuses them:
/// up to 2.4e-4 apart in the sharpest lobes.)
#[test]
fn values_match_pbrt_v3() {
    let data = include_str!("../../../tests/data/pbrt-v3/hair-values.txt");
    let mut hair = None;
    let mut counts = [0usize; 6];
    // Largest relative differences seen: f, pdf, sampled direction (absolute).
    let mut worst = [0.0f32; 3];
    let rel = |a: f32, b: f32| (a - b).abs() / (a.abs().max(b.abs()) + 1e-30);
    for line in data.lines() {
        let w: Vec<&str> = line.split_whitespace().filter(|s| *s != "->").collect();
        let n: Vec<f32> = w[1..].iter().map(|s| s.parse().unwrap()).collect();
        let v3 = |i: usize| Vec3::new(n[i], n[i + 1], n[i + 2]);
        let spectrum = |got: Spectrum, want: Spectrum, worst: &mut f32| {
            for c in 0..3 {
                *worst = worst.max(rel(got[c], want[c]));
            }
        };
        match w[0] {
            "demux" => {
                counts[0] += 1;
                assert_eq!(demux_float(n[0]), Vec2::new(n[1], n[2]), "{line}");
            }
            "conc" => {
                counts[1] += 1;
                let mut e = 0.0;
                spectrum(sigma_a_from_concentration(n[0], n[1]), v3(2), &mut e);
                assert!(e < 1e-6, "{e}: {line}");
            }
            "refl" => {
                counts[2] += 1;
                let mut e = 0.0;
                spectrum(sigma_a_from_reflectance(v3(0), n[3]), v3(4), &mut e);
                assert!(e < 1e-5, "{e}: {line}");
            }
            "hair" => {
                counts[3] += 1;
                hair = Some(HairBsdf::new(n[0], n[1], v3(2), n[5], n[6], n[7]));
            }
            "f" => {
                counts[4] += 1;
                let h = hair.unwrap();
                spectrum(h.f(v3(0), v3(3)), v3(6), &mut worst[0]);
                worst[1] = worst[1].max(rel(h.pdf(v3(0), v3(3)), n[9]));
            }
            "s" => {
                counts[5] += 1;
                let h = hair.unwrap();
                let (wi, f, pdf) = h.sample_f(v3(0), Vec2::new(n[3], n[4]));
                worst[2] = worst[2].max((wi - v3(5)).length());
                spectrum(f, v3(9), &mut worst[0]);
                worst[1] = worst[1].max(rel(pdf, n[8]));
            }
            _ => panic!("{line}"),
        }
    }
    assert_eq!(counts, [20, 10, 10, 30, 300, 300]);
    assert!(
        worst[0] < 1e-5 && worst[1] < 1e-5 && worst[2] < 1e-6,
        "{worst:?}"
    );
}

/// pbrt-v3's `RNG` (PCG32 with its default state and stream) and `UniformFloat`, so that
/// the tests ported from pbrt-v3 draw its own numbers: their Monte Carlo estimates are
/// then pbrt-v3's, and its bounds hold as they did there.
struct PbrtRng {
    state: u64,
    inc: u64,
}

impl PbrtRng {
    fn new() -> Self {
        Self {
            state: 0x853c_49e6_748f_ea9b,
            inc: 0xda3e_39cb_94b9_5bdb,
        }
    }

    fn uniform_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(0x5851_f42d_4c95_7f2d)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    fn uniform_float(&mut self) -> f32 {
        (self.uniform_u32() as f32 / 4_294_967_296.0).min(1.0 - f32::EPSILON / 2.0)
    }

    /// Two numbers in order, as pbrt-v3's `{rng.UniformFloat(), rng.UniformFloat()}`.
    fn uniform_2d(&mut self) -> Vec2 {
        let a = self.uniform_float();
        Vec2::new(a, self.uniform_float())
    }
}

/// pbrt-v3's `Hair.Pow` test: its `Pow<n>` for n up to 29.
#[test]
fn pow_gives_powers_of_two() {
    for n in 0..30 {
        assert_eq!(pow_n(2.0, n), (1u32 << n) as f32);
    }
}

/// Calls `body(beta_m, beta_n)` over pbrt-v3's float loops
/// `for (beta = start; beta < 1; beta += .2)`, in f32 as there.
fn beta_loops(start_m: f32, start_n: f32, mut body: impl FnMut(f32, f32)) {
    let mut beta_m = start_m;
    while beta_m < 1.0 {
        let mut beta_n = start_n;
        while beta_n < 1.0 {
            body(beta_m, beta_n);
            beta_n += 0.2;
        }
        beta_m += 0.2;
    }
}

/// pbrt-v3's `Hair.WhiteFurnace`: without absorption, the hair scatters all the light of a
/// uniform environment (within 5%), estimated with uniform directions.
#[test]
fn white_furnace() {
    let mut rng = PbrtRng::new();
    let wo = uniform_sample_sphere(rng.uniform_2d());
    // pbrt-v3's own first direction (printed by it): the same numbers are drawn.
    assert!(
        (wo - Vec3::new(0.54987, 0.0335902, 0.834575)).length() < 1e-5,
        "{wo}"
    );
    beta_loops(0.1, 0.1, |beta_m, beta_n| {
        let count = 300_000;
        let mut sum = Spectrum::ZERO;
        for _ in 0..count {
            let h = (-1.0 + 2.0 * rng.uniform_float() as f64) as f32;
            let hair = HairBsdf::new(h, 1.55, Spectrum::ZERO, beta_m, beta_n, 0.0);
            let wi = uniform_sample_sphere(rng.uniform_2d());
            sum += hair.f(wo, wi) * wi.z.abs();
        }
        let avg = crate::spectrum_luminance(sum) / (count as f32 * UNIFORM_SPHERE_PDF);
        assert!((0.95..=1.05).contains(&avg), "{beta_m} {beta_n}: {avg}");
    });
}

/// pbrt-v3's `Hair.WhiteFurnaceSampled`: the same with importance sampling, within 1%.
#[test]
fn white_furnace_sampled() {
    let mut rng = PbrtRng::new();
    let wo = uniform_sample_sphere(rng.uniform_2d());
    beta_loops(0.1, 0.1, |beta_m, beta_n| {
        let count = 300_000;
        let mut sum = Spectrum::ZERO;
        for _ in 0..count {
            let h = (-1.0 + 2.0 * rng.uniform_float() as f64) as f32;
            let hair = HairBsdf::new(h, 1.55, Spectrum::ZERO, beta_m, beta_n, 0.0);
            let (wi, f, pdf) = hair.sample_f(wo, rng.uniform_2d());
            if pdf > 0.0 {
                sum += f * wi.z.abs() / pdf;
            }
        }
        let avg = crate::spectrum_luminance(sum) / count as f32;
        assert!((0.99..=1.01).contains(&avg), "{beta_m} {beta_n}: {avg}");
    });
}

/// pbrt-v3's `Hair.SamplingWeights`: without absorption, every sample's weight
/// f |cos| / pdf is 1 (the sampling density is proportional to f).
#[test]
fn sampling_weights_are_one() {
    let mut rng = PbrtRng::new();
    beta_loops(0.1, 0.4, |beta_m, beta_n| {
        for _ in 0..10_000 {
            let h = -1.0 + 2.0 * rng.uniform_float();
            let hair = HairBsdf::new(h, 1.55, Spectrum::ZERO, beta_m, beta_n, 0.0);
            let wo = uniform_sample_sphere(rng.uniform_2d());
            let (wi, f, pdf) = hair.sample_f(wo, rng.uniform_2d());
            if pdf > 0.0 {
                let w = crate::spectrum_luminance(f) * wi.z.abs() / pdf;
                assert!(w > 0.999 && w < 1.001, "{beta_m} {beta_n} {h} {wo}: {w}");
            }
        }
    });
}

/// pbrt-v3's `Hair.SamplingConsistency`: with absorption, importance sampling and uniform
/// sampling estimate the same light scattered from an environment of z² (within 5%).
#[test]
fn sampling_is_consistent_with_evaluation() {
    let mut rng = PbrtRng::new();
    beta_loops(0.2, 0.4, |beta_m, beta_n| {
        let count = 64 * 1024;
        let sigma_a = Spectrum::splat(0.25);
        let wo = uniform_sample_sphere(rng.uniform_2d());
        let li = |w: Vec3| w.z * w.z;
        let (mut importance, mut uniform) = (Spectrum::ZERO, Spectrum::ZERO);
        for _ in 0..count {
            let h = -1.0 + 2.0 * rng.uniform_float();
            let hair = HairBsdf::new(h, 1.55, sigma_a, beta_m, beta_n, 0.0);
            let u = rng.uniform_2d();
            let (wi, f, pdf) = hair.sample_f(wo, u);
            if pdf > 0.0 {
                importance += f * li(wi) * wi.z.abs() / (count as f32 * pdf);
            }
            let wi = uniform_sample_sphere(u);
            uniform += hair.f(wo, wi) * li(wi) * wi.z.abs() / (count as f32 * UNIFORM_SPHERE_PDF);
        }
        let (a, b) = (
            crate::spectrum_luminance(importance),
            crate::spectrum_luminance(uniform),
        );
        assert!((a - b).abs() / b < 0.05, "{beta_m} {beta_n}: {a} vs {b}");
    });
}

/// The lobe adds no size to acr's `Bxdf` (held by value, eight to a BSDF): it is no larger
/// than the fields of `MicrofacetReflection` (r, distribution, conductor Fresnel), the
/// largest of the other lobes (60 bytes; `Bxdf` is 64).
#[test]
fn lobe_keeps_bxdf_small() {
    use crate::bsdf::Fresnel;
    use crate::microfacet::TrowbridgeReitz;
    let microfacet = std::mem::size_of::<(Spectrum, TrowbridgeReitz, Fresnel)>();
    assert!(std::mem::size_of::<HairBsdf>() <= microfacet);
}

/// Degenerate directions and parameters give finite values or NaN, never a panic or a hang;
/// the BSDF then turns non-finite values into nothing.
#[test]
fn degenerate_inputs_neither_panic_nor_hang() {
    let dirs = [
        Vec3::X,
        -Vec3::X,
        Vec3::Z,
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 1e-7),
    ];
    for (h, bm, bn) in [
        (1.0, 0.3, 0.3),
        (-1.0, 0.0, 0.0),
        (2.0, 1.0, 1.0),
        (0.3, 0.3, 0.3),
    ] {
        let hair = HairBsdf::new(h, 1.55, Spectrum::splat(0.5), bm, bn, 2.0);
        for wo in dirs {
            for wi in dirs {
                let _ = (hair.f(wo, wi), hair.pdf(wo, wi));
            }
            for u in [Vec2::ZERO, Vec2::splat(0.5), Vec2::ONE, Vec2::splat(-1.0)] {
                let _ = hair.sample_f(wo, u);
            }
        }
    }
    assert_eq!(demux_float(1.0), demux_float(1.0 - f32::EPSILON / 2.0));
}

/// A hit on a curve: the tangent (dp/du) along y, the normal along z, v across the hair.
fn curve_hit(v: f32) -> SurfaceInteraction {
    SurfaceInteraction {
        p: Vec3::ZERO,
        n: Vec3::Z,
        uv: Vec2::new(0.4, v),
        dpdu: Vec3::new(0.0, 2.0, 0.0),
        dpdv: Vec3::new(-0.1, 0.0, 0.0),
        shading_n: Vec3::Z,
        shading_dpdu: Vec3::new(0.0, 2.0, 0.0),
        shading_dpdv: Vec3::new(-0.1, 0.0, 0.0),
        dndu: Vec3::ZERO,
        dndv: Vec3::ZERO,
        wo: Vec3::Z,
        time: 0.0,
        p_error: 0.0,
        diff: Default::default(),
    }
}

/// Parses world-block text and builds its materials (every one used by a sphere).
fn build(text: &str) -> Result<(Vec<Material>, Vec<Warning>, Vec<Warning>)> {
    let full = format!("WorldBegin\n{text}\nShape \"sphere\"\nWorldEnd\n");
    let desc = parse_str(&full, Path::new("/tmp/scene.pbrt")).unwrap();
    let mut w = Vec::new();
    let m = build_materials(&desc, Path::new("/tmp"), glam::DMat4::IDENTITY, &mut w)?;
    Ok((m, w, desc.unused_parameter_warnings()))
}

fn hair_of(m: &[Material]) -> &HairMaterial {
    match m.last() {
        Some(Material::Hair(h)) => h,
        other => panic!("not hair: {other:?}"),
    }
}

/// The BSDF's frame is pbrt-v3's: x along the hair's dp/du, z the shading normal, y their
/// cross product (n x s); h = -1 + 2 v; the relative index is eta.
#[test]
fn material_lobe_is_in_the_hair_frame() {
    let (m, w, _) = build(r#"Material "hair" "float eta" 1.6"#).unwrap();
    assert!(w.is_empty(), "{w:?}");
    let si = curve_hit(0.3);
    let bsdf = m.last().unwrap().bsdf(&si);
    assert_eq!(bsdf.num_lobes(), 1);
    assert!((bsdf.eta() - 1.6).abs() < 1e-6);
    let want = HairBsdf::new(
        -0.4,
        1.6,
        sigma_a_from_concentration(1.3, 0.0),
        0.3,
        0.3,
        2.0,
    );
    let Bxdf::Hair(got) = bsdf.lobes()[0].bxdf else {
        panic!()
    };
    assert!((got.h - want.h).abs() < 1e-6);
    assert_eq!(
        HairBsdf {
            h: want.h,
            gamma_o: want.gamma_o,
            ..got
        },
        want
    );
    let (ss, ns) = (Vec3::Y, Vec3::Z);
    let ts = ns.cross(ss);
    let local = |v: Vec3| Vec3::new(v.dot(ss), v.dot(ts), v.dot(ns));
    let mut rng = Rng::new(9);
    for _ in 0..100 {
        let wo = uniform_sample_sphere(rng.next_2d());
        let wi = uniform_sample_sphere(rng.next_2d());
        if wo.z == 0.0 {
            continue;
        }
        let (a, b) = (bsdf.f(wo, wi), got.f(local(wo), local(wi)));
        assert!(
            (a - b).abs().max_element() <= 1e-4 * b.max_element() + 1e-7,
            "{a} {b}"
        );
        let (a, b) = (bsdf.pdf(wo, wi), got.pdf(local(wo), local(wi)));
        assert!((a - b).abs() <= 1e-4 * b + 1e-7, "{a} {b}");
    }
}

/// pbrt-v3's precedence: sigma_a, else color, else the melanins, else eumelanin 1.3; each
/// parameter that loses warns at its location, and the defaults are pbrt-v3's.
#[test]
fn absorption_follows_pbrt_v3_precedence() {
    let si = curve_hit(0.5);
    let sigma_of = |m: &[Material]| hair_of(m).bxdf(&si).0.sigma_a;

    let (m, w, _) = build(r#"Material "hair""#).unwrap();
    assert!(w.is_empty(), "{w:?}");
    let h = hair_of(&m);
    assert_eq!(
        h.sigma_a.as_ref().and_then(Texture::as_constant),
        Some(sigma_a_from_concentration(1.3, 0.0))
    );
    assert!(h.color.is_none() && h.eumelanin.is_none() && h.pheomelanin.is_none());
    let consts = [&h.eta, &h.beta_m, &h.beta_n, &h.alpha].map(|t| t.as_constant());
    assert_eq!(consts, [Some(1.55), Some(0.3), Some(0.3), Some(2.0)]);

    let (m, w, _) = build(
        r#"Material "hair" "rgb sigma_a" [0.1 -0.2 0.3] "rgb color" [0.5 0.5 0.5]
               "float eumelanin" 2 "float pheomelanin" 1"#,
    )
    .unwrap();
    assert_eq!(w.len(), 3, "{w:?}");
    for (warning, name) in w.iter().zip(["color", "eumelanin", "pheomelanin"]) {
        assert_eq!(
            warning.message,
            format!("Ignoring \"{name}\" parameter since \"sigma_a\" was provided.")
        );
        assert!(warning.loc.is_some());
    }
    // Negative absorption is clamped to zero, as pbrt-v3's Spectrum::Clamp.
    assert_eq!(sigma_of(&m), Spectrum::new(0.1, 0.0, 0.3));

    let (m, w, _) = build(
        r#"Material "hair" "rgb color" [0.3 0.2 0.1] "float beta_n" 0.5
               "float pheomelanin" 1"#,
    )
    .unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0]
        .message
        .contains("\"pheomelanin\" parameter since \"color\""));
    let want = sigma_a_from_reflectance(Spectrum::new(0.3, 0.2, 0.1), 0.5);
    assert_eq!(sigma_of(&m), want);
    // The albedo feature gives the colour back.
    let a = hair_of(&m).bxdf(&si).0.albedo();
    assert!(
        (a - Spectrum::new(0.3, 0.2, 0.1)).abs().max_element() < 1e-5,
        "{a}"
    );

    let (m, w, _) = build(r#"Material "hair" "float pheomelanin" 0.8"#).unwrap();
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(sigma_of(&m), sigma_a_from_concentration(0.0, 0.8));
    let (m, _, _) = build(r#"Material "hair" "float eumelanin" -1 "float pheomelanin" 2"#).unwrap();
    assert_eq!(sigma_of(&m), sigma_a_from_concentration(0.0, 2.0));

    // Textured parameters are evaluated at the hit.
    let (m, w, _) = build(
        r#"Texture "e" "float" "constant" "float value" 0.4
               Texture "c" "spectrum" "constant" "rgb value" [0.6 0.5 0.4]
               Material "hair" "texture eumelanin" "e" "texture beta_m" "e""#,
    )
    .unwrap();
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(sigma_of(&m), sigma_a_from_concentration(0.4, 0.0));
    assert_eq!(
        hair_of(&m).bxdf(&si).0.v0,
        HairBsdf::new(0.0, 1.55, Spectrum::ZERO, 0.4, 0.3, 2.0).v0
    );
}

/// Constants on which pbrt-v3 aborts are located errors; a bumpmap is not read (pbrt-v3's
/// hair has none), so it is reported unused; hair mixes like any material.
#[test]
fn bad_parameters_fail_and_bumpmap_is_unused() {
    for (param, what) in [
        (r#""float beta_m" 0"#, "beta_m"),
        (r#""float beta_m" 1.5"#, "beta_m"),
        (r#""float beta_n" -0.1"#, "beta_n"),
        (r#""float eta" 0.9"#, "eta"),
    ] {
        let e = build(&format!("Material \"hair\" {param}")).unwrap_err();
        assert!(matches!(e, Error::At { .. }), "{e}");
        assert!(e.message().contains(&format!("hair \"{what}\"")), "{e}");
    }
    let (m, w, unused) = build(
        r#"Texture "b" "float" "constant" "float value" 0.1
               Material "hair" "texture bumpmap" "b" "float beta_m" 1"#,
    )
    .unwrap();
    assert!(w.is_empty(), "{w:?}");
    assert!(matches!(m.last(), Some(Material::Hair(_))));
    assert!(
        unused.iter().any(|u| u.message.contains("bumpmap")),
        "{unused:?}"
    );

    let (m, _, _) = build(
        r#"MakeNamedMaterial "a" "string type" "hair"
               MakeNamedMaterial "b" "string type" "matte"
               MakeNamedMaterial "m" "string type" "mix" "string namedmaterial1" "a"
                 "string namedmaterial2" "b"
               NamedMaterial "m""#,
    )
    .unwrap();
    let b: Bsdf = m.last().unwrap().bsdf(&curve_hit(0.5));
    assert_eq!(b.num_lobes(), 2);
    assert!(matches!(b.lobes()[0].bxdf, Bxdf::Hair(_)));
    assert!((b.eta() - 1.55).abs() < 1e-6);
}
