//! Any byte string given to the legacy VTK reader yields a mesh or a `LoadError`, never a panic,
//! hang or huge allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = datasets::vtk_legacy::from_bytes(
        data,
        std::path::Path::new("fuzz.vtk"),
        &datasets::LoadOptions::default(),
    );
});
