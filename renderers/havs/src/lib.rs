//! HAVS: hardware-assisted visibility sorting (Callahan, Ikits, Comba, Silva, IEEE TVCG 2005).
//!
//! Object space (§3.1, §5.1): the mesh's unique triangles are sorted each frame by the
//! distance of their centroids from the eye, on the CPU with the LSD radix sort of §5.1 (or, as
//! a modern variant, on the GPU), and drawn front to back in that order. Image space (§3.2,
//! §4): each pixel keeps a k-buffer of `k` (scalar, depth) entries that completes the sort; the
//! two closest fragments give a ray segment whose colour and opacity come from the 3D
//! pre-integrated table (s_front, s_back, length), composited front to back. A screen pass
//! drains what is left after the last face.
//!
//! Two image-space modes: `fragment-race`, the paper's single pass whose fragment shader reads
//! and writes the pixel's k-buffer in storage and so races like the paper's render-to-texture
//! (§4, Fig. 5), and `race-free`, which first collects each pixel's fragments with their
//! submission index and then streams them in submission order through the same k-buffer code
//! (`kbuffer.wgsl`; CPU twin in [`kbuffer`]).

pub mod abuffer;
pub mod kbuffer;

use std::time::Instant;

use anyhow::{bail, Context};
use datasets::TetMesh;
use rayon::prelude::*;
use render_core::gpu::{Lifetime, MemoryLedger};
use render_core::preintegration::Table3d;
use render_core::sort::{radix_sort_indices, RadixScratch};
use render_core::{
    Camera, FrameStats, FrameTimer, Gpu, Image, Optics, Prepared, Renderer, Setting,
};

pub use kbuffer::{Tag, TagScheme};

/// Where the per-frame face sort runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SortMode {
    /// The paper: LSD radix sort of the centroid distances on the CPU (§5.1), then upload.
    CpuRadix,
    /// Modern variant: keys computed and radix-sorted on the GPU; nothing crosses the bus.
    GpuRadix,
}

impl SortMode {
    pub fn name(self) -> &'static str {
        match self {
            SortMode::CpuRadix => "cpu-radix",
            SortMode::GpuRadix => "gpu-radix",
        }
    }
}

/// How fragments reach the k-buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mode {
    /// The paper's single pass: read-modify-write of the k-buffer in the fragment shader,
    /// racing between fragments of one pixel (§4, Fig. 5).
    FragmentRace,
    /// Fragments appended to per-pixel lists with their submission index, then a compute pass
    /// streams each list in submission order through the k-buffer.
    RaceFree,
}

impl Mode {
    pub fn name(self) -> &'static str {
        match self {
            Mode::FragmentRace => "fragment-race",
            Mode::RaceFree => "race-free",
        }
    }
}

/// The paper's knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HavsSettings {
    /// k-buffer entries per pixel: 2–6 in the paper, also 8 and 16 here.
    pub k: u32,
    pub sort: SortMode,
    pub tags: TagScheme,
    pub mode: Mode,
    /// Early ray termination: stop a pixel once its opacity reaches
    /// [`kbuffer::EARLY_TERMINATION_ALPHA`].
    pub early_termination: bool,
    /// Entries per scalar axis and per length axis of the pre-integrated table.
    pub table_scalar: u32,
    pub table_length: u32,
}

impl Default for HavsSettings {
    fn default() -> Self {
        HavsSettings {
            k: 6,
            sort: SortMode::CpuRadix,
            tags: TagScheme::Two,
            mode: Mode::FragmentRace,
            early_termination: true,
            table_scalar: 128,
            table_length: 128,
        }
    }
}

/// Largest k the shaders are built for (the k-buffer lives in registers during a fragment).
pub const MAX_K: u32 = 16;

/// The variants `tetbench run` measures by default: k ∈ {2, 6} × sort ∈ {CPU, GPU}, faithful
/// single-pass mode (the paper's Tables 3 and 4 use k = 2 and k = 6).
pub fn default_variants() -> Vec<Box<dyn Renderer>> {
    let mut v: Vec<Box<dyn Renderer>> = Vec::new();
    for sort in [SortMode::CpuRadix, SortMode::GpuRadix] {
        for k in [2, 6] {
            v.push(Box::new(Havs::new(HavsSettings {
                k,
                sort,
                ..Default::default()
            })));
        }
    }
    v
}

