//! What `prepare` uploads once the voxels are chosen: the bricks, the footprint slices and the
//! transfer function as tables, the per-frame buffers sized for the largest brick, the sorts.

use anyhow::bail;
use render_core::bind::UNIFORM_STRIDE;
use render_core::gpu_sort::GpuRadixSort;
use render_core::table_texture::TableTexture;
use render_core::{FrameTimer, Gpu, Lifetime, MemoryLedger, Optics, Prepared};

use crate::gpu::{self, FrameParams, Pipelines};
use crate::kernel::{FootprintTable, Kernel, SIGMA};
use crate::voxels::{self, VoxelSet};
use crate::{Buckets, GpuSort, Splat, SplatSettings, State, TF_ENTRIES};

impl Splat {
    /// Everything `prepare` does once the voxels are chosen: `voxels` makes the set from the
    /// largest brick's voxel count; `tets` is the data set's tet count (for the row).
    pub(crate) fn prepare_set(
        &mut self,
        gpu: &Gpu,
        optics: &Optics,
        tets: usize,
        voxels: impl FnOnce(usize) -> VoxelSet,
    ) -> anyhow::Result<Prepared> {
        if !gpu.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
            bail!(
                "splat: adapter {} cannot blend into 32-bit float targets (FLOAT32_BLENDABLE)",
                gpu.adapter.name
            );
        }
        let s = self.settings.clone();
        if !(s.radius > 0.0 && s.slab > 0.0 && s.footprint >= 2 && s.subslices >= 1) {
            bail!("splat: radius, slab, footprint and subslices must be positive ({s:?})");
        }
        self.state = None;
        let binding = gpu.max_storage_binding();
        let cap = (binding / 16) as usize;
        let cap = s.brick.map_or(cap, |b| b.min(cap));
        let mut set = voxels(cap);
        set.misalign(s.misalign);
        set.border_voxels = set.count_border_voxels(s.radius);
        let table = FootprintTable::new(
            Kernel::new(s.radius, SIGMA),
            s.slab,
            s.subslices,
            s.footprint,
        );
        let mut ledger = MemoryLedger::default();
        let storage = wgpu::BufferUsages::STORAGE;
        let bricks = upload_bricks(gpu, &mut ledger, &set, s.buckets)?;
        let filtered = self.table_filtered(gpu);
        let (table_view, table_sampler, tf_buf) =
            device_tables(gpu, &mut ledger, &table, optics, filtered)?;
        let max_slabs = max_slabs(&set, &s);
        // One entry per step of a brick: each bucket, then the last r slabs' composites.
        let slab_buf = ledger.buffer(
            gpu,
            "splat slab steps",
            Lifetime::PerFrame,
            (max_slabs + table.radius_slabs) as u64 * UNIFORM_STRIDE,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let frame_buf = ledger.buffer(
            gpu,
            "splat frame",
            Lifetime::PerFrame,
            std::mem::size_of::<FrameParams>() as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let largest = set.largest_brick().max(1);
        let padded_max = match (s.buckets, s.sort) {
            (Buckets::Gpu, GpuSort::Bitonic) => largest.next_power_of_two().max(256),
            _ => largest,
        };
        let stages = gpu::bitonic_steps(padded_max as u32).len().max(1);
        let bitonic_buf = ledger.buffer(
            gpu,
            "splat bitonic stages",
            Lifetime::PerFrame,
            stages as u64 * UNIFORM_STRIDE,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let gpu_side = s.buckets == Buckets::Gpu;
        let key_len = if gpu_side { padded_max } else { 1 } as u64;
        let keys = ledger.buffer(
            gpu,
            "splat depth keys",
            Lifetime::PerFrame,
            key_len * 4,
            storage | wgpu::BufferUsages::COPY_SRC,
        )?;
        let vals = ledger.buffer(
            gpu,
            "splat voxel ids",
            Lifetime::PerFrame,
            key_len * 4,
            storage,
        )?;
        let sorted = ledger.buffer(
            gpu,
            "splat depth-sorted voxels",
            Lifetime::PerFrame,
            largest as u64 * 16,
            storage | wgpu::BufferUsages::COPY_DST,
        )?;
        let ends = ledger.buffer(
            gpu,
            "splat bucket ends",
            Lifetime::PerFrame,
            max_slabs as u64 * 4,
            storage | wgpu::BufferUsages::COPY_SRC,
        )?;
        let ese_dropped = ledger.buffer(
            gpu,
            "splat early-elimination count",
            Lifetime::PerFrame,
            4,
            storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        )?;
        let radix = if gpu_side && s.sort == GpuSort::Radix {
            Some(GpuRadixSort::new(gpu, largest as u32, &mut ledger)?)
        } else {
            None
        };
        let persistent = ledger.persistent;
        let frame_bytes = ledger.per_frame;
        self.state = Some(State {
            set,
            table,
            pipes: Pipelines::new(gpu, filtered),
            bricks,
            table_view,
            table_sampler,
            tf_buf,
            frame_buf,
            slab_buf,
            bitonic_buf,
            keys,
            vals,
            sorted,
            ends,
            ese_dropped,
            radix,
            cpu: Default::default(),
            max_slabs,
            length_unit: optics.length_unit,
            ledger,
            frame_bytes,
            timer: FrameTimer::new(gpu),
        });
        Ok(Prepared {
            persistent_bytes: persistent,
            tets: tets as u64,
        })
    }
}

/// The footprint slices as a filtered (or loaded) 3D texture with its sampler, and the
/// transfer function's table.
fn device_tables(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    table: &FootprintTable,
    optics: &Optics,
    filtered: bool,
) -> anyhow::Result<(wgpu::TextureView, wgpu::Sampler, wgpu::Buffer)> {
    let storage = wgpu::BufferUsages::STORAGE;
    let side = table.footprint + 2;
    let table_view = render_core::bind::texture_with_data(
        gpu,
        ledger,
        "splat footprint slices",
        wgpu::TextureDimension::D3,
        wgpu::TextureFormat::R32Float,
        [side, side, table.rows()],
        bytemuck::cast_slice(&table.bordered()),
    )?
    .create_view(&Default::default());
    let table_sampler = TableTexture::sampler(gpu, "splat footprint slices", filtered);
    let tf_buf = ledger.buffer_init(
        gpu,
        "splat transfer function",
        Lifetime::Persistent,
        bytemuck::cast_slice(&optics.tf.rgb_kappa_table(TF_ENTRIES)),
        storage,
    )?;
    Ok((table_view, table_sampler, tf_buf))
}

/// Slabs enough for any view of `set` with the settings' kernel and slab width.
fn max_slabs(set: &VoxelSet, s: &SplatSettings) -> u32 {
    // Enough slabs for any view: the voxels' diagonal plus the kernel on both sides.
    let d = (0..3)
        .map(|a| (set.max[a] - set.min[a]).powi(2))
        .sum::<f64>()
        .sqrt();
    ((d + 2.0 * s.radius * set.kernel_unit) / (s.slab * set.kernel_unit)).ceil() as u32 + 4
}

/// The bricks' voxels on the device, for the GPU buckets; none for the CPU buckets.
fn upload_bricks(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    set: &VoxelSet,
    buckets: Buckets,
) -> anyhow::Result<Vec<wgpu::Buffer>> {
    let storage = wgpu::BufferUsages::STORAGE;
    // The GPU buckets read each brick's voxels on the device; the CPU buckets sort them on
    // the host and upload each brick sorted (`sorted`), so they keep no device copy.
    let on_device: &[voxels::Brick] = match buckets {
        Buckets::Gpu => &set.bricks,
        Buckets::Cpu => &[],
    };
    on_device
        .iter()
        .map(|b| {
            ledger.buffer_init(
                gpu,
                "splat voxels (x, y, z, value)",
                Lifetime::Persistent,
                bytemuck::cast_slice(&set.voxels[b.range.clone()]),
                storage,
            )
        })
        .collect()
}
