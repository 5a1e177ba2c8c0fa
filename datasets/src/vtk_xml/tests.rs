//! Tests of the VTK XML reader: every layout our writer and VTK write, mixed cells, cell data,
//! structured grids and images, malformed and damaged files, and the fuzz seeds.

use super::xml::find;
use super::*;
use crate::mesh::TetMesh;
use crate::write_vtu::{vtu_bytes, VtuFormat, VtuOptions};

fn data_file(name: &str) -> Option<std::path::PathBuf> {
    crate::data_dir::test_data_file(name)
}

fn parse(text: &str) -> Result<Dataset, LoadError> {
    from_bytes(
        text.as_bytes(),
        Path::new("test.vtu"),
        &LoadOptions::default(),
    )
}

fn kind(text: &str) -> ErrorKind {
    parse(text).expect_err("must fail").kind
}

#[test]
fn reads_vtk_tetrahedron_vtu() {
    let Some(p) = data_file("Tetrahedron.vtu") else {
        return;
    };
    let ds = read(&p, &LoadOptions::default()).unwrap();
    assert_eq!((ds.mesh.num_points(), ds.mesh.num_tets()), (35, 96));
    assert_eq!(ds.mesh.scalar_name, "DistanceToCenter");
    let (lo, hi) = ds.mesh.scalar_range();
    assert!(
        lo.abs() < 1e-6 && (hi - 1.7320508).abs() < 1e-5,
        "{lo} {hi}"
    );
    let opts = LoadOptions {
        scalar: Some("Polynomial".into()),
        ..Default::default()
    };
    let ds = read(&p, &opts).unwrap();
    assert_eq!(ds.mesh.scalar_range(), (1.0, 7.0));
    let opts = LoadOptions {
        scalar: Some("Nope".into()),
        ..Default::default()
    };
    let err = read(&p, &opts).unwrap_err();
    assert!(
        matches!(&err.kind, ErrorKind::MissingArray { available, .. } if available.len() == 2),
        "{err}"
    );
}

fn all_layouts() -> Vec<VtuOptions> {
    let mut v = Vec::new();
    for format in [
        VtuFormat::Ascii,
        VtuFormat::Binary,
        VtuFormat::Appended,
        VtuFormat::AppendedBase64,
    ] {
        for compress in [false, true] {
            for header64 in [false, true] {
                for big_endian in [false, true] {
                    if format == VtuFormat::Ascii && (compress || big_endian) {
                        continue;
                    }
                    v.push(VtuOptions {
                        format,
                        compress,
                        header64,
                        big_endian,
                    });
                }
            }
        }
    }
    v
}

