//! GPU objects of the ray caster: the bind group layouts and pipelines (created once per
//! mesh), and the per-viewport traversal buffers, peeling layers and tile parameters.

use render_core::bind;
use render_core::gpu::{Lifetime, MemoryLedger};
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

fn buffer_entry(
    binding: u32,
    ty: wgpu::BufferBindingType,
    dynamic: bool,
) -> wgpu::BindGroupLayoutEntry {
    let e = bind::buffer_entry(binding, STAGES, ty);
    if dynamic {
        bind::with_dynamic_offset(e)
    } else {
        e
    }
}

fn uint_texture_entry(binding: u32, dim: wgpu::TextureViewDimension) -> wgpu::BindGroupLayoutEntry {
    bind::sampled_texture_entry(
        binding,
        wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
        wgpu::TextureSampleType::Uint,
        dim,
    )
}

const RO: wgpu::BufferBindingType = wgpu::BufferBindingType::Storage { read_only: true };
const RW: wgpu::BufferBindingType = wgpu::BufferBindingType::Storage { read_only: false };

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

/// Layouts and pipelines, independent of the viewport.
pub struct Pipelines {
    pub mesh_layout: wgpu::BindGroupLayout,
    pub peel_layout: wgpu::BindGroupLayout,
    pub cast_layout: wgpu::BindGroupLayout,
    pub probe_layout: wgpu::BindGroupLayout,
    /// The frame's parameters as a uniform block for the peel (group 2; `peel.wgsl`).
    pub peel_frame_layout: wgpu::BindGroupLayout,
    pub first: wgpu::RenderPipeline,
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

impl Pipelines {
    /// Layouts and pipelines. The frame's and the pass's parameters are bound with
    /// [`bind::params_entry`] (set again every pass); the mesh is `textures` array textures of
    /// `layers_per_texture` layers ([`mesh_wgsl`]).
    /// `tile_passes` (mode=passes): build [`TilePipelines`] where the device can force early
    /// depth tests.
    pub fn new(
        gpu: &Gpu,
        textures: usize,
        layers_per_texture: u32,
        tile_passes: bool,
    ) -> Pipelines {
        let dev = &gpu.device;
        let mut mesh_entries = vec![bind::params_entry(0, STAGES)];
        mesh_entries.extend(
            (1..=textures as u32)
                .map(|b| uint_texture_entry(b, wgpu::TextureViewDimension::D2Array)),
        );
        let mesh_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raycast frame + mesh"),
            entries: &mesh_entries,
        });
        let peel_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raycast previous layer"),
            entries: &[uint_texture_entry(0, wgpu::TextureViewDimension::D2)],
        });
        let table_entries =
            TableTexture::layout_entries(TableTexture::filterable_on(gpu), 4, 10, STAGES);
        let cast_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raycast traversal"),
            entries: &[
                buffer_entry(0, RW, false),
                buffer_entry(1, RW, false),
                buffer_entry(2, RW, false),
                uint_texture_entry(3, wgpu::TextureViewDimension::D2Array),
                table_entries[0],
                buffer_entry(5, RW, false),
                buffer_entry(6, RW, false),
                buffer_entry(7, RO, false),
                buffer_entry(8, RO, false),
                bind::params_entry(9, STAGES),
                table_entries[1],
            ],
        });
        let peel_frame_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raycast peel frame"),
            entries: &[bind::uniform_entry(
                0,
                wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
            )],
        });
        let probe_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raycast probe"),
            entries: &[buffer_entry(0, RO, false), buffer_entry(1, RW, false)],
        });
        let common = format!(
            "{}\n{}\n{}",
            render_core::texel_texture::TEXEL_WGSL,
            include_str!("common.wgsl"),
            mesh_wgsl(textures, layers_per_texture)
        );
        let peel_src = format!(
            "{common}\n{}\n{}",
            include_str!("peel.wgsl"),
            render_core::bind::FULLSCREEN_WGSL
        );
        let cast_src = format!(
            "{common}\n{}\n{}",
            render_core::table_texture::TABLE_WGSL,
            include_str!("cast.wgsl")
        );
        let probe_src = format!("{common}\n{}", include_str!("probe.wgsl"));
        let peel_module = gpu.shader("raycast peel", &peel_src);
        let cast_module = gpu.shader("raycast cast", &cast_src);
        let probe_module = gpu.shader("raycast probe", &probe_src);
        let layout = |label: &str, groups: &[Option<&wgpu::BindGroupLayout>]| {
            render_core::bind::pipeline_layout(gpu, label, groups)
        };
        let first_layout = layout(
            "raycast first hit",
            &[Some(&mesh_layout), None, Some(&peel_frame_layout)],
        );
        let peel_pl = layout(
            "raycast peel",
            &[
                Some(&mesh_layout),
                Some(&peel_layout),
                Some(&peel_frame_layout),
            ],
        );
        let cast_pl = layout("raycast cast", &[Some(&mesh_layout), Some(&cast_layout)]);
        let probe_pl = layout("raycast probe", &[Some(&mesh_layout), Some(&probe_layout)]);
        let (depth, stencil) = depth_format(gpu);
        let raster = |label: &str, pl: &wgpu::PipelineLayout, fs: &str| {
            dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(pl),
                vertex: wgpu::VertexState {
                    module: &peel_module,
                    entry_point: Some("vs_face"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: 20,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32x2],
                    })],
                },
                // §2.4: only front-facing boundary faces (back faces culled); boundary faces are
                // wound counter-clockwise seen from outside the mesh.
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode: Some(wgpu::Face::Back),
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: depth,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: if stencil {
                        wgpu::StencilState {
                            front: COUNT_CANDIDATES,
                            back: COUNT_CANDIDATES,
                            read_mask: 0xff,
                            write_mask: 0xff,
                        }
                    } else {
                        Default::default()
                    },
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &peel_module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: LAYER_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let first = raster("raycast first hit", &first_layout, "fs_first");
        let peel = raster("raycast peel", &peel_pl, "fs_peel");
        let more = stencil.then(|| {
            dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("raycast more candidates"),
                layout: Some(&layout("raycast more candidates", &[])),
                vertex: wgpu::VertexState {
                    module: &peel_module,
                    entry_point: Some("fullscreen_vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: depth,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Always),
                    stencil: wgpu::StencilState {
                        front: MORE_THAN_REFERENCE,
                        back: MORE_THAN_REFERENCE,
                        read_mask: 0xff,
                        write_mask: 0,
                    },
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &peel_module,
                    entry_point: Some("fs_nothing"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: LAYER_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::empty(),
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        });
        let cast = |label, entry| gpu.compute_pipeline(label, Some(&cast_pl), &cast_module, entry);
        let (init, step) = (cast("raycast init", "init"), cast("raycast step", "step"));
        let run_loop = cast("raycast loop", "run_loop");
        let load_layer = cast("raycast load layer", "load_layer");
        let probe = gpu.compute_pipeline("raycast probe", Some(&probe_pl), &probe_module, "probe");
        let early_depth = gpu
            .features
            .contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST);
        let tile_passes = (tile_passes && early_depth).then(|| {
            let groups = [&mesh_layout, &cast_layout, &peel_frame_layout];
            TilePipelines::build(
                gpu,
                &layout("raycast tile passes", &groups.map(Some)),
                &cast_src,
            )
        });
        Pipelines {
            mesh_layout,
            peel_layout,
            cast_layout,
            probe_layout,
            peel_frame_layout,
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
            gpu.device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(layout),
                    vertex: wgpu::VertexState {
                        module,
                        entry_point: Some("vs_tile"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: Default::default(),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: ZCULL_FORMAT,
                        depth_write_enabled: Some(write),
                        depth_compare: Some(compare),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets: &[],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
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
        let storage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let rays = ledger.buffer(
            gpu,
            "raycast current cell",
            Lifetime::PerFrame,
            pixels * 16,
            storage,
        )?;
        let colours = ledger.buffer(
            gpu,
            "raycast colour",
            Lifetime::PerFrame,
            pixels * 16,
            storage,
        )?;
        let aux = ledger.buffer(
            gpu,
            "raycast layer + steps",
            Lifetime::PerFrame,
            pixels * 8,
            storage,
        )?;
        let tile_counts = ledger.buffer(
            gpu,
            "raycast tile counts",
            Lifetime::PerFrame,
            MAX_TILES as u64 * 4,
            storage,
        )?;
        let stats = ledger.buffer(
            gpu,
            "raycast stats",
            Lifetime::PerFrame,
            STAT_SLOTS as u64 * 4,
            storage,
        )?;
        let tile_rects = ledger.buffer(
            gpu,
            "raycast tile rectangles",
            Lifetime::PerFrame,
            MAX_TILES as u64 * 16,
            storage,
        )?;
        let active_tiles = ledger.buffer(
            gpu,
            "raycast active tiles",
            Lifetime::PerFrame,
            MAX_TILES as u64 * 4,
            storage,
        )?;
        let params = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let pass_flags: Vec<wgpu::Buffer> = (0..2u32)
            .map(|c| {
                let mut bytes = [0u8; 16];
                bytes[..4].copy_from_slice(&c.to_le_bytes());
                ledger.buffer_init(gpu, "raycast pass flag", Lifetime::PerFrame, &bytes, params)
            })
            .collect::<anyhow::Result<_>>()?;
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: layer_slots,
        };
        let layers = ledger.texture(
            gpu,
            Lifetime::PerFrame,
            &wgpu::TextureDescriptor {
                label: Some("raycast peeling layers"),
                size,
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
        let (_, depth_view) = bind::render_target(
            gpu,
            ledger,
            "raycast depth",
            (width, height),
            depth_format(gpu).0,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )?;
        let layer_views: Vec<wgpu::TextureView> = (0..layer_slots)
            .map(|l| {
                layers.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("raycast layer"),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: l,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let array_view = layers.create_view(&wgpu::TextureViewDescriptor {
            label: Some("raycast layers"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        fn buf(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }
        }
        let [table_view, table_sampler] = table.bind_entries(4, 10);
        let cast_bind = |flag: &wgpu::Buffer| {
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("raycast traversal"),
                layout: &pipes.cast_layout,
                entries: &[
                    buf(0, &rays),
                    buf(1, &colours),
                    buf(2, &aux),
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(&array_view),
                    },
                    table_view.clone(),
                    buf(5, &tile_counts),
                    buf(6, &stats),
                    buf(7, &tile_rects),
                    buf(8, &active_tiles),
                    buf(9, flag),
                    table_sampler.clone(),
                ],
            })
        };
        let cast_binds = [cast_bind(&pass_flags[0]), cast_bind(&pass_flags[1])];
        let peel_binds = layer_views
            .iter()
            .map(|v| {
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("raycast previous layer"),
                    layout: &pipes.peel_layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(v),
                    }],
                })
            })
            .collect();
        let occlusion = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("raycast peel occlusion"),
            ty: wgpu::QueryType::Occlusion,
            count: 2 * layer_slots,
        });
        // Per layer l: queries 2l (the layer's samples) and 2l + 1 (pixels with more candidates,
        // `Pipelines::more`), resolved together at l × the alignment.
        let occlusion_resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("raycast occlusion resolve"),
            size: layer_slots as u64 * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let zcull = if pipes.tile_passes.is_some() {
            let (_, view) = bind::render_target(
                gpu,
                ledger,
                "raycast tile depth",
                (width, height),
                ZCULL_FORMAT,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            )?;
            Some(view)
        } else {
            None
        };
        Ok(Target {
            width,
            height,
            rays,
            colours,
            aux,
            layers,
            layer_views,
            depth_view,
            tile_rects,
            active_tiles,
            tile_counts,
            stats,
            cast_binds,
            peel_binds,
            occlusion,
            occlusion_resolve,
            zcull,
        })
    }
}
