//! The voxel volumes (fuel, the resampled brain, the splatting stand-ins) and their tet meshes.

use std::sync::Arc;

use rayon::prelude::*;

use crate::error::ErrorKind;
use crate::generate::{Field, FieldEval};
use crate::grid::{grid_ijk, GridValues};
use crate::volume::{split_cells, CellSplit, VoxelGrid};
use crate::voxel_volume::{CellCover, VoxelVolume};
use crate::TetMesh;

/// A volume's 6-tet split covers every cube up to this many tets; beyond, only the cubes of
/// the support (see [`volume_tet_mesh`]).
pub const MAX_VOLUME_MESH_TETS: usize = 60_000_000;

/// The most tets a support split may have: 16 B each, so 2.4 GB of tets, and about twice that
/// while [`TetMesh::new`] checks their orientation. The largest stand-in (StagBeetle, 13.8 M
/// effective voxels) stays below it.
pub const MAX_SUPPORT_MESH_TETS: usize = 150_000_000;

/// A voxel grid as a tet mesh, 6 tets per cube
/// ([`kuhn_cell_tets`](crate::volume::kuhn_cell_tets)), every cube.
pub fn six_tet_mesh(grid: &VoxelGrid) -> Result<TetMesh, ErrorKind> {
    kuhn_mesh(grid, |_, _, _| true)
}

/// A generated volume's tet mesh: every cube ([`six_tet_mesh`]) while that stays within
/// [`MAX_VOLUME_MESH_TETS`]; beyond it only the support, the cubes with a non-zero corner. The
/// cubes left out hold 0 at all eight corners, so under a transfer function with κ(0) = 0 (the
/// one that defines a stand-in's effective voxels) both meshes give the same image with the
/// same camera and optics (a run fits those to the mesh's bounds, so it frames the support;
/// `tests/roundtrip_generated.rs` checks the images agree). Under one
/// with κ(0) > 0 the data set *is* the support: the splatter splats only grid points that a tet
/// uses, so every algorithm still draws the same data. Points stay the whole grid, in grid
/// order, which is what lets [`TetMesh::source_grid`] stand for them.
pub fn volume_tet_mesh(grid: &VoxelGrid) -> Result<TetMesh, ErrorKind> {
    volume_tet_mesh_within(grid, MAX_VOLUME_MESH_TETS)
}

/// [`volume_tet_mesh`] with the full split's limit as a parameter (0: always the support).
pub fn volume_tet_mesh_within(grid: &VoxelGrid, full_limit: usize) -> Result<TetMesh, ErrorKind> {
    volume_voxels_within("volume", Arc::new(grid.clone()), full_limit)?.into_mesh()
}

/// The voxel data set of a generated volume, its tets ([`volume_tet_mesh`]) not split yet.
pub fn volume_voxels(name: &str, grid: Arc<VoxelGrid>) -> Result<VoxelVolume, ErrorKind> {
    volume_voxels_within(name, grid, MAX_VOLUME_MESH_TETS)
}

/// [`volume_voxels`] with the full split's limit as a parameter (0: always the support).
pub fn volume_voxels_within(
    name: &str,
    grid: Arc<VoxelGrid>,
    full_limit: usize,
) -> Result<VoxelVolume, ErrorKind> {
    let d = grid.dims;
    let cubes: usize = d.iter().map(|x| x.saturating_sub(1)).product();
    if cubes * 6 <= full_limit {
        return VoxelVolume::new(name, grid, CellSplit::Six, CellCover::All);
    }
    let volume = VoxelVolume::new(name, grid, CellSplit::Six, CellCover::Support)?;
    if volume.num_tets() > MAX_SUPPORT_MESH_TETS {
        return Err(ErrorKind::Invalid(format!(
            "the {}×{}×{} volume's support split would have {} tets (more than \
             {MAX_SUPPORT_MESH_TETS})",
            d[0],
            d[1],
            d[2],
            volume.num_tets()
        )));
    }
    Ok(volume)
}

/// The 6-tet split of the cubes `keep` accepts, with every grid point a mesh point.
fn kuhn_mesh(
    grid: &VoxelGrid,
    keep: impl Fn(usize, usize, usize) -> bool + Sync,
) -> Result<TetMesh, ErrorKind> {
    split_cells(grid, CellSplit::Six, keep)
}

/// The fuel stand-in: a 64³ grid on [-1,1]³ holding a synthetic jet — fuel entering at the
/// bottom along the z axis, spreading and thinning as it rises, with a ripple along the jet.
pub fn fuel_volume() -> VoxelGrid {
    let n = 64;
    let h = 2.0 / (n - 1) as f64;
    let values: Vec<f32> = (0..n * n * n)
        .into_par_iter()
        .map(|g| {
            let (x, y, z) = (
                -1.0 + (g % n) as f64 * h,
                -1.0 + ((g / n) % n) as f64 * h,
                -1.0 + (g / (n * n)) as f64 * h,
            );
            let t = (z + 1.0) * 0.5;
            let sigma = 0.06 + 0.3 * t;
            let r2 = x * x + y * y;
            let core = (-(r2) / (2.0 * sigma * sigma)).exp() * (1.0 - 0.6 * t);
            let ripple = 1.0 + 0.15 * (10.0 * t + 4.0 * x).sin();
            (core * ripple).max(0.0) as f32
        })
        .collect();
    VoxelGrid {
        dims: [n; 3],
        spacing: [h; 3],
        origin: [-1.0; 3],
        values: values.into(),
        scalar_name: "fuel_density".into(),
    }
}

