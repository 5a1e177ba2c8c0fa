//! GPU objects of the ray caster: the bind group layouts and pipelines (created once per
//! mesh), and the per-viewport traversal buffers, peeling layers and tile parameters.

use render_core::bind;
use render_core::gpu::{LayoutEntries, Lifetime, MemoryLedger, RasterState};
use render_core::Gpu;

use render_core::table_texture::TableTexture;

use crate::layout::mesh_wgsl;

/// Slots of the statistics buffer (see `STAT_*` in cast.wgsl).
pub const STAT_SLOTS: usize = 8;
/// At most 6 × 6 tiles (the paper's largest tiling).
pub const MAX_TILES: usize = 36;

/// The frame parameters (`Frame` in common.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameParams {
    pub o0: [f32; 4],
    pub ox: [f32; 4],
    pub oy: [f32; 4],
    pub d0: [f32; 4],
    pub dx: [f32; 4],
    pub dy: [f32; 4],
    pub view_proj: [[f32; 4]; 4],
    pub size: [u32; 4],
    pub counts: [u32; 4],
    pub misc: [f32; 4],
    pub table: [u32; 4],
}

/// One tile's rectangle (`TileRect` in cast.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TileRect {
    pub origin: [u32; 2],
    pub end: [u32; 2],
}

/// The `#[repr(C)]` structs this crate uploads to the GPU and the WGSL structs they mirror,
/// for the layout test (`tests/gpu_layouts.rs`, through [`crate::DESCRIPTION`]).
#[doc(hidden)]
pub fn gpu_layouts() -> render_core::gpu_layout::GpuLayouts {
    let structs = vec![
        render_core::rust_layout!(FrameParams => "common.wgsl::Frame" {
            o0, ox, oy, d0, dx, dy, view_proj, size, counts, misc, table
        }),
        render_core::rust_layout!(TileRect => "cast.wgsl::TileRect" { origin, end }),
    ];
    render_core::gpu_layout::GpuLayouts {
        structs,
        sources: vec![
            ("common.wgsl", include_str!("common.wgsl").into()),
            (
                "cast.wgsl",
                format!(
                    "{}\n{}",
                    include_str!("common.wgsl"),
                    include_str!("cast.wgsl")
                ),
            ),
        ],
    }
}

/// Every stage the ray caster's bind groups are visible to.
const STAGES: wgpu::ShaderStages =
    wgpu::ShaderStages::VERTEX_FRAGMENT.union(wgpu::ShaderStages::COMPUTE);
/// The stages that read the ray caster's `Rgba32Uint` textures (the mesh, the peeled layers).
const TEXTURE_STAGES: wgpu::ShaderStages =
    wgpu::ShaderStages::FRAGMENT.union(wgpu::ShaderStages::COMPUTE);

pub const LAYER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// [`DEPTH_FORMAT`] with a stencil, where the device has it (`DEPTH32FLOAT_STENCIL8`): the
/// same depths, and a count of each pixel's candidates for the layer being peeled
/// ([`Pipelines::more`]).
pub const DEPTH_STENCIL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32FloatStencil8;

/// The depth format of the peel on `gpu`, and whether it has the stencil.
pub fn depth_format(gpu: &Gpu) -> (wgpu::TextureFormat, bool) {
    if gpu.features.contains(wgpu::Features::DEPTH32FLOAT_STENCIL8) {
        (DEPTH_STENCIL_FORMAT, true)
    } else {
        (DEPTH_FORMAT, false)
    }
}

/// Every fragment a peeling pass does not discard (the candidates for its layer) adds 1 to its
/// pixel's stencil, whether or not it is the nearest. The test is 0 ≤ stencil (reference 0),
/// true everywhere like `Always`, but a test that reads the reference makes wgpu set it: Vulkan
/// requires the dynamic reference of a stencil-testing pipeline to be set before it draws,
/// and wgpu sets it only for a test or op that uses it (the validation layer reported
/// VUID-vkCmdDraw-commandBuffer-02701 under `Always`).
const COUNT_CANDIDATES: wgpu::StencilFaceState = wgpu::StencilFaceState {
    compare: wgpu::CompareFunction::LessEqual,
    fail_op: wgpu::StencilOperation::Keep,
    depth_fail_op: wgpu::StencilOperation::IncrementClamp,
    pass_op: wgpu::StencilOperation::IncrementClamp,
};

