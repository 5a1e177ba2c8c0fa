//! GATOR-style projected tetrahedra (Wylie, Moreland, Fisk, Crossno 2002, "Tetrahedral
//! projection using vertex shaders").
//!
//! Shirley–Tuchman projected tetrahedra done entirely in the vertex shader: every tet is drawn
//! as the paper's *basis graph* (the 4 vertices plus the thick/phantom vertex) and every vertex
//! invocation re-derives the projection's class from the tet's four vertices, read from
//! storage buffers (`gator.wgsl`). One vertex invocation per node of the basis graph (5 per
//! tet); wgpu has no triangle fans, so a fixed index buffer draws each tet's fan as 4
//! triangles (12 indices); for class-1 projections the fourth degenerates.
//!
//! Per frame the CPU only sorts, back to front, with one of the shared visibility orders
//! (`render_core::visibility`; default: centroid distance to the eye, HAVS §5.1's LSD radix
//! sort on float keys), then writes the tet order in one buffer write. The GPU draws the fans
//! into an `Rgba32Float` target with premultiplied "over" blending.
//!
//! `sort=gpu-radix` ([`GatorSort::GpuRadix`], not the paper's split: it sorts on the CPU)
//! orders the tets on the device instead: one encoder holds the key pass
//! (`render_core::gpu_sort::GpuCentroidKeys`, one call per tet chunk: each tet's centroid
//! distance and its id), the radix sort of those pairs far to near
//! (`render_core::gpu_sort::GpuRadixSort`) and the draw, which reads the sorted ids as its
//! order. Nothing is read back and the host keeps no per-tet sort data; the order is the
//! centroid radix order, up to the f32 rounding of the keys.
//!
//! Two variants, the paper's Table 3: **constant** cells (colour and extinction of the tet's
//! mean scalar) and **linear** cells (the average of the scalars where the eye ray enters and
//! leaves, interpolated from the thick vertex; the paper's average-scalar approach, not
//! pre-integration). Opacity α = 1 − exp(−κ(s̄)·l / length_unit) through a lookup table.
//!
//! Thickness and scalars are interpolated linearly on screen from the thick vertex to the
//! silhouette (Shirley–Tuchman, GATOR): exact for orthographic views, a first-order
//! approximation in (tet depth / view distance) in perspective. The thick segment itself is
//! computed exactly in world space (perspective-correct weights), so class boundaries and
//! degenerate projections stay continuous.
//!
//! [`classify_cpu`] is the f64 twin of the shader's classification; [`classify_gpu`] runs the
//! shader's own function in a compute pass and reads the results back, so tests compare them.

mod classify;
mod debug;
mod description;
mod frame;
mod mesh_gpu;
mod ordering;

pub use debug::{classify_gpu, GpuClassification};
pub use description::DESCRIPTION;

use anyhow::{anyhow, bail, Context};
use datasets::TetMesh;
use render_core::bind::{buffer_range, whole};
use render_core::gpu::{chunk_ranges, LayoutEntries};
pub use render_core::visibility::VisibilityOrder;
use render_core::visibility::VisibilitySorter;
use render_core::{
    Camera, FrameStats, FrameTimer, Gpu, Image, Lifetime, MemoryLedger, Optics, Prepared, Renderer,
    Settings,
};

use frame::{DrawChunk, State};
use mesh_gpu::{MeshGpu, Params};
use ordering::{DeviceSort, Ordering};

pub use classify::{
    classify_cpu, classify_cpu_with, classify_tet, world_segment, Classification, GeometricTests,
    ThickSegment, FAN_TRIANGLES, MAPPING_TABLE,
};

/// Entries of the transfer-function table (rgb, κ over the normalised scalar).
pub const TF_LUT_SIZE: u32 = 1024;
/// Entries of the opacity table α(τ) = 1 − exp(−τ), τ ∈ [0, TAU_MAX].
pub const EXP_LUT_SIZE: u32 = 4096;
/// Optical depth where the opacity table ends (α = 1 − e⁻¹⁶ ≈ 1 − 1.1·10⁻⁷ beyond).
pub const TAU_MAX: f32 = 16.0;
/// Storage bindings for the tet array and the point array (see `gator.wgsl`): meshes up to
/// 4 × 8 M tets and 3 × 8 M points at lavapipe's 128 MiB per binding.
const MAX_TET_CHUNKS: usize = 4;
const MAX_POINT_CHUNKS: usize = 3;

