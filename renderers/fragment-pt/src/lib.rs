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

use anyhow::{anyhow, bail, Context};
use datasets::TetMesh;
use render_core::bind::{
    buffer_entry, check_storage_bindings, render_target, texture_entry, view_entry,
    whole as storage, ChunkedBuffer,
};
use render_core::gpu::{Lifetime, MemoryLedger};
use render_core::sort;
use render_core::{Camera, FrameStats, Gpu, Image, Optics, Prepared, Renderer};

pub use description::{from_settings, DESCRIPTION};

use classify::packed_table;

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
}

impl Default for FragmentPtSettings {
    fn default() -> Self {
        FragmentPtSettings {
            shading: Shading::Psi,
            sort: SortMode::Merge,
        }
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
        if !gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
            bail!(
                "fragment-pt: adapter {} cannot blend into Rgba32Float (FLOAT32_BLENDABLE)",
                gpu.adapter.name
            );
        }
        let n = mesh.num_tets() as u64;
        let max_binding = match self.max_binding {
            Some(b) => b.min(gpu.max_storage_binding()) & !255,
            None => gpu.max_storage_binding(),
        }
        .max(256);
        // Vertices, tets and pass-1 records are split over storage bindings; the
        // centroid depths and the order stay one binding each, because the GPU radix sort and
        // the CPU upload take them whole (4 B/tet: 33 M tets at lavapipe's 128 MiB).
        let adapter_binding = gpu.max_storage_binding();
        if n * 4 > adapter_binding {
            bail!(
                "fragment-pt: mesh {} has {n} tets; its depth and order arrays need {} bytes \
                 each in one storage binding, the adapter allows {adapter_binding} bytes \
                 (max_storage_buffer_binding_size)",
                mesh.name,
                n * 4
            );
        }
        if n > u32::MAX as u64 / 12 {
            bail!("fragment-pt: {n} tets exceed the 32-bit vertex index range (12 per tet)");
        }
        let groups = n.div_ceil(WORKGROUP as u64).max(1);
        let gx = groups.min(gpu.limits.max_compute_workgroups_per_dimension as u64);
        let dispatch = (gx as u32, groups.div_ceil(gx) as u32);
        let mut ledger = MemoryLedger::default();
        let storage_use = wgpu::BufferUsages::STORAGE;
        // The model: vertices (xyz + scalar) and tet indices — nothing else persistent per tet.
        let verts: Vec<[f32; 4]> = mesh
            .points
            .iter()
            .zip(&mesh.scalars)
            .map(|(p, &s)| [p[0], p[1], p[2], s])
            .collect();
        let tets: Vec<[u32; 4]> = mesh.tets.clone();
        let vertices = ChunkedBuffer::with_data(
            gpu,
            &mut ledger,
            "fragment-pt vertices",
            Lifetime::Persistent,
            bytemuck::cast_slice(&verts),
            16,
            max_binding,
            storage_use,
        )?;
        drop(verts);
        let tet_buf = ChunkedBuffer::with_data(
            gpu,
            &mut ledger,
            "fragment-pt tets",
            Lifetime::Persistent,
            bytemuck::cast_slice(&tets),
            16,
            max_binding,
            storage_use,
        )?;
        drop(tets);
        let model_bytes = ledger.persistent;
        // View-independent tables (small; counted as persistent too).
        let table = ledger.buffer_init(
            gpu,
            "fragment-pt truth table",
            Lifetime::Persistent,
            bytemuck::cast_slice(&packed_table()),
            storage_use,
        )?;
        let tf = render_core::bind::lookup_texture(
            gpu,
            &mut ledger,
            "fragment-pt transfer function",
            wgpu::TextureFormat::Rgba32Float,
            (TF_ENTRIES as u32, 1),
            bytemuck::cast_slice(&optics.tf.rgb_kappa_table(TF_ENTRIES)),
        )?;
        let expt = render_core::bind::lookup_texture(
            gpu,
            &mut ledger,
            "fragment-pt exp table",
            wgpu::TextureFormat::R32Float,
            (EXP_ENTRIES as u32, 1),
            bytemuck::cast_slice(&exp_table()),
        )?;
        let (psi_side, psi_values) = match self.settings.shading {
            Shading::Psi => (
                PSI_SIDE as u32,
                render_core::preintegration::PsiTable::build(PSI_SIDE).data,
            ),
            // The average mode never reads ψ; bind a minimal texture.
            Shading::Average => (2, vec![0.0; 4]),
        };
        let psi = render_core::bind::lookup_texture(
            gpu,
            &mut ledger,
            "fragment-pt psi table",
            wgpu::TextureFormat::R32Float,
            (psi_side, psi_side),
            bytemuck::cast_slice(&psi_values),
        )?;
        // Per-frame buffers written by pass 1 and the sort.
        let records = ChunkedBuffer::new(
            gpu,
            &mut ledger,
            "fragment-pt pass-1 records",
            Lifetime::PerFrame,
            n,
            RECORD_BYTES,
            max_binding,
            storage_use | wgpu::BufferUsages::COPY_SRC,
        )?;
        let mesh_bindings = vertices.bindings() + tet_buf.bindings() + records.bindings();
        check_storage_bindings(gpu, "fragment-pt pass 2", 4 + mesh_bindings)?;
        let decls = |records_read_only: bool| {
            vertices.wgsl("vertices", "vec4<f32>", 0, MESH_BINDING, true)
                + &tet_buf.wgsl(
                    "tets",
                    "vec4<u32>",
                    0,
                    MESH_BINDING + vertices.bindings(),
                    true,
                )
                + &records.wgsl(
                    "records",
                    "TetOut",
                    0,
                    MESH_BINDING + vertices.bindings() + tet_buf.bindings(),
                    records_read_only,
                )
        };
        let mesh_entries = || {
            [
                vertices.bind_entries(MESH_BINDING),
                tet_buf.bind_entries(MESH_BINDING + vertices.bindings()),
                records.bind_entries(MESH_BINDING + vertices.bindings() + tet_buf.bindings()),
            ]
            .concat()
        };
        let depths = ledger.buffer(
            gpu,
            "fragment-pt centroid depths",
            Lifetime::PerFrame,
            n * 4,
            storage_use | wgpu::BufferUsages::COPY_SRC,
        )?;
        let order = ledger.buffer(
            gpu,
            "fragment-pt order",
            Lifetime::PerFrame,
            n * 4,
            storage_use | wgpu::BufferUsages::COPY_DST,
        )?;
        let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
        let pass1_params = ledger.buffer(
            gpu,
            "fragment-pt pass-1 params",
            Lifetime::PerFrame,
            std::mem::size_of::<Pass1Params>() as u64,
            uniform,
        )?;
        let pass2_params = ledger.buffer(
            gpu,
            "fragment-pt pass-2 params",
            Lifetime::PerFrame,
            std::mem::size_of::<Pass2Params>() as u64,
            uniform,
        )?;