#[test]
fn every_layout_reads_the_same_mesh() {
    let mut mesh = crate::generate::from_spec("slivers:3k:field=blobs", 5).unwrap();
    mesh.scalar_name = "a <strange> & \"quoted\" name".into();
    for o in all_layouts() {
        let bytes = vtu_bytes(&mesh, &o);
        let ds = from_bytes(&bytes, Path::new("x.vtu"), &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{o:?}: {e}"));
        let m = &ds.mesh;
        assert_eq!(m.points, mesh.points, "{o:?}");
        assert_eq!(m.scalars, mesh.scalars, "{o:?}");
        assert_eq!(m.tets, mesh.tets, "{o:?}");
        assert_eq!(m.scalar_name, mesh.scalar_name, "{o:?}");
    }
}

/// Unit cube hexahedron 0..7, a pyramid on its top face (apex 8) and a wedge on its x=1
/// face (points 9, 10): conforming splits leave exactly 2 triangles per quad on the boundary.
const MIXED: &str = r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
 <UnstructuredGrid><Piece NumberOfPoints="11" NumberOfCells="3">
  <PointData><DataArray type="Float64" Name="x" format="ascii">0 1 1 0 0 1 1 0 0.5 2 2</DataArray></PointData>
  <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">
   0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1  0.5 0.5 1.5  2 0 0.5  2 1 0.5
  </DataArray></Points>
  <Cells>
   <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 4 5 6 7  4 5 6 7 8  1 5 9 2 6 10</DataArray>
   <DataArray type="Int32" Name="offsets" format="ascii">8 13 19</DataArray>
   <DataArray type="UInt8" Name="types" format="ascii">12 14 13</DataArray>
  </Cells>
 </Piece></UnstructuredGrid>
</VTKFile>"#;

#[test]
fn hex_pyramid_wedge_split_conformingly() {
    let ds = parse(MIXED).unwrap();
    let m = &ds.mesh;
    // The hexahedron becomes 5 or 6 tets depending on its face diagonals.
    assert!(
        [5 + 2 + 3, 6 + 2 + 3].contains(&m.num_tets()),
        "{}",
        m.num_tets()
    );
    let vol: f64 = (0..m.num_tets())
        .map(|t| crate::mesh::signed_volume6(m.tet_points(t)) / 6.0)
        .sum();
    // Cube 1 + pyramid ⅓·1·½ + wedge ½·1 (triangle (1,0,0)(1,0,1)(2,0,.5) of area ½, length 1).
    assert!((vol - (1.0 + 1.0 / 6.0 + 0.5)).abs() < 1e-6, "{vol}");
    // Boundary: cube 4 free quads (8 tris) + pyramid 4 tris + wedge 2 tris + 2 quads (4 tris).
    assert_eq!(m.boundary_faces().len(), 8 + 4 + 2 + 4);
}

#[test]
fn voxel_and_quadratic_tet_cells() {
    let voxel = MIXED
        .replace(
            "0 1 2 3 4 5 6 7  4 5 6 7 8  1 5 9 2 6 10",
            "0 1 3 2 4 5 7 6",
        )
        .replace("8 13 19", "8")
        .replace("12 14 13", "11")
        .replace("NumberOfCells=\"3\"", "NumberOfCells=\"1\"");
    let ds = parse(&voxel).unwrap();
    assert_eq!(ds.mesh.num_tets(), 6);
    assert_eq!(ds.mesh.repair.unused_points, 3);
    let vol: f64 = (0..6)
        .map(|t| crate::mesh::signed_volume6(ds.mesh.tet_points(t)) / 6.0)
        .sum();
    assert!((vol - 1.0).abs() < 1e-6);
    let quad = MIXED
        .replace(
            "0 1 2 3 4 5 6 7  4 5 6 7 8  1 5 9 2 6 10",
            "0 1 3 4 2 5 6 7 8 9",
        )
        .replace("8 13 19", "10")
        .replace("12 14 13", "24")
        .replace("NumberOfCells=\"3\"", "NumberOfCells=\"1\"");
    let ds = parse(&quad).unwrap();
    assert_eq!(ds.mesh.tets.len(), 1);
    let mut t = ds.mesh.tets[0];
    t.sort_unstable();
    assert_eq!(t, [0, 1, 3, 4]);
}

#[test]
fn cell_data_only_is_averaged_with_a_warning() {
    let text = MIXED.replace(
            r#"<PointData><DataArray type="Float64" Name="x" format="ascii">0 1 1 0 0 1 1 0 0.5 2 2</DataArray></PointData>"#,
            r#"<CellData><DataArray type="Int16" Name="id" format="ascii">0 3 6</DataArray></CellData>"#,
        );
    let ds = parse(&text).unwrap();
    let m = &ds.mesh;
    assert_eq!(m.scalar_name, "id");
    assert!(m.repair.warnings.iter().any(|w| w.contains("averaged")));
    // Point 0: hex only → 0; point 8: pyramid only → 3; point 4 (hex, pyramid) → 1.5;
    // point 5 (all three) → 3; point 9 (wedge) → 6.
    assert_eq!(
        [
            m.scalars[0],
            m.scalars[8],
            m.scalars[4],
            m.scalars[5],
            m.scalars[9]
        ],
        [0.0, 3.0, 1.5, 3.0, 6.0]
    );
    let opts = LoadOptions {
        scalar: Some("x".into()),
        ..Default::default()
    };
    let err = from_bytes(text.as_bytes(), Path::new("t.vtu"), &opts).unwrap_err();
    assert!(
        matches!(&err.kind, ErrorKind::MissingArray { name, available } if name == "x" && available == &["id"])
    );
}

#[test]
fn structured_grid_and_image_data() {
    // 3×2×2 points, two pieces splitting x (sharing the plane i = 1).
    let vts = r#"<VTKFile type="StructuredGrid" version="0.1">
<StructuredGrid WholeExtent="0 2 0 1 0 1">
<Piece Extent="0 1 0 1 0 1"><PointData Scalars="s"><DataArray type="Float32" Name="v" NumberOfComponents="3" format="ascii">0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0</DataArray><DataArray type="Float32" Name="s" format="ascii">0 1 0 1 0 1 0 1</DataArray></PointData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 1 1 0 0 0 1 1 0 1 0 1 1 1 1 1</DataArray></Points></Piece>
<Piece Extent="1 2 0 1 0 1"><PointData Scalars="s"><DataArray type="Float32" Name="v" NumberOfComponents="3" format="ascii">0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0</DataArray><DataArray type="Float32" Name="s" format="ascii">1 2 1 2 1 2 1 2</DataArray></PointData>
<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">1 0 0 2 0 0 1 1 0 2 1 0 1 0 1 2 0 1 1 1 1 2 1 1</DataArray></Points></Piece>
</StructuredGrid></VTKFile>"#;
    let ds = from_bytes(vts.as_bytes(), Path::new("g.vts"), &LoadOptions::default()).unwrap();
    assert_eq!((ds.mesh.num_points(), ds.mesh.num_tets()), (12, 10));
    assert_eq!(ds.mesh.scalar_name, "s");
    assert_eq!(ds.mesh.scalars[..3], [0.0, 1.0, 2.0]);
    assert_eq!(ds.mesh.points[2], [2.0, 0.0, 0.0]);
    // Boundary quads: 2·(2×1) on z faces, 2·(2×1) on y faces, 2·(1×1) on x faces.
    assert_eq!(ds.mesh.boundary_faces().len(), 2 * (4 + 4 + 2));
    assert!(ds.volume.is_none());

    let vti = r#"<VTKFile type="ImageData" version="0.1" byte_order="LittleEndian">
<ImageData WholeExtent="1 3 0 1 0 1" Origin="10 0 0" Spacing="0.5 1 2">
<Piece Extent="1 3 0 1 0 1"><CellData><DataArray type="UInt8" Name="c" format="ascii">4 8</DataArray></CellData></Piece>
</ImageData></VTKFile>"#;
    let ds = from_bytes(vti.as_bytes(), Path::new("v.vti"), &LoadOptions::default()).unwrap();
    let vg = ds.volume.as_ref().unwrap();
    assert_eq!(vg.dims, [3, 2, 2]);
    assert_eq!(vg.origin, [10.5, 0.0, 0.0]);
    assert_eq!(vg.values.slice(0..3)[..], [4.0, 6.0, 8.0]);
    assert_eq!(ds.mesh.num_tets(), 10);
    assert_eq!(ds.mesh.points[1], [11.0, 0.0, 0.0]);
    assert!(ds
        .mesh
        .repair
        .warnings
        .iter()
        .any(|w| w.contains("averaged")));
}

fn binary_mesh() -> (TetMesh, VtuOptions) {
    let mesh = crate::generate::from_spec("box:1k:field=linear", 1).unwrap();
    (
        mesh,
        VtuOptions {
            format: VtuFormat::Binary,
            compress: false,
            header64: false,
            big_endian: false,
        },
    )
}

#[test]
fn malformed_inputs_give_typed_errors() {
    let (mesh, o) = binary_mesh();
    let good = String::from_utf8(vtu_bytes(&mesh, &o)).unwrap();
    // Truncated base64: the Points array loses its second half.
    let start = good.find("Name=\"Points\"").unwrap();
    let text_start = good[start..].find('>').unwrap() + start + 2;
    let text_end = good[text_start..].find('\n').unwrap() + text_start;
    let cut = format!(
        "{}{}",
        &good[..text_start + (text_end - text_start) / 2],
        &good[text_end..]
    );
    assert!(
        matches!(kind(&cut), ErrorKind::Truncated { .. }),
        "{:?}",
        kind(&cut)
    );
    // Not base64.
    let bad = format!("{}!!!!{}", &good[..text_start], &good[text_start + 4..]);
    assert!(
        matches!(kind(&bad), ErrorKind::Invalid(_)),
        "{:?}",
        kind(&bad)
    );
    // Wrong counts.
    let n = mesh.num_points();
    let wrong = good.replace(
        &format!("NumberOfPoints=\"{n}\""),
        &format!("NumberOfPoints=\"{}\"", n - 1),
    );
    assert!(matches!(kind(&wrong), ErrorKind::CountMismatch { .. }));
    // Unknown cell type: a triangle (5) instead of tets.
    let mut ascii = String::from_utf8(vtu_bytes(
        &mesh,
        &VtuOptions {
            format: VtuFormat::Ascii,
            ..o
        },
    ))
    .unwrap();
    let ty = ascii.find("Name=\"types\"").unwrap();
    let ten = ascii[ty..].find("10").unwrap() + ty;
    ascii.replace_range(ten..ten + 2, " 5");
    let k = kind(&ascii);
    assert!(
        matches!(&k, ErrorKind::UnknownCellType(s) if s.contains("TRIANGLE") && s.contains("(cell 0)")),
        "{k:?}"
    );
    // Index out of range in the connectivity.
    let m = MIXED.replace("1 5 9 2 6 10", "1 5 9 2 6 11");
    assert!(matches!(
        kind(&m),
        ErrorKind::IndexOutOfRange {
            index: 11,
            limit: 11,
            ..
        }
    ));
    // Offsets that run backwards or past the connectivity.
    assert!(matches!(
        kind(&MIXED.replace("8 13 19", "8 7 19")),
        ErrorKind::IndexOutOfRange { .. }
    ));
    assert!(matches!(
        kind(&MIXED.replace("8 13 19", "8 13 20")),
        ErrorKind::IndexOutOfRange { .. }
    ));
    // Non-finite coordinate.
    assert!(matches!(
        kind(&MIXED.replace("0.5 0.5 1.5", "0.5 nan 1.5")),
        ErrorKind::NonFinite { .. }
    ));
    // Text where a number belongs.
    assert!(matches!(
        kind(&MIXED.replace("2 0 0.5", "2 zero 0.5")),
        ErrorKind::Syntax { .. }
    ));
    // Float connectivity.
    assert!(matches!(
        kind(&MIXED.replace(
            "type=\"Int32\" Name=\"connectivity\"",
            "type=\"Float32\" Name=\"connectivity\""
        )),
        ErrorKind::Syntax { .. }
    ));
    // Truncated XML.
    assert!(matches!(
        kind(&MIXED[..MIXED.len() / 2]),
        ErrorKind::Truncated { .. } | ErrorKind::Syntax { .. }
    ));
    // Not VTK at all / mismatched tags.
    assert!(matches!(kind("<html></html>"), ErrorKind::Syntax { .. }));
    assert!(matches!(
        kind(&MIXED.replace("</Points>", "</Pointz>")),
        ErrorKind::Syntax { .. }
    ));
    // Bad byte order, header type, compressor, dataset type.
    assert!(matches!(
        kind(&MIXED.replace("LittleEndian", "MiddleEndian")),
        ErrorKind::ByteOrder(_)
    ));
    assert!(matches!(
        kind(&MIXED.replace("version=\"0.1\"", "header_type=\"UInt16\"")),
        ErrorKind::Syntax { .. }
    ));
    assert!(matches!(
        kind(&good.replace(
            "header_type=",
            "compressor=\"vtkLZ4DataCompressor\" header_type="
        )),
        ErrorKind::Unsupported(_)
    ));
    assert!(matches!(
        kind(&MIXED.replace("\"UnstructuredGrid\"", "\"PolyData\"")),
        ErrorKind::Unsupported(_)
    ));
    // Empty mesh.
    let empty = r#"<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="0" NumberOfCells="0"><Points><DataArray type="Float32" NumberOfComponents="3" format="ascii"></DataArray></Points><Cells><DataArray type="Int32" Name="connectivity" format="ascii"></DataArray><DataArray type="Int32" Name="offsets" format="ascii"></DataArray><DataArray type="UInt8" Name="types" format="ascii"></DataArray></Cells></Piece></UnstructuredGrid></VTKFile>"#;
    assert!(matches!(kind(empty), ErrorKind::EmptyMesh(_)));
}

#[test]
fn malformed_appended_and_compressed_data() {
    let (mesh, o) = binary_mesh();
    let raw = vtu_bytes(
        &mesh,
        &VtuOptions {
            format: VtuFormat::Appended,
            ..o
        },
    );
    let as_text = String::from_utf8_lossy(&raw).into_owned();
    let p = |b: &[u8]| {
        from_bytes(b, Path::new("a.vtu"), &LoadOptions::default())
            .expect_err("must fail")
            .kind
    };
    // File cut inside the appended block.
    assert!(matches!(
        p(&raw[..raw.len() - 200]),
        ErrorKind::Truncated { .. }
    ));
    // An offset beyond the appended data.
    let off = as_text.find("offset=\"0\"").unwrap();
    let mut bad = raw.clone();
    bad.splice(off..off + 10, b"offset=\"99999999\"".iter().copied());
    assert!(
        matches!(p(&bad), ErrorKind::IndexOutOfRange { .. }),
        "{:?}",
        p(&bad)
    );
    // Missing '_' marker.
    let us = find(&raw, b"encoding=\"raw\">\n   _").unwrap() + 19;
    assert_eq!(raw[us], b'_');
    let mut bad = raw.clone();
    bad[us] = b'X';
    assert!(matches!(p(&bad), ErrorKind::Syntax { .. }));
    // A block header announcing more bytes than exist.
    let mut bad = raw.clone();
    bad[us + 1..us + 5].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(p(&bad), ErrorKind::Truncated { .. }));
    // A byte count that is not a whole number of values.
    let mut bad = raw.clone();
    let n = u32::from_le_bytes(bad[us + 1..us + 5].try_into().unwrap());
    bad[us + 1..us + 5].copy_from_slice(&(n - 1).to_le_bytes());
    assert!(matches!(p(&bad), ErrorKind::Invalid(_)));
    // Corrupt zlib stream.
    let z = vtu_bytes(
        &mesh,
        &VtuOptions {
            format: VtuFormat::Appended,
            compress: true,
            ..o
        },
    );
    let us = find(&z, b"encoding=\"raw\">\n   _").unwrap() + 19;
    assert_eq!(z[us], b'_');
    let mut bad = z.clone();
    for b in &mut bad[us + 1 + 16 + 2..us + 1 + 16 + 12] {
        *b ^= 0x5A;
    }
    assert!(
        matches!(
            p(&bad),
            ErrorKind::Invalid(_) | ErrorKind::CountMismatch { .. }
        ),
        "{:?}",
        p(&bad)
    );
}

