//! vtkio's reading of a VTK file, turned into a [`TetMesh`] by the steps tetbench's readers
//! share — the cell split ([`datasets::load::cell_to_tets`]), the structured-grid split
//! ([`datasets::volume::structured_tets`]), cell-to-point averaging
//! ([`datasets::load::cell_data_to_points`]) and [`TetMesh::new`]'s checks — so that any
//! difference from our readers comes from the parsing alone.
//!
//! Only what vtkio parses is taken from vtkio: points, cells and their types, grid extents,
//! origin and spacing, and the attribute arrays with their names, component counts and values.

use std::path::Path;

use datasets::load::{cell_data_to_points, cell_to_tets, Format};
use datasets::volume::structured_tets;
use datasets::{ErrorKind, TetMesh};
use vtkio::model::{
    Attribute, Attributes, DataSet, ElementType, Extent, IOBuffer, Piece, VertexNumbers,
};

/// What vtkio made of a file.
pub enum VtkioOutcome {
    /// vtkio refused the file; its error message.
    Refused(String),
    /// vtkio parsed the file. Converting its model gave this mesh (with the asked-for scalar)
    /// and these array names (point arrays, then cell arrays), or the error our shared steps
    /// raise on it.
    Parsed(Result<Box<VtkioMesh>, ErrorKind>),
}

pub struct VtkioMesh {
    pub mesh: TetMesh,
    pub arrays: Vec<String>,
    /// Dims, origin and spacing of an image data set (legacy STRUCTURED_POINTS, `.vti`).
    pub grid: Option<([usize; 3], [f64; 3], [f64; 3])>,
}

/// One attribute array: name, components per tuple, values (as f64, exactly as stored).
struct Array {
    name: String,
    ncomp: usize,
    values: Vec<f64>,
}

/// The geometry read from the model, before the scalar is chosen.
struct Geometry {
    points: Vec<[f32; 3]>,
    tets: Vec<[u32; 4]>,
    /// Cell → point connectivity (CSR) for averaging cell data.
    cell_offsets: Vec<usize>,
    cell_points: Vec<u32>,
    grid: Option<([usize; 3], [f64; 3], [f64; 3])>,
}

/// Reads `bytes` with vtkio (legacy or XML, as `format` says) and builds the mesh with the
/// point array `scalar` (default: the first one-component point array, else the first point
/// array, else the first cell array averaged to the points, as our readers choose).
pub fn read(bytes: &[u8], format: Format, scalar: Option<&str>) -> VtkioOutcome {
    let parsed = match format {
        Format::VtkLegacy => vtkio::Vtk::parse_legacy_be(bytes),
        Format::VtkXml => vtkio::Vtk::parse_xml(bytes),
        _ => return VtkioOutcome::Refused("not a VTK file".into()),
    };
    match parsed {
        Err(e) => VtkioOutcome::Refused(e.to_string()),
        Ok(vtk) => VtkioOutcome::Parsed(build(vtk.data, scalar).map(Box::new)),
    }
}

fn unsupported(what: &str) -> ErrorKind {
    ErrorKind::Unsupported(what.to_string())
}

/// The one inline piece of a data set (tetbench reads single-piece files only).
fn single<P>(pieces: Vec<Piece<P>>) -> Result<P, ErrorKind> {
    let n = pieces.len();
    let mut it = pieces.into_iter();
    match (it.next(), n) {
        (Some(Piece::Inline(p)), 1) => Ok(*p),
        _ => Err(unsupported("not exactly one inline piece")),
    }
}

fn f64s(buf: &IOBuffer) -> Result<Vec<f64>, ErrorKind> {
    buf.cast_into::<f64>()
        .ok_or_else(|| unsupported("bit arrays"))
}

fn points_of(buf: &IOBuffer) -> Result<Vec<[f32; 3]>, ErrorKind> {
    let v = f64s(buf)?;
    if v.len() % 3 != 0 {
        return Err(ErrorKind::CountMismatch {
            what: "point coordinates (multiple of 3)".into(),
            expected: (v.len() / 3 * 3) as u64,
            found: v.len() as u64,
        });
    }
    Ok(v.chunks_exact(3)
        .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
        .collect())
}

