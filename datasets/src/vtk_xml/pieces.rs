//! What every dataset type shares: its pieces, a piece's points, the scalar's choice (point
//! data, else cell data averaged to the points), extents, and the mesh and dataset made at the
//! end. `unstructured.rs` and `structured.rs` build on it.

use rayon::prelude::*;

use super::{Element, XmlFile};
use crate::dataset::{Dataset, LoadOptions};
use crate::error::{ErrorKind, LoadError};
use crate::grid::grid_ijk;
use crate::mesh::TetMesh;
use crate::volume::VoxelGrid;

impl<'a> XmlFile<'a> {
    /// Chooses the point scalar: `options.scalar` by name, else the PointData's active
    /// `Scalars`, else its first one-component array, else its first array (as magnitude).
    /// Falls back to cell data (averaged by the caller) and finally to a zero field.
    pub(super) fn choose_scalar(
        &self,
        piece: &Element,
        options: &LoadOptions,
        npoints: usize,
        ncells: usize,
    ) -> Result<ScalarSource, LoadError> {
        let pd: Vec<&Element> = piece
            .child("PointData")
            .map(|p| p.children_named("DataArray").collect())
            .unwrap_or_default();
        let cd: Vec<&Element> = piece
            .child("CellData")
            .map(|p| p.children_named("DataArray").collect())
            .unwrap_or_default();
        let name_of = |e: &Element| e.attr("Name").unwrap_or("").to_string();
        if let Some(want) = &options.scalar {
            if let Some(e) = pd.iter().find(|e| e.attr("Name") == Some(want.as_str())) {
                return Ok(ScalarSource::Point(
                    want.clone(),
                    self.read_scalar_array(e, npoints)?,
                ));
            }
            if let Some(e) = cd.iter().find(|e| e.attr("Name") == Some(want.as_str())) {
                return Ok(ScalarSource::Cell(
                    want.clone(),
                    self.read_scalar_array(e, ncells)?,
                ));
            }
            return Err(self.err_el(
                piece,
                ErrorKind::MissingArray {
                    name: want.clone(),
                    available: pd.iter().chain(cd.iter()).map(|e| name_of(e)).collect(),
                },
            ));
        }
        if let Some(i) = pick_default(&pd, piece.child("PointData")) {
            return Ok(ScalarSource::Point(
                name_of(pd[i]),
                self.read_scalar_array(pd[i], npoints)?,
            ));
        }
        if let Some(i) = pick_default(&cd, piece.child("CellData")) {
            return Ok(ScalarSource::Cell(
                name_of(cd[i]),
                self.read_scalar_array(cd[i], ncells)?,
            ));
        }
        Ok(ScalarSource::None)
    }

