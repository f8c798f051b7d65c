//! Fuzz target `ply`: see [`cases::ply`].
#![no_main]

#[path = "../cases.rs"]
mod cases;

libfuzzer_sys::fuzz_target!(|data: &[u8]| cases::ply(data));
