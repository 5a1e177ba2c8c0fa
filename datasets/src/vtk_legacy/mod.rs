//! VTK legacy files (`.vtk`), ASCII and BINARY (big-endian), versions 1.0–4.2 and 5.1:
//! UNSTRUCTURED_GRID, STRUCTURED_GRID, STRUCTURED_POINTS, RECTILINEAR_GRID with POINT_DATA /
//! CELL_DATA attributes (SCALARS with LOOKUP_TABLE, FIELD arrays, and the other attribute kinds,
//! which are read and kept as arrays) and METADATA blocks (skipped).
//!
//! Why a hand-written parser instead of `vtkio`: vtkio 0.7.0-rc2 (the release with 5.1 support;
//! 0.6.3 fails on the OFFSETS/CONNECTIVITY layout) reports every parse failure as a bare
//! `nom::error::ErrorKind` — no line, no byte offset, no statement of what was expected — so it
//! cannot give the typed, located errors tetbench promises for bad input; its 5.1 cell reader
//! also accepts only `vtktypeint64` offsets. The format is small (keyword lines, then ASCII
//! tokens or packed big-endian values), so a direct reader is short, checks every count against
//! the bytes actually present before allocating, and converts binary blocks in bulk. vtkio is
//! kept as this reader's oracle (`tests/vtkio_oracle.rs`): it reads 11 of the 13 valid legacy
//! files the project has exactly as we do, and refuses `ironProt.vtk` (blank header lines) and
//! `unsigned_short` data.
//!
//! 5.1 layout: `CELLS n_offsets n_connectivity`, then `OFFSETS vtktypeint64` and
//! `CONNECTIVITY vtktypeint64` arrays; older versions use `CELLS n size` with `npts id…` per
//! cell. The layout is recognised from the content (an OFFSETS keyword), not the version line.
//!
//! The reader in four parts: `lexer.rs` (tokens, counts, value blocks, located errors),
//! `parse.rs` (the header and the sections into a [`VtkFile`]), `geometry.rs` (points and cells
//! into tets) and `scalars.rs` (attribute counts and the scalar at the points).

use std::path::Path;

use crate::dataset::{Dataset, LoadOptions};
use crate::error::LoadError;
use crate::read_util as util;
use crate::volume::VoxelGrid;
use crate::TetMesh;

mod geometry;
mod lexer;
mod parse;
mod scalars;
#[cfg(test)]
mod tests;

use lexer::Parser;

/// Reads a legacy VTK file.
pub fn read(path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    let bytes = util::read_file(path)?;
    from_bytes(&bytes, path, options)
}

/// Parses the content of a legacy VTK file; `path` only names it in errors and the mesh name.
/// Never panics on any input (fuzzed: `datasets/fuzz`).
pub fn from_bytes(bytes: &[u8], path: &Path, options: &LoadOptions) -> Result<Dataset, LoadError> {
    let mut p = Parser {
        b: bytes,
        pos: 0,
        binary: false,
        path,
    };
    let file = p.parse()?;
    file.build(&p, options)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DataType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F32,
    F64,
}

