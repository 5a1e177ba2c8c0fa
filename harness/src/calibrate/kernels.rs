//! The generic probes' workloads (`calibrate.wgsl`): small-triangle setup, fill, the
//! rasterisation of covering triangles at two sizes, compute throughput, storage-copy
//! bandwidth and the CPU radix sort. The work-specific ones are in `work.rs`.

use render_core::Gpu;

pub use crate::calibrate::workload::calibrate_source;
use crate::calibrate::workload::{Filler, ProbeContext, Workload};

const GRID: u64 = 256; // calibrate.wgsl GRID
const TRIANGLES: u64 = GRID * GRID * 2;
const FILL_SIZE: u32 = 512;
const FILL_LAYERS: u64 = 32;
pub(crate) const RASTER_SIZE: u32 = 512; // calibrate.wgsl RASTER_SIZE
const RASTER_TRIANGLES: u64 = 1 << 17;
/// The two leg lengths (pixels) of the rasterisation benchmark's right triangles.
pub(crate) const RASTER_LEGS: [u32; 2] = [4, 16];
const FMA_ITERS: u64 = 256; // calibrate.wgsl FMA_ITERS
const FMA_INVOCATIONS: u64 = 64 * 1024;
const COPY_BYTES: u64 = 32 << 20;
const SORT_KEYS: usize = 1 << 20;
/// The CPU sort's sizes (keys): the fastest is the figure.
const SORT_SIZES: [usize; 3] = [1 << 14, 1 << 17, SORT_KEYS];

/// The float format the algorithms composite into, where it blends on this device.
pub fn fill_format(gpu: &Gpu) -> wgpu::TextureFormat {
    if gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        wgpu::TextureFormat::Rgba32Float
    } else {
        wgpu::TextureFormat::Rgba16Float
    }
}

fn target(gpu: &Gpu, format: wgpu::TextureFormat, size: u32) -> wgpu::TextureView {
    gpu.device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("calibrate target"),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

/// One render pass that clears `view` and draws `vertices` × `instances`, submitted and
/// waited for.
fn draw(
    gpu: &Gpu,
    pipeline: &wgpu::RenderPipeline,
    view: &wgpu::TextureView,
    vertices: u32,
    instances: std::ops::Range<u32>,
) -> anyhow::Result<()> {
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = render_core::bind::color_pass(&mut enc, "calibrate", view, true, true, None);
        pass.set_pipeline(pipeline);
        pass.draw(0..vertices, instances);
    }
    gpu.queue.submit([enc.finish()]);
    gpu.wait()
}

/// One compute pass of `groups` workgroups, submitted and waited for.
pub fn dispatch(
    gpu: &Gpu,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    groups: u32,
) -> anyhow::Result<()> {
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass.dispatch_workgroups(groups, 1, 1);
    }
    gpu.queue.submit([enc.finish()]);
    gpu.wait()
}

/// Small-triangle setup: a grid of triangles covering one pixel centre or none.
pub fn triangle_setup<'g>(ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let gpu = ctx.gpu;
    let empty = empty_layout(gpu, "calibrate triangles");
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let pipeline = gpu.triangle_pipeline(
        "calibrate triangles",
        &empty,
        &ctx.module,
        "tri_vs",
        "tri_fs",
        format,
        None,
        wgpu::ColorWrites::ALL,
    );
    let view = target(gpu, format, GRID as u32);
    Ok(vec![Workload::split(
        TRIANGLES as f64,
        TRIANGLES as u32,
        move |k| draw(gpu, &pipeline, &view, k * 3, 0..1),
    )])
}

fn empty_layout(gpu: &Gpu, label: &str) -> wgpu::PipelineLayout {
    gpu.device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[],
            immediate_size: 0,
        })
}

/// Fill: viewport-sized triangles blended additively into the algorithms' float format.
pub fn fill<'g>(ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let gpu = ctx.gpu;
    let format = fill_format(gpu);
    let pipeline = additive_pipeline(gpu, &ctx.module, "calibrate fill", "fill_vs", format);
    let view = target(gpu, format, FILL_SIZE);
    let fragments = (FILL_SIZE as u64 * FILL_SIZE as u64 * FILL_LAYERS) as f64;
    Ok(vec![Workload::split(
        fragments,
        FILL_LAYERS as u32,
        move |k| draw(gpu, &pipeline, &view, 3, 0..k),
    )])
}

/// Rasterisation of covering triangles in the same format and blend, one workload per leg
/// length (the instance index is the leg); the parameter is its fragments per triangle.
pub fn rasterisation<'g>(ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let gpu = ctx.gpu;
    let format = fill_format(gpu);
    let pipeline = additive_pipeline(gpu, &ctx.module, "calibrate raster", "raster_vs", format);
    let view = target(gpu, format, RASTER_SIZE);
    Ok(RASTER_LEGS
        .map(|leg| {
            let (pipeline, view) = (pipeline.clone(), view.clone());
            Workload::split(RASTER_TRIANGLES as f64, RASTER_TRIANGLES as u32, move |k| {
                draw(gpu, &pipeline, &view, k * 3, leg..leg + 1)
            })
            .with_param(raster_fragments_per_triangle(leg))
        })
        .into())
}

