//! `tetbench calibrate`: a short, fixed micro-benchmark of the backend, and the roofline every
//! row gets from it.
//!
//! Five figures, each from one kernel that stresses one resource (`calibrate.wgsl`):
//! small-triangle setup rate (triangles covering one pixel each), fill rate (a viewport-sized
//! triangle blended additively into the target format the algorithms use), compute throughput
//! (vec4 FMA chains), storage-copy bandwidth (a compute copy between two storage buffers) and
//! the CPU radix sort of `render_core::sort` (HAVS §5.1) in keys/s. Each figure is the best of
//! five timed repetitions after one warm-up (a roofline wants the backend's peak, and on a busy
//! machine the best repetition is the one least disturbed), by wall clock around
//! submit-and-wait, so it is comparable with the rows' `total_ms`. The result is cached per adapter, driver and CPU in the
//! reference cache directory, so a run pays for it once (a few seconds on lavapipe).
//!
//! The roofline ([`annotate`]): for each row, the time each modelled resource alone would need
//! for the row's work — triangles / setup rate, fragments / fill rate, per-frame GPU bytes
//! (scratch, k-buffers, targets: each written at least once a frame) / copy bandwidth, keys
//! sorted on the CPU / sort rate — the largest of them (`roofline_ms`,
//! `bound_by`) and how close the row gets to it (`limit_fraction = roofline_ms / total_ms`).
//! `normalized_time = total_ms / roofline_ms` is what `compare --normalised` compares across
//! machines. The compute figure is recorded but enters no row's roofline: no algorithm reports
//! its arithmetic count, and inventing one would make the bound fiction.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use render_core::Gpu;

use crate::machine::MachineInfo;
use crate::results::Row;

/// Bumped whenever a kernel or its size changes (old cache files are then re-measured).
pub const CALIBRATION_VERSION: u32 = 2;

const GRID: u64 = 256; // calibrate.wgsl GRID
const TRIANGLES: u64 = GRID * GRID * 2;
const FILL_SIZE: u32 = 512;
const FILL_LAYERS: u64 = 32;
const FMA_ITERS: u64 = 256; // calibrate.wgsl FMA_ITERS
const FMA_INVOCATIONS: u64 = 64 * 1024;
const COPY_BYTES: u64 = 32 << 20;
const SORT_KEYS: usize = 1 << 20;
const REPS: usize = 5;

pub use crate::machine::Calibration;

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
        crate::names::slug(&gpu.adapter.name),
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
    let c = measure(gpu, machine)?;
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    std::fs::write(&path, serde_json::to_string_pretty(&c)?)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok((c, false))
}

/// Best seconds of `REPS` runs of `f` after one warm-up.
fn best_seconds(mut f: impl FnMut() -> anyhow::Result<()>) -> anyhow::Result<f64> {
    f()?;
    let mut t = Vec::with_capacity(REPS);
    for _ in 0..REPS {
        let t0 = Instant::now();
        f()?;
        t.push(t0.elapsed().as_secs_f64());
    }
    Ok(t.into_iter().fold(f64::INFINITY, f64::min).max(1e-9))
}

