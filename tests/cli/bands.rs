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
    // The spp AOV of a render by bands reads each released pixel's count alone.
    let spp_one = format!("spp={}", dir.join("spp1.exr").display());
    let mut one = band.to_vec();
    one.extend(["--threads", "1", "--aov", &spp_one]);
    let mut two = band.to_vec();
    two.extend(["--threads", "2"]);
    assert_eq!(bits(&render("one", &one).0), bits(&render("two", &two).0));
    let counts = read_image(&dir.join("spp1.exr"), false).unwrap().pixels;
    assert!(counts.len() == 24 * 200 && counts.iter().all(|c| c.x == 4.0));
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

/// A signal stops a render by bands at the end of the pass under way in its band: the image
/// written holds the rows reached (filtered) and black below, is not a mergeable file, and
/// the message says to render again.
// Signals, and `libc::kill` to send one, are Unix only.
#[cfg(unix)]
#[test]
fn a_signal_writes_the_rows_a_render_by_bands_reached() {
    let dir = TempDir::new("bands-signal");
    let scene = dir.write("c.pbrt", &example_scene("cornell-box.pbrt", 400, 200));
    let (out, stats) = (dir.join("c.exr"), dir.join("c.json"));
    let child = acr_command([
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
        "--sampler",
        "stratified",
        "--filter",
        "nfor",
        "--set",
        "filter.band=32",
        "--spp",
        "65536",
        "--threads",
        "1",
        "--quiet",
    ])
    .stderr(Stdio::piped())
    .spawn()
    .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    // SAFETY: kill(2) on our own child's pid, with a valid signal number.
    let rc = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    assert_eq!(rc, 0);
    let output = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{err}");
    assert!(err.contains("interrupted by a signal"), "{err}");
    assert!(err.contains("render again to finish it"), "{err}");
    let stats = read_stats(&stats);
    assert_eq!(stats["halted_by"], "signal", "{stats}");
    assert!(stats["bands"].as_u64().unwrap() > 1, "{stats}");
    let img = read_image(&out, false).unwrap();
    assert_eq!((img.width, img.height), (400, 200));
    let row_mean = |y: usize| {
        img.pixels[y * 400..(y + 1) * 400]
            .iter()
            .map(|c| f64::from(c.x + c.y + c.z))
            .sum::<f64>()
    };
    // The first chunk's rows were sampled, the last rows never.
    assert!(row_mean(5) > 0.0 && row_mean(5).is_finite());
    assert_eq!(row_mean(199), 0.0);
}
