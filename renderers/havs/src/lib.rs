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
mod description;
mod frame;
use frame::Draw;
pub mod kbuffer;
mod prepare;

use anyhow::{bail, Context};
use datasets::TetMesh;
use render_core::bind::check_storage_bindings;
use render_core::gpu::MemoryLedger;
use render_core::sort::RadixScratch;
use render_core::table_texture::TableTexture;
use render_core::{
    Camera, ChunkedBuffer, FrameStats, FrameTimer, Gpu, Image, Optics, Prepared, Renderer,
};

pub use description::{from_settings, DESCRIPTION};
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

/// The HAVS renderer.
pub struct Havs {
    pub settings: HavsSettings,
    state: Option<State>,
    /// Storage binding size to split at instead of the adapter's (tests of the split path).
    max_binding: Option<u64>,
}

impl Havs {
    pub fn new(settings: HavsSettings) -> Havs {
        Havs {
            settings,
            state: None,
            max_binding: None,
        }
    }

    /// Splits the vertex, face and order arrays at `bytes` per storage binding (rounded down
    /// to 256) instead of the adapter's limit. Only useful to test the split on small meshes.
    pub fn with_max_binding(mut self, bytes: u64) -> Havs {
        self.max_binding = Some(bytes);
        self
    }

    /// Bytes of every allocation so far (persistent and per frame), for reports.
    pub fn ledger(&self) -> Option<&MemoryLedger> {
        self.state.as_ref().map(|s| &s.ledger)
    }