/// Every combination the paper's analysis and this harness vary, from which `tetbench run
/// --settings …` selects: k ∈ {2, 3, 4, 5, 6, 8, 16} × sort × tag scheme × race mode × early
/// termination (the table sizes stay at their defaults).
pub fn all_variants() -> Vec<Box<dyn Renderer>> {
    let mut v: Vec<Box<dyn Renderer>> = Vec::new();
    for sort in [SortMode::CpuRadix, SortMode::GpuRadix] {
        for k in [2, 3, 4, 5, 6, 8, 16] {
            for tags in [TagScheme::Two, TagScheme::Single] {
                for mode in [Mode::FragmentRace, Mode::RaceFree] {
                    for early_termination in [true, false] {
                        v.push(Box::new(Havs::new(HavsSettings {
                            k,
                            sort,
                            tags,
                            mode,
                            early_termination,
                            ..Default::default()
                        })));
                    }
                }
            }
        }
    }
    v
}

/// The HAVS renderer.
pub struct Havs {
    pub settings: HavsSettings,
    state: Option<State>,
}

impl Havs {
    pub fn new(settings: HavsSettings) -> Havs {
        Havs {
            settings,
            state: None,
        }
    }

    /// Bytes of every allocation so far (persistent and per frame), for reports.
    pub fn ledger(&self) -> Option<&MemoryLedger> {
        self.state.as_ref().map(|s| &s.ledger)
    }

    /// Per pixel of the last frame (row-major), as `fs_kbuffer` counted them in
    /// `mode=fragment-race`: `[fragments the k-buffer took in, out-of-order pops before the
    /// drain pass]` (`Pixel.info.y`, `.z` of `havs.wgsl`). For the test that holds the racy
    /// pass to its CPU twin ([`kbuffer`]); race-free mode keeps no per-pixel counts (zeros).
    pub fn read_pixel_counts(&self, gpu: &Gpu) -> anyhow::Result<Vec<[u32; 2]>> {
        let t = self
            .state
            .as_ref()
            .and_then(|s| s.target.as_ref())
            .context("HAVS: read_pixel_counts before render")?;
        let n = t.width as u64 * t.height as u64;
        let bytes = gpu.read_buffer(&t.pixels, 0, n * 32)?;
        let px: &[[u32; 8]] = bytemuck::cast_slice(&bytes);
        Ok(px.iter().map(|p| [p[5], p[6]]).collect())
    }

