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
mod description;

pub use description::DESCRIPTION;

use std::time::Instant;

use anyhow::{anyhow, bail, ensure, Context};
use datasets::TetMesh;
use render_core::bind::{lookup_texture, storage_entry, texture_entry, uniform_entry};
use render_core::gpu::chunk_ranges;
use render_core::gpu_sort::{GpuCentroidKeys, GpuRadixSort, KeyRange};
pub use render_core::visibility::VisibilityOrder;
use render_core::visibility::VisibilitySorter;
use render_core::{
    Camera, FrameClock, FrameStats, FrameTimer, Gpu, Image, Lifetime, MemoryLedger, Optics,
    Prepared, Renderer, Settings,
};

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

/// The constant and linear variants (the paper's Table 3) with the default visibility order
/// (centroid radix sort), as the harness runs them.
pub fn default_variants() -> Vec<Box<dyn Renderer>> {
    variants(&[VisibilityOrder::default()])
}

/// Both cell models with each of `orders` (constant first, then linear, for each order).
pub fn variants(orders: &[VisibilityOrder]) -> Vec<Box<dyn Renderer>> {
    orders
        .iter()
        .flat_map(|&o| {
            [CellModel::Constant, CellModel::Linear]
                .map(|c| Box::new(GatorPt::new(c, o)) as Box<dyn Renderer>)
        })
        .collect()
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

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    view_proj: [[f32; 4]; 4],
    tets_per_chunk: u32,
    points_per_chunk: u32,
    num_tets: u32,
    cells: u32,
    inv_length_unit: f32,
    tau_max: f32,
    tf_size: u32,
    exp_size: u32,
}

/// The `#[repr(C)]` structs this crate uploads to the GPU and the WGSL structs they mirror,
/// for the layout test (`tests/gpu_layouts.rs`).
#[doc(hidden)]
pub fn gpu_layouts() -> Vec<render_core::gpu_layout::RustLayout> {
    vec![
        render_core::rust_layout!(Params => "gator.wgsl::Params" {
            view_proj, tets_per_chunk, points_per_chunk, num_tets, cells, inv_length_unit,
            tau_max, tf_size, exp_size
        }),
        render_core::rust_layout!(GpuClassification => "gator.wgsl::DebugRecord" {
            case, class, thick_vertex, ndc_thickness, length, s_front, s_back
        }),
    ]
}

/// Layouts, pipelines and the mesh on the GPU (shared by the renderer and the debug path).
struct MeshGpu {
    g0_layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    g0: wgpu::BindGroup,
    params_host: Params,
    num_tets: u32,
    /// The tet chunks (then placeholders up to [`MAX_TET_CHUNKS`]) and the tets each holds.
    tet_bufs: Vec<wgpu::Buffer>,
    tet_ranges: Vec<std::ops::Range<u64>>,
    /// The point chunks (then placeholders up to [`MAX_POINT_CHUNKS`]).
    point_bufs: Vec<wgpu::Buffer>,
}

fn lut_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    texture_entry(
        binding,
        wgpu::ShaderStages::FRAGMENT,
        false,
        wgpu::TextureViewDimension::D1,
    )
}

/// Opacity table: α(τ) = 1 − exp(−τ) for τ = i/(n−1)·TAU_MAX.
fn exp_table() -> Vec<f32> {
    (0..EXP_LUT_SIZE)
        .map(|i| {
            let tau = i as f64 / (EXP_LUT_SIZE - 1) as f64 * TAU_MAX as f64;
            (-(-tau).exp_m1()) as f32
        })
        .collect()
}

