//! The shader's own classification run on every tet in a compute pass and read back, for
//! the tests that hold it against the CPU twin ([`crate::classify_cpu`]).

use anyhow::bail;
use render_core::bind::whole;
use render_core::gpu::LayoutEntries;
use render_core::{Camera, Gpu, Lifetime, MemoryLedger};

use crate::mesh_gpu::MeshGpu;
use crate::{CellModel, SHADER};

/// The GPU classification of one tet, as `gator.wgsl`'s `classify_debug` writes it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuClassification {
    /// 1..=14 (see [`crate::Classification::case`]).
    pub case: u32,
    /// 1 or 2; 0 when a vertex was behind the eye (the tet is not drawn).
    pub class: u32,
    /// Thick vertex in normalised device coordinates.
    pub thick_vertex: [f32; 2],
    /// |Δz| in NDC between the two ends of the thick segment (the paper's thickness).
    pub ndc_thickness: f32,
    /// World length of the thick segment (what the optical model uses).
    pub length: f32,
    pub s_front: f32,
    pub s_back: f32,
}

/// Runs the vertex shader's classification (`project_and_classify` in `gator.wgsl`) on every
/// tet in a compute pass and reads the results back. `scalars` are passed through unchanged
/// (not normalised). Degenerate and inverted tets are accepted as they are.
pub fn classify_gpu(
    gpu: &Gpu,
    points: &[[f32; 3]],
    scalars: &[f32],
    tets: &[[u32; 4]],
    camera: &Camera,
) -> anyhow::Result<Vec<GpuClassification>> {
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
    let groups = (tets.len() as u64).div_ceil(64);
    if groups > gpu.limits.max_compute_workgroups_per_dimension as u64 {
        bail!(
            "classify_gpu: {} tets exceed one dispatch ({} workgroups of 64)",
            tets.len(),
            gpu.limits.max_compute_workgroups_per_dimension
        );
    }
    let mut ledger = MemoryLedger::default();
    let xyzs: Vec<[f32; 4]> = points
        .iter()
        .zip(scalars)
        .map(|(p, &s)| [p[0], p[1], p[2], s])
        .collect();
    let mut mesh = MeshGpu::new(
        gpu,
        &mut ledger,
        &xyzs,
        tets,
        None,
        gpu.max_storage_binding(),
    )?;
    mesh.write_params(gpu, camera, CellModel::Linear);
    let shader = gpu.shader("gator.wgsl", SHADER);
    let g1_layout = LayoutEntries::new(wgpu::ShaderStages::COMPUTE)
        .read_write(2)
        .build(gpu, "gator debug out");
    let [pipeline] = gpu.compute_pipelines(
        "gator debug",
        &[&mesh.g0_layout, &g1_layout],
        &shader,
        ["classify_debug"],
    );
    let size = (tets.len().max(1) * std::mem::size_of::<GpuClassification>()) as u64;
    let out = ledger.buffer(
        gpu,
        "gator debug out",
        Lifetime::PerFrame,
        size,
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    )?;
    let g1 = gpu.bind_group("gator debug out", &g1_layout, &[whole(2, &out)]);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("gator classify"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &mesh.g0, &[]);
        pass.set_bind_group(1, &g1, &[]);
        pass.dispatch_workgroups(groups as u32, 1, 1);
    }
    gpu.queue.submit([enc.finish()]);
    let bytes = gpu.read_buffer(&out, 0, size)?;
    let mut v: Vec<GpuClassification> = bytemuck::cast_slice(&bytes).to_vec();
    v.truncate(mesh.num_tets as usize);
    Ok(v)
}
