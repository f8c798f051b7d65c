//! Tests of the materials: building from scene descriptions, lobes, defaults and errors.

use super::build::{used_materials, MaterialBuilder};
use super::*;
use crate::bsdf::check::*;
use crate::bsdf::Bxdf;
use crate::geometry::{Vec2, Vec3};
use crate::texture::TextureBuilder;
use acr_parser::{parse_str, Error, Warning};
use std::path::Path;

fn si() -> SurfaceInteraction {
    SurfaceInteraction::flat(Vec3::new(0.1, 0.2, 0.0), Vec2::new(0.3, 0.6))
}

/// Parses world-block text and builds its materials, every one used by a shape.
fn build(text: &str) -> (Vec<Material>, Vec<Warning>) {
    build_in(text, Path::new("/tmp"))
}

fn build_in(text: &str, dir: &Path) -> (Vec<Material>, Vec<Warning>) {
    let full = format!("WorldBegin\n{text}\nWorldEnd\n");
    let desc = parse_str(&full, &dir.join("scene.pbrt")).unwrap();
    let mut w = Vec::new();
    let m = build_materials(&desc, dir, glam::DMat4::IDENTITY, &mut w).unwrap();
    (m, w)
}

fn build_err(text: &str) -> Error {
    let full = format!("WorldBegin\n{text}\nWorldEnd\n");
    let desc = parse_str(&full, Path::new("/tmp/scene.pbrt")).unwrap();
    build_materials(
        &desc,
        Path::new("/tmp"),
        glam::DMat4::IDENTITY,
        &mut Vec::new(),
    )
    .unwrap_err()
}

const SHAPE: &str = r#"Shape "sphere""#;