impl DataType {
    fn parse(name: &[u8]) -> Option<DataType> {
        let n = name.to_ascii_lowercase();
        Some(match n.as_slice() {
            b"unsigned_char" | b"vtktypeuint8" => DataType::U8,
            b"char" | b"signed_char" | b"vtktypeint8" => DataType::I8,
            b"unsigned_short" | b"vtktypeuint16" => DataType::U16,
            b"short" | b"vtktypeint16" => DataType::I16,
            b"unsigned_int" | b"vtktypeuint32" => DataType::U32,
            // VTK writes vtkIdType arrays of legacy files as 32-bit ints (vtkDataReader).
            b"int" | b"vtktypeint32" | b"vtkidtype" => DataType::I32,
            b"unsigned_long" | b"unsigned_long_long" | b"vtktypeuint64" => DataType::U64,
            b"long" | b"long_long" | b"vtktypeint64" => DataType::I64,
            b"float" | b"vtktypefloat32" => DataType::F32,
            b"double" | b"vtktypefloat64" => DataType::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            DataType::U8 | DataType::I8 => 1,
            DataType::U16 | DataType::I16 => 2,
            DataType::U32 | DataType::I32 | DataType::F32 => 4,
            DataType::U64 | DataType::I64 | DataType::F64 => 8,
        }
    }
    fn is_float(self) -> bool {
        matches!(self, DataType::F32 | DataType::F64)
    }
}

const TYPE_NAMES: &str = "a data type (unsigned_char, char, unsigned_short, short, unsigned_int, int, unsigned_long, long, float, double, vtktypeint64, …)";

/// A numeric array read from the file (values converted to f32).
#[derive(Debug, Clone)]
struct Array {
    name: String,
    ncomp: usize,
    values: Vec<f32>,
    /// First non-finite value: (value index, byte offset of its token or bytes, value).
    non_finite: Option<(usize, usize, f64)>,
}

/// Values read as f32 and the first non-finite one (value index, byte offset, value).
type Floats = (Vec<f32>, Option<(usize, usize, f64)>);

/// Points, tets, cell count and (for STRUCTURED_POINTS) dims, origin and spacing.
type Geometry = (
    Vec<[f32; 3]>,
    Vec<[u32; 4]>,
    u64,
    Option<([usize; 3], [f64; 3], [f64; 3])>,
);

/// Which attribute block arrays currently go to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    Dataset,
    Point,
    Cell,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Unstructured,
    StructuredGrid,
    StructuredPoints,
    Rectilinear,
}

/// Cell connectivity as CSR, with where the values came from (for located errors).
#[derive(Debug, Default)]
struct Cells {
    offsets: Vec<usize>,
    conn: Vec<i64>,
    /// Start of the connectivity values and whether the legacy layout (counts interleaved).
    conn_at: usize,
    legacy_layout: bool,
    conn_type: Option<DataType>,
    at: usize,
}

#[derive(Debug, Default)]
struct VtkFile {
    kind: Option<Kind>,
    points: Option<(Vec<f32>, usize)>,
    cells: Option<Cells>,
    cell_types: Option<(Vec<i64>, usize, bool)>,
    dims: Option<([u64; 3], usize)>,
    origin: Option<[f64; 3]>,
    spacing: Option<[f64; 3]>,
    coords: [Option<(Vec<f32>, usize)>; 3],
    point_data: Option<(u64, usize)>,
    cell_data: Option<(u64, usize)>,
    point_arrays: Vec<Array>,
    cell_arrays: Vec<Array>,
}

impl VtkFile {
    /// The dataset: geometry, attribute counts checked, the scalar chosen and at the points.
    fn build(self, p: &Parser, options: &LoadOptions) -> Result<Dataset, LoadError> {
        let path = p.path;
        let (points, tets, n_cells, regular) = self.geometry(p)?;
        self.check_attribute_counts(p, points.len(), n_cells)?;
        let mut warnings = Vec::new();
        let (scalars, scalar_name) = match self.choose_scalar(p, options)? {
            Some(chosen) => {
                let dims = regular.map(|r| r.0);
                let values = self.scalar_values(p, chosen, points.len(), dims, &mut warnings)?;
                (values, chosen.0.name.clone())
            }
            None => {
                warnings.push("no point or cell data: the scalar is 0 everywhere".to_string());
                (vec![0.0; points.len()], "none".to_string())
            }
        };
        let volume = regular.map(|(dims, origin, spacing)| {
            std::sync::Arc::new(VoxelGrid {
                dims,
                spacing,
                origin,
                values: scalars.clone().into(),
                scalar_name: scalar_name.clone(),
            })
        });
        let mut mesh = TetMesh::new(util::stem_name(path), points, scalars, scalar_name, tets)
            .map_err(|k| LoadError::new(path, k))?;
        mesh.repair.warnings.extend(warnings);
        Ok(Dataset {
            mesh,
            volume,
            source: path.display().to_string(),
        })
    }
}
