//! `tetbench calibrate`: a short, fixed micro-benchmark of the backend, and the roofline every
//! row gets from it.
//!
//! Nine figures, each from one kernel that stresses one resource (`calibrate.wgsl`):
//! small-triangle setup rate (triangles covering one pixel each), fill rate (a viewport-sized
//! triangle blended additively into the target format the algorithms use), rasterisation of
//! triangles that cover pixels (two sizes, fitted as a cost per triangle plus a cost per
//! fragment: small triangles cost far more per fragment than one viewport-sized triangle, and a
//! projected cell's are small), compute throughput
//! (vec4 FMA chains), storage-copy bandwidth (a compute copy between two storage buffers), the
//! CPU radix sort of `render_core::sort` (HAVS §5.1) in keys/s, and the work-specific ones of
//! `work.rs`: ray steps (a walk through 144-byte cells), splat fragments (a compute pass's
//! footprint lookup added into a two-u32 fixed-point sheet) and render-core's GPU radix sort.
//! Each figure is the best of five timed repetitions after one warm-up (a roofline wants the
//! backend's peak, and on a busy machine the best repetition is the one least disturbed), by
//! wall clock around submit-and-wait, so it is comparable with the rows' `total_ms`. The
//! result is cached per adapter, driver and CPU in the reference cache directory, so a run
//! pays for it once (a few seconds on lavapipe).
//!
//! The roofline ([`annotate`]) reads work counters, never names: each [`Resource`] lists the
//! counters that measure a row's work on it (`triangles`, `fragments`, `covering_tets`,
//! `splat_fragments`, `ray_steps`, `cpu_sort_keys`, `gpu_sort_keys`) with the calibrated cost
//! of one unit of each; a row's time on a resource is the sum of its counters times their
//! costs, plus per-frame GPU bytes (scratch, k-buffers, targets: each written at least once a
//! frame) over the copy bandwidth. The largest is the
//! bound (`roofline_ms`, `bound_by`), and `limit_fraction = roofline_ms / total_ms` says how
//! close the row gets to it. `normalized_time = total_ms / roofline_ms` is what
//! `compare --normalised` compares across machines. A renderer gets a meaningful bound by
//! reporting its work under these names (docs/roofline.md). The compute figure is recorded but
//! enters no row's roofline: no renderer reports its arithmetic count, and inventing one would
//! make the bound fiction.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use render_core::Gpu;

use crate::calibrate::work::best_seconds;
use crate::report::progress::Progress;
use crate::results::machine::MachineInfo;
use crate::results::Row;

pub mod floor;
pub mod work;

/// The calibration's kernels, with render-core's texel-texture addressing (`texel_at`).
fn calibrate_source() -> String {
    format!(
        "{}\n{}",
        include_str!("calibrate.wgsl"),
        render_core::texel_texture::TEXEL_WGSL
    )
}

/// Bumped whenever a kernel or its size changes (old cache files are then re-measured). 10:
/// the splat fill's filtered-texture variant (9 was a build taken back, whose cache files hold
/// a figure this one does not measure).
pub const CALIBRATION_VERSION: u32 = 10;

const GRID: u64 = 256; // calibrate.wgsl GRID
const TRIANGLES: u64 = GRID * GRID * 2;
const FILL_SIZE: u32 = 512;
const FILL_LAYERS: u64 = 32;
const RASTER_SIZE: u32 = 512; // calibrate.wgsl RASTER_SIZE
const RASTER_TRIANGLES: u64 = 1 << 17;
/// The two leg lengths (pixels) of the rasterisation benchmark's right triangles.
const RASTER_LEGS: [u32; 2] = [4, 16];
const FMA_ITERS: u64 = 256; // calibrate.wgsl FMA_ITERS
const FMA_INVOCATIONS: u64 = 64 * 1024;
const COPY_BYTES: u64 = 32 << 20;
const SORT_KEYS: usize = 1 << 20;
/// The CPU sort's sizes (keys): the fastest is the figure.
const SORT_SIZES: [usize; 3] = [1 << 14, 1 << 17, SORT_KEYS];

pub use crate::results::machine::Calibration;

fn driver_of(gpu: &Gpu) -> String {
    let a = &gpu.adapter;
    format!("{} {}", a.driver, a.driver_info).trim().to_string()
}

