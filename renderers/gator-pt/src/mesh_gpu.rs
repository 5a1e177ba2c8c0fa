//! The mesh on the GPU: points (xyz + normalised scalar) and tets split over storage bindings,
//! the transfer-function and opacity tables, the parameters, and their bind group (group 0,
//! shared by the draw and the debug classification).

use anyhow::{anyhow, bail};
use render_core::bind::{lookup_texture, view_entry, whole, whole_from};
use render_core::gpu::{chunk_ranges, LayoutEntries};
use render_core::{Camera, Gpu, Lifetime, MemoryLedger, Optics};

use crate::{
    CellModel, EXP_LUT_SIZE, MAX_POINT_CHUNKS, MAX_TET_CHUNKS, NODES, TAU_MAX, TF_LUT_SIZE,
};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Params {
    pub(crate) view_proj: [[f32; 4]; 4],
    pub(crate) tets_per_chunk: u32,
    pub(crate) points_per_chunk: u32,
    pub(crate) num_tets: u32,
    pub(crate) cells: u32,
    pub(crate) inv_length_unit: f32,
    pub(crate) tau_max: f32,
    pub(crate) tf_size: u32,
    pub(crate) exp_size: u32,
}

/// Layouts, pipelines and the mesh on the GPU (shared by the renderer and the debug path).
pub(crate) struct MeshGpu {
    pub(crate) g0_layout: wgpu::BindGroupLayout,
    pub(crate) params: wgpu::Buffer,
    pub(crate) g0: wgpu::BindGroup,
    pub(crate) params_host: Params,
    pub(crate) num_tets: u32,
    /// The tet chunks (then placeholders up to [`MAX_TET_CHUNKS`]) and the tets each holds.
    pub(crate) tet_bufs: Vec<wgpu::Buffer>,
    pub(crate) tet_ranges: Vec<std::ops::Range<u64>>,
    /// The point chunks (then placeholders up to [`MAX_POINT_CHUNKS`]).
    pub(crate) point_bufs: Vec<wgpu::Buffer>,
}

/// Opacity table: α(τ) = 1 − exp(−τ) for τ = i/(n−1)·TAU_MAX.
fn exp_table() -> Vec<f32> {
    (0..EXP_LUT_SIZE)
        .map(|i| {
            let tau = i as f64 / (EXP_LUT_SIZE - 1) as f64 * TAU_MAX as f64;
            (-(-tau).exp_m1()) as f32
        })
        .collect()
}

impl MeshGpu {
    /// Uploads points (xyz + scalar) and tets, split over storage bindings of at most
    /// `max_binding` bytes, and the lookup tables.
    pub(crate) fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        points: &[[f32; 4]],
        tets: &[[u32; 4]],
        optics: Option<&Optics>,
        max_binding: u64,
    ) -> anyhow::Result<MeshGpu> {
        let per = max_binding / 16;
        let tet_ranges = chunk_ranges(tets.len() as u64, 16, max_binding);
        let point_ranges = chunk_ranges(points.len() as u64, 16, max_binding);
        if tet_ranges.len() > MAX_TET_CHUNKS || point_ranges.len() > MAX_POINT_CHUNKS {
            bail!(
                "gator-pt: mesh of {} tets / {} points needs {} + {} storage bindings of {} bytes; \
                 at most {MAX_TET_CHUNKS} + {MAX_POINT_CHUNKS} are bound",
                tets.len(),
                points.len(),
                tet_ranges.len(),
                point_ranges.len(),
                max_binding
            );
        }
        if tets.len() as u64 * NODES as u64 > i32::MAX as u64 {
            bail!(
                "gator-pt: {} tets exceed the 32-bit vertex index range ({NODES} vertices per tet)",
                tets.len()
            );
        }
        let tet_bufs = chunk_buffers(
            gpu,
            ledger,
            "gator tets",
            bytemuck::cast_slice(tets),
            &tet_ranges,
            MAX_TET_CHUNKS,
        )?;
        let point_bufs = chunk_buffers(
            gpu,
            ledger,
            "gator points",
            bytemuck::cast_slice(points),
            &point_ranges,
            MAX_POINT_CHUNKS,
        )?;

        let default_optics;
        let optics = match optics {
            Some(o) => o,
            None => {
                default_optics = Optics {
                    tf: render_core::TransferFunction::preset("low-opacity")
                        .ok_or_else(|| anyhow!("no low-opacity preset"))?,
                    scalar_min: 0.0,
                    scalar_max: 1.0,
                    length_unit: 1.0,
                };
                &default_optics
            }
        };
        let (tf_view, exp_view) = lookup_tables(gpu, ledger, optics)?;

        let params_host = Params {
            view_proj: [[0.0; 4]; 4],
            tets_per_chunk: per as u32,
            points_per_chunk: per as u32,
            num_tets: tets.len() as u32,
            cells: 1,
            inv_length_unit: (1.0 / optics.length_unit.max(1e-300)) as f32,
            tau_max: TAU_MAX,
            tf_size: TF_LUT_SIZE,
            exp_size: EXP_LUT_SIZE,
        };
        let params = ledger.buffer_init(
            gpu,
            "gator params",
            Lifetime::Persistent,
            bytemuck::bytes_of(&params_host),
            wgpu::BufferUsages::UNIFORM,
        )?;

        let (g0_layout, g0) = bind_group(gpu, &params, &tet_bufs, &point_bufs, &tf_view, &exp_view);
        Ok(MeshGpu {
            g0_layout,
            params,
            g0,
            params_host,
            num_tets: tets.len() as u32,
            tet_bufs,
            tet_ranges,
            point_bufs,
        })
    }

    pub(crate) fn write_params(&mut self, gpu: &Gpu, camera: &Camera, cells: CellModel) {
        self.params_host.view_proj = camera.view_proj_f32();
        self.params_host.cells = match cells {
            CellModel::Constant => 0,
            CellModel::Linear => 1,
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&self.params_host));
    }
}

