//! What every tetbench renderer shares: scene and cameras, the transfer function and optical
//! model, the headless GPU context with timing and memory accounting, the [`Renderer`] trait,
//! and the CPU sorts used for visibility ordering.

pub mod bind;
pub mod description;
pub mod frame;
pub mod gpu;
pub mod gpu_layout;
pub mod gpu_sort;
pub mod image;
pub mod image_error;
pub mod preintegration;
pub mod renderer;
pub mod scene;
pub mod settings;
pub mod silhouette;
pub mod sort;
pub mod table_texture;
pub mod texel_texture;
pub mod tile_counts;
pub mod transfer;
pub mod visibility;

pub use bind::ChunkedBuffer;
pub use description::{
    AlgorithmDescription, CounterEvidence, Hue, Origin, Param, Shading, Tolerance,
};
pub use frame::{FrameClock, FrameTimes};
pub use gpu::{AdapterDescription, DeviceRequest, FrameTimer, Gpu, Lifetime, MemoryLedger};
pub use image::Image;
pub use renderer::{DeclaredAccuracy, FrameStats, Prepared, Renderer};
pub use scene::{fixed_viewpoints, orbit_viewpoints, Camera, Projection, Ray, Viewpoint};
pub use settings::{Setting, SettingValue, Settings, SettingsError, SettingsFilter, ValueKind};
pub use tile_counts::TileCounts;
pub use transfer::{Optics, TransferFunction};
