//! Tiled ray casting with depth peeling: Bernardon, Pagot, Comba and Silva (2005), "GPU-based
//! Tiled Ray Casting using Depth Peeling" — the one image-order algorithm of tetbench.
//!
//! * Mesh layout ([`layout`], §3.1 Table 1): 144 bytes per tet in a 2D array texture, as many
//!   layers as it needs (up to [`layout::MESH_LAYERS`]) so rays walk across layers (the
//!   paper's 2D-texture coordinates (t_u, t_v) become (layer, index)).
//! * Phases 1–2 (`peel.wgsl`, §2.4, §3.2): the front-facing boundary faces are rasterised with
//!   the Z-buffer to find each pixel's entry tet and λ; each further layer peels the next entry
//!   behind the previous one (bias on λ), until a layer is empty (an occlusion query per layer)
//!   or [`RaycastSettings::max_layers`]. Where the device has a stencil with its 32-bit depth,
//!   each pass also counts every pixel's candidates, and a layer after which no pixel had two
//!   ends the peel without drawing the empty layer (`resources::Pipelines::more`).
//! * Phase 3a (`cast.wgsl`): each active ray crosses one tet per step and composites the segment
//!   front to back with the 2D or 3D pre-integrated table; a ray that leaves the mesh continues
//!   from its next layer; early ray termination at opacity [`ET_OPACITY`] (the paper's code).
//! * Phase 3b / tiles (§2.3): the screen is cut into N×N tiles; each runs its own number of
//!   passes. The paper's occlusion query every k passes is here an atomic count of the tile's
//!   active rays in every k-th pass ([`RaycastSettings::k`]), read back by the CPU. As in the paper, a tile
//!   spends its passes layer by layer: once its count is zero its rays start again from their
//!   next peeling layer (`load_layer`), and a tile where none does gets no more passes; a tile
//!   no ray enters gets none at all. Its passes are the sum over its layers of the longest
//!   stretch in each, rounded up to whole rounds ([`passmap::passes_per_tile`] is the twin). Its z-update is drawn
//!   where the device forces early depth tests (`tile_pass.wgsl`): each pass a rectangle per
//!   active tile, the step in the fragment shader, rays that have ended given depth 0 at the
//!   start of each round so that the early depth test rejects them (§3.2); elsewhere the passes
//!   are compute dispatches over the tiles.
//! * [`Mode::Loop`]: the modern variant, one dispatch per tile looping each ray to its end.
//!
//! The CPU twin of a ray step is [`step`]; the pass-count map (the paper's Fig. 5) is
//! [`passmap`].

mod description;
pub mod layout;
pub mod passmap;
mod render;
pub mod resources;
pub mod settings;
pub mod step;
pub mod twin;

pub use description::DESCRIPTION;
pub use render::{PassData, Raycast};
pub use settings::{Mode, RaycastSettings, TableKind};

/// Opacity at which a ray stops when early termination is on (the paper's shader uses 0.95).
pub const ET_OPACITY: f32 = 0.95;
/// The default k ([`RaycastSettings::k`]): the termination test (an atomic count of active rays
/// per tile) runs in every k-th pass; the paper amortises its occlusion query the same way
/// without giving k.
pub const COUNT_EVERY: u32 = 8;
/// Entries per scalar axis of both tables, and per length axis of the 3D one (HAVS' 128³).
pub const TABLE_SCALAR: usize = 128;
pub const TABLE_LENGTH: usize = 128;
/// Bias on λ between peeling layers, relative to the bounding-box diagonal (the paper adds an
/// unstated bias; its code uses 0.01 scene units). Well above f32 round-off of λ (~4e-7 of the
/// diagonal at the fitted camera distance).
pub const PEEL_BIAS: f64 = 1e-5;
