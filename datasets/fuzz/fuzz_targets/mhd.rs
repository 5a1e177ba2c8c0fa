//! Any header and data byte strings given to the MetaImage reader yield a mesh or a
//! `LoadError`, never a panic. The first two bytes (little-endian u16) choose where the rest
//! splits into the `.mhd` header and the data file it names (with `ElementDataFile = LOCAL`
//! the data is the header's tail, as in an `.mha`), like the PLOT3D target's XYZ/Q split.
#![no_main]

use datasets::LoadOptions;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 {
        return;
    }
    let rest = &data[2..];
    let split = u16::from_le_bytes([data[0], data[1]]) as usize % (rest.len() + 1);
    let (header, raw) = rest.split_at(split);
    let _ = datasets::mhd::from_bytes(header, raw, "fuzz.mhd".as_ref(), &LoadOptions::default());
});
