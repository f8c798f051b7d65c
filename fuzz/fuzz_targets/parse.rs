//! Tokenizer, parser and graphics-state builder on arbitrary text: any input gives a scene or an
//! error, never a panic, a hang or a huge allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        // A directory that does not exist: Include and plymesh names fail cleanly instead of
        // reading whatever the fuzzer names.
        let _ = acr_parser::parse_str(text, Path::new("/nonexistent-acr-fuzz/scene.pbrt"));
    }
});
