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
//! probe's fastest configuration (chosen once per run from the calibration's own set), a
//! share of its pieces sized to about [`TARGET_S`] (the rates are per unit of work, so a share
//! measures the same figure as the whole), once. A row's round is priced with the best of the
//! two samples around it (the less disturbed, as the calibration keeps the best repetition),
//! kept in the row as `round_control`.

use std::time::Instant;

use crate::calibrate::probes::{ProbeContext, Timing, PROBES};
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

/// How long one configuration of a control probe runs in a sample, once: long enough that a
/// submission's fixed cost (tens of µs on lavapipe) is a small part of it, short enough that a
/// sample of every probe stays a fraction of a second. Shorter or repeated shares did worse:
/// on the default suite, idle and beside two busy loops (2-core Xeon VM, llvmpipe), the busy
/// run's median fractions over the idle run's read ×0.80–×1.01 with one 10 ms share,
/// ×0.53–×0.98 with the median of three 5 ms shares and ×0.65–×1.02 with one 20 ms share:
/// short shares slip between the busy loops' time slices where the rows' frames do not, so
/// they understate how much slower a busy machine runs the rows.
pub const TARGET_S: f64 = 0.01;

/// The fewest pieces a share runs (all of them where there are fewer): a share must still
/// spread over the device's threads as the whole does. Measured: the splat probe's widest
/// footprints make 2 workgroups in all, and one of them ran on one of lavapipe's two threads,
/// at half the rate, so six splat rows of the default suite beat a bound priced by it.
pub const MIN_PIECES: u32 = 256;

/// The control probes prepared for a run: each probe's fastest configuration and the share of
/// its pieces that runs in about [`TARGET_S`], kept between samples (pipelines and buffers are
/// made once).
pub struct ControlBench<'g> {
    chosen: Vec<Chosen<'g>>,
}

struct Chosen<'g> {
    probe: &'static crate::calibrate::probes::Probe,
    /// Each kept configuration and how many of its pieces a sample runs.
    workloads: Vec<(crate::calibrate::probes::Workload<'g>, u32)>,
}

/// One timed share of a workload: its units, parameter and seconds.
fn time_part(w: &mut crate::calibrate::probes::Workload, k: u32) -> anyhow::Result<Timing> {
    let t0 = Instant::now();
    let units = w.run_part(k)?;
    Ok(Timing {
        units,
        param: w.param,
        seconds: t0.elapsed().as_secs_f64().max(1e-9),
    })
}

impl<'g> ControlBench<'g> {
    /// Prepares every control probe, times a sixteenth of each configuration (at least
    /// [`MIN_PIECES`]; after a warm-up of the same), keeps the fastest (all of them for the rasterisation fit) and sizes its
    /// share to [`TARGET_S`]. A probe that cannot be prepared here is left out (its figures are
    /// then scaled, and the rows say so).
    pub fn new(ctx: &ProbeContext<'g>) -> ControlBench<'g> {
        let mut chosen = vec![];
        for probe in PROBES.iter().filter(|p| p.in_control) {
            let Ok(workloads) = (probe.prepare)(ctx) else {
                continue;
            };
            let mut timed = vec![];
            for mut w in workloads {
                let fewest = MIN_PIECES.min(w.pieces);
                let k = (w.pieces / 16).max(fewest);
                let Ok(t) = time_part(&mut w, k).and_then(|_| time_part(&mut w, k)) else {
                    continue;
                };
                let share = (k as f64 * TARGET_S / t.seconds)
                    .round()
                    .clamp(fewest as f64, w.pieces as f64);
                timed.push((w, share as u32, t.rate()));
            }
            if probe.combine == crate::calibrate::probes::Combine::Fastest && timed.len() > 1 {
                let best = timed
                    .iter()
                    .enumerate()
                    .max_by(|a, b| a.1 .2.total_cmp(&b.1 .2))
                    .map_or(0, |(i, _)| i);
                let keep = timed.swap_remove(best);
                timed = vec![keep];
            }
            if !timed.is_empty() {
                chosen.push(Chosen {
                    probe,
                    workloads: timed.into_iter().map(|(w, k, _)| (w, k)).collect(),
                });
            }
        }
        ControlBench { chosen }
    }

    pub fn probe_names(&self) -> Vec<String> {
        self.chosen
            .iter()
            .map(|c| c.probe.name.to_string())
            .collect()
    }

    /// One control measurement: each kept configuration's share once.
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
            let timings: Vec<Timing> = c
                .workloads
                .iter_mut()
                .filter_map(|(w, k)| time_part(w, *k).ok())
                .collect();
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
