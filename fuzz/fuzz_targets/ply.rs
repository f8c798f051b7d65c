//! PLY reader on arbitrary bytes: a mesh whose indices are all in range, or an error.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(ply) = acr_parser::ply::parse_ply(data) {
        let n = ply.mesh.positions.len();
        assert!(ply.mesh.indices.iter().all(|&i| (i as usize) < n));
    }
});