/// Passes where the stencil holds more than the reference (set to 1: two candidates or more).
const MORE_THAN_REFERENCE: wgpu::StencilFaceState = wgpu::StencilFaceState {
    compare: wgpu::CompareFunction::Less,
    fail_op: wgpu::StencilOperation::Keep,
    depth_fail_op: wgpu::StencilOperation::Keep,
    pass_op: wgpu::StencilOperation::Keep,
};

/// The two pipelines of mode=passes drawn as rectangles (`tile_pass.wgsl`).
pub struct TilePipelines {
    /// One ray step per pixel; ended rays fail the early depth test.
    pub step: wgpu::RenderPipeline,
    /// The depth update: depth 0 where the ray has ended.
    pub cull: wgpu::RenderPipeline,
}

/// The depth format of the tile passes' early depth test (depth only).
pub const ZCULL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The bind-group layouts: group 0 (`mesh`) for every pipeline, then what each pass adds.
pub struct Layouts {
    /// The frame's parameters and the mesh textures ([`mesh_wgsl`]).
    pub mesh: wgpu::BindGroupLayout,
    /// The previous peeling layer (group 1 of `peel.wgsl`).
    pub peel: wgpu::BindGroupLayout,
    /// The traversal's buffers, the layers, the table and the pass flag (group 1 of `cast.wgsl`).
    pub cast: wgpu::BindGroupLayout,
    /// The probe's input and output (group 1 of `probe.wgsl`).
    pub probe: wgpu::BindGroupLayout,
    /// The frame's parameters as a uniform block for the peel and the tile passes (group 2).
    pub peel_frame: wgpu::BindGroupLayout,
}

impl Layouts {
    /// The layouts for a mesh in `textures` textures. The frame's and the pass's parameters are
    /// bound with [`bind::params_entry`] (set again every pass).
    fn new(gpu: &Gpu, textures: u32) -> Layouts {
        use wgpu::TextureViewDimension::{D2Array, D2};
        let table = TableTexture::layout_entries(TableTexture::filterable_on(gpu), 4, 10, STAGES);
        Layouts {
            mesh: LayoutEntries::new(STAGES)
                .params(0)
                .visible(TEXTURE_STAGES)
                .uint_texture(1..=textures, D2Array)
                .build(gpu, "raycast frame + mesh"),
            peel: LayoutEntries::new(TEXTURE_STAGES)
                .uint_texture(0, D2)
                .build(gpu, "raycast previous layer"),
            cast: LayoutEntries::new(STAGES)
                .read_write(0..=2)
                .read_write(5..=6)
                .read(7..=8)
                .params(9)
                .with(table)
                .visible(TEXTURE_STAGES)
                .uint_texture(3, D2Array)
                .build(gpu, "raycast traversal"),
            probe: LayoutEntries::new(STAGES)
                .read(0)
                .read_write(1)
                .build(gpu, "raycast probe"),
            peel_frame: LayoutEntries::new(wgpu::ShaderStages::VERTEX_FRAGMENT)
                .uniform(0)
                .build(gpu, "raycast peel frame"),
        }
    }
}

/// Layouts and pipelines, independent of the viewport.
pub struct Pipelines {
    pub layouts: Layouts,
    /// Phase 1 (§3.2): the first boundary entry per pixel.
    pub first: wgpu::RenderPipeline,
    /// Phase 2: the next boundary entry behind the previous layer's.
    pub peel: wgpu::RenderPipeline,
    /// With a stencil: a full-screen triangle that passes where a peeling pass left two
    /// candidates or more in a pixel. Drawn under an occlusion query after each layer, it
    /// says whether the next layer can hold anything: every candidate of layer l + 1 (λ beyond
    /// layer l's plus the bias) was a candidate of layer l besides layer l's own fragment. At
    /// 0 the empty pass that would find that out is not drawn.
    pub more: Option<wgpu::RenderPipeline>,
    pub init: wgpu::ComputePipeline,
    pub step: wgpu::ComputePipeline,
    /// mode=passes: a tile's rays that left their layer start again from the next.
    pub load_layer: wgpu::ComputePipeline,
    /// mode=passes as rectangles per tile (`tile_pass.wgsl`), where the device can force early
    /// depth tests; `None`: the compute pass `step`.
    pub tile_passes: Option<TilePipelines>,
    pub run_loop: wgpu::ComputePipeline,
    pub probe: wgpu::ComputePipeline,
}

