//! The one trait all five algorithms implement, and what they return.
//!
//! Data flows one way: mesh + [`Optics`] → [`Renderer::prepare`] (upload, persistent bytes) →
//! [`Renderer::render`] per camera (timings) → [`Renderer::read_image`] (only when the harness
//! wants the picture, so readback never pollutes the timings).

use std::sync::Arc;

use datasets::{TetMesh, VoxelVolume};

use crate::gpu::Gpu;
use crate::image::Image;
use crate::scene::Camera;
use crate::settings::Settings;
use crate::tile_counts::TileCounts;
use crate::transfer::Optics;

/// What [`Renderer::prepare`] uploaded.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Prepared {
    /// GPU bytes that live as long as the mesh (the papers' bytes/tet counts these).
    pub persistent_bytes: u64,
    /// Tets the renderer draws (after discarding nothing, normally the mesh's count).
    pub tets: u64,
}

/// Timings and counters of one rendered frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameStats {
    /// CPU work inside the frame: sorting, classification on the host, uploads (ms).
    pub cpu_ms: f64,
    /// GPU time from timestamp queries, or `None` when the adapter has none.
    pub gpu_ms: Option<f64>,
    /// Wall clock from the start of the frame until the GPU finished (ms).
    pub total_ms: f64,
    /// GPU bytes allocated for this frame only (per-frame buffers, k-buffers, sort scratch).
    pub frame_bytes: u64,
    /// Named stage timings (ms), e.g. `sort`, `classify`, `draw`, `drain`.
    pub stages: Vec<(String, f64)>,
    /// Named counters, e.g. `fragments`, `kbuffer_overflows`.
    pub counters: Vec<(String, f64)>,
}

/// A volume renderer for tetrahedral meshes.
pub trait Renderer {
    /// Stable short name used in result rows and on the command line (`gator-pt`, `havs`…).
    fn algorithm(&self) -> &'static str;

    /// The paper's knobs with their values for this instance (the same [`Settings`] its
    /// description's `build` takes).
    fn settings(&self) -> Settings;

    /// Uploads the mesh and every view-independent table. The mesh is shared: a renderer that
    /// reads it every frame (a CPU visibility sort, work counters) keeps a clone of the `Arc`,
    /// never a copy of the mesh, so that a run holds each mesh once (at 20 M tets a copy is
    /// 385 MB).
    fn prepare(
        &mut self,
        gpu: &Gpu,
        mesh: &Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared>;

    /// Whether [`Renderer::prepare_voxels`] draws a voxel data set from its grid alone (the
    /// splatter): a run then never splits such a data set into tets for this renderer.
    fn draws_voxels(&self) -> bool {
        false
    }

    /// [`Renderer::prepare`] for a voxel data set, without its tets; the same [`Prepared`] and
    /// the same frames as `prepare` with the volume's split mesh. Only called when
    /// [`Renderer::draws_voxels`] says so.
    fn prepare_voxels(
        &mut self,
        _gpu: &Gpu,
        _volume: &VoxelVolume,
        _optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        anyhow::bail!("{} draws tets, not voxels", self.algorithm())
    }

    /// Renders one view into the renderer's own target and waits for the GPU.
    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats>;

    /// Reads back the last rendered image (premultiplied linear RGBA, row 0 at the top).
    fn read_image(&mut self, gpu: &Gpu) -> anyhow::Result<Image>;

    /// An optional second picture of the last frame that the harness saves beside the
    /// rendering as `….SUFFIX.png` (e.g. the ray caster's pass-count map, `passes`).
    fn extra_image(&mut self, _gpu: &Gpu) -> anyhow::Result<Option<(&'static str, Image)>> {
        Ok(None)
    }

    /// The last frame's counts per screen tile, for a renderer that spends its work tile by
    /// tile (the ray caster's passes); the harness writes them beside the rendering as
    /// `….NAME.json` and names that file in the row. Default none.
    fn tile_counts(&mut self, _gpu: &Gpu) -> anyhow::Result<Option<TileCounts>> {
        Ok(None)
    }

    /// The accuracy a renderer that approximates by design declares for itself (known after
    /// `prepare`); `None` for one that claims the conformance check's full accuracy. The check
    /// (`tetbench external check`) passes such a renderer's views at the declared PSNR, as long
    /// as each image is still nearer the reference than any convention mistake.
    fn declared_accuracy(&self) -> Option<DeclaredAccuracy> {
        None
    }
}

/// What a renderer declares about its own accuracy (`accuracy` in an external renderer's
/// hello, `docs/external-renderers.md`).
#[derive(Debug, Clone, PartialEq)]
pub struct DeclaredAccuracy {
    /// The PSNR (dB, RGBA against the exact reference) it expects to reach on the check's views.
    pub min_psnr_db: f64,
    /// Why it cannot do better, in plain words (e.g. "vertices snapped to the pixel grid").
    pub reason: String,
}
