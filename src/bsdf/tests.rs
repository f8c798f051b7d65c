//! Tests of the BSDFs: lobes, frames, sampling against evaluation.

use super::check::*;
use super::*;
use crate::microfacet::TrowbridgeReitz;
use std::f32::consts::FRAC_1_PI;

fn local_bsdf(bxdfs: &[Bxdf], eta: f32) -> Bsdf {
    let mut b = Bsdf::from_frame(Frame::from_z(Vec3::Z), Vec3::Z, eta);
    for &x in bxdfs {
        assert!(b.add(x));
    }
    b
}

fn ggx(ax: f32, ay: f32) -> TrowbridgeReitz {
    TrowbridgeReitz::new(ax, ay)
}

/// Every non-specular lobe with typical, white parameters.
fn non_specular_lobes() -> Vec<(&'static str, Bxdf)> {
    let conductor = Fresnel::Conductor {
        eta_i: Spectrum::ONE,
        eta_t: Spectrum::new(0.200438, 0.924033, 1.10221),
        k: Spectrum::new(3.91295, 2.45285, 2.14219),
    };
    vec![
        ("lambertian", Bxdf::Lambertian { r: Spectrum::ONE }),
        ("oren-nayar", Bxdf::oren_nayar(Spectrum::ONE, 20.0)),
        (
            "microfacet-dielectric",
            Bxdf::MicrofacetReflection {
                r: Spectrum::ONE,
                distribution: ggx(0.3, 0.3),
                fresnel: Fresnel::Dielectric {
                    eta_i: 1.0,
                    eta_t: 1.5,
                },
            },
        ),
        (
            "microfacet-conductor-aniso",
            Bxdf::MicrofacetReflection {
                r: Spectrum::ONE,
                distribution: ggx(0.2, 0.6),
                fresnel: conductor,
            },
        ),
        (
            "microfacet-noop-rough",
            Bxdf::MicrofacetReflection {
                r: Spectrum::ONE,
                distribution: ggx(0.8, 0.8),
                fresnel: Fresnel::NoOp,
            },
        ),
        (
            "microfacet-transmission",
            Bxdf::MicrofacetTransmission {
                t: Spectrum::ONE,
                distribution: ggx(0.3, 0.4),
                eta_a: 1.0,
                eta_b: 1.5,
            },
        ),
        (
            "fresnel-blend",
            Bxdf::FresnelBlend {
                rd: Spectrum::ONE,
                rs: Spectrum::splat(0.04),
                distribution: ggx(0.25, 0.25),
            },
        ),
        (
            "lambertian transmission",
            Bxdf::LambertianTransmission { t: Spectrum::ONE },
        ),
        (
            "hair",
            Bxdf::Hair(super::hair::HairBsdf::new(
                0.3,
                1.55,
                Spectrum::ZERO,
                0.3,
                0.3,
                2.0,
            )),
        ),
    ]
}

#[test]
fn fresnel_dielectric_normal_incidence_and_tir() {
    for n in [1.33f32, 1.5, 2.4] {
        let want = ((n - 1.0) / (n + 1.0)).powi(2);
        assert!((fr_dielectric(1.0, 1.0, n) - want).abs() < 1e-6);
        // From inside, at normal incidence: the same.
        assert!((fr_dielectric(-1.0, 1.0, n) - want).abs() < 1e-6);
        // Beyond the critical angle from inside: total internal reflection.
        let crit = (1.0 / n).asin();
        let cos = -(crit + 0.05).cos();
        assert_eq!(fr_dielectric(cos, 1.0, n), 1.0);
        // Just inside the critical angle: partial.
        assert!(fr_dielectric(-(crit - 0.05).cos(), 1.0, n) < 1.0);
    }
    // Grazing from outside reflects everything; matched indices reflect nothing.
    assert!((fr_dielectric(0.0, 1.0, 1.5) - 1.0).abs() < 1e-6);
    assert_eq!(fr_dielectric(0.7, 1.5, 1.5), 0.0);
}