        let m1 = gpu.shader(
            "fragment-pt pass 1",
            &(decls(false) + include_str!("pass1.wgsl")),
        );
        let pass1 = gpu.compute_pipeline("fragment-pt pass 1", None, &m1, "classify");
        let pass1_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fragment-pt pass 1"),
            layout: &pass1.get_bind_group_layout(0),
            entries: &[
                vec![
                    storage(0, &pass1_params),
                    storage(3, &table),
                    storage(5, &depths),
                    storage(6, &order),
                ],
                mesh_entries(),
            ]
            .concat(),
        });
        let m2 = gpu.shader(
            "fragment-pt pass 2",
            &(decls(true) + include_str!("pass2.wgsl")),
        );
        let fs = match self.settings.shading {
            Shading::Average => "fs_average",
            Shading::Psi => "fs_psi",
        };
        // An explicit layout: each shading mode leaves some tables unused, and an automatic
        // layout would drop their bindings.
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let mut layout_entries = vec![buffer_entry(0, vf, wgpu::BufferBindingType::Uniform)];
        layout_entries.push(buffer_entry(4, vf, ro));
        layout_entries.extend([
            texture_entry(5, vf, false, wgpu::TextureViewDimension::D1),
            texture_entry(6, vf, false, wgpu::TextureViewDimension::D1),
            texture_entry(7, vf, false, wgpu::TextureViewDimension::D2),
        ]);
        layout_entries.extend((0..mesh_bindings).map(|i| buffer_entry(MESH_BINDING + i, vf, ro)));
        let pass2_layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("fragment-pt pass 2"),
                entries: &layout_entries,
            });
        let pipeline_layout =
            render_core::bind::pipeline_layout(gpu, "fragment-pt pass 2", &[Some(&pass2_layout)]);
        // Back to front, premultiplied: dst = src + (1 − src.a) · dst.
        let pass2 = gpu.triangle_pipeline(
            "fragment-pt pass 2",
            &pipeline_layout,
            &m2,
            "vs_main",
            fs,
            wgpu::TextureFormat::Rgba32Float,
            Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
            wgpu::ColorWrites::ALL,
        );
        let pass2_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fragment-pt pass 2"),
            layout: &pass2_layout,
            entries: &[
                vec![
                    storage(0, &pass2_params),
                    storage(4, &order),
                    view_entry(5, &tf),
                    view_entry(6, &expt),
                    view_entry(7, &psi),
                ],
                mesh_entries(),
            ]
            .concat(),
        });
        let gpu_sort = if self.settings.sort == SortMode::Gpu {
            Some(render_core::gpu_sort::GpuRadixSort::new(
                gpu,
                n as u32,
                &mut ledger,
            )?)
        } else {
            None
        };
        let visibility = if self.settings.sort == SortMode::Mpvonc {
            Some(render_core::visibility::VisibilitySorter::new(
                render_core::visibility::VisibilityOrder::Mpvonc,
            ))
        } else {
            None
        };
        let queries = if gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            let qs = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("fragment-pt timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 4,
            });
            let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("fragment-pt timestamp resolve"),
                size: 32,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            Some((qs, buf))
        } else {
            None
        };
        let range = optics.scalar_max - optics.scalar_min;
        let persistent = ledger.persistent;
        self.state = Some(State {
            mesh: std::sync::Arc::clone(mesh),
            tets: n as u32,
            ledger,
            model_bytes,
            pass1_params,
            pass2_params,
            records,
            dispatch,
            mesh_bindings,
            depths,
            order,
            pass1,
            pass1_bind,
            pass2,
            pass2_bind,
            target: None,
            queries,
            scalar_min: optics.scalar_min as f32,
            scalar_inv_range: if range > 0.0 {
                (1.0 / range) as f32
            } else {
                0.0
            },
            inv_length_unit: (1.0 / optics.length_unit.max(f64::MIN_POSITIVE)) as f32,
            indices: Vec::new(),
            radix: Default::default(),
            merge: Vec::new(),
            visibility,
            gpu_sort,
            fragments: Default::default(),
        });
        Ok(Prepared {
            persistent_bytes: persistent,
            tets: n,
        })
    }

    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        let sort_mode = self.settings.sort;
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
        frame::render(gpu, st, camera, sort_mode)
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
