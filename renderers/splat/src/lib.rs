//! Image-space sheet-buffered splatting on the GPU (Grau & Tost 2007), with the per-slab
//! buckets built on the GPU (`buckets=gpu`, the paper's pipeline) or on the CPU and uploaded
//! each frame (`buckets=cpu`, the paper's "CPU FPS" baseline of Table 1).
//!
//! Input is a voxel grid: the mesh's own (`TetMesh::source_grid`, volume data sets and
//! generated volumes) or the mesh resampled onto a grid with `grid` points along its longest
//! side (the row's counters say `resampled=1`). The relevant voxels (κ > 0 under the transfer
//! function) are selected once in `prepare`, 16 bytes each (x, y, z, value; §3.2).
//!
//! Per frame and brick (§3.1–3.6): view depth per voxel → depth sort (bitonic, the paper's,
//! or render-core's radix sort) → gather into depth order → bucket boundaries on the GPU →
//! read back only the bucket-end table (one u32 per slab) → slabs front to back: slab i
//! splats the voxels of buckets i − r … i + r with the footprint slice of their offset from
//! the slab (one table of all slices, `kernel.rs`) into its sheet, then the sheet is
//! classified (post-classification on the slab's mean value), composited under the image and
//! zeroed for the next slab.
//!
//! The paper draws each splat as a point sprite and lets the blender add it to the sheet. Here
//! a compute pass walks each footprint's pixel centres (the rasteriser's own coverage rule,
//! `coverage.rs`) and adds to the sheet in fixed point with atomics: the same sums, exact and
//! in any order. On lavapipe a splat quad's two triangles cost ~0.3 µs of set-up for one to a
//! few dozen fragments, which made StagBeetle's 69 M splats a 41 s frame (docs/profile.md).
//! Pixels already opaque discard their splats (early splat elimination, `ese`). Bricks (§4)
//! split the voxels by octants when they exceed one storage binding (or `brick=N`); they are
//! drawn in camera order, and kernels crossing a brick face are composited out of order (the
//! `border_voxels` counter).
//!
//! Orthographic and perspective cameras: slabs are planes of constant view depth; a
//! perspective footprint is scaled by focal length / depth, and each sheet's opacity uses the
//! ray's length through the slab.

mod buckets;
pub mod coverage;
mod description;
mod gpu;
#[doc(hidden)]
pub use gpu::gpu_layouts;
pub mod kernel;
pub mod voxels;

use std::time::Instant;

use anyhow::{bail, Context};
use datasets::{TetMesh, VoxelVolume};
use render_core::bind::{color_pass, render_target, whole as entry};
use render_core::gpu_sort::GpuRadixSort;
use render_core::{
    Camera, FrameClock, FrameStats, FrameTimer, Gpu, Image, Lifetime, MemoryLedger, Optics,
    Prepared, Renderer,
};

pub use buckets::{bucket_ends, depth, SlabGeometry};
use coverage::{FragmentCount, QuadParams};
pub use description::{from_settings, DESCRIPTION};
use gpu::{FrameParams, Pipelines, SlabParams, IMAGE_FORMAT};
use kernel::{FootprintTable, Kernel, SIGMA};
use render_core::bind::{strided_uniforms, UNIFORM_STRIDE};
use render_core::table_texture::TableTexture;
use voxels::VoxelSet;

/// Where the per-slab buckets are built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Buckets {
    Cpu,
    Gpu,
}

/// The GPU depth sort (with `buckets=gpu`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GpuSort {
    /// Grau & Tost §3.4 (Govindaraju et al.'s bitonic network).
    Bitonic,
    /// render-core's LSD radix sort.
    Radix,
}

/// The knobs (every one appears in the `settings` column).
#[derive(Debug, Clone, PartialEq)]
pub struct SplatSettings {
    pub buckets: Buckets,
    pub sort: GpuSort,
    /// Kernel radius in grid spacings.
    pub radius: f64,
    /// Slab thickness in grid spacings.
    pub slab: f64,
    /// Footprint slice texels per side.
    pub footprint: u32,
    /// Footprint slices per slab of voxel offset.
    pub subslices: u32,
    /// Grid points along the longest side when a mesh without its own grid is resampled.
    pub grid: usize,
    /// Largest brick in voxels; `None`: as many as one storage binding holds.
    pub brick: Option<usize>,
    /// Early splat elimination.
    pub ese: bool,
}

