//! The calibration's work-specific probes (`calibrate.wgsl`), one per counter that no generic
//! figure prices: a ray step (`walk_main`), a splat fragment (`splat_cs`), a key of
//! render-core's GPU radix sort and a tet classification. Each prepares its configurations as
//! [`Workload`]s (see `probes.rs`).

use crate::calibrate::kernels::dispatch;
use crate::calibrate::workload::{Filler, ProbeContext, Workload};
use render_core::gpu::{Lifetime, MemoryLedger};
use render_core::gpu_sort::GpuRadixSort;
use render_core::table_texture::TableTexture;
use render_core::texel_texture::TexelTexture;
use render_core::Gpu;

/// Cells of the walk table (144 bytes each: 64 MiB of geometry + 8 MiB of neighbours).
const WALK_CELLS: u64 = 1 << 19;
const WALK_STEPS: u64 = 32; // calibrate.wgsl WALK_STEPS
const WALK_TABLE: u64 = 4096; // calibrate.wgsl WALK_TABLE
const WALK_INVOCATIONS: u64 = 32 * 1024;
const SPLAT_TARGET: u64 = 512; // calibrate.wgsl SPLAT_TARGET
const SPLAT_SLICE: u64 = 32; // calibrate.wgsl SPLAT_SLICE
const SPLAT_SLICES: u64 = 8; // slices of the table (q + o + 1 < 8 for q < 3, o < 5)
const SPLAT_RING: u64 = 5; // calibrate.wgsl SPLAT_RING
/// Square sides (pixels, even: each square then covers exactly side² centres) of the splat
/// benchmark. The default suite's footprints cover 80–90 pixels a voxel and slab (box:10k and
/// shell:10k at 128², `splat_fragments / splats`), the paper's volumes at 512² several
/// hundred: the sizes span both, and the fastest is the peak.
pub const SPLAT_SIDES: [u32; 4] = [4, 8, 16, 32];
/// Splat fragments per timed dispatch at every side (the squares are repeated to reach it).
const SPLAT_FRAGMENTS: u64 = 2 << 20;
const GPU_SORT_SIZES: [u32; 2] = [1 << 16, 1 << 18];

fn storage(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    label: &str,
    data: &[u8],
) -> anyhow::Result<wgpu::Buffer> {
    ledger.buffer_init(
        gpu,
        label,
        Lifetime::PerFrame,
        data,
        wgpu::BufferUsages::STORAGE,
    )
}

/// Ray steps per second: `WALK_INVOCATIONS` walks of `WALK_STEPS` dependent cell gathers, the
/// faster of two layouts: cells and table in storage buffers (`walk_main`), and cells in a
/// texture with the table a filtered 3D texture (`walk_tex_main`, the ray caster's layout).
pub fn ray_steps<'g>(ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let (gpu, module) = (ctx.gpu, &ctx.module);
    // Whole rows of the texture walk's 8192 texels (9 a cell, TEXEL_ROW): a multiple of 8192
    // cells.
    let cells = (WALK_CELLS.min(gpu.max_storage_binding() / 128) / 8192 * 8192).max(8192);
    let WalkMesh {
        geometry,
        next,
        table,
    } = walk_mesh(cells);
    let mut ledger = MemoryLedger::default();
    let cells_buf = storage(
        gpu,
        &mut ledger,
        "calibrate walk cells",
        bytemuck::cast_slice(&geometry),
    )?;
    let next_buf = storage(
        gpu,
        &mut ledger,
        "calibrate walk neighbours",
        bytemuck::cast_slice(&next),
    )?;
    let table_buf = storage(
        gpu,
        &mut ledger,
        "calibrate walk table",
        bytemuck::cast_slice(&table),
    )?;
    let out = ledger.buffer(
        gpu,
        "calibrate walk out",
        Lifetime::PerFrame,
        WALK_INVOCATIONS * 16,
        wgpu::BufferUsages::STORAGE,
    )?;
    let pipeline = gpu.compute_pipeline("calibrate walk", None, module, "walk_main");
    let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("calibrate walk"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            render_core::bind::whole(3, &cells_buf),
            render_core::bind::whole(4, &next_buf),
            render_core::bind::whole(5, &table_buf),
            render_core::bind::whole(6, &out),
        ],
    });
    let steps = (WALK_INVOCATIONS * WALK_STEPS) as f64;
    let walk = |pipeline: wgpu::ComputePipeline, bind: wgpu::BindGroup| {
        Workload::split(steps, (WALK_INVOCATIONS / 64) as u32, move |k| {
            dispatch(gpu, &pipeline, &bind, k)
        })
    };
    let storage_walk = walk(pipeline, bind);

    let (tex_pipeline, tex_bind) = texture_walk(
        gpu,
        &mut ledger,
        module,
        &out,
        WalkMesh {
            geometry,
            next,
            table,
        },
    )?;
    // The buffers and textures live as long as the bind groups that hold them.
    Ok(vec![storage_walk, walk(tex_pipeline, tex_bind)])
}

