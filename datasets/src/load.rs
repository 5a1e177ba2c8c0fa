//! Loading any supported file into a [`Dataset`]: the format is chosen by extension or by
//! sniffing the content.

use std::path::PathBuf;

use crate::volume::VoxelGrid;
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
