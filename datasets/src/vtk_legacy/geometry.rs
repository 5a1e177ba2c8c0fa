//! The geometry of a parsed file: its points and its cells split into conforming tets, the
//! cell count, and for STRUCTURED_POINTS the voxel grid's dimensions, origin and spacing.

use super::lexer::{byte_order_error, swapped_i64_plausible, Parser};
use super::{Cells, DataType, Geometry, Kind, VtkFile};
use crate::cells;
use crate::error::{ErrorKind, LoadError};
use crate::read_util as util;
use crate::volume::structured_tets;

impl VtkFile {
    pub(super) fn geometry(&self, p: &Parser) -> Result<Geometry, LoadError> {
        match self.kind.unwrap_or(Kind::Unstructured) {
            Kind::Unstructured => self.unstructured(p),
            kind => self.structured(p, kind),
        }
    }

    /// UNSTRUCTURED_GRID: POINTS, CELLS and CELL_TYPES, each cell split into tets.
    fn unstructured(&self, p: &Parser) -> Result<Geometry, LoadError> {
        let end = p.b.len();
        let (pts, _) = self.points.as_ref().ok_or_else(|| {
            p.err(
                end,
                ErrorKind::Truncated {
                    expected: "a POINTS section".into(),
                },
            )
        })?;
        let points: Vec<[f32; 3]> = pts.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let Some(cells) = self.cells.as_ref() else {
            return Err(p.err(end, ErrorKind::EmptyMesh(" (no CELLS section)".into())));
        };
        let ncells = cells.offsets.len() - 1;
        let Some((types, tstart, _)) = self.cell_types.as_ref() else {
            return Err(p.err(
                end,
                ErrorKind::Truncated {
                    expected: "a CELL_TYPES section".into(),
                },
            ));
        };
        if types.len() != ncells {
            return Err(p.err(
                *tstart,
                ErrorKind::CountMismatch {
                    what: "CELL_TYPES entries vs CELLS".into(),
                    expected: ncells as u64,
                    found: types.len() as u64,
                },
            ));
        }
        let conn = point_indices(p, cells, points.len() as i64)?;
        let mut tets = Vec::with_capacity(ncells);
        for c in 0..ncells {
            let t = types[c];
            let ids = &conn[cells.offsets[c]..cells.offsets[c + 1]];
            // Located only on error: finding an ASCII value's offset re-reads the block.
            let at = || p.value_pos(*tstart, c, DataType::I32);
            let t32 = u32::try_from(t).unwrap_or(u32::MAX);
            if cells::vtk_cell_size(t32).is_none()
                && p.binary
                && swapped_i64_plausible(t, DataType::I32, 81)
            {
                return Err(p.err(at(), byte_order_error("cell type", t)));
            }
            cells::cell_to_tets(t32, ids, &mut tets).map_err(|k| {
                let k = match k {
                    ErrorKind::UnknownCellType(s) if t32 == u32::MAX => {
                        ErrorKind::UnknownCellType(format!(
                            "{t} (not a VTK cell type) {}",
                            &s[s.find(';').unwrap_or(0)..]
                        ))
                    }
                    ErrorKind::CountMismatch {
                        what,
                        expected,
                        found,
                    } => ErrorKind::CountMismatch {
                        what: format!("{what} (cell {c})"),
                        expected,
                        found,
                    },
                    k => k,
                };
                p.err(at(), k)
            })?;
        }
        if tets.len() > u32::MAX as usize {
            return Err(p.err(
                cells.at,
                ErrorKind::IndexOverflow {
                    what: "tets".into(),
                    count: tets.len() as u64,
                },
            ));
        }
        Ok((points, tets, ncells as u64, None))
    }

    /// STRUCTURED_GRID, STRUCTURED_POINTS and RECTILINEAR_GRID: the points of DIMENSIONS
    /// (given, implicit or from the three coordinate arrays) and the hexahedra split into tets.
    fn structured(&self, p: &Parser, kind: Kind) -> Result<Geometry, LoadError> {
        let end = p.b.len();
        let (dims, dat) = self.dims.ok_or_else(|| {
            p.err(
                end,
                ErrorKind::Truncated {
                    expected: "a DIMENSIONS line".into(),
                },
            )
        })?;
        let n = util::grid_count(dims).map_err(|k| p.err(dat, k))?;
        let d = dims.map(|x| x as usize);
        let n_cells = d
            .iter()
            .map(|&x| x.saturating_sub(1) as u64)
            .product::<u64>();
        if n_cells == 0 {
            return Err(p.err(
                dat,
                ErrorKind::EmptyMesh(format!(
                    " (a {}×{}×{} grid has no 3-D cells)",
                    d[0], d[1], d[2]
                )),
            ));
        }
        let mut regular = None;
        let points = match kind {
            Kind::StructuredGrid => self.grid_points(p, n)?,
            _ => {
                self.check_implicit_points_backed(p, n, n_cells, dat)?;
                if kind == Kind::StructuredPoints {
                    let origin = self.origin.unwrap_or([0.0; 3]);
                    let spacing = self.spacing.unwrap_or([1.0; 3]);
                    regular = Some((d, origin, spacing));
                    util::grid_points(d, origin, spacing)
                } else {
                    self.rectilinear_points(p, d)?
                }
            }
        };
        Ok((points, structured_tets(d), n_cells, regular))
    }

