//! A render by bands under nfor (docs/reconstruction.md, "Rendering by bands"): the same image,
//! byte for byte, as the whole film filtered at the end, on any thread count and in a crop.

use super::*;

/// Each channel's bits.
fn bits(img: &[acr::geometry::Spectrum]) -> Vec<u32> {
    img.iter()
        .flat_map(|c| [c.x.to_bits(), c.y.to_bits(), c.z.to_bits()])
        .collect()
}

#[test]
fn a_render_by_bands_is_the_whole_images_render_byte_for_byte() {
    let dir = TempDir::new("bands");
    // Tall enough for several bands of 32 rows; motion and a lens, so time and lens are drawn.
    let scene = dir.write("m.pbrt", &example_scene("motion-dof.pbrt", 24, 200));
    let render = |name: &str, extra: &[&str]| {
        let out = dir.join(format!("{name}.exr"));
        let stats = dir.join(format!("{name}.json"));
        let mut args = vec![
            "--sampler",
            "stratified",
            "--filter",
            "nfor",
            "--spp",
            "4",
            "--stats",
            stats.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        render_ok(&scene, &out, &args);
        (read_image(&out, false).unwrap().pixels, read_stats(&stats))
    };
    let band = ["--set", "filter.band=32"];
    let (banded, stats) = render("banded", &band);
    // 200 rows in bands of 32, the last 8 within the halo of the one before joining it.
    assert_eq!(stats["bands"], 6, "{stats}");
    assert!(stats["seconds"]["reconstruct"].as_f64().unwrap() > 0.0);
    // The whole film filtered at the end: at once, and in the filter's bands of 32 (a time
    // limit renders the whole film).
    let (whole, stats) = render("whole", &["--set", "filter.band=0"]);
    assert!(stats["bands"].is_null(), "{stats}");
    assert_eq!(bits(&banded), bits(&whole));
    let mut limited = band.to_vec();
    limited.extend(["--time-limit", "1000"]);
    let (at_end, stats) = render("at-end", &limited);
    assert!(stats["bands"].is_null(), "{stats}");
    assert_eq!(bits(&banded), bits(&at_end));
    // One thread and two.
    let mut one = band.to_vec();
    one.extend(["--threads", "1"]);
    let mut two = band.to_vec();
    two.extend(["--threads", "2"]);
    assert_eq!(bits(&render("one", &one).0), bits(&render("two", &two).0));
    // A crop, with the spp and variance AOVs (each released pixel's statistics kept).
    let aovs = format!(
        "spp={},variance={}",
        dir.join("spp.exr").display(),
        dir.join("var.exr").display()
    );
    let mut crop = band.to_vec();
    crop.extend(["--cropwindow", "0.1,0.8,0.05,0.9", "--aov", &aovs]);
    let (cropped, stats) = render("crop", &crop);
    assert!(stats["bands"].as_u64().unwrap() > 1, "{stats}");
    let read = |name: &str| read_image(&dir.join(name), false).unwrap().pixels;
    let (spp, var) = (read("spp.exr"), read("var.exr"));
    assert!(spp.iter().all(|c| c.x == 4.0), "every pixel its 4 samples");
    crop[1] = "filter.band=0";
    let (cropped_whole, stats) = render("crop-whole", &crop);
    assert!(stats["bands"].is_null(), "{stats}");
    assert_eq!(bits(&cropped), bits(&cropped_whole));
    assert_eq!(bits(&spp), bits(&read("spp.exr")));
    assert_eq!(bits(&var), bits(&read("var.exr")));
}
