//! Arbitrary output variables: samples per pixel, variance and the first-hit features.

use super::*;

#[test]
fn aovs_write_samples_per_pixel_and_variance() {
    let dir = TempDir::new("aov");
    let scene = dir.write("s.pbrt", &small_scene(""));
    let (spp_exr, spp_png, var_exr) = (
        dir.join("spp.exr"),
        dir.join("spp.png"),
        dir.join("var.exr"),
    );
    let arg = format!("spp={},variance={}", spp_exr.display(), var_exr.display());
    let o = render_ok(
        &scene,
        &dir.join("img.exr"),
        &[
            "--spp",
            "5",
            "--aov",
            &arg,
            "--aov",
            &format!("spp={}", spp_png.display()),
        ],
    );
    let _ = o;
    let counts = read_image(&spp_exr, false).unwrap();
    assert_eq!((counts.width, counts.height), (24, 16));
    assert!(counts.pixels.iter().all(|c| c.x == 5.0), "5 samples each");
    let var = read_image(&var_exr, false).unwrap();
    assert!(var
        .pixels
        .iter()
        .all(|c| c.is_finite() && c.min_element() >= 0.0));
    // The sphere's noisy pixels have some variance; a pixel seeing only the sky has none.
    assert!(var.pixels.iter().any(|c| c.max_element() > 0.0));
    let png = read_image(&spp_png, true).unwrap();
    assert_eq!((png.width, png.height), (24, 16));
    // Every pixel has the highest count: white, the top of the scale.
    assert!(png.pixels.iter().all(|c| c.min_element() > 0.99));
    let bytes = std::fs::read(&spp_png).unwrap();
    let needle = b"5 samples per pixel";
    assert!(
        bytes.windows(needle.len()).any(|w| w == needle),
        "the scale is written into the PNG"
    );
}

/// A camera at the origin looking down +z (16 x 16, fov 30) at a matte wall at z = 4 with
/// Kd (0.2, 0.4, 0.6); with `mirror`, a mirror at z = 2 faces the camera and a second matte
/// wall, Kd (0.5, 0.25, 0.1), stands behind it at z = -3, facing +z.
fn feature_scene(mirror: bool) -> String {
    let mut s = String::from(
        "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
         Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
         Sampler \"random\" \"integer pixelsamples\" 8\nWorldBegin\n\
         LightSource \"point\" \"point from\" [0 0 1] \"rgb I\" [5 5 5]\n\
         Material \"matte\" \"rgb Kd\" [0.2 0.4 0.6]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [-9 -9 4  9 -9 4  9 9 4  -9 9 4]\n",
    );
    if mirror {
        s += "AttributeBegin\nMaterial \"mirror\"\n\
              Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
              \"point3 P\" [-9 -9 2  9 -9 2  9 9 2  -9 9 2]\nAttributeEnd\n\
              Material \"matte\" \"rgb Kd\" [0.5 0.25 0.1]\n\
              Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
              \"point3 P\" [-9 -9 -3  9 -9 -3  9 9 -3  -9 9 -3]\n";
    }
    s + "WorldEnd\n"
}

/// `--aov albedo,normal,depth`: the first non-specular surface's albedo, normal (facing the
/// path) and path length, per pixel, through a mirror too, with either integrator; asking for
/// them leaves the image as it was; a PNG is refused before rendering.
#[test]
fn feature_aovs_hold_the_first_non_specular_surface() {
    let dir = TempDir::new("features");
    let cases = [
        (false, "path", [0.2, 0.4, 0.6], -1.0, 4.0),
        (true, "path", [0.5, 0.25, 0.1], 1.0, 7.0),
        (true, "directlighting", [0.5, 0.25, 0.1], 1.0, 7.0),
    ];
    for (mirror, integrator, albedo, nz, depth) in cases {
        let what = format!("mirror {mirror}, {integrator}");
        let scene = dir.write("f.pbrt", &feature_scene(mirror));
        let (a, n, d) = (dir.join("a.exr"), dir.join("n.pfm"), dir.join("d.exr"));
        let aov = format!(
            "albedo={},normal={},depth={}",
            a.display(),
            n.display(),
            d.display()
        );
        let with = dir.join("with.exr");
        render_ok(&scene, &with, &["--integrator", integrator, "--aov", &aov]);
        let read = |p: &Path| read_image(p, false).unwrap_or_else(|e| panic!("{what}: {e}"));
        let (a, n, d) = (read(&a), read(&n), read(&d));
        assert_eq!(
            (a.width, a.height, n.width, d.height),
            (16, 16, 16, 16),
            "{what}"
        );
        for i in 0..256 {
            let got = a.pixels[i].to_array();
            for c in 0..3 {
                assert!(
                    (got[c] - albedo[c]).abs() < 1e-5,
                    "{what}: albedo {got:?} at {i}"
                );
            }
            let normal = n.pixels[i];
            assert!(
                (normal.z - nz).abs() < 1e-5 && normal.x.abs() < 1e-5,
                "{what}: {normal}"
            );
            // From straight ahead to the corner rays, 20.7 degrees off the axis.
            let t = d.pixels[i].x;
            assert!(
                t >= depth - 1e-3 && t <= depth * 1.071,
                "{what}: depth {t} at {i}"
            );
        }
        // The features do not disturb the render.
        let without = dir.join("without.exr");
        render_ok(&scene, &without, &["--integrator", integrator]);
        assert_eq!(read(&with).pixels, read(&without).pixels, "{what}");
    }
    let scene = dir.write("f.pbrt", &feature_scene(false));
    let png = format!("albedo={}", dir.join("a.png").display());
    render_fails(
        &scene,
        &dir.join("x.exr"),
        &["--aov", &png],
        "must be an .exr or .pfm",
    );
}
