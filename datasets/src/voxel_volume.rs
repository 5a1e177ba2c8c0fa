//! Voxel data sets whose tets are split only when something asks for them.
//!
//! A generated volume (`vol:N`, the splatting stand-ins, `fuel`, `brain`) is a grid whose tet
//! mesh is a fixed function of it: every cell, or only the cells with a non-zero corner, split
//! into 5 or 6 tets. The splatter reads the voxels alone, so a run that measures only it never
//! needs the tets (StagBeetle's support split is 84 M tets, several GB while it is checked).
//! [`VoxelVolume`] holds the grid once (an `Arc` that the split mesh shares as its
//! [`TetMesh::source_grid`]) and answers what a run asks of the mesh — tet and point counts,
//! bounds, scalar range, which grid points the tets use — from the grid alone, with the same
//! values the split mesh would give; [`VoxelVolume::mesh`] splits it on first use.

use std::sync::{Arc, OnceLock};

use rayon::prelude::*;

use crate::error::ErrorKind;
use crate::grid::{grid_ijk, VoxelGrid};
use crate::mesh::{Aabb, TetMesh};
use crate::volume::{split_cells, CellSplit};

/// Which cells of the grid the split covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellCover {
    /// Every cell.
    All,
    /// Only the cells with a non-zero corner ([`VoxelGrid::cube_has_nonzero_corner`]): the
    /// support of a volume that is exactly 0 elsewhere.
    Support,
}

/// What a volume's split uses of its grid, counted from the grid without splitting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    /// Cells the split covers (each gives [`CellSplit::tets_per_cell`] tets).
    pub cells: usize,
    /// Grid points that are a corner of a covered cell: the points the mesh's tets use.
    pub used_points: usize,
    /// (min, max) value over the used points (the mesh's `scalar_range`).
    pub scalar_range: (f32, f32),
    /// Smallest and largest grid index per axis over the used points.
    pub index_min: [usize; 3],
    pub index_max: [usize; 3],
}

impl Footprint {
    fn empty() -> Footprint {
        Footprint {
            cells: 0,
            used_points: 0,
            scalar_range: (f32::INFINITY, f32::NEG_INFINITY),
            index_min: [usize::MAX; 3],
            index_max: [0; 3],
        }
    }

    fn merge(self, o: Footprint) -> Footprint {
        Footprint {
            cells: self.cells + o.cells,
            used_points: self.used_points + o.used_points,
            scalar_range: (
                self.scalar_range.0.min(o.scalar_range.0),
                self.scalar_range.1.max(o.scalar_range.1),
            ),
            index_min: [0, 1, 2].map(|a| self.index_min[a].min(o.index_min[a])),
            index_max: [0, 1, 2].map(|a| self.index_max[a].max(o.index_max[a])),
        }
    }
}

/// A regular volume as a data set: its grid, held once, and the tets it splits into on demand.
#[derive(Debug)]
pub struct VoxelVolume {
    /// The name its split mesh gets.
    pub name: String,
    grid: Arc<VoxelGrid>,
    split: CellSplit,
    cover: CellCover,
    footprint: OnceLock<Footprint>,
    /// Shared (`Arc`) so that renderers which read the mesh every frame keep a handle, not
    /// a copy.
    mesh: OnceLock<Arc<TetMesh>>,
}

