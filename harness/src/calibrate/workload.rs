//! What a probe prepares and times: the device and shader module it is prepared with
//! ([`ProbeContext`]), one configuration ready to run ([`Workload`]) and one timing of it
//! ([`Timing`]). The lowest layer of the calibration: the probes' kernels (`kernels.rs`,
//! `work.rs`) and their table (`probes.rs`) import it, it imports none of them.

use render_core::Gpu;

/// xorshift64: reproducible filler for the tables.
pub struct Filler(pub u64);
impl Filler {
    pub fn unit(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// What every probe is prepared with: the device and the calibration's shader module.
pub struct ProbeContext<'g> {
    pub gpu: &'g Gpu,
    pub module: wgpu::ShaderModule,
}

impl<'g> ProbeContext<'g> {
    pub fn new(gpu: &'g Gpu) -> ProbeContext<'g> {
        ProbeContext {
            gpu,
            module: gpu.shader("calibrate", &calibrate_source()),
        }
    }
}

/// One configuration of a probe, ready to run: `run(k)` submits `k` of its `pieces` equal
/// parts (triangles, instances, workgroups) and waits for them; all of them do `units` of the
/// figure's work. The calibration runs every piece; the control runs a share of them sized to
/// take a few milliseconds.
pub struct Workload<'g> {
    /// Units of work all the pieces do (triangles, fragments, keys, steps, bytes, GFLOP).
    pub units: f64,
    /// A parameter of the configuration the figure needs besides the time (the
    /// rasterisation's fragments per triangle; 0 elsewhere).
    pub param: f64,
    /// How many equal parts the work splits into (1: it does not split, as a sort).
    pub pieces: u32,
    run: Box<dyn FnMut(u32) -> anyhow::Result<()> + 'g>,
}

impl<'g> Workload<'g> {
    /// Work that runs whole.
    pub fn new(units: f64, mut run: impl FnMut() -> anyhow::Result<()> + 'g) -> Workload<'g> {
        Workload::split(units, 1, move |_| run())
    }

    /// Work of `pieces` equal parts; `run(k)` runs the first `k`.
    pub fn split(
        units: f64,
        pieces: u32,
        run: impl FnMut(u32) -> anyhow::Result<()> + 'g,
    ) -> Workload<'g> {
        Workload {
            units,
            param: 0.0,
            pieces: pieces.max(1),
            run: Box::new(run),
        }
    }

    pub fn with_param(mut self, param: f64) -> Workload<'g> {
        self.param = param;
        self
    }

    /// Runs every piece.
    pub fn run(&mut self) -> anyhow::Result<()> {
        (self.run)(self.pieces)
    }

    /// Runs `k` pieces (at least one, at most all); returns the units they do.
    pub fn run_part(&mut self, k: u32) -> anyhow::Result<f64> {
        let k = k.clamp(1, self.pieces);
        (self.run)(k)?;
        Ok(self.units * k as f64 / self.pieces as f64)
    }
}

/// One timed configuration: its units, parameter and seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    pub units: f64,
    pub param: f64,
    pub seconds: f64,
}

impl Timing {
    pub fn rate(&self) -> f64 {
        self.units / self.seconds.max(1e-12)
    }
}

/// The calibration's kernels, with render-core's texel-texture addressing (`texel_at`).
pub fn calibrate_source() -> String {
    format!(
        "{}\n{}",
        include_str!("calibrate.wgsl"),
        render_core::texel_texture::TEXEL_WGSL
    )
}
