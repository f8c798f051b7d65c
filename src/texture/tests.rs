//! Tests of the textures: building from scene descriptions, mappings, lookups and errors.

use super::*;
use crate::geometry::{Vec2, Vec3};
use crate::image_io::RgbImage;
use crate::spectrum::srgb_to_linear;
use acr_parser::parse_str;
use acr_parser::SceneDescription;
use glam::DMat4;
use std::path::Path;

fn si_uv(u: f32, v: f32) -> SurfaceInteraction {
    SurfaceInteraction::flat(Vec3::new(u, v, 0.0), Vec2::new(u, v))
}

fn si_p(p: Vec3) -> SurfaceInteraction {
    SurfaceInteraction {
        p,
        ..si_uv(0.0, 0.0)
    }
}

fn scene(text: &str, dir: &Path) -> SceneDescription {
    let full = format!("WorldBegin\n{text}\nWorldEnd\n");
    parse_str(&full, &dir.join("scene.pbrt")).unwrap()
}

fn named(desc: &SceneDescription, name: &str) -> usize {
    desc.textures.iter().rposition(|t| t.name == name).unwrap()
}

#[test]
fn checkerboard_alternates_on_uv() {
    let desc = scene(
        r#"Texture "c" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]
           "float uscale" 4 "float vscale" 4"#,
        Path::new("/tmp"),
    );
    let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
    let t = b.spectrum_texture(named(&desc, "c")).unwrap();
    let red = Spectrum::new(1.0, 0.0, 0.0);
    let blue = Spectrum::new(0.0, 0.0, 1.0);
    assert_eq!(t.eval(&si_uv(0.1, 0.1)), red);
    assert_eq!(t.eval(&si_uv(0.3, 0.1)), blue);
    assert_eq!(t.eval(&si_uv(0.3, 0.3)), red);
    assert_eq!(t.eval(&si_uv(0.1, 0.3)), blue);
    // Negative coordinates continue the pattern.
    assert_eq!(t.eval(&si_uv(-0.1, 0.1)), blue);
    assert_eq!(t.eval(&si_uv(-0.1, -0.1)), red);
    assert!(b.finish().is_empty());

    // Float checkerboard with defaults 1 and 0, and a 3D one.
    let desc = scene(
        r#"Texture "f" "float" "checkerboard"
           Texture "g" "float" "checkerboard" "integer dimension" 3"#,
        Path::new("/tmp"),
    );
    let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
    let f = b.float_texture(named(&desc, "f")).unwrap();
    assert_eq!(f.eval(&si_uv(0.5, 0.5)), 1.0);
    assert_eq!(f.eval(&si_uv(1.5, 0.5)), 0.0);
    let g = b.float_texture(named(&desc, "g")).unwrap();
    assert_eq!(g.eval(&si_p(Vec3::new(0.5, 0.5, 0.5))), 1.0);
    assert_eq!(g.eval(&si_p(Vec3::new(0.5, 0.5, 1.5))), 0.0);
    let desc = scene(
        r#"Texture "h" "float" "checkerboard" "integer dimension" 4"#,
        Path::new("/tmp"),
    );
    let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
    assert!(b.float_texture(0).is_err());
}

#[test]
fn uv_mapping_scales_and_offsets() {
    let desc = scene(
        r#"Texture "u" "spectrum" "uv" "float uscale" 2 "float vscale" 3
           "float udelta" 0.25 "float vdelta" 0.5"#,
        Path::new("/tmp"),
    );
    let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
    let t = b.spectrum_texture(0).unwrap();
    // s = 2 * 0.1 + 0.25 = 0.45; t = 3 * 0.1 + 0.5 = 0.8.
    let c = t.eval(&si_uv(0.1, 0.1));
    assert!(
        (c - Spectrum::new(0.45, 0.8, 0.0)).abs().max_element() < 1e-5,
        "{c}"
    );
    // Fractional parts: s = 2 * 0.5 + 0.25 = 1.25 -> 0.25.
    let c = t.eval(&si_uv(0.5, 0.5));
    assert!(
        (c - Spectrum::new(0.25, 0.0, 0.0)).abs().max_element() < 1e-5,
        "{c}"
    );
}