impl VoxelVolume {
    /// Checks what [`TetMesh::new`] would refuse of the split (value count, index range,
    /// finite values and positions, at least one tet), so that [`Self::mesh`] cannot fail
    /// later; a regular grid of non-zero spacing has no degenerate tets.
    pub fn new(
        name: impl Into<String>,
        grid: Arc<VoxelGrid>,
        split: CellSplit,
        cover: CellCover,
    ) -> Result<VoxelVolume, ErrorKind> {
        grid.checked_num_voxels()?;
        let geometry = grid.origin.iter().chain(&grid.spacing);
        if let Some(v) = geometry.copied().find(|v| !v.is_finite()) {
            return Err(ErrorKind::NonFinite {
                what: "grid origin or spacing".into(),
                index: 0,
                value: v,
            });
        }
        if grid.spacing.contains(&0.0) {
            return Err(ErrorKind::Invalid(format!(
                "grid spacing {:?}: every tet would be flat",
                grid.spacing
            )));
        }
        if let Some((i, v)) = grid
            .values
            .par_iter()
            .enumerate()
            .find_first(|(_, v)| !v.is_finite())
        {
            return Err(ErrorKind::NonFinite {
                what: "scalar of point".into(),
                index: i as u64,
                value: v as f64,
            });
        }
        let volume = VoxelVolume {
            name: name.into(),
            grid,
            split,
            cover,
            footprint: OnceLock::new(),
            mesh: OnceLock::new(),
        };
        if volume.num_tets() == 0 {
            return Err(ErrorKind::EmptyMesh(String::new()));
        }
        Ok(volume)
    }

    pub fn grid(&self) -> &Arc<VoxelGrid> {
        &self.grid
    }
    pub fn split(&self) -> CellSplit {
        self.split
    }
    pub fn cover(&self) -> CellCover {
        self.cover
    }

    /// What the split uses of the grid (one pass over the grid, then cached).
    pub fn footprint(&self) -> &Footprint {
        self.footprint.get_or_init(|| match self.cover {
            CellCover::All => all_cells_footprint(&self.grid),
            CellCover::Support => support_footprint(&self.grid),
        })
    }

    /// The split mesh's tet count, without splitting.
    pub fn num_tets(&self) -> usize {
        self.footprint().cells * self.split.tets_per_cell()
    }

    /// The split mesh's point count: every grid point.
    pub fn num_points(&self) -> usize {
        self.grid.num_voxels()
    }

    /// The split mesh's [`TetMesh::bounds`] (its used points, at their f32 positions).
    pub fn bounds(&self) -> Aabb {
        let f = self.footprint();
        if f.used_points == 0 {
            return Aabb::of_points(&[]);
        }
        let at = |ijk: [usize; 3]| {
            self.grid
                .point(ijk[0], ijk[1], ijk[2])
                .map(|c| c as f32 as f64)
        };
        let (lo, hi) = (at(f.index_min), at(f.index_max));
        Aabb {
            min: [0, 1, 2].map(|a| lo[a].min(hi[a])),
            max: [0, 1, 2].map(|a| lo[a].max(hi[a])),
        }
    }

    /// The split mesh's [`TetMesh::scalar_range`].
    pub fn scalar_range(&self) -> (f32, f32) {
        self.footprint().scalar_range
    }

    /// Whether the split's tets use grid point `index` (x fastest).
    pub fn point_is_used(&self, index: usize) -> bool {
        let g = &*self.grid;
        if self.footprint().cells == 0 {
            return false;
        }
        match self.cover {
            CellCover::All => true,
            // A point is used when one of the (up to 8) cells around it is kept, i.e. when a
            // point of its 3×3×3 neighbourhood (clamped to the grid) is non-zero.
            CellCover::Support => {
                if g.values.get(index) != 0.0 {
                    return true;
                }
                let d = g.dims;
                let ijk = grid_ijk(index, d);
                let lo = ijk.map(|c| c.saturating_sub(1));
                let hi = [0, 1, 2].map(|a| (ijk[a] + 1).min(d[a] - 1));
                (lo[2]..=hi[2]).any(|k| {
                    (lo[1]..=hi[1])
                        .any(|j| (lo[0]..=hi[0]).any(|i| g.values.get(g.index(i, j, k)) != 0.0))
                })
            }
        }
    }

    /// Whether the tets have been split yet.
    pub fn tets_built(&self) -> bool {
        self.mesh.get().is_some()
    }

    /// The split mesh, built on first use and kept; it shares the grid
    /// ([`TetMesh::source_grid`]), so the values are held by the grid and once more as the
    /// mesh's point scalars, only while the mesh exists.
    pub fn mesh(&self) -> Result<&Arc<TetMesh>, ErrorKind> {
        if let Some(m) = self.mesh.get() {
            return Ok(m);
        }
        let m = Arc::new(self.split_now()?);
        Ok(self.mesh.get_or_init(|| m))
    }

