//! `tetbench calibrate --floor`: what one frame costs before any algorithm does any work, step
//! by step. On a GPU a frame of a small mesh is mostly this floor: a submission,
//! the wait for the device, the readbacks of a frame's counters and timestamps. Each step is
//! timed on its own, `FLOOR_REPS` times after warming up, and reported as the median and the
//! fastest; the report stands beside the rows (`scripts/gpu.sh`), never subtracted from them.
//!
//! The steps, each what the frame loop (`harness/src/run/measure.rs`, `render_core::FrameClock`)
//! does or did:
//!
//! - `submit`: an empty command buffer handed to the queue (no wait);
//! - `submit + wait`: the same, then the device wait every frame ends with;
//! - `clear + wait`: a render pass that only clears a viewport-sized `Rgba32Float` target (the
//!   frame of an empty mesh: every renderer clears its target), submitted and waited for;
//! - `64 empty render passes + wait`, `64 empty compute passes + wait`: [`PASSES`] passes
//!   that do nothing (the render passes load and store that target), in one command buffer,
//!   submitted and waited for: less `submit + wait`, over 64, the fixed cost of a pass;
//! - `readback, new buffer`: 32 bytes copied into a mappable buffer created for it, submitted,
//!   mapped (what every counter and timestamp readback cost before the reuse);
//! - `readback, reused buffer`: the same into a buffer kept from the last readback (what
//!   `Gpu::read_buffer` does now);
//! - `timestamps`: a frame's two timestamps written, resolved and copied in one command buffer,
//!   submitted, waited for and mapped (`FrameTimer`); absent without timestamp queries.

use std::time::{Duration, Instant};

use render_core::{FrameTimer, Gpu};
use serde::{Deserialize, Serialize};

/// Timed repetitions of each step (after `FLOOR_REPS / 10` warm-ups).
pub const FLOOR_REPS: usize = 200;

/// Empty passes in one submission of the passes steps: enough that the submission and the
/// wait (the `submit + wait` step) are a small part of the step.
pub const PASSES: u32 = 64;

/// The name of the step that times [`PASSES`] empty passes of `kind` ("render", "compute").
pub fn passes_step(kind: &str) -> String {
    format!("{PASSES} empty {kind} passes + wait")
}

/// One step's times (microseconds).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FloorStep {
    pub step: String,
    pub median_us: f64,
    pub min_us: f64,
}

/// The floor of one adapter at one viewport.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Floor {
    pub adapter: String,
    pub width: u32,
    pub reps: usize,
    pub steps: Vec<FloorStep>,
    /// One empty render pass and one empty compute pass, µs ([`Floor::per_pass_us`]); absent
    /// in floors measured before the passes steps.
    #[serde(default)]
    pub render_pass_us: Option<f64>,
    #[serde(default)]
    pub compute_pass_us: Option<f64>,
}

fn step(
    name: &str,
    reps: usize,
    mut f: impl FnMut() -> anyhow::Result<()>,
) -> anyhow::Result<FloorStep> {
    for _ in 0..(reps / 10).max(1) {
        f()?;
    }
    let mut t = Vec::with_capacity(reps);
    for _ in 0..reps {
        let t0 = Instant::now();
        f()?;
        t.push(t0.elapsed().as_secs_f64() * 1e6);
    }
    t.sort_by(f64::total_cmp);
    Ok(FloorStep {
        step: name.to_string(),
        median_us: t[t.len() / 2],
        min_us: t[0],
    })
}

/// Commands a step records into its command buffer.
type Encode<'a> = &'a dyn Fn(&mut wgpu::CommandEncoder);

/// Submitting an empty command buffer, without and with waiting for it.
fn submit_steps(gpu: &Gpu, reps: usize) -> anyhow::Result<Vec<FloorStep>> {
    let empty = || {
        gpu.device
            .create_command_encoder(&Default::default())
            .finish()
    };
    let mut steps = vec![];
    steps.push(step("submit", reps, || {
        gpu.queue.submit([empty()]);
        Ok(())
    })?);
    gpu.wait()?;
    steps.push(step("submit + wait", reps, || {
        gpu.queue.submit([empty()]);
        gpu.wait()
    })?);
    Ok(steps)
}