/// The walk's synthetic mesh: per cell four planes and a scalar gradient (8 texels), its
/// four neighbours, and the table it samples.
struct WalkMesh {
    geometry: Vec<[f32; 4]>,
    next: Vec<[u32; 4]>,
    table: Vec<[f32; 4]>,
}

/// `cells` cells of seeded values: four planes whose normals point to a tetrahedron's corners
/// (some face is always an exit), a scalar gradient, three filler texels; neighbours a few
/// cells to a few thousand cells ahead, as a mesh's tets are numbered.
fn walk_mesh(cells: u64) -> WalkMesh {
    let mut fill = Filler(0x2545_F491_4F6C_DD1D);
    let normals = [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    let mut geometry: Vec<[f32; 4]> = Vec::with_capacity(cells as usize * 8);
    for _ in 0..cells {
        for n in normals {
            geometry.push([n[0], n[1], n[2], 0.1 + fill.unit()]);
        }
        for _ in 0..4 {
            geometry.push([fill.unit(), fill.unit(), fill.unit(), fill.unit()]);
        }
    }
    let next: Vec<[u32; 4]> = (0..cells)
        .map(|c| [1u64, 97, 1031, 32771].map(|o| ((c + o) % cells) as u32))
        .collect();
    let table: Vec<[f32; 4]> = (0..WALK_TABLE)
        .map(|_| [fill.unit(), fill.unit(), fill.unit(), fill.unit() * 0.01])
        .collect();
    WalkMesh {
        geometry,
        next,
        table,
    }
}

/// The texture walk's pipeline and bind group: the same cells as texels (each its 8 geometry
/// texels, then its neighbours) and the table as a 3D texture, writing to `out`.
fn texture_walk(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    module: &wgpu::ShaderModule,
    out: &wgpu::Buffer,
    mesh: WalkMesh,
) -> anyhow::Result<(wgpu::ComputePipeline, wgpu::BindGroup)> {
    let WalkMesh {
        geometry,
        next,
        table,
    } = mesh;
    let mut texels: Vec<[u32; 4]> = Vec::with_capacity(next.len() * 9);
    for (c, n) in next.iter().enumerate() {
        texels.extend(
            geometry[c * 8..c * 8 + 8]
                .iter()
                .map(|g| g.map(f32::to_bits)),
        );
        texels.push(*n);
    }
    drop(geometry);
    let cells_tex = TexelTexture::new(
        gpu,
        ledger,
        "calibrate walk cells texture",
        Lifetime::PerFrame,
        TexelTexture::rows_for(texels.len()),
        1,
    )?;
    cells_tex.write_layer(gpu, 0, &texels);
    drop(texels);
    let side = (WALK_TABLE as f64).cbrt().round() as u32;
    let table_tex = TableTexture::new(
        gpu,
        ledger,
        "calibrate walk table texture",
        [side; 3],
        &table,
    )?;
    let compute = wgpu::ShaderStages::COMPUTE;
    let mut entries = vec![
        render_core::bind::storage_entry(6, compute, false),
        render_core::bind::sampled_texture_entry(
            14,
            compute,
            wgpu::TextureSampleType::Uint,
            wgpu::TextureViewDimension::D2Array,
        ),
    ];
    entries.extend(TableTexture::layout_entries(
        table_tex.filterable,
        15,
        16,
        compute,
    ));
    let tex_layout = gpu
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("calibrate texture walk"),
            entries: &entries,
        });
    let tex_pipeline = gpu.compute_pipeline(
        "calibrate texture walk",
        Some(&render_core::bind::pipeline_layout(
            gpu,
            "calibrate texture walk",
            &[Some(&tex_layout)],
        )),
        module,
        "walk_tex_main",
    );
    let mut bind_entries = vec![
        render_core::bind::whole(6, out),
        wgpu::BindGroupEntry {
            binding: 14,
            resource: wgpu::BindingResource::TextureView(&cells_tex.view),
        },
    ];
    bind_entries.extend(table_tex.bind_entries(15, 16));
    let tex_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("calibrate texture walk"),
        layout: &tex_layout,
        entries: &bind_entries,
    });
    Ok((tex_pipeline, tex_bind))
}

