//! The memory ledger every buffer and texture goes through, and the split of large arrays
//! across storage bindings.

use super::Gpu;

/// Where an allocation belongs in the memory report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lifetime {
    /// Lives as long as the mesh: counted in bytes/tet.
    Persistent,
    /// Scratch of one frame (k-buffers, sort buffers, render targets).
    PerFrame,
}

/// Largest piece [`MemoryLedger::buffer_init`] stages at once (see there).
pub const UPLOAD_CHUNK: usize = 16 << 20;

/// Counts every buffer and texture an algorithm allocates.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MemoryLedger {
    pub persistent: u64,
    pub per_frame: u64,
    pub entries: Vec<(String, Lifetime, u64)>,
}

impl MemoryLedger {
    pub fn record(&mut self, label: &str, lifetime: Lifetime, bytes: u64) {
        match lifetime {
            Lifetime::Persistent => self.persistent += bytes,
            Lifetime::PerFrame => self.per_frame += bytes,
        }
        self.entries.push((label.to_string(), lifetime, bytes));
    }

    /// Creates a buffer and records it; fails, naming the buffer, the bytes it needs and the
    /// adapter's limit, where wgpu would raise a validation error.
    pub fn buffer(
        &mut self,
        gpu: &Gpu,
        label: &str,
        lifetime: Lifetime,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> anyhow::Result<wgpu::Buffer> {
        let size = size.max(16).div_ceil(4) * 4;
        gpu.check_buffer(label, size)?;
        self.record(label, lifetime, size);
        Ok(gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        }))
    }

    /// Creates a buffer holding `data` and records it; data past [`UPLOAD_CHUNK`] bytes is
    /// uploaded piece by piece, each piece's staging copy released before the next.
    pub fn buffer_init(
        &mut self,
        gpu: &Gpu,
        label: &str,
        lifetime: Lifetime,
        data: &[u8],
        usage: wgpu::BufferUsages,
    ) -> anyhow::Result<wgpu::Buffer> {
        let buf = self.buffer(
            gpu,
            label,
            lifetime,
            data.len() as u64,
            usage | wgpu::BufferUsages::COPY_DST,
        )?;
        if data.len() <= UPLOAD_CHUNK {
            gpu.queue.write_buffer(&buf, 0, data);
        } else {
            // Each write is staged in a copy of its bytes until a submission carries it; in
            // pieces, each flushed and waited for, the copies of a large upload never add up
            // (on lavapipe, where "device" memory is host memory, a mesh's buffers were
            // otherwise held three times during prepare: the caller's array, the staging copy
            // and the buffer).
            for (i, piece) in data.chunks(UPLOAD_CHUNK).enumerate() {
                gpu.queue
                    .write_buffer(&buf, (i * UPLOAD_CHUNK) as u64, piece);
                gpu.queue.submit([]);
                gpu.wait()?;
            }
        }
        Ok(buf)
    }

    /// Creates a texture and records its size; fails on sizes the adapter does not allow.
    pub fn texture(
        &mut self,
        gpu: &Gpu,
        lifetime: Lifetime,
        desc: &wgpu::TextureDescriptor,
    ) -> anyhow::Result<wgpu::Texture> {
        gpu.check_texture(desc)?;
        let texel = desc.format.block_copy_size(None).unwrap_or(4) as u64;
        let s = desc.size;
        self.record(
            desc.label.unwrap_or("texture"),
            lifetime,
            texel * s.width as u64 * s.height as u64 * s.depth_or_array_layers as u64,
        );
        Ok(gpu.device.create_texture(desc))
    }

    pub fn total(&self) -> u64 {
        self.persistent + self.per_frame
    }

    /// Bytes of the buffers and textures whose label starts with `prefix`: what one kind of
    /// data takes on the device, as allocated.
    pub fn bytes_labelled(&self, prefix: &str) -> u64 {
        self.entries
            .iter()
            .filter(|(label, _, _)| label.starts_with(prefix))
            .map(|(_, _, bytes)| bytes)
            .sum()
    }
}

/// Splits `count` elements of `element_bytes` each into ranges that fit one storage binding.
/// Large meshes (20 M tets = 320 MB of indices) are drawn chunk by chunk, never refused.
pub fn chunk_ranges(count: u64, element_bytes: u64, max_binding: u64) -> Vec<std::ops::Range<u64>> {
    let per = (max_binding / element_bytes).max(1);
    (0..count.div_ceil(per))
        .map(|i| i * per..((i + 1) * per).min(count))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_cover_everything_once() {
        let r = chunk_ranges(1000, 16, 16 * 300);
        assert_eq!(r, vec![0..300, 300..600, 600..900, 900..1000]);
        assert_eq!(chunk_ranges(5, 16, 1 << 27), vec![0..5]);
    }
}
