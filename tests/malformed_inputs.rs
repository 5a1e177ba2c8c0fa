//! A corpus of malformed files, made here, one per fault: every reader must answer with the
//! specific typed error, naming the faulty file (and where in it), never a panic.

use std::path::{Path, PathBuf};

use datasets::load::load;
use datasets::{ErrorKind, LoadError, LoadOptions, Location, Plot3dField};

/// Writes `files` (name, bytes) into a fresh directory, loads the first, returns the error and
/// the directory (kept alive by the caller).
fn fail_with(files: &[(&str, Vec<u8>)], options: &LoadOptions) -> (LoadError, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    let path = dir.path().join(files[0].0);
    match load(&path, options) {
        Ok(ds) => panic!(
            "{} loaded ({} tets) but should fail",
            files[0].0,
            ds.mesh.num_tets()
        ),
        Err(e) => {
            // Every error prints as "file: [where:] what".
            assert!(e.to_string().starts_with(&e.path.display().to_string()));
            (e, dir)
        }
    }
}

/// Loads one file expected to fail, asserting the error names it.
fn fail(name: &str, bytes: impl Into<Vec<u8>>) -> LoadError {
    fail_opts(name, bytes, &LoadOptions::default())
}

fn fail_opts(name: &str, bytes: impl Into<Vec<u8>>, options: &LoadOptions) -> LoadError {
    let (e, dir) = fail_with(&[(name, bytes.into())], options);
    assert_eq!(
        e.path,
        dir.path().join(name),
        "error names another file: {e}"
    );
    e
}

/// Loads the malformed legacy VTK file `case` of the shared corpus (`tests/malformed_vtk.rs`).
fn fail_case(case: &str) -> LoadError {
    let c = tetbench_tests::malformed_vtk::case(case);
    let options = LoadOptions {
        scalar: c.scalar.map(String::from),
        ..Default::default()
    };
    fail_opts(c.file, c.bytes, &options)
}

fn in_dir(e: &LoadError, name: &str) -> bool {
    e.path.file_name().is_some_and(|n| n == name)
}

// ------------------------------------------------------------------------------------------
// Legacy VTK

#[test]
fn the_well_formed_base_loads() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("ok.vtk");
    let base = tetbench_tests::malformed_vtk::case("well_formed_base");
    std::fs::write(&p, base.bytes).unwrap();
    assert_eq!(
        load(&p, &LoadOptions::default()).unwrap().mesh.num_tets(),
        2
    );
}

#[test]
fn vtk_not_a_vtk_header() {
    let e = fail_case("not_a_vtk_header");
    assert!(matches!(e.kind, ErrorKind::Syntax { .. }), "{e}");
    assert_eq!(e.location, Some(Location::Line(1)));
}

#[test]
fn vtk_unsupported_version() {
    let e = fail_case("unsupported_version");
    assert!(matches!(e.kind, ErrorKind::Unsupported(_)), "{e}");
}

#[test]
fn vtk_polydata_is_unsupported() {
    let e = fail_case("polydata");
    assert!(
        matches!(&e.kind, ErrorKind::Unsupported(s) if s.contains("POLYDATA")),
        "{e}"
    );
    assert_eq!(e.location, Some(Location::Line(4)));
}

#[test]
fn vtk_truncated_points() {
    let e = fail_case("truncated_points");
    assert!(matches!(e.kind, ErrorKind::Truncated { .. }), "{e}");
}

#[test]
fn vtk_absurd_point_count_is_checked_against_the_file_size() {
    // A billion points announced in a 100-byte file: refused before anything is allocated.
    let e = fail_case("absurd_point_count");
    assert!(
        matches!(&e.kind, ErrorKind::Truncated { expected } if expected.contains("1000000000") || expected.contains("3000000000")),
        "{e}"
    );
}