#[test]
fn spherical_cylindrical_and_planar_mappings() {
    let world_from_texture = DMat4::from_translation(glam::DVec3::new(0.0, 0.0, 5.0));
    let sph = Mapping2D::Spherical {
        texture_from_world: world_from_texture.inverse().as_mat4(),
    };
    // A point above the texture-space origin: theta = 0.
    let st = sph.map(&si_p(Vec3::new(0.0, 0.0, 7.0)));
    assert!(st.x.abs() < 1e-6);
    // On the texture-space +y axis: theta = pi/2, phi = pi/2.
    let st = sph.map(&si_p(Vec3::new(0.0, 2.0, 5.0)));
    assert!((st - Vec2::new(0.5, 0.25)).length() < 1e-5, "{st}");
    let cyl = Mapping2D::Cylindrical {
        texture_from_world: world_from_texture.inverse().as_mat4(),
    };
    let st = cyl.map(&si_p(Vec3::new(-1.0, 0.0, 5.0)));
    assert!((st.x - 1.0).abs() < 1e-5 || st.x.abs() < 1e-5, "{st}");
    let st = cyl.map(&si_p(Vec3::new(1.0, 0.0, 5.0)));
    assert!((st - Vec2::new(0.5, 0.0)).length() < 1e-5, "{st}");
    let planar = Mapping2D::Planar {
        vs: Vec3::X,
        vt: Vec3::Z,
        ds: 0.5,
        dt: -1.0,
    };
    let st = planar.map(&si_p(Vec3::new(2.0, 9.0, 3.0)));
    assert_eq!(st, Vec2::new(2.5, 2.0));
    // Unknown mappings are errors.
    let desc = scene(
        r#"Texture "c" "float" "checkerboard" "string mapping" "sphere""#,
        Path::new("/tmp"),
    );
    let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
    let e = b.float_texture(0).unwrap_err();
    assert!(e.message().contains("unknown texture mapping"), "{e}");
}

#[test]
fn scale_and_mix() {
    let desc = scene(
        r#"Texture "a" "float" "constant" "float value" 0.25
           Texture "s" "spectrum" "scale" "rgb tex1" [1 2 3] "rgb tex2" [0.5 0.5 2]
           Texture "m" "spectrum" "mix" "rgb tex1" [1 0 0] "rgb tex2" [0 1 0] "texture amount" "a"
           Texture "fs" "float" "scale" "texture tex1" "a" "float tex2" 4
           Texture "fm" "float" "mix"
           Texture "check" "float" "checkerboard" "float uscale" 2
           Texture "mc" "spectrum" "mix" "texture amount" "check""#,
        Path::new("/tmp"),
    );
    let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
    let si = si_uv(0.1, 0.1);
    let s = b.spectrum_texture(named(&desc, "s")).unwrap();
    assert_eq!(s.eval(&si), Spectrum::new(0.5, 1.0, 6.0));
    let m = b.spectrum_texture(named(&desc, "m")).unwrap();
    assert!(
        (m.eval(&si) - Spectrum::new(0.75, 0.25, 0.0))
            .abs()
            .max_element()
            < 1e-6
    );
    let fs = b.float_texture(named(&desc, "fs")).unwrap();
    assert_eq!(fs.eval(&si), 1.0);
    // Mix defaults: tex1 0, tex2 1, amount 0.5.
    let fm = b.float_texture(named(&desc, "fm")).unwrap();
    assert_eq!(fm.eval(&si), 0.5);
    // A textured amount: all of tex2 on even checks, all of tex1 on odd.
    let mc = b.spectrum_texture(named(&desc, "mc")).unwrap();
    assert_eq!(mc.eval(&si_uv(0.1, 0.1)), Spectrum::ONE);
    assert_eq!(mc.eval(&si_uv(0.6, 0.1)), Spectrum::ZERO);
    // The float texture "a" was built once and shared.
    assert!(b.floats[named(&desc, "a")].is_some());
}