fn storage(gpu: &Gpu, label: &str, bytes: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

/// Compute throughput: vec4 FMA chains; the units are GFLOP (1 FMA = 2 FLOPs).
pub fn compute<'g>(ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let gpu = ctx.gpu;
    let pipeline = gpu.compute_pipeline("calibrate fma", None, &ctx.module, "fma_main");
    let out = storage(gpu, "calibrate fma out", FMA_INVOCATIONS * 16);
    let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("calibrate fma"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[render_core::bind::whole(0, &out)],
    });
    let gflop = (FMA_INVOCATIONS * FMA_ITERS * 4 * 4 * 2) as f64 * 1e-9;
    let groups = (FMA_INVOCATIONS / 64) as u32;
    Ok(vec![Workload::split(gflop, groups, move |k| {
        dispatch(gpu, &pipeline, &bind, k)
    })])
}

/// Storage copy bandwidth (halved where one binding cannot hold 32 MiB); the units are bytes
/// read plus bytes written.
pub fn storage_copy<'g>(ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let gpu = ctx.gpu;
    let bytes = COPY_BYTES.min(gpu.max_storage_binding()) & !1023;
    let pipeline = gpu.compute_pipeline("calibrate copy", None, &ctx.module, "copy_main");
    let (src, dst) = (
        storage(gpu, "calibrate copy src", bytes),
        storage(gpu, "calibrate copy dst", bytes),
    );
    let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("calibrate copy"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            render_core::bind::whole(1, &src),
            render_core::bind::whole(2, &dst),
        ],
    });
    let groups = (bytes / 16).div_ceil(64);
    anyhow::ensure!(
        groups <= gpu.limits.max_compute_workgroups_per_dimension as u64,
        "calibration copy needs {groups} workgroups, more than the adapter allows"
    );
    // Each workgroup copies 64 × 16 bytes (the last may copy fewer: counted as many).
    Ok(vec![Workload::split(
        (2 * bytes) as f64,
        groups as u32,
        move |k| dispatch(gpu, &pipeline, &bind, k),
    )])
}

/// The CPU radix sort of `render_core::sort` (what HAVS' and the PT algorithms' CPU orders
/// run on) at several sizes: the rows sort from a few thousand keys (in cache) to millions,
/// and a peak must hold at every size a row sorts. Each size is checked to sort once here.
pub fn cpu_sort<'g>(_ctx: &ProbeContext<'g>) -> anyhow::Result<Vec<Workload<'g>>> {
    let mut fill = Filler(0x9E37_79B9_7F4A_7C15);
    let keys: std::sync::Arc<Vec<f32>> =
        std::sync::Arc::new((0..SORT_KEYS).map(|_| fill.unit()).collect());
    let mut out = vec![];
    for n in SORT_SIZES {
        let keys = keys.clone();
        let mut scratch = render_core::sort::RadixScratch::default();
        let mut indices: Vec<u32> = (0..n as u32).collect();
        render_core::sort::radix_sort_indices(&keys[..n], &mut indices, &mut scratch);
        anyhow::ensure!(
            indices
                .windows(2)
                .all(|w| keys[w[0] as usize] <= keys[w[1] as usize]),
            "the calibration's radix sort did not sort"
        );
        out.push(Workload::new(n as f64, move || {
            indices.clear();
            indices.extend(0..n as u32);
            render_core::sort::radix_sort_indices(&keys[..n], &mut indices, &mut scratch);
            Ok(())
        }));
    }
    Ok(out)
}

/// `calibrate.wgsl`'s `vertex_entry` with `fill_fs`, no bindings, blended additively into
/// `format` (as the cell-projection algorithms composite): the pipeline of the fill and
/// rasterisation benchmarks.
pub(crate) fn additive_pipeline(
    gpu: &Gpu,
    module: &wgpu::ShaderModule,
    label: &str,
    vertex_entry: &str,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let layout = empty_layout(gpu, label);
    let add = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    gpu.triangle_pipeline(
        label,
        &layout,
        module,
        vertex_entry,
        "fill_fs",
        format,
        Some(wgpu::BlendState {
            color: add,
            alpha: add,
        }),
        wgpu::ColorWrites::ALL,
    )
}

/// Fragments of one of the rasterisation benchmark's triangles: the pixel centres `(i, j)` of
/// its cell with `i + j < leg` (calibrate.wgsl, `raster_vs`).
pub fn raster_fragments_per_triangle(leg: u32) -> f64 {
    (leg as f64) * (leg as f64 + 1.0) / 2.0
}
