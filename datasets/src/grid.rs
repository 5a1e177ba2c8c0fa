//! The voxel grid type on its own (no mesh dependency), so that `TetMesh::source_grid` can
//! name it without `mesh` and `volume` depending on each other; the conversions between grids
//! and meshes are in [`crate::volume`].

use serde::{Deserialize, Serialize};

/// A regular grid of values at the grid points (VTK "point data" layout: x fastest).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VoxelGrid {
    /// Number of grid points along x, y, z.
    pub dims: [usize; 3],
    pub spacing: [f64; 3],
    pub origin: [f64; 3],
    /// `dims[0] * dims[1] * dims[2]` values, x fastest.
    pub values: Vec<f32>,
    pub scalar_name: String,
}

impl VoxelGrid {
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }
    pub fn num_voxels(&self) -> usize {
        self.dims.iter().product()
    }

    /// Whether any of the 8 corners of cube (i, j, k) (grid points (i..=i+1, j..=j+1,
    /// k..=k+1)) holds a non-zero value: the cubes a volume's support split keeps.
    pub fn cube_has_nonzero_corner(&self, i: usize, j: usize, k: usize) -> bool {
        (0..8).any(|b| {
            self.values[self.index(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1))] != 0.0
        })
    }

    /// Position of grid point (i, j, k).
    pub fn point(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        let ijk = [i, j, k];
        [0, 1, 2].map(|a| self.origin[a] + ijk[a] as f64 * self.spacing[a])
    }
}
