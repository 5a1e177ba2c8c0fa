//! The control: the probes the roofline prices ([`PROBES`] with `in_control`), timed beside the
//! rows of every run, so that every time is judged against the machine of the same moment.
//!
//! Why: on a shared or virtual machine the speed of the hour is most of a timing. The cached
//! calibration is the best this adapter ever reached, at another hour; a row's fraction of it
//! measured the hour as much as the renderer (the same VM calibrated fill at 1.5·10⁸ and
//! 8.6·10⁸ fragments/s), and `compare` could not tell a busy runner from a slower build. A
//! control taken within seconds of each row makes the row's roofline, and compare's drift, a
//! ratio taken in one run.
//!
//! How: the run takes a [`ControlSample`] before every round of a data set and after its last
//! (one variant at a time, `--rounds 1`: before the data set's first variant, after its last,
//! and between variants when [`INTERVAL_S`] has passed). Each sample runs every control
//! probe's fastest configuration (chosen once per run from the calibration's own set) once
//! after one warm-up. A row's round is priced with the best of the two samples around it
//! (the less disturbed, as the calibration keeps the best repetition): [`RoundControl`].

use std::time::Instant;

use crate::calibrate::probes::{best_seconds_of, ProbeContext, Timing, PROBES};
pub use crate::results::control::{
    best_figures, median_figures, row_figures, speed_factor, Control, ControlSample, Figures,
    Pricing,
};
use crate::results::machine::{Calibration, Figure};

/// Between two samples of a data set measured one variant at a time, at most this long.
pub const INTERVAL_S: f64 = 20.0;

/// The calibration a row is priced with: `base` with every figure the control measured
/// replaced by the control's, and every other figure the roofline prices scaled by the
/// control's factor against `base` (named in the returned list).
pub fn priced(base: &Calibration, control: &Figures) -> (Calibration, Vec<Figure>) {
    let mut out = base.clone();
    let base_figures: Figures = Figure::ALL.iter().map(|&f| (f, f.get(base))).collect();
    let factor = speed_factor(control, &base_figures).unwrap_or(1.0);
    let mut scaled = vec![];
    for probe in PROBES.iter().filter(|p| p.in_control) {
        for &figure in probe.figures {
            match control.get(&figure) {
                Some(&v) if figure.speed(v) > 0.0 => figure.set(&mut out, v),
                _ if figure.speed(figure.get(base)) > 0.0 => {
                    let speed = figure.speed(figure.get(base)) * factor;
                    figure.set(&mut out, figure.from_speed(speed));
                    scaled.push(figure);
                }
                _ => {}
            }
        }
    }
    (out, scaled)
}

/// The control probes prepared for a run: each probe's fastest configuration, kept between
/// samples (pipelines and buffers are made once).
pub struct ControlBench<'g> {
    chosen: Vec<Chosen<'g>>,
}

struct Chosen<'g> {
    probe: &'static crate::calibrate::probes::Probe,
    workloads: Vec<crate::calibrate::probes::Workload<'g>>,
}

impl<'g> ControlBench<'g> {
    /// Prepares every control probe and keeps its fastest configuration (all of them for the
    /// rasterisation fit), timing each once after a warm-up. A probe that cannot be prepared
    /// here is left out (its figures are then scaled, and the row says so).
    pub fn new(ctx: &ProbeContext<'g>) -> ControlBench<'g> {
        let mut chosen = vec![];
        for probe in PROBES.iter().filter(|p| p.in_control) {
            let Ok(mut workloads) = (probe.prepare)(ctx) else {
                continue;
            };
            if probe.combine == crate::calibrate::probes::Combine::Fastest && workloads.len() > 1 {
                let mut best = (0, 0.0);
                for (i, w) in workloads.iter_mut().enumerate() {
                    let units = w.units;
                    if let Ok(s) = best_seconds_of(1, || w.run()) {
                        if units / s > best.1 {
                            best = (i, units / s);
                        }
                    }
                }
                let keep = workloads.swap_remove(best.0);
                workloads = vec![keep];
            }
            chosen.push(Chosen { probe, workloads });
        }
        ControlBench { chosen }
    }

    pub fn probe_names(&self) -> Vec<String> {
        self.chosen
            .iter()
            .map(|c| c.probe.name.to_string())
            .collect()
    }

    /// One control measurement: each kept configuration once after one warm-up.
    pub fn sample(
        &mut self,
        dataset: &str,
        round: u32,
        rows_before: usize,
        at_s: f64,
    ) -> ControlSample {
        let started = Instant::now();
        let mut figures = Figures::new();
        for c in &mut self.chosen {
            let mut timings = vec![];
            for w in &mut c.workloads {
                let (units, param) = (w.units, w.param);
                if let Ok(seconds) = best_seconds_of(1, || w.run()) {
                    timings.push(Timing {
                        units,
                        param,
                        seconds,
                    });
                }
            }
            if timings.len() == c.workloads.len() {
                figures.extend(c.probe.figures_of(&timings));
            }
        }
        ControlSample {
            dataset: dataset.to_string(),
            round,
            rows_before,
            at_s,
            utc: crate::results::machine::iso8601_utc(std::time::SystemTime::now()),
            seconds: started.elapsed().as_secs_f64(),
            figures,
        }
    }
}
