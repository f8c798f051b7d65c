//! Scenes compressed with gzip (`.pbrt.gz`), read as pbrt-v4 reads them: the same scene as
//! the plain text, and errors located in the decompressed text.

use acr_parser::parse_file;
use std::io::Write;
use std::path::PathBuf;

/// A fresh empty folder under the system's temporary folder.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("acr-gzip-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn gzip(text: &str) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(text.as_bytes()).unwrap();
    enc.finish().unwrap()
}

#[test]
fn a_gz_scene_and_its_gz_include_parse_as_their_text_and_errors_keep_file_line_col() {
    let dir = temp_dir("scene");
    let inc = "AttributeBegin\n  Shape \"sphere\" \"float radius\" [ 2 ]\nAttributeEnd\n";
    let main = "Film \"image\" \"integer xresolution\" [ 8 ]\nWorldBegin\nInclude \"inc.pbrt.gz\"\nWorldEnd\n";
    std::fs::write(dir.join("inc.pbrt.gz"), gzip(inc)).unwrap();
    std::fs::write(dir.join("main.pbrt.gz"), gzip(main)).unwrap();
    std::fs::write(dir.join("inc.pbrt"), inc).unwrap();
    std::fs::write(dir.join("main.pbrt"), main.replace(".pbrt.gz", ".pbrt")).unwrap();
    let gz = parse_file(&dir.join("main.pbrt.gz")).unwrap_or_else(|e| panic!("{e}"));
    let plain = parse_file(&dir.join("main.pbrt")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(gz.shapes.len(), 1);
    // The same parameters, located in the compressed file's text.
    let params = format!("{:?}", gz.shapes[0].plugin.params);
    assert!(params.contains("inc.pbrt.gz:2:18"), "{params}");
    assert_eq!(
        params.replace(".pbrt.gz", ".pbrt"),
        format!("{:?}", plain.shapes[0].plugin.params)
    );
    assert_eq!(gz.files.len(), 2);
    assert_eq!(gz.files[1].text().as_str(), inc);
    // A misspelled directive in the compressed include: located in its decompressed text.
    std::fs::write(
        dir.join("inc.pbrt.gz"),
        gzip("AttributeBegin\n  Shpae \"sphere\"\nAttributeEnd\n"),
    )
    .unwrap();
    let e = parse_file(&dir.join("main.pbrt.gz"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("inc.pbrt.gz:2:3:"), "{e}");
    // A `.gz` that is not gzip: an error naming the file.
    std::fs::write(dir.join("main.pbrt.gz"), main).unwrap();
    let e = parse_file(&dir.join("main.pbrt.gz"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("main.pbrt.gz") && e.contains("not a readable gzip file"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