const SHADER: &str = include_str!("gator.wgsl");

/// Nodes of the basis graph, i.e. vertex invocations per tet.
const NODES: u32 = 5;
/// The fan over the 5 nodes as a triangle list (see `vs_main` in gator.wgsl).
const FAN_INDICES: [u16; 12] = [0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1];
/// Tets per indexed draw: one 24 KB index buffer serves any mesh, each draw offset by
/// `base_vertex` (u16 indices allow up to 13,107 tets per draw; fewer keep the buffer small
/// against the mesh, which bytes/tet counts, at a cost of one draw call per 1,024 tets).
const TETS_PER_DRAW: u64 = 1024;

/// The index buffer: [`FAN_INDICES`] for tets 0..TETS_PER_DRAW, node indices 5k + j.
fn fan_index_buffer() -> Vec<u16> {
    (0..TETS_PER_DRAW as u16)
        .flat_map(|k| FAN_INDICES.map(|j| k * NODES as u16 + j))
        .collect()
}

/// The cell model of the paper's Table 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellModel {
    /// One colour and extinction per tet, from the mean of its four vertex scalars.
    Constant,
    /// Scalars interpolated linearly: the average of s_front and s_back along each ray.
    Linear,
}

impl CellModel {
    pub fn name(self) -> &'static str {
        match self {
            CellModel::Constant => "constant",
            CellModel::Linear => "linear",
        }
    }
}

/// Where GATOR's back-to-front order comes from: the `sort` setting.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GatorSort {
    /// A visibility order on the CPU each frame, uploaded (the paper's split, §3).
    Cpu(VisibilityOrder),
    /// Centroid distances and their radix sort on the device, in the frame's one encoder.
    GpuRadix,
}

impl GatorSort {
    /// The setting's text for the GPU sort.
    pub const GPU_RADIX: &'static str = "gpu-radix";

    /// Every value of the setting: the CPU orders, then the GPU sort.
    pub fn all() -> Vec<GatorSort> {
        VisibilityOrder::ALL
            .into_iter()
            .map(GatorSort::Cpu)
            .chain([GatorSort::GpuRadix])
            .collect()
    }
}

impl Default for GatorSort {
    fn default() -> GatorSort {
        GatorSort::Cpu(VisibilityOrder::default())
    }
}

impl From<VisibilityOrder> for GatorSort {
    fn from(order: VisibilityOrder) -> GatorSort {
        GatorSort::Cpu(order)
    }
}

impl std::fmt::Display for GatorSort {
    /// The CPU orders' names (`radix`, `bucket`, `merge`, `mpvonc`) or `gpu-radix`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GatorSort::Cpu(order) => order.fmt(f),
            GatorSort::GpuRadix => f.write_str(GatorSort::GPU_RADIX),
        }
    }
}

impl std::str::FromStr for GatorSort {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> anyhow::Result<GatorSort> {
        if s.trim().eq_ignore_ascii_case(GatorSort::GPU_RADIX) {
            return Ok(GatorSort::GpuRadix);
        }
        s.parse::<VisibilityOrder>()
            .map(GatorSort::Cpu)
            .map_err(|e| anyhow!("gator-pt: sort={s}: {e}, or gpu-radix"))
    }
}

/// The GATOR renderer. Construct with [`GatorPt::new`], then [`Renderer::prepare`].
pub struct GatorPt {
    cells: CellModel,
    sort: GatorSort,
    /// Largest storage binding to use (defaults to the device's); tests lower it to exercise
    /// chunking on small meshes.
    max_binding: Option<u64>,
    state: Option<State>,
}

impl GatorPt {
    /// `sort`: a [`VisibilityOrder`] (sorted on the CPU) or a [`GatorSort`].
    pub fn new(cells: CellModel, sort: impl Into<GatorSort>) -> GatorPt {
        GatorPt {
            cells,
            sort: sort.into(),
            max_binding: None,
            state: None,
        }
    }

    /// Splits the mesh arrays at `bytes` per storage binding instead of the device limit
    /// (rounded down to 256). Only useful to test chunking on small meshes.
    pub fn with_max_binding(mut self, bytes: u64) -> GatorPt {
        self.max_binding = Some((bytes & !255).max(256));
        self
    }

    pub fn cells(&self) -> CellModel {
        self.cells
    }

    pub fn sort(&self) -> GatorSort {
        self.sort
    }