impl Default for SplatSettings {
    fn default() -> Self {
        SplatSettings {
            buckets: Buckets::Gpu,
            sort: GpuSort::Bitonic,
            radius: 2.0,
            slab: 1.0,
            footprint: 32,
            subslices: 8,
            grid: 32,
            brick: None,
            ese: true,
        }
    }
}

/// A pixel at least this opaque drops the splats behind it (the error this allows is at most
/// 1 − ESE_ALPHA per pixel).
pub const ESE_ALPHA: f32 = 0.999;

/// Footprint rows per invocation of the splat pass (`Splat::lanes`), the most invocations one
/// voxel is split over, and the most invocations of one dispatch (a bucket of many voxels is
/// split less, so that voxels × lanes stays a u32 the dispatch can hold).
const ROWS_PER_LANE: f64 = 2.0;
const MAX_LANES: u32 = 64;
const MAX_SPLAT_INVOCATIONS: u32 = 1 << 30;

/// Transfer function table entries (linear between entries).
const TF_ENTRIES: usize = 256;

struct Targets {
    width: u32,
    height: u32,
    image: wgpu::Texture,
    image_view: wgpu::TextureView,
    /// Per pixel and ring slot two u32: a slab's fixed-point sums (splat.wgsl).
    sheet: wgpu::Buffer,
    /// Sheets in the ring, 2r + 1.
    ring: u64,
    bytes: u64,
}

struct State {
    set: VoxelSet,
    table: FootprintTable,
    pipes: Pipelines,
    bricks: Vec<wgpu::Buffer>,
    /// The footprint slices, an `R32Float` 3D texture ((footprint + 2)² texels a slice row).
    table_view: wgpu::TextureView,
    table_sampler: wgpu::Sampler,
    tf_buf: wgpu::Buffer,
    frame_buf: wgpu::Buffer,
    slab_buf: wgpu::Buffer,
    bitonic_buf: wgpu::Buffer,
    keys: wgpu::Buffer,
    vals: wgpu::Buffer,
    sorted: wgpu::Buffer,
    ends: wgpu::Buffer,
    /// One u32: splat fragments dropped by early splat elimination this frame.
    ese_dropped: wgpu::Buffer,
    radix: Option<GpuRadixSort>,
    cpu: buckets::CpuBuckets,
    max_slabs: u32,
    length_unit: f64,
    ledger: MemoryLedger,
    frame_bytes: u64,
    timer: FrameTimer,
}

/// The splat renderer.
pub struct Splat {
    pub settings: SplatSettings,
    state: Option<State>,
    targets: Option<Targets>,
    /// The last view's splat coverage (work counters are derived once per view).
    coverage: Option<(QuadParams, SlabGeometry, FragmentCount)>,
    /// Test hook: every splat fragment is counted as dropped (`ese_dropped_fragments` becomes
    /// the GPU's own count of splat fragments) and the image stays empty.
    count_every_fragment: bool,
    /// Test hook: each slab splats its buckets i − r … i + r on its own (the paper's order),
    /// instead of each bucket once into a ring of sheets.
    slab_by_slab: bool,
    /// Test hook: invocations per voxel in the splat pass, whatever the adapter
    /// (`Splat::lanes`).
    forced_lanes: Option<u32>,
    /// Test hook: the footprint table loaded and interpolated by hand, the path of devices
    /// that cannot filter `R32Float`.
    table_loads: bool,
}

/// What one brick of one frame did.
#[derive(Default)]
struct BrickStats {
    slabs: u64,
    splats: u64,
    buckets_ms: f64,
    splat_ms: f64,
}

impl Splat {
    pub fn new(settings: SplatSettings) -> Splat {
        Splat {
            settings,
            state: None,
            targets: None,
            coverage: None,
            count_every_fragment: false,
            slab_by_slab: false,
            forced_lanes: None,
            table_loads: false,
        }
    }

    /// Whether the footprint table is sampled with trilinear filtering: where the device
    /// filters `R32Float` (`FLOAT32_FILTERABLE`) and no test asked for the loads.
    fn table_filtered(&self, gpu: &Gpu) -> bool {
        !self.table_loads && TableTexture::filterable_on(gpu)
    }

    /// Every GPU allocation of the prepared data (after `prepare`).
    pub fn memory(&self) -> Option<&MemoryLedger> {
        self.state.as_ref().map(|s| &s.ledger)
    }

