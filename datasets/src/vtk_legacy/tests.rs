//! The legacy reader's own cases: both cell layouts in ASCII and binary, byte order, the
//! structured kinds and their cell data, mixed cells.

use super::*;
use crate::error::{ErrorKind, Location};

fn parse(text: &[u8]) -> Result<Dataset, LoadError> {
    from_bytes(text, Path::new("test.vtk"), &LoadOptions::default())
}

/// Two tets sharing a face, as ASCII legacy text of the given version and cell layout.
fn two_tets_ascii(version: &str, modern: bool) -> String {
    let cells = if modern {
        "CELLS 3 8\nOFFSETS vtktypeint64\n0 4 8\nCONNECTIVITY vtktypeint64\n0 1 2 3\n1 2 3 4\n"
    } else {
        "CELLS 2 10\n4 0 1 2 3\n4 1 2 3 4\n"
    };
    format!(
        "# vtk DataFile Version {version}\ntwo tets\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n0 0 0 1 0 0 0 1 0\n0 0 1 1 1 1\n{cells}CELL_TYPES 2\n10\n10\nPOINT_DATA 5\nSCALARS temp float 1\nLOOKUP_TABLE default\n0 1 2 3 4\nFIELD FieldData 1\npressure 1 5 double\n5 6 7 8 9\n"
    )
}

