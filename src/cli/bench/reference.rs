//! A scene's reference image: a file the manifest names, or a render by a named method,
//! cached under a key of everything it depends on.

use super::child::RenderRun;
use super::{file_safe, BenchOptions, Manifest, Method, Reference, SceneEntry};
use crate::image_io::{read_image, RgbImage};
use std::path::Path;
use std::time::Instant;

/// FNV-1a, 64 bits: a stable hash for cache keys (std's hasher may change between releases).
fn fnv1a(h: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *h ^= u64::from(b);
        *h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
}

/// The cache key of a reference: every file the scene reads, the method, budget, seed and
/// crop.
fn reference_key(
    scene: &Path,
    method: &Method,
    spp: u32,
    seed: u64,
    pixelbounds: Option<[u32; 4]>,
) -> Result<u64, String> {
    let desc = acr_parser::parse_file(scene).map_err(|e| e.to_string())?;
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for f in &desc.files {
        fnv1a(&mut h, f.text().as_bytes());
        fnv1a(&mut h, &[0xff]);
    }
    // Meshes and images the scene loads are files too; their bytes count when present.
    let dir = scene.parent().unwrap_or(Path::new("."));
    for f in &desc.files {
        for word in f.text().split('"') {
            let lower = word.to_ascii_lowercase();
            if [".ply", ".exr", ".png", ".pfm", ".hdr"]
                .iter()
                .any(|e| lower.ends_with(e))
            {
                if let Ok(bytes) = std::fs::read(dir.join(word)) {
                    fnv1a(&mut h, &bytes);
                }
            }
        }
    }
    let m = format!(
        "{:?}|{:?}|{:?}|{:?}|{spp}|{seed}|{}",
        method.sampler,
        method.filter,
        method.integrator,
        method.set,
        env!("CARGO_PKG_VERSION")
    );
    fnv1a(&mut h, m.as_bytes());
    // A scene whose textures read the footprint filters them for the reference's own budget
    // (docs/pbrt-v3-compatibility.md, "Ray differentials"): references cached before that
    // rule used the scene's own spp and must not be read back. Other keys are unchanged.
    if crate::scene::uses_differentials(&desc) {
        fnv1a(&mut h, format!("|footprint spp {spp}").as_bytes());
    }
    // Uncropped keys stay those of before, so that cached references remain valid.
    if let Some(b) = pixelbounds {
        fnv1a(&mut h, format!("|pixelbounds {b:?}").as_bytes());
    }
    Ok(h)
}

/// The scene's reference image: read, or rendered (and cached) by the named method.
pub(super) fn reference_image(
    m: &Manifest,
    scene: &SceneEntry,
    scene_path: &Path,
    base: &Path,
    cache: &Path,
    opts: &BenchOptions,
) -> Result<RgbImage, String> {
    let spec = scene
        .reference
        .as_ref()
        .or(m.reference.as_ref())
        .ok_or("no reference")?;
    let path = match spec {
        Reference::Image { image } => base.join(image),
        Reference::Render { spp, .. } => {
            let meth = spec.method(&m.methods)?.ok_or("no method")?;
            let meth = &meth;
            let key = reference_key(scene_path, meth, *spp, m.seed, scene.pixelbounds)?;
            let path = cache.join(format!("{}-{key:016x}.exr", file_safe(&scene.name)));
            if !path.is_file() {
                eprintln!(
                    "{}: rendering the reference ({:?} {:?}, {spp} spp) -> {}",
                    scene.name,
                    meth.sampler,
                    meth.filter,
                    path.display()
                );
                let t = Instant::now();
                let tmp = path.with_extension("partial.exr");
                let run = RenderRun {
                    exe: &opts.exe,
                    scene: scene_path,
                    method: meth,
                    seed: m.seed,
                    threads: m.threads,
                    pixelbounds: scene.pixelbounds,
                };
                run.run(&tmp, *spp, None, false)?;
                std::fs::rename(&tmp, &path).map_err(|e| format!("{}: {e}", path.display()))?;
                let _ = std::fs::remove_file(tmp.with_extension("json"));
                eprintln!(
                    "{}: reference took {:.1} s",
                    scene.name,
                    t.elapsed().as_secs_f64()
                );
            }
            path
        }
    };
    read_image(&path, false).map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Keys of references cached before the footprint rule: an untextured scene's key is the
    /// same as then, one whose textures read the footprint is not.
    #[test]
    fn only_textured_keys_carry_the_footprint() {
        let dir = std::env::temp_dir().join(format!("acr-refkey-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let plain = "WorldBegin\nShape \"sphere\"\nWorldEnd\n";
        let textured = "WorldBegin\nTexture \"c\" \"spectrum\" \"checkerboard\"\n\
                        Shape \"sphere\"\nWorldEnd\n";
        let method = Method {
            sampler: Some("sobol".into()),
            filter: Some("box".into()),
            ..Method::default()
        };
        let key = |name: &str, text: &str| {
            let path = dir.join(name);
            std::fs::write(&path, text).unwrap();
            let desc = acr_parser::parse_file(&path).unwrap();
            // The key as computed before the rule: the files, then the method string.
            let mut old = 0xcbf2_9ce4_8422_2325u64;
            for f in &desc.files {
                fnv1a(&mut old, f.text().as_bytes());
                fnv1a(&mut old, &[0xff]);
            }
            let m = format!(
                "{:?}|{:?}|{:?}|{:?}|{}|{}|{}",
                method.sampler,
                method.filter,
                method.integrator,
                method.set,
                1024,
                1,
                env!("CARGO_PKG_VERSION")
            );
            fnv1a(&mut old, m.as_bytes());
            (reference_key(&path, &method, 1024, 1, None).unwrap(), old)
        };
        let (now, before) = key("plain.pbrt", plain);
        assert_eq!(now, before);
        let (now, before) = key("textured.pbrt", textured);
        assert_ne!(now, before);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn fnv_is_stable() {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        fnv1a(&mut h, b"a");
        assert_eq!(h, 0xaf63_dc4c_8601_ec8c);
    }
}
