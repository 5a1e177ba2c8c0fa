//! The calibration's work-specific micro-benchmarks (`calibrate.wgsl`), one per counter that
//! no generic figure prices: a ray step (`walk_main`), a splat fragment (`splat_cs`) and a key
//! of render-core's GPU radix sort. Each returns its rate per second, best of the
//! calibration's repetitions; 0 where the adapter cannot run it.

use render_core::gpu::{Lifetime, MemoryLedger};
use render_core::gpu_sort::GpuRadixSort;
use render_core::Gpu;
use std::time::Instant;

/// Timed repetitions after one warm-up (the best is kept: a roofline wants the backend's peak,
/// and on a busy machine the best repetition is the one least disturbed).
const REPS: usize = 5;

/// Best seconds of `REPS` runs of `f` after one warm-up.
pub fn best_seconds(mut f: impl FnMut() -> anyhow::Result<()>) -> anyhow::Result<f64> {
    f()?;
    let mut t = Vec::with_capacity(REPS);
    for _ in 0..REPS {
        let t0 = Instant::now();
        f()?;
        t.push(t0.elapsed().as_secs_f64());
    }
    Ok(t.into_iter().fold(f64::INFINITY, f64::min).max(1e-9))
}

/// Cells of the walk table (144 bytes each: 64 MiB of geometry + 8 MiB of neighbours).
const WALK_CELLS: u64 = 1 << 19;
const WALK_STEPS: u64 = 32; // calibrate.wgsl WALK_STEPS
const WALK_TABLE: u64 = 4096; // calibrate.wgsl WALK_TABLE
const WALK_INVOCATIONS: u64 = 32 * 1024;
const SPLAT_GRID: u64 = 128; // calibrate.wgsl SPLAT_GRID
const SPLAT_PX: u64 = 4; // calibrate.wgsl SPLAT_PX (each square covers SPLAT_PX² centres)
const SPLAT_TARGET: u64 = 512; // calibrate.wgsl SPLAT_TARGET
const SPLAT_SLICE: u64 = 32; // calibrate.wgsl SPLAT_SLICE
const SPLAT_RING: u64 = 5; // calibrate.wgsl SPLAT_RING
const SPLAT_REPEATS: u64 = 16;
const GPU_SORT_KEYS: u32 = 1 << 18;

/// xorshift64: reproducible filler for the tables.
struct Filler(u64);
impl Filler {
    fn unit(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

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

/// Ray steps per second: `WALK_INVOCATIONS` walks of `WALK_STEPS` dependent cell gathers.
pub fn ray_steps_per_sec(gpu: &Gpu, module: &wgpu::ShaderModule) -> anyhow::Result<f64> {
    let cells = WALK_CELLS.min(gpu.max_storage_binding() / 128);
    let mut fill = Filler(0x2545_F491_4F6C_DD1D);
    // Four planes whose normals point to a tetrahedron's corners (some face is always an
    // exit), a scalar gradient, three filler texels.
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
    // Neighbours a few cells to a few thousand cells ahead, as a mesh's tets are numbered.
    let next: Vec<[u32; 4]> = (0..cells)
        .map(|c| [1u64, 97, 1031, 32771].map(|o| ((c + o) % cells) as u32))
        .collect();
    let table: Vec<[f32; 4]> = (0..WALK_TABLE)
        .map(|_| [fill.unit(), fill.unit(), fill.unit(), fill.unit() * 0.01])
        .collect();
    let mut ledger = MemoryLedger::default();
    let cells_buf = storage(
        gpu,
        &mut ledger,
        "calibrate walk cells",
        bytemuck::cast_slice(&geometry),
    )?;
    drop(geometry);
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
    let s = best_seconds(|| {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups((WALK_INVOCATIONS / 64) as u32, 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.wait()
    })?;
    Ok((WALK_INVOCATIONS * WALK_STEPS) as f64 / s)
}

/// Splat fragments per second of the splatter's compute fill (`splat_cs`).
pub fn splat_fragments_per_sec(gpu: &Gpu, module: &wgpu::ShaderModule) -> anyhow::Result<f64> {
    let mut fill = Filler(0x9E37_79B9_7F4A_7C15);
    let table: Vec<f32> = (0..8 * SPLAT_SLICE * SPLAT_SLICE)
        .map(|_| fill.unit())
        .collect();
    let mut ledger = MemoryLedger::default();
    let table_buf = storage(
        gpu,
        &mut ledger,
        "calibrate splat table",
        bytemuck::cast_slice(&table),
    )?;
    let sheet = ledger.buffer(
        gpu,
        "calibrate splat sheet",
        Lifetime::PerFrame,
        SPLAT_TARGET * SPLAT_TARGET * 8 * SPLAT_RING,
        wgpu::BufferUsages::STORAGE,
    )?;
    let c = wgpu::ShaderStages::COMPUTE;
    let group = gpu
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("calibrate splat"),
            entries: &[
                render_core::bind::storage_entry(7, c, true),
                render_core::bind::storage_entry(8, c, false),
            ],
        });
    let layout = render_core::bind::pipeline_layout(gpu, "calibrate splat", &[Some(&group)]);
    let pipeline = gpu.compute_pipeline("calibrate splat", Some(&layout), module, "splat_cs");
    let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("calibrate splat"),
        layout: &group,
        entries: &[
            render_core::bind::whole(7, &table_buf),
            render_core::bind::whole(8, &sheet),
        ],
    });
    let splats = SPLAT_GRID * SPLAT_GRID * SPLAT_REPEATS;
    let s = best_seconds(|| {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups((splats / 256) as u32, 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.wait()
    })?;
    Ok((splats * SPLAT_PX * SPLAT_PX * SPLAT_RING) as f64 / s)
}

/// Keys per second of render-core's GPU radix sort (HAVS' and fragment PT's device sorts)
/// on 2^18 f32 keys (an LSD radix sort costs the same per key at any size that fills the
/// device; on lavapipe 2^20 took seconds).
pub fn gpu_sort_keys_per_sec(gpu: &Gpu) -> anyhow::Result<f64> {
    let n = GPU_SORT_KEYS.min((gpu.max_storage_binding() / 4) as u32);
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
    let s = best_seconds(|| {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        sorter.encode(&mut enc, &keys_buf, &ids_buf, n, false)?;
        gpu.queue.submit([enc.finish()]);
        gpu.wait()
    })?;
    Ok(n as f64 / s)
}
