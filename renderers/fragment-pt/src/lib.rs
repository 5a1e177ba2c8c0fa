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

use std::time::Instant;

use anyhow::{anyhow, bail, Context};
use datasets::TetMesh;
use render_core::gpu::{Lifetime, MemoryLedger};
use render_core::sort;
use render_core::{Camera, FrameStats, Gpu, Image, Optics, Prepared, Renderer, Setting};

use classify::{packed_table, ZERO_AREA_REL};

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
/// for the layout test (`tests/gpu_layouts.rs`).
#[doc(hidden)]
pub fn gpu_layouts() -> Vec<render_core::gpu_layout::RustLayout> {
    vec![
        render_core::rust_layout!(Pass1Params => "pass1.wgsl::Params" { view_proj, eye, forward, misc, counts }),
        render_core::rust_layout!(Pass2Params => "pass2.wgsl::Params" { view_proj, misc, sizes }),
    ]
}

/// Everything uploaded by `prepare`.
struct State {
    mesh: TetMesh,
    tets: u32,
    ledger: MemoryLedger,
    model_bytes: u64,
    pass1_params: wgpu::Buffer,
    pass2_params: wgpu::Buffer,
    records: wgpu::Buffer,
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
}

/// Fragment PT renderer (`fragment-pt`).
pub struct FragmentPt {
    pub settings: FragmentPtSettings,
    state: Option<State>,
}

impl FragmentPt {
    pub fn new(settings: FragmentPtSettings) -> FragmentPt {
        FragmentPt {
            settings,
            state: None,
        }
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
        write_params(gpu, st, camera);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        encode_pass1(&mut enc, st, None);
        gpu.queue.submit([enc.finish()]);
        let n = st.tets as u64;
        let rec_bytes = gpu.read_buffer(&st.records, 0, n * RECORD_BYTES)?;
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

/// Both shadings × the paper's orders (bucket while moving, merge when still) and the
/// GPU-resident variant; `radix` and `mpvonc` are available through [`FragmentPtSettings`].
pub fn default_variants() -> Vec<Box<dyn Renderer>> {
    let mut v: Vec<Box<dyn Renderer>> = Vec::new();
    for shading in [Shading::Average, Shading::Psi] {
        for sort in [SortMode::Bucket, SortMode::Merge, SortMode::Gpu] {
            v.push(Box::new(FragmentPt::new(FragmentPtSettings {
                shading,
                sort,
            })));
        }
    }
    v
}

/// Every combination of shading and order (for `--settings` filters that ask for radix/mpvonc).
pub fn all_variants() -> Vec<Box<dyn Renderer>> {
    let mut v: Vec<Box<dyn Renderer>> = Vec::new();
    for shading in [Shading::Average, Shading::Psi] {
        for sort in SortMode::ALL {
            v.push(Box::new(FragmentPt::new(FragmentPtSettings {
                shading,
                sort,
            })));
        }
    }
    v
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

fn write_params(gpu: &Gpu, st: &State, camera: &Camera) {
    let p = project_params(st, camera);
    let p1 = Pass1Params {
        view_proj: p.view_proj,
        eye: [
            p.eye[0],
            p.eye[1],
            p.eye[2],
            if p.perspective { 1.0 } else { 0.0 },
        ],
        forward: [p.forward[0], p.forward[1], p.forward[2], 0.0],
        misc: [
            p.scalar_min,
            p.scalar_inv_range,
            p.inv_length_unit,
            ZERO_AREA_REL,
        ],
        counts: [st.tets, 0, 0, 0],
    };
    gpu.queue
        .write_buffer(&st.pass1_params, 0, bytemuck::bytes_of(&p1));
    let p2 = Pass2Params {
        view_proj: p.view_proj,
        misc: [p.scalar_min, p.scalar_inv_range, EXP_MAX_TAU, 0.0],
        sizes: [TF_ENTRIES as u32, EXP_ENTRIES as u32, PSI_SIDE as u32, 0],
    };
    gpu.queue
        .write_buffer(&st.pass2_params, 0, bytemuck::bytes_of(&p2));
}

fn encode_pass1(enc: &mut wgpu::CommandEncoder, st: &State, ts: Option<(&wgpu::QuerySet, u32)>) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some("fragment-pt pass 1"),
        timestamp_writes: ts.map(|(qs, i)| wgpu::ComputePassTimestampWrites {
            query_set: qs,
            beginning_of_pass_write_index: Some(i),
            end_of_pass_write_index: Some(i + 1),
        }),
    });
    pass.set_pipeline(&st.pass1);
    pass.set_bind_group(0, &st.pass1_bind, &[]);
    pass.dispatch_workgroups(st.tets.div_ceil(WORKGROUP), 1, 1);
}

