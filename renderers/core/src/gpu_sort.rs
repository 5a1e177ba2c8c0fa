//! GPU LSD radix sort of (f32 key, u32 payload) pairs, in place in storage buffers the caller
//! owns, so that HAVS (its "GPU sort" setting) and fragment PT (its GPU-resident
//! order) can compute keys, sort and draw with no readback.
//!
//! Algorithm (`gpu_sort.wgsl`): four passes of 8 bits, each a per-tile histogram, a scan over
//! tiles per digit, and a stable scatter. Keys are written by the caller as f32 (bits in a
//! `u32`/`f32` storage array); the first pass maps them to ordered u32 (HAVS §5.1), the last maps
//! them back, so afterwards the key buffer holds the sorted f32 keys and the value buffer the
//! payloads in the same order. Four passes (an even number) leave the result in the caller's
//! buffers; the ping-pong copies live in this struct.
//!
//! Keys are usually computed on the device too: [`GpuCentroidKeys`] writes, per tet or face,
//! the centroid's sort distance as key and the primitive id as value, so a frame is "key pass,
//! sort, draw" in one encoder with nothing read back.
//!
//! Limits: `n` ≤ `max_len`. Arrays larger than one storage binding
//! (`Gpu::max_storage_binding() / 4` keys: 32 Mi at 128 MiB on lavapipe) are sorted in one
//! piece all the same: the shader sees each of its four arrays as `chunks` bindings of one
//! buffer ([`crate::bind::chunked_wgsl`], [`crate::bind::range_entries`]), so HAVS's 20 M-tet
//! meshes (about 40 M faces, 160 MB of keys) sort on the device. Each
//! [`GpuRadixSort::encode`] writes its pass parameters through the queue, so encode at most
//! one sort per instance per submission.

use anyhow::ensure;

use crate::bind::{buffer_range, whole};
use crate::gpu::{Gpu, LayoutEntries, Lifetime, MemoryLedger};

/// Keys per workgroup tile (256 threads × 16 sub-blocks); must match `TILE` in the shader.
pub const TILE: u32 = 4096;
const PASSES: usize = 4;
/// Each pass's parameters, at dynamic-offset spacing.
const PARAM_STRIDE: u64 = crate::bind::UNIFORM_STRIDE;

const MAP_IN: u32 = 1;
const DESCENDING: u32 = 2;
const UNMAP_OUT: u32 = 4;

/// What a caller's key and value buffers need besides what the caller uses them for.
pub const REQUIRED_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    shift: u32,
    num_tiles: u32,
    flags: u32,
}

/// First binding of the four sorted arrays (`keys_in`, `vals_in`, `keys_out`, `vals_out`,
/// `chunks` bindings each, in that order).
const ARRAYS_BINDING: u32 = 10;

/// The sort shader for arrays of `chunks` bindings of `per_chunk` keys each.
fn sort_source(chunks: u32, per_chunk: u64) -> String {
    let mut s = String::new();
    for (a, (name, read_only)) in [
        ("keys_in", true),
        ("vals_in", true),
        ("keys_out", false),
        ("vals_out", false),
    ]
    .into_iter()
    .enumerate()
    {
        let first = ARRAYS_BINDING + a as u32 * chunks;
        s += &crate::bind::chunked_wgsl(name, "u32", 0, first, chunks, per_chunk, read_only);
    }
    s + include_str!("gpu_sort.wgsl")
}

/// How a pass computes, for each digit, the exclusive prefix of its counts over the tiles and
/// its total (the same integers either way).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TileScan {
    /// One workgroup a digit, its tiles scanned in parallel (`scan_tiles`): 256 workgroups a
    /// pass, a few microseconds on a GPU.
    PerDigit,
    /// One workgroup, each invocation a digit walking its tiles in order (`scan_digits`). A CPU
    /// backend runs a workgroup on one core and each barrier as a switch through all its
    /// invocations: `PerDigit`'s 256 workgroups of 16 barriers cost lavapipe 12.5 ms a sort
    /// whatever its size (docs/roofline.md), this one a load and a store a digit a tile.
    Serial,
}

impl TileScan {
    /// `Serial` on a CPU adapter, `PerDigit` on a GPU.
    pub fn for_adapter(gpu: &Gpu) -> TileScan {
        if gpu.adapter.is_cpu() {
            TileScan::Serial
        } else {
            TileScan::PerDigit
        }
    }
}

