//! GPU time of a frame by timestamp queries.

use std::time::Duration;

use super::Gpu;

/// GPU time of a frame from two timestamps (wall and host time: [`crate::FrameClock`]), and
/// optionally of its parts, split at marks between them ([`FrameTimer::with_marks`]). The
/// timestamps are resolved and copied into a mappable buffer by the frame's own last command
/// buffer ([`FrameTimer::end`]), so reading them ([`FrameTimer::gpu_ms`]) is one map: no
/// further submission and no buffer created per frame.
pub struct FrameTimer {
    query_set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    readback: Option<wgpu::Buffer>,
    period_ns: f32,
    /// Timestamps: begin, the marks, end.
    count: u32,
}

impl Gpu {
    /// `count` queries of type `ty` and the buffer of `resolve_bytes` they are resolved into,
    /// to be copied on from there (timestamps, occlusion counts).
    pub fn query_set(
        &self,
        label: &str,
        ty: wgpu::QueryType,
        count: u32,
        resolve_bytes: u64,
    ) -> (wgpu::QuerySet, wgpu::Buffer) {
        let set = self.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some(label),
            ty,
            count,
        });
        let resolve = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{label} resolve")),
            size: resolve_bytes,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        (set, resolve)
    }
}

impl FrameTimer {
    pub fn new(gpu: &Gpu) -> FrameTimer {
        FrameTimer::with_marks(gpu, 0)
    }

    /// A timer whose frame is split into `marks + 1` intervals by `marks` timestamps written
    /// with [`FrameTimer::mark`] (each of them every frame, in order, between begin and end).
    pub fn with_marks(gpu: &Gpu, marks: u32) -> FrameTimer {
        let count = marks + 2;
        let bytes = count as u64 * 8;
        let (query_set, resolve, readback) = if gpu.has_timestamps() {
            let (qs, buf) =
                gpu.query_set("frame timestamps", wgpu::QueryType::Timestamp, count, bytes);
            let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            (Some(qs), Some(buf), Some(readback))
        } else {
            (None, None, None)
        };
        FrameTimer {
            query_set,
            resolve,
            readback,
            period_ns: gpu.queue.get_timestamp_period(),
            count,
        }
    }

    /// Writes the "begin" timestamp into `encoder` (first command of the frame's GPU work).
    pub fn begin(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(qs) = &self.query_set {
            encoder.write_timestamp(qs, 0);
        }
    }

    /// Writes mark `i` (0-based, below the `marks` of [`FrameTimer::with_marks`]): the end of
    /// interval `i` and the start of interval `i + 1`.
    pub fn mark(&self, encoder: &mut wgpu::CommandEncoder, i: u32) {
        assert!(
            i + 2 < self.count,
            "FrameTimer: mark {i} of {}",
            self.count - 2
        );
        if let Some(qs) = &self.query_set {
            encoder.write_timestamp(qs, i + 1);
        }
    }

    /// Writes the "end" timestamp, resolves them all and copies them where
    /// [`FrameTimer::gpu_ms`] maps them (last commands of the frame's GPU work).
    pub fn end(&self, encoder: &mut wgpu::CommandEncoder) {
        if let (Some(qs), Some(buf), Some(readback)) =
            (&self.query_set, &self.resolve, &self.readback)
        {
            encoder.write_timestamp(qs, self.count - 1);
            encoder.resolve_query_set(qs, 0..self.count, buf, 0);
            encoder.copy_buffer_to_buffer(buf, 0, readback, 0, self.count as u64 * 8);
        }
    }

    /// GPU milliseconds between begin and end (after the work was submitted; blocks).
    pub fn gpu_ms(&self, gpu: &Gpu) -> anyhow::Result<Option<f64>> {
        Ok(self.gpu_intervals_ms(gpu)?.map(|v| v.iter().sum()))
    }

    /// GPU milliseconds of each interval, begin to the first mark, …, the last mark to end
    /// (after the work was submitted; blocks). Their sum is [`FrameTimer::gpu_ms`].
    pub fn gpu_intervals_ms(&self, gpu: &Gpu) -> anyhow::Result<Option<Vec<f64>>> {
        let Some(readback) = &self.readback else {
            return Ok(None);
        };
        let bytes = gpu.map_and_copy(readback, self.count as u64 * 8, &mut Duration::default())?;
        let t: &[u64] = bytemuck::cast_slice(&bytes);
        let ms = self.period_ns as f64 * 1e-6;
        Ok(Some(
            t.windows(2)
                .map(|w| w[1].saturating_sub(w[0]) as f64 * ms)
                .collect(),
        ))
    }
}