/// The two tables of the splat benchmark: 8 slices of 32² texels, one with no zero (every
/// term adds), one shaped like the splatter's kernel (kernel.rs: radius R = 2 grid spacings,
/// slabs 1 spacing thick, a ring of 5 slabs): slice k lies z_k = (k + ½)·5/8 − 2.5 slabs from
/// the voxel, its texels span ±R, and it holds 1 − r²/R² inside the ball of radius R and 0
/// outside, so the outermost slices are all zero and the zero terms skip their atomics as the
/// splatter's do.
pub fn splat_tables() -> [Vec<f32>; 2] {
    let mut fill = Filler(0x9E37_79B9_7F4A_7C15);
    let texels = (SPLAT_SLICES * SPLAT_SLICE * SPLAT_SLICE) as usize;
    let dense: Vec<f32> = (0..texels).map(|_| 0.05 + fill.unit()).collect();
    // Texel centres in units of R: across a slice −1 … 1; along the ring ±2.5 slabs, ±1.25 R.
    let centre = |i: u64, n: u64| (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
    let ball: Vec<f32> = (0..texels as u64)
        .map(|t| {
            let (k, y, x) = (
                t / (SPLAT_SLICE * SPLAT_SLICE),
                t / SPLAT_SLICE % SPLAT_SLICE,
                t % SPLAT_SLICE,
            );
            let (z, y, x) = (
                centre(k, SPLAT_SLICES) * 1.25,
                centre(y, SPLAT_SLICE),
                centre(x, SPLAT_SLICE),
            );
            (1.0 - x * x - y * y - z * z).max(0.0)
        })
        .collect();
    [dense, ball]
}

/// Squares per row of the splat benchmark's grid at `side` pixels: squares half a side apart,
/// the last one inside the 512² sheet, at most 128.
pub fn splat_grid(side: u32) -> u32 {
    let side = side as u64;
    ((SPLAT_TARGET - side) * 2 / side + 1).min(128) as u32
}

/// Splat fragments per second of the splatter's compute fill (`splat_cs`): the fastest of
/// every square side of [`SPLAT_SIDES`] with each of [`splat_tables`] (a roofline wants the
/// peak, and a row whose footprints are larger, or whose kernel has more zero terms, than
/// one configuration's would otherwise beat its bound), each with the table in a storage
/// buffer and, where the device filters `R32Float`, in a filtered 3D texture (`splat_tex_cs`,
/// the splatter's layout there: on lavapipe 1.6 times the storage table's rate).
pub fn splat_fill<'g>(ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let (gpu, module) = (ctx.gpu, &ctx.module);
    let mut ledger = MemoryLedger::default();
    let sheet = ledger.buffer(
        gpu,
        "calibrate splat sheet",
        Lifetime::PerFrame,
        SPLAT_TARGET * SPLAT_TARGET * 8 * SPLAT_RING,
        wgpu::BufferUsages::STORAGE,
    )?;
    let c = wgpu::ShaderStages::COMPUTE;
    let sampler = TableTexture::sampler(gpu, "calibrate splat table", true);
    // The storage table (binding 7) and, where the device filters R32Float, the texture (17,
    // with its sampler at 18), each with both tables.
    let mut out = vec![];
    let textures = [false, true];
    for texture in textures
        .into_iter()
        .filter(|&t| !t || TableTexture::filterable_on(gpu))
    {
        let mut entries = vec![
            render_core::bind::storage_entry(8, c, false),
            render_core::bind::storage_entry(9, c, true),
        ];
        if texture {
            entries.extend(TableTexture::layout_entries(true, 17, 18, c));
        } else {
            entries.push(render_core::bind::storage_entry(7, c, true));
        }
        let entry = if texture { "splat_tex_cs" } else { "splat_cs" };
        let group = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("calibrate splat"),
                entries: &entries,
            });
        let layout = render_core::bind::pipeline_layout(gpu, "calibrate splat", &[Some(&group)]);
        let pipeline = gpu.compute_pipeline("calibrate splat", Some(&layout), module, entry);
        for table in splat_tables() {
            let table = SplatTable::new(gpu, &mut ledger, &table, texture)?;
            for side in SPLAT_SIDES {
                let grid = splat_grid(side);
                let params = storage(
                    gpu,
                    &mut ledger,
                    "calibrate splat params",
                    bytemuck::cast_slice(&[side, grid, 0, 0]),
                )?;
                let mut bind_entries = vec![
                    render_core::bind::whole(8, &sheet),
                    render_core::bind::whole(9, &params),
                ];
                match &table {
                    SplatTable::Storage(b) => bind_entries.push(render_core::bind::whole(7, b)),
                    SplatTable::Texture(v) => bind_entries.extend([
                        wgpu::BindGroupEntry {
                            binding: 17,
                            resource: wgpu::BindingResource::TextureView(v),
                        },
                        wgpu::BindGroupEntry {
                            binding: 18,
                            resource: wgpu::BindingResource::Sampler(&sampler),
                        },
                    ]),
                }
                let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("calibrate splat"),
                    layout: &group,
                    entries: &bind_entries,
                });
                out.push(splat_workload(gpu, pipeline.clone(), bind, side));
            }
        }
    }
    Ok(out)
}

