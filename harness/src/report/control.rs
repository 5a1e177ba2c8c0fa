//! The report's view of the control measured beside the rows ([`crate::calibrate::control`]):
//! each sample's speed against the run's median, in the order taken, so that a reader sees
//! when the machine slowed and which rows it slowed with.

use serde::Serialize;

use crate::results::control::{speed_factor, Control};

/// One sample as the report shows it.
#[derive(Serialize)]
pub struct ControlLine {
    pub at_s: String,
    pub dataset: String,
    pub round: u32,
    /// Speed against the run's median control (1.00: typical; 0.50: half as fast).
    pub speed: String,
    pub seconds: String,
}

/// What the report's control section shows.
#[derive(Serialize)]
pub struct ControlView {
    pub lines: Vec<ControlLine>,
    /// The samples as an SVG polyline's points (x: seconds into the run, y: speed), on a
    /// 600 × 120 canvas with speed 0 at the bottom and 2 at the top.
    pub points: String,
    /// y of speed 1 on that canvas.
    pub median_y: f64,
    pub summary: String,
}

const WIDTH: f64 = 600.0;
const HEIGHT: f64 = 120.0;

pub fn view(control: &Control, run_seconds: Option<f64>) -> Option<ControlView> {
    let median = control.median();
    let speeds: Vec<(f64, f64)> = control
        .samples
        .iter()
        .map(|s| {
            (
                s.at_s,
                speed_factor(&s.figures, &median).unwrap_or(f64::NAN),
            )
        })
        .collect();
    let last = speeds.iter().map(|p| p.0).fold(1e-9, f64::max);
    let y = |speed: f64| HEIGHT - speed.clamp(0.0, 2.0) / 2.0 * HEIGHT;
    let points = speeds
        .iter()
        .filter(|p| p.1.is_finite())
        .map(|(t, s)| format!("{:.1},{:.1}", t / last * WIDTH, y(*s)))
        .collect::<Vec<_>>()
        .join(" ");
    let finite: Vec<f64> = speeds
        .iter()
        .map(|p| p.1)
        .filter(|s| s.is_finite())
        .collect();
    if finite.is_empty() {
        return None;
    }
    let (lo, hi) = finite.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), s| {
        (lo.min(*s), hi.max(*s))
    });
    let share = run_seconds
        .filter(|t| *t > 0.0)
        .map(|t| format!(", {:.1} % of the run", control.seconds() / t * 100.0))
        .unwrap_or_default();
    Some(ControlView {
        lines: control
            .samples
            .iter()
            .zip(&speeds)
            .map(|(s, (_, speed))| ControlLine {
                at_s: format!("{:.1}", s.at_s),
                dataset: s.dataset.clone(),
                round: s.round,
                speed: format!("{speed:.2}"),
                seconds: format!("{:.2}", s.seconds),
            })
            .collect(),
        points,
        median_y: y(1.0),
        summary: format!(
            "{} samples of {} probes ({}), {:.1} s in all{share}; the machine's speed ranged \
             ×{lo:.2}–×{hi:.2} of the run's median",
            control.samples.len(),
            control.probes.len(),
            control.probes.join(", "),
            control.seconds()
        ),
    })
}
