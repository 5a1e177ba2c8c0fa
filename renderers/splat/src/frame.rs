//! One frame's steps: the slab geometry of a view, each brick's buckets (sorted and cut on
//! the device or on the host), the per-frame parameters, the lanes per voxel, the targets of a
//! viewport, and a brick's splat and composite passes over the ring of sheets.

use std::time::Instant;

use anyhow::{bail, Context};
use render_core::bind::UNIFORM_STRIDE;
use render_core::bind::{
    buffer_range, color_pass, render_target, strided_uniforms, view_entry, whole as entry,
    whole_from,
};
use render_core::{Camera, FrameClock, Gpu, Lifetime, MemoryLedger};

use crate::buckets::{depth, SlabGeometry};
use crate::gpu::{self, FrameParams, SlabParams, IMAGE_FORMAT};
use crate::{BrickStats, Buckets, GpuSort, Splat, State, Targets};
use crate::{ESE_ALPHA, MAX_LANES, MAX_SPLAT_INVOCATIONS, ROWS_PER_LANE, TF_ENTRIES};

impl Splat {
    /// Slab geometry of a camera (the same for every brick of a frame).
    pub(crate) fn geometry(&self, st: &State, camera: &Camera) -> SlabGeometry {
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
    pub(crate) fn buckets(
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
                let bind = gpu.bind_group(
                    "splat buckets",
                    &st.pipes.compute_layout,
                    &whole_from(
                        0,
                        &[
                            &st.frame_buf,
                            &st.bricks[b],
                            &st.keys,
                            &st.vals,
                            &st.sorted,
                            &st.ends,
                        ],
                    ),
                );
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
                        let bind = gpu.bind_group(
                            "splat bitonic",
                            &st.pipes.bitonic_layout,
                            &[
                                buffer_range(0, &st.bitonic_buf, 0, 16),
                                entry(1, &st.keys),
                                entry(2, &st.vals),
                            ],
                        );
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

    pub(crate) fn write_frame(
        &self,
        gpu: &Gpu,
        camera: &Camera,
        geom: &SlabGeometry,
        brick: usize,
    ) {
        let u = self.frame_params(camera, geom, brick);
        let st = self.state.as_ref().unwrap();
        gpu.queue
            .write_buffer(&st.frame_buf, 0, bytemuck::bytes_of(&u));
    }

    pub(crate) fn frame_params(
        &self,
        camera: &Camera,
        geom: &SlabGeometry,
        brick: usize,
    ) -> FrameParams {
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
    pub(crate) fn lanes(&self, gpu: &Gpu, camera: &Camera, geom: &SlabGeometry) -> u32 {
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

    pub(crate) fn ensure_targets(
        &mut self,
        gpu: &Gpu,
        width: u32,
        height: u32,
    ) -> anyhow::Result<()> {
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
    pub(crate) fn draw_brick(
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
        let splat_bind = gpu.bind_group(
            "splat sheet",
            &st.pipes.splat_layout,
            &[
                entry(0, &st.frame_buf),
                entry(1, &st.sorted),
                view_entry(2, &st.table_view),
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: wgpu::BindingResource::Sampler(&st.table_sampler),
                },
                view_entry(3, &t.image_view),
                entry(4, &st.ese_dropped),
                entry(5, &t.sheet),
            ],
        );
        let slab_size = std::mem::size_of::<SlabParams>() as u64;
        let slab_bind = gpu.bind_group(
            "splat slab",
            &st.pipes.slab_layout,
            &[buffer_range(0, &st.slab_buf, 0, slab_size)],
        );
        let comp_bind = gpu.bind_group(
            "splat composite",
            &st.pipes.composite_layout,
            &whole_from(0, &[&st.frame_buf, &t.sheet, &st.tf_buf]),
        );
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
pub(crate) fn depth_row(camera: &Camera) -> [f32; 4] {
    let v = camera.view_f32();
    [v[0][2], v[1][2], v[2][2], v[3][2]]
}
