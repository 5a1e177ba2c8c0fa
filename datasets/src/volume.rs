//! Regular voxel volumes (for splatting, and the papers' regular data sets) and the conversion
//! of structured (hexahedral) grids to conforming tets.

use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;

use crate::error::ErrorKind;
use crate::grid::grid_ijk;
use crate::mesh::{cross, dot, sub, TetMesh};

pub use crate::grid::VoxelGrid;

impl VoxelGrid {
    /// The voxel count, once the values match it and every voxel fits a `u32` index (what the
    /// tet split and the voxel-only volume both need).
    pub fn checked_num_voxels(&self) -> Result<usize, ErrorKind> {
        let n = self.num_voxels();
        if self.values.len() != n {
            return Err(ErrorKind::CountMismatch {
                what: "voxel values".into(),
                expected: n as u64,
                found: self.values.len() as u64,
            });
        }
        if n > u32::MAX as usize {
            return Err(ErrorKind::IndexOverflow {
                what: "voxels".into(),
                count: n as u64,
            });
        }
        Ok(n)
    }

    /// The volume as a tet mesh: grid points become mesh points (same order, same values) and
    /// each cell 5 tets ([`structured_tets`]); a 68³ volume gives 67³·5 = 1,503,815 tets.
    pub fn to_tets(&self) -> Result<TetMesh, ErrorKind> {
        let n = self.checked_num_voxels()?;
        let [nx, ny, _] = self.dims;
        let points: Vec<[f32; 3]> = (0..n)
            .into_par_iter()
            .map(|g| {
                self.point(g % nx, (g / nx) % ny, g / (nx * ny))
                    .map(|c| c as f32)
            })
            .collect();
        TetMesh::new(
            "volume",
            points,
            self.values.to_vec(),
            self.scalar_name.clone(),
            structured_tets(self.dims),
        )
    }

    /// Samples `mesh` at the points of a regular grid of `dims` points spanning its bounding
    /// box (for splatting renderers, which need a voxel grid). Each grid point takes the
    /// barycentric (linear) interpolation of the tet containing it, so a field linear over
    /// the mesh is reproduced exactly; points outside the mesh (holes, non-convex regions)
    /// take the mesh's minimum scalar, i.e. "empty" under any transfer function ramp.
    ///
    /// Point location: every tet visits the grid points inside its bounding box and claims
    /// those inside it with an atomic minimum of its index — the voxel grid itself serves as
    /// the uniform bin structure, the work is O(tets + covered grid points) and parallel, and
    /// the smallest containing tet wins, so the result is deterministic.
    pub fn resample(mesh: &TetMesh, dims: [usize; 3]) -> VoxelGrid {
        VoxelGrid::resample_with_inside(mesh, dims).0
    }

    /// [`VoxelGrid::resample`], also returning which grid points lie inside the mesh (the
    /// others hold the minimum only as a filler; a splatter must not draw them).
    pub fn resample_with_inside(mesh: &TetMesh, dims: [usize; 3]) -> (VoxelGrid, Vec<bool>) {
        let dims = dims.map(|d| d.max(1));
        let b = mesh.bounds();
        let mut origin = b.min;
        let mut spacing = [1.0; 3];
        for a in 0..3 {
            let e = b.max[a] - b.min[a];
            if dims[a] > 1 {
                spacing[a] = e / (dims[a] - 1) as f64;
            } else {
                origin[a] = 0.5 * (b.min[a] + b.max[a]);
                spacing[a] = if e > 0.0 { e } else { 1.0 };
            }
        }
        let n: usize = dims.iter().product();
        let claim: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(u32::MAX)).collect();
        let inv = |a: usize, x: f64| {
            if spacing[a] > 0.0 {
                (x - origin[a]) / spacing[a]
            } else {
                0.0
            }
        };
        (0..mesh.num_tets()).into_par_iter().for_each(|t| {
            let p = mesh.tet_points(t);
            let bary = Barycentric::new(p);
            let mut lo = [0usize; 3];
            let mut hi = [0usize; 3];
            for a in 0..3 {
                let mn = p.iter().map(|q| q[a]).fold(f64::INFINITY, f64::min);
                let mx = p.iter().map(|q| q[a]).fold(f64::NEG_INFINITY, f64::max);
                let l = (inv(a, mn) - 1e-6).ceil().max(0.0);
                let h = (inv(a, mx) + 1e-6).floor().min((dims[a] - 1) as f64);
                if h < l {
                    return;
                }
                lo[a] = l as usize;
                hi[a] = h as usize;
            }
            for k in lo[2]..=hi[2] {
                for j in lo[1]..=hi[1] {
                    for i in lo[0]..=hi[0] {
                        let q = [0, 1, 2].map(|a| origin[a] + [i, j, k][a] as f64 * spacing[a]);
                        if bary.weights(q).iter().all(|&w| w >= -BARY_TOLERANCE) {
                            claim[i + dims[0] * (j + dims[1] * k)]
                                .fetch_min(t as u32, Ordering::Relaxed);
                        }
                    }
                }
            }
        });
        let outside = mesh.scalar_range().0;
        let values: Vec<f32> = (0..n)
            .into_par_iter()
            .map(|g| {
                let t = claim[g].load(Ordering::Relaxed);
                if t == u32::MAX {
                    return outside;
                }
                let q = grid_ijk(g, dims);
                let q = [0, 1, 2].map(|a| origin[a] + q[a] as f64 * spacing[a]);
                let w = Barycentric::new(mesh.tet_points(t as usize)).weights(q);
                let s = mesh.tets[t as usize].map(|v| mesh.scalars[v as usize] as f64);
                (0..4).map(|c| w[c] * s[c]).sum::<f64>() as f32
            })
            .collect();
        let inside = claim
            .par_iter()
            .map(|c| c.load(Ordering::Relaxed) != u32::MAX)
            .collect();
        (
            VoxelGrid {
                dims,
                spacing,
                origin,
                values: values.into(),
                scalar_name: mesh.scalar_name.clone(),
            },
            inside,
        )
    }
}

