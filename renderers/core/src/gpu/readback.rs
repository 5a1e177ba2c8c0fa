//! Copies from the device to the host, through mappable buffers kept for reuse.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::anyhow;

use super::Gpu;
use crate::image::Image;

/// Readback buffers kept for reuse at most (the rest are dropped when returned).
const STAGING_KEPT: usize = 8;

impl Gpu {
    /// Copies a buffer range to the host (blocking).
    pub fn read_buffer(
        &self,
        buffer: &wgpu::Buffer,
        offset: u64,
        size: u64,
    ) -> anyhow::Result<Vec<u8>> {
        let mut waited = Duration::ZERO;
        self.read_buffer_timed(buffer, offset, size, &mut waited)
    }

    /// [`Gpu::read_buffer`] that adds the time spent waiting for the map to `waited` (the
    /// rest, encoding the copy and copying the mapped bytes, is host work; see
    /// [`crate::FrameClock`]).
    pub fn read_buffer_timed(
        &self,
        buffer: &wgpu::Buffer,
        offset: u64,
        size: u64,
        waited: &mut Duration,
    ) -> anyhow::Result<Vec<u8>> {
        let staging = self.take_staging(size);
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(buffer, offset, &staging, 0, size);
        // The submit counts as waiting (see FrameClock::submit).
        let t = Instant::now();
        self.queue.submit([enc.finish()]);
        *waited += t.elapsed();
        let data = self.map_and_copy(&staging, size, waited);
        self.return_staging(staging);
        data
    }

    /// A mappable buffer of at least `size` bytes: the smallest kept one that fits, else a new
    /// one (sizes rounded up to 4 KiB, so that a frame's readbacks of slightly different
    /// sizes share one).
    pub fn take_staging(&self, size: u64) -> wgpu::Buffer {
        let mut kept = self.staging.lock().unwrap_or_else(|e| e.into_inner());
        let fit = kept
            .iter()
            .enumerate()
            .filter(|(_, b)| b.size() >= size)
            .min_by_key(|(_, b)| b.size())
            .map(|(i, _)| i);
        if let Some(i) = fit {
            return kept.swap_remove(i);
        }
        drop(kept);
        self.staging_created
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: size.max(1).next_multiple_of(4096),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Gives an unmapped readback buffer back for reuse.
    pub fn return_staging(&self, buffer: wgpu::Buffer) {
        let mut kept = self.staging.lock().unwrap_or_else(|e| e.into_inner());
        if kept.len() < STAGING_KEPT {
            kept.push(buffer);
        }
    }

    /// Mappable buffers created for readbacks since the device was opened.
    pub fn staging_buffers_created(&self) -> u64 {
        self.staging_created
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Maps the first `size` bytes of `staging` (after the work that fills it was submitted),
    /// copies them out and unmaps it; the wait for the map is added to `waited`.
    pub fn map_and_copy(
        &self,
        staging: &wgpu::Buffer,
        size: u64,
        waited: &mut Duration,
    ) -> anyhow::Result<Vec<u8>> {
        let (tx, rx) = mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, ..size, move |r| {
            let _ = tx.send(r);
        });
        let t = Instant::now();
        let r = self.wait();
        *waited += t.elapsed();
        r?;
        rx.recv()
            .map_err(|_| anyhow!("readback callback dropped"))?
            .map_err(|e| anyhow!("mapping readback buffer: {e}"))?;
        let data = staging
            .get_mapped_range(..size)
            .map_err(|e| anyhow!("mapped range: {e:?}"))?
            .to_vec();
        staging.unmap();
        Ok(data)
    }

    /// Reads an `Rgba32Float` texture (premultiplied linear) into an [`Image`].
    pub fn read_rgba32f(&self, texture: &wgpu::Texture) -> anyhow::Result<Image> {
        let (w, h) = (texture.width(), texture.height());
        let bytes = self.read_texture_layer(texture, 0)?;
        let mut img = Image::new(w, h);
        img.pixels.copy_from_slice(bytemuck::cast_slice(&bytes));
        Ok(img)
    }

    /// Reads layer `layer` of a 2D (array) texture of 16-byte texels, rows unpadded.
    pub fn read_texture_layer(
        &self,
        texture: &wgpu::Texture,
        layer: u32,
    ) -> anyhow::Result<Vec<u8>> {
        let (w, h) = (texture.width(), texture.height());
        let unpadded = w as u64 * 16;
        let padded = unpadded.div_ceil(256) * 256;
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("image readback"),
            size: padded * h as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer,
                },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded as u32),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.queue.submit([enc.finish()]);
        let mut waited = Duration::ZERO;
        let bytes = self.map_and_copy(&staging, staging.size(), &mut waited)?;
        let mut out = Vec::with_capacity((unpadded * h as u64) as usize);
        for y in 0..h as usize {
            out.extend_from_slice(
                &bytes[y * padded as usize..y * padded as usize + unpadded as usize],
            );
        }
        Ok(out)
    }
}