impl MeshGpu {
    /// Uploads points (xyz + scalar) and tets, split over storage bindings of at most
    /// `max_binding` bytes, and the lookup tables.
    fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        points: &[[f32; 4]],
        tets: &[[u32; 4]],
        optics: Option<&Optics>,
        max_binding: u64,
    ) -> anyhow::Result<MeshGpu> {
        let per = max_binding / 16;
        let tet_ranges = chunk_ranges(tets.len() as u64, 16, max_binding);
        let point_ranges = chunk_ranges(points.len() as u64, 16, max_binding);
        if tet_ranges.len() > MAX_TET_CHUNKS || point_ranges.len() > MAX_POINT_CHUNKS {
            bail!(
                "gator-pt: mesh of {} tets / {} points needs {} + {} storage bindings of {} bytes; \
                 at most {MAX_TET_CHUNKS} + {MAX_POINT_CHUNKS} are bound",
                tets.len(),
                points.len(),
                tet_ranges.len(),
                point_ranges.len(),
                max_binding
            );
        }
        if tets.len() as u64 * NODES as u64 > i32::MAX as u64 {
            bail!(
                "gator-pt: {} tets exceed the 32-bit vertex index range ({NODES} vertices per tet)",
                tets.len()
            );
        }
        let usage = wgpu::BufferUsages::STORAGE;
        let chunk_buffers = |ledger: &mut MemoryLedger,
                             label: &str,
                             bytes: &[u8],
                             ranges: &[std::ops::Range<u64>],
                             max: usize|
         -> anyhow::Result<Vec<wgpu::Buffer>> {
            let mut bufs: Vec<wgpu::Buffer> = ranges
                .iter()
                .map(|r| {
                    ledger.buffer_init(
                        gpu,
                        label,
                        Lifetime::Persistent,
                        &bytes[(r.start * 16) as usize..(r.end * 16) as usize],
                        usage,
                    )
                })
                .collect::<anyhow::Result<_>>()?;
            // Unused bindings get a tiny placeholder buffer (counted: it is allocated).
            while bufs.len() < max {
                bufs.push(ledger.buffer(
                    gpu,
                    "gator unused binding",
                    Lifetime::Persistent,
                    16,
                    usage,
                )?);
            }
            Ok(bufs)
        };
        let tet_bufs = chunk_buffers(
            ledger,
            "gator tets",
            bytemuck::cast_slice(tets),
            &tet_ranges,
            MAX_TET_CHUNKS,
        )?;
        let point_bufs = chunk_buffers(
            ledger,
            "gator points",
            bytemuck::cast_slice(points),
            &point_ranges,
            MAX_POINT_CHUNKS,
        )?;

        let default_optics;
        let optics = match optics {
            Some(o) => o,
            None => {
                default_optics = Optics {
                    tf: render_core::TransferFunction::preset("low-opacity")
                        .ok_or_else(|| anyhow!("no low-opacity preset"))?,
                    scalar_min: 0.0,
                    scalar_max: 1.0,
                    length_unit: 1.0,
                };
                &default_optics
            }
        };
        let tf = optics.tf.rgb_kappa_table(TF_LUT_SIZE as usize);
        let tf_view = lookup_texture(
            gpu,
            ledger,
            "gator tf table",
            wgpu::TextureFormat::Rgba32Float,
            (TF_LUT_SIZE, 1),
            bytemuck::cast_slice(&tf),
        )?;
        let ex = exp_table();
        let exp_view = lookup_texture(
            gpu,
            ledger,
            "gator opacity table",
            wgpu::TextureFormat::R32Float,
            (EXP_LUT_SIZE, 1),
            bytemuck::cast_slice(&ex),
        )?;

        let params_host = Params {
            view_proj: [[0.0; 4]; 4],
            tets_per_chunk: per as u32,
            points_per_chunk: per as u32,
            num_tets: tets.len() as u32,
            cells: 1,
            inv_length_unit: (1.0 / optics.length_unit.max(1e-300)) as f32,
            tau_max: TAU_MAX,
            tf_size: TF_LUT_SIZE,
            exp_size: EXP_LUT_SIZE,
        };
        let params = ledger.buffer_init(
            gpu,
            "gator params",
            Lifetime::Persistent,
            bytemuck::bytes_of(&params_host),
            wgpu::BufferUsages::UNIFORM,
        )?;

        let vc = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::COMPUTE;
        let mut entries = vec![uniform_entry(
            0,
            wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
        )];
        for b in 1..=(MAX_TET_CHUNKS + MAX_POINT_CHUNKS) as u32 {
            entries.push(storage_entry(b, vc, true));
        }
        entries.push(lut_entry(8));
        entries.push(lut_entry(9));
        let g0_layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("gator g0"),
                entries: &entries,
            });
        let mut bind = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: params.as_entire_binding(),
        }];
        for (i, b) in tet_bufs.iter().chain(point_bufs.iter()).enumerate() {
            bind.push(wgpu::BindGroupEntry {
                binding: 1 + i as u32,
                resource: b.as_entire_binding(),
            });
        }
        bind.push(wgpu::BindGroupEntry {
            binding: 8,
            resource: wgpu::BindingResource::TextureView(&tf_view),
        });
        bind.push(wgpu::BindGroupEntry {
            binding: 9,
            resource: wgpu::BindingResource::TextureView(&exp_view),
        });
        let g0 = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gator g0"),
            layout: &g0_layout,
            entries: &bind,
        });
        Ok(MeshGpu {
            g0_layout,
            params,
            g0,
            params_host,
            num_tets: tets.len() as u32,
            tet_bufs,
            tet_ranges,
            point_bufs,
        })
    }

    fn write_params(&mut self, gpu: &Gpu, camera: &Camera, cells: CellModel) {
        self.params_host.view_proj = camera.view_proj_f32();
        self.params_host.cells = match cells {
            CellModel::Constant => 0,
            CellModel::Linear => 1,
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&self.params_host));
    }
}