    /// GPU memory of the prepared mesh (after [`Renderer::prepare`]).
    pub fn ledger(&self) -> Option<&MemoryLedger> {
        self.state.as_ref().map(|s| &s.ledger)
    }

    /// The order the last frame drew (tet ids, back to front), read back from the device: for
    /// tests of the order, CPU or GPU made, outside any timed frame.
    #[doc(hidden)]
    pub fn debug_read_order(&self, gpu: &Gpu) -> anyhow::Result<Vec<u32>> {
        let st = self
            .state
            .as_ref()
            .ok_or_else(|| anyhow!("gator-pt: debug_read_order called before prepare"))?;
        let n = st.mesh.num_tets as u64;
        if n == 0 {
            return Ok(Vec::new());
        }
        let bytes = gpu.read_buffer(&st.order_buf, 0, n * 4)?;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }
}

/// The `#[repr(C)]` structs this crate uploads to the GPU and the WGSL structs they mirror,
/// for the layout test (`tests/gpu_layouts.rs`, through [`DESCRIPTION`]).
#[doc(hidden)]
pub fn gpu_layouts() -> render_core::gpu_layout::GpuLayouts {
    let structs = vec![
        render_core::rust_layout!(Params => "gator.wgsl::Params" {
            view_proj, tets_per_chunk, points_per_chunk, num_tets, cells, inv_length_unit,
            tau_max, tf_size, exp_size
        }),
        render_core::rust_layout!(GpuClassification => "gator.wgsl::DebugRecord" {
            case, class, thick_vertex, ndc_thickness, length, s_front, s_back
        }),
    ];
    render_core::gpu_layout::GpuLayouts {
        structs,
        sources: vec![("gator.wgsl", SHADER.into())],
    }
}

fn max_binding(gpu: &Gpu, over: Option<u64>) -> u64 {
    let dev = gpu.max_storage_binding();
    over.map_or(dev, |o| o.min(dev))
}

impl Renderer for GatorPt {
    fn algorithm(&self) -> &'static str {
        "gator-pt"
    }

    fn settings(&self) -> Settings {
        description::settings_of(self.cells, self.sort)
    }

    fn prepare(
        &mut self,
        gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        self.state = None;
        if !gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
            bail!("gator-pt needs FLOAT32_BLENDABLE (blending into an Rgba32Float target); adapter {} lacks it", gpu.adapter.name);
        }
        let mb = max_binding(gpu, self.max_binding);
        if self.sort == GatorSort::GpuRadix {
            // The key pass reads the points from one storage binding (the draw reads up to
            // MAX_POINT_CHUNKS): refuse before uploading anything.
            let point_bindings = chunk_ranges(mesh.num_points() as u64, 16, mb).len();
            if point_bindings > 1 {
                bail!(
                    "gator-pt sort=gpu-radix: mesh {} has {} points ({} bytes as xyz + scalar), \
                     over one storage binding of {mb} bytes: the GPU key pass reads the points \
                     from one binding (a CPU sort such as sort=radix reads them from up to \
                     {MAX_POINT_CHUNKS})",
                    mesh.name,
                    mesh.num_points(),
                    mesh.num_points() as u64 * 16,
                );
            }
        }
        let mut ledger = MemoryLedger::default();
        let points: Vec<[f32; 4]> = mesh
            .points
            .iter()
            .zip(&mesh.scalars)
            .map(|(p, &s)| [p[0], p[1], p[2], optics.normalise(s as f64) as f32])
            .collect();
        let meshgpu = MeshGpu::new(gpu, &mut ledger, &points, &mesh.tets, Some(optics), mb)
            .with_context(|| format!("uploading mesh {}", mesh.name))?;

        let (pipeline, g1_layout) = pipeline(gpu, &meshgpu.g0_layout);

        let n = mesh.num_tets() as u64;
        // The order is rewritten every frame: per-frame memory, not per mesh. With the GPU
        // sort it is the sort's value buffer. COPY_SRC: `debug_read_order`.
        let order_buf = ledger.buffer(
            gpu,
            "gator order",
            Lifetime::PerFrame,
            n * 4,
            render_core::gpu_sort::REQUIRED_USAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        )?;
        let index_buf = ledger.buffer_init(
            gpu,
            "gator fan indices",
            Lifetime::Persistent,
            bytemuck::cast_slice(&fan_index_buffer()),
            wgpu::BufferUsages::INDEX,
        )?;
        let chunks = order_chunks(gpu, &mut ledger, &g1_layout, &order_buf, n, mb)?;
        let host_mesh = std::sync::Arc::clone(mesh);
        let (ordering, timer) = self.ordering(gpu, &mut ledger, &meshgpu, &host_mesh)?;
        let persistent = ledger.persistent;
        self.state = Some(State {
            ledger,
            mesh: meshgpu,
            pipeline,
            order_buf,
            index_buf,
            chunks,
            host_mesh,
            ordering,
            timer,
            target: None,
            fragments: Default::default(),
        });
        Ok(Prepared {
            persistent_bytes: persistent,
            tets: n,
        })
    }

    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        let cells = self.cells;
        self.state
            .as_mut()
            .ok_or_else(|| anyhow!("gator-pt: render called before prepare"))?
            .render(gpu, camera, cells)
    }

    fn read_image(&mut self, gpu: &Gpu) -> anyhow::Result<Image> {
        let st = self
            .state
            .as_ref()
            .ok_or_else(|| anyhow!("gator-pt: read_image called before prepare"))?;
        let target = st
            .target
            .as_ref()
            .ok_or_else(|| anyhow!("gator-pt: read_image called before render"))?;
        gpu.read_rgba32f(&target.texture)
    }
}