fn build(data: DataSet, scalar: Option<&str>) -> Result<VtkioMesh, ErrorKind> {
    let (geometry, attributes, ncells) = match data {
        DataSet::UnstructuredGrid { pieces, .. } => {
            let piece = single(pieces)?;
            let points = points_of(&piece.points)?;
            let (geometry, ncells) = unstructured(points, piece.cells)?;
            (geometry, piece.data, ncells)
        }
        DataSet::ImageData {
            extent,
            origin,
            spacing,
            pieces,
            ..
        } => {
            let dims = grid_dims(extent)?;
            let piece = single(pieces)?;
            let (origin, spacing) = (origin.map(f64::from), spacing.map(f64::from));
            let n = backed_grid(dims, &piece.data)?;
            let mut points = Vec::with_capacity(n);
            for k in 0..dims[2] {
                for j in 0..dims[1] {
                    for i in 0..dims[0] {
                        points.push([
                            (origin[0] + i as f64 * spacing[0]) as f32,
                            (origin[1] + j as f64 * spacing[1]) as f32,
                            (origin[2] + k as f64 * spacing[2]) as f32,
                        ]);
                    }
                }
            }
            let mut g = structured(points, dims)?;
            g.0.grid = Some((dims, origin, spacing));
            (g.0, piece.data, g.1)
        }
        DataSet::StructuredGrid { extent, pieces, .. } => {
            let dims = grid_dims(extent)?;
            let piece = single(pieces)?;
            let points = points_of(&piece.points)?;
            if points.len() != dims.iter().product::<usize>() {
                return Err(ErrorKind::CountMismatch {
                    what: "points vs grid dimensions".into(),
                    expected: dims.iter().product::<usize>() as u64,
                    found: points.len() as u64,
                });
            }
            let g = structured(points, dims)?;
            (g.0, piece.data, g.1)
        }
        DataSet::RectilinearGrid { extent, pieces, .. } => {
            let dims = grid_dims(extent)?;
            let piece = single(pieces)?;
            backed_grid(dims, &piece.data)?;
            let axes = [&piece.coords.x, &piece.coords.y, &piece.coords.z]
                .map(|b| f64s(b).map(|v| v.into_iter().map(|x| x as f32).collect::<Vec<_>>()));
            let [x, y, z] = axes;
            let (x, y, z) = (x?, y?, z?);
            for (a, c) in [&x, &y, &z].into_iter().enumerate() {
                if c.len() != dims[a] {
                    return Err(ErrorKind::CountMismatch {
                        what: "coordinates vs grid dimensions".into(),
                        expected: dims[a] as u64,
                        found: c.len() as u64,
                    });
                }
            }
            let mut points = Vec::with_capacity(x.len() * y.len() * z.len());
            for &zk in &z {
                for &yj in &y {
                    for &xi in &x {
                        points.push([xi, yj, zk]);
                    }
                }
            }
            let g = structured(points, dims)?;
            (g.0, piece.data, g.1)
        }
        DataSet::PolyData { .. } => return Err(unsupported("POLYDATA")),
        DataSet::Field { .. } => return Err(unsupported("FIELD data set")),
    };
    let np = geometry.points.len();
    let (point_arrays, cell_arrays) = arrays(attributes);
    for (arrays, tuples, what) in [
        (&point_arrays, np, "point data"),
        (&cell_arrays, ncells, "cell data"),
    ] {
        for a in arrays {
            if a.values.len() != a.ncomp * tuples {
                return Err(ErrorKind::CountMismatch {
                    what: format!("{what} {}", a.name),
                    expected: (a.ncomp * tuples) as u64,
                    found: a.values.len() as u64,
                });
            }
        }
    }
    let names: Vec<String> = point_arrays
        .iter()
        .chain(&cell_arrays)
        .map(|a| a.name.clone())
        .collect();
    let chosen = match scalar {
        Some(name) => {
            let found = point_arrays
                .iter()
                .find(|a| a.name == name)
                .map(|a| (a, false))
                .or_else(|| {
                    cell_arrays
                        .iter()
                        .find(|a| a.name == name)
                        .map(|a| (a, true))
                });
            if found.is_none() {
                return Err(ErrorKind::MissingArray {
                    name: name.to_string(),
                    available: names,
                });
            }
            found
        }
        None => {
            let pick = |v: &'_ [Array]| -> Option<usize> {
                v.iter()
                    .position(|a| a.ncomp == 1)
                    .or(if v.is_empty() { None } else { Some(0) })
            };
            pick(&point_arrays)
                .map(|i| (&point_arrays[i], false))
                .or_else(|| pick(&cell_arrays).map(|i| (&cell_arrays[i], true)))
        }
    };
    let (scalars, scalar_name) = match chosen {
        None => (vec![0.0; np], "none".to_string()),
        Some((a, is_cell)) => {
            let mut v: Vec<f32> = a
                .values
                .chunks_exact(a.ncomp.max(1))
                .map(|t| {
                    if t.len() == 1 {
                        t[0] as f32
                    } else {
                        t.iter().map(|x| x * x).sum::<f64>().sqrt() as f32
                    }
                })
                .collect();
            if is_cell {
                v = cell_data_to_points(np, &geometry.cell_offsets, &geometry.cell_points, &v);
            }
            (v, a.name.clone())
        }
    };
    let mesh = TetMesh::new(
        "vtkio",
        geometry.points,
        scalars,
        scalar_name,
        geometry.tets,
    )?;
    Ok(VtkioMesh {
        mesh,
        arrays: names,
        grid: geometry.grid,
    })
}