/// One order-buffer chunk of the draw.
struct DrawChunk {
    range: std::ops::Range<u64>,
    bind_group: wgpu::BindGroup,
}

struct Target {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    bytes: u64,
}

/// Where a frame's order comes from ([`GatorSort`]).
enum Ordering {
    /// Sorted on the host each frame and uploaded into `State::order_buf`.
    Cpu {
        sorter: VisibilitySorter,
        order: Vec<u32>,
    },
    /// Keyed and sorted on the device; `State::order_buf` is the sort's value buffer.
    Gpu(DeviceSort),
}

/// The device's sort of `sort=gpu-radix`.
struct DeviceSort {
    keys_pass: GpuCentroidKeys,
    sorter: GpuRadixSort,
    /// Each tet's centroid distance, sorted along with the ids in `State::order_buf`.
    keys: wgpu::Buffer,
    /// Per-frame device bytes of the sort besides the order: the keys, the sorter's scratch
    /// and the key pass's parameters (from the ledger).
    bytes: u64,
}

impl DeviceSort {
    /// The key pass (one call per tet chunk), the sorter and the key buffer for `n` tets,
    /// recorded in `ledger` as per-frame bytes.
    fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        mesh: &MeshGpu,
        n: u64,
    ) -> anyhow::Result<DeviceSort> {
        // One binding each for the keys and the ids: GATOR binds at most MAX_TET_CHUNKS chunks
        // of max_binding / 16 tets, so 4 bytes a tet make at most max_binding / 4 · 4 bytes
        // = one binding (32 Mi tets, 128 MiB, on lavapipe).
        ensure!(
            n * 4 <= gpu.max_storage_binding(),
            "gator-pt sort=gpu-radix: {n} tets' keys exceed one storage binding of {} bytes",
            gpu.max_storage_binding()
        );
        let before = ledger.per_frame;
        let keys = ledger.buffer(
            gpu,
            "gator sort keys",
            Lifetime::PerFrame,
            n * 4,
            render_core::gpu_sort::REQUIRED_USAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let keys_pass = GpuCentroidKeys::with_calls(gpu, mesh.tet_ranges.len() as u32, ledger)?;
        let sorter = GpuRadixSort::new(gpu, n as u32, ledger)?;
        Ok(DeviceSort {
            keys_pass,
            sorter,
            keys,
            bytes: ledger.per_frame - before,
        })
    }

    /// Records the key pass over every tet chunk and the sort of its pairs far to near, so
    /// that `order` holds the tet ids back to front.
    fn encode(
        &self,
        enc: &mut wgpu::CommandEncoder,
        camera: &Camera,
        mesh: &MeshGpu,
        order: &wgpu::Buffer,
    ) -> anyhow::Result<()> {
        let ranges: Vec<KeyRange> = mesh
            .tet_ranges
            .iter()
            .zip(&mesh.tet_bufs)
            .map(|(r, prims)| KeyRange {
                prims,
                first: r.start as u32,
                count: (r.end - r.start) as u32,
            })
            .collect();
        // Points: xyz + normalised scalar, 4 floats, in one binding (checked in prepare).
        self.keys_pass.encode_ranges(
            enc,
            camera,
            &mesh.point_bufs[0],
            4,
            4,
            &ranges,
            &self.keys,
            order,
        )?;
        self.sorter
            .encode(enc, &self.keys, order, mesh.num_tets, true)
    }
}