#[test]
fn damaged_files_never_panic() {
    let (mesh, o) = binary_mesh();
    let mut inputs = Vec::new();
    for opts in [
        o,
        VtuOptions {
            compress: true,
            ..o
        },
        VtuOptions {
            format: VtuFormat::Appended,
            compress: true,
            ..o
        },
        VtuOptions {
            format: VtuFormat::Ascii,
            ..o
        },
    ] {
        inputs.push(vtu_bytes(&mesh, &opts));
    }
    // Deterministic damage: truncations and byte flips at many positions.
    let mut state = 0x1234_5678_9abc_def0u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for input in &inputs {
        for _ in 0..150 {
            let mut b = input.clone();
            match next() % 3 {
                0 => b.truncate((next() as usize) % b.len()),
                1 => {
                    let i = (next() as usize) % b.len();
                    b[i] = next() as u8;
                }
                _ => {
                    let i = (next() as usize) % b.len();
                    b[i] = b"<>\"_=0 9-"[(next() % 9) as usize];
                }
            }
            let _ = from_bytes(&b, Path::new("fuzz.vtu"), &LoadOptions::default());
        }
    }
}

// Files written by VTK 9.7.2's XML writers (Python `vtk` wheel) from Tetrahedron.vtu and a
// vtkRTAnalyticSource wavelet: cross-checks the reader against VTK's own layouts. They live
// in datasets/testdata/vtk-written/ so that tests/vtkio_oracle.rs reads them too.
const VTK_INLINE_ZLIB_U32: &str =
    include_str!("../../testdata/vtk-written/tetrahedron-inline-zlib-u32.vtu");
