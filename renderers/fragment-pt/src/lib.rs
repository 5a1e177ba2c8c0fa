//! Fragment PT: Marroquim, Maximo, Farias and Esperança (2006), "GPU-based cell projection for
//! interactive volume rendering".
//!
//! The paper moved the projected-tetrahedra classification of Wylie et al. (GATOR) off the
//! vertex shader into a first GPU pass that runs once per tet (a fragment shader then; a compute
//! pass here), so each tet is projected once instead of once per fan vertex. A second pass draws
//! the fans. The model lives on the GPU as a tet-index array and a vertex array only (≈ 20 bytes
//! per tet); everything else is per frame.
//!
//! * Pass 1 (`pass1.wgsl`, CPU twin [`classify::classify_tet`]): project, four ternary sign
//!   tests → 81-entry truth table ([`classify`]), thick vertex, s_f, s_b, thickness, fan, and
//!   the centroid depth used for sorting.
//! * Sort ([`SortMode`]): as the paper, centroid depths read back and sorted on the CPU — bucket
//!   sort into ≈ 20 depth slabs while the camera moves, merge sort for still frames (§4) — plus
//!   a full radix sort, the exact MPVONC order, and a GPU-resident variant that sorts on the
//!   device and draws with no readback.
//! * Pass 2 (`pass2.wgsl`): each tet's fan as 4 triangles (12 vertices, degenerate where the
//!   fan has fewer), shaded by the average scalar with an exponential table
//!   ([`Shading::Average`]) or by partial pre-integration with the ψ table ([`Shading::Psi`],
//!   §3.4); back-to-front premultiplied blending into an `Rgba32Float` target.

pub mod classify;
mod description;
mod frame;
mod prepare;

use anyhow::{anyhow, Context};
use datasets::TetMesh;
use render_core::bind::{render_target, ChunkedBuffer};
use render_core::gpu::MemoryLedger;
use render_core::sort;
use render_core::{Camera, FrameStats, Gpu, Image, Optics, Prepared, Renderer};

pub use description::{from_settings, DESCRIPTION};

/// How pass 2 colours a fragment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shading {
    /// The average of s_f and s_b through the transfer function, α = 1 − e^(−κl) from a 1D
    /// exponential table (Shirley & Tuchman 1990), as the paper's faster mode.
    Average,
    /// Partial pre-integration (Moreland & Angel 2004) with the ψ table (the paper's §3.4).
    Psi,
}

impl Shading {
    pub fn name(self) -> &'static str {
        match self {
            Shading::Average => "average",
            Shading::Psi => "psi",
        }
    }
}

/// Which visibility order pass 2 draws in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SortMode {
    /// Centroid depths read back, CPU bucket sort into [`sort::DEFAULT_SLABS`] depth slabs
    /// (the paper's §4 order while the camera moves).
    Bucket,
    /// Centroid depths read back, CPU merge sort (the paper's order for still frames).
    Merge,
    /// Centroid depths read back, CPU LSD radix sort (HAVS §5.1; the suite's default order).
    Radix,
    /// The exact MPVONC order (Williams 1992) over the face adjacency, on the CPU.
    Mpvonc,
    /// GPU-resident: centroid depths sorted on the device, drawn with no readback.
    Gpu,
}

impl SortMode {
    pub const ALL: [SortMode; 5] = [
        SortMode::Bucket,
        SortMode::Merge,
        SortMode::Radix,
        SortMode::Mpvonc,
        SortMode::Gpu,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SortMode::Bucket => "bucket",
            SortMode::Merge => "merge",
            SortMode::Radix => "radix",
            SortMode::Mpvonc => "mpvonc",
            SortMode::Gpu => "gpu",
        }
    }

    pub fn parse(s: &str) -> anyhow::Result<SortMode> {
        SortMode::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                anyhow!("unknown fragment-pt sort {s:?} (bucket, merge, radix, mpvonc, gpu)")
            })
    }
}

/// The paper's knobs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FragmentPtSettings {
    pub shading: Shading,
    pub sort: SortMode,
    /// A perturbation, not a configuration (the positive control of the bucket sort's image
    /// claim): the bucket sort's depth slabs where they are not the paper's
    /// [`sort::DEFAULT_SLABS`] (`None`: the paper's, §4). Only with [`SortMode::Bucket`].
    pub slabs: Option<usize>,
}

impl Default for FragmentPtSettings {
    fn default() -> Self {
        FragmentPtSettings {
            shading: Shading::Psi,
            sort: SortMode::Merge,
            slabs: None,
        }
    }
}