/// A point is in a tet when all its barycentric weights are ≥ −this (relative; absorbs the
/// rounding of points on shared faces and on the mesh boundary).
const BARY_TOLERANCE: f64 = 1e-7;

/// Barycentric coordinates in one tet: λ₁..₃ = rows of the inverse edge matrix · (q − p₀).
struct Barycentric {
    p0: [f64; 3],
    rows: [[f64; 3]; 3],
}

impl Barycentric {
    fn new(p: [[f64; 3]; 4]) -> Barycentric {
        let e = [sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0])];
        let det = dot(e[0], cross(e[1], e[2]));
        let inv = if det != 0.0 { 1.0 / det } else { 0.0 };
        let rows =
            [cross(e[1], e[2]), cross(e[2], e[0]), cross(e[0], e[1])].map(|r| r.map(|x| x * inv));
        Barycentric { p0: p[0], rows }
    }
    fn weights(&self, q: [f64; 3]) -> [f64; 4] {
        let d = sub(q, self.p0);
        let l = self.rows.map(|r| dot(r, d));
        [1.0 - l[0] - l[1] - l[2], l[0], l[1], l[2]]
    }
}

/// The five tets of hexahedral cell (i, j, k) of a structured grid, as indices into the grid's
/// points (x fastest). Cells alternate between the two mirror-image 5-tet splits by the parity
/// of i + j + k, so the diagonals of shared faces match and the mesh is conforming; this gives
/// the papers' counts (Blunt Fin 39·31·31·5 = 187,395 tets).
pub fn hex_cell_tets(dims: [usize; 3], i: usize, j: usize, k: usize) -> [[u32; 4]; 5] {
    let idx = |di: usize, dj: usize, dk: usize| {
        (i + di + dims[0] * ((j + dj) + dims[1] * (k + dk))) as u32
    };
    // Corners: c[b] with b = dx + 2 dy + 4 dz.
    let c: [u32; 8] = std::array::from_fn(|b| idx(b & 1, (b >> 1) & 1, (b >> 2) & 1));
    if (i + j + k).is_multiple_of(2) {
        // Central tet on corners 1, 2, 4, 7 (its edges are the face diagonals).
        [
            [c[0], c[1], c[2], c[4]],
            [c[3], c[1], c[2], c[7]],
            [c[5], c[1], c[4], c[7]],
            [c[6], c[2], c[4], c[7]],
            [c[1], c[2], c[4], c[7]],
        ]
    } else {
        // Mirror split: central tet on corners 0, 3, 5, 6.
        [
            [c[1], c[0], c[3], c[5]],
            [c[2], c[0], c[3], c[6]],
            [c[4], c[0], c[5], c[6]],
            [c[7], c[3], c[5], c[6]],
            [c[0], c[3], c[5], c[6]],
        ]
    }
}

