//! Records of 16-byte texels in an `Rgba32Uint` 2D array texture, [`TEXEL_ROW`] texels a row,
//! read in WGSL with `texel_at(texture, layer, i)` ([`TEXEL_WGSL`]). A texture rather than a
//! storage buffer where a shader gathers records at addresses that differ between invocations:
//! a CPU backend (llvmpipe) fetches a texel for every SIMD lane at once, where it runs such a
//! storage load lane by lane (the ray caster's frame halved, docs/roofline.md). The ray
//! caster's mesh (Bernardon et al. 2005, Table 1) and the calibration's walk use it.

use crate::gpu::{Gpu, Lifetime, MemoryLedger};

/// Texels in a row: a power of two (a shader's address is a mask and a shift) within
/// WebGPU's guaranteed 8192.
pub const TEXEL_ROW: u32 = 8192;

/// WGSL of `texel_at`.
pub const TEXEL_WGSL: &str = include_str!("texel_texture.wgsl");

/// The texture and its `D2Array` view.
pub struct TexelTexture {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
}

impl TexelTexture {
    /// Rows enough for `texels` texels in a layer.
    pub fn rows_for(texels: usize) -> u32 {
        (texels.max(1) as u64).div_ceil(TEXEL_ROW as u64) as u32
    }

    /// A texture of `layers` layers of `rows` rows, recorded in `ledger` under `label`.
    pub fn new(
        gpu: &Gpu,
        ledger: &mut MemoryLedger,
        label: &str,
        lifetime: Lifetime,
        rows: u32,
        layers: u32,
    ) -> anyhow::Result<TexelTexture> {
        let texture = ledger.texture(
            gpu,
            lifetime,
            &wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: TEXEL_ROW,
                    height: rows,
                    depth_or_array_layers: layers,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Uint,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            },
        )?;
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        Ok(TexelTexture { texture, view })
    }

    /// Writes `data` to layer `layer` from its first texel, row by row (the last row partly);
    /// returns the bytes written.
    pub fn write_layer(&self, gpu: &Gpu, layer: u32, data: &[[u32; 4]]) -> u64 {
        let width = TEXEL_ROW as usize;
        let full_rows = data.len() / width;
        let write = |row: usize, texels: &[[u32; 4]]| {
            let rows = texels.len().div_ceil(width).max(1) as u32;
            let row_texels = texels.len().min(width) as u32;
            gpu.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &self.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: row as u32,
                        z: layer,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(texels),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row_texels * 16),
                    rows_per_image: Some(rows),
                },
                wgpu::Extent3d {
                    width: row_texels,
                    height: rows,
                    depth_or_array_layers: 1,
                },
            );
        };
        if full_rows > 0 {
            write(0, &data[..full_rows * width]);
        }
        if data.len() > full_rows * width {
            write(full_rows, &data[full_rows * width..]);
        }
        data.len() as u64 * 16
    }
}