impl GatorPt {
    /// Where the frames' order comes from, with its per-mesh work done here (the visibility
    /// order's centroids or face planes, the device sort's buffers), not in the first frame.
    fn ordering(
        &self,
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        meshgpu: &MeshGpu,
        mesh: &std::sync::Arc<TetMesh>,
    ) -> anyhow::Result<(Ordering, FrameTimer)> {
        let n = mesh.num_tets() as u64;
        Ok(match self.sort {
            GatorSort::Cpu(order) => {
                // Per-mesh work of the visibility order (centroids; MPVONC's face planes) is
                // done here, not in the first timed frame.
                let mut sorter = VisibilitySorter::new(order);
                let mut order = Vec::with_capacity(n as usize);
                let warm = Camera::fit(
                    &mesh.bounds(),
                    &render_core::fixed_viewpoints()[0],
                    Default::default(),
                    16,
                    16,
                );
                sorter.back_to_front(mesh, &warm, &mut order);
                (Ordering::Cpu { sorter, order }, FrameTimer::new(gpu))
            }
            GatorSort::GpuRadix => (
                Ordering::Gpu(DeviceSort::new(gpu, ledger, meshgpu, n)?),
                FrameTimer::with_marks(gpu, 1),
            ),
        })
    }
}

/// The fans' pipeline: premultiplied "over", back to front, over group 0 (the mesh) and
/// group 1 (an order chunk); and group 1's layout.
fn pipeline(
    gpu: &Gpu,
    g0_layout: &wgpu::BindGroupLayout,
) -> (wgpu::RenderPipeline, wgpu::BindGroupLayout) {
    let shader = gpu.shader("gator.wgsl", SHADER);
    let g1_layout = LayoutEntries::new(wgpu::ShaderStages::VERTEX)
        .read(0)
        .uniform(1)
        .build(gpu, "gator order");
    let layout = gpu.pipeline_layout("gator", &[g0_layout, &g1_layout]);
    // Premultiplied "over", back to front: dst = src + (1 − src_α)·dst.
    let pipeline = gpu.triangle_pipeline(
        "gator",
        &layout,
        &shader,
        "vs_main",
        "fs_main",
        wgpu::TextureFormat::Rgba32Float,
        Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
        wgpu::ColorWrites::ALL,
    );
    (pipeline, g1_layout)
}

/// Group 1 per chunk of the order (at most one storage binding each) with its first index.
fn order_chunks(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    g1_layout: &wgpu::BindGroupLayout,
    order_buf: &wgpu::Buffer,
    n: u64,
    max_binding: u64,
) -> anyhow::Result<Vec<DrawChunk>> {
    let mut chunks = Vec::new();
    for range in chunk_ranges(n, 4, max_binding) {
        let cp = [range.start as u32, 0, 0, 0];
        let cbuf = ledger.buffer_init(
            gpu,
            "gator chunk params",
            Lifetime::Persistent,
            bytemuck::cast_slice(&cp),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let size = ((range.end - range.start) * 4).max(4);
        let bind_group = gpu.bind_group(
            "gator order chunk",
            g1_layout,
            &[
                buffer_range(0, order_buf, range.start * 4, size),
                whole(1, &cbuf),
            ],
        );
        chunks.push(DrawChunk { range, bind_group });
    }
    Ok(chunks)
}