    /// Per pixel of the last frame (row-major), in `mode=race-free`: the fragments `fs_append`
    /// stored, as `(v, d, submission index)` in list order (v = scalar + 2·tag, d = distance
    /// along the ray, as `fragment_entry` in `havs.wgsl` computes them). For the test that
    /// streams the GPU's own fragments through the CPU twin ([`kbuffer`]).
    pub fn read_fragment_lists(&self, gpu: &Gpu) -> anyhow::Result<Vec<Vec<(f32, f32, u32)>>> {
        let st = self
            .state
            .as_ref()
            .context("HAVS: read_fragment_lists before prepare")?;
        let t = st
            .target
            .as_ref()
            .context("HAVS: read_fragment_lists before render")?;
        if self.settings.mode != Mode::RaceFree {
            bail!("HAVS: fragment lists exist in mode=race-free only");
        }
        let npx = t.width as u64 * t.height as u64;
        let heads: Vec<u32> =
            bytemuck::cast_slice(&gpu.read_buffer(&t.heads, 0, npx * 4)?).to_vec();
        let used: u32 = bytemuck::cast_slice::<u8, u32>(&gpu.read_buffer(&st.counters, 12, 4)?)[0];
        let used = (used as u64).min(t.node_capacity);
        let nodes: Vec<[u32; 4]> = if used == 0 {
            vec![]
        } else {
            bytemuck::cast_slice(&gpu.read_buffer(&t._nodes, 0, used * 16)?).to_vec()
        };
        let mut lists = Vec::with_capacity(heads.len());
        for &h in &heads {
            let mut list = vec![];
            let mut cur = h;
            while cur != 0 {
                let n = nodes
                    .get(cur as usize - 1)
                    .context("HAVS: a fragment list points past the nodes written")?;
                list.push((f32::from_bits(n[0]), f32::from_bits(n[1]), n[2]));
                cur = n[3];
            }
            lists.push(list);
        }
        Ok(lists)
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Uniforms {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    forward: [f32; 4],
    width: u32,
    height: u32,
    flags: u32,
    base_face: u32,
    max_len: f32,
    n_s: f32,
    n_l: f32,
    node_capacity: u32,
    et_alpha: f32,
    _pad: [u32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct KeyUniforms {
    eye: [f32; 4],
    forward: [f32; 4],
    faces: u32,
    _pad: [u32; 3],
}

/// The `#[repr(C)]` structs this crate uploads to the GPU and the WGSL structs they mirror,
/// for the layout test (`tests/gpu_layouts.rs`).
#[doc(hidden)]
pub fn gpu_layouts() -> Vec<render_core::gpu_layout::RustLayout> {
    vec![
        render_core::rust_layout!(Uniforms => "havs.wgsl::Uniforms" {
            view_proj, eye, forward, width, height, flags, base_face, max_len, n_s, n_l,
            node_capacity, et_alpha, _pad
        }),
        render_core::rust_layout!(KeyUniforms => "keys.wgsl::KeyUniforms" { eye, forward, faces, _pad }),
    ]
}

/// Per-frame buffers for one viewport size.
struct Target {
    width: u32,
    height: u32,
    pixels: wgpu::Buffer,
    kentries: wgpu::Buffer,
    heads: wgpu::Buffer,
    _nodes: wgpu::Buffer,
    node_capacity: u64,
    dummy_view: wgpu::TextureView,
    bind_groups: Vec<wgpu::BindGroup>,
}

struct GpuSortState {
    sorter: render_core::gpu_sort::GpuRadixSort,
    keys: wgpu::Buffer,
    ids: wgpu::Buffer,
    key_uniforms: wgpu::Buffer,
    key_pipeline: wgpu::ComputePipeline,
    key_bind_group: wgpu::BindGroup,
}

struct State {
    ledger: MemoryLedger,
    verts: wgpu::Buffer,
    faces: wgpu::Buffer,
    num_faces: u64,
    /// Face centroids for the CPU sort.
    centroids: Vec<[f32; 3]>,
    order: wgpu::Buffer,
    /// Face ranges of the order buffer that fit one storage binding each.
    chunks: Vec<std::ops::Range<u64>>,
    uniforms: Vec<wgpu::Buffer>,
    counters: wgpu::Buffer,
    table_view: wgpu::TextureView,
    sampler: wgpu::Sampler,
    layout: wgpu::BindGroupLayout,
    draw_pipeline: wgpu::RenderPipeline,
    drain_pipeline: wgpu::ComputePipeline,
    max_len: f32,
    n_s: u32,
    n_l: u32,
    tets: u64,
    target: Option<Target>,
    timer: FrameTimer,
    scratch: RadixScratch,
    keys: Vec<f32>,
    sorted: Vec<u32>,
    gpu_sort: Option<GpuSortState>,
}

/// The vertex array HAVS draws from, and the faces as indices into it. Boundary faces use
/// copies of their vertices whose scalar carries +2: the paper's per-vertex boundary tag (§4),
/// so a fragment knows it lies on the boundary; whether it is an entry or an exit is decided in
/// the fragment shader from the face's orientation (boundary faces are wound outward).
pub fn tagged_geometry(mesh: &TetMesh, optics: &Optics) -> abuffer::Geometry {
    let uf = mesh.unique_faces();
    let mut verts: Vec<[f32; 4]> = mesh
        .points
        .iter()
        .zip(&mesh.scalars)
        .map(|(p, &s)| [p[0], p[1], p[2], optics.normalise(s as f64) as f32])
        .collect();
    let mut copy = vec![u32::MAX; mesh.points.len()];
    let mut faces = Vec::with_capacity(uf.faces.len());
    for (f, &b) in uf.faces.iter().zip(&uf.boundary) {
        if b {
            faces.push(f.map(|v| {
                if copy[v as usize] == u32::MAX {
                    let mut c = verts[v as usize];
                    c[3] += 2.0;
                    copy[v as usize] = verts.len() as u32;
                    verts.push(c);
                }
                copy[v as usize]
            }));
        } else {
            faces.push(*f);
        }
    }
    abuffer::Geometry { verts, faces }
}

/// Sort key of a point (HAVS §5.1: distance of the face centroid from the viewpoint), in f32
/// as the GPU computes it.
fn sort_key(eye: [f32; 3], forward: [f32; 3], perspective: bool, c: [f32; 3]) -> f32 {
    let r = [c[0] - eye[0], c[1] - eye[1], c[2] - eye[2]];
    if perspective {
        (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt()
    } else {
        r[0] * forward[0] + r[1] * forward[1] + r[2] * forward[2]
    }
}

fn shader_source(k: u32) -> String {
    format!(
        "const K: u32 = {k}u;\n{}\n{}",
        include_str!("havs.wgsl"),
        include_str!("kbuffer.wgsl")
    )
}

fn storage_entry(
    binding: u32,
    read_only: bool,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl Renderer for Havs {
    fn algorithm(&self) -> &'static str {
        "havs"
    }

    fn settings(&self) -> Vec<Setting> {
        let s = &self.settings;
        vec![
            Setting::new("k", s.k),
            Setting::new("sort", s.sort.name()),
            Setting::new(
                "tags",
                if s.tags == TagScheme::Two {
                    "two"
                } else {
                    "single"
                },
            ),
            Setting::new("mode", s.mode.name()),
            Setting::new("et", if s.early_termination { "on" } else { "off" }),
        ]
    }

    fn prepare(&mut self, gpu: &Gpu, mesh: &TetMesh, optics: &Optics) -> anyhow::Result<Prepared> {
        let s = self.settings;
        if s.k < 1 || s.k > MAX_K {
            bail!("HAVS: k = {} is outside 1..={MAX_K}", s.k);
        }
        if s.table_scalar < 2 || s.table_length < 2 {
            bail!("HAVS: the pre-integrated table needs at least 2 entries per axis");
        }
        let mut ledger = MemoryLedger::default();
        let abuffer::Geometry { verts, faces } = tagged_geometry(mesh, optics);
        let max_binding = gpu.max_storage_binding();
        let vert_bytes = verts.len() as u64 * 16;
        let face_bytes = faces.len() as u64 * 12;
        if vert_bytes > max_binding || face_bytes > max_binding {
            bail!(
                "HAVS: mesh {:?} needs {} vertex bytes and {} face bytes, over one storage binding ({} bytes) of {}",
                mesh.name,
                vert_bytes,
                face_bytes,
                max_binding,
                gpu.adapter.name
            );
        }
        let storage = wgpu::BufferUsages::STORAGE;
        let verts_buf = ledger.buffer_init(
            gpu,
            "havs vertices",
            Lifetime::Persistent,
            bytemuck::cast_slice(&verts),
            storage,
        )?;
        let faces_buf = ledger.buffer_init(
            gpu,
            "havs faces",
            Lifetime::Persistent,
            bytemuck::cast_slice(&faces),
            storage,
        )?;
        let num_faces = faces.len() as u64;
        let centroids: Vec<[f32; 3]> = faces
            .par_iter()
            .map(|f| {
                let p = f.map(|v| verts[v as usize]);
                [0, 1, 2].map(|a| (p[0][a] + p[1][a] + p[2][a]) / 3.0)
            })
            .collect();

        // The 3D pre-integrated table (s_front, s_back, length), lengths up to the longest
        // edge: no segment inside a tet is longer.
        let max_len = mesh.quality().max_edge.max(f64::MIN_POSITIVE);
        let table = Table3d::build(
            optics,
            s.table_scalar as usize,
            s.table_length as usize,
            max_len,
        );
        let (n_s, n_l) = (s.table_scalar, s.table_length);
        let tex = ledger.texture(
            gpu,
            Lifetime::Persistent,
            &wgpu::TextureDescriptor {
                label: Some("havs preintegration table"),
                size: wgpu::Extent3d {
                    width: n_s,
                    height: n_s,
                    depth_or_array_layers: n_l,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            },
        )?;
        gpu.queue.write_texture(
            tex.as_image_copy(),
            bytemuck::cast_slice(&table.data),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(n_s * 16),
                rows_per_image: Some(n_s),
            },
            wgpu::Extent3d {
                width: n_s,
                height: n_s,
                depth_or_array_layers: n_l,
            },
        );
        let table_view = tex.create_view(&Default::default());
        let filterable = gpu.features.contains(wgpu::Features::FLOAT32_FILTERABLE);
        let filter = if filterable {
            wgpu::FilterMode::Linear
        } else {
            wgpu::FilterMode::Nearest
        };
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("havs table sampler"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            address_mode_w: wgpu::AddressMode::ClampToEdge,
            mag_filter: filter,
            min_filter: filter,
            ..Default::default()
        });

        // The order buffer (face indices front to back) is bound in chunks that each fit one
        // storage binding, with offsets aligned as the device requires.
        let align_elems = (gpu.limits.min_storage_buffer_offset_alignment as u64 / 4).max(1);
        let per_chunk = ((max_binding / 4) / align_elems * align_elems).max(align_elems);
        let chunks: Vec<_> = (0..num_faces.div_ceil(per_chunk))
            .map(|i| i * per_chunk..((i + 1) * per_chunk).min(num_faces))
            .collect();
        let order = ledger.buffer(
            gpu,
            "havs face order",
            Lifetime::PerFrame,
            num_faces * 4,
            storage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        )?;
        let uniforms: Vec<wgpu::Buffer> = chunks
            .iter()
            .map(|_| {
                ledger.buffer(
                    gpu,
                    "havs uniforms",
                    Lifetime::PerFrame,
                    std::mem::size_of::<Uniforms>() as u64,
                    wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                )
            })
            .collect::<anyhow::Result<_>>()?;
        let counters = ledger.buffer(
            gpu,
            "havs counters",
            Lifetime::PerFrame,
            16,
            storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        )?;

        let all =
            wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let fc = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("havs layout"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: all,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Uniform,
                            has_dynamic_offset: false,
                            min_binding_size: None,
                        },
                        count: None,
                    },
                    storage_entry(1, true, all),
                    storage_entry(2, true, all),
                    storage_entry(3, true, all),
                    wgpu::BindGroupLayoutEntry {
                        binding: 4,
                        visibility: fc,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable },
                            view_dimension: wgpu::TextureViewDimension::D3,
                            multisampled: false,
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 5,
                        visibility: fc,
                        ty: wgpu::BindingType::Sampler(if filterable {
                            wgpu::SamplerBindingType::Filtering
                        } else {
                            wgpu::SamplerBindingType::NonFiltering
                        }),
                        count: None,
                    },
                    storage_entry(6, false, fc),
                    storage_entry(7, false, fc),
                    storage_entry(8, false, fc),
                    storage_entry(9, false, fc),
                    storage_entry(10, false, fc),
                ],
            });
        let pipeline_layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("havs pipeline layout"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
        let module = gpu.shader("havs", &shader_source(s.k));
        let fs_entry = match s.mode {
            Mode::FragmentRace => "fs_kbuffer",
            Mode::RaceFree => "fs_append",
        };
        // Every face is needed from both sides (entry and exit of a ray). wgpu needs an attachment;
        // the k-buffer lives in storage, so nothing is written to it.
        let draw_pipeline = gpu.triangle_pipeline(
            "havs draw",
            &pipeline_layout,
            &module,
            "vs",
            fs_entry,
            wgpu::TextureFormat::R8Unorm,
            None,
            wgpu::ColorWrites::empty(),
        );
        let drain_pipeline = gpu.compute_pipeline(
            "havs drain",
            Some(&pipeline_layout),
            &module,
            match s.mode {
                Mode::FragmentRace => "drain",
                Mode::RaceFree => "resolve_lists",
            },
        );

        let gpu_sort = match s.sort {
            SortMode::CpuRadix => None,
            SortMode::GpuRadix => Some(GpuSortState::new(
                gpu,
                &mut ledger,
                &verts_buf,
                &faces_buf,
                num_faces,
            )?),
        };

        let prepared = Prepared {
            persistent_bytes: ledger.persistent,
            tets: mesh.num_tets() as u64,
        };
        self.state = Some(State {
            ledger,
            verts: verts_buf,
            faces: faces_buf,
            num_faces,
            centroids,
            order,
            chunks,
            uniforms,
            counters,
            table_view,
            sampler,
            layout,
            draw_pipeline,
            drain_pipeline,
            max_len: max_len as f32,
            n_s,
            n_l,
            tets: mesh.num_tets() as u64,
            target: None,
            timer: FrameTimer::new(gpu),
            scratch: RadixScratch::default(),
            keys: Vec::new(),
            sorted: Vec::new(),
            gpu_sort,
        });
        Ok(prepared)
    }

    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        let settings = self.settings;
        let st = self
            .state
            .as_mut()
            .context("HAVS: render called before prepare")?;
        let (w, h) = (camera.width, camera.height);
        st.ensure_target(gpu, settings, w, h, None)?;
        loop {
            let stats = st.frame(gpu, settings, camera)?;
            // Race-free mode: the node pool was too small for this view's fragments. Grow it
            // and render the frame again (the first frame of a new view pays this once).
            let needed = stats
                .counters
                .iter()
                .find(|(n, _)| n == "nodes")
                .map(|c| c.1 as u64)
                .unwrap_or(0);
            let cap = st.target.as_ref().map(|t| t.node_capacity).unwrap_or(0);
            if settings.mode == Mode::RaceFree && needed > cap {
                st.ensure_target(gpu, settings, w, h, Some(needed + needed / 4))?;
                continue;
            }
            return Ok(stats);
        }
    }

    fn read_image(&mut self, gpu: &Gpu) -> anyhow::Result<Image> {
        let st = self
            .state
            .as_ref()
            .context("HAVS: read_image before prepare")?;
        let t = st
            .target
            .as_ref()
            .context("HAVS: read_image before render")?;
        let n = t.width as u64 * t.height as u64;
        let bytes = gpu.read_buffer(&t.pixels, 0, n * 32)?;
        let px: &[[f32; 8]] = bytemuck::cast_slice(&bytes);
        let mut img = Image::new(t.width, t.height);
        for (o, p) in img.pixels.iter_mut().zip(px) {
            *o = [p[0], p[1], p[2], p[3]];
        }
        Ok(img)
    }
}