/// A mesh array split into storage buffers by `ranges` (16-byte elements), then tiny
/// placeholders up to `max` for the unused bindings (counted: they are allocated).
fn chunk_buffers(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    label: &str,
    bytes: &[u8],
    ranges: &[std::ops::Range<u64>],
    max: usize,
) -> anyhow::Result<Vec<wgpu::Buffer>> {
    let usage = wgpu::BufferUsages::STORAGE;
    let mut bufs: Vec<wgpu::Buffer> = ranges
        .iter()
        .map(|r| {
            ledger.buffer_init(
                gpu,
                label,
                Lifetime::Persistent,
                &bytes[(r.start * 16) as usize..(r.end * 16) as usize],
                usage,
            )
        })
        .collect::<anyhow::Result<_>>()?;
    while bufs.len() < max {
        bufs.push(ledger.buffer(gpu, "gator unused binding", Lifetime::Persistent, 16, usage)?);
    }
    Ok(bufs)
}

/// The transfer function's and the opacity's lookup tables as 1D textures.
fn lookup_tables(
    gpu: &Gpu,
    ledger: &mut MemoryLedger,
    optics: &Optics,
) -> anyhow::Result<(wgpu::TextureView, wgpu::TextureView)> {
    let tf = optics.tf.rgb_kappa_table(TF_LUT_SIZE as usize);
    let tf_view = lookup_texture(
        gpu,
        ledger,
        "gator tf table",
        wgpu::TextureFormat::Rgba32Float,
        (TF_LUT_SIZE, 1),
        bytemuck::cast_slice(&tf),
    )?;
    let ex = exp_table();
    let exp_view = lookup_texture(
        gpu,
        ledger,
        "gator opacity table",
        wgpu::TextureFormat::R32Float,
        (EXP_LUT_SIZE, 1),
        bytemuck::cast_slice(&ex),
    )?;
    Ok((tf_view, exp_view))
}

/// Group 0: the parameters, the tet and point chunks, the two tables.
fn bind_group(
    gpu: &Gpu,
    params: &wgpu::Buffer,
    tet_bufs: &[wgpu::Buffer],
    point_bufs: &[wgpu::Buffer],
    tf_view: &wgpu::TextureView,
    exp_view: &wgpu::TextureView,
) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
    let g0_layout =
        LayoutEntries::new(wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE)
            .uniform(0)
            .visible(wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::COMPUTE)
            .read(1..=(MAX_TET_CHUNKS + MAX_POINT_CHUNKS) as u32)
            .visible(wgpu::ShaderStages::FRAGMENT)
            .texture(8..=9, wgpu::TextureViewDimension::D1)
            .build(gpu, "gator g0");
    let chunks: Vec<&wgpu::Buffer> = tet_bufs.iter().chain(point_bufs).collect();
    let entries = [
        vec![whole(0, params)],
        whole_from(1, &chunks),
        vec![view_entry(8, tf_view), view_entry(9, exp_view)],
    ];
    let g0 = gpu.bind_group("gator g0", &g0_layout, &entries.concat());
    (g0_layout, g0)
}