    /// Per pixel of the last frame (row-major), as `fs_kbuffer_counting` counted them in
    /// `mode=fragment-race`: `[fragments the k-buffer took in, out-of-order pops before the
    /// drain pass, fragments shaded]` (`Pixel.info.y`, `.z` of `havs.wgsl`, racing, and the
    /// exact atomic count in `heads`). The last frame must be a counting frame: the first
    /// `render` of a view ends with one. For the test that holds the racy pass to its CPU twin
    /// ([`kbuffer`]); race-free mode keeps no per-pixel counts (zeros and list heads).
    pub fn read_pixel_counts(&self, gpu: &Gpu) -> anyhow::Result<Vec<[u32; 3]>> {
        let st = self
            .state
            .as_ref()
            .context("HAVS: read_pixel_counts before prepare")?;
        if !st.last_frame_counted {
            bail!("HAVS: the last frame counted nothing (only the first render of a view counts)");
        }
        let t = st
            .target
            .as_ref()
            .context("HAVS: read_pixel_counts before render")?;
        let n = t.width as u64 * t.height as u64;
        let bytes = gpu.read_buffer(&t.pixels, 0, n * 32)?;
        let px: &[[u32; 8]] = bytemuck::cast_slice(&bytes);
        let shaded = gpu.read_buffer(&t.heads, 0, n * 4)?;
        let shaded: &[u32] = bytemuck::cast_slice(&shaded);
        Ok(px
            .iter()
            .zip(shaded)
            .map(|(p, &s)| [p[5], p[6], s])
            .collect())
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
    rect_x0: u32,
    rect_y0: u32,
    _pad: u32,
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
/// for the layout test (`tests/gpu_layouts.rs`, through [`DESCRIPTION`]).
#[doc(hidden)]
pub fn gpu_layouts() -> render_core::gpu_layout::GpuLayouts {
    let structs = vec![
        render_core::rust_layout!(Uniforms => "havs.wgsl::Uniforms" {
            view_proj, eye, forward, width, height, flags, base_face, max_len, n_s, n_l,
            node_capacity, et_alpha, rect_x0, rect_y0, _pad
        }),
        render_core::rust_layout!(KeyUniforms => "keys.wgsl::KeyUniforms" { eye, forward, faces, _pad }),
    ];
    render_core::gpu_layout::GpuLayouts {
        structs,
        sources: vec![
            // `const K` in front, the shared k-buffer after, as `pipelines` composes it (any K:
            // the uniforms do not depend on it).
            (
                "havs.wgsl",
                format!(
                    "const K: u32 = 6u;\n{}\n{}",
                    include_str!("havs.wgsl"),
                    include_str!("kbuffer.wgsl")
                ),
            ),
            ("keys.wgsl", include_str!("keys.wgsl").into()),
        ],
    }
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
    verts: ChunkedBuffer,
    faces: ChunkedBuffer,
    num_faces: u64,
    /// Face centroids for the CPU sort.
    centroids: Vec<[f32; 3]>,
    /// The mesh's bounding box: the per-pixel passes cover only its screen rectangle.
    bounds: datasets::Aabb,
    /// The mesh, for the counters derived on the CPU once per view (`covering_faces`).
    host_mesh: std::sync::Arc<TetMesh>,
    face_work: render_core::silhouette::PerView<render_core::silhouette::FaceWork>,
    order: wgpu::Buffer,
    /// Face ranges of the order buffer that fit one storage binding each.
    chunks: Vec<std::ops::Range<u64>>,
    uniforms: Vec<wgpu::Buffer>,
    counters: wgpu::Buffer,
    table: TableTexture,
    /// The draw and drain pipelines. In `mode=fragment-race` the counting draw
    /// (`fs_kbuffer_counting`) runs in one untimed frame per view; the timed frames draw with
    /// `fs_kbuffer`, the paper's program, which counts nothing.
    pipes: prepare::Pipelines,
    /// The counts of the last view's counting frame (`counters` of havs.wgsl).
    counts: render_core::silhouette::PerView<[u32; 8]>,
    /// Whether the last frame drawn was a counting frame (its per-pixel counts are readable).
    last_frame_counted: bool,
    max_len: f32,
    n_s: u32,
    n_l: u32,
    /// The adapter cannot filter f32 textures: the table is sampled nearest.
    table_nearest: bool,
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
    let datasets::UniqueFaces {
        mut faces,
        boundary,
    } = mesh.unique_faces();
    let mut verts: Vec<[f32; 4]> = mesh
        .points
        .iter()
        .zip(&mesh.scalars)
        .map(|(p, &s)| [p[0], p[1], p[2], optics.normalise(s as f64) as f32])
        .collect();
    // Boundary faces are redirected to the vertex copies in place: at 20 M tets a second face
    // array would be 481 MB more at the prepare's peak.
    let mut copy = vec![u32::MAX; mesh.points.len()];
    for (f, _) in faces.iter_mut().zip(&boundary).filter(|(_, &b)| b) {
        *f = f.map(|v| {
            if copy[v as usize] == u32::MAX {
                let mut c = verts[v as usize];
                c[3] += 2.0;
                copy[v as usize] = verts.len() as u32;
                verts.push(c);
            }
            copy[v as usize]
        });
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

/// First binding of the vertex chunks in the draw/drain layout (faces follow them).
const MESH_BINDING: u32 = 11;
/// First binding of the vertex chunks in the GPU key pass (faces follow them).
const KEY_MESH_BINDING: u32 = 5;

/// WGSL of the chunked vertex and face arrays (`verts_at`, `faces_at`) from binding `first`.
fn mesh_decls(verts: &ChunkedBuffer, faces: &ChunkedBuffer, first: u32) -> String {
    verts.wgsl("verts", "vec4<f32>", 0, first, true)
        + &faces.wgsl("faces", "u32", 0, first + verts.bindings(), true)
}

fn shader_source(k: u32, decls: &str) -> String {
    format!(
        "const K: u32 = {k}u;\n{decls}\n{}\n{}\n{}",
        include_str!("havs.wgsl"),
        render_core::table_texture::TABLE_WGSL,
        include_str!("kbuffer.wgsl")
    )
}

impl Renderer for Havs {
    fn algorithm(&self) -> &'static str {
        "havs"
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
        let s = self.settings;
        if s.k < 1 || s.k > MAX_K {
            bail!("HAVS: k = {} is outside 1..={MAX_K}", s.k);
        }
        if s.table_scalar < 2 || s.table_length < 2 {
            bail!("HAVS: the pre-integrated table needs at least 2 entries per axis");
        }
        let mut ledger = MemoryLedger::default();
        let geometry = tagged_geometry(mesh, optics);
        let max_binding = match self.max_binding {
            Some(b) => b.min(gpu.max_storage_binding()) & !255,
            None => gpu.max_storage_binding(),
        }
        .max(256);
        let (verts, faces) = prepare::upload_mesh(gpu, &mut ledger, &geometry, max_binding)?;
        check_storage_bindings(gpu, "HAVS", 6 + verts.bindings() + faces.bindings())?;
        let num_faces = geometry.faces.len() as u64;
        let centroids = match s.sort {
            SortMode::CpuRadix => prepare::face_centroids(&geometry),
            SortMode::GpuRadix => Vec::new(),
        };
        drop(geometry);
        let max_len = mesh.quality().max_edge.max(f64::MIN_POSITIVE);
        let table = prepare::table(gpu, &mut ledger, optics, s, max_len)?;
        let prepare::OrderBuffers {
            order,
            chunks,
            uniforms,
            counters,
        } = prepare::OrderBuffers::new(gpu, &mut ledger, num_faces, max_binding)?;
        let pipes = prepare::Pipelines::new(gpu, s, &verts, &faces, table.filterable);
        let gpu_sort = match s.sort {
            SortMode::CpuRadix => None,
            SortMode::GpuRadix => Some(GpuSortState::new(
                gpu,
                &mut ledger,
                &verts,
                &faces,
                num_faces,
            )?),
        };
        let prepared = Prepared {
            persistent_bytes: ledger.persistent,
            tets: mesh.num_tets() as u64,
        };
        self.state = Some(State {
            ledger,
            verts,
            faces,
            num_faces,
            centroids,
            bounds: mesh.bounds(),
            host_mesh: mesh.clone(),
            face_work: Default::default(),
            order,
            chunks,
            uniforms,
            counters,
            table_nearest: !table.filterable,
            table,
            pipes,
            counts: Default::default(),
            last_frame_counted: false,
            max_len: max_len as f32,
            n_s: s.table_scalar,
            n_l: s.table_length,
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
            let (mut stats, counts) = match settings.mode {
                // The race-free mode's counts are its lists, made in its own frame.
                Mode::RaceFree => st.frame(gpu, settings, camera, Draw::Counting)?,
                // The timed frame draws with the paper's program; the counts come from one
                // counting frame of the same view, after it and outside its clock (the
                // harness books that time as its own, `harness_ms`).
                Mode::FragmentRace => {
                    let (stats, _) = st.frame(gpu, settings, camera, Draw::Timed)?;
                    let counts = match st.counts.kept(camera) {
                        Some(c) => c,
                        None => {
                            let (_, c) = st.frame(gpu, settings, camera, Draw::Counting)?;
                            st.counts.keep(camera, c);
                            c
                        }
                    };
                    (stats, counts)
                }
            };
            // Race-free mode: the node pool was too small for this view's fragments. Grow it
            // and render the frame again (the first frame of a new view pays this once).
            let needed = counts[3] as u64;
            let cap = st.target.as_ref().map(|t| t.node_capacity).unwrap_or(0);
            if settings.mode == Mode::RaceFree && needed > cap {
                st.ensure_target(gpu, settings, w, h, Some(needed + needed / 4))?;
                continue;
            }
            stats
                .counters
                .splice(0..0, frame::gpu_counters(settings.mode, &counts));
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
