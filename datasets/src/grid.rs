//! The voxel grid type on its own (no mesh dependency), so that `TetMesh::source_grid` can
//! name it without `mesh` and `volume` depending on each other; the conversions between grids
//! and meshes are in [`crate::volume`].

use std::borrow::Cow;
use std::ops::Range;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A grid's values: f32, or 16-bit levels times a step. Levels halve the largest array a
/// volume holds (StagBeetle's 342 M values: 684 MB instead of 1.37 GB); the splatting
/// stand-ins use them, as the papers' scanner volumes have 8-16 bits a voxel. Every read
/// goes through [`GridValues::get`] (level × step in f32), so a split mesh's scalars and the
/// splatter's voxels see the same values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum GridValues {
    F32(Vec<f32>),
    Levels { levels: Vec<u16>, step: f32 },
}

impl From<Vec<f32>> for GridValues {
    fn from(v: Vec<f32>) -> GridValues {
        GridValues::F32(v)
    }
}

impl GridValues {
    pub fn len(&self) -> usize {
        match self {
            GridValues::F32(v) => v.len(),
            GridValues::Levels { levels, .. } => levels.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value `i` (x fastest).
    #[inline]
    pub fn get(&self, i: usize) -> f32 {
        match self {
            GridValues::F32(v) => v[i],
            GridValues::Levels { levels, step } => levels[i] as f32 * step,
        }
    }

    /// Values `range`, borrowed when they are f32.
    pub fn slice(&self, range: Range<usize>) -> Cow<'_, [f32]> {
        match self {
            GridValues::F32(v) => Cow::Borrowed(&v[range]),
            GridValues::Levels { .. } => Cow::Owned(range.map(|i| self.get(i)).collect()),
        }
    }

    pub fn iter(&self) -> impl ExactSizeIterator<Item = f32> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }

    pub fn par_iter(&self) -> impl IndexedParallelIterator<Item = f32> + '_ {
        (0..self.len()).into_par_iter().map(|i| self.get(i))
    }

    /// All values as f32 (a split mesh's point scalars).
    pub fn to_vec(&self) -> Vec<f32> {
        self.par_iter().collect()
    }
}

/// A regular grid of values at the grid points (VTK "point data" layout: x fastest).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VoxelGrid {
    /// Number of grid points along x, y, z.
    pub dims: [usize; 3],
    pub spacing: [f64; 3],
    pub origin: [f64; 3],
    /// `dims[0] * dims[1] * dims[2]` values, x fastest.
    pub values: GridValues,
    pub scalar_name: String,
}

/// The `[i, j, k]` of flat index `g` in a grid of `dims` points or cells, x fastest.
pub fn grid_ijk(g: usize, dims: [usize; 3]) -> [usize; 3] {
    [
        g % dims[0],
        (g / dims[0]) % dims[1],
        g / (dims[0] * dims[1]),
    ]
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
            self.values
                .get(self.index(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1)))
                != 0.0
        })
    }

    /// Position of grid point (i, j, k).
    pub fn point(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        let ijk = [i, j, k];
        [0, 1, 2].map(|a| self.origin[a] + ijk[a] as f64 * self.spacing[a])
    }
}