/// Runs the five micro-benchmarks (a few seconds on lavapipe, well under one on a GPU).
pub fn measure(gpu: &Gpu, machine: &MachineInfo) -> anyhow::Result<Calibration> {
    let started = Instant::now();
    let module = gpu.shader("calibrate", include_str!("calibrate.wgsl"));
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
                instances: u32|
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
            pass.draw(0..vertices, 0..instances);
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
    let tri_s = best_seconds(|| draw(&tri, &tri_view, (TRIANGLES * 3) as u32, 1))?;

    // 2. Fill: the float format the algorithms composite into, when it blends here.
    let fill_format = if gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
        wgpu::TextureFormat::Rgba32Float
    } else {
        wgpu::TextureFormat::Rgba16Float
    };
    let add = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    let fill = gpu.triangle_pipeline(
        "calibrate fill",
        &empty,
        &module,
        "fill_vs",
        "fill_fs",
        fill_format,
        Some(wgpu::BlendState {
            color: add,
            alpha: add,
        }),
        wgpu::ColorWrites::ALL,
    );
    let fill_view = target(fill_format, FILL_SIZE);
    let fill_s = best_seconds(|| draw(&fill, &fill_view, 3, FILL_LAYERS as u32))?;

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
    let mut scratch = render_core::sort::RadixScratch::default();
    let mut indices = Vec::with_capacity(SORT_KEYS);
    let sort_s = best_seconds(|| {
        indices.clear();
        indices.extend(0..SORT_KEYS as u32);
        render_core::sort::radix_sort_indices(&keys, &mut indices, &mut scratch);
        Ok(())
    })?;
    anyhow::ensure!(
        indices
            .windows(2)
            .all(|w| keys[w[0] as usize] <= keys[w[1] as usize]),
        "the calibration's radix sort did not sort"
    );

    Ok(Calibration {
        version: CALIBRATION_VERSION,
        adapter: gpu.adapter.name.clone(),
        driver: driver_of(gpu),
        cpu_model: machine.cpu_model.clone(),
        cpu_cores: machine.cpu_cores,
        date_utc: crate::machine::iso8601_utc(std::time::SystemTime::now()),
        seconds: started.elapsed().as_secs_f64(),
        triangles_per_sec: TRIANGLES as f64 / tri_s,
        fill_fragments_per_sec: (FILL_SIZE as u64 * FILL_SIZE as u64 * FILL_LAYERS) as f64 / fill_s,
        fill_format: format!("{fill_format:?}"),
        compute_gflops: (FMA_INVOCATIONS * FMA_ITERS * 4 * 4 * 2) as f64 / fma_s * 1e-9,
        copy_bytes_per_sec: (2 * copy_bytes) as f64 / copy_s,
        sort_keys_per_sec: SORT_KEYS as f64 / sort_s,
    })
}

// ---------------------------------------------------------------------------------------------
// Roofline
// ---------------------------------------------------------------------------------------------

/// Triangles the row draws per frame: a `triangles` counter when the algorithm reports one,
/// else the algorithm's fixed count — GATOR draws each tet as the 4 triangles of its basis
/// graph (Wylie et al. 2002 §4), fragment PT 4 triangles per tet (Marroquim et al. 2006 §3.2,
/// `tets·12` vertices), HAVS each unique face once (Callahan et al. 2005 §4, the `faces` counter).
fn triangles(row: &Row) -> Option<f64> {
    row.counter("triangles")
        .or_else(|| match row.algorithm.as_str() {
            "gator-pt" | "fragment-pt" => Some(4.0 * row.tets as f64),
            "havs" => row.counter("faces"),
            _ => None,
        })
}

/// Keys the row sorts on the CPU per frame (none for the GPU-resident sorts).
fn cpu_sort_keys(row: &Row) -> Option<f64> {
    let sort = row.setting("sort")?;
    if sort.starts_with("gpu") {
        return None;
    }
    match row.algorithm.as_str() {
        "havs" => row.counter("faces"),
        "gator-pt" | "fragment-pt" => Some(row.tets as f64),
        _ => None,
    }
}

/// Fragments per frame: the row's `fragments` counter (HAVS counts every rasterised face
/// fragment); a projected-tetrahedra row borrows it from a HAVS row of the same data set, view
/// and size — a ray through the mesh yields one PT fragment per tet it crosses, i.e. about one
/// per face crossing, which is what HAVS counts.
fn fragments(row: &Row, rows: &[Row]) -> Option<f64> {
    row.counter("fragments").or_else(|| {
        rows.iter()
            .filter(|r| {
                r.algorithm == "havs"
                    && r.dataset == row.dataset
                    && r.viewpoint == row.viewpoint
                    && (r.width, r.height) == (row.width, row.height)
            })
            .find_map(|r| r.counter("fragments"))
            .filter(|_| matches!(row.algorithm.as_str(), "gator-pt" | "fragment-pt"))
    })
}