fn storage(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
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

    fn settings(&self) -> Vec<Setting> {
        vec![
            Setting::new("shading", self.settings.shading.name()),
            Setting::new("sort", self.settings.sort.name()),
        ]
    }

    fn prepare(&mut self, gpu: &Gpu, mesh: &TetMesh, optics: &Optics) -> anyhow::Result<Prepared> {
        self.state = None;
        if !gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
            bail!(
                "fragment-pt: adapter {} cannot blend into Rgba32Float (FLOAT32_BLENDABLE)",
                gpu.adapter.name
            );
        }
        let n = mesh.num_tets() as u64;
        let max_binding = gpu.max_storage_binding();
        // One dispatch covers at most 65535 workgroups; the largest per-tet array (records, 32 B)
        // must fit one storage binding. Both allow ~4 M tets on lavapipe (128 MiB bindings).
        let max_tets = (max_binding / RECORD_BYTES).min(65535 * WORKGROUP as u64);
        if n > max_tets {
            bail!(
                "fragment-pt: mesh {} has {n} tets; this adapter allows at most {max_tets} \
                 (storage binding {max_binding} bytes)",
                mesh.name
            );
        }
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
        let vertices = ledger.buffer_init(
            gpu,
            "fragment-pt vertices",
            Lifetime::Persistent,
            bytemuck::cast_slice(&verts),
            storage_use,
        )?;
        let tet_buf = ledger.buffer_init(
            gpu,
            "fragment-pt tets",
            Lifetime::Persistent,
            bytemuck::cast_slice(&tets),
            storage_use,
        )?;
        let model_bytes = ledger.persistent;
        // View-independent tables (small; counted as persistent too).
        let table = ledger.buffer_init(
            gpu,
            "fragment-pt truth table",
            Lifetime::Persistent,
            bytemuck::cast_slice(&packed_table()),
            storage_use,
        )?;
        let tf = ledger.buffer_init(
            gpu,
            "fragment-pt transfer function",
            Lifetime::Persistent,
            bytemuck::cast_slice(&optics.tf.rgb_kappa_table(TF_ENTRIES)),
            storage_use,
        )?;
        let expt = ledger.buffer_init(
            gpu,
            "fragment-pt exp table",
            Lifetime::Persistent,
            bytemuck::cast_slice(&exp_table()),
            storage_use,
        )?;
        let psi_values: Vec<f32> = match self.settings.shading {
            Shading::Psi => render_core::preintegration::PsiTable::build(PSI_SIDE).data,
            // The average mode never reads ψ; bind a minimal buffer.
            Shading::Average => vec![0.0; 4],
        };
        let psi = ledger.buffer_init(
            gpu,
            "fragment-pt psi table",
            Lifetime::Persistent,
            bytemuck::cast_slice(&psi_values),
            storage_use,
        )?;
        // Per-frame buffers written by pass 1 and the sort.
        let records = ledger.buffer(
            gpu,
            "fragment-pt pass-1 records",
            Lifetime::PerFrame,
            n * RECORD_BYTES,
            storage_use | wgpu::BufferUsages::COPY_SRC,
        )?;
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

        let m1 = gpu.shader("fragment-pt pass 1", include_str!("pass1.wgsl"));
        let pass1 = gpu.compute_pipeline("fragment-pt pass 1", None, &m1, "classify");
        let pass1_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fragment-pt pass 1"),
            layout: &pass1.get_bind_group_layout(0),
            entries: &[
                storage(0, &pass1_params),
                storage(1, &vertices),
                storage(2, &tet_buf),
                storage(3, &table),
                storage(4, &records),
                storage(5, &depths),
                storage(6, &order),
            ],
        });
        let m2 = gpu.shader("fragment-pt pass 2", include_str!("pass2.wgsl"));
        let fs = match self.settings.shading {
            Shading::Average => "fs_average",
            Shading::Psi => "fs_psi",
        };
        // An explicit layout: each shading mode leaves some tables unused, and an automatic
        // layout would drop their bindings.
        let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let pass2_layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("fragment-pt pass 2"),
                entries: &[
                    entry(0, wgpu::BufferBindingType::Uniform),
                    entry(1, ro),
                    entry(2, ro),
                    entry(3, ro),
                    entry(4, ro),
                    entry(5, ro),
                    entry(6, ro),
                    entry(7, ro),
                ],
            });
        let pipeline_layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("fragment-pt pass 2"),
                bind_group_layouts: &[Some(&pass2_layout)],
                immediate_size: 0,
            });
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
                storage(0, &pass2_params),
                storage(1, &vertices),
                storage(2, &tet_buf),
                storage(3, &records),
                storage(4, &order),
                storage(5, &tf),
                storage(6, &expt),
                storage(7, &psi),
            ],
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
            mesh: mesh.clone(),
            tets: n as u32,
            ledger,
            model_bytes,
            pass1_params,
            pass2_params,
            records,
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
            let tex = st.ledger.texture(
                gpu,
                Lifetime::PerFrame,
                &wgpu::TextureDescriptor {
                    label: Some("fragment-pt target"),
                    size: wgpu::Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::Rgba32Float,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                },
            )?;
            let view = tex.create_view(&Default::default());
            st.target = Some((tex, view));
        }
        let started = Instant::now();
        write_params(gpu, st, camera);
        let qs = st.queries.as_ref().map(|(q, _)| q);
        let mut stages = Vec::new();
        let mut cpu_ms = 0.0;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        encode_pass1(&mut enc, st, qs.map(|q| (q, 0)));
        match sort_mode {
            SortMode::Gpu => {
                // Everything on the device: pass 1 wrote the centroid depths (keys) and the tet
                // ids (payload); sort both in place, far to near, then draw. No readback.
                let gs = st
                    .gpu_sort
                    .as_ref()
                    .ok_or_else(|| anyhow!("fragment-pt: GPU sort not prepared"))?;
                gs.encode(&mut enc, &st.depths, &st.order, st.tets, true)?;
            }
            _ => {
                gpu.queue.submit([enc.finish()]);
                enc = gpu.device.create_command_encoder(&Default::default());
                let t0 = Instant::now();
                let keys: Vec<f32> = if sort_mode == SortMode::Mpvonc {
                    Vec::new()
                } else {
                    // The paper reads the centroid depths pass 1 wrote back to the host.
                    let bytes = gpu.read_buffer(&st.depths, 0, st.tets as u64 * 4)?;
                    bytemuck::cast_slice(&bytes).to_vec()
                };
                let t1 = Instant::now();
                match sort_mode {
                    SortMode::Bucket => {
                        sort::bucket_sort_indices(
                            &keys,
                            sort::DEFAULT_SLABS,
                            true,
                            &mut st.indices,
                        );
                    }
                    SortMode::Merge => {
                        sort::merge_sort_indices(&keys, true, &mut st.indices, &mut st.merge)
                    }
                    SortMode::Radix => {
                        sort::radix_sort_indices_descending(&keys, &mut st.indices, &mut st.radix)
                    }
                    SortMode::Mpvonc => {
                        let v = st
                            .visibility
                            .as_mut()
                            .ok_or_else(|| anyhow!("fragment-pt: MPVONC not prepared"))?;
                        v.back_to_front(&st.mesh, camera, &mut st.indices);
                    }
                    SortMode::Gpu => unreachable!(),
                }
                if st.indices.len() != st.tets as usize {
                    bail!(
                        "fragment-pt: visibility order has {} entries for {} tets",
                        st.indices.len(),
                        st.tets
                    );
                }
                let t2 = Instant::now();
                gpu.queue
                    .write_buffer(&st.order, 0, bytemuck::cast_slice(&st.indices));
                let t3 = Instant::now();
                let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
                stages.push(("readback".to_string(), ms(t0, t1)));
                stages.push(("sort".to_string(), ms(t1, t2)));
                stages.push(("upload".to_string(), ms(t2, t3)));
                cpu_ms = ms(t0, t3);
            }
        }
        {
            let (_, view) = st.target.as_ref().expect("target created above");
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("fragment-pt pass 2"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: qs.map(|q| wgpu::RenderPassTimestampWrites {
                    query_set: q,
                    beginning_of_pass_write_index: Some(2),
                    end_of_pass_write_index: Some(3),
                }),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&st.pass2);
            pass.set_bind_group(0, &st.pass2_bind, &[]);
            pass.draw(0..st.tets * 12, 0..1);
        }
        if let Some((q, buf)) = &st.queries {
            enc.resolve_query_set(q, 0..4, buf, 0);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.wait()?;
        let total_ms = started.elapsed().as_secs_f64() * 1e3;
        let gpu_ms = match &st.queries {
            Some((_, buf)) => {
                let b = gpu.read_buffer(buf, 0, 32)?;
                let t: &[u64] = bytemuck::cast_slice(&b);
                let period = gpu.queue.get_timestamp_period() as f64 * 1e-6;
                let pass1 = t[1].saturating_sub(t[0]) as f64 * period;
                let pass2 = t[3].saturating_sub(t[2]) as f64 * period;
                stages.push(("classify".to_string(), pass1));
                stages.push(("draw".to_string(), pass2));
                if sort_mode == SortMode::Gpu {
                    // One submission: pass 1, the device sort and pass 2 back to back.
                    let all = t[3].saturating_sub(t[0]) as f64 * period;
                    stages.push(("gpu_sort".to_string(), (all - pass1 - pass2).max(0.0)));
                    Some(all)
                } else {
                    // The readback wait contains pass 1 on the GPU; only the rest is CPU time.
                    cpu_ms = (cpu_ms - pass1).max(0.0);
                    Some(pass1 + pass2)
                }
            }
            None => None,
        };
        Ok(FrameStats {
            cpu_ms,
            gpu_ms,
            total_ms,
            frame_bytes: st.ledger.per_frame,
            stages,
            counters: vec![(
                "model_bytes_per_tet".to_string(),
                st.model_bytes as f64 / st.tets.max(1) as f64,
            )],
        })
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