/// Every material with typical (white where it matters) parameters.
fn typical() -> Vec<(&'static str, String)> {
    [
            ("matte", r#"Material "matte" "rgb Kd" [1 1 1]"#),
            ("matte-oren-nayar", r#"Material "matte" "rgb Kd" [1 1 1] "float sigma" 30"#),
            ("plastic", r#"Material "plastic" "rgb Kd" [0.5 0.5 0.5] "rgb Ks" [0.5 0.5 0.5]"#),
            ("plastic-smooth", r#"Material "plastic" "float roughness" 0.01"#),
            ("metal", r#"Material "metal""#),
            ("metal-aniso", r#"Material "metal" "float uroughness" 0.05 "float vroughness" 0.3"#),
            ("metal-raw", r#"Material "metal" "float roughness" 0.3 "bool remaproughness" false"#),
            ("glass-rough", r#"Material "glass" "float uroughness" 0.2 "float vroughness" 0.2"#),
            ("uber", r#"Material "uber" "rgb Kd" [0.5 0.5 0.5] "rgb Ks" [0.5 0.5 0.5]"#),
            (
                "uber-translucent",
                r#"Material "uber" "rgb Kd" [0.5 0.5 0.5] "rgb opacity" [0.5 0.5 0.5]"#,
            ),
            ("substrate", r#"Material "substrate" "rgb Kd" [1 1 1] "rgb Ks" [0.04 0.04 0.04]"#),
            (
                "mix",
                r#"MakeNamedMaterial "a" "string type" "matte" "rgb Kd" [1 1 1]
                   MakeNamedMaterial "b" "string type" "plastic" "rgb Kd" [0.5 0.5 0.5] "rgb Ks" [0.5 0.5 0.5]
                   MakeNamedMaterial "m" "string type" "mix" "string namedmaterial1" "a"
                     "string namedmaterial2" "b" "rgb amount" [0.3 0.5 0.7]
                   NamedMaterial "m""#,
            ),
        ]
        .into_iter()
        .map(|(n, t)| (n, format!("{t}\n{SHAPE}")))
        .collect()
}

#[test]
fn typical_materials_sample_consistently_and_conserve_energy() {
    for (name, text) in typical() {
        let (mats, warnings) = build(&text);
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        let m = mats.last().unwrap();
        let bsdf = m.bsdf(&si());
        assert!(bsdf.num_lobes() > 0, "{name}");
        assert!(bsdf.has_non_specular(), "{name}");
        for (k, wo) in test_directions().into_iter().enumerate() {
            sample_matches_eval(&bsdf, wo, 1000, 17 + k as u64);
            let (integral, se, success) = pdf_integral(&bsdf, wo, 120, 3 + k as u64);
            let tol = 4.0 * se + 0.01;
            let transmits = bsdf
                .lobes()
                .iter()
                .any(|l| matches!(l.bxdf, Bxdf::MicrofacetTransmission { .. }));
            if transmits && wo.z.abs() < 0.2 {
                // pbrt-v3's rough transmission pdf counts back-facing microfacets at grazing
                // angles, which its sampler never picks (see the bsdf tests).
                assert!(integral < 1.1, "{name} {wo}: ∫pdf = {integral}");
            } else {
                assert!(
                    integral <= 1.0 + tol && (integral - success).abs() < tol,
                    "{name} {wo}: ∫pdf = {integral} ± {se}, success rate {success}"
                );
            }
            if wo.z > 0.0 {
                let (a, se) = albedo(&bsdf, wo, 10_000, 5 + k as u64);
                assert!(
                    a.max_element() <= 1.0 + 3.0 * se + 1e-3,
                    "{name} {wo}: albedo {a} ± {se}"
                );
            }
        }
    }
}

#[test]
fn defaults_follow_pbrt_v3() {
    let (m, _) = build(&format!("Material \"plastic\"\n{SHAPE}"));
    let Material::Plastic(Plastic {
        kd,
        ks,
        roughness,
        remap_roughness,
    }) = m.last().unwrap()
    else {
        panic!()
    };
    assert_eq!(kd.as_constant(), Some(Spectrum::splat(0.25)));
    assert_eq!(ks.as_constant(), Some(Spectrum::splat(0.25)));
    assert_eq!(roughness.as_constant(), Some(0.1));
    assert!(remap_roughness);

    let (m, _) = build(&format!("Material \"metal\"\n{SHAPE}"));
    let Material::Metal(Metal {
        eta,
        k,
        roughness,
        u_roughness,
        ..
    }) = m.last().unwrap()
    else {
        panic!()
    };
    assert_eq!(eta.as_constant(), Some(COPPER_ETA));
    assert_eq!(k.as_constant(), Some(COPPER_K));
    assert_eq!(roughness.as_constant(), Some(0.01));
    assert!(u_roughness.is_none());

    // The default material (index 0) is matte 0.5.
    let Material::Matte(Matte { kd, sigma }) = &m[0] else {
        panic!()
    };
    assert_eq!(kd.as_constant(), Some(Spectrum::splat(0.5)));
    assert_eq!(sigma.as_constant(), Some(0.0));

    // Glass takes "eta", or else "index".
    let (m, _) = build(&format!("Material \"glass\" \"float index\" 1.33\n{SHAPE}"));
    let Material::Glass(Glass { eta, .. }) = m.last().unwrap() else {
        panic!()
    };
    assert_eq!(eta.as_constant(), Some(1.33));
    let (m, _) = build(&format!("Material \"glass\" \"float eta\" 2.4\n{SHAPE}"));
    let Material::Glass(Glass { eta, .. }) = m.last().unwrap() else {
        panic!()
    };
    assert_eq!(eta.as_constant(), Some(2.4));
}

#[test]
fn smooth_glass_is_one_fresnel_specular_lobe() {
    let (m, _) = build(&format!("Material \"glass\"\n{SHAPE}"));
    let b = m.last().unwrap().bsdf(&si());
    assert_eq!(b.num_lobes(), 1);
    assert!(!b.has_non_specular());
    assert!((b.eta() - 1.5).abs() < 1e-6);
    assert!(matches!(b.lobes()[0].bxdf, Bxdf::FresnelSpecular { .. }));
    // Reflection and transmission probabilities sum to one over many samples.
    let wo = Vec3::new(0.3, 0.0, 0.954).normalize();
    let mut rng = Rng::new(4);
    let n = 20_000;
    let mut reflected = 0;
    for _ in 0..n {
        let s = b.sample_f(wo, rng.next_2d(), rng.next_f32()).unwrap();
        assert!(s.specular);
        if s.wi.z > 0.0 {
            reflected += 1;
            assert!((s.f * s.wi.z / s.pdf - Spectrum::ONE).abs().max_element() < 1e-4);
        } else {
            let w = s.f * s.wi.z.abs() / s.pdf;
            assert!(
                (w - Spectrum::splat(1.0 / 2.25)).abs().max_element() < 1e-4,
                "{w}"
            );
        }
    }
    let fr = crate::bsdf::fr_dielectric(wo.z, 1.0, 1.5);
    assert!((reflected as f32 / n as f32 - fr).abs() < 0.005);
    // Without multiple lobes: separate specular reflection and transmission.
    let b = m.last().unwrap().bsdf_with(&si(), false);
    assert_eq!(b.num_lobes(), 2);
}

#[test]
fn mirror_and_uber_specular_lobes() {
    let (m, _) = build(&format!("Material \"mirror\"\n{SHAPE}"));
    let b = m.last().unwrap().bsdf(&si());
    let s = b.sample_f(Vec3::Z, Vec2::splat(0.5), 0.5).unwrap();
    assert!(s.specular);
    assert!(
        (s.f * s.wi.z / s.pdf - Spectrum::splat(0.9))
            .abs()
            .max_element()
            < 1e-5
    );

    let (m, _) = build(&format!(
            "Material \"uber\" \"rgb Kr\" [1 1 1] \"rgb Kt\" [1 1 1] \"rgb opacity\" [0.25 0.25 0.25]\n{SHAPE}"
        ));
    let b = m.last().unwrap().bsdf(&si());
    // Straight-through transmission, diffuse, glossy, specular reflection and transmission.
    assert_eq!(b.num_lobes(), 5);
    assert_eq!(b.eta(), 1.0);
    let Bxdf::SpecularTransmission { t, eta_a, eta_b } = b.lobes()[0].bxdf else {
        panic!()
    };
    assert_eq!((t, eta_a, eta_b), (Spectrum::splat(0.75), 1.0, 1.0));
}

#[test]
fn mix_scales_first_by_amount() {
    let text = format!(
        r#"MakeNamedMaterial "a" "string type" "matte" "rgb Kd" [1 1 1]
               MakeNamedMaterial "b" "string type" "matte" "rgb Kd" [0 1 0]
               MakeNamedMaterial "m" "string type" "mix" "string namedmaterial1" "a"
                 "string namedmaterial2" "b" "float amount" 0.25
               NamedMaterial "m"
               {SHAPE}"#
    );
    // A float amount is not a spectrum: pbrt-v3 ignores it (default 0.5) and so does acr.
    let (m, _) = build(&text);
    let b = m.last().unwrap().bsdf(&si());
    assert_eq!(b.num_lobes(), 2);
    let f = b.f(Vec3::Z, Vec3::Z);
    assert!(
        (f - Spectrum::new(0.5, 1.0, 0.5) / std::f32::consts::PI)
            .abs()
            .max_element()
            < 1e-6
    );

    let text = text.replace("\"float amount\" 0.25", "\"rgb amount\" [0.25 0.25 0.25]");
    let (m, _) = build(&text);
    let b = m.last().unwrap().bsdf(&si());
    assert_eq!(b.lobes()[0].scale, Spectrum::splat(0.25));
    assert_eq!(b.lobes()[1].scale, Spectrum::splat(0.75));
    let f = b.f(Vec3::Z, Vec3::Z) * std::f32::consts::PI;
    assert!(
        (f - Spectrum::new(0.25, 1.0, 0.25)).abs().max_element() < 1e-6,
        "{f}"
    );
}

#[test]
fn textured_parameters_vary_over_the_surface() {
    let text = format!(
        r#"Texture "c" "spectrum" "checkerboard" "float uscale" 2 "float vscale" 2
                 "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]
               Material "matte" "texture Kd" "c"
               {SHAPE}"#
    );
    let (m, _) = build(&text);
    let mut s = si();
    s.uv = Vec2::new(0.1, 0.1);
    let a = m.last().unwrap().bsdf(&s).f(Vec3::Z, Vec3::Z);
    s.uv = Vec2::new(0.6, 0.1);
    let b = m.last().unwrap().bsdf(&s).f(Vec3::Z, Vec3::Z);
    assert!(
        a.x > 0.0 && a.z == 0.0 && b.x == 0.0 && b.z > 0.0,
        "{a} {b}"
    );
}

#[test]
fn unsupported_parameters_warn_once_and_unknown_types_fail() {
    let (m, w) = build(&format!(
        r#"Texture "bump" "float" "constant"
               Material "matte" "texture bumpmap" "bump" "texture normalmap" "bump"
               {SHAPE}
               Material "plastic" "texture bumpmap" "bump" "texture normalmap" "bump"
               {SHAPE}"#
    ));
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].message.contains("normalmap") && w[0].loc.is_some());
    // bumpmap is built (docs/pbrt-v3-compatibility.md): every material carries it.
    let bumped = m.iter().filter(|m| matches!(m, Material::Bumped { .. }));
    assert_eq!(bumped.count(), 2, "{m:?}");

    let e = build_err(&format!("Material \"platic\"\n{SHAPE}"));
    assert!(e.message().contains("unknown material \"platic\""), "{e}");
    assert!(e.message().contains("plastic"), "{e}");
    assert!(matches!(e, Error::At { .. }));

    // fourier reads its table (docs/pbrt-v3-compatibility.md): without one, a located error.
    let e = build_err(&format!(
        "Material \"fourier\" \"rgb Kd\" [0.2 0.2 0.2]\n{SHAPE}"
    ));
    assert!(e.message().contains("bsdffile"), "{e}");

    // translucent (docs/pbrt-v3-compatibility.md): pbrt-v3's four lobes with its defaults, index
    // 1.5.
    let (m, w) = build(&format!("Material \"translucent\"\n{SHAPE}"));
    assert!(w.is_empty(), "{w:?}");
    let b = m.last().unwrap().bsdf(&si());
    assert_eq!(b.num_lobes(), 4);
    // Diffuse transmission: 0.5 x 0.25 / pi straight through, and nothing of it on the
    // same side (the reflection lobes give that).
    let through = b.f(Vec3::Z, -Vec3::Z);
    let diffuse_t = 0.5 * 0.25 / std::f32::consts::PI;
    assert!(through.x >= diffuse_t - 1e-6, "{through}");
    let (m, _) = build(&format!(
        "Material \"translucent\" \"rgb transmit\" [0 0 0] \"rgb Ks\" [0 0 0]\n{SHAPE}"
    ));
    let b = m.last().unwrap().bsdf(&si());
    assert_eq!(b.num_lobes(), 1);
    assert_eq!(b.f(Vec3::Z, -Vec3::Z), Spectrum::ZERO);

    let (m, _) = build(&format!(
        "MakeNamedMaterial \"air\" \"string type\" \"none\"\nNamedMaterial \"air\"\n{SHAPE}"
    ));
    assert!(m.last().unwrap().is_interface());
    assert_eq!(m.last().unwrap().bsdf(&si()).num_lobes(), 0);
}

#[test]
fn unused_materials_load_no_images() {
    let dir = std::env::temp_dir().join(format!("acr-material-lazy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The image does not exist: reading it would fail.
    let text = r#"Texture "img" "spectrum" "imagemap" "string filename" "missing.png"
            Material "matte" "texture Kd" "img"
            Material "plastic"
            Shape "sphere""#;
    let (m, w) = build_in(text, &dir);
    assert!(w.is_empty(), "{w:?}");
    assert!(matches!(m.last().unwrap(), Material::Plastic(_)));
    // Used, it is an error.
    let text = text.replace("Material \"plastic\"\n", "");
    let full = format!("WorldBegin\n{text}\nWorldEnd\n");
    let desc = parse_str(&full, &dir.join("scene.pbrt")).unwrap();
    let e = build_materials(&desc, &dir, glam::DMat4::IDENTITY, &mut Vec::new()).unwrap_err();
    assert!(e.message().contains("missing.png"), "{e}");
    assert!(desc.unused_parameter_warnings().is_empty());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn images_shared_by_materials_are_read_once() {
    let dir = std::env::temp_dir().join(format!("acr-material-once-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut img = crate::image_io::RgbImage::new(2, 2);
    img.pixels.fill(Spectrum::splat(0.5));
    crate::image_io::write_image(&dir.join("t.pfm"), &img).unwrap();
    let text = r#"Texture "a" "spectrum" "imagemap" "string filename" "t.pfm"
            Texture "b" "spectrum" "imagemap" "string filename" "t.pfm" "float uscale" 4
            Material "matte" "texture Kd" "a"
            Shape "sphere"
            Material "plastic" "texture Kd" "b" "texture Ks" "a"
            Shape "sphere""#;
    let full = format!("WorldBegin\n{text}\nWorldEnd\n");
    let desc = parse_str(&full, &dir.join("scene.pbrt")).unwrap();
    let used = used_materials(&desc);
    let mut b = MaterialBuilder {
        desc: &desc,
        textures: TextureBuilder::new(&desc, &dir),
        built: vec![None; desc.materials.len()],
        in_progress: vec![false; desc.materials.len()],
    };
    for (i, u) in used.iter().enumerate() {
        if *u {
            b.build(i).unwrap();
        }
    }
    assert_eq!(b.textures.files_read(), 1);
    std::fs::remove_dir_all(&dir).ok();
}

/// subsurface and kdsubsurface (docs/subsurface.md): pbrt-v3's parameters, a BSSRDF at each
/// hit, warnings and located errors for bad input.
#[test]
fn subsurface_materials_build_with_pbrt_v3_parameters() {
    let (m, w) = build(&format!(
        "Material \"subsurface\" \"string name\" \"Skin1\" \"float scale\" [2] \"float g\" [0.5]\n{SHAPE}"
    ));
    assert!(w.is_empty(), "{w:?}");
    let b = m.last().unwrap().bssrdf(&si()).unwrap();
    // Skin1's coefficients times the scale; g forced to 0 by the name (its table is g = 0's).
    let (a, s) = crate::medium::presets::lookup("Skin1").unwrap();
    assert!(
        (b.sigma_t - 2.0 * (a + s)).abs().max_element() < 1e-6,
        "{}",
        b.sigma_t
    );
    assert!(std::ptr::eq(b.table, &*crate::bssrdf::table_for(0.0, 1.33)));
    // The boundary: one FresnelSpecular, index 1.33.
    let bsdf = m.last().unwrap().bsdf(&si());
    assert_eq!((bsdf.num_lobes(), bsdf.eta()), (1, 1.33));
    // Defaults: pbrt-v3's whole milk.
    let (m, _) = build(&format!("Material \"subsurface\"\n{SHAPE}"));
    let b = m.last().unwrap().bssrdf(&si()).unwrap();
    assert!((b.sigma_t.x - (0.0011 + 2.55)).abs() < 1e-5);
    // kdsubsurface: Kd inverted through the table, mfp 1.
    let (m, w) = build(&format!(
        "Material \"kdsubsurface\" \"rgb Kd\" [0.2 0.5 0.9] \"rgb mfp\" [1 0.5 2]\n{SHAPE}"
    ));
    assert!(w.is_empty(), "{w:?}");
    let b = m.last().unwrap().bssrdf(&si()).unwrap();
    assert!(
        (b.sigma_t - Spectrum::new(1.0, 2.0, 0.5))
            .abs()
            .max_element()
            < 1e-4
    );
    // A bumped subsurface keeps its BSSRDF; other materials have none.
    let (m, _) = build(&format!(
        "Texture \"bump\" \"float\" \"constant\"\nMaterial \"kdsubsurface\" \"texture bumpmap\" \"bump\"\n{SHAPE}\nMaterial \"matte\"\n{SHAPE}"
    ));
    assert!(m[m.len() - 2].bssrdf(&si()).is_some());
    assert!(m.last().unwrap().bssrdf(&si()).is_none());

    // An unknown name: pbrt-v3's warning (located, with a hint), its defaults used.
    let (m, w) = build(&format!(
        "Material \"subsurface\" \"string name\" \"Ketchp\"\n{SHAPE}"
    ));
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].message.contains("Ketchup") && w[0].loc.is_some(),
        "{w:?}"
    );
    assert!(m.last().unwrap().bssrdf(&si()).is_some());
    // Negative coefficients: a located warning, clamped as pbrt-v3 clamps them.
    let (m, w) = build(&format!(
        "Material \"subsurface\" \"rgb sigma_a\" [-1 0.1 0.1]\n{SHAPE}"
    ));
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].message.contains("sigma_a") && w[0].loc.is_some());
    let b = m.last().unwrap().bssrdf(&si()).unwrap();
    assert!(b.sigma_t.x >= 0.0 && b.sigma_t.is_finite());
    // Parameters the table cannot take: located errors.
    for bad in [
        "\"float eta\" [0.9]",
        "\"float g\" [1]",
        "\"float scale\" [-2]",
    ] {
        let e = build_err(&format!("Material \"kdsubsurface\" {bad}\n{SHAPE}"));
        assert!(matches!(e, Error::At { .. }), "{bad}: {e}");
    }
}

/// `bsdf_into` over a BSDF that held another material's lobes (more of them, another index)
/// gives `bsdf`'s BSDF: what bdpt's kept vertices rely on.
#[test]
fn bsdf_into_a_used_bsdf_is_bsdf() {
    let all = typical();
    let (glass, _) = build(&format!(
        "Material \"glass\" \"float uroughness\" 0.2\n{SHAPE}"
    ));
    let other = SurfaceInteraction::flat(Vec3::new(-0.4, 0.7, 0.0), Vec2::new(0.9, 0.1));
    for (name, text) in all {
        let (mats, _) = build(&text);
        let m = mats.last().unwrap();
        let mut b = glass.last().unwrap().bsdf(&other);
        b.add(Bxdf::Lambertian { r: Spectrum::ONE });
        m.bsdf_into(&si(), &mut b);
        let want = m.bsdf(&si());
        assert_eq!(b.lobes(), want.lobes(), "{name}");
        assert_eq!(b.eta(), want.eta(), "{name}");
        // And with separate lobes, as directlighting and whitted refill theirs.
        let mut single = m.bsdf(&other);
        m.bsdf_into_with(&si(), false, &mut single);
        let want_single = m.bsdf_with(&si(), false);
        assert_eq!(single.lobes(), want_single.lobes(), "{name}");
        assert_eq!(single.eta(), want_single.eta(), "{name}");
        for wo in test_directions() {
            for wi in test_directions() {
                let (w, x) = (want.frame().from_local(wo), want.frame().from_local(wi));
                assert_eq!(b.f(w, x), want.f(w, x), "{name}");
                assert_eq!(b.pdf(w, x), want.pdf(w, x), "{name}");
            }
        }
    }
}

/// `shade` in place is `shading`: a bumped material, a mix whose first material is bumped, and
/// materials it leaves alone.
#[test]
fn shade_in_place_is_shading() {
    let (m, _) = build(&format!(
        r#"Texture "b" "float" "fbm"
           MakeNamedMaterial "bumped" "string type" "matte" "texture bumpmap" "b"
           MakeNamedMaterial "plain" "string type" "plastic"
           NamedMaterial "bumped"
           {SHAPE}
           Material "mix" "string namedmaterial1" "bumped" "string namedmaterial2" "plain"
           {SHAPE}
           NamedMaterial "plain"
           {SHAPE}"#
    ));
    let fields = |s: &SurfaceInteraction| {
        let shading = (s.shading_n, s.shading_dpdu, s.shading_dpdv);
        (s.p, s.n, s.dpdu, s.dpdv, shading, s.wo, s.uv)
    };
    let (mut moved, mut kept) = (0, 0);
    for (i, mat) in m.iter().enumerate() {
        let want = mat.shading(&si());
        let mut got = si();
        mat.shade(&mut got);
        assert_eq!(fields(&got), fields(&want), "material {i}: {mat:?}");
        if got.shading_n == si().shading_n {
            kept += 1;
        } else {
            moved += 1;
        }
    }
    assert!(
        moved >= 2 && kept >= 1,
        "{moved} bumped, {kept} not, of {m:?}"
    );
}