fn be_f32(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}
fn be_i32(v: &[i32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}
fn be_i64(v: &[i64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_be_bytes()).collect()
}

fn two_tets_binary(modern: bool) -> Vec<u8> {
    let mut b =
        b"# vtk DataFile Version 5.1\nbin\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n"
            .to_vec();
    b.extend(be_f32(&[
        0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 1., 1., 1.,
    ]));
    if modern {
        b.extend_from_slice(b"\nCELLS 3 8\nOFFSETS vtktypeint64\n");
        b.extend(be_i64(&[0, 4, 8]));
        b.extend_from_slice(b"\nCONNECTIVITY vtktypeint64\n");
        b.extend(be_i64(&[0, 1, 2, 3, 1, 2, 3, 4]));
    } else {
        b.extend_from_slice(b"\nCELLS 2 10\n");
        b.extend(be_i32(&[4, 0, 1, 2, 3, 4, 1, 2, 3, 4]));
    }
    b.extend_from_slice(b"\nCELL_TYPES 2\n");
    b.extend(be_i32(&[10, 10]));
    b.extend_from_slice(b"\nPOINT_DATA 5\nSCALARS temp double\nLOOKUP_TABLE default\n");
    b.extend([0f64, 1., 2., 3., 4.].iter().flat_map(|x| x.to_be_bytes()));
    b.extend_from_slice(b"\nMETADATA\nINFORMATION 0\n\n");
    b
}

fn check_two_tets(ds: &Dataset) {
    assert_eq!(ds.mesh.num_points(), 5);
    assert_eq!(ds.mesh.num_tets(), 2);
    assert_eq!(ds.mesh.scalar_name, "temp");
    assert_eq!(ds.mesh.scalars, vec![0., 1., 2., 3., 4.]);
    assert_eq!(ds.mesh.boundary_faces().len(), 6);
}

#[test]
fn ascii_legacy_layouts() {
    for (v, modern) in [
        ("2.0", false),
        ("3.0", false),
        ("4.2", false),
        ("5.1", true),
    ] {
        let ds = parse(two_tets_ascii(v, modern).as_bytes()).unwrap();
        check_two_tets(&ds);
    }
    let opts = LoadOptions {
        scalar: Some("pressure".into()),
        ..Default::default()
    };
    let ds = from_bytes(
        two_tets_ascii("4.2", false).as_bytes(),
        Path::new("t.vtk"),
        &opts,
    )
    .unwrap();
    assert_eq!(ds.mesh.scalars, vec![5., 6., 7., 8., 9.]);
    let opts = LoadOptions {
        scalar: Some("nope".into()),
        ..Default::default()
    };
    let err = from_bytes(
        two_tets_ascii("4.2", false).as_bytes(),
        Path::new("t.vtk"),
        &opts,
    )
    .unwrap_err();
    assert!(
        matches!(&err.kind, ErrorKind::MissingArray { available, .. } if available == &["temp", "pressure"]),
        "{err}"
    );
}

#[test]
fn binary_legacy_layouts() {
    check_two_tets(&parse(&two_tets_binary(false)).unwrap());
    check_two_tets(&parse(&two_tets_binary(true)).unwrap());
}

#[test]
fn little_endian_binary_is_a_byte_order_error() {
    let good = two_tets_binary(false);
    // Re-encode the CELL_TYPES block little-endian.
    let key = b"CELL_TYPES 2\n";
    let at = good.windows(key.len()).position(|w| w == key).unwrap() + key.len();
    let mut bad = good.clone();
    bad[at..at + 8].copy_from_slice(&[10, 0, 0, 0, 10, 0, 0, 0]);
    let err = parse(&bad).unwrap_err();
    assert!(matches!(err.kind, ErrorKind::ByteOrder(_)), "{err}");
    assert_eq!(err.location, Some(Location::Byte(at as u64)));
}

#[test]
fn structured_points_and_cell_data() {
    let text = b"# vtk DataFile Version 3.0\nv\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 3 2 2\nORIGIN 1 2 3\nSPACING 0.5 1 2\nCELL_DATA 2\nSCALARS c float\nLOOKUP_TABLE default\n1 3\n";
    let ds = parse(text).unwrap();
    let vol = ds.volume.as_ref().unwrap();
    assert_eq!(vol.dims, [3, 2, 2]);
    assert_eq!(ds.mesh.num_tets(), 10);
    assert_eq!(ds.mesh.points[11], [2.0, 3.0, 5.0]);
    // Middle column of points touches both cells: mean 2; the ends 1 and 3.
    assert_eq!(ds.mesh.scalars[0], 1.0);
    assert_eq!(ds.mesh.scalars[1], 2.0);
    assert_eq!(ds.mesh.scalars[2], 3.0);
    assert!(ds
        .mesh
        .repair
        .warnings
        .iter()
        .any(|w| w.contains("averaged")));
}

#[test]
fn rectilinear_and_structured_grid() {
    let text = b"# vtk DataFile Version 4.2\nr\nASCII\nDATASET RECTILINEAR_GRID\nDIMENSIONS 2 2 3\nX_COORDINATES 2 float\n0 1\nY_COORDINATES 2 double\n0 2\nZ_COORDINATES 3 float\n0 1 3\nPOINT_DATA 12\nSCALARS s int 1\nLOOKUP_TABLE default\n0 1 2 3 4 5 6 7 8 9 10 11\n";
    let ds = parse(text).unwrap();
    assert_eq!(ds.mesh.num_tets(), 10);
    assert_eq!(ds.mesh.points[11], [1.0, 2.0, 3.0]);
    let text = b"# vtk DataFile Version 4.2\ns\nASCII\nDATASET STRUCTURED_GRID\nDIMENSIONS 2 2 2\nPOINTS 8 float\n0 0 0 1 0 0 0 1 0 1 1 0 0 0 1 1 0 1 0 1 1 1 1 1\nPOINT_DATA 8\nVECTORS v float\n1 0 0 0 3 4 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0\n";
    let ds = parse(text).unwrap();
    assert_eq!(ds.mesh.num_tets(), 5);
    assert_eq!(ds.mesh.scalars[1], 5.0);
}

#[test]
fn mixed_cells_become_conforming_tets() {
    // A hexahedron, a wedge on top of it and a pyramid beside it.
    let text = b"# vtk DataFile Version 4.2\nmix\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 11 float\n0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1\n0.5 0 2 0.5 1 2\n2 0.5 0.5\nCELLS 3 22\n8 0 1 2 3 4 5 6 7\n6 4 5 8 7 6 9\n5 1 2 6 5 10\nCELL_TYPES 3\n12\n13\n14\n";
    let ds = parse(text).unwrap();
    assert_eq!(ds.mesh.num_tets(), 6 + 3 + 2);
    // Conforming: every internal face has two tets, so the boundary is the outer surface:
    // hex 4 free quads (8 tris) + wedge 2 tris + 2 quads (4 tris) + pyramid 4 tris.
    assert_eq!(ds.mesh.boundary_faces().len(), 8 + 2 + 4 + 4);
    let total: f64 = (0..ds.mesh.num_tets())
        .map(|t| crate::mesh::signed_volume6(ds.mesh.tet_points(t)) / 6.0)
        .sum();
    assert!((total - (1.0 + 0.5 + 1.0 / 3.0)).abs() < 1e-6, "{total}");
}

// The fuzz targets (datasets/fuzz) run for minutes; this is their quick stand-in that CI
// runs every time: random bytes and random corruptions of valid files (ASCII and BINARY,
// both cell layouts) give a mesh or a LoadError, never a panic.
proptest::proptest! {
    #[test]
    fn random_bytes_never_panic(data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..600)) {
        let mut with_header = b"# vtk DataFile Version 4.2\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\n".to_vec();
        with_header.extend_from_slice(&data);
        let _ = parse(&data);
        let _ = parse(&with_header);
    }

    #[test]
    fn corrupted_files_never_panic(which in 0usize..4, edits in proptest::collection::vec((proptest::prelude::any::<usize>(), proptest::prelude::any::<u8>()), 1..6)) {
        let mut b = match which {
            0 => two_tets_ascii("4.2", false).into_bytes(),
            1 => two_tets_ascii("5.1", true).into_bytes(),
            2 => two_tets_binary(false),
            _ => two_tets_binary(true),
        };
        for (at, v) in edits {
            let i = at % b.len();
            b[i] = v;
        }
        let _ = parse(&b);
    }
}