impl GpuSortState {
    fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        verts: &wgpu::Buffer,
        faces: &wgpu::Buffer,
        num_faces: u64,
    ) -> anyhow::Result<GpuSortState> {
        if num_faces * 4 > gpu.max_storage_binding() {
            bail!("HAVS GPU sort: {num_faces} keys exceed one storage binding; use sort=cpu-radix");
        }
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let keys = ledger.buffer(
            gpu,
            "havs sort keys",
            Lifetime::PerFrame,
            num_faces * 4,
            usage,
        )?;
        let ids = ledger.buffer(
            gpu,
            "havs sort ids",
            Lifetime::PerFrame,
            num_faces * 4,
            usage,
        )?;
        let key_uniforms = ledger.buffer(
            gpu,
            "havs key uniforms",
            Lifetime::PerFrame,
            std::mem::size_of::<KeyUniforms>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let module = gpu.shader("havs keys", include_str!("keys.wgsl"));
        let key_pipeline = gpu.compute_pipeline("havs face keys", None, &module, "face_keys");
        let key_bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("havs keys"),
            layout: &key_pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: key_uniforms.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: verts.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: faces.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: keys.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: ids.as_entire_binding(),
                },
            ],
        });
        let sorter = render_core::gpu_sort::GpuRadixSort::new(gpu, num_faces as u32, ledger)?;
        Ok(GpuSortState {
            sorter,
            keys,
            ids,
            key_uniforms,
            key_pipeline,
            key_bind_group,
        })
    }
}