/// A table of [`splat_tables`] as the benchmark reads it: a storage buffer of its slices, or an
/// `R32Float` 3D texture of them, each slice bordered by a texel of zeros.
enum SplatTable {
    Storage(wgpu::Buffer),
    Texture(wgpu::TextureView),
}

impl SplatTable {
    fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        table: &[f32],
        texture: bool,
    ) -> anyhow::Result<SplatTable> {
        if !texture {
            let label = "calibrate splat table";
            return Ok(SplatTable::Storage(storage(
                gpu,
                ledger,
                label,
                bytemuck::cast_slice(table),
            )?));
        }
        let (n, bordered) = (SPLAT_SLICE as usize, SPLAT_SLICE as usize + 2);
        let mut texels = vec![0.0f32; bordered * bordered * SPLAT_SLICES as usize];
        for (row, values) in table.chunks_exact(n).enumerate() {
            let (k, y) = (row / n, row % n);
            let to = (k * bordered + y + 1) * bordered + 1;
            texels[to..to + n].copy_from_slice(values);
        }
        let view = render_core::bind::texture_with_data(
            gpu,
            ledger,
            "calibrate splat table texture",
            wgpu::TextureDimension::D3,
            wgpu::TextureFormat::R32Float,
            [bordered as u32, bordered as u32, SPLAT_SLICES as u32],
            bytemuck::cast_slice(&texels),
        )?
        .create_view(&Default::default());
        Ok(SplatTable::Texture(view))
    }
}

/// One configuration of the splat benchmark (`side`-pixel squares): enough workgroups for
/// [`SPLAT_FRAGMENTS`] footprint pixels.
fn splat_workload(
    gpu: &Gpu,
    pipeline: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    side: u32,
) -> Workload<'_> {
    let per_splat = side as u64 * side as u64 * SPLAT_RING;
    let groups = SPLAT_FRAGMENTS.div_ceil(per_splat * 256);
    Workload::split((groups * 256 * per_splat) as f64, groups as u32, move |k| {
        dispatch(gpu, &pipeline, &bind, k)
    })
}