const VTK_APPENDED_BASE64_ZLIB_BIG: &str =
    include_str!("../../testdata/vtk-written/tetrahedron-appended-base64-zlib-be.vtu");
const VTK_VTS_INLINE_ZLIB_BIG: &str =
    include_str!("../../testdata/vtk-written/wavelet-inline-zlib-be.vts");
const VTK_VTI_RAW_ZLIB: &[u8] = include_bytes!("../../testdata/vtk-written/wavelet-raw-zlib.vti");

#[test]
fn reads_files_written_by_vtk() {
    let p = |bytes: &[u8], name: &str| {
        from_bytes(bytes, Path::new(name), &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let a = p(VTK_INLINE_ZLIB_U32.as_bytes(), "a.vtu");
    let b = p(VTK_APPENDED_BASE64_ZLIB_BIG.as_bytes(), "b.vtu");
    for m in [&a.mesh, &b.mesh] {
        assert_eq!((m.num_points(), m.num_tets()), (35, 96));
        assert_eq!(m.scalar_name, "DistanceToCenter");
        assert_eq!(m.boundary_faces().len(), 48);
    }
    assert_eq!(
        (&a.mesh.points, &a.mesh.scalars, &a.mesh.tets),
        (&b.mesh.points, &b.mesh.scalars, &b.mesh.tets)
    );
    if let Some(path) = data_file("Tetrahedron.vtu") {
        let o = read(&path, &LoadOptions::default()).unwrap();
        assert_eq!(
            (&a.mesh.points, &a.mesh.scalars, &a.mesh.tets),
            (&o.mesh.points, &o.mesh.scalars, &o.mesh.tets)
        );
    }
    let img = p(VTK_VTI_RAW_ZLIB, "w.vti");
    let vg = img.volume.as_ref().unwrap();
    assert_eq!(
        (vg.dims, vg.origin, vg.spacing),
        ([7, 5, 5], [-3.0, -2.0, 0.0], [1.0; 3])
    );
    assert_eq!(
        (
            img.mesh.num_points(),
            img.mesh.num_tets(),
            img.mesh.scalar_name.as_str()
        ),
        (175, 480, "RTData")
    );
    assert_eq!(img.mesh.scalar_range().1, 260.0);
    // The structured grid is the wavelet's points moved by (x + 0.1y, y, z + 0.05x²).
    let sg = p(VTK_VTS_INLINE_ZLIB_BIG.as_bytes(), "s.vts");
    assert_eq!(sg.mesh.scalars, img.mesh.scalars);
    assert_eq!(sg.mesh.tets, img.mesh.tets);
    for (q, r) in sg.mesh.points.iter().zip(&img.mesh.points) {
        let want = [r[0] + 0.1 * r[1], r[1], r[2] + 0.05 * r[0] * r[0]];
        assert!(
            (0..3).all(|k| (q[k] - want[k]).abs() < 1e-5),
            "{q:?} vs {want:?}"
        );
    }
}

/// The fuzz target's seeds (VTK-written, one per data mode) all read: the fuzzer starts
/// inside every decoding path rather than at the first error.
#[test]
fn fuzz_seeds_read() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/vtk_xml");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        let ds = read(&p, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert!(ds.mesh.num_tets() > 0, "{}", p.display());
        n += 1;
    }
    assert_eq!(n, 20);
}
