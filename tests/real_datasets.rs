//! The papers' real data sets (../shared/datasets, see its MANIFEST.md) load with exactly the
//! counts the papers and the manifest give. Skipped with a printed reason when the data
//! directory is absent.

use std::path::PathBuf;

use datasets::load::{detect_format, load, Format};
use datasets::{Dataset, LoadOptions, Plot3dField};
use tetbench_tests::data_dir;

fn file(name: &str) -> Option<PathBuf> {
    let p = data_dir()?.join(name);
    assert!(
        p.is_file(),
        "{} is missing from the data directory",
        p.display()
    );
    Some(p)
}

fn open(name: &str, options: &LoadOptions) -> Option<Dataset> {
    let p = file(name)?;
    Some(load(&p, options).unwrap_or_else(|e| panic!("{e}")))
}

fn field(f: Plot3dField) -> LoadOptions {
    LoadOptions {
        plot3d_field: Some(f),
        ..Default::default()
    }
}

#[test]
fn blunt_fin() {
    let Some(ds) = open("bluntfinxyz.bin", &LoadOptions::default()) else {
        return;
    };
    let m = &ds.mesh;
    assert_eq!(m.num_points(), 40_960);
    // The 5-per-hex split gives the papers' 39·31·31·5 = 187,395 tets. 77 of them have exactly
    // zero volume: the grid repeats points (collapsed cells along the j = 0 line at the fin's
    // leading edge, e.g. cell (0,0,0) has two identical corners), and the mesh model drops
    // zero-volume tets and counts them.
    assert_eq!(m.num_tets() + m.repair.degenerate_dropped, 187_395);
    assert_eq!(m.repair.degenerate_dropped, 77);
    assert_eq!(m.scalar_name, "density");
    assert_eq!(m.name, "bluntfin");
    assert!(ds.source.ends_with("bluntfinxyz.bin"));
    // The Q file's 484 bytes of zero padding are recognised, not mistaken for data.
    assert!(
        m.repair
            .warnings
            .iter()
            .any(|w| w.contains("484 trailing zero bytes")),
        "{:?}",
        m.repair.warnings
    );
    let (lo, hi) = m.scalar_range();
    assert!(lo > 0.0 && hi > lo, "density range {lo}..{hi}");
    // Conforming: the boundary is at most two triangles per boundary quad of the 39×31×31
    // cells (fewer where collapsed cells lost their zero-area faces).
    let quads = 2 * (39 * 31 + 39 * 31 + 31 * 31);
    let b = m.boundary_faces().len();
    assert!(b <= 2 * quads && b > 2 * quads - 200, "{b} boundary faces");
    // Pressure p = (γ−1)(E − ½ρ|v|²) is positive in a physical flow.
    let p = open("bluntfinxyz.bin", &field(Plot3dField::Pressure)).unwrap();
    assert!(p.mesh.scalar_range().0 > 0.0);
    assert_eq!(p.mesh.scalar_name, "pressure");
}

#[test]
fn combustion_chamber() {
    let Some(ds) = open("combxyz.bin", &LoadOptions::default()) else {
        return;
    };
    assert_eq!(ds.mesh.num_points(), 47_025);
    assert_eq!(ds.mesh.num_tets(), 215_040);
    assert_eq!(ds.mesh.repair.degenerate_dropped, 0);
    // The manifest: the energy block is all zero.
    let e = open("combxyz.bin", &field(Plot3dField::Energy)).unwrap();
    assert_eq!(e.mesh.scalar_range(), (0.0, 0.0));
}

