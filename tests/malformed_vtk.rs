//! The malformed legacy VTK files of the corpus, one per fault, by case name.
//!
//! `tests/malformed_inputs.rs` checks the typed error our reader gives for each;
//! `tests/vtkio_oracle.rs` feeds the same bytes to vtkio. Keeping them in one table means a case
//! added here is seen by both.

/// One malformed file: the case, the file name it is written under, its bytes, and the point
/// array asked for (`--scalar`), if any.
pub struct MalformedVtk {
    pub case: &'static str,
    pub file: &'static str,
    pub bytes: Vec<u8>,
    pub scalar: Option<&'static str>,
}

const HEAD: &str = "# vtk DataFile Version 4.2\nmalformed\nASCII\nDATASET UNSTRUCTURED_GRID\n";
const PTS: &str = "POINTS 5 float\n0 0 0 1 0 0 0 1 0\n0 0 1 1 1 1\n";
const CELLS: &str = "CELLS 2 10\n4 0 1 2 3\n4 1 2 3 4\nCELL_TYPES 2\n10\n10\n";
const DATA: &str = "POINT_DATA 5\nSCALARS s float\nLOOKUP_TABLE default\n0 1 2 3 4\n";

/// An ASCII unstructured grid: the common header, then `body`.
fn vtk(body: &str) -> Vec<u8> {
    format!("{HEAD}{body}").into_bytes()
}

fn be_i32(v: &[i32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}

/// A BINARY grid of two tets whose CELL_TYPES block is `cell_types`.
fn binary_vtk(cell_types: Vec<u8>) -> Vec<u8> {
    let mut b =
        b"# vtk DataFile Version 4.2\nb\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n"
            .to_vec();
    b.extend(
        [0f32, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 1., 1., 1.]
            .iter()
            .flat_map(|v| v.to_be_bytes()),
    );
    b.extend_from_slice(b"\nCELLS 2 10\n");
    b.extend(be_i32(&[4, 0, 1, 2, 3, 4, 1, 2, 3, 4]));
    b.extend_from_slice(b"\nCELL_TYPES 2\n");
    b.extend(cell_types);
    b.push(b'\n');
    b
}

/// Every case (the first, `well_formed_base`, is the valid file the others spoil).
pub fn cases() -> Vec<MalformedVtk> {
    let a = |case, body: String| MalformedVtk {
        case,
        file: "a.vtk",
        bytes: vtk(&body),
        scalar: None,
    };
    let raw = |case, file, bytes: Vec<u8>| MalformedVtk {
        case,
        file,
        bytes,
        scalar: None,
    };
    let mut le: Vec<u8> = 10i32.to_le_bytes().to_vec();
    le.extend(10i32.to_le_bytes());
    let good_binary = binary_vtk(be_i32(&[10, 10]));
    vec![
        a("well_formed_base", format!("{PTS}{CELLS}{DATA}")),
        raw("not_a_vtk_header", "a.vtk", b"hello world\n".to_vec()),
        raw(
            "unsupported_version",
            "a.vtk",
            b"# vtk DataFile Version 6.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n".to_vec(),
        ),
        raw(
            "polydata",
            "a.vtk",
            b"# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n".to_vec(),
        ),
        a(
            "truncated_points",
            "POINTS 5 float\n0 0 0 1 0 0 0 1 0\n".into(),
        ),
        a(
            "absurd_point_count",
            "POINTS 1000000000 float\n0 0 0\n".into(),
        ),
        a(
            "point_count_overflowing_u32",
            "POINTS 5000000000 float\n0 0 0\n".into(),
        ),
        a(
            "index_out_of_range",
            format!("{PTS}CELLS 2 10\n4 0 1 2 3\n4 1 2 3 9\nCELL_TYPES 2\n10\n10\n{DATA}"),
        ),
        a(
            "nan_coordinate",
            format!("POINTS 5 float\n0 0 0 1 0 0 0 nan 0\n0 0 1 1 1 1\n{CELLS}{DATA}"),
        ),
        a(
            "infinite_scalar",
            format!(
                "{PTS}{CELLS}POINT_DATA 5\nSCALARS s double\nLOOKUP_TABLE default\n0 1\n2 inf 4\n"
            ),
        ),
        a(
            "unknown_cell_type",
            format!("{PTS}CELLS 2 9\n4 0 1 2 3\n3 1 2 3\nCELL_TYPES 2\n10\n5\n{DATA}"),
        ),
        a(
            "cell_types_count_mismatch",
            format!("{PTS}CELLS 2 10\n4 0 1 2 3\n4 1 2 3 4\nCELL_TYPES 1\n10\n{DATA}"),
        ),
        a(
            "cells_size_mismatch",
            format!("{PTS}CELLS 2 11\n4 0 1 2 3\n4 1 2 3 4 0\nCELL_TYPES 2\n10\n10\n{DATA}"),
        ),
        a(
            "point_data_count_mismatch",
            format!("{PTS}{CELLS}POINT_DATA 4\nSCALARS s float\nLOOKUP_TABLE default\n0 1 2 3\n"),
        ),
        a(
            "wrong_vertex_count_for_tet",
            format!("{PTS}CELLS 2 9\n4 0 1 2 3\n3 1 2 3\nCELL_TYPES 2\n10\n10\n{DATA}"),
        ),
        a("no_cells", format!("{PTS}{DATA}")),
        a(
            "all_tets_degenerate",
            format!("POINTS 5 float\n0 0 0 1 0 0 0 1 0\n1 1 0 2 2 0\n{CELLS}{DATA}"),
        ),
        MalformedVtk {
            case: "missing_array",
            file: "a.vtk",
            bytes: vtk(&format!("{PTS}{CELLS}{DATA}")),
            scalar: Some("temperature"),
        },
        a(
            "bad_number",
            format!("POINTS 5 float\n0 0 0 1 0 0 0 1 0\n0 0 1 1 1 one\n{CELLS}"),
        ),
        a(
            "offsets_decreasing_51",
            format!("{PTS}CELLS 3 8\nOFFSETS vtktypeint64\n0 5 4\nCONNECTIVITY vtktypeint64\n0 1 2 3 1 2 3 4\nCELL_TYPES 2\n10\n10\n"),
        ),
        raw("binary_little_endian", "b.vtk", binary_vtk(le)),
        raw(
            "binary_truncated",
            "b.vtk",
            good_binary[..good_binary.len() - 6].to_vec(),
        ),
        raw(
            "structured_points_overflowing_u32",
            "v.vtk",
            b"# vtk DataFile Version 3.0\nv\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 100000 100000 100000\nPOINT_DATA 1\nSCALARS s float\n0\n".to_vec(),
        ),
        // 10⁹ implicit points and no data backing them: must be refused, not allocated.
        raw(
            "structured_points_without_data",
            "v.vtk",
            b"# vtk DataFile Version 3.0\nv\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 1000 1000 1000\nSPACING 1 1 1\n".to_vec(),
        ),
    ]
}

/// The case named `case` (panics on a name not in [`cases`]: a typo in a test).
pub fn case(case: &str) -> MalformedVtk {
    cases()
        .into_iter()
        .find(|c| c.case == case)
        .unwrap_or_else(|| panic!("no malformed VTK case {case:?}"))
}
