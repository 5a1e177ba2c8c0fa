//! Where a frame's order comes from: a shared visibility order sorted on the host, or the
//! device's centroid keys and radix sort (`sort=gpu-radix`).

use anyhow::ensure;
use render_core::gpu_sort::{GpuCentroidKeys, GpuRadixSort, KeyRange};
use render_core::visibility::VisibilitySorter;
use render_core::{Camera, Gpu, Lifetime, MemoryLedger};

use crate::mesh_gpu::MeshGpu;

/// Where a frame's order comes from ([`GatorSort`]).
pub(crate) enum Ordering {
    /// Sorted on the host each frame and uploaded into `State::order_buf`.
    Cpu {
        sorter: VisibilitySorter,
        order: Vec<u32>,
    },
    /// Keyed and sorted on the device; `State::order_buf` is the sort's value buffer.
    Gpu(DeviceSort),
}

/// The device's sort of `sort=gpu-radix`.
pub(crate) struct DeviceSort {
    keys_pass: GpuCentroidKeys,
    sorter: GpuRadixSort,
    /// Each tet's centroid distance, sorted along with the ids in `State::order_buf`.
    keys: wgpu::Buffer,
    /// Per-frame device bytes of the sort besides the order: the keys, the sorter's scratch
    /// and the key pass's parameters (from the ledger).
    pub(crate) bytes: u64,
}

impl DeviceSort {
    /// The key pass (one call per tet chunk), the sorter and the key buffer for `n` tets,
    /// recorded in `ledger` as per-frame bytes.
    pub(crate) fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        mesh: &MeshGpu,
        n: u64,
    ) -> anyhow::Result<DeviceSort> {
        // One binding each for the keys and the ids: GATOR binds at most MAX_TET_CHUNKS chunks
        // of max_binding / 16 tets, so 4 bytes a tet make at most max_binding / 4 · 4 bytes
        // = one binding (32 Mi tets, 128 MiB, on lavapipe).
        ensure!(
            n * 4 <= gpu.max_storage_binding(),
            "gator-pt sort=gpu-radix: {n} tets' keys exceed one storage binding of {} bytes",
            gpu.max_storage_binding()
        );
        let before = ledger.per_frame;
        let keys = ledger.buffer(
            gpu,
            "gator sort keys",
            Lifetime::PerFrame,
            n * 4,
            render_core::gpu_sort::REQUIRED_USAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let keys_pass = GpuCentroidKeys::with_calls(gpu, mesh.tet_ranges.len() as u32, ledger)?;
        let sorter = GpuRadixSort::new(gpu, n as u32, ledger)?;
        Ok(DeviceSort {
            keys_pass,
            sorter,
            keys,
            bytes: ledger.per_frame - before,
        })
    }

    /// Records the key pass over every tet chunk and the sort of its pairs far to near, so
    /// that `order` holds the tet ids back to front.
    pub(crate) fn encode(
        &self,
        enc: &mut wgpu::CommandEncoder,
        camera: &Camera,
        mesh: &MeshGpu,
        order: &wgpu::Buffer,
    ) -> anyhow::Result<()> {
        let ranges: Vec<KeyRange> = mesh
            .tet_ranges
            .iter()
            .zip(&mesh.tet_bufs)
            .map(|(r, prims)| KeyRange {
                prims,
                first: r.start as u32,
                count: (r.end - r.start) as u32,
            })
            .collect();
        // Points: xyz + normalised scalar, 4 floats, in one binding (checked in prepare).
        self.keys_pass.encode_ranges(
            enc,
            camera,
            &mesh.point_bufs[0],
            4,
            4,
            &ranges,
            &self.keys,
            order,
        )?;
        self.sorter
            .encode(enc, &self.keys, order, mesh.num_tets, true)
    }
}