/// The attribute arrays, point then cell; FIELD blocks contribute each of their arrays.
/// LOOKUP_TABLE blocks are colour tables, not data, and are left out (as our readers do).
fn arrays(attributes: Attributes) -> (Vec<Array>, Vec<Array>) {
    let conv = |list: Vec<Attribute>| -> Vec<Array> {
        let mut out = Vec::new();
        for a in list {
            match a {
                Attribute::DataArray(d) => {
                    if d.elem == ElementType::LookupTable {
                        continue;
                    }
                    if let Some(values) = d.data.cast_into::<f64>() {
                        out.push(Array {
                            ncomp: d.elem.num_comp() as usize,
                            name: d.name,
                            values,
                        });
                    }
                }
                Attribute::Field { data_array, .. } => {
                    for f in data_array {
                        if let Some(values) = f.data.cast_into::<f64>() {
                            out.push(Array {
                                ncomp: f.elem as usize,
                                name: f.name,
                                values,
                            });
                        }
                    }
                }
            }
        }
        out
    };
    (conv(attributes.point), conv(attributes.cell))
}

/// Cells (either vtkio layout) → tets by our split; the CSR connectivity is kept for averaging.
fn unstructured(
    points: Vec<[f32; 3]>,
    cells: vtkio::model::Cells,
) -> Result<(Geometry, usize), ErrorKind> {
    let np = points.len() as u64;
    let ncells = cells.types.len();
    let mut offsets = vec![0usize];
    let mut conn: Vec<u64> = Vec::new();
    match cells.cell_verts {
        VertexNumbers::Legacy {
            num_cells,
            vertices,
        } => {
            let mut i = 0;
            for _ in 0..num_cells {
                let n = *vertices.get(i).ok_or_else(|| ErrorKind::Truncated {
                    expected: "a cell's point count".into(),
                })? as usize;
                let ids = vertices
                    .get(i + 1..i + 1 + n)
                    .ok_or_else(|| ErrorKind::Truncated {
                        expected: "a cell's point ids".into(),
                    })?;
                conn.extend(ids.iter().map(|&v| v as u64));
                offsets.push(conn.len());
                i += 1 + n;
            }
        }
        VertexNumbers::XML {
            connectivity,
            offsets: ends,
        } => {
            // Legacy 5.x files give a leading 0; XML files give only the ends.
            let ends = if ends.len() == ncells + 1 && ends.first() == Some(&0) {
                &ends[1..]
            } else {
                &ends[..]
            };
            for &e in ends {
                let e = e as usize;
                if e < *offsets.last().unwrap_or(&0) || e > connectivity.len() {
                    return Err(ErrorKind::Invalid(format!(
                        "cell offset {e} out of order or beyond the connectivity"
                    )));
                }
                offsets.push(e);
            }
            conn = connectivity;
        }
    }
    if offsets.len() - 1 != ncells {
        return Err(ErrorKind::CountMismatch {
            what: "cell types vs cells".into(),
            expected: (offsets.len() - 1) as u64,
            found: ncells as u64,
        });
    }
    let mut conn32 = Vec::with_capacity(conn.len());
    for &v in &conn {
        if v >= np {
            return Err(ErrorKind::IndexOutOfRange {
                what: "point".into(),
                index: v,
                limit: np,
            });
        }
        conn32.push(v as u32);
    }
    let mut tets = Vec::with_capacity(ncells);
    for (c, ty) in cells.types.iter().enumerate() {
        cell_to_tets(
            *ty as u8 as u32,
            &conn32[offsets[c]..offsets[c + 1]],
            &mut tets,
        )?;
    }
    Ok((
        Geometry {
            points,
            tets,
            cell_offsets: offsets,
            cell_points: conn32,
            grid: None,
        },
        ncells,
    ))
}