/// The WGSL of the ray caster's modules, each after the shared prelude (texel records,
/// `common.wgsl`, the mesh's textures).
struct Sources {
    peel: String,
    cast: String,
    probe: String,
}

impl Sources {
    fn new(textures: usize, layers_per_texture: u32) -> Sources {
        let common = format!(
            "{}\n{}\n{}",
            render_core::texel_texture::TEXEL_WGSL,
            include_str!("common.wgsl"),
            mesh_wgsl(textures, layers_per_texture)
        );
        Sources {
            peel: format!(
                "{common}\n{}\n{}",
                include_str!("peel.wgsl"),
                bind::FULLSCREEN_WGSL
            ),
            cast: format!(
                "{common}\n{}\n{}",
                render_core::table_texture::TABLE_WGSL,
                include_str!("cast.wgsl")
            ),
            probe: format!("{common}\n{}", include_str!("probe.wgsl")),
        }
    }
}

/// The peel's pipelines (phases 1–2, §2.4 and §3.2): `first`, `peel` and `more`.
struct PeelPipelines {
    first: wgpu::RenderPipeline,
    peel: wgpu::RenderPipeline,
    more: Option<wgpu::RenderPipeline>,
}

impl PeelPipelines {
    fn new(gpu: &Gpu, layouts: &Layouts, source: &str) -> PeelPipelines {
        let module = gpu.shader("raycast peel", source);
        let (depth, stencil) = depth_format(gpu);
        let faces = [Some(wgpu::VertexBufferLayout {
            array_stride: 20,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32x2],
        })];
        let layer = [Some(wgpu::ColorTargetState::from(LAYER_FORMAT))];
        let faces_state = |fragment_entry| {
            let state = RasterState {
                vertex_buffers: &faces,
                // §2.4: only front-facing boundary faces (back faces culled); boundary faces
                // are wound counter-clockwise seen from outside the mesh.
                primitive: wgpu::PrimitiveState {
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode: Some(wgpu::Face::Back),
                    ..Default::default()
                },
                targets: &layer,
                ..RasterState::new("vs_face", fragment_entry)
            }
            .depth_test(depth, wgpu::CompareFunction::Less, true);
            if stencil {
                state.stencil(both_faces(COUNT_CANDIDATES, 0xff))
            } else {
                state
            }
        };
        let (mesh, peel, frame) = (&layouts.mesh, &layouts.peel, &layouts.peel_frame);
        // Group 1 (the previous layer) is unused by the first hit.
        let first_layout =
            bind::pipeline_layout(gpu, "raycast first hit", &[Some(mesh), None, Some(frame)]);
        let peel_layout = gpu.pipeline_layout("raycast peel", &[mesh, peel, frame]);
        let first = gpu.render_pipeline(
            "raycast first hit",
            &first_layout,
            &module,
            faces_state("fs_first"),
        );
        let peel = gpu.render_pipeline(
            "raycast peel",
            &peel_layout,
            &module,
            faces_state("fs_peel"),
        );
        let more = stencil.then(|| {
            let nothing = [Some(wgpu::ColorTargetState {
                write_mask: wgpu::ColorWrites::empty(),
                ..LAYER_FORMAT.into()
            })];
            let state = RasterState {
                targets: &nothing,
                ..RasterState::new("fullscreen_vs", "fs_nothing")
            }
            .depth_test(depth, wgpu::CompareFunction::Always, false)
            .stencil(both_faces(MORE_THAN_REFERENCE, 0));
            let layout = gpu.pipeline_layout("raycast more candidates", &[]);
            gpu.render_pipeline("raycast more candidates", &layout, &module, state)
        });
        PeelPipelines { first, peel, more }
    }
}

/// `face` on both sides, every stencil bit read, `write_mask`'s written.
fn both_faces(face: wgpu::StencilFaceState, write_mask: u32) -> wgpu::StencilState {
    wgpu::StencilState {
        front: face,
        back: face,
        read_mask: 0xff,
        write_mask,
    }
}