#[test]
fn fresnel_conductor_limits() {
    // k = 0 makes a conductor a dielectric.
    let r = fr_conductor(1.0, Spectrum::ONE, Spectrum::splat(1.5), Spectrum::ZERO);
    assert!((r.x - 0.04).abs() < 1e-5, "{r}");
    let r = fr_conductor(0.6, Spectrum::ONE, Spectrum::splat(1.5), Spectrum::ZERO);
    assert!((r.x - fr_dielectric(0.6, 1.0, 1.5)).abs() < 1e-5, "{r}");
    // Copper at normal incidence: ((n-1)² + k²) / ((n+1)² + k²).
    let (n, k) = (0.2f32, 3.9f32);
    let want = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
    let r = fr_conductor(1.0, Spectrum::ONE, Spectrum::splat(n), Spectrum::splat(k));
    assert!((r.x - want).abs() < 1e-4, "{r} {want}");
    // Grazing reflects everything.
    let r = fr_conductor(0.0, Spectrum::ONE, Spectrum::splat(n), Spectrum::splat(k));
    assert!((r.x - 1.0).abs() < 1e-4, "{r}");
}

#[test]
fn refraction_obeys_snell() {
    let wo = Vec3::new(0.6, 0.0, 0.8);
    let wt = refract(wo, Vec3::Z, 1.0 / 1.5).unwrap();
    assert!((wt.length() - 1.0).abs() < 1e-5);
    assert!(wt.z < 0.0);
    assert!((wt.x.abs() * 1.5 - 0.6).abs() < 1e-5, "{wt}");
    assert!(refract(Vec3::new(0.9, 0.0, 0.436), Vec3::Z, 1.5).is_none());
}

#[test]
fn non_specular_sampling_matches_evaluation() {
    for (name, bxdf) in non_specular_lobes() {
        let b = local_bsdf(&[bxdf], 1.5);
        for (k, wo) in test_directions().into_iter().enumerate() {
            sample_matches_eval(&b, wo, 2000, 7 + k as u64);
            let _ = name;
        }
    }
    // And mixtures of lobes (the combined pdf and f).
    let lobes = non_specular_lobes();
    let b = local_bsdf(&[lobes[0].1, lobes[2].1, lobes[5].1], 1.5);
    for wo in test_directions() {
        sample_matches_eval(&b, wo, 2000, 3);
    }
}

#[test]
fn pdfs_integrate_to_the_sampling_success_rate() {
    for (name, bxdf) in non_specular_lobes() {
        let b = local_bsdf(&[bxdf], 1.5);
        for (k, wo) in test_directions().into_iter().enumerate() {
            let (integral, se, success) = pdf_integral(&b, wo, 200, 11 + k as u64);
            // Monte Carlo error of both estimates, with a margin.
            let tol = 4.0 * se + 0.01;
            if matches!(bxdf, Bxdf::MicrofacetTransmission { .. }) && wo.z.abs() < 0.2 {
                // pbrt-v3's transmission pdf also counts microfacets that face away from a
                // grazing wo, which its sampler never picks: a few percent too much.
                assert!(
                    integral < 1.1 && integral + tol > success,
                    "{name} {wo}: {integral}"
                );
                continue;
            }
            assert!(
                integral <= 1.0 + tol,
                "{name} {wo}: ∫pdf = {integral} ± {se}"
            );
            assert!(
                (integral - success).abs() < tol,
                "{name} {wo}: ∫pdf = {integral} ± {se}, success rate {success}"
            );
            if matches!(bxdf, Bxdf::Lambertian { .. } | Bxdf::OrenNayar { .. }) {
                assert!((integral - 1.0).abs() < 0.01, "{name} {wo}: {integral}");
            }
        }
    }
}

#[test]
fn white_lobes_conserve_energy() {
    for (name, bxdf) in non_specular_lobes() {
        let b = local_bsdf(&[bxdf], 1.5);
        for (k, wo) in test_directions().into_iter().enumerate() {
            if wo.z < 0.0 && bxdf.kind().contains(BxdfType::TRANSMISSION) {
                // Leaving a denser medium, radiance grows by (eta_i / eta_t)²: not a loss.
                continue;
            }
            let (a, se) = albedo(&b, wo, 20_000, 5 + k as u64);
            assert!(
                a.max_element() <= 1.0 + 3.0 * se + 1e-3,
                "{name} {wo}: albedo {a} ± {se}"
            );
        }
    }
    // Lambertian white reflects everything.
    let b = local_bsdf(&[Bxdf::Lambertian { r: Spectrum::ONE }], 1.0);
    let (a, _) = albedo(&b, Vec3::new(0.3, 0.1, 0.9).normalize(), 1000, 1);
    assert!((a - Spectrum::ONE).abs().max_element() < 1e-4, "{a}");
}