#[test]
fn lox_post_reports_iblank() {
    let Some(ds) = open("postxyz.bin", &field(Plot3dField::VelocityMagnitude)) else {
        return;
    };
    assert_eq!(ds.mesh.num_points(), 109_744);
    assert_eq!(ds.mesh.num_tets(), 513_375);
    assert!(
        ds.mesh
            .repair
            .warnings
            .iter()
            .any(|w| w.starts_with("IBLANK present: ")),
        "{:?}",
        ds.mesh.repair.warnings
    );
    // The manifest: ρ = 1 everywhere.
    let d = open("postxyz.bin", &LoadOptions::default()).unwrap();
    assert_eq!(d.mesh.scalar_range(), (1.0, 1.0));
    let (lo, hi) = ds.mesh.scalar_range();
    assert!(hi > lo);
}

#[test]
fn spx() {
    let Some(ds) = open("spx.vtk", &LoadOptions::default()) else {
        return;
    };
    let m = &ds.mesh;
    assert_eq!(m.num_points(), 2_896);
    assert_eq!(m.num_tets(), 12_936);
    assert_eq!(m.boundary_faces().len(), 2_760);
    assert!(!m.is_convex());
    let (lo, hi) = m.scalar_range();
    assert!(lo >= 0.0 && (hi - 2.254).abs() < 1e-3, "{lo}..{hi}");
}

#[test]
fn tetra_mesh() {
    let Some(ds) = open("tetraMesh.vtk", &LoadOptions::default()) else {
        return;
    };
    assert_eq!(ds.mesh.num_points(), 55);
    assert_eq!(ds.mesh.num_tets(), 160);
    assert_eq!(ds.mesh.scalar_name, "scalars");
}

#[test]
fn iron_protein_volume() {
    let Some(ds) = open("ironProt.vtk", &LoadOptions::default()) else {
        return;
    };
    let vol = ds
        .volume
        .as_ref()
        .expect("STRUCTURED_POINTS keeps its voxel grid");
    assert_eq!(vol.dims, [68, 68, 68]);
    assert_eq!(vol.values.len(), 68 * 68 * 68);
    assert_eq!(ds.mesh.num_tets(), 1_503_815);
    let (lo, hi) = ds.mesh.scalar_range();
    assert!(lo >= 0.0 && hi <= 255.0 && hi > lo);
}

#[test]
fn head_mr_volume() {
    let Some(ds) = open("HeadMRVolume.mhd", &LoadOptions::default()) else {
        return;
    };
    let vol = ds.volume.as_ref().unwrap();
    assert_eq!(vol.dims, [48, 62, 42]);
    assert_eq!(vol.spacing, [4.0, 4.0, 4.0]);
    assert_eq!(ds.mesh.num_points(), 48 * 62 * 42);
    assert_eq!(ds.mesh.num_tets(), 47 * 61 * 41 * 5);
}

#[test]
fn tetrahedron_vtu() {
    let Some(ds) = open("Tetrahedron.vtu", &LoadOptions::default()) else {
        return;
    };
    assert_eq!(ds.mesh.num_points(), 35);
    assert_eq!(ds.mesh.num_tets(), 96);
}

#[test]
fn formats_are_detected() {
    let Some(dir) = data_dir() else { return };
    for (name, f) in [
        ("bluntfinxyz.bin", Format::Plot3d),
        ("spx.vtk", Format::VtkLegacy),
        ("ironProt.vtk", Format::VtkLegacy),
        ("Tetrahedron.vtu", Format::VtkXml),
        ("HeadMRVolume.mhd", Format::MetaImage),
    ] {
        assert_eq!(detect_format(&dir.join(name)).unwrap(), f, "{name}");
    }
    // Content wins over a misleading name: PLOT3D sniffed from header + size, VTK from magic.
    let tmp = tempfile::tempdir().unwrap();
    for (src, dst, f) in [
        ("bluntfinxyz.bin", "grid.dat", Format::Plot3d),
        ("spx.vtk", "spx.txt", Format::VtkLegacy),
    ] {
        let p = tmp.path().join(dst);
        std::fs::copy(dir.join(src), &p).unwrap();
        assert_eq!(detect_format(&p).unwrap(), f);
    }
}