struct State {
    ledger: MemoryLedger,
    mesh: MeshGpu,
    pipeline: wgpu::RenderPipeline,
    /// The tet ids back to front, which the draw reads.
    order_buf: wgpu::Buffer,
    index_buf: wgpu::Buffer,
    chunks: Vec<DrawChunk>,
    /// The loaded mesh, shared, not copied (a CPU visibility sorter reads its centroids / face
    /// adjacency, the counters its silhouette).
    host_mesh: std::sync::Arc<TetMesh>,
    ordering: Ordering,
    /// Begin, [end of the device sort,] end.
    timer: FrameTimer,
    target: Option<Target>,
    /// The fragments counter, derived once per view (render_core::silhouette).
    fragments: render_core::silhouette::FragmentsPerView,
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

        let shader = gpu.shader("gator.wgsl", SHADER);
        let g1_layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("gator order"),
                entries: &[
                    storage_entry(0, wgpu::ShaderStages::VERTEX, true),
                    uniform_entry(1, wgpu::ShaderStages::VERTEX),
                ],
            });
        let layout = render_core::bind::pipeline_layout(
            gpu,
            "gator",
            &[Some(&meshgpu.g0_layout), Some(&g1_layout)],
        );
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
        let mut chunks = Vec::new();
        for range in chunk_ranges(n, 4, mb) {
            let cp = [range.start as u32, 0, 0, 0];
            let cbuf = ledger.buffer_init(
                gpu,
                "gator chunk params",
                Lifetime::Persistent,
                bytemuck::cast_slice(&cp),
                wgpu::BufferUsages::UNIFORM,
            )?;
            let size = std::num::NonZeroU64::new(((range.end - range.start) * 4).max(4));
            let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("gator order chunk"),
                layout: &g1_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &order_buf,
                            offset: range.start * 4,
                            size,
                        }),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: cbuf.as_entire_binding(),
                    },
                ],
            });
            chunks.push(DrawChunk { range, bind_group });
        }
        let host_mesh = std::sync::Arc::clone(mesh);
        let (ordering, timer) = match self.sort {
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
                sorter.back_to_front(&host_mesh, &warm, &mut order);
                (Ordering::Cpu { sorter, order }, FrameTimer::new(gpu))
            }
            GatorSort::GpuRadix => (
                Ordering::Gpu(DeviceSort::new(gpu, &mut ledger, &meshgpu, n)?),
                FrameTimer::with_marks(gpu, 1),
            ),
        };
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
        let st = self
            .state
            .as_mut()
            .ok_or_else(|| anyhow!("gator-pt: render called before prepare"))?;
        let (w, h) = (camera.width, camera.height);
        if st
            .target
            .as_ref()
            .is_none_or(|t| t.texture.width() != w || t.texture.height() != h)
        {
            let (texture, view) = render_core::bind::render_target(
                gpu,
                &mut st.ledger,
                "gator target",
                (w, h),
                wgpu::TextureFormat::Rgba32Float,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            )?;
            st.target = Some(Target {
                texture,
                view,
                bytes: w as u64 * h as u64 * 16,
            });
        }

        let mut clock = FrameClock::start();
        let mut cycle_breaks = 0;
        match &mut st.ordering {
            // CPU part of the frame: sort keys, radix sort, one upload of the order.
            Ordering::Cpu { sorter, order } => {
                let t0 = Instant::now();
                let sort = sorter.back_to_front(&st.host_mesh, camera, order);
                clock.stage("sort", t0);
                let t1 = Instant::now();
                gpu.queue
                    .write_buffer(&st.order_buf, 0, bytemuck::cast_slice(order));
                st.mesh.write_params(gpu, camera, cells);
                clock.stage("upload", t1);
                if sort.precompute_ms > 0.0 {
                    clock.push_stage("sort_precompute", sort.precompute_ms);
                }
                cycle_breaks = sort.cycle_breaks;
            }
            // The order is made on the device, in the encoder below.
            Ordering::Gpu(_) => {
                let t1 = Instant::now();
                st.mesh.write_params(gpu, camera, cells);
                clock.stage("upload", t1);
            }
        }

        let target = st.target.as_ref().expect("target created above");
        let mut enc = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("gator frame"),
            });
        st.timer.begin(&mut enc);
        if let Ordering::Gpu(ds) = &st.ordering {
            ds.encode(&mut enc, camera, &st.mesh, &st.order_buf)?;
            st.timer.mark(&mut enc, 0);
        }
        // Draws of TETS_PER_DRAW in passes of at most `gpu.triangles_per_pass` (4 a tet; see
        // render_core::gpu::MAX_TRIANGLES_PER_PASS): the first pass clears the target, the
        // rest blend onto it. A chunk's bind group is set once per pass it spans.
        let tets_per_pass = (gpu.triangles_per_pass / 4).max(1) as u64;
        let mut pass: Option<wgpu::RenderPass<'static>> = None;
        let mut in_pass = 0u64;
        let mut first = true;
        // Indices issued by the draws below: the triangles the frame actually draws (§3.4:
        // four per tet, class-1 cases with a degenerate fourth).
        let mut indices_drawn = 0u64;
        let open_pass = |enc: &mut wgpu::CommandEncoder, first: bool| {
            let mut p =
                render_core::bind::color_pass(enc, "gator fans", &target.view, first, true, None)
                    .forget_lifetime();
            p.set_pipeline(&st.pipeline);
            p.set_bind_group(0, &st.mesh.g0, &[]);
            p.set_index_buffer(st.index_buf.slice(..), wgpu::IndexFormat::Uint16);
            p
        };
        for chunk in &st.chunks {
            let mut start = chunk.range.start;
            let mut bound = false;
            while start < chunk.range.end {
                if pass.is_none() || in_pass >= tets_per_pass {
                    drop(pass.take());
                    pass = Some(open_pass(&mut enc, first));
                    first = false;
                    in_pass = 0;
                    bound = false;
                }
                let p = pass.as_mut().expect("opened above");
                if !bound {
                    p.set_bind_group(1, &chunk.bind_group, &[]);
                    bound = true;
                }
                let len = (chunk.range.end - start)
                    .min(TETS_PER_DRAW)
                    .min(tets_per_pass - in_pass);
                // Vertex index = fan index + base_vertex = 5·(sorted position) + node.
                p.draw_indexed(0..(12 * len) as u32, (start * NODES as u64) as i32, 0..1);
                indices_drawn += 12 * len;
                start += len;
                in_pass += len;
            }
        }
        if first {
            // Nothing drawn: the one pass still clears the target.
            open_pass(&mut enc, true);
        }
        drop(pass);
        st.timer.end(&mut enc);
        clock.submit(gpu, [enc.finish()]);
        clock.wait(gpu)?;
        let times = clock.finish();
        let (gpu_ms, stages, sort_bytes) = match &st.ordering {
            Ordering::Cpu { .. } => {
                let gpu_ms = st.timer.gpu_ms(gpu)?;
                (gpu_ms, gpu_ms.map(|g| vec![("draw".to_string(), g)]), 0)
            }
            Ordering::Gpu(ds) => {
                // GPU-timed stages: the key pass and the sort, then the draw.
                let parts = st.timer.gpu_intervals_ms(gpu)?;
                let stages = parts
                    .as_ref()
                    .map(|p| vec![("gpu_sort".to_string(), p[0]), ("draw".to_string(), p[1])]);
                (parts.map(|p| p.iter().sum()), stages, ds.bytes)
            }
        };
        let sorted_on = match st.ordering {
            Ordering::Cpu { .. } => "cpu_sort_keys",
            Ordering::Gpu(_) => "gpu_sort_keys",
        };
        let n = st.mesh.num_tets as f64;
        let projected = st.fragments.get(camera, &st.host_mesh);
        let counters = vec![
            ("tets".to_string(), n),
            ("basis_graph_vertices".to_string(), NODES as f64 * n),
            ("cycle_breaks".to_string(), cycle_breaks as f64),
            // The roofline's work: the basis graph's 4 triangles per tet (12 indices), every
            // tet ordered, on the CPU or on the device.
            ("triangles".to_string(), 4.0 * n),
            // Counted from the draw calls issued (indices / 3), not from the formula above.
            ("triangles_drawn".to_string(), (indices_drawn / 3) as f64),
            (sorted_on.to_string(), n),
            // Outside the timed frame, once per view: the pixel centres of every tet's
            // projection, which its four triangles cover once each, and the tets that hold any.
            ("fragments".to_string(), projected.fragments as f64),
            ("covering_tets".to_string(), projected.covering_tets as f64),
            // The vertex program classifies the tet once per basis-graph node it shades
            // (§3: every node's invocation repeats the tests): at least 5 per tet, since an
            // indexed draw shades each of its 5 indices at least once.
            ("tet_classifications".to_string(), NODES as f64 * n),
            // Tets with a vertex at or behind the eye: the vertex shader drops them (no
            // near-plane clipping, as the paper); counted outside the timed frame.
            (
                "tets_behind_eye".to_string(),
                camera.tets_behind_eye(&st.host_mesh) as f64,
            ),
        ];
        Ok(times.with_stages(stages.into_iter().flatten()).stats(
            gpu_ms,
            st.mesh.num_tets as u64 * 4
                + std::mem::size_of::<Params>() as u64
                + target.bytes
                + sort_bytes,
            counters,
        ))
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