impl Pipelines {
    /// Layouts and pipelines for a mesh in `textures` array textures of `layers_per_texture`
    /// layers ([`mesh_wgsl`]). `tile_passes` (mode=passes): build [`TilePipelines`] where the
    /// device can force early depth tests.
    pub fn new(
        gpu: &Gpu,
        textures: usize,
        layers_per_texture: u32,
        tile_passes: bool,
    ) -> Pipelines {
        let layouts = Layouts::new(gpu, textures as u32);
        let sources = Sources::new(textures, layers_per_texture);
        let PeelPipelines { first, peel, more } = PeelPipelines::new(gpu, &layouts, &sources.peel);
        let (mesh, cast) = (&layouts.mesh, &layouts.cast);
        let cast_module = gpu.shader("raycast cast", &sources.cast);
        let [init, step, run_loop, load_layer] = gpu.compute_pipelines(
            "raycast",
            &[mesh, cast],
            &cast_module,
            ["init", "step", "run_loop", "load_layer"],
        );
        let probe_module = gpu.shader("raycast probe", &sources.probe);
        let [probe] =
            gpu.compute_pipelines("raycast", &[mesh, &layouts.probe], &probe_module, ["probe"]);
        let early_depth = gpu
            .features
            .contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST);
        let tile_passes = (tile_passes && early_depth).then(|| {
            let layout =
                gpu.pipeline_layout("raycast tile passes", &[mesh, cast, &layouts.peel_frame]);
            TilePipelines::build(gpu, &layout, &sources.cast)
        });
        Pipelines {
            layouts,
            first,
            peel,
            more,
            init,
            step,
            load_layer,
            tile_passes,
            run_loop,
            probe,
        }
    }
}

impl TilePipelines {
    /// The pipelines from `cast_src` (cast.wgsl with its prelude) and `tile_pass.wgsl`.
    fn build(gpu: &Gpu, layout: &wgpu::PipelineLayout, cast_src: &str) -> Self {
        let src = format!("{cast_src}\n{}", include_str!("tile_pass.wgsl"));
        TilePipelines::new(gpu, layout, &gpu.shader("raycast tile passes", &src))
    }

    fn new(gpu: &Gpu, layout: &wgpu::PipelineLayout, module: &wgpu::ShaderModule) -> Self {
        let pipeline = |label: &str, fs: &str, compare, write| {
            let state = RasterState::new("vs_tile", fs).depth_test(ZCULL_FORMAT, compare, write);
            gpu.render_pipeline(label, layout, module, state)
        };
        TilePipelines {
            // The rectangles lie at depth 0.5: in front of the clear (1), behind an ended ray (0).
            step: pipeline(
                "raycast tile step",
                "fs_step",
                wgpu::CompareFunction::Less,
                false,
            ),
            cull: pipeline(
                "raycast tile cull",
                "fs_cull",
                wgpu::CompareFunction::Always,
                true,
            ),
        }
    }
}

/// Everything sized by the viewport: traversal structures (the paper's Table 2: current cell
/// and colour, plus the layer index and step count per ray), the peeling layers, the depth
/// buffer, per-tile parameters and counters.
pub struct Target {
    pub width: u32,
    pub height: u32,
    pub rays: wgpu::Buffer,
    pub colours: wgpu::Buffer,
    pub aux: wgpu::Buffer,
    pub layers: wgpu::Texture,
    /// One view per layer (render attachments and the previous-layer input of peeling).
    pub layer_views: Vec<wgpu::TextureView>,
    pub depth_view: wgpu::TextureView,
    pub tile_rects: wgpu::Buffer,
    pub active_tiles: wgpu::Buffer,
    pub tile_counts: wgpu::Buffer,
    pub stats: wgpu::Buffer,
    /// `cast_binds[c]`: traversal bindings with the pass's count flag `c` (0: plain pass,
    /// 1: the pass that ends a round and counts active rays).
    pub cast_binds: [wgpu::BindGroup; 2],
    /// `peel_binds[l]` reads layer `l` (used while peeling layer `l + 1`).
    pub peel_binds: Vec<wgpu::BindGroup>,
    pub occlusion: wgpu::QuerySet,
    pub occlusion_resolve: wgpu::Buffer,
    /// The tile passes' depth ([`ZCULL_FORMAT`]): 0 where a ray has ended. Only with
    /// [`Pipelines::tile_passes`].
    pub zcull: Option<wgpu::TextureView>,
}

