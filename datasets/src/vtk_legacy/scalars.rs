//! The attributes of a parsed file: their counts against the geometry, the array chosen as
//! the scalar (named, else the first point array, else a cell array averaged to the points)
//! and its values, one per point.

use super::lexer::Parser;
use super::{Array, Kind, VtkFile};
use crate::cells;
use crate::dataset::LoadOptions;
use crate::error::{ErrorKind, LoadError};
use crate::read_util as util;

impl VtkFile {
    /// POINT_DATA and CELL_DATA counts must match the geometry.
    pub(super) fn check_attribute_counts(
        &self,
        p: &Parser,
        points: usize,
        n_cells: u64,
    ) -> Result<(), LoadError> {
        if let Some((m, at)) = self.point_data {
            if m != points as u64 {
                return Err(p.err(
                    at,
                    ErrorKind::CountMismatch {
                        what: "POINT_DATA values vs points".into(),
                        expected: points as u64,
                        found: m,
                    },
                ));
            }
        }
        if let Some((m, at)) = self.cell_data {
            if m != n_cells {
                return Err(p.err(
                    at,
                    ErrorKind::CountMismatch {
                        what: "CELL_DATA values vs cells".into(),
                        expected: n_cells,
                        found: m,
                    },
                ));
            }
        }
        Ok(())
    }

    /// The scalar array and whether it is cell data: the one `options` names, else the first
    /// point array (one component preferred), else the first cell array; `None` when the file
    /// has no array.
    pub(super) fn choose_scalar(
        &self,
        p: &Parser,
        options: &LoadOptions,
    ) -> Result<Option<(&Array, bool)>, LoadError> {
        let path = p.path;
        Ok(match &options.scalar {
            Some(name) => {
                let found = self
                    .point_arrays
                    .iter()
                    .find(|a| &a.name == name)
                    .map(|a| (a, false))
                    .or_else(|| {
                        self.cell_arrays
                            .iter()
                            .find(|a| &a.name == name)
                            .map(|a| (a, true))
                    });
                if found.is_none() {
                    let available = self
                        .point_arrays
                        .iter()
                        .chain(&self.cell_arrays)
                        .map(|a| a.name.clone())
                        .collect();
                    return Err(LoadError::new(
                        path,
                        ErrorKind::MissingArray {
                            name: name.clone(),
                            available,
                        },
                    ));
                }
                found
            }
            None => {
                fn pick(v: &[Array]) -> Option<&Array> {
                    v.iter().find(|a| a.ncomp == 1).or_else(|| v.first())
                }
                pick(&self.point_arrays)
                    .map(|a| (a, false))
                    .or_else(|| pick(&self.cell_arrays).map(|a| (a, true)))
            }
        })
    }

    /// The chosen array's values at the points: its magnitude per tuple, cell data averaged to
    /// the points; what that took is added to `warnings`.
    pub(super) fn scalar_values(
        &self,
        p: &Parser,
        (arr, is_cell): (&Array, bool),
        points: usize,
        regular_dims: Option<[usize; 3]>,
        warnings: &mut Vec<String>,
    ) -> Result<Vec<f32>, LoadError> {
        let kind = self.kind.unwrap_or(Kind::Unstructured);
        if let Some((i, pos, v)) = arr.non_finite {
            let what = format!(
                "value of array {} at {}",
                arr.name,
                if is_cell { "cell" } else { "point" }
            );
            return Err(p.err(
                pos,
                ErrorKind::NonFinite {
                    what,
                    index: (i / arr.ncomp) as u64,
                    value: v,
                },
            ));
        }
        let mut values = util::tuple_magnitudes(&arr.values, arr.ncomp);
        if arr.ncomp > 1 {
            warnings.push(format!(
                "array {} has {} components: its magnitude is the scalar",
                arr.name, arr.ncomp
            ));
        }
        if is_cell {
            warnings.push(format!(
                "cell data {} averaged to points (the file has no point array to use)",
                arr.name
            ));
            values = match (&self.cells, kind) {
                (Some(cells), Kind::Unstructured) => {
                    let conn: Vec<u32> = cells.conn.iter().map(|&v| v as u32).collect();
                    cells::cell_data_to_points(points, &cells.offsets, &conn, &values)
                }
                _ => structured_cell_to_points(
                    regular_dims
                        .or(self.dims.map(|d| d.0.map(|x| x as usize)))
                        .unwrap_or([1; 3]),
                    &values,
                ),
            };
        }
        Ok(values)
    }
}

/// Cell values of a structured grid (x fastest over cells) averaged to its points.
fn structured_cell_to_points(dims: [usize; 3], cell_values: &[f32]) -> Vec<f32> {
    let c = dims.map(|d| d.saturating_sub(1).max(1));
    let mut sum = vec![0f64; dims[0] * dims[1] * dims[2]];
    let mut cnt = vec![0u32; sum.len()];
    for k in 0..dims[2].saturating_sub(1) {
        for j in 0..dims[1].saturating_sub(1) {
            for i in 0..dims[0].saturating_sub(1) {
                let v = cell_values
                    .get(i + c[0] * (j + c[1] * k))
                    .copied()
                    .unwrap_or(0.0) as f64;
                for b in 0..8 {
                    let p =
                        (i + (b & 1)) + dims[0] * ((j + ((b >> 1) & 1)) + dims[1] * (k + (b >> 2)));
                    sum[p] += v;
                    cnt[p] += 1;
                }
            }
        }
    }
    sum.iter()
        .zip(&cnt)
        .map(|(&s, &n)| if n == 0 { 0.0 } else { (s / n as f64) as f32 })
        .collect()
}