/// A reusable GPU radix sorter for up to `max_len` pairs.
pub struct GpuRadixSort {
    device: wgpu::Device,
    queue: wgpu::Queue,
    max_len: u32,
    /// Keys per storage binding, and bindings per array.
    per_chunk: u64,
    chunks: u32,
    layout: wgpu::BindGroupLayout,
    histogram: wgpu::ComputePipeline,
    scan_tiles: wgpu::ComputePipeline,
    scan_digits: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    tile_scan: TileScan,
    params: wgpu::Buffer,
    tmp_keys: wgpu::Buffer,
    tmp_vals: wgpu::Buffer,
    tile_hist: wgpu::Buffer,
    digit_total: wgpu::Buffer,
}

impl GpuRadixSort {
    /// Compiles the pipelines and allocates the scratch (recorded in `ledger` as per-frame sort
    /// buffers: 8 bytes per key of ping-pong copies plus 1 KiB of histogram per tile).
    pub fn new(gpu: &Gpu, max_len: u32, ledger: &mut MemoryLedger) -> anyhow::Result<GpuRadixSort> {
        let max_len = max_len.max(1);
        let per_chunk = gpu.max_storage_binding() / 4;
        let chunks = (max_len as u64).div_ceil(per_chunk) as u32;
        crate::bind::check_storage_bindings(gpu, "GPU radix sort", 4 * chunks + 3)?;
        let tiles = max_len.div_ceil(TILE);
        ensure!(
            tiles <= gpu.limits.max_compute_workgroups_per_dimension,
            "too many tiles for one dispatch"
        );
        let module = gpu.shader("gpu_sort.wgsl", &sort_source(chunks, per_chunk));
        // The four arrays in chunks: keys and values in (read), keys and values out.
        let arrays = ARRAYS_BINDING;
        let layout = LayoutEntries::new(wgpu::ShaderStages::COMPUTE)
            .params(0)
            .read_write(5..=6)
            .read(arrays..arrays + 2 * chunks)
            .read_write(arrays + 2 * chunks..arrays + 4 * chunks)
            .build(gpu, "radix sort");
        let [histogram, scan_tiles, scan_digits, scatter] = gpu.compute_pipelines(
            "radix sort",
            &[&layout],
            &module,
            ["histogram", "scan_tiles", "scan_digits", "scatter"],
        );
        let storage = wgpu::BufferUsages::STORAGE;
        Ok(GpuRadixSort {
            device: gpu.device.clone(),
            queue: gpu.queue.clone(),
            max_len,
            per_chunk,
            chunks,
            histogram,
            scan_tiles,
            scan_digits,
            scatter,
            tile_scan: TileScan::for_adapter(gpu),
            layout,
            params: ledger.buffer(
                gpu,
                "radix sort params",
                Lifetime::PerFrame,
                PARAM_STRIDE * PASSES as u64,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            )?,
            tmp_keys: ledger.buffer(
                gpu,
                "radix sort keys (ping-pong)",
                Lifetime::PerFrame,
                max_len as u64 * 4,
                storage,
            )?,
            tmp_vals: ledger.buffer(
                gpu,
                "radix sort values (ping-pong)",
                Lifetime::PerFrame,
                max_len as u64 * 4,
                storage,
            )?,
            tile_hist: ledger.buffer(
                gpu,
                "radix sort tile histograms",
                Lifetime::PerFrame,
                tiles as u64 * 256 * 4,
                storage,
            )?,
            digit_total: ledger.buffer(
                gpu,
                "radix sort digit totals",
                Lifetime::PerFrame,
                256 * 4,
                storage,
            )?,
        })
    }

    /// The same sorter with the prefix over tiles computed the other way (tests run both
    /// on any adapter; both give the same result bit for bit).
    pub fn with_tile_scan(mut self, tile_scan: TileScan) -> GpuRadixSort {
        self.tile_scan = tile_scan;
        self
    }

    /// The largest `n` this sorter takes.
    pub fn max_len(&self) -> u32 {
        self.max_len
    }

    /// Storage bindings each of its four arrays is split over (1 where `max_len` keys fit one).
    pub fn bindings_per_array(&self) -> u32 {
        self.chunks
    }