impl FragmentPtSettings {
    /// The depth slabs of the bucket sort: the paper's about 20 unless perturbed.
    pub fn bucket_slabs(&self) -> usize {
        self.slabs.unwrap_or(sort::DEFAULT_SLABS)
    }
}

/// Entries of the transfer-function table pass 2 interpolates.
const TF_ENTRIES: usize = 1024;
/// Entries and range of the exponential table e^(−x), x ∈ [0, EXP_MAX_TAU]: beyond 20 the
/// segment is opaque to f32 precision (e^(−20) ≈ 2e-9).
const EXP_ENTRIES: usize = 4096;
const EXP_MAX_TAU: f32 = 20.0;
/// Side of the ψ table (VTK uses 512²; 256² keeps it at 256 KiB, bilinearly interpolated).
const PSI_SIDE: usize = 256;
/// Pass 1 workgroup size (matches `@workgroup_size` in pass1.wgsl).
const WORKGROUP: u32 = 64;
/// Bytes of one pass-1 record (`TetOut` in the shaders).
const RECORD_BYTES: u64 = 32;
/// First binding of the chunked vertex, tet and record arrays in both passes.
const MESH_BINDING: u32 = 10;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Pass1Params {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    forward: [f32; 4],
    misc: [f32; 4],
    counts: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Pass2Params {
    view_proj: [[f32; 4]; 4],
    misc: [f32; 4],
    sizes: [u32; 4],
}

/// The `#[repr(C)]` structs this crate uploads to the GPU and the WGSL structs they mirror,
/// for the layout test (`tests/gpu_layouts.rs`, through [`DESCRIPTION`]).
#[doc(hidden)]
pub fn gpu_layouts() -> render_core::gpu_layout::GpuLayouts {
    let structs = vec![
        render_core::rust_layout!(Pass1Params => "pass1.wgsl::Params" { view_proj, eye, forward, misc, counts }),
        render_core::rust_layout!(Pass2Params => "pass2.wgsl::Params" { view_proj, misc, sizes }),
    ];
    render_core::gpu_layout::GpuLayouts {
        structs,
        sources: vec![
            ("pass1.wgsl", include_str!("pass1.wgsl").into()),
            ("pass2.wgsl", include_str!("pass2.wgsl").into()),
        ],
    }
}

/// Everything uploaded by `prepare`.
struct State {
    /// The loaded mesh, shared: the CPU sort variants and the work counters read it per frame.
    mesh: std::sync::Arc<TetMesh>,
    tets: u32,
    ledger: MemoryLedger,
    model_bytes: u64,
    pass1_params: wgpu::Buffer,
    pass2_params: wgpu::Buffer,
    records: ChunkedBuffer,
    /// Pass 1's 2D dispatch (workgroups per row, rows).
    dispatch: (u32, u32),
    /// Storage bindings the model and records take.
    mesh_bindings: u32,
    depths: wgpu::Buffer,
    order: wgpu::Buffer,
    pass1: wgpu::ComputePipeline,
    pass1_bind: wgpu::BindGroup,
    pass2: wgpu::RenderPipeline,
    pass2_bind: wgpu::BindGroup,
    target: Option<(wgpu::Texture, wgpu::TextureView)>,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    scalar_min: f32,
    scalar_inv_range: f32,
    inv_length_unit: f32,
    // CPU sort scratch, reused between frames.
    indices: Vec<u32>,
    radix: sort::RadixScratch,
    merge: Vec<u64>,
    visibility: Option<render_core::visibility::VisibilitySorter>,
    /// The device-resident sort of the `gpu` variant: sorts pass 1's centroid depths (keys)
    /// with the tet ids pass 1 wrote into `order` (payload), in place.
    gpu_sort: Option<render_core::gpu_sort::GpuRadixSort>,
    /// The fragments counter, derived once per view (render_core::silhouette).
    fragments: render_core::silhouette::FragmentsPerView,
}

/// Fragment PT renderer (`fragment-pt`).
pub struct FragmentPt {
    pub settings: FragmentPtSettings,
    state: Option<State>,
    /// Storage binding size to split at instead of the adapter's (tests of the split path).
    max_binding: Option<u64>,
}

impl FragmentPt {
    pub fn new(settings: FragmentPtSettings) -> FragmentPt {
        FragmentPt {
            settings,
            state: None,
            max_binding: None,
        }
    }

    /// Splits the vertex, tet and record arrays at `bytes` per storage binding (rounded down
    /// to 256) instead of the adapter's limit. Only useful to test the split on small meshes.
    pub fn with_max_binding(mut self, bytes: u64) -> FragmentPt {
        self.max_binding = Some(bytes);
        self
    }

    /// GPU bytes of the model alone (tet indices + vertices), the quantity the paper reports as
    /// ≈ 20 bytes per tet; `None` before `prepare`.
    pub fn model_bytes(&self) -> Option<u64> {
        self.state.as_ref().map(|s| s.model_bytes)
    }

    /// Runs pass 1 alone for `camera` and reads back every tet's record and centroid key (for
    /// tests against the CPU twin).
    pub fn classify_on_gpu(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
    ) -> anyhow::Result<Vec<(classify::TetRecord, f32)>> {
        let st = self
            .state
            .as_mut()
            .ok_or_else(|| anyhow!("fragment-pt: prepare before classify_on_gpu"))?;
        frame::write_params(gpu, st, camera);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        frame::encode_pass1(&mut enc, st, None);
        gpu.queue.submit([enc.finish()]);
        let n = st.tets as u64;
        let mut rec_bytes = Vec::with_capacity((n * RECORD_BYTES) as usize);
        for (i, b) in st.records.buffers.iter().enumerate() {
            let len = (n - i as u64 * st.records.per_chunk).min(st.records.per_chunk);
            rec_bytes.extend(gpu.read_buffer(b, 0, len * RECORD_BYTES)?);
        }
        let dep_bytes = gpu.read_buffer(&st.depths, 0, n * 4)?;
        let raw: &[[u32; 8]] = bytemuck::cast_slice(&rec_bytes);
        let depths: &[f32] = bytemuck::cast_slice(&dep_bytes);
        Ok(raw
            .iter()
            .zip(depths)
            .map(|(r, &d)| {
                let f = |i: usize| f32::from_bits(r[i]);
                (
                    classify::TetRecord {
                        thick_clip: [f(0), f(1), f(2), f(3)],
                        s_front: f(4),
                        s_back: f(5),
                        thickness: f(6),
                        fan: r[7],
                    },
                    d,
                )
            })
            .collect())
    }

    /// The per-frame parameters pass 1 uses, as the CPU twin takes them.
    pub fn project_params(&self, camera: &Camera) -> anyhow::Result<classify::ProjectParams> {
        let st = self
            .state
            .as_ref()
            .ok_or_else(|| anyhow!("fragment-pt: prepare first"))?;
        Ok(project_params(st, camera))
    }
}

fn project_params(st: &State, camera: &Camera) -> classify::ProjectParams {
    let eye = camera.eye.map(|c| c as f32);
    let fwd = camera.forward().map(|c| c as f32);
    classify::ProjectParams {
        view_proj: camera.view_proj_f32(),
        eye,
        forward: fwd,
        perspective: camera.is_perspective(),
        scalar_min: st.scalar_min,
        scalar_inv_range: st.scalar_inv_range,
        inv_length_unit: st.inv_length_unit,
    }
}

/// Shirley & Tuchman's exponential table: e^(−x) at x = i / (n − 1) · EXP_MAX_TAU.
fn exp_table() -> Vec<f32> {
    (0..EXP_ENTRIES)
        .map(|i| (-(i as f64) / (EXP_ENTRIES - 1) as f64 * EXP_MAX_TAU as f64).exp() as f32)
        .collect()
}

impl Renderer for FragmentPt {
    fn algorithm(&self) -> &'static str {
        "fragment-pt"
    }

    fn settings(&self) -> render_core::Settings {
        description::settings_of(&self.settings)
    }

    fn prepare(
        &mut self,
        gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        self.state = None;
        let state = prepare::build_state(&self.settings, self.max_binding, gpu, mesh, optics)?;
        let prepared = Prepared {
            persistent_bytes: state.ledger.persistent,
            tets: state.tets as u64,
        };
        self.state = Some(state);
        Ok(prepared)
    }

    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        let settings = self.settings;
        let st = self
            .state
            .as_mut()
            .ok_or_else(|| anyhow!("fragment-pt: render before prepare"))?;
        let (w, h) = (camera.width, camera.height);
        if st
            .target
            .as_ref()
            .is_none_or(|(t, _)| t.width() != w || t.height() != h)
        {
            st.target = Some(render_target(
                gpu,
                &mut st.ledger,
                "fragment-pt target",
                (w, h),
                wgpu::TextureFormat::Rgba32Float,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            )?);
        }
        frame::render(gpu, st, camera, &settings)
    }

    fn read_image(&mut self, gpu: &Gpu) -> anyhow::Result<Image> {
        let st = self
            .state
            .as_ref()
            .ok_or_else(|| anyhow!("fragment-pt: read_image before prepare"))?;
        let (tex, _) = st
            .target
            .as_ref()
            .ok_or_else(|| anyhow!("fragment-pt: read_image before render"))?;
        gpu.read_rgba32f(tex)
            .context("fragment-pt: reading the image back")
    }
}
