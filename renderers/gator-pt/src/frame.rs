//! One frame: the viewport's target, the order (sorted on the host and uploaded, or made on
//! the device in the frame's encoder), the fans drawn in bounded passes, and the frame's
//! times and work counters.

use std::time::Instant;

use datasets::TetMesh;
use render_core::{Camera, FrameClock, FrameStats, FrameTimer, Gpu, MemoryLedger};

use crate::mesh_gpu::{MeshGpu, Params};
use crate::ordering::Ordering;
use crate::{CellModel, NODES, TETS_PER_DRAW};

/// One order-buffer chunk of the draw.
pub(crate) struct DrawChunk {
    pub(crate) range: std::ops::Range<u64>,
    pub(crate) bind_group: wgpu::BindGroup,
}

pub(crate) struct Target {
    pub(crate) texture: wgpu::Texture,
    pub(crate) view: wgpu::TextureView,
    pub(crate) bytes: u64,
}

pub(crate) struct State {
    pub(crate) ledger: MemoryLedger,
    pub(crate) mesh: MeshGpu,
    pub(crate) pipeline: wgpu::RenderPipeline,
    /// The tet ids back to front, which the draw reads.
    pub(crate) order_buf: wgpu::Buffer,
    pub(crate) index_buf: wgpu::Buffer,
    pub(crate) chunks: Vec<DrawChunk>,
    /// The loaded mesh, shared, not copied (a CPU visibility sorter reads its centroids / face
    /// adjacency, the counters its silhouette).
    pub(crate) host_mesh: std::sync::Arc<TetMesh>,
    pub(crate) ordering: Ordering,
    /// Begin, [end of the device sort,] end.
    pub(crate) timer: FrameTimer,
    pub(crate) target: Option<Target>,
    /// The fragments counter, derived once per view (render_core::silhouette).
    pub(crate) fragments: render_core::silhouette::FragmentsPerView,
}