    /// Records the sort of the first `n` pairs of `keys` (f32) and `values` (u32) into `encoder`,
    /// ascending or descending by key, stable (equal keys keep their order). Both buffers need
    /// [`REQUIRED_USAGE`] and at least `4 n` bytes; callers normally fill them with their own
    /// compute pass earlier in the same encoder (e.g. key = centroid distance, value = tet id).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        keys: &wgpu::Buffer,
        values: &wgpu::Buffer,
        n: u32,
        descending: bool,
    ) -> anyhow::Result<()> {
        ensure!(
            n <= self.max_len,
            "GPU radix sort: {n} keys exceed the sorter's capacity of {}",
            self.max_len
        );
        ensure!(
            keys.size() >= n as u64 * 4 && values.size() >= n as u64 * 4,
            "GPU radix sort: key/value buffers hold fewer than {n} elements"
        );
        if n == 0 {
            return Ok(());
        }
        let num_tiles = n.div_ceil(TILE);
        let dir = if descending { DESCENDING } else { 0 };
        let params: Vec<Params> = (0..PASSES)
            .map(|pass| {
                let mut flags = dir;
                if pass == 0 {
                    flags |= MAP_IN;
                }
                if pass == PASSES - 1 {
                    flags |= UNMAP_OUT;
                }
                Params {
                    n,
                    shift: 8 * pass as u32,
                    num_tiles,
                    flags,
                }
            })
            .collect();
        self.queue
            .write_buffer(&self.params, 0, &crate::bind::strided_uniforms(&params));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("radix sort"),
            timestamp_writes: None,
        });
        for p in 0..PASSES {
            // Even passes read the caller's buffers, odd passes the ping-pong copies.
            let (ki, vi, ko, vo) = if p % 2 == 0 {
                (keys, values, &self.tmp_keys, &self.tmp_vals)
            } else {
                (&self.tmp_keys, &self.tmp_vals, keys, values)
            };
            let mut entries = vec![
                buffer_range(0, &self.params, p as u64 * PARAM_STRIDE, 16),
                whole(5, &self.tile_hist),
                whole(6, &self.digit_total),
            ];
            for (a, buffer) in [ki, vi, ko, vo].into_iter().enumerate() {
                entries.extend(crate::bind::range_entries(
                    ARRAYS_BINDING + a as u32 * self.chunks,
                    buffer,
                    4,
                    self.per_chunk,
                    self.chunks,
                    n as u64,
                ));
            }
            let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("radix sort pass"),
                layout: &self.layout,
                entries: &entries,
            });
            pass.set_bind_group(0, &bind, &[]);
            pass.set_pipeline(&self.histogram);
            pass.dispatch_workgroups(num_tiles, 1, 1);
            match self.tile_scan {
                TileScan::PerDigit => {
                    pass.set_pipeline(&self.scan_tiles);
                    pass.dispatch_workgroups(256, 1, 1);
                }
                TileScan::Serial => {
                    pass.set_pipeline(&self.scan_digits);
                    pass.dispatch_workgroups(1, 1, 1);
                }
            }
            pass.set_pipeline(&self.scatter);
            pass.dispatch_workgroups(num_tiles, 1, 1);
        }
        Ok(())
    }

    /// Uploads `keys`, sorts them with payload 0..n on the GPU, waits, and returns the sorted
    /// keys and payloads (for tests and one-off timings; renderers keep everything on the GPU).
    pub fn sort_pairs_blocking(
        &self,
        gpu: &Gpu,
        keys: &[f32],
        descending: bool,
    ) -> anyhow::Result<(Vec<f32>, Vec<u32>)> {
        let n = keys.len() as u32;
        let mut ledger = MemoryLedger::default();
        let usage = REQUIRED_USAGE | wgpu::BufferUsages::COPY_SRC;
        let kbuf = ledger.buffer_init(
            gpu,
            "sort keys",
            Lifetime::PerFrame,
            bytemuck::cast_slice(keys),
            usage,
        )?;
        let vals: Vec<u32> = (0..n).collect();
        let vbuf = ledger.buffer_init(
            gpu,
            "sort values",
            Lifetime::PerFrame,
            bytemuck::cast_slice(&vals),
            usage,
        )?;
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.encode(&mut enc, &kbuf, &vbuf, n, descending)?;
        gpu.queue.submit([enc.finish()]);
        if n == 0 {
            return Ok((Vec::new(), Vec::new()));
        }
        let k = gpu.read_buffer(&kbuf, 0, n as u64 * 4)?;
        let v = gpu.read_buffer(&vbuf, 0, n as u64 * 4)?;
        Ok((
            bytemuck::cast_slice(&k).to_vec(),
            bytemuck::cast_slice(&v).to_vec(),
        ))
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct KeyParams {
    eye: [f32; 3],
    perspective: u32,
    forward: [f32; 3],
    count: u32,
    point_stride: u32,
    verts: u32,
    value_base: u32,
    out_base: u32,
}

/// The `#[repr(C)]` structs this crate uploads to the GPU and the WGSL structs they mirror,
/// for the layout test (`tests/gpu_layouts.rs`).
#[doc(hidden)]
pub fn gpu_layouts() -> crate::gpu_layout::GpuLayouts {
    let structs = vec![
        crate::rust_layout!(Params => "gpu_sort.wgsl::Params" { n, shift, num_tiles, flags }),
        crate::rust_layout!(KeyParams => "gpu_sort.wgsl::KeyParams" {
            eye, perspective, forward, count, point_stride, verts, value_base, out_base
        }),
    ];
    crate::gpu_layout::GpuLayouts {
        structs,
        sources: vec![("gpu_sort.wgsl", include_str!("gpu_sort.wgsl").into())],
    }
}

/// Computes sort keys on the GPU, the pass before [`GpuRadixSort::encode`]: for each primitive
/// (tet: 4 vertex indices, face: 3) the centroid's [`crate::Camera::sort_distance`] (in f32) as
/// key and the primitive's id as value. Points are read from a caller's f32 storage buffer with
/// 3 (xyz) or 4 (xyz + scalar) floats per point, in one storage binding.
///
/// Primitives split over several buffers (a mesh larger than one storage binding) are one key
/// pass of several calls ([`GpuCentroidKeys::encode_ranges`], at most `max_calls` of them): each
/// call reads one buffer and writes its keys and ids at their place in one key and one value
/// buffer. Each call's parameters sit [`crate::bind::UNIFORM_STRIDE`] bytes apart in one buffer, written
/// through the queue once per key pass: encode at most one key pass per instance per
/// submission.
pub struct GpuCentroidKeys {
    device: wgpu::Device,
    queue: wgpu::Queue,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    max_calls: u32,
}

/// One call of a key pass: `count` primitives stored in `prims`, which holds primitives
/// `first .. first + count` of the caller's whole array. Their keys go to `keys[first + p]` and
/// their ids, `first + p`, to `values[first + p]`.
#[derive(Debug, Clone, Copy)]
pub struct KeyRange<'a> {
    pub prims: &'a wgpu::Buffer,
    pub first: u32,
    pub count: u32,
}