    /// One value per tuple; arrays of several components give their Euclidean magnitude.
    pub(super) fn read_scalar_array(
        &self,
        el: &Element,
        tuples: usize,
    ) -> Result<Vec<f64>, LoadError> {
        let nc = self.components(el)?;
        let v = self.read_f64(el, tuples.saturating_mul(nc))?;
        if nc == 1 {
            return Ok(v);
        }
        Ok(v.chunks_exact(nc)
            .map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt())
            .collect())
    }

    // -- Shared by every dataset type ----------------------------------------------------------

    /// The grid's `<Piece>` elements; none is an error.
    pub(super) fn pieces<'e>(&self, grid: &'e Element) -> Result<Vec<&'e Element>, LoadError> {
        let pieces: Vec<&Element> = grid.children_named("Piece").collect();
        if pieces.is_empty() {
            return Err(self.err_el(grid, ErrorKind::EmptyMesh(" (no <Piece>)".into())));
        }
        Ok(pieces)
    }

    /// Appends the `np` points of the piece's `<Points>` array to `out`.
    pub(super) fn piece_points(
        &self,
        piece: &Element,
        np: usize,
        out: &mut Vec<[f32; 3]>,
    ) -> Result<(), LoadError> {
        let pts_el = piece
            .child("Points")
            .and_then(|p| p.child("DataArray"))
            .ok_or_else(|| {
                self.err_el(
                    piece,
                    ErrorKind::Syntax {
                        expected: "<Points><DataArray …>".into(),
                        found: "none".into(),
                    },
                )
            })?;
        self.read_points(pts_el, np, out)
    }

    /// The checked mesh of the file's name.
    pub(super) fn tet_mesh(
        &self,
        points: Vec<[f32; 3]>,
        scalars: Vec<f32>,
        scalar_name: String,
        tets: Vec<[u32; 4]>,
    ) -> Result<TetMesh, LoadError> {
        TetMesh::new(self.mesh_name(), points, scalars, scalar_name, tets)
            .map_err(|k| LoadError::new(self.path, k))
    }

    /// The dataset of `mesh` (and the voxel grid it was split from), the reader's `warnings`
    /// added to its repair report.
    pub(super) fn dataset(
        &self,
        mut mesh: TetMesh,
        volume: Option<std::sync::Arc<VoxelGrid>>,
        warnings: Vec<String>,
    ) -> Dataset {
        mesh.repair.warnings.extend(warnings);
        Dataset {
            mesh,
            volume,
            source: self.path.display().to_string(),
        }
    }

    pub(super) fn read_points(
        &self,
        el: &Element,
        np: usize,
        out: &mut Vec<[f32; 3]>,
    ) -> Result<(), LoadError> {
        let nc = self.components(el)?;
        if nc != 3 {
            return Err(self.err_el(
                el,
                ErrorKind::CountMismatch {
                    what: "components of Points".into(),
                    expected: 3,
                    found: nc as u64,
                },
            ));
        }
        let v = self.read_f64(el, np.saturating_mul(3))?;
        out.extend(
            v.chunks_exact(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32]),
        );
        Ok(())
    }

    pub(super) fn extent_dims(&self, el: &Element, ext: &[i64]) -> Result<[usize; 3], LoadError> {
        let mut d = [0usize; 3];
        for a in 0..3 {
            let n = ext[2 * a + 1]
                .checked_sub(ext[2 * a])
                .and_then(|n| n.checked_add(1))
                .unwrap_or(0);
            if n < 1 {
                return Err(self.err_el(el, ErrorKind::Invalid(format!("empty extent {ext:?}"))));
            }
            d[a] = n as usize;
        }
        Ok(d)
    }
}

/// The default scalar among `arrays`: the holder's active `Scalars`, else the first
/// one-component array, else the first array.
pub(super) fn pick_default(arrays: &[&Element], holder: Option<&Element>) -> Option<usize> {
    let active = holder.and_then(|h| h.attr("Scalars"));
    active
        .and_then(|a| arrays.iter().position(|e| e.attr("Name") == Some(a)))
        .or_else(|| {
            arrays
                .iter()
                .position(|e| e.attr("NumberOfComponents").is_none_or(|c| c.trim() == "1"))
        })
        .or(if arrays.is_empty() { None } else { Some(0) })
}

/// Averages cell values of a structured grid (cells x fastest) to its points.
pub(super) fn cells_to_points(dims: [usize; 3], cells: &[f64]) -> Vec<f64> {
    let cd = dims.map(|d| d.saturating_sub(1).max(1));
    let n = dims.iter().product::<usize>();
    (0..n)
        .into_par_iter()
        .map(|g| {
            let ijk = grid_ijk(g, dims);
            let (mut s, mut c) = (0.0, 0u32);
            for dk in 0..2 {
                for dj in 0..2 {
                    for di in 0..2 {
                        let d = [di, dj, dk];
                        let mut cell = [0usize; 3];
                        let mut ok = true;
                        for a in 0..3 {
                            if ijk[a] < d[a] || ijk[a] - d[a] >= cd[a] {
                                ok = false;
                            } else {
                                cell[a] = ijk[a] - d[a];
                            }
                        }
                        if ok {
                            s += cells[cell[0] + cd[0] * (cell[1] + cd[1] * cell[2])];
                            c += 1;
                        }
                    }
                }
            }
            if c > 0 {
                s / c as f64
            } else {
                0.0
            }
        })
        .collect()
}

pub(super) enum ScalarSource {
    Point(String, Vec<f64>),
    Cell(String, Vec<f64>),
    None,
}