    /// The split mesh, the volume given up.
    pub fn into_mesh(mut self) -> Result<TetMesh, ErrorKind> {
        match self.mesh.take() {
            Some(m) => Ok(Arc::unwrap_or_clone(m)),
            None => self.split_now(),
        }
    }

    fn split_now(&self) -> Result<TetMesh, ErrorKind> {
        let g = &*self.grid;
        let mut mesh = match self.cover {
            CellCover::All => split_cells(g, self.split, |_, _, _| true),
            CellCover::Support => {
                split_cells(g, self.split, |i, j, k| g.cube_has_nonzero_corner(i, j, k))
            }
        }?;
        mesh.name = self.name.clone();
        mesh.source_grid = Some(Arc::clone(&self.grid));
        Ok(mesh)
    }
}

fn all_cells_footprint(g: &VoxelGrid) -> Footprint {
    let cells: usize = g.dims.iter().map(|d| d.saturating_sub(1)).product();
    if cells == 0 {
        return Footprint::empty();
    }
    let scalar_range = g
        .values
        .par_iter()
        .fold(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |(lo, hi), v| (lo.min(v), hi.max(v)),
        )
        .reduce(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    Footprint {
        cells,
        used_points: g.num_voxels(),
        scalar_range,
        index_min: [0; 3],
        index_max: g.dims.map(|d| d - 1),
    }
}

/// Planes (constant k) a task of [`support_footprint`] takes.
const PLANES_PER_TASK: usize = 8;

/// The support split's footprint in one pass of plane masks: a cell is kept when one of its 8
/// corners is non-zero, a point is used when a kept cell has it as a corner (a non-zero point
/// in its clamped 3×3×3 neighbourhood). No mask larger than a few planes is ever held.
fn support_footprint(g: &VoxelGrid) -> Footprint {
    let [nx, ny, nz] = g.dims;
    if nx < 2 || ny < 2 || nz < 2 {
        return Footprint::empty();
    }
    let plane = nx * ny;
    let nonzero = |k: usize| -> Vec<bool> {
        (k * plane..(k + 1) * plane)
            .map(|i| g.values.get(i) != 0.0)
            .collect()
    };
    // Any non-zero in the clamped 3×3 window around each point of a plane.
    let near = |n: &[bool]| -> Vec<bool> {
        let mut rows = vec![false; plane];
        for j in 0..ny {
            let r = &n[j * nx..(j + 1) * nx];
            for i in 0..nx {
                rows[j * nx + i] = r[i] || (i > 0 && r[i - 1]) || (i + 1 < nx && r[i + 1]);
            }
        }
        (0..plane)
            .map(|p| {
                let j = p / nx;
                rows[p] || (j > 0 && rows[p - nx]) || (j + 1 < ny && rows[p + nx])
            })
            .collect()
    };
    // Any non-zero among the 4 corners in this plane of each cell (i, j) (i < nx − 1, j < ny − 1).
    let corners = |n: &[bool]| -> Vec<bool> {
        (0..(nx - 1) * (ny - 1))
            .map(|c| {
                let (i, j) = (c % (nx - 1), c / (nx - 1));
                let p = j * nx + i;
                n[p] || n[p + 1] || n[p + nx] || n[p + nx + 1]
            })
            .collect()
    };
    (0..nz.div_ceil(PLANES_PER_TASK))
        .into_par_iter()
        .map(|task| {
            let k0 = task * PLANES_PER_TASK;
            let k1 = (k0 + PLANES_PER_TASK).min(nz);
            // Planes k0 − 1 ..= k1, clamped: the neighbours of the task's planes.
            let first = k0.saturating_sub(1);
            let last = k1.min(nz - 1);
            let masks: Vec<Vec<bool>> = (first..=last).map(nonzero).collect();
            let near_masks: Vec<Vec<bool>> = masks.iter().map(|m| near(m)).collect();
            let corner_masks: Vec<Vec<bool>> = masks.iter().map(|m| corners(m)).collect();
            let at = |k: usize| k - first;
            let mut f = Footprint::empty();
            for k in k0..k1 {
                if k + 1 < nz {
                    let (a, b) = (&corner_masks[at(k)], &corner_masks[at(k + 1)]);
                    f.cells += a.iter().zip(b).filter(|(x, y)| **x || **y).count();
                }
                let below = (k > 0).then(|| &near_masks[at(k - 1)]);
                let above = (k + 1 < nz).then(|| &near_masks[at(k + 1)]);
                let here = &near_masks[at(k)];
                let values = g.values.slice(k * plane..(k + 1) * plane);
                for p in 0..plane {
                    let used =
                        here[p] || below.is_some_and(|m| m[p]) || above.is_some_and(|m| m[p]);
                    if used {
                        let (i, j) = (p % nx, p / nx);
                        f.used_points += 1;
                        let v = values[p];
                        f.scalar_range = (f.scalar_range.0.min(v), f.scalar_range.1.max(v));
                        for (a, c) in [i, j, k].into_iter().enumerate() {
                            f.index_min[a] = f.index_min[a].min(c);
                            f.index_max[a] = f.index_max[a].max(c);
                        }
                    }
                }
            }
            f
        })
        .reduce(Footprint::empty, Footprint::merge)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{hex_cell_tets, kuhn_cell_tets};

    /// A grid with non-zero values in a few places, borders and corners included, so that
    /// clamping at every face is exercised.
    fn sparse_grid(dims: [usize; 3], nonzero: &[[usize; 3]]) -> VoxelGrid {
        let mut values = vec![0.0; dims.iter().product()];
        for (n, &[i, j, k]) in nonzero.iter().enumerate() {
            values[i + dims[0] * (j + dims[1] * k)] = 1.0 + n as f32;
        }
        VoxelGrid {
            dims,
            spacing: [0.5, 1.25, 0.75],
            origin: [-1.0, 2.0, 0.25],
            values: values.into(),
            scalar_name: "s".into(),
        }
    }

    /// About one point in eight non-zero, scattered by a fixed hash (no generator needed: this
    /// module must not import `standins`, which imports it).
    fn scattered_grid(dims: [usize; 3]) -> VoxelGrid {
        let n: usize = dims.iter().product();
        let spots: Vec<[usize; 3]> = (0..n)
            .filter(|&p| (p as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 61 == 0)
            .map(|p| grid_ijk(p, dims))
            .collect();
        sparse_grid(dims, &spots)
    }

    /// The split built here independently of `split_cells` (the loops the readers and
    /// generators used before volumes split lazily).
    fn reference_split(g: &VoxelGrid, split: CellSplit, cover: CellCover) -> TetMesh {
        let d = g.dims;
        let mut tets = vec![];
        for k in 0..d[2] - 1 {
            for j in 0..d[1] - 1 {
                for i in 0..d[0] - 1 {
                    let keep = cover == CellCover::All
                        || (0..8).any(|b| {
                            g.values
                                .get(g.index(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1)))
                                != 0.0
                        });
                    if keep {
                        match split {
                            CellSplit::Five => tets.extend(hex_cell_tets(d, i, j, k)),
                            CellSplit::Six => tets.extend(kuhn_cell_tets(d, i, j, k)),
                        }
                    }
                }
            }
        }
        let mut points = vec![];
        for k in 0..d[2] {
            for j in 0..d[1] {
                for i in 0..d[0] {
                    points.push(g.point(i, j, k).map(|c| c as f32));
                }
            }
        }
        TetMesh::new("ref", points, g.values.to_vec(), "s", tets).unwrap()
    }

    #[test]
    fn counts_bounds_and_range_match_the_split_without_building_it() {
        let grids = [
            sparse_grid([7, 5, 6], &[[0, 0, 0], [6, 4, 5], [3, 2, 3]]),
            sparse_grid([9, 4, 11], &[[8, 1, 0], [0, 3, 10], [4, 0, 5]]),
            sparse_grid([6, 6, 19], &[[2, 3, 9]]), // several tasks of planes
            sparse_grid([5, 4, 3], &[[4, 3, 2]]),
            scattered_grid([13, 11, 17]),
        ];
        for g in grids {
            let g = Arc::new(g);
            for split in [CellSplit::Five, CellSplit::Six] {
                for cover in [CellCover::All, CellCover::Support] {
                    let what = format!("{:?} {split:?} {cover:?}", g.dims);
                    let v = VoxelVolume::new("v", g.clone(), split, cover).unwrap();
                    let m = reference_split(&g, split, cover);
                    assert_eq!(v.num_tets(), m.num_tets(), "{what}");
                    assert_eq!(v.num_points(), m.num_points(), "{what}");
                    assert_eq!(v.bounds(), m.bounds(), "{what}");
                    assert_eq!(v.scalar_range(), m.scalar_range(), "{what}");
                    let mut used = vec![false; m.num_points()];
                    m.tets
                        .iter()
                        .flatten()
                        .for_each(|&p| used[p as usize] = true);
                    assert_eq!(
                        v.footprint().used_points,
                        used.iter().filter(|u| **u).count(),
                        "{what}"
                    );
                    for (p, &u) in used.iter().enumerate() {
                        assert_eq!(v.point_is_used(p), u, "{what} point {p}");
                    }
                    // Nothing above split the volume.
                    assert!(!v.tets_built(), "{what}");
                    let built = v.mesh().unwrap();
                    assert!(v.tets_built());
                    assert_eq!(built.tets, m.tets, "{what}");
                    assert_eq!(built.points, m.points, "{what}");
                    assert_eq!(built.scalars, m.scalars, "{what}");
                }
            }
        }
    }

    #[test]
    fn the_split_shares_the_grid_and_holds_the_values_once_more_only_while_it_exists() {
        let g = Arc::new(scattered_grid([10, 9, 8]));
        let v = VoxelVolume::new("v", g.clone(), CellSplit::Six, CellCover::Support).unwrap();
        // The volume holds the grid; nothing else (no mesh, no copy).
        assert_eq!(Arc::strong_count(&g), 2);
        let _ = v.num_tets();
        assert_eq!(Arc::strong_count(&g), 2);
        let mesh = v.mesh().unwrap();
        let shared = mesh.source_grid.as_ref().unwrap();
        assert!(Arc::ptr_eq(shared, &g));
        let mesh = v.into_mesh().unwrap();
        assert!(Arc::ptr_eq(mesh.source_grid.as_ref().unwrap(), &g));
        assert_eq!(Arc::strong_count(&g), 2);
    }

    #[test]
    fn what_the_split_would_refuse_is_refused_at_once() {
        let empty = Arc::new(sparse_grid([4, 4, 4], &[]));
        let err = VoxelVolume::new("e", empty.clone(), CellSplit::Five, CellCover::Support);
        assert!(matches!(err, Err(ErrorKind::EmptyMesh(_))));
        assert!(VoxelVolume::new("e", empty, CellSplit::Five, CellCover::All).is_ok());
        let mut nan = sparse_grid([3, 3, 3], &[[1, 1, 1]]);
        let mut values = nan.values.to_vec();
        values[4] = f32::NAN;
        nan.values = values.into();
        let err = VoxelVolume::new("n", Arc::new(nan), CellSplit::Six, CellCover::All);
        assert!(matches!(err, Err(ErrorKind::NonFinite { index: 4, .. })));
        let mut short = sparse_grid([3, 3, 3], &[[1, 1, 1]]);
        let mut values = short.values.to_vec();
        values.pop();
        short.values = values.into();
        let err = VoxelVolume::new("s", Arc::new(short), CellSplit::Six, CellCover::All);
        assert!(matches!(err, Err(ErrorKind::CountMismatch { .. })));
    }
}
