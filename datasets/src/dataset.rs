//! What every reader returns and takes: the loaded [`Dataset`], the [`LoadOptions`] and the
//! PLOT3D field choice. Its own module (not `load`) so that readers never depend on the
//! format dispatcher that depends on them.

use std::path::PathBuf;

use crate::grid::VoxelGrid;
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

/// A loaded data set: always a tet mesh; regular volumes keep their voxel grid too.
#[derive(Debug, Clone)]
pub struct Dataset {
    pub mesh: TetMesh,
    pub volume: Option<VoxelGrid>,
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
                self.mesh.source_grid = Some(std::sync::Arc::new(grid.clone()));
            }
        }
    }
}
