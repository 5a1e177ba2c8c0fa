//! Meshes for tetbench: one checked tetrahedral mesh model ([`TetMesh`]), readers for the
//! formats the papers' data sets come in, deterministic generators, and a registry of named
//! data sets resolved from a data directory.

pub mod cells;
pub mod data_dir;
pub mod dataset;
pub mod entry;
pub mod error;
pub mod gen_volume;
pub mod generate;
pub mod grid;
pub mod load;
pub mod mesh;
pub mod mhd;
pub mod plot3d;
pub mod read_util;
pub mod registry;
pub mod split;
pub mod standins;
pub mod toff;
pub mod volume;
pub mod voxel_volume;
pub mod vtk_legacy;
pub mod vtk_xml;
pub mod write_vtu;

pub use dataset::{Dataset, LazyDataset, LoadOptions, Plot3dField};
pub use error::{ErrorKind, LoadError, Location};
pub use grid::{GridValues, VoxelGrid};
pub use mesh::{
    Aabb, BoundaryFace, QualityStats, RepairReport, TetMesh, UniqueFaces, NO_NEIGHBOUR, TET_FACES,
};
pub use volume::CellSplit;
pub use voxel_volume::{CellCover, VoxelVolume};
