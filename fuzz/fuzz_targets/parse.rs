//! Fuzz target `parse`: see [`cases::parse`].
#![no_main]

#[path = "../cases.rs"]
mod cases;

libfuzzer_sys::fuzz_target!(|data: &[u8]| cases::parse(data));
