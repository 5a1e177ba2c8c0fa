//! Any byte string given to the TOFF reader yields a mesh or a `LoadError`, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = datasets::toff::from_bytes(
        data,
        std::path::Path::new("fuzz.toff"),
        &datasets::LoadOptions::default(),
    );
});
