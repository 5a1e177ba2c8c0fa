//! The measurements behind the decision whether vtkio should write or read tetbench's `.vtu`
//! files (docs/dependencies.md). Blunt Fin (PLOT3D, 187,395 tets after the 5-tet split) is
//! written by our writer and by vtkio, each file is read back by our reader and by vtkio, and
//! every read is compared with the mesh written. Times are the best of 7 runs (the
//! development machine is shared, so the minimum is the steadiest figure).
//!
//! ```sh
//! cargo run --release -p datasets --example vtkio_measure -- OUT_DIR
//! ```
//!
//! OUT_DIR receives the two files (`ours.vtu`, `vtkio.vtu`), so that VTK's own reader can be
//! pointed at them (`scripts/vtk_readback.py`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use datasets::write_vtu::{write_vtu_with, VtuFormat, VtuOptions};
use datasets::{LoadOptions, TetMesh};
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    UnstructuredGridPiece, Version, VertexNumbers,
};

const RUNS: usize = 7;

/// Shortest wall time of `RUNS` calls, in ms, and the last result.
fn timed<T>(mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::with_capacity(RUNS);
    let mut last = None;
    for _ in 0..RUNS {
        let t = Instant::now();
        last = Some(f());
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    (times[0], last.unwrap())
}

/// The mesh as a vtkio model: Float32 points and scalar, XML-style cells, all VTK_TETRA.
fn vtkio_model(mesh: &TetMesh) -> vtkio::Vtk {
    let points: Vec<f32> = mesh.points.iter().flatten().copied().collect();
    let connectivity: Vec<u64> = mesh.tets.iter().flatten().map(|&v| v as u64).collect();
    let offsets: Vec<u64> = (1..=mesh.tets.len() as u64).map(|i| 4 * i).collect();
    vtkio::Vtk {
        version: Version::default(),
        title: String::new(),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: IOBuffer::F32(points),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity,
                    offsets,
                },
                types: vec![CellType::Tetra; mesh.tets.len()],
            },
            data: Attributes {
                point: vec![Attribute::DataArray(DataArray {
                    name: mesh.scalar_name.clone(),
                    elem: ElementType::Scalars {
                        num_comp: 1,
                        lookup_table: None,
                    },
                    data: IOBuffer::F32(mesh.scalars.clone()),
                })],
                cell: vec![],
            },
        }),
    }
}

/// vtkio's reading of a `.vtu` made into a checked mesh, as our reader makes it (so both
/// timings include `TetMesh::new`).
fn vtkio_read(bytes: &[u8]) -> Result<TetMesh, String> {
    let vtk = vtkio::Vtk::parse_xml(bytes).map_err(|e| e.to_string())?;
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        return Err("not an unstructured grid".into());
    };
    let piece = pieces
        .into_iter()
        .next()
        .ok_or("no piece")?
        .into_loaded_piece_data(None)
        .map_err(|e| e.to_string())?;
    let p: Vec<f32> = piece.points.cast_into().ok_or("points")?;
    let (conn, _) = piece.cells.cell_verts.into_xml();
    let tets = conn
        .chunks_exact(4)
        .map(|c| [c[0] as u32, c[1] as u32, c[2] as u32, c[3] as u32])
        .collect();
    let s = match piece.data.point.first() {
        Some(Attribute::DataArray(d)) => d.data.cast_into::<f32>().ok_or("scalars")?,
        _ => return Err("no point array".into()),
    };
    let points = p.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    TetMesh::new("vtkio", points, s, "s", tets).map_err(|e| e.to_string())
}

fn same(mesh: &TetMesh, got: (&[[f32; 3]], &[[u32; 4]], &[f32])) -> bool {
    mesh.points == got.0 && mesh.tets == got.1 && mesh.scalars == got.2
}

fn main() {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "out/vtkio".into()),
    );
    std::fs::create_dir_all(&out).unwrap();
    let registry = datasets::registry::Registry::new(datasets::registry::default_data_dir());
    let mesh = registry
        .resolve("bluntfin", &LoadOptions::default())
        .expect("Blunt Fin (set TETBENCH_DATA)")
        .mesh;
    println!(
        "Blunt Fin: {} points, {} tets; best of {} runs",
        mesh.num_points(),
        mesh.num_tets(),
        RUNS
    );
    // The mesh itself, raw little-endian, for scripts/vtk_readback.py to compare VTK's reading
    // with: points (f32 × 3), tets (u32 × 4), scalars (f32).
    let raw = |name: &str, bytes: Vec<u8>| std::fs::write(out.join(name), bytes).unwrap();
    raw(
        "points.f32",
        mesh.points
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
    );
    raw(
        "tets.u32",
        mesh.tets
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
    );
    raw(
        "scalars.f32",
        mesh.scalars.iter().flat_map(|v| v.to_le_bytes()).collect(),
    );
    let layouts = [
        (
            "ours.vtu",
            VtuOptions::default(),
            "raw appended, UInt64 headers (default)",
        ),
        (
            "ours-base64.vtu",
            VtuOptions {
                format: VtuFormat::Binary,
                compress: false,
                header64: true,
                big_endian: false,
            },
            "inline base64 (vtkio's layout)",
        ),
    ];
    println!("| file | writer | layout | write ms | bytes | our read ms, identical | vtkio read ms, identical |");
    println!("|---|---|---|---|---|---|---|");
    let mut files: Vec<(PathBuf, &str, String)> = Vec::new();
    for (name, o, what) in layouts {
        let path = out.join(name);
        let (ms, r) = timed(|| write_vtu_with(&mesh, &path, &o));
        r.unwrap();
        files.push((path, "ours", format!("{what} | {ms:.1}")));
    }
    let path = out.join("vtkio.vtu");
    let (ms, r) = timed(|| {
        let f = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        vtkio_model(&mesh).write_xml(f)
    });
    r.unwrap();
    files.push((path, "vtkio", format!("inline base64 | {ms:.1}")));
    for (path, writer, what) in &files {
        let bytes = std::fs::read(path).unwrap();
        let (ours_ms, ours) =
            timed(|| datasets::vtk_xml::from_bytes(&bytes, path, &LoadOptions::default()));
        let ours = match ours {
            Ok(ds) => format!(
                "{ours_ms:.1}, {}",
                same(&mesh, (&ds.mesh.points, &ds.mesh.tets, &ds.mesh.scalars))
            ),
            Err(e) => format!("fails: {e}"),
        };
        let (vtkio_ms, theirs) = timed(|| vtkio_read(&bytes));
        let theirs = match theirs {
            Ok(m) => format!(
                "{vtkio_ms:.1}, {}",
                same(&mesh, (&m.points, &m.tets, &m.scalars))
            ),
            Err(e) => format!("fails: {}", e.chars().take(60).collect::<String>()),
        };
        println!(
            "| {} | {writer} | {what} | {} | {ours} | {theirs} |",
            file_name(path),
            bytes.len()
        );
    }
}

fn file_name(p: &Path) -> String {
    p.file_name().unwrap().to_string_lossy().into_owned()
}