impl State {
    /// One frame of the prepared mesh from `camera`.
    pub(crate) fn render(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
        cells: CellModel,
    ) -> anyhow::Result<FrameStats> {
        self.ensure_target(gpu, camera.width, camera.height)?;
        let mut clock = FrameClock::start();
        let cycle_breaks = self.order(gpu, camera, cells, &mut clock);
        let target = self.target.as_ref().expect("target created above");
        let mut enc = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("gator frame"),
            });
        self.timer.begin(&mut enc);
        if let Ordering::Gpu(ds) = &self.ordering {
            ds.encode(&mut enc, camera, &self.mesh, &self.order_buf)?;
            self.timer.mark(&mut enc, 0);
        }
        let indices_drawn = self.encode_draws(gpu, &mut enc, target);
        let target_bytes = target.bytes;
        self.timer.end(&mut enc);
        clock.submit(gpu, [enc.finish()]);
        clock.wait(gpu)?;
        let times = clock.finish();
        let (gpu_ms, stages, sort_bytes) = match &self.ordering {
            Ordering::Cpu { .. } => {
                let gpu_ms = self.timer.gpu_ms(gpu)?;
                (gpu_ms, gpu_ms.map(|g| vec![("draw".to_string(), g)]), 0)
            }
            Ordering::Gpu(ds) => {
                // GPU-timed stages: the key pass and the sort, then the draw.
                let parts = self.timer.gpu_intervals_ms(gpu)?;
                let stages = parts
                    .as_ref()
                    .map(|p| vec![("gpu_sort".to_string(), p[0]), ("draw".to_string(), p[1])]);
                (parts.map(|p| p.iter().sum()), stages, ds.bytes)
            }
        };
        let counters = self.counters(camera, cycle_breaks, indices_drawn);
        Ok(times.with_stages(stages.into_iter().flatten()).stats(
            gpu_ms,
            self.mesh.num_tets as u64 * 4
                + std::mem::size_of::<Params>() as u64
                + target_bytes
                + sort_bytes,
            counters,
        ))
    }

    /// The render target of a `w` × `h` viewport, made anew when the size changed.
    fn ensure_target(&mut self, gpu: &Gpu, w: u32, h: u32) -> anyhow::Result<()> {
        if self
            .target
            .as_ref()
            .is_none_or(|t| t.texture.width() != w || t.texture.height() != h)
        {
            let (texture, view) = render_core::bind::render_target(
                gpu,
                &mut self.ledger,
                "gator target",
                (w, h),
                wgpu::TextureFormat::Rgba32Float,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            )?;
            self.target = Some(Target {
                texture,
                view,
                bytes: w as u64 * h as u64 * 16,
            });
        }
        Ok(())
    }

    /// The CPU part of the frame: with a host order, its sort and one upload of it (their
    /// stages in `clock`); the parameters either way. Returns the sort's cycle breaks.
    fn order(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
        cells: CellModel,
        clock: &mut FrameClock,
    ) -> usize {
        let mut cycle_breaks = 0;
        match &mut self.ordering {
            // CPU part of the frame: sort keys, radix sort, one upload of the order.
            Ordering::Cpu { sorter, order } => {
                let t0 = Instant::now();
                let sort = sorter.back_to_front(&self.host_mesh, camera, order);
                clock.stage("sort", t0);
                let t1 = Instant::now();
                gpu.queue
                    .write_buffer(&self.order_buf, 0, bytemuck::cast_slice(order));
                self.mesh.write_params(gpu, camera, cells);
                clock.stage("upload", t1);
                if sort.precompute_ms > 0.0 {
                    clock.push_stage("sort_precompute", sort.precompute_ms);
                }
                cycle_breaks = sort.cycle_breaks;
            }
            // The order is made on the device, in the encoder below.
            Ordering::Gpu(_) => {
                let t1 = Instant::now();
                self.mesh.write_params(gpu, camera, cells);
                clock.stage("upload", t1);
            }
        }
        cycle_breaks
    }

    /// Draws of TETS_PER_DRAW in passes of at most `gpu.triangles_per_pass` (4 a tet; see
    /// render_core::gpu::MAX_TRIANGLES_PER_PASS): the first pass clears the target, the rest
    /// blend onto it. A chunk's bind group is set once per pass it spans. Returns the indices
    /// issued: the triangles the frame actually draws (§3.4: four per tet, class-1 cases with
    /// a degenerate fourth), times 3.
    fn encode_draws(&self, gpu: &Gpu, enc: &mut wgpu::CommandEncoder, target: &Target) -> u64 {
        let tets_per_pass = (gpu.triangles_per_pass / 4).max(1) as u64;
        let mut pass: Option<wgpu::RenderPass<'static>> = None;
        let mut in_pass = 0u64;
        let mut first = true;
        let mut indices_drawn = 0u64;
        let open_pass = |enc: &mut wgpu::CommandEncoder, first: bool| {
            let mut p =
                render_core::bind::color_pass(enc, "gator fans", &target.view, first, true, None)
                    .forget_lifetime();
            p.set_pipeline(&self.pipeline);
            p.set_bind_group(0, &self.mesh.g0, &[]);
            p.set_index_buffer(self.index_buf.slice(..), wgpu::IndexFormat::Uint16);
            p
        };
        for chunk in &self.chunks {
            let mut start = chunk.range.start;
            let mut bound = false;
            while start < chunk.range.end {
                if pass.is_none() || in_pass >= tets_per_pass {
                    drop(pass.take());
                    pass = Some(open_pass(enc, first));
                    first = false;
                    in_pass = 0;
                    bound = false;
                }
                let p = pass.as_mut().expect("opened above");
                if !bound {
                    p.set_bind_group(1, &chunk.bind_group, &[]);
                    bound = true;
                }
                let len = (chunk.range.end - start)
                    .min(TETS_PER_DRAW)
                    .min(tets_per_pass - in_pass);
                // Vertex index = fan index + base_vertex = 5·(sorted position) + node.
                p.draw_indexed(0..(12 * len) as u32, (start * NODES as u64) as i32, 0..1);
                indices_drawn += 12 * len;
                start += len;
                in_pass += len;
            }
        }
        if first {
            // Nothing drawn: the one pass still clears the target.
            open_pass(enc, true);
        }
        drop(pass);
        indices_drawn
    }

    /// The frame's work counters.
    fn counters(
        &mut self,
        camera: &Camera,
        cycle_breaks: usize,
        indices_drawn: u64,
    ) -> Vec<(String, f64)> {
        let sorted_on = match self.ordering {
            Ordering::Cpu { .. } => "cpu_sort_keys",
            Ordering::Gpu(_) => "gpu_sort_keys",
        };
        let n = self.mesh.num_tets as f64;
        let projected = self.fragments.get(camera, &self.host_mesh);
        vec![
            ("tets".to_string(), n),
            ("basis_graph_vertices".to_string(), NODES as f64 * n),
            ("cycle_breaks".to_string(), cycle_breaks as f64),
            // The roofline's work: the basis graph's 4 triangles per tet (12 indices), every
            // tet ordered, on the CPU or on the device.
            ("triangles".to_string(), 4.0 * n),
            // Counted from the draw calls issued (indices / 3), not from the formula above.
            ("triangles_drawn".to_string(), (indices_drawn / 3) as f64),
            (sorted_on.to_string(), n),
            // Outside the timed frame, once per view: the pixel centres of every tet's
            // projection, which its four triangles cover once each, and the tets that hold any.
            ("fragments".to_string(), projected.fragments as f64),
            ("covering_tets".to_string(), projected.covering_tets as f64),
            // The vertex program classifies the tet once per basis-graph node it shades
            // (§3: every node's invocation repeats the tests): at least 5 per tet, since an
            // indexed draw shades each of its 5 indices at least once.
            ("tet_classifications".to_string(), NODES as f64 * n),
            // Tets with a vertex at or behind the eye: the vertex shader drops them (no
            // near-plane clipping, as the paper); counted outside the timed frame.
            (
                "tets_behind_eye".to_string(),
                camera.tets_behind_eye(&self.host_mesh) as f64,
            ),
        ]
    }
}