/// Clearing a `width`² target, and [`PASSES`] empty render and compute passes.
fn pass_steps(gpu: &Gpu, width: u32, reps: usize) -> anyhow::Result<Vec<FloorStep>> {
    let mut steps = vec![];
    let target = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("floor target"),
        size: wgpu::Extent3d {
            width,
            height: width,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = target.create_view(&Default::default());
    // One command buffer, encoded by `encode`, submitted and waited for.
    let submitted = |encode: Encode| {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        encode(&mut enc);
        gpu.queue.submit([enc.finish()]);
        gpu.wait()
    };
    steps.push(step("clear + wait", reps, || {
        submitted(&|enc| {
            drop(render_core::bind::color_pass(
                enc, "floor", &view, true, true, None,
            ))
        })
    })?);
    // What a pass costs before it does anything: the ray caster's passes mode draws ~10 a
    // round and the splatter one a slab, so a frame of many passes pays this many times.
    let empty_passes: [(&str, Encode); 2] = [
        ("render", &|enc| {
            drop(render_core::bind::color_pass(
                enc, "floor", &view, false, true, None,
            ))
        }),
        ("compute", &|enc| {
            drop(enc.begin_compute_pass(&Default::default()))
        }),
    ];
    for (kind, one_pass) in empty_passes {
        steps.push(step(&passes_step(kind), reps, || {
            submitted(&|enc| {
                for _ in 0..PASSES {
                    one_pass(enc);
                }
            })
        })?);
    }
    Ok(steps)
}

/// Reading a few bytes back (into a new and into a reused buffer) and, where the adapter has
/// them, a pair of timestamps.
fn readback_steps(gpu: &Gpu, reps: usize) -> anyhow::Result<Vec<FloorStep>> {
    let mut steps = vec![];
    let counters = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("floor counters"),
        size: 32,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    steps.push(step("readback, new buffer", reps, || {
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("floor readback"),
            size: 32,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&counters, 0, &staging, 0, 32);
        gpu.queue.submit([enc.finish()]);
        gpu.map_and_copy(&staging, 32, &mut Duration::default())
            .map(|_| ())
    })?);
    steps.push(step("readback, reused buffer", reps, || {
        gpu.read_buffer(&counters, 0, 32).map(|_| ())
    })?);
    if gpu.has_timestamps() {
        let timer = FrameTimer::new(gpu);
        steps.push(step("timestamps", reps, || {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            timer.begin(&mut enc);
            timer.end(&mut enc);
            gpu.queue.submit([enc.finish()]);
            gpu.wait()?;
            timer.gpu_ms(gpu).map(|_| ())
        })?);
    }
    Ok(steps)
}

/// Measures every step at a `width`² viewport, `reps` times each.
pub fn measure(gpu: &Gpu, width: u32, reps: usize) -> anyhow::Result<Floor> {
    anyhow::ensure!(reps >= 1, "the floor needs at least one repetition");
    let mut steps = submit_steps(gpu, reps)?;
    steps.extend(pass_steps(gpu, width, reps)?);
    steps.extend(readback_steps(gpu, reps)?);
    let mut floor = Floor {
        adapter: gpu.adapter.name.clone(),
        width,
        reps,
        steps,
        render_pass_us: None,
        compute_pass_us: None,
    };
    floor.render_pass_us = floor.per_pass_us("render");
    floor.compute_pass_us = floor.per_pass_us("compute");
    Ok(floor)
}

impl Floor {
    /// The fastest time of the step named `name` (µs).
    fn fastest(&self, name: &str) -> Option<f64> {
        self.steps.iter().find(|s| s.step == name).map(|s| s.min_us)
    }

    /// The fixed cost of one empty pass of `kind` ("render", "compute"), µs: the fastest
    /// [`PASSES`]-pass step less the fastest `submit + wait`, over [`PASSES`]; never below 0.
    pub fn per_pass_us(&self, kind: &str) -> Option<f64> {
        let passes = self.fastest(&passes_step(kind))?;
        let submit = self.fastest("submit + wait")?;
        Some(((passes - submit) / PASSES as f64).max(0.0))
    }

