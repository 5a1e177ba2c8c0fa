//! Regular voxel volumes (for splatting, and the papers' regular data sets) and the conversion
//! of structured (hexahedral) grids to conforming tets.

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
}

/// The five tets of hexahedral cell (i, j, k) of a structured grid, as indices into the grid's
/// points (x fastest). Cells alternate between the two mirror-image 5-tet splits by the parity
/// of i + j + k, so the diagonals of shared faces match and the mesh is conforming; this gives
/// the papers' counts (Blunt Fin 39·31·31·5 = 187,395 tets).
pub fn hex_cell_tets(dims: [usize; 3], i: usize, j: usize, k: usize) -> [[u32; 4]; 5] {
    let idx = |di: usize, dj: usize, dk: usize| (i + di + dims[0] * ((j + dj) + dims[1] * (k + dk))) as u32;
    // Corners: c[b] with b = dx + 2 dy + 4 dz.
    let c: [u32; 8] = std::array::from_fn(|b| idx(b & 1, (b >> 1) & 1, (b >> 2) & 1));
    if (i + j + k) % 2 == 0 {
        // Central tet on corners 1, 2, 4, 7 (its edges are the face diagonals).
        [[c[0], c[1], c[2], c[4]], [c[3], c[1], c[2], c[7]], [c[5], c[1], c[4], c[7]], [c[6], c[2], c[4], c[7]], [c[1], c[2], c[4], c[7]]]
    } else {
        // Mirror split: central tet on corners 0, 3, 5, 6.
        [[c[1], c[0], c[3], c[5]], [c[2], c[0], c[3], c[6]], [c[4], c[0], c[5], c[6]], [c[7], c[3], c[5], c[6]], [c[0], c[3], c[5], c[6]]]
    }
}

/// All tets of a structured grid with `dims` points (orientation is fixed later by
/// [`crate::TetMesh::new`]).
pub fn structured_tets(dims: [usize; 3]) -> Vec<[u32; 4]> {
    let mut tets = Vec::with_capacity(5 * dims.iter().map(|d| d.saturating_sub(1)).product::<usize>());
    for k in 0..dims[2].saturating_sub(1) {
        for j in 0..dims[1].saturating_sub(1) {
            for i in 0..dims[0].saturating_sub(1) {
                tets.extend_from_slice(&hex_cell_tets(dims, i, j, k));
            }
        }
    }
    tets
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TetMesh;

    #[test]
    fn structured_split_is_conforming() {
        let dims = [4, 3, 5];
        let mut points = Vec::new();
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    points.push([i as f32, j as f32 * 1.5, k as f32 * 0.7]);
                }
            }
        }
        let n = points.len();
        let mesh = TetMesh::new("grid", points, vec![0.0; n], "zero", structured_tets(dims)).unwrap();
        assert_eq!(mesh.num_tets(), 3 * 2 * 4 * 5);
        assert_eq!(mesh.repair.degenerate_dropped, 0);
        // Conforming: boundary faces are exactly 2 triangles per boundary quad.
        let quads = 2 * (3 * 2 + 2 * 4 + 3 * 4);
        assert_eq!(mesh.boundary_faces().len(), 2 * quads);
        assert!(mesh.is_convex());
    }
}