/// All tets of a structured grid with `dims` points (orientation is fixed later by
/// [`crate::TetMesh::new`]).
pub fn structured_tets(dims: [usize; 3]) -> Vec<[u32; 4]> {
    let mut tets =
        Vec::with_capacity(5 * dims.iter().map(|d| d.saturating_sub(1)).product::<usize>());
    for k in 0..dims[2].saturating_sub(1) {
        for j in 0..dims[1].saturating_sub(1) {
            for i in 0..dims[0].saturating_sub(1) {
                tets.extend_from_slice(&hex_cell_tets(dims, i, j, k));
            }
        }
    }
    tets
}

/// The 6 tets of cube (i, j, k) of a grid with `dims` points: Kuhn's split along the diagonal
/// from the cube's lowest to its highest corner. Every face is cut along the diagonal through
/// its lowest corner, the same in both cubes that share it, so the mesh conforms. Tets are
/// emitted positively oriented (the permutation's parity decides the vertex order).
pub fn kuhn_cell_tets(dims: [usize; 3], i: usize, j: usize, k: usize) -> [[u32; 4]; 6] {
    let idx = |d: [usize; 3]| (i + d[0] + dims[0] * ((j + d[1]) + dims[1] * (k + d[2]))) as u32;
    const PERMS: [([usize; 3], bool); 6] = [
        ([0, 1, 2], true),
        ([1, 2, 0], true),
        ([2, 0, 1], true),
        ([0, 2, 1], false),
        ([2, 1, 0], false),
        ([1, 0, 2], false),
    ];
    PERMS.map(|(p, even)| {
        let mut d = [0usize; 3];
        let c0 = idx(d);
        d[p[0]] = 1;
        let c1 = idx(d);
        d[p[1]] = 1;
        let c2 = idx(d);
        let c3 = idx([1, 1, 1]);
        if even {
            [c0, c1, c2, c3]
        } else {
            [c0, c2, c1, c3]
        }
    })
}

/// How a grid's cells become tets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellSplit {
    /// Five per cell, the two mirror splits alternating ([`hex_cell_tets`]).
    Five,
    /// Six per cell around its main diagonal ([`kuhn_cell_tets`]).
    Six,
}

impl CellSplit {
    pub fn tets_per_cell(self) -> usize {
        match self {
            CellSplit::Five => 5,
            CellSplit::Six => 6,
        }
    }
}

/// The tet mesh of the cells (i, j, k) that `keep` accepts, split by `split`, in cell order
/// (x fastest): every grid point is a mesh point (same order and value, unused ones included),
/// which is what lets [`TetMesh::source_grid`] stand for them.
pub fn split_cells(
    grid: &VoxelGrid,
    split: CellSplit,
    keep: impl Fn(usize, usize, usize) -> bool + Sync,
) -> Result<TetMesh, ErrorKind> {
    let d = grid.dims;
    let (nx, ny) = (d[0], d[1]);
    let points: Vec<[f32; 3]> = (0..grid.num_voxels())
        .into_par_iter()
        .map(|g| {
            grid.point(g % nx, (g / nx) % ny, g / (nx * ny))
                .map(|c| c as f32)
        })
        .collect();
    let c = d.map(|x| x.saturating_sub(1));
    let tets: Vec<[u32; 4]> = (0..c[2])
        .into_par_iter()
        .flat_map_iter(|k| {
            let mut out = Vec::new();
            for j in 0..c[1] {
                for i in 0..c[0] {
                    if keep(i, j, k) {
                        match split {
                            CellSplit::Five => out.extend_from_slice(&hex_cell_tets(d, i, j, k)),
                            CellSplit::Six => out.extend_from_slice(&kuhn_cell_tets(d, i, j, k)),
                        }
                    }
                }
            }
            out
        })
        .collect();
    TetMesh::new(
        "volume",
        points,
        grid.values.to_vec(),
        grid.scalar_name.clone(),
        tets,
    )
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
        let mesh =
            TetMesh::new("grid", points, vec![0.0; n], "zero", structured_tets(dims)).unwrap();
        assert_eq!(mesh.num_tets(), 3 * 2 * 4 * 5);
        assert_eq!(mesh.repair.degenerate_dropped, 0);
        // Conforming: boundary faces are exactly 2 triangles per boundary quad.
        let quads = 2 * (3 * 2 + 2 * 4 + 3 * 4);
        assert_eq!(mesh.boundary_faces().len(), 2 * quads);
        assert!(mesh.is_convex());
    }
}