    /// The voxels prepared (after `prepare`).
    pub fn voxels(&self) -> Option<&VoxelSet> {
        self.state.as_ref().map(|s| &s.set)
    }

    /// Slab geometry of a camera (the same for every brick of a frame).
    fn geometry(&self, st: &State, camera: &Camera) -> SlabGeometry {
        let row = depth_row(camera);
        let (mut dmin, mut dmax) = (f64::INFINITY, f64::NEG_INFINITY);
        for c in 0..8 {
            let p = [0, 1, 2].map(|a| {
                if c >> a & 1 == 1 {
                    st.set.max[a]
                } else {
                    st.set.min[a]
                }
            });
            let d = depth(row, [p[0] as f32, p[1] as f32, p[2] as f32, 0.0]) as f64;
            dmin = dmin.min(d);
            dmax = dmax.max(d);
        }
        let unit = st.set.kernel_unit;
        SlabGeometry::new(
            dmin,
            dmax,
            self.settings.radius * unit,
            self.settings.slab * unit,
            st.table.radius_slabs,
        )
    }

    /// Builds the bucket table of brick `b` the way the settings say; leaves the sorted voxels
    /// in `sorted`. Returns the table (and the depth-sorted keys when `want_keys`).
    #[allow(clippy::too_many_arguments)]
    fn buckets(
        &mut self,
        gpu: &Gpu,
        b: usize,
        geom: &SlabGeometry,
        row: [f32; 4],
        want_keys: bool,
        stats: &mut BrickStats,
        clock: &mut FrameClock,
    ) -> anyhow::Result<(Vec<u32>, Vec<f32>)> {
        let st = self.state.as_mut().unwrap();
        let range = st.set.bricks[b].range.clone();
        let n = range.len() as u32;
        let t0 = Instant::now();
        match self.settings.buckets {
            Buckets::Cpu => {
                let voxels = &st.set.voxels[range];
                let ends = st.cpu.run(voxels, row, geom);
                let (queue, sorted) = (&gpu.queue, &st.sorted);
                st.cpu.gather(voxels, |first, piece| {
                    queue.write_buffer(sorted, first as u64 * 16, bytemuck::cast_slice(piece))
                });
                stats.buckets_ms += t0.elapsed().as_secs_f64() * 1e3;
                let keys = if want_keys {
                    st.cpu.sorted_keys.clone()
                } else {
                    vec![]
                };
                Ok((ends, keys))
            }
            Buckets::Gpu => {
                let padded = match self.settings.sort {
                    GpuSort::Bitonic => n.next_power_of_two().max(256),
                    GpuSort::Radix => n,
                };
                let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("splat buckets"),
                    layout: &st.pipes.compute_layout,
                    entries: &[
                        entry(0, &st.frame_buf),
                        entry(1, &st.bricks[b]),
                        entry(2, &st.keys),
                        entry(3, &st.vals),
                        entry(4, &st.sorted),
                        entry(5, &st.ends),
                    ],
                });
                let mut enc = gpu.device.create_command_encoder(&Default::default());
                dispatch(&mut enc, &st.pipes.transform, &bind, padded);
                match self.settings.sort {
                    GpuSort::Radix => st
                        .radix
                        .as_ref()
                        .context("radix sorter missing")?
                        .encode(&mut enc, &st.keys, &st.vals, n, false)?,
                    GpuSort::Bitonic => {
                        let steps = gpu::bitonic_steps(padded);
                        let params: Vec<[u32; 4]> =
                            steps.iter().map(|step| step.params(padded)).collect();
                        gpu.queue
                            .write_buffer(&st.bitonic_buf, 0, &strided_uniforms(&params));
                        let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                            label: Some("splat bitonic"),
                            layout: &st.pipes.bitonic_layout,
                            entries: &[
                                wgpu::BindGroupEntry {
                                    binding: 0,
                                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                        buffer: &st.bitonic_buf,
                                        offset: 0,
                                        size: wgpu::BufferSize::new(16),
                                    }),
                                },
                                entry(1, &st.keys),
                                entry(2, &st.vals),
                            ],
                        });
                        let mut pass = enc.begin_compute_pass(&Default::default());
                        for (s, &step) in steps.iter().enumerate() {
                            pass.set_pipeline(match step {
                                gpu::BitonicStep::Double { .. } => &st.pipes.bitonic_double,
                                gpu::BitonicStep::Wide { .. } => &st.pipes.bitonic_wide,
                                gpu::BitonicStep::Narrow { .. } => &st.pipes.bitonic_narrow,
                            });
                            pass.set_bind_group(0, &bind, &[(s as u64 * UNIFORM_STRIDE) as u32]);
                            let (x, y) = gpu::workgroups(step.invocations(padded));
                            pass.dispatch_workgroups(x, y, 1);
                        }
                    }
                }
                dispatch(&mut enc, &st.pipes.gather, &bind, n);
                dispatch(&mut enc, &st.pipes.boundaries, &bind, n);
                clock.submit(gpu, [enc.finish()]);
                // Only the small table of bucket ends comes back (§3.5).
                let bytes = clock.read_buffer(gpu, &st.ends, 0, geom.num_slabs as u64 * 4)?;
                let keys = if want_keys {
                    bytemuck::cast_slice::<u8, f32>(&clock.read_buffer(
                        gpu,
                        &st.keys,
                        0,
                        n as u64 * 4,
                    )?)
                    .to_vec()
                } else {
                    vec![]
                };
                stats.buckets_ms += t0.elapsed().as_secs_f64() * 1e3;
                Ok((bytemuck::cast_slice(&bytes).to_vec(), keys))
            }
        }
    }

    /// Test hook: the bucket table and the depth-sorted keys of brick 0 for `camera`, built as
    /// the settings say (GPU: read back from the device).
    pub fn bucket_table(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
    ) -> anyhow::Result<(SlabGeometry, Vec<u32>, Vec<f32>)> {
        let st = self.state.as_ref().context("prepare first")?;
        let geom = self.geometry(st, camera);
        let row = depth_row(camera);
        self.write_frame(gpu, camera, &geom, 0);
        let mut stats = BrickStats::default();
        let (ends, keys) = self.buckets(
            gpu,
            0,
            &geom,
            row,
            true,
            &mut stats,
            &mut FrameClock::start(),
        )?;
        Ok((geom, ends, keys))
    }

    /// The pixels a sheet can hold, `[x0, y0, x1, y1)`: the effective voxels' box widened by
    /// twice the kernel radius (a footprint square's corners lie √2 radii from its voxel, in
    /// the plane facing the eye) and projected (`Camera::covered_rect`). Slabs composite only
    /// these, which also zeroes everything the splats wrote.
    pub fn composite_rect(&self, camera: &Camera) -> Option<[u32; 4]> {
        let st = self.state.as_ref()?;
        let pad = 2.0 * self.settings.radius * st.set.kernel_unit;
        let bounds = datasets::Aabb {
            min: st.set.min.map(|v| v - pad),
            max: st.set.max.map(|v| v + pad),
        };
        Some(camera.covered_rect(&bounds))
    }

    fn write_frame(&self, gpu: &Gpu, camera: &Camera, geom: &SlabGeometry, brick: usize) {
        let u = self.frame_params(camera, geom, brick);
        let st = self.state.as_ref().unwrap();
        gpu.queue
            .write_buffer(&st.frame_buf, 0, bytemuck::bytes_of(&u));
    }

    fn frame_params(&self, camera: &Camera, geom: &SlabGeometry, brick: usize) -> FrameParams {
        let st = self.state.as_ref().unwrap();
        let n = st.set.bricks.get(brick).map_or(0, |b| b.range.len()) as u32;
        let padded = match (self.settings.buckets, self.settings.sort) {
            (Buckets::Gpu, GpuSort::Bitonic) => n.next_power_of_two().max(256),
            _ => n,
        };
        let (w, h) = (camera.width as f64, camera.height as f64);
        let (focal, tan_half, persp) = match camera.projection {
            render_core::Projection::Perspective { fovy_deg } => {
                let t = (fovy_deg.to_radians() * 0.5).tan();
                (0.5 * h / t, [(t * w / h) as f32, t as f32], 1)
            }
            render_core::Projection::Orthographic => {
                (h / (2.0 * camera.ortho_half_height), [0.0, 0.0], 0)
            }
        };
        let unit = st.set.kernel_unit;
        FrameParams {
            view_proj: camera.view_proj_f32(),
            depth_row: depth_row(camera),
            viewport: [w as f32, h as f32],
            tan_half,
            focal_px: focal as f32,
            perspective: persp,
            d0: geom.d0,
            inv_delta: geom.inv_delta,
            delta_world: (self.settings.slab * unit) as f32,
            num_slabs: geom.num_slabs,
            n,
            padded,
            radius_slabs: st.table.radius_slabs,
            subslices: st.table.subslices,
            footprint: st.table.footprint,
            tf_entries: TF_ENTRIES as u32,
            kernel_radius: self.settings.radius as f32,
            kernel_unit: unit as f32,
            density_scale: st.set.density_scale as f32,
            ese_alpha: match (self.count_every_fragment, self.settings.ese) {
                // Every fragment's alpha is at least −1: all are counted and dropped.
                (true, _) => -1.0,
                (false, true) => ESE_ALPHA,
                (false, false) => 2.0,
            },
            kernel_radius_world: (self.settings.radius * unit) as f32,
            length_unit: st.length_unit as f32,
            pad: [0.0; 2],
        }
    }

    /// Invocations per voxel in the splat pass (`SlabParams::lanes`). On a GPU, about one per
    /// [`ROWS_PER_LANE`] rows of the largest footprint of the frame, the nearest slab's (a
    /// footprint is 2 · kernel radius · pixels per world unit wide), at most [`MAX_LANES`]:
    /// a bucket's few voxels, each walking its whole footprint alone, left an H200 waiting
    /// (docs/gpu.md). On a CPU adapter one: lavapipe's two cores are busy with a bucket's voxels
    /// already, and the split cost Engine and Lobster 25-40 % a frame there. Any value gives
    /// the same image.
    fn lanes(&self, gpu: &Gpu, camera: &Camera, geom: &SlabGeometry) -> u32 {
        if let Some(lanes) = self.forced_lanes {
            return lanes.max(1);
        }
        if gpu.adapter.is_cpu() {
            return 1;
        }
        // The frame's own projection constants, as the shaders get them (any brick's).
        let u = self.frame_params(camera, geom, 0);
        let radius_world = u.kernel_radius_world as f64;
        let focal = u.focal_px as f64;
        let px_per_world = if u.perspective != 0 {
            // The nearest depth a voxel of the first slab can have; a camera at or inside the
            // volume gets the most lanes.
            let near = geom.d0 as f64;
            if near <= radius_world {
                return MAX_LANES;
            }
            focal / near
        } else {
            focal
        };
        let rows = 2.0 * radius_world * px_per_world + 2.0;
        ((rows / ROWS_PER_LANE).ceil() as u32).clamp(1, MAX_LANES)
    }

    fn ensure_targets(&mut self, gpu: &Gpu, width: u32, height: u32) -> anyhow::Result<()> {
        let ring = 2 * self.state.as_ref().unwrap().table.radius_slabs as u64 + 1;
        if self
            .targets
            .as_ref()
            .is_some_and(|t| t.width == width && t.height == height && t.ring == ring)
        {
            return Ok(());
        }
        let sheet_bytes = width as u64 * height as u64 * ring * 8;
        if sheet_bytes > gpu.max_storage_binding() {
            bail!(
                "splat: {width}×{height} pixels with {ring} sheets in the ring (kernel radius {} \
                 over slab {}) need a {sheet_bytes}-byte sheet buffer, above this adapter's \
                 {}-byte storage binding; use a smaller viewport or thicker slabs",
                self.settings.radius,
                self.settings.slab,
                gpu.max_storage_binding()
            );
        }
        let mut ledger = MemoryLedger::default();
        let both = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let (image, image_view) = render_target(
            gpu,
            &mut ledger,
            "splat image",
            (width, height),
            IMAGE_FORMAT,
            both | wgpu::TextureUsages::COPY_SRC,
        )?;
        // Created zeroed; every composite zeroes what it read.
        let sheet = ledger.buffer(
            gpu,
            "splat sheet ring",
            Lifetime::PerFrame,
            sheet_bytes,
            wgpu::BufferUsages::STORAGE,
        )?;
        self.targets = Some(Targets {
            width,
            height,
            image_view,
            sheet,
            ring,
            image,
            bytes: ledger.per_frame,
        });
        Ok(())
    }

    /// Splats the slabs of one brick (its sorted voxels and bucket table are ready).
    #[allow(clippy::too_many_arguments)]
    fn draw_brick(
        &self,
        gpu: &Gpu,
        geom: &SlabGeometry,
        ends: &[u32],
        rect: [u32; 4],
        lanes: u32,
        stats: &mut BrickStats,
        clock: &mut FrameClock,
    ) {
        let st = self.state.as_ref().unwrap();
        let t = self.targets.as_ref().unwrap();
        let t0 = Instant::now();
        let [x0, y0, x1, y1] = rect;
        // One dynamic-offset entry per step t (written before this brick's submit, so each
        // brick sees its own): splat bucket t into the sheets of slabs t − r … t + r (a ring of
        // 2r + 1, slot = slab mod 2r + 1), then composite slab t − r, whose last bucket that
        // was. Empty buckets are not dispatched, and slabs with nothing to splat not
        // composited (their slot stayed empty). The test hook `slab_by_slab` takes the paper's
        // steps instead: slab t splats buckets t − r … t + r into its sheet alone.
        let drawn = geom.num_slabs.min(st.max_slabs);
        let splat_ranges: Vec<_> = (0..drawn).map(|s| geom.splat_range(ends, s)).collect();
        let r = if self.slab_by_slab {
            0
        } else {
            geom.radius_slabs
        };
        let steps: Vec<(SlabParams, Option<u32>)> = (0..drawn + r)
            .map(|t| {
                let (voxels, slabs) = match (t < drawn, self.slab_by_slab) {
                    (false, _) => (0..0, 0..=0),
                    (true, false) => (
                        geom.bucket_range(ends, t),
                        t.saturating_sub(r)..=(t + r).min(drawn - 1),
                    ),
                    (true, true) => (splat_ranges[t as usize].clone(), t..=t),
                };
                let composite = t
                    .checked_sub(r)
                    .filter(|&s| s < drawn && !splat_ranges[s as usize].is_empty());
                let step = SlabParams {
                    first: voxels.start,
                    count: voxels.len() as u32,
                    first_slab: *slabs.start(),
                    last_slab: *slabs.end(),
                    slot: composite.map_or(0, |s| s % geom.ring()),
                    lanes: lanes
                        .min(MAX_SPLAT_INVOCATIONS / (voxels.len() as u32).max(1))
                        .max(1),
                    ..Default::default()
                };
                (step, composite)
            })
            .collect();
        for range in splat_ranges.iter().filter(|r| !r.is_empty()) {
            stats.slabs += 1;
            stats.splats += range.len() as u64;
        }
        let params: Vec<SlabParams> = steps.iter().map(|(u, _)| *u).collect();
        if !params.is_empty() {
            gpu.queue
                .write_buffer(&st.slab_buf, 0, &strided_uniforms(&params));
        }
        let splat_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("splat sheet"),
            layout: &st.pipes.splat_layout,
            entries: &[
                entry(0, &st.frame_buf),
                entry(1, &st.sorted),
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&st.table_view),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: wgpu::BindingResource::Sampler(&st.table_sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&t.image_view),
                },
                entry(4, &st.ese_dropped),
                entry(5, &t.sheet),
            ],
        });
        let slab_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("splat slab"),
            layout: &st.pipes.slab_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &st.slab_buf,
                    offset: 0,
                    size: wgpu::BufferSize::new(std::mem::size_of::<SlabParams>() as u64),
                }),
            }],
        });
        let comp_bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("splat composite"),
            layout: &st.pipes.composite_layout,
            entries: &[
                entry(0, &st.frame_buf),
                entry(1, &t.sheet),
                entry(2, &st.tf_buf),
            ],
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for (index, (step, composite)) in steps.iter().enumerate() {
            let offset = (index as u64 * UNIFORM_STRIDE) as u32;
            if step.count > 0 {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("splat bucket"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&st.pipes.splat);
                pass.set_bind_group(0, &splat_bind, &[]);
                pass.set_bind_group(1, &slab_bind, &[offset]);
                let (x, y) = gpu::workgroups_of(step.count * step.lanes, gpu::SPLAT_WORKGROUP);
                pass.dispatch_workgroups(x, y, 1);
            }
            if composite.is_some() {
                let mut pass = color_pass(
                    &mut enc,
                    "splat composite",
                    &t.image_view,
                    false,
                    true,
                    None,
                );
                pass.set_scissor_rect(x0, y0, x1.saturating_sub(x0), y1.saturating_sub(y0));
                pass.set_pipeline(&st.pipes.composite);
                pass.set_bind_group(0, &comp_bind, &[]);
                pass.set_bind_group(1, &slab_bind, &[offset]);
                pass.draw(0..3, 0..1);
            }
        }
        clock.submit(gpu, [enc.finish()]);
        stats.splat_ms += t0.elapsed().as_secs_f64() * 1e3;
    }
}

