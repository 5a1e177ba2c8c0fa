//! Tests that open the device: allocations past its limits, readbacks and their reuse.

use super::*;

/// An allocation past the adapter's limits fails with the figures, before wgpu sees it.
#[test]
fn oversized_buffers_and_textures_are_refused_with_the_limit() {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let mut ledger = MemoryLedger::default();
    let max = gpu.limits.max_buffer_size;
    let too_big = (max + 4).div_ceil(4) * 4;
    let e = ledger
        .buffer(
            &gpu,
            "k-buffer",
            Lifetime::PerFrame,
            too_big,
            wgpu::BufferUsages::STORAGE,
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains(&format!("needs {too_big} bytes")), "{e}");
    assert!(e.contains("\"k-buffer\""), "{e}");
    assert!(e.contains(&format!("allows {max} bytes")), "{e}");
    assert_eq!(ledger.total(), 0, "nothing was allocated");
    let side = gpu.limits.max_texture_dimension_2d + 1;
    let e = ledger
        .texture(
            &gpu,
            Lifetime::PerFrame,
            &wgpu::TextureDescriptor {
                label: Some("target"),
                size: wgpu::Extent3d {
                    width: side,
                    height: 8,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            },
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("max_texture_dimension_2d"), "{e}");
}

/// The headless device opens (lavapipe on machines without a GPU) and round-trips data.
#[test]
fn device_opens_and_reads_back() {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let mut ledger = MemoryLedger::default();
    let data: Vec<u32> = (0..1000).collect();
    let buf = ledger
        .buffer_init(
            &gpu,
            "test",
            Lifetime::Persistent,
            bytemuck::cast_slice(&data),
            wgpu::BufferUsages::COPY_SRC,
        )
        .unwrap();
    let back = gpu.read_buffer(&buf, 0, 4000).unwrap();
    assert_eq!(bytemuck::cast_slice::<u8, u32>(&back), &data[..]);
    assert_eq!(ledger.persistent, 4000);
    assert!(!gpu.adapter.name.is_empty());
    eprintln!(
        "adapter: {:?}, timestamps: {}, limits: {:?}",
        gpu.adapter,
        gpu.has_timestamps(),
        gpu.limits
    );
}

/// Readbacks reuse their mappable buffers (none created per frame) and still
/// return exactly the bytes asked for: a smaller read after a larger one, an offset read,
/// and a larger one that needs a new buffer.
#[test]
fn readbacks_reuse_their_buffers_and_return_the_same_bytes() {
    let gpu = Gpu::new().expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let mut ledger = MemoryLedger::default();
    let data: Vec<u32> = (0..4096).map(|i| i * 7 + 1).collect();
    let buf = ledger
        .buffer_init(
            &gpu,
            "test",
            Lifetime::Persistent,
            bytemuck::cast_slice(&data),
            wgpu::BufferUsages::COPY_SRC,
        )
        .unwrap();
    let created = gpu.staging_buffers_created();
    let read = |offset: u64, size: u64| -> Vec<u32> {
        bytemuck::cast_slice(&gpu.read_buffer(&buf, offset, size).unwrap()).to_vec()
    };
    assert_eq!(read(0, 4000), &data[..1000]);
    assert_eq!(read(0, 32), &data[..8]);
    assert_eq!(read(400, 64), &data[100..116]);
    assert_eq!(
        gpu.staging_buffers_created() - created,
        1,
        "one 4 KiB buffer serves all three"
    );
    assert_eq!(read(0, 16384), &data[..]);
    assert_eq!(gpu.staging_buffers_created() - created, 2);
    for _ in 0..10 {
        assert_eq!(read(4, 8), &data[1..3]);
    }
    assert_eq!(gpu.staging_buffers_created() - created, 2);
    // The frame timer maps its own buffer: no readback buffer per frame either.
    let timer = FrameTimer::new(&gpu);
    for _ in 0..3 {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        timer.begin(&mut enc);
        timer.end(&mut enc);
        gpu.queue.submit([enc.finish()]);
        gpu.wait().unwrap();
        let ms = timer.gpu_ms(&gpu).unwrap();
        assert_eq!(ms.is_some(), gpu.has_timestamps());
        assert!(ms.is_none_or(|m| m >= 0.0));
    }
    assert_eq!(gpu.staging_buffers_created() - created, 2);
}
