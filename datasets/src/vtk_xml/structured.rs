//! StructuredGrid and ImageData: pieces are sub-extents of `WholeExtent`, each read on its
//! own, then assembled into one grid, split by [`structured_tets`] (5 tets per cell,
//! conforming) or, for an axis-aligned image, kept as a voxel grid beside its tets.

use super::pieces::{cells_to_points, ScalarSource};
use super::{Element, XmlFile};
use crate::dataset::{Dataset, LoadOptions};
use crate::error::{ErrorKind, LoadError};
use crate::grid::grid_ijk;
use crate::volume::{structured_tets, VoxelGrid};

const IDENTITY: [f64; 9] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

/// The grid's whole extent and what follows from it.
struct Whole {
    extent: Vec<i64>,
    /// Points per axis.
    dims: [usize; 3],
    points: usize,
    /// An image's placement: origin, spacing and direction (row-major 3×3; empty for a
    /// structured grid, whose points are given).
    origin: [f64; 3],
    spacing: [f64; 3],
    direction: Vec<f64>,
}

impl Whole {
    fn cell_dims(&self) -> [usize; 3] {
        self.dims.map(|d| d.saturating_sub(1).max(1))
    }

    /// A point's position in an image with a rotating `Direction`.
    fn image_point(&self, g: usize) -> [f32; 3] {
        let ijk = grid_ijk(g, self.dims);
        let l = [0, 1, 2].map(|a| (ijk[a] as f64 + self.extent[2 * a] as f64) * self.spacing[a]);
        let d = &self.direction;
        [0, 1, 2].map(|r| {
            (self.origin[r] + d[3 * r] * l[0] + d[3 * r + 1] * l[1] + d[3 * r + 2] * l[2]) as f32
        })
    }
}

/// One piece, read: where it lies in the whole grid, its points (a structured grid's) and
/// its scalar.
struct PieceData {
    off: [usize; 3],
    pdims: [usize; 3],
    points: Vec<[f32; 3]>,
    name: String,
    vals: Vec<f64>,
    is_point: bool,
}

impl PieceData {
    /// The whole grid's index of local point (`cells` false) or cell `l` (x fastest), for a
    /// grid of `dims` points or cells.
    fn global(&self, l: usize, cells: bool, dims: [usize; 3]) -> usize {
        let d = if cells {
            self.pdims.map(|d| d.saturating_sub(1).max(1))
        } else {
            self.pdims
        };
        let [i, j, k] = grid_ijk(l, d);
        let off = self.off;
        (i + off[0]) + dims[0] * ((j + off[1]) + dims[1] * (k + off[2]))
    }
}

impl<'a> XmlFile<'a> {
    /// StructuredGrid (`image` false) and ImageData.
    pub(super) fn build_structured(
        &self,
        grid: &Element,
        image: bool,
        options: &LoadOptions,
    ) -> Result<Dataset, LoadError> {
        let whole = self.whole(grid, image)?;
        // Read every piece first (their arrays are checked against the data actually present),
        // then assemble: a WholeExtent the pieces cannot fill is an error, not an allocation.
        let read = self
            .pieces(grid)?
            .into_iter()
            .map(|piece| self.read_structured_piece(piece, &whole, image, options))
            .collect::<Result<Vec<_>, _>>()?;
        let covered = read
            .iter()
            .fold(0usize, |n, p| n.saturating_add(p.pdims.iter().product()));
        if covered < whole.points {
            return Err(self.err_el(
                grid,
                ErrorKind::CountMismatch {
                    what: "grid points given by the pieces (WholeExtent)".into(),
                    expected: whole.points as u64,
                    found: covered as u64,
                },
            ));
        }
        let (scalar_name, point_scalar) = (read[0].name.clone(), read[0].is_point);
        if read
            .iter()
            .any(|p| p.name != scalar_name || p.is_point != point_scalar)
        {
            return Err(self.err_el(
                grid,
                ErrorKind::Invalid(format!(
                    "pieces disagree on the scalar array ({scalar_name:?})"
                )),
            ));
        }
        let (points, scalars) = assemble(read, &whole, image, point_scalar);
        self.structured_dataset(whole, image, points, scalars, scalar_name, point_scalar)
    }

    /// `WholeExtent`, checked, and an image's placement.
    fn whole(&self, grid: &Element, image: bool) -> Result<Whole, LoadError> {
        let extent: Vec<i64> = self.attr_numbers(grid, "WholeExtent", 6)?.ok_or_else(|| {
            self.err_el(
                grid,
                ErrorKind::Syntax {
                    expected: "a WholeExtent attribute".into(),
                    found: "nothing".into(),
                },
            )
        })?;
        let dims = self.extent_dims(grid, &extent)?;
        let points = dims[0]
            .checked_mul(dims[1])
            .and_then(|d| d.checked_mul(dims[2]))
            .unwrap_or(usize::MAX);
        if points > u32::MAX as usize {
            return Err(self.err_el(
                grid,
                ErrorKind::IndexOverflow {
                    what: "points".into(),
                    count: points as u64,
                },
            ));
        }
        let (origin, spacing, direction) = if image {
            let numbers = |key: &str, n: usize, default: &[f64]| {
                self.attr_numbers::<f64>(grid, key, n)
                    .map(|v| v.unwrap_or_else(|| default.to_vec()))
            };
            let o = numbers("Origin", 3, &[0.0; 3])?;
            let s = numbers("Spacing", 3, &[1.0; 3])?;
            let d = numbers("Direction", 9, &IDENTITY)?;
            ([o[0], o[1], o[2]], [s[0], s[1], s[2]], d)
        } else {
            ([0.0; 3], [1.0; 3], vec![])
        };
        Ok(Whole {
            extent,
            dims,
            points,
            origin,
            spacing,
            direction,
        })
    }