#[test]
fn reflection_lobes_are_reciprocal() {
    let mut rng = Rng::new(99);
    for (name, bxdf) in non_specular_lobes() {
        if bxdf.kind().contains(BxdfType::TRANSMISSION) {
            continue;
        }
        for _ in 0..500 {
            let a = crate::sampling::cosine_sample_hemisphere(rng.next_2d());
            let b = crate::sampling::cosine_sample_hemisphere(rng.next_2d());
            if a.z < 1e-3 || b.z < 1e-3 {
                continue;
            }
            let (fab, fba) = (bxdf.f(a, b), bxdf.f(b, a));
            for c in 0..3 {
                assert!(
                    (fab[c] - fba[c]).abs() <= 1e-4 * fab[c].abs().max(1.0),
                    "{name}: f({a},{b}) = {fab} vs {fba}"
                );
            }
        }
    }
}

#[test]
fn fresnel_specular_chooses_by_fresnel_and_weights_correctly() {
    let (eta_a, eta_b) = (1.0f32, 1.5f32);
    let r = Spectrum::new(1.0, 0.8, 0.6);
    let t = Spectrum::new(0.5, 0.7, 0.9);
    let lobe = Bxdf::FresnelSpecular { r, t, eta_a, eta_b };
    for wo in test_directions() {
        let fr = fr_dielectric(wo.z, eta_a, eta_b);
        let n = 10_000;
        let (mut reflected, mut p_sum) = (0usize, 0.0f64);
        for i in 0..n {
            let u = Vec2::new((i as f32 + 0.5) / n as f32, 0.5);
            let s = lobe.sample_f(wo, u).unwrap();
            let w = s.f * s.wi.z.abs() / s.pdf;
            if s.kind.contains(BxdfType::REFLECTION) {
                reflected += 1;
                assert!((s.pdf - fr).abs() < 1e-6);
                assert!((w - r).abs().max_element() < 1e-4, "{w}");
                assert!(s.wi.z * wo.z > 0.0);
            } else {
                assert!((s.pdf - (1.0 - fr)).abs() < 1e-6);
                let (ei, et) = if wo.z > 0.0 {
                    (eta_a, eta_b)
                } else {
                    (eta_b, eta_a)
                };
                assert!(
                    (w - t * (ei * ei) / (et * et)).abs().max_element() < 1e-4,
                    "{w}"
                );
                assert!(s.wi.z * wo.z < 0.0);
            }
            p_sum += s.pdf as f64;
        }
        // The two events' probabilities sum to one, and each is chosen that often.
        let frac = reflected as f64 / n as f64;
        assert!((frac - fr as f64).abs() < 2e-3, "{wo}: {frac} vs {fr}");
        let mean_p = p_sum / n as f64;
        let want = (fr * fr + (1.0 - fr) * (1.0 - fr)) as f64;
        assert!((mean_p - want).abs() < 2e-3);
    }
}

#[test]
fn specular_lobes_sample_deltas() {
    let mirror = Bxdf::SpecularReflection {
        r: Spectrum::splat(0.9),
        fresnel: Fresnel::NoOp,
    };
    let b = local_bsdf(&[mirror], 1.0);
    let wo = Vec3::new(0.3, 0.4, 0.866).normalize();
    let s = b.sample_f(wo, Vec2::new(0.3, 0.6), 0.2).unwrap();
    assert!(s.specular && s.pdf == 1.0);
    assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
    assert!(
        (s.f * s.wi.z / s.pdf - Spectrum::splat(0.9))
            .abs()
            .max_element()
            < 1e-5
    );
    assert_eq!(b.f(wo, s.wi), Spectrum::ZERO);
    assert_eq!(b.pdf(wo, s.wi), 0.0);
    assert!(!b.has_non_specular());

    // Specular transmission scales radiance by (eta_i / eta_t)².
    let tr = Bxdf::SpecularTransmission {
        t: Spectrum::ONE,
        eta_a: 1.0,
        eta_b: 1.5,
    };
    let s = tr.sample_f(Vec3::Z, Vec2::ZERO).unwrap();
    let w = s.f * s.wi.z.abs() / s.pdf;
    assert!((w.x - (1.0 - 0.04) / 2.25).abs() < 1e-5, "{w}");
    assert!((s.wi + Vec3::Z).length() < 1e-6);
    // Total internal reflection from inside: nothing.
    assert!(tr
        .sample_f(Vec3::new(0.9, 0.0, -0.436).normalize(), Vec2::ZERO)
        .is_none());

    // Mixed with a diffuse lobe, the delta is chosen half the time with pdf 1/2.
    let b = local_bsdf(&[Bxdf::Lambertian { r: Spectrum::ONE }, mirror], 1.0);
    let s = b.sample_f(wo, Vec2::new(0.3, 0.6), 0.75).unwrap();
    assert!(s.specular && (s.pdf - 0.5).abs() < 1e-6);
    let s = b.sample_f(wo, Vec2::new(0.3, 0.6), 0.25).unwrap();
    assert!(!s.specular);
    assert!((s.pdf - 0.5 * s.wi.z * FRAC_1_PI).abs() < 1e-6);
    assert!(b.has_non_specular());
}