impl Target {
    /// `layer_slots` = maximum peeling layers + 1 (the slot that counts dropped re-entries).
    pub fn new(
        gpu: &Gpu,
        pipes: &Pipelines,
        ledger: &mut MemoryLedger,
        table: &TableTexture,
        width: u32,
        height: u32,
        layer_slots: u32,
    ) -> anyhow::Result<Target> {
        let pixels = width as u64 * height as u64;
        let mut storage = |label: &str, bytes: u64| {
            let usage = wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST;
            ledger.buffer(gpu, label, Lifetime::PerFrame, bytes, usage)
        };
        // The traversal (Table 2), then the tiles' rectangles and counts and the statistics.
        let rays = storage("raycast current cell", pixels * 16)?;
        let colours = storage("raycast colour", pixels * 16)?;
        let aux = storage("raycast layer + steps", pixels * 8)?;
        let tile_counts = storage("raycast tile counts", MAX_TILES as u64 * 4)?;
        let stats = storage("raycast stats", STAT_SLOTS as u64 * 4)?;
        let tile_rects = storage("raycast tile rectangles", MAX_TILES as u64 * 16)?;
        let active_tiles = storage("raycast active tiles", MAX_TILES as u64 * 4)?;
        let plain = pass_flag(gpu, ledger, 0)?;
        let counting = pass_flag(gpu, ledger, 1)?;
        let peeled = PeelLayers::new(gpu, ledger, (width, height), layer_slots)?;
        let (_, depth_view) = bind::render_target(
            gpu,
            ledger,
            "raycast depth",
            (width, height),
            depth_format(gpu).0,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )?;
        let [table_view, table_sampler] = table.bind_entries(4, 10);
        let cast_bind = |flag: &wgpu::Buffer| {
            let tiles = [&tile_counts, &stats, &tile_rects, &active_tiles, flag];
            let mut entries = bind::whole_from(0, &[&rays, &colours, &aux]);
            entries.push(bind::view_entry(3, &peeled.array));
            entries.push(table_view.clone());
            entries.extend(bind::whole_from(5, &tiles));
            entries.push(table_sampler.clone());
            gpu.bind_group("raycast traversal", &pipes.layouts.cast, &entries)
        };
        let cast_binds = [cast_bind(&plain), cast_bind(&counting)];
        let peel_binds = peeled
            .views
            .iter()
            .map(|v| {
                let entries = [bind::view_entry(0, v)];
                gpu.bind_group("raycast previous layer", &pipes.layouts.peel, &entries)
            })
            .collect();
        // Per layer l: queries 2l (the layer's samples) and 2l + 1 (pixels with more candidates,
        // `Pipelines::more`), resolved together at l × the alignment.
        let (occlusion, occlusion_resolve) = gpu.query_set(
            "raycast peel occlusion",
            wgpu::QueryType::Occlusion,
            2 * layer_slots,
            layer_slots as u64 * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT,
        );
        let zcull = pipes.tile_passes.is_some().then(|| {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
            let size = (width, height);
            bind::render_target(gpu, ledger, "raycast tile depth", size, ZCULL_FORMAT, usage)
                .map(|(_, view)| view)
        });
        Ok(Target {
            width,
            height,
            rays,
            colours,
            aux,
            layers: peeled.texture,
            layer_views: peeled.views,
            depth_view,
            tile_rects,
            active_tiles,
            tile_counts,
            stats,
            cast_binds,
            peel_binds,
            occlusion,
            occlusion_resolve,
            zcull: zcull.transpose()?,
        })
    }
}

/// The pass's parameter block: its count flag `c` (0: a plain pass, 1: the pass that ends a
/// round and counts active rays).
fn pass_flag(gpu: &Gpu, ledger: &mut MemoryLedger, c: u32) -> anyhow::Result<wgpu::Buffer> {
    let mut bytes = [0u8; 16];
    bytes[..4].copy_from_slice(&c.to_le_bytes());
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    ledger.buffer_init(gpu, "raycast pass flag", Lifetime::PerFrame, &bytes, usage)
}

/// The peeling layers' texture (one slot a layer), a view of each slot and one of them all.
struct PeelLayers {
    texture: wgpu::Texture,
    views: Vec<wgpu::TextureView>,
    array: wgpu::TextureView,
}

impl PeelLayers {
    fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        (width, height): (u32, u32),
        slots: u32,
    ) -> anyhow::Result<PeelLayers> {
        let texture = ledger.texture(
            gpu,
            Lifetime::PerFrame,
            &wgpu::TextureDescriptor {
                label: Some("raycast peeling layers"),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: slots,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: LAYER_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            },
        )?;
        let views = (0..slots)
            .map(|l| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("raycast layer"),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: l,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let array = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("raycast layers"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        Ok(PeelLayers {
            texture,
            views,
            array,
        })
    }
}
