//! A pre-integration table on the GPU as the papers sample it: a 3D texture with trilinear
//! filtering (HAVS §3.2 and Bernardon et al. 2005 §2.2 both look the segment up in a 3D
//! texture of (s_front, s_back, length)); a 2D table is the same texture one layer deep.
//!
//! Entry `i` of an axis of `n` stands for `i / (n − 1)` ([`crate::preintegration`]), so a
//! shader samples it at `(x · (n − 1) + 0.5) / n`. One filtered sample is one lookup for the
//! backend's texture unit; interpolating by hand from storage costs eight (3D) or four (2D)
//! vec4 loads a step, which is what a CPU backend executes lane by lane.

use crate::gpu::{Gpu, MemoryLedger};

/// WGSL of `table_coord(x, n)`: the texture coordinate of x ∈ [0, 1] on an axis of `n`
/// entries. Every shader that samples a [`TableTexture`] includes it (tested against
/// `Table3d::sample` and `Table2d::sample` in tests/table_texture.rs).
pub const TABLE_WGSL: &str = include_str!("table_texture.wgsl");

/// The table's texture view and its sampler.
pub struct TableTexture {
    pub view: wgpu::TextureView,
    pub sampler: wgpu::Sampler,
    /// Whether the sampler filters. Without `FLOAT32_FILTERABLE` an `Rgba32Float` texture can
    /// only be sampled nearest: a visible approximation, which the renderer must count in its
    /// rows (`table_filter_nearest`).
    pub filterable: bool,
    /// Bytes of the texture.
    pub bytes: u64,
}

impl TableTexture {
    /// Uploads `data`, `[width, height, depth]` texels x fastest (the layout of
    /// `Table3d::data`; a `Table2d` is `depth` 1).
    pub fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        label: &str,
        size: [u32; 3],
        data: &[[f32; 4]],
    ) -> anyhow::Result<TableTexture> {
        let [width, height, depth] = size;
        anyhow::ensure!(
            data.len() as u64 == width as u64 * height as u64 * depth as u64,
            "{label}: {} texels for a {width}×{height}×{depth} table",
            data.len()
        );
        let tex = crate::bind::texture_with_data(
            gpu,
            ledger,
            label,
            wgpu::TextureDimension::D3,
            wgpu::TextureFormat::Rgba32Float,
            size,
            bytemuck::cast_slice(data),
        )?;
        let filterable = TableTexture::filterable_on(gpu);
        Ok(TableTexture {
            view: tex.create_view(&Default::default()),
            sampler: TableTexture::sampler(gpu, label, filterable),
            filterable,
            bytes: data.len() as u64 * 16,
        })
    }

    /// A table's sampler: clamped to the edge on every axis, linear where `filterable` (what
    /// [`TableTexture::layout_entries`] declares for it), else nearest.
    pub fn sampler(gpu: &Gpu, label: &str, filterable: bool) -> wgpu::Sampler {
        let filter = if filterable {
            wgpu::FilterMode::Linear
        } else {
            wgpu::FilterMode::Nearest
        };
        gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some(label),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            address_mode_w: wgpu::AddressMode::ClampToEdge,
            mag_filter: filter,
            min_filter: filter,
            ..Default::default()
        })
    }

    /// Whether `gpu` can filter the table (`FLOAT32_FILTERABLE`): what the layout must declare.
    pub fn filterable_on(gpu: &Gpu) -> bool {
        gpu.features.contains(wgpu::Features::FLOAT32_FILTERABLE)
    }

    /// The layout entries of the texture (`binding`) and its sampler (`sampler_binding`).
    pub fn layout_entries(
        filterable: bool,
        binding: u32,
        sampler_binding: u32,
        visibility: wgpu::ShaderStages,
    ) -> [wgpu::BindGroupLayoutEntry; 2] {
        [
            crate::bind::texture_entry(
                binding,
                visibility,
                filterable,
                wgpu::TextureViewDimension::D3,
            ),
            wgpu::BindGroupLayoutEntry {
                binding: sampler_binding,
                visibility,
                ty: wgpu::BindingType::Sampler(if filterable {
                    wgpu::SamplerBindingType::Filtering
                } else {
                    wgpu::SamplerBindingType::NonFiltering
                }),
                count: None,
            },
        ]
    }

    /// The bind group entries matching [`TableTexture::layout_entries`].
    pub fn bind_entries(
        &self,
        binding: u32,
        sampler_binding: u32,
    ) -> [wgpu::BindGroupEntry<'_>; 2] {
        [
            wgpu::BindGroupEntry {
                binding,
                resource: wgpu::BindingResource::TextureView(&self.view),
            },
            wgpu::BindGroupEntry {
                binding: sampler_binding,
                resource: wgpu::BindingResource::Sampler(&self.sampler),
            },
        ]
    }
}