/// The cache file of this adapter + driver + CPU (the CPU matters: on lavapipe it *is* the GPU).
pub fn cache_path(cache_dir: &Path, gpu: &Gpu, machine: &MachineInfo) -> PathBuf {
    let key = format!(
        "v{CALIBRATION_VERSION}|{}|{}|{}|{}|{}",
        gpu.adapter.name,
        gpu.adapter.backend,
        driver_of(gpu),
        machine.cpu_model,
        machine.cpu_cores
    );
    let hex = blake3::hash(key.as_bytes()).to_hex();
    cache_dir.join("calibration").join(format!(
        "{}-{}.json",
        crate::results::names::slug(&gpu.adapter.name),
        &hex[..16]
    ))
}

/// The cached calibration if there is one for this backend, else a fresh measurement (then
/// cached). `force` always measures.
pub fn cached_or_measure(
    gpu: &Gpu,
    machine: &MachineInfo,
    cache_dir: &Path,
    force: bool,
) -> anyhow::Result<(Calibration, bool)> {
    let path = cache_path(cache_dir, gpu, machine);
    if !force {
        if let Some(c) = std::fs::read_to_string(&path)
            .ok()
            .and_then(|t| serde_json::from_str::<Calibration>(&t).ok())
            .filter(|c| c.version == CALIBRATION_VERSION)
        {
            return Ok((c, true));
        }
    }
    // A figure is a peak: a new measurement keeps, figure by figure, the faster of itself and
    // the cached one of this same backend (a repetition disturbed by other work on the machine
    // only ever makes a figure slower).
    let cached = std::fs::read_to_string(&path)
        .ok()
        .and_then(|t| serde_json::from_str::<Calibration>(&t).ok())
        .filter(|c| c.version == CALIBRATION_VERSION);
    let measured = measure(gpu, machine)?;
    let c = match &cached {
        Some(old) => measured.peak_with(old),
        None => measured,
    };
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    std::fs::write(&path, serde_json::to_string_pretty(&c)?)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok((c, false))
}