    /// One piece: its extent (checked inside the whole), a structured grid's points and the
    /// scalar.
    fn read_structured_piece(
        &self,
        piece: &Element,
        whole: &Whole,
        image: bool,
        options: &LoadOptions,
    ) -> Result<PieceData, LoadError> {
        let w = &whole.extent;
        let ext: Vec<i64> = self
            .attr_numbers(piece, "Extent", 6)?
            .unwrap_or_else(|| w.clone());
        let pdims = self.extent_dims(piece, &ext)?;
        if (0..3).any(|a| ext[2 * a] < w[2 * a] || ext[2 * a + 1] > w[2 * a + 1]) {
            return Err(self.err_el(
                piece,
                ErrorKind::Invalid(format!(
                    "piece Extent {ext:?} lies outside WholeExtent {w:?}"
                )),
            ));
        }
        // Inside the whole extent, so the products cannot overflow.
        let pn = pdims.iter().product::<usize>();
        let pcells = pdims
            .map(|d| d.saturating_sub(1).max(1))
            .iter()
            .product::<usize>();
        let mut points = Vec::new();
        if !image {
            self.piece_points(piece, pn, &mut points)?;
        }
        let (name, vals, is_point) = match self.choose_scalar(piece, options, pn, pcells)? {
            ScalarSource::Point(n, v) => (n, v, true),
            ScalarSource::Cell(n, v) => (n, v, false),
            ScalarSource::None if image => {
                return Err(self.err_el(
                    piece,
                    ErrorKind::MissingArray {
                        name: "any point or cell array".into(),
                        available: vec![],
                    },
                ))
            }
            ScalarSource::None => (String::new(), Vec::new(), true),
        };
        Ok(PieceData {
            off: [0, 1, 2].map(|a| (ext[2 * a] - w[2 * a]) as usize),
            pdims,
            points,
            name,
            vals,
            is_point,
        })
    }

    /// The assembled grid as a mesh: an axis-aligned image keeps its voxel grid, a rotated
    /// image gets its points placed, a structured grid has its own.
    fn structured_dataset(
        &self,
        whole: Whole,
        image: bool,
        mut points: Vec<[f32; 3]>,
        scalars: Vec<f64>,
        scalar_name: String,
        point_scalar: bool,
    ) -> Result<Dataset, LoadError> {
        let mut warnings = Vec::new();
        let scalar_name = if scalar_name.is_empty() {
            warnings.push("no point or cell data: scalar set to 0".into());
            "zero".to_string()
        } else {
            scalar_name
        };
        let scalars = if point_scalar {
            scalars
        } else {
            warnings.push(format!(
                "no point data: cell array {scalar_name:?} averaged to the points"
            ));
            cells_to_points(whole.dims, &scalars)
        };
        let values: Vec<f32> = scalars.iter().map(|&v| v as f32).collect();
        let identity = whole.direction.is_empty() || whole.direction == IDENTITY;
        if image && identity {
            let vg = VoxelGrid {
                dims: whole.dims,
                spacing: whole.spacing,
                origin: [0, 1, 2]
                    .map(|a| whole.origin[a] + whole.extent[2 * a] as f64 * whole.spacing[a]),
                values: values.into(),
                scalar_name,
            };
            let mut mesh = vg.to_tets().map_err(|k| LoadError::new(self.path, k))?;
            mesh.name = self.mesh_name();
            return Ok(self.dataset(mesh, Some(std::sync::Arc::new(vg)), warnings));
        }
        if image {
            warnings.push(
                "ImageData with a non-identity Direction: converted to tets only (no voxel grid)"
                    .into(),
            );
            points = (0..whole.points).map(|g| whole.image_point(g)).collect();
        }
        let mesh = self.tet_mesh(points, values, scalar_name, structured_tets(whole.dims))?;
        Ok(self.dataset(mesh, None, warnings))
    }
}

/// The pieces' points (a structured grid's) and scalars (at the points or the cells) in the
/// whole grid's order.
fn assemble(
    read: Vec<PieceData>,
    whole: &Whole,
    image: bool,
    point_scalar: bool,
) -> (Vec<[f32; 3]>, Vec<f64>) {
    let (dims, cdims) = (whole.dims, whole.cell_dims());
    let mut points = vec![[0f32; 3]; if image { 0 } else { whole.points }];
    let scalar_count = if point_scalar {
        whole.points
    } else {
        cdims.iter().product()
    };
    let mut scalars = vec![0f64; scalar_count];
    for p in read {
        for (l, q) in p.points.iter().enumerate() {
            points[p.global(l, false, dims)] = *q;
        }
        for (l, &v) in p.vals.iter().enumerate() {
            let g = if point_scalar {
                p.global(l, false, dims)
            } else {
                p.global(l, true, cdims)
            };
            scalars[g] = v;
        }
    }
    (points, scalars)
}