/// One dispatch of the key pass as [`GpuCentroidKeys`] records it.
struct KeyCall<'a> {
    prims: &'a wgpu::Buffer,
    count: u32,
    value_base: u32,
    out_base: u32,
}

impl GpuCentroidKeys {
    /// A key pass of one call per submission ([`GpuCentroidKeys::encode`]).
    pub fn new(gpu: &Gpu, ledger: &mut MemoryLedger) -> anyhow::Result<GpuCentroidKeys> {
        GpuCentroidKeys::with_calls(gpu, 1, ledger)
    }

    /// A key pass of up to `max_calls` calls per submission
    /// ([`GpuCentroidKeys::encode_ranges`]); its parameter buffer ([`crate::bind::UNIFORM_STRIDE`] bytes a
    /// call) is recorded in `ledger` as per-frame.
    pub fn with_calls(
        gpu: &Gpu,
        max_calls: u32,
        ledger: &mut MemoryLedger,
    ) -> anyhow::Result<GpuCentroidKeys> {
        let max_calls = max_calls.max(1);
        // The module's sort entry points need their arrays declared; one binding each.
        let module = gpu.shader(
            "gpu_sort.wgsl",
            &sort_source(1, gpu.max_storage_binding() / 4),
        );
        let layout = LayoutEntries::new(wgpu::ShaderStages::COMPUTE)
            .params(0)
            .read(1..=2)
            .read_write(3..=4)
            .build(gpu, "centroid keys");
        let pipeline_layout =
            crate::bind::pipeline_layout(gpu, "centroid keys", &[None, Some(&layout)]);
        let pipeline = gpu.compute_pipeline(
            "centroid_keys",
            Some(&pipeline_layout),
            &module,
            "centroid_keys",
        );
        let params = ledger.buffer(
            gpu,
            "centroid key params",
            Lifetime::PerFrame,
            PARAM_STRIDE * max_calls as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        Ok(GpuCentroidKeys {
            device: gpu.device.clone(),
            queue: gpu.queue.clone(),
            layout,
            pipeline,
            params,
            max_calls,
        })
    }

    /// Calls one key pass may hold.
    pub fn max_calls(&self) -> u32 {
        self.max_calls
    }

    /// Records the key pass for `count` primitives of `verts` (3 or 4) indices each in `prims`,
    /// writing `keys[p]` and `values[p] = value_base + p`. Like [`GpuRadixSort::encode`], it
    /// writes its parameters through the queue: one key pass per instance per submission.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &crate::Camera,
        points: &wgpu::Buffer,
        point_stride: u32,
        prims: &wgpu::Buffer,
        verts: u32,
        count: u32,
        value_base: u32,
        keys: &wgpu::Buffer,
        values: &wgpu::Buffer,
    ) -> anyhow::Result<()> {
        let call = KeyCall {
            prims,
            count,
            value_base,
            out_base: 0,
        };
        self.encode_calls(
            encoder,
            camera,
            points,
            point_stride,
            verts,
            &[call],
            keys,
            values,
        )
    }

