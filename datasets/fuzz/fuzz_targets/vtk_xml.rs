//! Any byte string given to the VTK XML reader yields a mesh or a `LoadError`, never a panic.
//! The seeds (VTK's own writers: ASCII, inline base64 with and without zlib, appended raw,
//! raw + zlib and base64, UInt64 headers big-endian; `.vtu`, `.vts`, `.vti`) put the fuzzer in
//! every data-array decoding path at once.
#![no_main]

use datasets::LoadOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = datasets::vtk_xml::from_bytes(data, "fuzz.vtu".as_ref(), &LoadOptions::default());
});
