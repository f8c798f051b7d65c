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
        fnv1a(&mut h, f.text.as_bytes());
        fnv1a(&mut h, &[0xff]);
    }
    // Meshes and images the scene loads are files too; their bytes count when present.
    let dir = scene.parent().unwrap_or(Path::new("."));
    for f in &desc.files {
        for word in f.text.split('"') {
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

    #[test]
    fn fnv_is_stable() {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        fnv1a(&mut h, b"a");
        assert_eq!(h, 0xaf63_dc4c_8601_ec8c);
    }
}