/// Trilinear resampling of `grid` onto `dims` points spanning the same box.
pub fn resample_trilinear(grid: &VoxelGrid, dims: [usize; 3]) -> VoxelGrid {
    let ext: [f64; 3] = std::array::from_fn(|a| (grid.dims[a] - 1) as f64 * grid.spacing[a]);
    let spacing: [f64; 3] = std::array::from_fn(|a| {
        if dims[a] > 1 {
            ext[a] / (dims[a] - 1) as f64
        } else {
            grid.spacing[a]
        }
    });
    let sample = |q: [f64; 3]| -> f32 {
        let mut i0 = [0usize; 3];
        let mut f = [0.0f64; 3];
        for a in 0..3 {
            let u =
                ((q[a] - grid.origin[a]) / grid.spacing[a]).clamp(0.0, (grid.dims[a] - 1) as f64);
            let base = (u.floor() as usize).min(grid.dims[a].saturating_sub(2));
            i0[a] = base;
            f[a] = u - base as f64;
        }
        let mut acc = 0.0f64;
        for c in 0..8 {
            let d = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
            let w: f64 = (0..3)
                .map(|a| if d[a] == 1 { f[a] } else { 1.0 - f[a] })
                .product();
            let ii: [usize; 3] = std::array::from_fn(|a| (i0[a] + d[a]).min(grid.dims[a] - 1));
            acc += w * grid.values.get(grid.index(ii[0], ii[1], ii[2])) as f64;
        }
        acc as f32
    };
    let n = dims.iter().product::<usize>();
    let values: Vec<f32> = (0..n)
        .into_par_iter()
        .map(|g| {
            let ijk = grid_ijk(g, dims);
            sample(std::array::from_fn(|a| {
                grid.origin[a] + ijk[a] as f64 * spacing[a]
            }))
        })
        .collect();
    VoxelGrid {
        dims,
        spacing,
        origin: grid.origin,
        values: values.into(),
        scalar_name: grid.scalar_name.clone(),
    }
}

/// A splatting stand-in volume: `dims` grid points of a seeded blob field of which exactly
/// `effective` voxels are non-zero (the largest values; ties broken by voxel index), the rest
/// 0 — the paper's "effective voxels" under any transfer function that maps 0 to transparent.
/// The values are 16-bit levels ([`GridValues::Levels`]), as the papers' scanner volumes
/// are: StagBeetle's 342 M voxels take 684 MB, and no f32 copy is made on the way.
pub fn splat_volume(dims: [usize; 3], effective: usize, seed: u64) -> VoxelGrid {
    let n: usize = dims.iter().product();
    let field = FieldEval::new(Field::Blobs, seed);
    let h: [f64; 3] = std::array::from_fn(|a| 2.0 / (dims[a].max(2) - 1) as f64);
    // Levels of a step the field cannot exceed, at least 1: 0 is kept for "empty".
    let step = field.upper_bound().unwrap_or(1.0).max(f64::MIN_POSITIVE) / u16::MAX as f64;
    // Sampled separably: eight exp per point were most of StagBeetle's generation.
    let lattice = field
        .on_lattice(dims, [-1.0; 3], h)
        .expect("the blob field is separable");
    let mut levels: Vec<u16> = (0..n)
        .into_par_iter()
        .map(|g| {
            let ijk = grid_ijk(g, dims);
            (lattice.at(ijk) / step).round().clamp(1.0, u16::MAX as f64) as u16
        })
        .collect();
    let effective = effective.min(n);
    // The smallest level τ with at most `effective` voxels above it, from the levels'
    // histogram; of the voxels at τ, the first in index order fill the count.
    let histogram = levels
        .par_iter()
        .fold(
            || vec![0usize; 1 << 16],
            |mut h, &l| {
                h[l as usize] += 1;
                h
            },
        )
        .reduce(
            || vec![0usize; 1 << 16],
            |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            },
        );
    let (mut tau, mut above) = (u16::MAX as usize, 0usize);
    while tau > 0 && above + histogram[tau] <= effective {
        above += histogram[tau];
        tau -= 1;
    }
    let mut ties_left = effective - above;
    for l in levels.iter_mut() {
        if *l as usize > tau {
            continue;
        }
        if *l as usize == tau && ties_left > 0 {
            ties_left -= 1;
        } else {
            *l = 0;
        }
    }
    VoxelGrid {
        dims,
        spacing: h,
        origin: [-1.0; 3],
        values: GridValues::Levels {
            levels,
            step: step as f32,
        },
        scalar_name: field.name().into(),
    }
}