fn grid_dims(extent: Extent) -> Result<[usize; 3], ErrorKind> {
    let d = extent.into_dims();
    let n = d.iter().map(|&x| x as u64).product::<u64>();
    if n > u32::MAX as u64 {
        return Err(ErrorKind::IndexOverflow {
            what: "grid points".into(),
            count: n,
        });
    }
    Ok(d.map(|x| x as usize))
}

/// Point count of a grid whose points are implicit; refused unless the file has a data array
/// of that many tuples (a tiny file must not make the test allocate a 10⁹-point grid).
fn backed_grid(dims: [usize; 3], data: &Attributes) -> Result<usize, ErrorKind> {
    let n = dims.iter().product::<usize>();
    let (pa, ca) = arrays(data.clone());
    let nc = dims.iter().map(|&d| d.saturating_sub(1)).product::<usize>();
    let backed = pa.iter().any(|a| a.values.len() == n * a.ncomp)
        || ca.iter().any(|a| a.values.len() == nc * a.ncomp);
    if !backed || n == 0 {
        return Err(ErrorKind::MissingArray {
            name: "(point or cell data for the grid)".into(),
            available: vec![],
        });
    }
    Ok(n)
}

/// A structured grid's tets (our 5-tet split) and the hexahedra's corners for averaging.
fn structured(points: Vec<[f32; 3]>, dims: [usize; 3]) -> Result<(Geometry, usize), ErrorKind> {
    let c = dims.map(|d| d.saturating_sub(1));
    let ncells = c[0] * c[1] * c[2];
    if ncells == 0 {
        return Err(ErrorKind::EmptyMesh(" (grid without 3-D cells)".into()));
    }
    let mut offsets = vec![0];
    let mut corners = Vec::with_capacity(8 * ncells);
    for k in 0..c[2] {
        for j in 0..c[1] {
            for i in 0..c[0] {
                for b in 0..8 {
                    let p =
                        (i + (b & 1)) + dims[0] * ((j + ((b >> 1) & 1)) + dims[1] * (k + (b >> 2)));
                    corners.push(p as u32);
                }
                offsets.push(corners.len());
            }
        }
    }
    Ok((
        Geometry {
            points,
            tets: structured_tets(dims),
            cell_offsets: offsets,
            cell_points: corners,
            grid: None,
        },
        ncells,
    ))
}

/// Whether the file at `path` is one vtkio can be asked about (legacy or XML VTK).
pub fn vtk_format(path: &Path) -> Option<Format> {
    match datasets::load::detect_format(path) {
        Ok(f @ (Format::VtkLegacy | Format::VtkXml)) => Some(f),
        _ => None,
    }
}
