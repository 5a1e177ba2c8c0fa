//! What every reader returns and takes: the loaded [`Dataset`], the [`LoadOptions`] and the
//! PLOT3D field choice. Its own module (not `load`) so that readers never depend on the
//! format dispatcher that depends on them.

use std::path::PathBuf;
use std::sync::Arc;

use crate::error::LoadError;
use crate::grid::VoxelGrid;
use crate::mesh::Aabb;
use crate::voxel_volume::VoxelVolume;
use crate::TetMesh;

/// Which PLOT3D Q quantity becomes the point scalar.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Plot3dField {
    #[default]
    Density,
    MomentumMagnitude,
    Energy,
    VelocityMagnitude,
    /// p = (γ − 1)(E − ½ρ|v|²), γ = 1.4.
    Pressure,
}

impl Plot3dField {
    pub const ALL: [Plot3dField; 5] = [
        Plot3dField::Density,
        Plot3dField::MomentumMagnitude,
        Plot3dField::Energy,
        Plot3dField::VelocityMagnitude,
        Plot3dField::Pressure,
    ];

    /// The scalar name the mesh gets (and that `LoadOptions::scalar` may name).
    pub fn name(self) -> &'static str {
        match self {
            Plot3dField::Density => "density",
            Plot3dField::MomentumMagnitude => "momentum_magnitude",
            Plot3dField::Energy => "energy",
            Plot3dField::VelocityMagnitude => "velocity_magnitude",
            Plot3dField::Pressure => "pressure",
        }
    }

    pub fn from_name(name: &str) -> Option<Plot3dField> {
        Plot3dField::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(name))
    }
}

/// Options for [`load`].
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Point array to use as the scalar (default: the first scalar array of the file).
    pub scalar: Option<String>,
    /// PLOT3D: the Q file (default: the XYZ file's name with `xyz` replaced by `q`).
    pub q_file: Option<PathBuf>,
    /// PLOT3D: which Q quantity (default density).
    pub plot3d_field: Option<Plot3dField>,
}

/// A loaded data set: always a tet mesh; regular volumes keep their voxel grid too (shared
/// with the mesh's [`TetMesh::source_grid`] once [`Dataset::attach_grid`] ran).
#[derive(Debug, Clone)]
pub struct Dataset {
    pub mesh: TetMesh,
    pub volume: Option<Arc<VoxelGrid>>,
    /// Where it came from (file path or generator spec).
    pub source: String,
}

impl Dataset {
    /// Keeps a regular volume's grid with its mesh ([`TetMesh::source_grid`]) when the mesh's
    /// points are the grid's points in grid order (every volume split this crate makes), so
    /// that voxel renderers splat the exact voxels instead of resampling the tets.
    pub fn attach_grid(&mut self) {
        if let Some(grid) = &self.volume {
            if self.mesh.source_grid.is_none() && grid.num_voxels() == self.mesh.num_points() {
                self.mesh.source_grid = Some(Arc::clone(grid));
            }
        }
    }
}

/// A data set as a run holds it: a tet mesh, or a voxel volume whose tets are split only when
/// something asks for them ([`LazyDataset::mesh`]); a voxel renderer takes the volume itself
/// ([`LazyDataset::voxels`]).
#[derive(Debug)]
pub struct LazyDataset {
    /// Where it came from (file path or generator spec).
    pub source: String,
    content: Content,
}

#[derive(Debug)]
enum Content {
    /// The mesh is shared (`Arc`): a renderer that reads it every frame keeps a handle to this
    /// one instead of a copy (at 20 M tets a copy is 385 MB).
    Mesh {
        mesh: Arc<TetMesh>,
        volume: Option<Arc<VoxelGrid>>,
    },
    Voxels(Box<VoxelVolume>),
}

impl From<Dataset> for LazyDataset {
    fn from(ds: Dataset) -> LazyDataset {
        LazyDataset {
            source: ds.source,
            content: Content::Mesh {
                mesh: Arc::new(ds.mesh),
                volume: ds.volume,
            },
        }
    }
}

impl LazyDataset {
    pub fn from_voxels(volume: VoxelVolume, source: impl Into<String>) -> LazyDataset {
        LazyDataset {
            source: source.into(),
            content: Content::Voxels(Box::new(volume)),
        }
    }

    /// The voxel volume, for a data set that is one (none for a mesh, even one split from a
    /// grid: its grid is the mesh's [`TetMesh::source_grid`]).
    pub fn voxels(&self) -> Option<&VoxelVolume> {
        match &self.content {
            Content::Voxels(v) => Some(v),
            Content::Mesh { .. } => None,
        }
    }

    /// The tet mesh, split from the voxels on first use.
    pub fn mesh(&self) -> Result<&Arc<TetMesh>, LoadError> {
        match &self.content {
            Content::Mesh { mesh, .. } => Ok(mesh),
            Content::Voxels(v) => v.mesh().map_err(|k| LoadError::new(&self.source, k)),
        }
    }

    /// Whether the tet mesh exists (always for a mesh; for voxels, once [`Self::mesh`] ran).
    pub fn tets_built(&self) -> bool {
        match &self.content {
            Content::Mesh { .. } => true,
            Content::Voxels(v) => v.tets_built(),
        }
    }

    pub fn num_points(&self) -> usize {
        match &self.content {
            Content::Mesh { mesh, .. } => mesh.num_points(),
            Content::Voxels(v) => v.num_points(),
        }
    }

    /// Tets of the mesh, counted without splitting the voxels.
    pub fn num_tets(&self) -> usize {
        match &self.content {
            Content::Mesh { mesh, .. } => mesh.num_tets(),
            Content::Voxels(v) => v.num_tets(),
        }
    }

    /// The mesh's [`TetMesh::bounds`], without splitting the voxels.
    pub fn bounds(&self) -> Aabb {
        match &self.content {
            Content::Mesh { mesh, .. } => mesh.bounds(),
            Content::Voxels(v) => v.bounds(),
        }
    }

    /// The mesh's [`TetMesh::scalar_range`], without splitting the voxels.
    pub fn scalar_range(&self) -> (f32, f32) {
        match &self.content {
            Content::Mesh { mesh, .. } => mesh.scalar_range(),
            Content::Voxels(v) => v.scalar_range(),
        }
    }

    /// The data set with its mesh (split now if it was voxels), sharing the grid.
    pub fn into_dataset(self) -> Result<Dataset, LoadError> {
        match self.content {
            Content::Mesh { mesh, volume } => Ok(Dataset {
                mesh: Arc::unwrap_or_clone(mesh),
                volume,
                source: self.source,
            }),
            Content::Voxels(v) => {
                let volume = Some(Arc::clone(v.grid()));
                let mesh = v.into_mesh().map_err(|k| LoadError::new(&self.source, k))?;
                Ok(Dataset {
                    mesh,
                    volume,
                    source: self.source,
                })
            }
        }
    }
}