#[test]
fn geometric_normal_decides_reflection() {
    // Shading normal tilted from the geometric one: a direction above the shading
    // hemisphere but below the geometric one is treated as transmission.
    let ns = Vec3::new(0.3, 0.0, 1.0).normalize();
    let mut b = Bsdf::from_frame(Frame::from_z(ns), Vec3::Z, 1.0);
    b.add(Bxdf::Lambertian { r: Spectrum::ONE });
    let wo = Vec3::new(0.0, 0.0, 1.0);
    let wi = Vec3::new(0.99, 0.0, -0.1).normalize();
    assert!(wi.dot(ns) > 0.0);
    assert_eq!(b.f(wo, wi), Spectrum::ZERO);
    assert!(b.pdf(wo, wi) > 0.0);
}

#[test]
fn degenerate_inputs_give_no_nan() {
    let mut all: Vec<Bxdf> = non_specular_lobes().into_iter().map(|(_, b)| b).collect();
    all.push(Bxdf::FresnelSpecular {
        r: Spectrum::ONE,
        t: Spectrum::ONE,
        eta_a: 1.0,
        eta_b: 1.5,
    });
    all.push(Bxdf::SpecularTransmission {
        t: Spectrum::ONE,
        eta_a: 1.0,
        eta_b: 1.5,
    });
    all.push(Bxdf::MicrofacetReflection {
        r: Spectrum::ONE,
        distribution: TrowbridgeReitz::new(0.0, 0.0),
        fresnel: Fresnel::NoOp,
    });
    let dirs = degenerate_directions();
    let us = edge_samples();
    for bxdf in all {
        let b = local_bsdf(&[bxdf], 1.5);
        for wo in dirs {
            for wi in dirs {
                assert!(b.f(wo, wi).is_finite(), "{bxdf:?} {wo} {wi}");
                assert!(b.pdf(wo, wi).is_finite(), "{bxdf:?} {wo} {wi}");
            }
            for u in us {
                if let Some(s) = b.sample_f(wo, u, 0.5) {
                    assert!(s.f.is_finite() && s.pdf.is_finite() && s.wi.is_finite());
                    assert!(s.pdf > 0.0);
                }
            }
        }
    }
    let empty = local_bsdf(&[], 1.0);
    assert!(empty.sample_f(Vec3::Z, Vec2::splat(0.5), 0.5).is_none());
    assert_eq!(empty.pdf(Vec3::Z, Vec3::Z), 0.0);
    assert_eq!(empty.f(Vec3::Z, Vec3::Z), Spectrum::ZERO);
}

#[test]
fn at_most_eight_lobes() {
    let mut b = local_bsdf(&[], 1.0);
    for _ in 0..MAX_LOBES {
        assert!(b.add(Bxdf::Lambertian { r: Spectrum::ONE }));
    }
    assert!(!b.add(Bxdf::Lambertian { r: Spectrum::ONE }));
    assert_eq!(b.num_lobes(), MAX_LOBES);
    b.scale_lobes(Spectrum::splat(0.5));
    assert!(b.lobes().iter().all(|l| l.scale == Spectrum::splat(0.5)));
}