/// Keys per second of render-core's GPU radix sort (HAVS' and fragment PT's device sorts):
/// the fastest of 2^16 and 2^18 f32 keys (an LSD radix sort costs about the same per key at
/// any size that fills the device, but a small sort pays its passes' fixed costs on fewer
/// keys, and a peak must hold at the rows' sizes; on lavapipe 2^20 took seconds).
pub fn gpu_sort<'g>(ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let gpu = ctx.gpu;
    let mut out = vec![];
    for size in GPU_SORT_SIZES {
        let n = size.min((gpu.max_storage_binding() / 4) as u32);
        let mut fill = Filler(0xD1B5_4A32_D192_ED03);
        let keys: Vec<f32> = (0..n).map(|_| fill.unit()).collect();
        let ids: Vec<u32> = (0..n).collect();
        let mut ledger = MemoryLedger::default();
        let sorter = GpuRadixSort::new(gpu, n, &mut ledger)?;
        let keys_buf = storage(
            gpu,
            &mut ledger,
            "calibrate sort keys",
            bytemuck::cast_slice(&keys),
        )?;
        let ids_buf = storage(
            gpu,
            &mut ledger,
            "calibrate sort ids",
            bytemuck::cast_slice(&ids),
        )?;
        // Sorted keys sort no faster: an LSD radix sort does the same passes on any input.
        out.push(Workload::new(n as f64, move || {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            sorter.encode(&mut enc, &keys_buf, &ids_buf, n, false)?;
            gpu.queue.submit([enc.finish()]);
            gpu.wait()
        }));
    }
    Ok(out)
}

/// Tets of the classification benchmark (a pass as long as a small mesh's, run often: see
/// `probes::best_seconds_of`).
const CLASSIFY_TETS: u64 = 1 << 15;

/// Tet classifications per second (`classify_cs`): the projection, orientation tests and
/// diagonal intersection every projected-tetrahedra classification does, on a jittered
/// lattice of 2^15 points with tets of nearby vertices (as a mesh numbers them).
pub fn classification<'g>(ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let (gpu, module) = (ctx.gpu, &ctx.module);
    let side = 32u64;
    let n = CLASSIFY_TETS;
    let mut fill = Filler(0x6A09_E667_F3BC_C908);
    let points: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let (x, y, z) = (i % side, i / side % side, i / (side * side));
            [
                x as f32 + 0.3 * fill.unit(),
                y as f32 + 0.3 * fill.unit(),
                z as f32 + 0.3 * fill.unit(),
                fill.unit(),
            ]
        })
        .collect();
    let tets: Vec<[u32; 4]> = (0..n)
        .map(|t| [t, t + 1, t + side, t + side * side].map(|v| (v % n) as u32))
        .collect();
    // A perspective view of the lattice from outside it (column-major, as WGSL reads it).
    let f = 1.0 / (side as f32 * 2.0);
    let matrix: [f32; 16] = [
        f,
        0.0,
        0.0,
        0.0, //
        0.0,
        f,
        0.0,
        0.0, //
        0.0,
        0.0,
        -f,
        0.5 * f, //
        -0.5,
        -0.5,
        1.0,
        3.0, //
    ];
    let mut ledger = MemoryLedger::default();
    let tets_buf = storage(
        gpu,
        &mut ledger,
        "calibrate classify tets",
        bytemuck::cast_slice(&tets),
    )?;
    let points_buf = storage(
        gpu,
        &mut ledger,
        "calibrate classify points",
        bytemuck::cast_slice(&points),
    )?;
    let matrix_buf = storage(
        gpu,
        &mut ledger,
        "calibrate classify matrix",
        bytemuck::cast_slice(&matrix),
    )?;
    let out = ledger.buffer(
        gpu,
        "calibrate classify out",
        Lifetime::PerFrame,
        n * 16,
        wgpu::BufferUsages::STORAGE,
    )?;
    let pipeline = gpu.compute_pipeline("calibrate classify", None, module, "classify_cs");
    let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("calibrate classify"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            render_core::bind::whole(10, &tets_buf),
            render_core::bind::whole(11, &points_buf),
            render_core::bind::whole(12, &matrix_buf),
            render_core::bind::whole(13, &out),
        ],
    });
    Ok(vec![Workload::new(n as f64, move || {
        dispatch(gpu, &pipeline, &bind, (n / 64) as u32)
    })])
}