impl State {
    /// (Re)creates the per-frame buffers for a `w`×`h` viewport (and, in race-free mode, a node
    /// pool of `nodes` fragments).
    fn ensure_target(
        &mut self,
        gpu: &Gpu,
        s: HavsSettings,
        w: u32,
        h: u32,
        nodes: Option<u64>,
    ) -> anyhow::Result<()> {
        if let Some(t) = &self.target {
            if t.width == w && t.height == h && nodes.is_none() {
                return Ok(());
            }
        }
        // Forget the previous target's bytes before counting the new one.
        self.ledger.entries.retain(|(label, life, bytes)| {
            let keep = !label.starts_with("havs target ");
            if !keep && *life == Lifetime::PerFrame {
                self.ledger.per_frame -= bytes;
            }
            keep
        });
        let npx = w as u64 * h as u64;
        let max_binding = gpu.max_storage_binding();
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let pixels = self.ledger.buffer(
            gpu,
            "havs target pixels",
            Lifetime::PerFrame,
            npx * 32,
            usage,
        )?;
        let (kentries, heads, nodes_buf, node_capacity) = match s.mode {
            Mode::FragmentRace => {
                let bytes = npx * s.k as u64 * 8;
                if bytes > max_binding {
                    bail!("HAVS: a {w}x{h} k-buffer with k = {} needs {bytes} bytes, over one storage binding", s.k);
                }
                let kb = self.ledger.buffer(
                    gpu,
                    "havs target k-buffer",
                    Lifetime::PerFrame,
                    bytes,
                    usage,
                )?;
                let heads = self.ledger.buffer(
                    gpu,
                    "havs target unused heads",
                    Lifetime::PerFrame,
                    16,
                    usage,
                )?;
                let nodes = self.ledger.buffer(
                    gpu,
                    "havs target unused nodes",
                    Lifetime::PerFrame,
                    16,
                    usage,
                )?;
                (kb, heads, nodes, 0)
            }
            Mode::RaceFree => {
                // Start from a pool of 8 fragments per pixel; `render` grows it when a view needs more.
                let cap = nodes.unwrap_or(npx * 8).max(1024);
                if cap * 16 > max_binding {
                    bail!(
                        "HAVS race-free mode: {cap} fragments need {} bytes of lists, over one storage binding ({max_binding}); \
                         use mode=fragment-race or a smaller image",
                        cap * 16
                    );
                }
                let kb = self.ledger.buffer(
                    gpu,
                    "havs target unused k-buffer",
                    Lifetime::PerFrame,
                    16,
                    usage,
                )?;
                let heads = self.ledger.buffer(
                    gpu,
                    "havs target list heads",
                    Lifetime::PerFrame,
                    npx * 4,
                    usage,
                )?;
                let nodes = self.ledger.buffer(
                    gpu,
                    "havs target fragment lists",
                    Lifetime::PerFrame,
                    cap * 16,
                    usage,
                )?;
                (kb, heads, nodes, cap)
            }
        };
        let dummy = self.ledger.texture(
            gpu,
            Lifetime::PerFrame,
            &wgpu::TextureDescriptor {
                label: Some("havs target attachment"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R8Unorm,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            },
        )?;
        let dummy_view = dummy.create_view(&Default::default());
        let bind_groups = self
            .chunks
            .iter()
            .zip(&self.uniforms)
            .map(|(range, ub)| {
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("havs bind group"),
                    layout: &self.layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: ub.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: self.verts.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: self.faces.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 3,
                            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                buffer: &self.order,
                                offset: range.start * 4,
                                size: std::num::NonZeroU64::new(
                                    (range.end - range.start).max(1) * 4,
                                ),
                            }),
                        },
                        wgpu::BindGroupEntry {
                            binding: 4,
                            resource: wgpu::BindingResource::TextureView(&self.table_view),
                        },
                        wgpu::BindGroupEntry {
                            binding: 5,
                            resource: wgpu::BindingResource::Sampler(&self.sampler),
                        },
                        wgpu::BindGroupEntry {
                            binding: 6,
                            resource: pixels.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 7,
                            resource: kentries.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 8,
                            resource: self.counters.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 9,
                            resource: heads.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 10,
                            resource: nodes_buf.as_entire_binding(),
                        },
                    ],
                })
            })
            .collect();
        self.target = Some(Target {
            width: w,
            height: h,
            pixels,
            kentries,
            heads,
            _nodes: nodes_buf,
            node_capacity,
            dummy_view,
            bind_groups,
        });
        Ok(())
    }

    fn frame(&mut self, gpu: &Gpu, s: HavsSettings, camera: &Camera) -> anyhow::Result<FrameStats> {
        let eye = camera.eye.map(|c| c as f32);
        let fwd = camera.forward().map(|c| c as f32);
        let persp = camera.is_perspective();
        let mut stages = Vec::new();
        self.timer.start_wall();
        let t0 = Instant::now();

        // Object space: sort the faces front to back by centroid distance (§5.1).
        if s.sort == SortMode::CpuRadix {
            let cents = &self.centroids;
            self.keys.clear();
            self.keys
                .par_extend(cents.par_iter().map(|&c| sort_key(eye, fwd, persp, c)));
            let tk = t0.elapsed().as_secs_f64() * 1e3;
            radix_sort_indices(&self.keys, &mut self.sorted, &mut self.scratch);
            let ts = t0.elapsed().as_secs_f64() * 1e3;
            gpu.queue
                .write_buffer(&self.order, 0, bytemuck::cast_slice(&self.sorted));
            let tu = t0.elapsed().as_secs_f64() * 1e3;
            stages.push(("keys".to_string(), tk));
            stages.push(("sort".to_string(), ts - tk));
            stages.push(("upload".to_string(), tu - ts));
        }
        let t = self.target.as_ref().expect("target ensured");
        let flags = (s.tags == TagScheme::Two) as u32 | ((s.early_termination as u32) << 1);
        for (range, ub) in self.chunks.iter().zip(&self.uniforms) {
            let u = Uniforms {
                view_proj: camera.view_proj_f32(),
                eye: [eye[0], eye[1], eye[2], persp as u32 as f32],
                forward: [fwd[0], fwd[1], fwd[2], 0.0],
                width: t.width,
                height: t.height,
                flags,
                base_face: range.start as u32,
                max_len: self.max_len,
                n_s: self.n_s as f32,
                n_l: self.n_l as f32,
                node_capacity: t.node_capacity.min(u32::MAX as u64) as u32,
                et_alpha: kbuffer::EARLY_TERMINATION_ALPHA,
                _pad: [0; 3],
            };
            gpu.queue.write_buffer(ub, 0, bytemuck::bytes_of(&u));
        }
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.timer.begin(&mut enc);
        if let Some(gs) = &self.gpu_sort {
            let ku = KeyUniforms {
                eye: [eye[0], eye[1], eye[2], persp as u32 as f32],
                forward: [fwd[0], fwd[1], fwd[2], 0.0],
                faces: self.num_faces as u32,
                _pad: [0; 3],
            };
            gpu.queue
                .write_buffer(&gs.key_uniforms, 0, bytemuck::bytes_of(&ku));
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("havs keys"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&gs.key_pipeline);
                pass.set_bind_group(0, &gs.key_bind_group, &[]);
                let groups = self.num_faces.div_ceil(256) as u32;
                let max = gpu.limits.max_compute_workgroups_per_dimension;
                let (gx, gy) = if groups <= max {
                    (groups, 1)
                } else {
                    (max, groups.div_ceil(max))
                };
                pass.dispatch_workgroups(gx, gy, 1);
            }
            gs.sorter
                .encode(&mut enc, &gs.keys, &gs.ids, self.num_faces as u32, false)?;
            enc.copy_buffer_to_buffer(&gs.ids, 0, &self.order, 0, self.num_faces * 4);
        }
        enc.clear_buffer(&t.pixels, 0, None);
        enc.clear_buffer(&self.counters, 0, None);
        match s.mode {
            Mode::FragmentRace => enc.clear_buffer(&t.kentries, 0, None),
            Mode::RaceFree => enc.clear_buffer(&t.heads, 0, None),
        }
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("havs faces"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &t.dummy_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.draw_pipeline);
            // Chunks in order: the faces stay in sorted order across chunk boundaries.
            for (range, bg) in self.chunks.iter().zip(&t.bind_groups) {
                pass.set_bind_group(0, bg, &[]);
                pass.draw(0..((range.end - range.start) * 3) as u32, 0..1);
            }
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("havs drain"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.drain_pipeline);
            pass.set_bind_group(0, &t.bind_groups[0], &[]);
            pass.dispatch_workgroups(t.width.div_ceil(8), t.height.div_ceil(8), 1);
        }
        self.timer.end(&mut enc);
        let cpu_ms = t0.elapsed().as_secs_f64() * 1e3;
        gpu.queue.submit([enc.finish()]);
        gpu.wait()?;
        let total_ms = self.timer.wall_ms();
        let gpu_ms = self.timer.gpu_ms(gpu)?;
        let c = gpu.read_buffer(&self.counters, 0, 16)?;
        let c: &[u32] = bytemuck::cast_slice(&c);
        let mut counters = vec![
            ("fragments".to_string(), c[0] as f64),
            ("kbuffer_out_of_order".to_string(), c[1] as f64),
        ];
        if s.mode == Mode::RaceFree {
            counters.push(("lists_over_512".to_string(), c[2] as f64));
            counters.push(("nodes".to_string(), c[3] as f64));
        }
        counters.push(("faces".to_string(), self.num_faces as f64));
        let _ = self.tets;
        Ok(FrameStats {
            cpu_ms,
            gpu_ms,
            total_ms,
            frame_bytes: self.ledger.per_frame,
            stages,
            counters,
        })
    }
}