#[test]
fn vtk_point_count_overflowing_u32() {
    let e = fail_case("point_count_overflowing_u32");
    assert!(
        matches!(
            e.kind,
            ErrorKind::IndexOverflow {
                count: 5_000_000_000,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(e.location, Some(Location::Line(5)));
}

#[test]
fn vtk_index_out_of_range() {
    let e = fail_case("index_out_of_range");
    assert_eq!(
        e.kind,
        ErrorKind::IndexOutOfRange {
            what: "point".into(),
            index: 9,
            limit: 5
        }
    );
    assert_eq!(e.location, Some(Location::Line(10)));
}

#[test]
fn vtk_nan_coordinate() {
    let e = fail_case("nan_coordinate");
    assert!(
        matches!(e.kind, ErrorKind::NonFinite { index: 2, .. }),
        "{e}"
    );
    assert_eq!(e.location, Some(Location::Line(6)));
}

#[test]
fn vtk_infinite_scalar() {
    let e = fail_case("infinite_scalar");
    assert!(
        matches!(e.kind, ErrorKind::NonFinite { index: 3, .. }),
        "{e}"
    );
    assert_eq!(e.location, Some(Location::Line(18)));
}

#[test]
fn vtk_unknown_cell_type_is_named() {
    let e = fail_case("unknown_cell_type");
    assert!(
        matches!(&e.kind, ErrorKind::UnknownCellType(s) if s.starts_with("5 (VTK_TRIANGLE)")),
        "{e}"
    );
    assert_eq!(e.location, Some(Location::Line(13)));
}

#[test]
fn vtk_cell_types_count_mismatch() {
    let e = fail_case("cell_types_count_mismatch");
    assert!(
        matches!(
            e.kind,
            ErrorKind::CountMismatch {
                expected: 2,
                found: 1,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn vtk_cells_size_mismatch() {
    let e = fail_case("cells_size_mismatch");
    assert!(
        matches!(
            e.kind,
            ErrorKind::CountMismatch {
                expected: 11,
                found: 10,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn vtk_point_data_count_mismatch() {
    let e = fail_case("point_data_count_mismatch");
    assert!(
        matches!(
            e.kind,
            ErrorKind::CountMismatch {
                expected: 5,
                found: 4,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn vtk_wrong_vertex_count_for_tet() {
    let e = fail_case("wrong_vertex_count_for_tet");
    assert!(
        matches!(
            e.kind,
            ErrorKind::CountMismatch {
                expected: 4,
                found: 3,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn vtk_no_cells_is_an_empty_mesh() {
    let e = fail_case("no_cells");
    assert!(matches!(e.kind, ErrorKind::EmptyMesh(_)), "{e}");
}

#[test]
fn vtk_all_tets_degenerate_is_an_empty_mesh() {
    let e = fail_case("all_tets_degenerate");
    assert!(
        matches!(&e.kind, ErrorKind::EmptyMesh(s) if s.contains("2 degenerate")),
        "{e}"
    );
}

#[test]
fn vtk_missing_array() {
    let e = fail_case("missing_array");
    assert_eq!(
        e.kind,
        ErrorKind::MissingArray {
            name: "temperature".into(),
            available: vec!["s".into()]
        }
    );
}

#[test]
fn vtk_bad_number() {
    let e = fail_case("bad_number");
    assert!(
        matches!(&e.kind, ErrorKind::Syntax { found, .. } if found == "one"),
        "{e}"
    );
    assert_eq!(e.location, Some(Location::Line(7)));
}

#[test]
fn vtk_51_offsets_must_not_decrease() {
    let e = fail_case("offsets_decreasing_51");
    assert!(matches!(e.kind, ErrorKind::Invalid(_)), "{e}");
}

#[test]
fn vtk_binary_little_endian_is_a_byte_order_error() {
    let e = fail_case("binary_little_endian");
    assert!(matches!(e.kind, ErrorKind::ByteOrder(_)), "{e}");
    assert!(matches!(e.location, Some(Location::Byte(_))));
}

#[test]
fn vtk_binary_truncated() {
    let e = fail_case("binary_truncated");
    assert!(matches!(e.kind, ErrorKind::Truncated { .. }), "{e}");
    assert!(matches!(e.location, Some(Location::Byte(_))));
}

#[test]
fn vtk_structured_points_overflowing_u32() {
    let e = fail_case("structured_points_overflowing_u32");
    assert!(matches!(e.kind, ErrorKind::IndexOverflow { .. }), "{e}");
}

#[test]
fn vtk_structured_points_without_data() {
    // 10⁹ implicit points and no data backing them: refused, not allocated.
    let e = fail_case("structured_points_without_data");
    assert!(matches!(e.kind, ErrorKind::MissingArray { .. }), "{e}");
}

// ------------------------------------------------------------------------------------------
// TOFF

const TOFF: &str = "5\n2\n0 0 0 0.5\n1 0 0 1\n0 1 0 2\n0 0 1 3\n1 1 1 4\n0 1 2 3\n1 2 3 4\n";

#[test]
fn toff_index_out_of_range() {
    let e = fail("m.toff", TOFF.replace("1 2 3 4", "1 2 3 7"));
    assert_eq!(
        e.kind,
        ErrorKind::IndexOutOfRange {
            what: "point".into(),
            index: 7,
            limit: 5
        }
    );
    assert_eq!(e.location, Some(Location::Line(9)));
}

#[test]
fn toff_truncated() {
    let e = fail(
        "m.toff",
        "5\n2\n0 0 0 0.5\n1 0 0 1\n0 1 0 2\n0 0 1 3\n1 1 1 4\n0 1 2 3\n1 2\n",
    );
    assert!(matches!(e.kind, ErrorKind::Truncated { .. }), "{e}");
}

#[test]
fn toff_absurd_counts() {
    let e = fail("m.toff", "4000000000\n4000000000\n0 0 0 0\n");
    assert!(matches!(e.kind, ErrorKind::Truncated { .. }), "{e}");
}

#[test]
fn toff_count_overflowing_u32() {
    let e = fail("m.toff", "5000000000\n1\n0 0 0 0\n");
    assert!(
        matches!(
            e.kind,
            ErrorKind::IndexOverflow {
                count: 5_000_000_000,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(e.location, Some(Location::Line(1)));
}

#[test]
fn toff_infinite_scalar() {
    let e = fail("m.toff", TOFF.replace("0 0 1 3", "0 0 1 1e400"));
    assert!(
        matches!(e.kind, ErrorKind::NonFinite { index: 3, .. }),
        "{e}"
    );
    assert_eq!(e.location, Some(Location::Line(6)));
}

#[test]
fn toff_not_a_number() {
    let e = fail("m.toff", TOFF.replace("1 0 0 1", "1 0 x 1"));
    assert!(
        matches!(&e.kind, ErrorKind::Syntax { found, .. } if found == "x"),
        "{e}"
    );
}

#[test]
fn toff_trailing_data_is_a_wrong_count() {
    let e = fail("m.toff", format!("{TOFF}0 1 2 4\n"));
    assert!(matches!(e.kind, ErrorKind::Syntax { .. }), "{e}");
    assert_eq!(e.location, Some(Location::Line(10)));
}

#[test]
fn toff_no_tets() {
    let e = fail("m.toff", "1\n0\n0 0 0 0\n");
    assert!(matches!(e.kind, ErrorKind::EmptyMesh(_)), "{e}");
}

#[test]
fn geomview_off_is_not_toff() {
    let e = fail("m.off", "OFF\n4 4 6\n0 0 0\n");
    assert!(matches!(e.kind, ErrorKind::Syntax { .. }), "{e}");
}

// ------------------------------------------------------------------------------------------
// PLOT3D

fn plot3d_pair(dims: [usize; 3], q: impl Fn(usize) -> [f32; 5]) -> (Vec<u8>, Vec<u8>) {
    datasets::plot3d::write_test_pair(
        dims,
        datasets::load::ByteOrder::Big,
        false,
        false,
        |i, j, k| [i as f32, j as f32, k as f32],
        q,
    )
}

#[test]
fn plot3d_truncated_grid() {
    let (x, q) = plot3d_pair([3, 3, 3], |_| [1.0, 0.0, 0.0, 0.0, 2.5]);
    let (e, _d) = fail_with(
        &[("gxyz.bin", x[..x.len() - 10].to_vec()), ("gq.bin", q)],
        &LoadOptions::default(),
    );
    assert!(matches!(e.kind, ErrorKind::Truncated { .. }), "{e}");
    assert!(in_dir(&e, "gxyz.bin"));
}

#[test]
fn plot3d_q_grid_mismatch_names_the_q_file() {
    let (x, _) = plot3d_pair([3, 3, 3], |_| [1.0, 0.0, 0.0, 0.0, 2.5]);
    let (_, q) = plot3d_pair([3, 3, 2], |_| [1.0, 0.0, 0.0, 0.0, 2.5]);
    let (e, _d) = fail_with(&[("gxyz.bin", x), ("gq.bin", q)], &LoadOptions::default());
    assert!(
        matches!(
            e.kind,
            ErrorKind::CountMismatch {
                expected: 27,
                found: 18,
                ..
            }
        ),
        "{e}"
    );
    assert!(in_dir(&e, "gq.bin"));
}

#[test]
fn plot3d_missing_q_file() {
    let (x, _) = plot3d_pair([3, 3, 3], |_| [1.0, 0.0, 0.0, 0.0, 2.5]);
    let (e, _d) = fail_with(&[("gxyz.bin", x)], &LoadOptions::default());
    assert!(matches!(e.kind, ErrorKind::Io(_)), "{e}");
    assert!(
        in_dir(&e, "gq.bin"),
        "the error names the Q file it looked for: {e}"
    );
}

#[test]
fn plot3d_garbage_header() {
    let mut x = vec![0xffu8; 12];
    x.extend([0u8; 100]);
    let (e, _d) = fail_with(
        &[("gxyz.bin", x), ("gq.bin", vec![0; 40])],
        &LoadOptions::default(),
    );
    assert!(matches!(e.kind, ErrorKind::Syntax { .. }), "{e}");
    assert_eq!(e.location, Some(Location::Byte(0)));
}

#[test]
fn plot3d_grid_overflowing_u32() {
    let x: Vec<u8> = [100_000i32, 100_000, 100_000]
        .iter()
        .flat_map(|v| v.to_be_bytes())
        .collect();
    let (e, _d) = fail_with(
        &[("gxyz.bin", x), ("gq.bin", vec![0; 40])],
        &LoadOptions::default(),
    );
    assert!(matches!(e.kind, ErrorKind::IndexOverflow { .. }), "{e}");
}

#[test]
fn plot3d_data_in_the_other_byte_order() {
    let (mut x, q) = plot3d_pair([3, 3, 3], |_| [1.0, 0.0, 0.0, 0.0, 2.5]);
    // Re-encode the coordinates little-endian under the big-endian header.
    for c in x[12..].chunks_exact_mut(4) {
        c.reverse();
    }
    // A value NaN as read big-endian (as the header says), a finite denormal little-endian.
    x[16..20].copy_from_slice(&[0x7f, 0xc0, 0x00, 0x00]);
    let (e, _d) = fail_with(&[("gxyz.bin", x), ("gq.bin", q)], &LoadOptions::default());
    assert!(matches!(e.kind, ErrorKind::ByteOrder(_)), "{e}");
    assert_eq!(e.location, Some(Location::Byte(16)));
}

#[test]
fn plot3d_nan_density_names_the_q_file() {
    let (x, q) = plot3d_pair([3, 3, 3], |p| {
        [if p == 5 { f32::NAN } else { 1.0 }, 0.0, 0.0, 0.0, 2.5]
    });
    let (e, _d) = fail_with(&[("gxyz.bin", x), ("gq.bin", q)], &LoadOptions::default());
    assert!(
        matches!(e.kind, ErrorKind::NonFinite { index: 5, .. }),
        "{e}"
    );
    assert!(in_dir(&e, "gq.bin"));
    assert_eq!(e.location, Some(Location::Byte(28 + 5 * 4)));
}

#[test]
fn plot3d_zero_density_velocity() {
    let (x, q) = plot3d_pair([3, 3, 3], |p| {
        [if p == 2 { 0.0 } else { 1.0 }, 1.0, 0.0, 0.0, 2.5]
    });
    let opts = LoadOptions {
        plot3d_field: Some(Plot3dField::VelocityMagnitude),
        ..Default::default()
    };
    let (e, _d) = fail_with(&[("gxyz.bin", x), ("gq.bin", q)], &opts);
    assert!(
        matches!(e.kind, ErrorKind::NonFinite { index: 2, .. }),
        "{e}"
    );
}

#[test]
fn plot3d_unknown_field_name() {
    let (x, q) = plot3d_pair([2, 2, 2], |_| [1.0, 0.0, 0.0, 0.0, 2.5]);
    let opts = LoadOptions {
        scalar: Some("vorticity".into()),
        ..Default::default()
    };
    let (e, _d) = fail_with(&[("gxyz.bin", x), ("gq.bin", q)], &opts);
    assert!(
        matches!(&e.kind, ErrorKind::MissingArray { available, .. } if available.len() == 5),
        "{e}"
    );
}

// ------------------------------------------------------------------------------------------
// MetaImage

fn mhd(header: &str, raw: Option<Vec<u8>>) -> LoadError {
    let mut files = vec![("img.mhd", header.as_bytes().to_vec())];
    if let Some(r) = raw {
        files.push(("img.raw", r));
    }
    fail_with(&files, &LoadOptions::default()).0
}

const MHD: &str = "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = img.raw\n";

#[test]
fn mhd_missing_raw_file() {
    let e = mhd(MHD, None);
    assert!(matches!(e.kind, ErrorKind::Io(_)), "{e}");
    assert!(in_dir(&e, "img.raw"));
}

#[test]
fn mhd_raw_too_short() {
    let e = mhd(MHD, Some(vec![1; 5]));
    assert!(matches!(e.kind, ErrorKind::Truncated { .. }), "{e}");
    assert!(in_dir(&e, "img.raw"));
    assert_eq!(e.location, Some(Location::Byte(5)));
}

#[test]
fn mhd_dims_overflowing_u32() {
    let e = mhd(
        &MHD.replace("2 2 2", "100000 100000 100000"),
        Some(vec![1; 8]),
    );
    assert!(matches!(e.kind, ErrorKind::IndexOverflow { .. }), "{e}");
    assert!(in_dir(&e, "img.mhd"));
    assert_eq!(e.location, Some(Location::Line(3)));
}

#[test]
fn mhd_wrong_byte_order_flag() {
    let mut raw: Vec<u8> = (0..8)
        .flat_map(|i| (1.0f32 + i as f32).to_le_bytes())
        .collect();
    raw[4..8].copy_from_slice(&[0x7f, 0xc0, 0x00, 0x00]);
    let e = mhd(
        &MHD.replace("MET_UCHAR", "MET_FLOAT\nBinaryDataByteOrderMSB = True"),
        Some(raw),
    );
    assert!(matches!(e.kind, ErrorKind::ByteOrder(_)), "{e}");
    assert_eq!(e.location, Some(Location::Byte(4)));
}

#[test]
fn mhd_nan_voxel() {
    let mut raw: Vec<u8> = (0..8)
        .flat_map(|i| (1.0f32 + i as f32).to_le_bytes())
        .collect();
    raw[8..12].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = mhd(&MHD.replace("MET_UCHAR", "MET_FLOAT"), Some(raw));
    assert!(
        matches!(e.kind, ErrorKind::NonFinite { index: 2, .. }),
        "{e}"
    );
}

#[test]
fn mhd_two_dimensional() {
    let e = mhd(&MHD.replace("NDims = 3", "NDims = 2"), Some(vec![1; 8]));
    assert!(matches!(e.kind, ErrorKind::Unsupported(_)), "{e}");
    assert_eq!(e.location, Some(Location::Line(2)));
}

#[test]
fn mhd_unknown_element_type() {
    let e = mhd(
        &MHD.replace("MET_UCHAR", "MET_LONG_LONG"),
        Some(vec![1; 64]),
    );
    assert!(
        matches!(&e.kind, ErrorKind::Unsupported(s) if s.contains("MET_LONG_LONG")),
        "{e}"
    );
}

#[test]
fn mhd_missing_data_file_key() {
    let e = mhd(
        "NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\n",
        None,
    );
    assert!(
        matches!(&e.kind, ErrorKind::Truncated { expected } if expected.contains("ElementDataFile")),
        "{e}"
    );
}

// ------------------------------------------------------------------------------------------
// Unknown content

#[test]
fn unknown_format() {
    let e = fail("mystery.dat", vec![0x13u8, 0x37, 0x00, 0x42, 0x99]);
    assert!(matches!(e.kind, ErrorKind::UnknownFormat(_)), "{e}");
}

#[test]
fn missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let p: PathBuf = dir.path().join("nowhere.vtk");
    let e = load(&p, &LoadOptions::default()).unwrap_err();
    assert!(matches!(e.kind, ErrorKind::Io(_)));
    assert_eq!(e.path, p);
    let _: &Path = &e.path;
}