/// Runs the ten micro-benchmarks (seconds on an idle lavapipe, well under one on a GPU).
pub fn measure(gpu: &Gpu, machine: &MachineInfo) -> anyhow::Result<Calibration> {
    let started = Instant::now();
    // One step per benchmark (the rasterisation's two legs are two).
    let mut progress = Progress::new("tetbench calibrate", 11, "benchmarks");
    progress.activity("triangle setup");
    let module = gpu.shader("calibrate", &calibrate_source());
    let empty = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("calibrate raster"),
            bind_group_layouts: &[],
            immediate_size: 0,
        });
    let target = |format: wgpu::TextureFormat, size: u32| {
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
    };
    let draw = |pipeline: &wgpu::RenderPipeline,
                view: &wgpu::TextureView,
                vertices: u32,
                instances: std::ops::Range<u32>|
     -> anyhow::Result<()> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("calibrate"),
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
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(pipeline);
            pass.draw(0..vertices, instances);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.wait()
    };

    // 1. Small-triangle setup.
    let tri_format = wgpu::TextureFormat::Rgba8Unorm;
    let tri = gpu.triangle_pipeline(
        "calibrate triangles",
        &empty,
        &module,
        "tri_vs",
        "tri_fs",
        tri_format,
        None,
        wgpu::ColorWrites::ALL,
    );
    let tri_view = target(tri_format, GRID as u32);
    let tri_s = best_seconds(|| draw(&tri, &tri_view, (TRIANGLES * 3) as u32, 0..1))?;
    progress.step("triangle setup");

    // 2. Fill: the float format the algorithms composite into, when it blends here.
    let fill_format = if gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        wgpu::TextureFormat::Rgba32Float
    } else {
        wgpu::TextureFormat::Rgba16Float
    };
    let fill = additive_pipeline(gpu, &module, "calibrate fill", "fill_vs", fill_format);
    let fill_view = target(fill_format, FILL_SIZE);
    let fill_s = best_seconds(|| draw(&fill, &fill_view, 3, 0..FILL_LAYERS as u32))?;
    progress.step("fill");

    // 2b. Rasterisation of covering triangles, the same format and blend: seconds per triangle
    // at each leg length (the instance index is the leg), then the fit.
    let raster = additive_pipeline(gpu, &module, "calibrate raster", "raster_vs", fill_format);
    let raster_view = target(fill_format, RASTER_SIZE);
    let mut raster_points = [(0.0, 0.0); 2];
    for (point, leg) in raster_points.iter_mut().zip(RASTER_LEGS) {
        let vertices = (RASTER_TRIANGLES * 3) as u32;
        let s = best_seconds(|| draw(&raster, &raster_view, vertices, leg..leg + 1))?;
        *point = (
            raster_fragments_per_triangle(leg),
            s / RASTER_TRIANGLES as f64,
        );
        progress.step(&format!("rasterisation, leg {leg}"));
    }
    let (raster_seconds_per_triangle, raster_seconds_per_fragment) =
        raster_costs(raster_points[0], raster_points[1]);

    // 3. Compute throughput.
    let storage = |label: &str, bytes: u64| {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    };
    let dispatch = |pipeline: &wgpu::ComputePipeline,
                    bind: &wgpu::BindGroup,
                    groups: u32|
     -> anyhow::Result<()> {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(groups, 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.wait()
    };
    let fma = gpu.compute_pipeline("calibrate fma", None, &module, "fma_main");
    let fma_out = storage("calibrate fma out", FMA_INVOCATIONS * 16);
    let fma_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("calibrate fma"),
        layout: &fma.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: fma_out.as_entire_binding(),
        }],
    });
    let fma_s = best_seconds(|| dispatch(&fma, &fma_bind, (FMA_INVOCATIONS / 64) as u32))?;
    progress.step("compute");

    // 4. Storage copy bandwidth (halved where one binding cannot hold 32 MiB).
    let copy_bytes = COPY_BYTES.min(gpu.max_storage_binding()) & !1023;
    let copy = gpu.compute_pipeline("calibrate copy", None, &module, "copy_main");
    let (src, dst) = (
        storage("calibrate copy src", copy_bytes),
        storage("calibrate copy dst", copy_bytes),
    );
    let copy_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("calibrate copy"),
        layout: &copy.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 1,
                resource: src.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: dst.as_entire_binding(),
            },
        ],
    });
    let copy_groups = (copy_bytes / 16).div_ceil(64);
    anyhow::ensure!(
        copy_groups <= gpu.limits.max_compute_workgroups_per_dimension as u64,
        "calibration copy needs {copy_groups} workgroups, more than the adapter allows"
    );
    let copy_s = best_seconds(|| dispatch(&copy, &copy_bind, copy_groups as u32))?;
    progress.step("storage copy");

    // 5. CPU radix sort (what HAVS' and the PT algorithms' CPU orders run on).
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let keys: Vec<f32> = (0..SORT_KEYS)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        })
        .collect();
    // The fastest of several sizes: the rows sort from a few thousand keys (in cache) to
    // millions, and a peak must hold at every size a row sorts.
    let mut scratch = render_core::sort::RadixScratch::default();
    let mut indices = Vec::with_capacity(SORT_KEYS);
    let mut sort_keys_per_sec = 0.0f64;
    for n in SORT_SIZES {
        let keys = &keys[..n];
        let s = best_seconds(|| {
            indices.clear();
            indices.extend(0..n as u32);
            render_core::sort::radix_sort_indices(keys, &mut indices, &mut scratch);
            Ok(())
        })?;
        anyhow::ensure!(
            indices
                .windows(2)
                .all(|w| keys[w[0] as usize] <= keys[w[1] as usize]),
            "the calibration's radix sort did not sort"
        );
        sort_keys_per_sec = sort_keys_per_sec.max(n as f64 / s);
    }
    progress.step("CPU radix sort");

    // 6–8. The work of the counters no generic figure prices (work.rs).
    let ray_steps_per_sec = crate::calibrate::work::ray_steps_per_sec(gpu, &module)?;
    progress.step("ray steps");
    let splat_fragments_per_sec = crate::calibrate::work::splat_fragments_per_sec(gpu, &module)?;
    progress.step("splat fill");
    let gpu_sort_keys_per_sec = crate::calibrate::work::gpu_sort_keys_per_sec(gpu)?;
    progress.step("GPU radix sort");
    let tet_classifications_per_sec =
        crate::calibrate::work::tet_classifications_per_sec(gpu, &module)?;
    progress.step("vertex classification");
    progress.finish();

    Ok(Calibration {
        version: CALIBRATION_VERSION,
        adapter: gpu.adapter.name.clone(),
        driver: driver_of(gpu),
        cpu_model: machine.cpu_model.clone(),
        cpu_cores: machine.cpu_cores,
        date_utc: crate::results::machine::iso8601_utc(std::time::SystemTime::now()),
        seconds: started.elapsed().as_secs_f64(),
        triangles_per_sec: TRIANGLES as f64 / tri_s,
        fill_fragments_per_sec: (FILL_SIZE as u64 * FILL_SIZE as u64 * FILL_LAYERS) as f64 / fill_s,
        fill_format: format!("{fill_format:?}"),
        compute_gflops: (FMA_INVOCATIONS * FMA_ITERS * 4 * 4 * 2) as f64 / fma_s * 1e-9,
        copy_bytes_per_sec: (2 * copy_bytes) as f64 / copy_s,
        sort_keys_per_sec,
        ray_steps_per_sec,
        splat_fragments_per_sec,
        gpu_sort_keys_per_sec,
        tet_classifications_per_sec,
        raster_seconds_per_triangle,
        raster_seconds_per_fragment,
    })
}