    /// Records one key pass over primitives split over several buffers, one call per
    /// [`KeyRange`] (at most [`GpuCentroidKeys::max_calls`]): afterwards `keys[i]` is the sort
    /// distance of primitive `i` of the whole array and `values[i] = i`, for every `i` a range
    /// covers. Parameters are written through the queue, as in [`GpuCentroidKeys::encode`].
    #[allow(clippy::too_many_arguments)]
    pub fn encode_ranges(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &crate::Camera,
        points: &wgpu::Buffer,
        point_stride: u32,
        verts: u32,
        ranges: &[KeyRange<'_>],
        keys: &wgpu::Buffer,
        values: &wgpu::Buffer,
    ) -> anyhow::Result<()> {
        let calls: Vec<KeyCall> = ranges
            .iter()
            .map(|r| KeyCall {
                prims: r.prims,
                count: r.count,
                value_base: r.first,
                out_base: r.first,
            })
            .collect();
        self.encode_calls(
            encoder,
            camera,
            points,
            point_stride,
            verts,
            &calls,
            keys,
            values,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn encode_calls(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        camera: &crate::Camera,
        points: &wgpu::Buffer,
        point_stride: u32,
        verts: u32,
        calls: &[KeyCall<'_>],
        keys: &wgpu::Buffer,
        values: &wgpu::Buffer,
    ) -> anyhow::Result<()> {
        ensure!(
            verts == 3 || verts == 4,
            "centroid keys: {verts} vertices per primitive (3 or 4)"
        );
        ensure!(
            point_stride >= 3,
            "centroid keys: point stride {point_stride} < 3 floats"
        );
        ensure!(
            calls.len() <= self.max_calls as usize,
            "centroid keys: {} calls in one key pass, this instance holds {}",
            calls.len(),
            self.max_calls
        );
        for c in calls {
            let end = c.out_base as u64 + c.count as u64;
            ensure!(
                c.prims.size() >= c.count as u64 * verts as u64 * 4
                    && keys.size() >= end * 4
                    && values.size() >= end * 4,
                "centroid keys: buffers hold fewer than {} primitives (from {})",
                c.count,
                c.out_base
            );
            ensure!(
                c.value_base as u64 + c.count as u64 <= u32::MAX as u64 + 1,
                "centroid keys: ids past 2^32"
            );
        }
        let calls: Vec<&KeyCall> = calls.iter().filter(|c| c.count > 0).collect();
        if calls.is_empty() {
            return Ok(());
        }
        let params: Vec<KeyParams> = calls
            .iter()
            .map(|c| KeyParams {
                eye: camera.eye.map(|x| x as f32),
                perspective: camera.is_perspective() as u32,
                forward: camera.forward().map(|x| x as f32),
                count: c.count,
                point_stride,
                verts,
                value_base: c.value_base,
                out_base: c.out_base,
            })
            .collect();
        self.queue
            .write_buffer(&self.params, 0, &crate::bind::strided_uniforms(&params));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("centroid keys"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        for (i, c) in calls.iter().enumerate() {
            let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("centroid keys"),
                layout: &self.layout,
                entries: &[
                    buffer_range(
                        0,
                        &self.params,
                        i as u64 * PARAM_STRIDE,
                        std::mem::size_of::<KeyParams>() as u64,
                    ),
                    whole(1, points),
                    whole(2, c.prims),
                    whole(3, keys),
                    whole(4, values),
                ],
            });
            let groups = c.count.div_ceil(256);
            // Two-dimensional grid when one dimension's 65,535 workgroups do not suffice.
            let x = groups.min(65_535);
            let y = groups.div_ceil(x);
            pass.set_bind_group(1, &bind, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        Ok(())
    }
}

/// Sorts `keys` ascending on the GPU and returns the permutation (index of the smallest key
/// first), like [`crate::sort::radix_sort_indices`]. Builds a sorter for this one call.
pub fn sort_blocking(gpu: &Gpu, keys: &[f32]) -> anyhow::Result<Vec<u32>> {
    let sorter = GpuRadixSort::new(gpu, keys.len() as u32, &mut MemoryLedger::default())?;
    Ok(sorter.sort_pairs_blocking(gpu, keys, false)?.1)
}

#[cfg(test)]
#[path = "gpu_sort_tests.rs"]
mod tests;