#[test]
fn world_frame_follows_the_shading_tangent() {
    let si = SurfaceInteraction {
        p: Vec3::ZERO,
        n: Vec3::Y,
        uv: Vec2::ZERO,
        dpdu: Vec3::X,
        dpdv: Vec3::Z,
        shading_n: Vec3::Y,
        shading_dpdu: Vec3::X,
        shading_dpdv: Vec3::Y,
        dndu: Vec3::ZERO,
        dndv: Vec3::ZERO,
        wo: Vec3::Y,
        time: 0.0,
        p_error: 0.0,
        diff: Default::default(),
    };
    let b = Bsdf::new(&si, 1.0);
    assert!((b.frame().n - Vec3::Y).length() < 1e-6);
    assert!((b.frame().s - Vec3::X).length() < 1e-6);
    // Anisotropic roughness follows the tangent: a highlight stretched along dpdu.
    let mut b = Bsdf::new(&si, 1.0);
    b.add(Bxdf::MicrofacetReflection {
        r: Spectrum::ONE,
        distribution: TrowbridgeReitz::new(0.5, 0.05),
        fresnel: Fresnel::NoOp,
    });
    let wo = Vec3::Y;
    let along_u = b.f(wo, Vec3::new(0.2, 1.0, 0.0).normalize());
    let along_v = b.f(wo, Vec3::new(0.0, 1.0, 0.2).normalize());
    assert!(along_u.x > 10.0 * along_v.x, "{along_u} {along_v}");
}

#[test]
fn lobes_said_to_sample_their_value_do_so_bit_for_bit() {
    // `Bsdf::sample_f` takes such a lobe's value from its sample instead of evaluating it
    // again: the images stay the same only if the two agree exactly.
    let adapter = Bxdf::BssrdfAdapter {
        eta: 1.33,
        scale: crate::bssrdf::adapter::adapter_scale(1.33),
    };
    let mut rng = Rng::new(11);
    let mut kinds = 0;
    for (name, bxdf) in non_specular_lobes()
        .into_iter()
        .chain([("adapter", adapter)])
    {
        if !bxdf.sample_is_f() {
            continue;
        }
        kinds += 1;
        let mut sampled = 0;
        for wo in test_directions() {
            for _ in 0..2000 {
                if let Some(s) = bxdf.sample_f(wo, rng.next_2d()) {
                    assert_eq!(s.f, bxdf.f(wo, s.wi), "{name}: wo {wo} wi {}", s.wi);
                    sampled += 1;
                }
            }
        }
        assert!(sampled > 1000, "{name}: {sampled} samples");
    }
    assert_eq!(kinds, 9);
}

#[test]
fn a_refilled_bsdf_is_a_fresh_one() {
    let si = SurfaceInteraction {
        shading_n: Vec3::new(0.1, 0.0, 1.0).normalize(),
        ..SurfaceInteraction::flat(Vec3::ZERO, Vec2::ZERO)
    };
    let lobes = non_specular_lobes();
    // Three lobes, then refilled with two: the third slot still holds a lobe, never read.
    let mut kept = local_bsdf(&[lobes[2].1, lobes[5].1, lobes[6].1], 1.5);
    kept.reset(&si, 1.0);
    assert_eq!(kept.num_lobes(), 0);
    assert!(kept.sample_f(Vec3::Z, Vec2::splat(0.5), 0.5).is_none());
    let mut fresh = Bsdf::new(&si, 1.0);
    for b in [&mut kept, &mut fresh] {
        b.add(lobes[0].1);
        b.add_scaled(lobes[3].1, Spectrum::new(0.2, 0.5, 0.7));
    }
    assert_eq!(kept.lobes(), fresh.lobes());
    assert_eq!(kept.eta(), 1.0);
    let mut rng = Rng::new(5);
    for wo in test_directions() {
        for _ in 0..500 {
            let (u, u_lobe, wi) = (rng.next_2d(), rng.next_f32(), test_directions()[1]);
            let (a, b) = (kept.sample_f(wo, u, u_lobe), fresh.sample_f(wo, u, u_lobe));
            assert_eq!(a.map(|s| (s.wi, s.f, s.pdf)), b.map(|s| (s.wi, s.f, s.pdf)));
            assert_eq!(kept.f(wo, wi), fresh.f(wo, wi));
            assert_eq!(kept.pdf(wo, wi), fresh.pdf(wo, wi));
        }
    }
}