/// `calibrate.wgsl`'s `vertex_entry` with `fill_fs`, no bindings, blended additively into
/// `format` (as the cell-projection algorithms composite): the pipeline of the fill and
/// rasterisation benchmarks.
fn additive_pipeline(
    gpu: &Gpu,
    module: &wgpu::ShaderModule,
    label: &str,
    vertex_entry: &str,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let layout = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[],
            immediate_size: 0,
        });
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

/// The straight line `t = a + f·b` through two (fragments per triangle, seconds per triangle)
/// points: `(a, b)`, the cost of a triangle and of each of its fragments. Each is at least 0,
/// since timing noise can tilt a two-point fit.
pub fn raster_costs(small: (f64, f64), large: (f64, f64)) -> (f64, f64) {
    let per_fragment = ((large.1 - small.1) / (large.0 - small.0)).max(0.0);
    let per_triangle = (small.1 - small.0 * per_fragment).max(0.0);
    (per_triangle, per_fragment)
}

// ---------------------------------------------------------------------------------------------
// Roofline
// ---------------------------------------------------------------------------------------------

/// A work counter's name and the calibrated seconds one unit of that work costs (0 where the
/// calibration did not measure it).
pub type CounterCost = (&'static str, fn(&Calibration) -> f64);

/// One resource of the roofline: the work counters a row reports on it, each at its own cost.
pub struct Resource {
    pub name: &'static str,
    pub costs: &'static [CounterCost],
}

/// Seconds per unit of a rate (0 for a rate not measured).
fn per(rate: f64) -> f64 {
    if rate > 0.0 {
        1.0 / rate
    } else {
        0.0
    }
}

/// What a triangle that yields fragments costs beyond its setup (the rasterisation fit's
/// per-triangle figure less the sub-pixel one).
fn covering_triangle_cost(c: &Calibration) -> f64 {
    (c.raster_seconds_per_triangle - per(c.triangles_per_sec)).max(0.0)
}

/// Every counter-priced resource. A renderer opts in by reporting the counter; nothing here
/// knows which renderer reports what.
pub const RESOURCES: [Resource; 8] = [
    Resource {
        name: "triangle setup",
        costs: &[("triangles", |c| per(c.triangles_per_sec))],
    },
    Resource {
        name: "fill",
        costs: &[("fragments", |c| per(c.fill_fragments_per_sec))],
    },
    // Every triangle costs at least its setup (the sub-pixel figure); one that yields fragments
    // costs the fit's per-triangle figure, and each fragment the fit's per-fragment one.
    // `covering_tets` (tets whose projection holds a pixel centre) is a lower bound of the
    // triangles that yield fragments: each such tet draws at least one. `covering_faces`
    // (faces drawn as one triangle each whose projection holds a pixel centre) counts them.
    // Rows without either (and calibrations without the fit) price no triangle above its setup.
    Resource {
        name: "rasterisation",
        costs: &[
            ("triangles", |c| {
                if c.raster_seconds_per_fragment > 0.0 || c.raster_seconds_per_triangle > 0.0 {
                    per(c.triangles_per_sec)
                } else {
                    0.0
                }
            }),
            ("covering_tets", covering_triangle_cost),
            ("covering_faces", covering_triangle_cost),
            ("fragments", |c| c.raster_seconds_per_fragment),
        ],
    },
    // `splat_fragments` counts every footprint pixel; early splat elimination skips the
    // lookups and atomics of those behind an opaque pixel (`ese_dropped_fragments`, the GPU's
    // exact count), so they are taken back: a bound must not price work the frame skipped.
    Resource {
        name: "splat fill",
        costs: &[
            ("splat_fragments", |c| per(c.splat_fragments_per_sec)),
            ("ese_dropped_fragments", |c| -per(c.splat_fragments_per_sec)),
        ],
    },
    Resource {
        name: "ray steps",
        costs: &[("ray_steps", |c| per(c.ray_steps_per_sec))],
    },
    Resource {
        name: "cpu sort",
        costs: &[("cpu_sort_keys", |c| per(c.sort_keys_per_sec))],
    },
    Resource {
        name: "gpu sort",
        costs: &[("gpu_sort_keys", |c| per(c.gpu_sort_keys_per_sec))],
    },
    // A resource of its own, not a term of `rasterisation`: a vertex stage's classification
    // may overlap the rasterisation of earlier triangles (llvmpipe bins and rasterises in
    // different threads), so only the larger of the two is a bound.
    Resource {
        name: "classification",
        costs: &[(
            "tet_classifications",
            |c| per(c.tet_classifications_per_sec),
        )],
    },
];

/// The time (ms) each modelled resource alone needs for the row's work: each resource whose
/// counters the row reports (and whose rate the calibration has), and the per-frame GPU bytes
/// (scratch, targets: each written at least once a frame) at the copy bandwidth.
pub fn resource_times(row: &Row, cal: &Calibration) -> Vec<(&'static str, f64)> {
    let mut t = vec![];
    for r in &RESOURCES {
        let priced: Vec<(f64, f64)> = r
            .costs
            .iter()
            .filter_map(|(counter, cost)| Some((row.counter(counter)?, cost(cal))))
            .filter(|&(_, cost)| cost != 0.0)
            .collect();
        // A negative cost takes back work a positive one counted but the frame skipped; the
        // resource is priced only where some work is counted, and never below 0.
        if priced.iter().any(|&(_, cost)| cost > 0.0) {
            let seconds: f64 = priced.iter().map(|(work, cost)| work * cost).sum();
            t.push((r.name, seconds.max(0.0) * 1e3));
        }
    }
    if let Some(b) = row.gpu_bytes_frame {
        if cal.copy_bytes_per_sec > 0.0 {
            t.push(("memory", b as f64 / cal.copy_bytes_per_sec * 1e3));
        }
    }
    t
}

/// Fills each measured row's roofline columns from `cal`.
pub fn annotate(rows: &mut [Row], cal: &Calibration) {
    for row in rows.iter_mut() {
        if row.total_ms.is_none_or(|t| t <= 0.0) {
            continue;
        }
        let bound = resource_times(row, cal)
            .into_iter()
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((name, ms)) = bound.filter(|b| b.1 > 0.0) {
            row.roofline_ms = Some(ms);
            row.bound_by = name.to_string();
            set_fraction(row);
        }
    }
}

/// Sets `limit_fraction` (roofline / total) and `normalized_time` (its inverse) from the row's
/// `roofline_ms` and `total_ms`: by [`annotate`], and again wherever a row's total changes
/// after it (rounds merged into one row, `ab`), so that the fraction is always the one of the
/// time the row reports.
pub fn set_fraction(row: &mut Row) {
    if let (Some(ms), Some(total)) = (row.roofline_ms, row.total_ms.filter(|t| *t > 0.0)) {
        row.limit_fraction = Some(ms / total);
        row.normalized_time = Some(total / ms);
    }
}

/// Whether the row's fastest timed frame beat its roofline (`roofline_ms > total_ms_min`). A
/// lower bound that a measured frame beats is a defect of the bound (a calibrated figure that
/// is not the backend's peak for that work, or a counter that counts work the frame did not
/// do), never a fast renderer: the run lists such rows.
pub fn beats_bound(row: &Row) -> bool {
    matches!((row.roofline_ms, row.total_ms_min), (Some(bound), Some(fastest)) if bound > fastest)
}

/// `tetbench calibrate`.
pub fn run_command(cache_dir: &Path, force: bool, json: bool) -> anyhow::Result<()> {
    let gpu = Gpu::new()?;
    let machine = MachineInfo::collect();
    let (cal, cached) = cached_or_measure(&gpu, &machine, cache_dir, force)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&cal)?);
    } else {
        println!("{}", cal.describe());
        println!(
            "{} {}",
            if cached { "cached in" } else { "stored in" },
            cache_path(cache_dir, &gpu, &machine).display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests;
