//! The one clock every renderer times its frames with, so that `cpu_ms`, `gpu_ms` and
//! `total_ms` mean the same in every row.
//!
//! * `total_ms`: wall time from [`FrameClock::start`] (before the frame's first host work) until
//!   the GPU finished the frame ([`FrameClock::finish`], called right after the last wait).
//! * `cpu_ms`: `total_ms` minus the time the host spent handing work to the GPU and blocked on
//!   it inside the frame (every submission, device wait and buffer map goes through
//!   [`FrameClock::submit`], [`FrameClock::wait`] or [`FrameClock::read_buffer`]). What is
//!   left is the frame's own host work: sorting, host classification, buffer writes and
//!   uploads, command encoding, and the copy out of a mapped readback. Submissions count on
//!   the GPU's side because on a software adapter (lavapipe) a submit may execute the work or
//!   wait for the previous submission before returning (measured: a second submit in a frame
//!   blocked for the whole of the first one's GPU time). Defined by subtraction, so no host work can be forgotten by an
//!   unannotated span, and `cpu_ms + wait_ms = total_ms`, hence `cpu_ms ≤ total_ms`.
//! * `gpu_ms`: only from timestamp queries ([`crate::FrameTimer`] or a renderer's own query
//!   set), `None` where the adapter has none; never derived from wall clocks.
//!
//! Readbacks of counters and timestamps after the frame (for the row's columns) happen after
//! `finish` and are not part of the frame.

use std::time::{Duration, Instant};

use crate::gpu::Gpu;
use crate::renderer::FrameStats;

/// Wall clock of one frame, with the GPU waits inside it counted apart.
#[derive(Debug)]
pub struct FrameClock {
    started: Instant,
    waited: Duration,
    stages: Vec<(String, f64)>,
}

/// What [`FrameClock::finish`] measured.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameTimes {
    pub total_ms: f64,
    pub cpu_ms: f64,
    pub wait_ms: f64,
    /// Named spans recorded with [`FrameClock::stage`] / [`FrameClock::push_stage`], then
    /// `wait` (the GPU waits).
    pub stages: Vec<(String, f64)>,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

impl FrameClock {
    /// Starts the frame: call before its first host work.
    pub fn start() -> FrameClock {
        FrameClock {
            started: Instant::now(),
            waited: Duration::ZERO,
            stages: Vec::new(),
        }
    }

    /// Milliseconds since the start.
    pub fn elapsed_ms(&self) -> f64 {
        ms(self.started.elapsed())
    }

    /// Blocks until all submitted work is done; the time counts as waiting, not host work.
    pub fn wait(&mut self, gpu: &Gpu) -> anyhow::Result<()> {
        let t = Instant::now();
        let r = gpu.wait();
        self.waited += t.elapsed();
        r
    }

    /// Submits command buffers; the call counts as waiting for the GPU, not as host work: a
    /// software adapter (lavapipe) may execute the work, or wait for earlier submissions,
    /// inside the submit, and on hardware a submission costs microseconds.
    pub fn submit(
        &mut self,
        gpu: &Gpu,
        commands: impl IntoIterator<Item = wgpu::CommandBuffer>,
    ) -> wgpu::SubmissionIndex {
        let t = Instant::now();
        let i = gpu.queue.submit(commands);
        self.waited += t.elapsed();
        i
    }

    /// Times `f` as a wait for the GPU (for waits that do not go through [`Gpu::wait`]).
    pub fn waiting<R>(&mut self, f: impl FnOnce() -> R) -> R {
        let t = Instant::now();
        let r = f();
        self.waited += t.elapsed();
        r
    }

    /// Copies a buffer range to the host inside the frame: encoding the copy and copying the
    /// mapped bytes are host work, waiting for the map is not.
    pub fn read_buffer(
        &mut self,
        gpu: &Gpu,
        buffer: &wgpu::Buffer,
        offset: u64,
        size: u64,
    ) -> anyhow::Result<Vec<u8>> {
        gpu.read_buffer_timed(buffer, offset, size, &mut self.waited)
    }

    /// Records a named host span that began at `since` (a stage of the row's `stages`) and
    /// returns its milliseconds. Stages are for reading; `cpu_ms` does not add them up.
    pub fn stage(&mut self, name: &str, since: Instant) -> f64 {
        let v = ms(since.elapsed());
        self.stages.push((name.to_string(), v));
        v
    }

    /// Records a named stage measured elsewhere (e.g. a GPU pass from timestamps).
    pub fn push_stage(&mut self, name: &str, v: f64) {
        self.stages.push((name.to_string(), v));
    }

    /// Ends the frame (call right after the wait for its last GPU work).
    pub fn finish(mut self) -> FrameTimes {
        let total = self.started.elapsed();
        let waited = self.waited.min(total);
        let wait_ms = ms(waited);
        self.stages.push(("wait".to_string(), wait_ms));
        FrameTimes {
            total_ms: ms(total),
            cpu_ms: ms(total - waited),
            wait_ms,
            stages: self.stages,
        }
    }
}

impl FrameTimes {
    /// The frame's [`FrameStats`]; `gpu_ms` must come from timestamp queries (or be `None`).
    pub fn stats(
        self,
        gpu_ms: Option<f64>,
        frame_bytes: u64,
        counters: Vec<(String, f64)>,
    ) -> FrameStats {
        FrameStats {
            cpu_ms: self.cpu_ms,
            gpu_ms,
            total_ms: self.total_ms,
            frame_bytes,
            stages: self.stages,
            counters,
        }
    }

    /// Adds stages known only after the frame (e.g. GPU passes from timestamps).
    pub fn with_stages(mut self, extra: impl IntoIterator<Item = (String, f64)>) -> FrameTimes {
        self.stages.extend(extra);
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_is_total_minus_waits_and_never_above_total() {
        let mut c = FrameClock::start();
        let t = Instant::now();
        std::thread::sleep(Duration::from_millis(3));
        c.stage("sort", t);
        c.waiting(|| std::thread::sleep(Duration::from_millis(5)));
        let f = c.finish();
        assert!(f.cpu_ms <= f.total_ms);
        assert!(f.wait_ms >= 5.0, "{f:?}");
        assert!(f.cpu_ms >= 3.0, "{f:?}");
        assert!((f.cpu_ms + f.wait_ms - f.total_ms).abs() < 1e-9, "{f:?}");
        assert_eq!(f.stages[0].0, "sort");
        assert_eq!(f.stages.last().unwrap().0, "wait");
        let s = f.stats(None, 7, vec![]);
        assert_eq!(s.gpu_ms, None);
        assert_eq!(s.frame_bytes, 7);
    }
}