/// The GPU classification of one tet, as `gator.wgsl`'s `classify_debug` writes it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuClassification {
    /// 1..=14 (see [`Classification::case`]).
    pub case: u32,
    /// 1 or 2; 0 when a vertex was behind the eye (the tet is not drawn).
    pub class: u32,
    /// Thick vertex in normalised device coordinates.
    pub thick_vertex: [f32; 2],
    /// |Δz| in NDC between the two ends of the thick segment (the paper's thickness).
    pub ndc_thickness: f32,
    /// World length of the thick segment (what the optical model uses).
    pub length: f32,
    pub s_front: f32,
    pub s_back: f32,
}

/// Runs the vertex shader's classification (`project_and_classify` in `gator.wgsl`) on every
/// tet in a compute pass and reads the results back. `scalars` are passed through unchanged
/// (not normalised). Degenerate and inverted tets are accepted as they are.
pub fn classify_gpu(
    gpu: &Gpu,
    points: &[[f32; 3]],
    scalars: &[f32],
    tets: &[[u32; 4]],
    camera: &Camera,
) -> anyhow::Result<Vec<GpuClassification>> {
    if points.len() != scalars.len() {
        bail!(
            "classify_gpu: {} points but {} scalars",
            points.len(),
            scalars.len()
        );
    }
    if let Some((t, bad)) = tets
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&i| i as usize >= points.len()))
    {
        bail!(
            "classify_gpu: tet {t} {bad:?} indexes past the {} points",
            points.len()
        );
    }
    let groups = (tets.len() as u64).div_ceil(64);
    if groups > gpu.limits.max_compute_workgroups_per_dimension as u64 {
        bail!(
            "classify_gpu: {} tets exceed one dispatch ({} workgroups of 64)",
            tets.len(),
            gpu.limits.max_compute_workgroups_per_dimension
        );
    }
    let mut ledger = MemoryLedger::default();
    let xyzs: Vec<[f32; 4]> = points
        .iter()
        .zip(scalars)
        .map(|(p, &s)| [p[0], p[1], p[2], s])
        .collect();
    let mut mesh = MeshGpu::new(
        gpu,
        &mut ledger,
        &xyzs,
        tets,
        None,
        gpu.max_storage_binding(),
    )?;
    mesh.write_params(gpu, camera, CellModel::Linear);
    let shader = gpu.shader("gator.wgsl", SHADER);
    let g1_layout = gpu
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gator debug out"),
            entries: &[storage_entry(2, wgpu::ShaderStages::COMPUTE, false)],
        });
    let layout = render_core::bind::pipeline_layout(
        gpu,
        "gator debug",
        &[Some(&mesh.g0_layout), Some(&g1_layout)],
    );
    let pipeline = gpu.compute_pipeline(
        "gator classify debug",
        Some(&layout),
        &shader,
        "classify_debug",
    );
    let size = (tets.len().max(1) * std::mem::size_of::<GpuClassification>()) as u64;
    let out = ledger.buffer(
        gpu,
        "gator debug out",
        Lifetime::PerFrame,
        size,
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    )?;
    let g1 = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("gator debug out"),
        layout: &g1_layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 2,
            resource: out.as_entire_binding(),
        }],
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("gator classify"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &mesh.g0, &[]);
        pass.set_bind_group(1, &g1, &[]);
        pass.dispatch_workgroups(groups as u32, 1, 1);
    }
    gpu.queue.submit([enc.finish()]);
    let bytes = gpu.read_buffer(&out, 0, size)?;
    let mut v: Vec<GpuClassification> = bytemuck::cast_slice(&bytes).to_vec();
    v.truncate(mesh.num_tets as usize);
    Ok(v)
}
