//! Fuzz target `fourier`: see [`cases::fourier`].
#![no_main]

#[path = "../cases.rs"]
mod cases;

libfuzzer_sys::fuzz_target!(|data: &[u8]| cases::fourier(data));
