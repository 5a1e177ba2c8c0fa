//! Any pair of byte strings given to the PLOT3D reader as XYZ and Q files yields a mesh or a
//! `LoadError`, never a panic. The first two bytes choose where the input splits into the two
//! files; the third picks the Q field.
#![no_main]

use datasets::{LoadOptions, Plot3dField};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 3 {
        return;
    }
    let rest = &data[3..];
    let split = u16::from_le_bytes([data[0], data[1]]) as usize % (rest.len() + 1);
    let (xyz, q) = rest.split_at(split);
    let field = Plot3dField::ALL[data[2] as usize % Plot3dField::ALL.len()];
    let options = LoadOptions {
        plot3d_field: Some(field),
        ..Default::default()
    };
    let _ = datasets::plot3d::from_bytes(
        xyz,
        q,
        "fuzz_xyz.bin".as_ref(),
        "fuzz_q.bin".as_ref(),
        &options,
    );
});