/// A 2x2 PFM: top row (1, 2), bottom row (3, 4) in every channel.
fn write_2x2(dir: &Path, name: &str) {
    let mut img = RgbImage::new(2, 2);
    img.set(0, 0, Spectrum::splat(1.0));
    img.set(1, 0, Spectrum::splat(2.0));
    img.set(0, 1, Spectrum::splat(3.0));
    img.set(1, 1, Spectrum::splat(4.0));
    crate::image_io::write_image(&dir.join(name), &img).unwrap();
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("acr-texture-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn image_bilinear_on_2x2() {
    let dir = temp_dir("bilerp");
    write_2x2(&dir, "quad.pfm");
    let desc = scene(
        r#"Texture "i" "float" "imagemap" "string filename" "quad.pfm" "string wrap" "clamp"
           Texture "j" "spectrum" "imagemap" "string filename" "quad.pfm" "float scale" 2
           Texture "k" "float" "imagemap" "string filename" "quad.pfm" "string wrap" "black""#,
        &dir,
    );
    let mut b = TextureBuilder::new(&desc, &dir);
    let i = b.float_texture(named(&desc, "i")).unwrap();
    // Texel centres: t = 0.25 is the bottom row (3, 4), t = 0.75 the top (1, 2).
    assert!((i.eval(&si_uv(0.25, 0.25)) - 3.0).abs() < 1e-5);
    assert!((i.eval(&si_uv(0.75, 0.25)) - 4.0).abs() < 1e-5);
    assert!((i.eval(&si_uv(0.25, 0.75)) - 1.0).abs() < 1e-5);
    assert!((i.eval(&si_uv(0.75, 0.75)) - 2.0).abs() < 1e-5);
    // The centre is the average; halfway along the bottom row, 3.5.
    assert!((i.eval(&si_uv(0.5, 0.5)) - 2.5).abs() < 1e-5);
    assert!((i.eval(&si_uv(0.5, 0.25)) - 3.5).abs() < 1e-5);
    // Clamped beyond the edge.
    assert!((i.eval(&si_uv(0.0, 0.0)) - 3.0).abs() < 1e-5);
    // Repeat (default) wraps: at s = 0 the left column blends with the right one.
    let j = b.spectrum_texture(named(&desc, "j")).unwrap();
    assert!((j.eval(&si_uv(0.0, 0.25)).x - 2.0 * 3.5).abs() < 1e-5);
    // Black fades to zero outside.
    let k = b.float_texture(named(&desc, "k")).unwrap();
    assert!((k.eval(&si_uv(0.0, 0.25)) - 1.5).abs() < 1e-5);
    assert_eq!(k.eval(&si_uv(-1.0, 0.25)), 0.0);
    // One file read for the three textures.
    assert_eq!(b.files_read(), 1);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn png_gamma_and_invert() {
    let dir = temp_dir("gamma");
    let buf = ::image::RgbImage::from_raw(1, 1, vec![128, 128, 128]).unwrap();
    buf.save(dir.join("grey.png")).unwrap();
    let desc = scene(
        r#"Texture "a" "spectrum" "imagemap" "string filename" "grey.png"
           Texture "b" "spectrum" "imagemap" "string filename" "grey.png" "bool gamma" false
           Texture "c" "float" "imagemap" "string filename" "grey.png" "bool invert" true"#,
        &dir,
    );
    let mut b = TextureBuilder::new(&desc, &dir);
    let si = si_uv(0.3, 0.3);
    let a = b.spectrum_texture(0).unwrap().eval(&si);
    assert!((a.x - srgb_to_linear(128.0 / 255.0)).abs() < 1e-5, "{a}");
    let raw = b.spectrum_texture(1).unwrap().eval(&si);
    assert!((raw.x - 128.0 / 255.0).abs() < 1e-5, "{raw}");
    let c = b.float_texture(2).unwrap().eval(&si);
    assert!(
        (c - (1.0 - srgb_to_linear(128.0 / 255.0))).abs() < 1e-4,
        "{c}"
    );
    assert_eq!(b.files_read(), 1);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn missing_images_are_errors_where_named() {
    let dir = temp_dir("missing");
    let desc = scene(
        r#"Texture "a" "spectrum" "imagemap" "string filename" "nope.png""#,
        &dir,
    );
    let mut b = TextureBuilder::new(&desc, &dir);
    let e = b.spectrum_texture(0).unwrap_err();
    assert!(e.message().contains("nope.png"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn params_become_textures() {
    let desc = scene(
        r#"Texture "t" "spectrum" "constant" "rgb value" [0.1 0.2 0.3]
           Texture "f" "float" "constant" "float value" 0.7
           Material "matte" "texture Kd" "t" "float sigma" 10 "rgb Ks" [1 1 1]
             "texture roughness" "f" "float weird" 1 "texture bad" "f""#,
        Path::new("/tmp"),
    );
    let params = &desc.materials.last().unwrap().plugin.params;
    let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
    let si = si_uv(0.5, 0.5);
    let kd = b.spectrum_param(params, "Kd", Spectrum::ONE).unwrap();
    assert!(
        (kd.eval(&si) - Spectrum::new(0.1, 0.2, 0.3))
            .abs()
            .max_element()
            < 1e-6
    );
    let sigma = b.float_param(params, "sigma", 0.0).unwrap();
    assert_eq!(sigma.as_constant(), Some(10.0));
    let rough = b.float_param(params, "roughness", 0.0).unwrap();
    assert!((rough.eval(&si) - 0.7).abs() < 1e-6);
    let ks = b.spectrum_param(params, "Ks", Spectrum::ZERO).unwrap();
    assert_eq!(ks.as_constant(), Some(Spectrum::ONE));
    // Absent: the default. Wrong type: the default, and left unused.
    let kr = b
        .spectrum_param(params, "Kr", Spectrum::splat(0.5))
        .unwrap();
    assert_eq!(kr.as_constant(), Some(Spectrum::splat(0.5)));
    let weird = b
        .spectrum_param(params, "weird", Spectrum::splat(0.5))
        .unwrap();
    assert_eq!(weird.as_constant(), Some(Spectrum::splat(0.5)));
    assert!(params.unused().any(|p| p.name == "weird"));
    // A float texture where a spectrum is needed: the default, with a warning.
    let bad = b
        .spectrum_param(params, "bad", Spectrum::splat(0.25))
        .unwrap();
    assert_eq!(bad.as_constant(), Some(Spectrum::splat(0.25)));
    assert_eq!(b.finish().len(), 1);
}

#[test]
fn unsupported_and_unknown_classes() {
    let desc = scene(
        r#"Texture "a" "float" "ptex"
           Texture "b" "float" "checkerbord"
           Texture "c" "float" "bilerp" "float v00" 1 "float v01" 2 "float v10" 3 "float v11" 4"#,
        Path::new("/tmp"),
    );
    let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
    assert_eq!(b.float_texture(0).unwrap().as_constant(), Some(0.5));
    let e = b.float_texture(1).unwrap_err();
    assert!(e.message().contains("checkerboard"), "{e}");
    let c = b.float_texture(2).unwrap();
    // (1-s)(1-t) 1 + (1-s) t 2 + s (1-t) 3 + s t 4 at (0.5, 0.25).
    let v = c.eval(&si_uv(0.5, 0.25));
    assert!((v - (0.375 + 0.25 + 1.125 + 0.5)).abs() < 1e-5, "{v}");
    assert_eq!(b.finish().len(), 1);
}

#[test]
fn procedural_classes_build_and_check_their_parameters() {
    let desc = scene(
        r#"Texture "f" "float" "fbm" "integer octaves" 3 "float roughness" 0.7
           Texture "m" "float" "marble"
           Texture "o" "float" "wrinkled" "integer octaves" -2
           Texture "d" "spectrum" "dots" "rgb inside" [1 0 0] "rgb outside" [0 0 1]
           Texture "s" "spectrum" "marble" "float scale" 2"#,
        Path::new("/tmp"),
    );
    let mut b = TextureBuilder::new(&desc, Path::new("/tmp"));
    let f = b.float_texture(0).unwrap();
    let p = Vec3::new(0.3, 1.7, -2.2);
    assert_eq!(
        f.eval(&si_p(p)),
        crate::noise::fbm(p, Vec3::ZERO, Vec3::ZERO, 0.7, 3)
    );
    let e = b.float_texture(1).unwrap_err();
    assert!(e.message().contains("spectrum texture"), "{e}");
    let e = b.float_texture(2).unwrap_err();
    assert!(e.message().contains("octaves -2"), "{e}");
    // pbrt-v3's order: "inside" off the dots, "outside" on them.
    let d = b.spectrum_texture(3).unwrap();
    let off = d.eval(&si_uv(0.0, 0.0));
    assert_eq!(off, Spectrum::new(1.0, 0.0, 0.0));
    let m = b.spectrum_texture(4).unwrap();
    assert!(m.eval(&si_p(p)).is_finite());
    assert!(b.finish().is_empty());
}

#[test]
fn files_resolve_next_to_the_naming_file_then_the_main_dir() {
    let dir = temp_dir("resolve");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::write(dir.join("main.txt"), "").unwrap();
    std::fs::write(dir.join("sub").join("local.txt"), "").unwrap();
    let file = acr_parser::SourceFile::new(dir.join("sub").join("inc.pbrt"), "");
    let loc = Loc::new(&file, 0);
    assert_eq!(
        resolve_file("local.txt", &loc, &dir),
        dir.join("sub").join("local.txt")
    );
    assert_eq!(resolve_file("main.txt", &loc, &dir), dir.join("main.txt"));
    assert_eq!(
        resolve_file("none.txt", &loc, &dir),
        dir.join("sub").join("none.txt")
    );
    assert_eq!(
        resolve_file("/abs/x.png", &loc, &dir),
        PathBuf::from("/abs/x.png")
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A `w` x `h` 8-bit PNG of `channels` channels (1, 2, 3 or 4) of scattered bytes.
fn write_png(path: &Path, w: u32, h: u32, channels: u8) {
    let n = (w * h * channels as u32) as usize;
    let data: Vec<u8> = (0..n)
        .map(|i| ((i * 97 + i / 3 * 31) % 256) as u8)
        .collect();
    let color = match channels {
        1 => ::image::ExtendedColorType::L8,
        2 => ::image::ExtendedColorType::La8,
        3 => ::image::ExtendedColorType::Rgb8,
        _ => ::image::ExtendedColorType::Rgba8,
    };
    ::image::save_buffer(path, &data, w, h, color).unwrap();
}

#[test]
fn eight_bit_pngs_kept_in_bytes_read_as_the_float_reader_reads_them() {
    let dir = temp_dir("bytes");
    for channels in 1..=4u8 {
        let path = dir.join(format!("c{channels}.png"));
        write_png(&path, 7, 5, channels);
        let source::Source::Bytes(bytes) = source::read_source(&path).unwrap() else {
            panic!("{channels} channels: not kept in bytes");
        };
        let floats = crate::image_io::read_image(&path, false).unwrap();
        assert_eq!((bytes.width, bytes.height), (7, 5));
        for y in 0..5 {
            for x in 0..7 {
                let k = (y * 7 + x) * bytes.channels;
                let px = &bytes.data[k..k + bytes.channels];
                assert_eq!(bytes.rgb(px), floats.get(x, y), "{channels}: {x} {y}");
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn byte_pyramids_keep_the_files_own_texels_and_round_the_others() {
    let dir = temp_dir("byte-mip");
    write_png(&dir.join("even.png"), 8, 4, 3);
    write_png(&dir.join("odd.png"), 7, 5, 3);
    write_png(&dir.join("grey.png"), 6, 3, 1);
    let desc = scene(
        r#"Texture "even" "spectrum" "imagemap" "string filename" "even.png"
           Texture "odd" "spectrum" "imagemap" "string filename" "odd.png" "bool invert" true
           Texture "rgbfloat" "float" "imagemap" "string filename" "even.png"
           Texture "grey" "float" "imagemap" "string filename" "grey.png" "float scale" 0.5"#,
        &dir,
    );
    let mut b = TextureBuilder::new(&desc, &dir);
    let mip = |t: &Texture<Spectrum>| match t {
        Texture::Image { image, .. } => Arc::clone(image),
        _ => panic!("not an image"),
    };
    let even = mip(&b.spectrum_texture(named(&desc, "even")).unwrap());
    let odd = mip(&b.spectrum_texture(named(&desc, "odd")).unwrap());
    assert!(even.in_bytes() && odd.in_bytes());
    assert_eq!(even.texel_bytes(), (32 + 8 + 2 + 1) * 3);
    let Texture::Image {
        image: rgb_float, ..
    } = &*b.float_texture(2).unwrap()
    else {
        panic!("not an image");
    };
    assert!(
        !rgb_float.in_bytes(),
        "a float of a colour is not one table entry"
    );
    let Texture::Image { image: grey, .. } = &*b.float_texture(3).unwrap() else {
        panic!("not an image");
    };
    assert!(grey.in_bytes());
    assert_eq!(b.files_read(), 3);
    // The same images kept in floats.
    let floats = |name: &str, invert: bool| {
        let img = crate::image_io::read_image(&dir.join(name), false).unwrap();
        let map = ImageMap::new(&img, Wrap::Repeat, |c| {
            Spectrum::from_texel(c, 1.0, true, invert)
        });
        crate::mipmap::MipMap::new(&map, false, 8.0)
    };
    let (even_f, odd_f) = (floats("even.png", false), floats("odd.png", true));
    let none = Vec2::splat(f32::NAN);
    let mut worst = [0.0f32; 2];
    for i in 0..200 {
        let st = Vec2::new((i as f32 * 0.618).fract(), (i as f32 * 0.382).fract());
        // Bilinear in the file's own texels: the same to the bit.
        assert_eq!(even.lookup(st, none, none), even_f.lookup(st, none, none));
        // Coarser levels: rounded to the nearest byte's value.
        let d = Vec2::new(0.06 * (i % 7) as f32, 0.02 * (i % 5) as f32);
        let e = Vec2::new(-0.02 * (i % 3) as f32, 0.05 * (i % 11) as f32);
        for (k, (a, f)) in [(&even, &even_f), (&odd, &odd_f)].into_iter().enumerate() {
            let diff = (a.lookup(st, d, e) - f.lookup(st, d, e))
                .abs()
                .max_element();
            worst[k] = worst[k].max(diff);
        }
    }
    // Half the widest step of the sRGB table (at 1) is 0.0045.
    assert!(worst[0] > 0.0 && worst[0] < 0.0046, "{worst:?}");
    // Resampled levels also lose the Lanczos lobes' overshoot above 1 (as pbrt-v4's 8-bit
    // levels do): on this image of scattered bytes, up to a few hundredths.
    assert!(worst[1] > 0.0 && worst[1] < 0.03, "{worst:?}");
    std::fs::remove_dir_all(&dir).ok();
}