    /// STRUCTURED_GRID's POINTS, as many as DIMENSIONS has.
    fn grid_points(&self, p: &Parser, n: usize) -> Result<Vec<[f32; 3]>, LoadError> {
        let end = p.b.len();
        let (pts, pat) = self.points.as_ref().ok_or_else(|| {
            p.err(
                end,
                ErrorKind::Truncated {
                    expected: "a POINTS section".into(),
                },
            )
        })?;
        if pts.len() / 3 != n {
            return Err(p.err(
                *pat,
                ErrorKind::CountMismatch {
                    what: "POINTS vs DIMENSIONS".into(),
                    expected: n as u64,
                    found: (pts.len() / 3) as u64,
                },
            ));
        }
        Ok(pts.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    /// Implicit points: their number is only backed by the file through its data arrays, so
    /// demand them before allocating (a tiny file must not conjure a 10⁹-point grid).
    fn check_implicit_points_backed(
        &self,
        p: &Parser,
        n: usize,
        n_cells: u64,
        dat: usize,
    ) -> Result<(), LoadError> {
        let backed = self
            .point_data
            .is_some_and(|(m, _)| m == n as u64 && !self.point_arrays.is_empty())
            || self
                .cell_data
                .is_some_and(|(m, _)| m == n_cells && !self.cell_arrays.is_empty());
        if !backed {
            if let Some((m, pat)) = self.point_data.filter(|(m, _)| *m != n as u64) {
                return Err(p.err(
                    pat,
                    ErrorKind::CountMismatch {
                        what: "POINT_DATA vs DIMENSIONS".into(),
                        expected: n as u64,
                        found: m,
                    },
                ));
            }
            return Err(p.err(
                dat,
                ErrorKind::MissingArray {
                    name: "(point or cell data for the grid)".into(),
                    available: vec![],
                },
            ));
        }
        Ok(())
    }

    /// RECTILINEAR_GRID's points from its X, Y and Z coordinates, x fastest.
    fn rectilinear_points(&self, p: &Parser, d: [usize; 3]) -> Result<Vec<[f32; 3]>, LoadError> {
        let end = p.b.len();
        let n = d[0] * d[1] * d[2];
        let mut axes: Vec<&Vec<f32>> = Vec::with_capacity(3);
        for a in 0..3 {
            let (c, cat) = self.coords[a].as_ref().ok_or_else(|| {
                p.err(
                    end,
                    ErrorKind::Truncated {
                        expected: format!("{}_COORDINATES", ["X", "Y", "Z"][a]),
                    },
                )
            })?;
            if c.len() != d[a] {
                return Err(p.err(
                    *cat,
                    ErrorKind::CountMismatch {
                        what: format!("{}_COORDINATES vs DIMENSIONS", ["X", "Y", "Z"][a]),
                        expected: d[a] as u64,
                        found: c.len() as u64,
                    },
                ));
            }
            axes.push(c);
        }
        let mut pts = Vec::with_capacity(n);
        for k in 0..d[2] {
            for j in 0..d[1] {
                for i in 0..d[0] {
                    pts.push([axes[0][i], axes[1][j], axes[2][k]]);
                }
            }
        }
        Ok(pts)
    }
}

/// The connectivity as point indices, each checked against the number of points `np` and
/// located in the file when out of range (as a byte-order error where its swap would fit).
fn point_indices(p: &Parser, cells: &Cells, np: i64) -> Result<Vec<u32>, LoadError> {
    let conn_ty = cells.conn_type.unwrap_or(DataType::I32);
    // Index of value j of the connectivity within the file's value stream.
    let file_index = |j: usize| -> usize {
        if cells.legacy_layout {
            // Counts are interleaved: value j of cell c sits after c + 1 counts.
            let c = cells.offsets.partition_point(|&o| o <= j);
            j + c
        } else {
            j
        }
    };
    let mut conn = Vec::with_capacity(cells.conn.len());
    for (j, &v) in cells.conn.iter().enumerate() {
        if v < 0 || v >= np {
            let at = p.value_pos(cells.conn_at, file_index(j), conn_ty);
            if p.binary && swapped_i64_plausible(v, conn_ty, np - 1) {
                return Err(p.err(at, byte_order_error("point index", v)));
            }
            if v < 0 {
                return Err(p.err(
                    at,
                    ErrorKind::Syntax {
                        expected: "a non-negative point index".into(),
                        found: v.to_string(),
                    },
                ));
            }
            return Err(p.err(
                at,
                ErrorKind::IndexOutOfRange {
                    what: "point".into(),
                    index: v as u64,
                    limit: np as u64,
                },
            ));
        }
        conn.push(v as u32);
    }
    Ok(conn)
}