/// The time (ms) each modelled resource alone needs for the row's work.
pub fn resource_times(row: &Row, rows: &[Row], cal: &Calibration) -> Vec<(&'static str, f64)> {
    let mut t = vec![];
    if let Some(n) = triangles(row) {
        t.push(("triangle setup", n / cal.triangles_per_sec * 1e3));
    }
    if let Some(n) = fragments(row, rows) {
        t.push(("fill", n / cal.fill_fragments_per_sec * 1e3));
    }
    if let Some(b) = row.gpu_bytes_frame {
        t.push(("memory", b as f64 / cal.copy_bytes_per_sec * 1e3));
    }
    if let Some(n) = cpu_sort_keys(row) {
        t.push(("cpu sort", n / cal.sort_keys_per_sec * 1e3));
    }
    t
}

/// Fills each measured row's roofline columns from `cal`.
pub fn annotate(rows: &mut [Row], cal: &Calibration) {
    let snapshot = rows.to_vec();
    for row in rows.iter_mut() {
        let Some(total) = row.total_ms.filter(|t| *t > 0.0) else {
            continue;
        };
        let bound = resource_times(row, &snapshot, cal)
            .into_iter()
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((name, ms)) = bound.filter(|b| b.1 > 0.0) {
            row.roofline_ms = Some(ms);
            row.bound_by = name.to_string();
            row.limit_fraction = Some(ms / total);
            row.normalized_time = Some(total / ms);
        }
    }
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
mod tests {
    use super::*;

    fn cal() -> Calibration {
        Calibration {
            version: CALIBRATION_VERSION,
            adapter: "a".into(),
            driver: "d".into(),
            cpu_model: "c".into(),
            cpu_cores: 2,
            date_utc: String::new(),
            seconds: 1.0,
            triangles_per_sec: 1e6,
            fill_fragments_per_sec: 1e8,
            fill_format: "Rgba32Float".into(),
            compute_gflops: 10.0,
            copy_bytes_per_sec: 1e10,
            sort_keys_per_sec: 1e7,
        }
    }

    /// The bound is the resource with the largest time: 40 k triangles at 1 M/s = 40 ms beats
    /// the fill (borrowed from the HAVS row: 1 M fragments at 100 M/s = 10 ms) and the sort.
    #[test]
    fn roofline_picks_the_slowest_resource() {
        let gator = Row {
            algorithm: "gator-pt".into(),
            settings: "variant=linear;sort=radix".into(),
            tets: 10_000,
            total_ms: Some(80.0),
            gpu_bytes_frame: Some(1_000_000),
            ..Row::default()
        };
        let havs = Row {
            algorithm: "havs".into(),
            settings: "k=2;sort=gpu-radix".into(),
            counters: "fragments=1000000;faces=20000".into(),
            total_ms: Some(50.0),
            ..Row::default()
        };
        let mut rows = vec![gator, havs];
        annotate(&mut rows, &cal());
        let times = resource_times(&rows[0], &rows, &cal());
        assert_eq!(
            times,
            vec![
                ("triangle setup", 40.0),
                ("fill", 10.0),
                ("memory", 0.1),
                ("cpu sort", 1.0)
            ]
        );
        assert_eq!(rows[0].bound_by, "triangle setup");
        assert_eq!(rows[0].limit_fraction, Some(0.5));
        assert_eq!(rows[0].normalized_time, Some(2.0));
        // HAVS with a GPU sort: 20 k faces = 20 ms of setup, no CPU sort term.
        assert_eq!(rows[1].roofline_ms, Some(20.0));
        assert!(!resource_times(&rows[1], &rows, &cal())
            .iter()
            .any(|(n, _)| *n == "cpu sort"));
    }
}