    /// A Markdown table of the steps.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "Per-frame floor on {} at {w}×{w}, {} repetitions a step \
             (`tetbench calibrate --floor`; never subtracted from a row):\n\n\
             | step | median (µs) | fastest (µs) |\n|---|---:|---:|\n",
            self.adapter,
            self.reps,
            w = self.width
        );
        for st in &self.steps {
            s.push_str(&format!(
                "| {} | {:.1} | {:.1} |\n",
                st.step, st.median_us, st.min_us
            ));
        }
        if let (Some(render), Some(compute)) = (self.render_pass_us, self.compute_pass_us) {
            s.push_str(&format!(
                "\nOne empty pass (the fastest {PASSES}-pass step less the fastest `submit + wait`, \
                 over {PASSES}): render {render:.1} µs, compute {compute:.1} µs.\n"
            ));
        }
        s
    }
}

/// `tetbench calibrate --floor`.
pub fn run_command(width: u32, reps: usize, json: bool) -> anyhow::Result<()> {
    let gpu = Gpu::new()?;
    let floor = measure(&gpu, width, reps)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&floor)?);
    } else {
        print!("{}", floor.markdown());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every step is measured (timestamps where the adapter has them), in the table's order,
    /// with positive, ordered times; the reused readback creates at most one buffer however
    /// often it runs.
    #[test]
    fn the_floor_has_every_step() {
        let gpu = Gpu::new().expect("an adapter (lavapipe)");
        let before = gpu.staging_buffers_created();
        let floor = measure(&gpu, 16, 5).unwrap();
        let names: Vec<&str> = floor.steps.iter().map(|s| s.step.as_str()).collect();
        let mut want = vec![
            "submit",
            "submit + wait",
            "clear + wait",
            "64 empty render passes + wait",
            "64 empty compute passes + wait",
            "readback, new buffer",
            "readback, reused buffer",
        ];
        if gpu.has_timestamps() {
            want.push("timestamps");
        }
        assert_eq!(names, want);
        for s in &floor.steps {
            assert!(s.min_us > 0.0 && s.min_us <= s.median_us, "{s:?}");
        }
        assert!(gpu.staging_buffers_created() - before <= 1);
        assert!(floor.render_pass_us.is_some() && floor.compute_pass_us.is_some());
        assert_eq!(floor.render_pass_us, floor.per_pass_us("render"));
        let table = floor.markdown();
        assert_eq!(
            table.lines().filter(|l| l.starts_with("| ")).count(),
            want.len() + 1
        );
    }

    /// A pass's cost is the passes step less one submission and wait, over the passes: it
    /// moves with either step, and reads 0 rather than below it.
    #[test]
    fn one_pass_is_the_passes_less_the_submission() {
        let at = |step: &str, min_us: f64| FloorStep {
            step: step.to_string(),
            median_us: min_us + 1.0,
            min_us,
        };
        let mut floor = Floor {
            adapter: "test".into(),
            width: 16,
            reps: 1,
            steps: vec![
                at("submit + wait", 40.0),
                at(&passes_step("render"), 40.0 + 64.0 * 17.0),
                at(&passes_step("compute"), 40.0 + 64.0 * 14.0),
            ],
            render_pass_us: None,
            compute_pass_us: None,
        };
        assert_eq!(floor.per_pass_us("render"), Some(17.0));
        assert_eq!(floor.per_pass_us("compute"), Some(14.0));
        assert!(!floor.markdown().contains("One empty pass"));
        floor.render_pass_us = floor.per_pass_us("render");
        floor.compute_pass_us = floor.per_pass_us("compute");
        assert!(floor.markdown().contains("render 17.0 µs, compute 14.0 µs"));
        floor.steps[0].min_us = 40.0 + 64.0;
        assert_eq!(floor.per_pass_us("render"), Some(16.0));
        floor.steps[0].min_us = 1e6;
        assert_eq!(floor.per_pass_us("compute"), Some(0.0));
        floor.steps.remove(0);
        assert_eq!(floor.per_pass_us("render"), None);
    }
}