fn dispatch(
    enc: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    threads: u32,
) {
    if threads == 0 {
        return;
    }
    let mut pass = enc.begin_compute_pass(&Default::default());
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    let (x, y) = gpu::workgroups(threads);
    pass.dispatch_workgroups(x, y, 1);
}

/// Row 2 of the camera's view matrix (view depth = −row · (p, 1)), in f32.
fn depth_row(camera: &Camera) -> [f32; 4] {
    let v = camera.view_f32();
    [v[0][2], v[1][2], v[2][2], v[3][2]]
}

impl Splat {
    /// Everything `prepare` does once the voxels are chosen: `voxels` makes the set from the
    /// largest brick's voxel count; `tets` is the data set's tet count (for the row).
    fn prepare_set(
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
        set.border_voxels = set.count_border_voxels(s.radius);
        let table = FootprintTable::new(
            Kernel::new(s.radius, SIGMA),
            s.slab,
            s.subslices,
            s.footprint,
        );
        let mut ledger = MemoryLedger::default();
        let storage = wgpu::BufferUsages::STORAGE;
        // The GPU buckets read each brick's voxels on the device; the CPU buckets sort them on
        // the host and upload each brick sorted (`sorted`), so they keep no device copy.
        let on_device: &[voxels::Brick] = match s.buckets {
            Buckets::Gpu => &set.bricks,
            Buckets::Cpu => &[],
        };
        let bricks: Vec<wgpu::Buffer> = on_device
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
            .collect::<anyhow::Result<_>>()?;
        let side = table.footprint + 2;
        let table_view = render_core::bind::texture_with_data(
            gpu,
            &mut ledger,
            "splat footprint slices",
            wgpu::TextureDimension::D3,
            wgpu::TextureFormat::R32Float,
            [side, side, table.rows()],
            bytemuck::cast_slice(&table.bordered()),
        )?
        .create_view(&Default::default());
        let filtered = self.table_filtered(gpu);
        let table_sampler = TableTexture::sampler(gpu, "splat footprint slices", filtered);
        let tf_buf = ledger.buffer_init(
            gpu,
            "splat transfer function",
            Lifetime::Persistent,
            bytemuck::cast_slice(&optics.tf.rgb_kappa_table(TF_ENTRIES)),
            storage,
        )?;
        // Enough slabs for any view: the voxels' diagonal plus the kernel on both sides.
        let d = (0..3)
            .map(|a| (set.max[a] - set.min[a]).powi(2))
            .sum::<f64>()
            .sqrt();
        let max_slabs =
            ((d + 2.0 * s.radius * set.kernel_unit) / (s.slab * set.kernel_unit)).ceil() as u32 + 4;
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

impl Renderer for Splat {
    fn algorithm(&self) -> &'static str {
        "splat"
    }

    fn settings(&self) -> render_core::Settings {
        description::settings_of(&self.settings)
    }

    fn prepare(
        &mut self,
        gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        let grid = self.settings.grid;
        self.prepare_set(gpu, optics, mesh.num_tets(), |cap| {
            VoxelSet::new(mesh, optics, grid, cap)
        })
    }

    fn draws_voxels(&self) -> bool {
        true
    }

    fn prepare_voxels(
        &mut self,
        gpu: &Gpu,
        volume: &VoxelVolume,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        self.prepare_set(gpu, optics, volume.num_tets(), |cap| {
            VoxelSet::from_volume(volume, optics, cap)
        })
    }

    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        self.state
            .as_ref()
            .context("splat: render before prepare")?;
        let mut clock = FrameClock::start();
        self.ensure_targets(gpu, camera.width, camera.height)?;
        let st = self.state.as_ref().unwrap();
        let geom = self.geometry(st, camera);
        if geom.num_slabs > st.max_slabs {
            bail!(
                "splat: {} slabs needed, {} prepared (camera inside the volume?)",
                geom.num_slabs,
                st.max_slabs
            );
        }
        let row = depth_row(camera);
        let fwd = camera.forward();
        let order = st.set.brick_order(camera.eye, fwd, camera.is_perspective());
        let t = self.targets.as_ref().unwrap();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        st.timer.begin(&mut enc);
        enc.clear_buffer(&st.ese_dropped, 0, None);
        color_pass(&mut enc, "splat clear", &t.image_view, true, true, None);
        clock.submit(gpu, [enc.finish()]);
        let rect = self.composite_rect(camera).expect("prepared");
        let lanes = self.lanes(gpu, camera, &geom);
        let mut stats = BrickStats::default();
        for b in order {
            if self.state.as_ref().unwrap().set.bricks[b].range.is_empty() {
                continue;
            }
            self.write_frame(gpu, camera, &geom, b);
            let (ends, _) = self.buckets(gpu, b, &geom, row, false, &mut stats, &mut clock)?;
            self.draw_brick(gpu, &geom, &ends, rect, lanes, &mut stats, &mut clock);
        }
        let st = self.state.as_ref().unwrap();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        st.timer.end(&mut enc);
        clock.submit(gpu, [enc.finish()]);
        clock.wait(gpu)?;
        let times = clock.finish().with_stages([
            ("buckets".into(), stats.buckets_ms),
            ("splat".into(), stats.splat_ms),
        ]);
        let total_ms = times.total_ms;
        // Work counters, after the timed frame: the quads' pixels are derived on the CPU once
        // per view (`coverage.rs`).
        let cover = self.fragment_count(camera)?;
        let st = self.state.as_ref().unwrap();
        let gpu_ms = st.timer.gpu_ms(gpu)?;
        // Counter readback, after the timed frame.
        let ese_dropped = u32::from_le_bytes(
            gpu.read_buffer(&st.ese_dropped, 0, 4)?[..4]
                .try_into()
                .expect("4 bytes read"),
        );
        let eff = st.set.voxels.len() as f64;
        let t = self.targets.as_ref().unwrap();
        Ok(times.stats(
            gpu_ms,
            st.frame_bytes + t.bytes,
            vec![
                ("effective_voxels".into(), eff),
                ("grid_points".into(), st.set.grid_points as f64),
                ("resampled".into(), st.set.resampled as u8 as f64),
                ("grid_x".into(), st.set.dims[0] as f64),
                ("grid_y".into(), st.set.dims[1] as f64),
                ("grid_z".into(), st.set.dims[2] as f64),
                ("bricks".into(), st.set.bricks.len() as f64),
                ("border_voxels".into(), st.set.border_voxels as f64),
                ("slabs".into(), stats.slabs as f64),
                ("splats".into(), stats.splats as f64),
                ("splat_fragments".into(), cover.fragments as f64),
                // Each drawn slab composites one viewport-covering triangle, scissored to the
                // rectangle its sheet can hold (the splats themselves are a compute pass:
                // `splat_fragments`).
                (
                    "fragments".into(),
                    stats.slabs as f64
                        * (rect[2].saturating_sub(rect[0]) as f64)
                        * (rect[3].saturating_sub(rect[1]) as f64),
                ),
                ("triangles".into(), stats.slabs as f64),
                (
                    match self.settings.buckets {
                        Buckets::Cpu => "cpu_sort_keys",
                        Buckets::Gpu => "gpu_sort_keys",
                    }
                    .into(),
                    eff,
                ),
                // Early splat elimination drops these; each pixel it touches is already at
                // least ESE_ALPHA opaque, so it changes that pixel by at most 1 − ESE_ALPHA.
                ("ese_dropped_fragments".into(), ese_dropped as f64),
                // The paper's (x, y, z, value) texel.
                (
                    "bytes_per_voxel".into(),
                    std::mem::size_of::<[f32; 4]>() as f64,
                ),
                (
                    "voxels_per_sec".into(),
                    if total_ms > 0.0 {
                        eff / (total_ms * 1e-3)
                    } else {
                        0.0
                    },
                ),
            ],
        ))
    }

    fn read_image(&mut self, gpu: &Gpu) -> anyhow::Result<Image> {
        let t = self
            .targets
            .as_ref()
            .context("splat: read_image before render")?;
        gpu.read_rgba32f(&t.image)
    }
}

impl std::fmt::Debug for Splat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Splat")
            .field("settings", &self.settings)
            .finish()
    }
}
