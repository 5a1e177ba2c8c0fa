//! The shader's own classification run on every tet in a compute pass and read back, for
//! the tests that hold it against the CPU twin ([`crate::classify_cpu`]) and for the claims
//! that judge what draws (GATOR's G1 and G8). It is never part of a timed frame: the renderer
//! does not use it, and it prepares its own copy of the mesh.

use anyhow::bail;
use render_core::bind::{storage_entry, uniform_entry};
use render_core::{Camera, Gpu, Lifetime, MemoryLedger};

use crate::mesh_gpu::MeshGpu;
use crate::{CellModel, SHADER};

/// The GPU classification of one tet, as `gator.wgsl`'s `classify_debug` writes it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuClassification {
    /// Screen x (NDC) of the four input vertices, as the shader projected them.
    pub screen_x: [f32; 4],
    /// Screen y (NDC) of the four input vertices.
    pub screen_y: [f32; 4],
    /// 1..=14 (see [`crate::Classification::case`]).
    pub case: u32,
    /// 1 or 2; 0 when a vertex was behind the eye (the tet is not drawn).
    pub class: u32,
    /// Bit i set: the shader's test t(i+1) held (the order of [`crate::Classification::tests`]).
    pub tests: u32,
    pub pad0: u32,
    /// Thick vertex in normalised device coordinates.
    pub thick_vertex: [f32; 2],
    /// |Δz| in NDC between the two ends of the thick segment (the paper's thickness).
    pub ndc_thickness: f32,
    /// World length of the thick segment (what the optical model uses).
    pub length: f32,
    pub s_front: f32,
    pub s_back: f32,
    pub pad1: [u32; 2],
}

impl GpuClassification {
    /// The four test outcomes, t1 first (as [`crate::Classification::tests`]).
    pub fn test_outcomes(&self) -> [bool; 4] {
        std::array::from_fn(|i| self.tests & (1 << i) != 0)
    }

    /// The projected vertices in the geometric check's form (x, y; z is not recorded and
    /// reads 0).
    pub fn screen_points(&self) -> [[f64; 3]; 4] {
        std::array::from_fn(|i| [self.screen_x[i] as f64, self.screen_y[i] as f64, 0.0])
    }
}

const RECORD: u64 = std::mem::size_of::<GpuClassification>() as u64;
const WORKGROUP: u64 = 64;

/// The mesh uploaded once and the debug pipeline, to classify it from any number of cameras.
/// Results come back in chunks of at most one storage binding (`max_binding`) and one
/// dispatch's workgroups, so any mesh the renderer draws can be classified.
pub struct GpuClassifier {
    mesh: MeshGpu,
    pipeline: wgpu::ComputePipeline,
    g1: wgpu::BindGroup,
    chunk_params: wgpu::Buffer,
    out: wgpu::Buffer,
    /// Tets per dispatch (a multiple of the workgroup size).
    per_chunk: u64,
    _ledger: MemoryLedger,
}

impl GpuClassifier {
    /// Uploads the mesh (`scalars` passed through unchanged, not normalised). Degenerate and
    /// inverted tets are accepted as they are. `max_binding`: the largest storage binding to
    /// use (`None`: the device's), lowered by tests to exercise the chunks on small meshes.
    pub fn new(
        gpu: &Gpu,
        points: &[[f32; 3]],
        scalars: &[f32],
        tets: &[[u32; 4]],
        max_binding: Option<u64>,
    ) -> anyhow::Result<GpuClassifier> {
        if points.len() != scalars.len() {
            bail!(
                "classify_gpu: {} points but {} scalars",
                points.len(),
                scalars.len()
            );
        }
        if let Some((t, bad)) = tets
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&i| i as usize >= points.len()))
        {
            bail!(
                "classify_gpu: tet {t} {bad:?} indexes past the {} points",
                points.len()
            );
        }
        let binding = crate::max_binding(gpu, max_binding.map(|b| (b & !255).max(256)));
        let dispatch = gpu.limits.max_compute_workgroups_per_dimension as u64 * WORKGROUP;
        let per_chunk = ((binding / RECORD).min(dispatch) / WORKGROUP * WORKGROUP).max(WORKGROUP);
        let mut ledger = MemoryLedger::default();
        let xyzs: Vec<[f32; 4]> = points
            .iter()
            .zip(scalars)
            .map(|(p, &s)| [p[0], p[1], p[2], s])
            .collect();
        let mesh = MeshGpu::new(gpu, &mut ledger, &xyzs, tets, None, binding)?;
        let shader = gpu.shader("gator.wgsl", SHADER);
        let g1_layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("gator debug out"),
                entries: &[
                    uniform_entry(1, wgpu::ShaderStages::COMPUTE),
                    storage_entry(2, wgpu::ShaderStages::COMPUTE, false),
                ],
            });
        let layout = render_core::bind::pipeline_layout(
            gpu,
            "gator debug",
            &[Some(&mesh.g0_layout), Some(&g1_layout)],
        );
        let pipeline = gpu.compute_pipeline(
            "gator classify debug",
            Some(&layout),
            &shader,
            "classify_debug",
        );
        let chunk_params = ledger.buffer(
            gpu,
            "gator debug chunk",
            Lifetime::PerFrame,
            16,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let records = per_chunk.min(tets.len().max(1) as u64);
        let out = ledger.buffer(
            gpu,
            "gator debug out",
            Lifetime::PerFrame,
            records * RECORD,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let g1 = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gator debug out"),
            layout: &g1_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: chunk_params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: out.as_entire_binding(),
                },
            ],
        });
        Ok(GpuClassifier {
            mesh,
            pipeline,
            g1,
            chunk_params,
            out,
            per_chunk,
            _ledger: ledger,
        })
    }

    /// Tets classified per dispatch and read back at once.
    pub fn tets_per_chunk(&self) -> u64 {
        self.per_chunk
    }

    /// Every tet classified from `camera`, in mesh order.
    pub fn classify(
        &mut self,
        gpu: &Gpu,
        camera: &Camera,
    ) -> anyhow::Result<Vec<GpuClassification>> {
        self.mesh.write_params(gpu, camera, CellModel::Linear);
        let n = self.mesh.num_tets as u64;
        let mut all = Vec::with_capacity(n as usize);
        let mut base = 0;
        while base < n {
            let count = self.per_chunk.min(n - base);
            let params: [u32; 4] = [base as u32, 0, 0, 0];
            gpu.queue
                .write_buffer(&self.chunk_params, 0, bytemuck::cast_slice(&params));
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("gator classify"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.mesh.g0, &[]);
                pass.set_bind_group(1, &self.g1, &[]);
                pass.dispatch_workgroups(count.div_ceil(WORKGROUP) as u32, 1, 1);
            }
            gpu.queue.submit([enc.finish()]);
            let bytes = gpu.read_buffer(&self.out, 0, count * RECORD)?;
            all.extend(bytemuck::pod_collect_to_vec::<u8, GpuClassification>(
                &bytes,
            ));
            base += count;
        }
        Ok(all)
    }
}

/// Runs the vertex shader's classification (`project_and_classify` in `gator.wgsl`) on every
/// tet from one camera and reads the results back ([`GpuClassifier`] for several cameras).
pub fn classify_gpu(
    gpu: &Gpu,
    points: &[[f32; 3]],
    scalars: &[f32],
    tets: &[[u32; 4]],
    camera: &Camera,
) -> anyhow::Result<Vec<GpuClassification>> {
    GpuClassifier::new(gpu, points, scalars, tets, None)?.classify(gpu, camera)
}
