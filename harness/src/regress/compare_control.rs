//! compare divides by the machine, not by the rows: where both runs carry the control measured
//! beside their rows ([`crate::calibrate::control`]), every round value of both sides is put
//! on the scale of BASE's median control before any test.
//!
//! Why: the old rule divided NEW by the run-wide factor (the median of the groups' ratios).
//! That cannot tell a slower machine from a change that slows every algorithm alike: two runs
//! of one build, the second beside a compile, read as a ×2.19 regression beyond the drift
//! limit, and a render-core change that made every frame ×1.36 slower was divided out as
//! drift. The control is measured by the same machine at the same moments but by none of the
//! renderers' code, so what it shows is the machine, and what the rows show beyond it is the
//! code.
//!
//! How: a row's round r value t is replaced by t · k_r, where k_r is the speed of that round's
//! control over BASE's run median ([`crate::calibrate::control::speed_factor`], a geometric
//! mean over the control's figures): a round measured while the machine ran at 60 % of its
//! usual speed counts 0.6 of its time. The machine's drift between the runs is the ratio of
//! the two runs' median controls, reported, never judged. What remains is judged as before,
//! and a run-wide residual beyond the threshold is a change common to every algorithm.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::calibrate::control::{self, Figures};
use crate::results::metrics::summarize;
use crate::results::{ResultsFile, Row};

/// What the control says of the two runs' machines (`compare.json`'s `machine`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MachineDrift {
    /// The time NEW's machine needed for BASE's work, over BASE's (the two runs' median
    /// controls): 2.0 means NEW ran on a machine half as fast, whatever the code.
    pub factor: f64,
    /// Figures of the control both runs measured.
    pub figures: Vec<String>,
}

/// Whether a results set carries a control for every measured row.
pub fn has_control(f: &ResultsFile) -> bool {
    let rounds = f.run.rounds.max(1) as usize;
    f.control.is_some()
        && f.rows
            .iter()
            .filter(|r| r.ok() && !r.samples.total_ms.is_empty())
            .all(|r| r.round_control.len() == rounds)
}

/// Why a side without a control is judged by the old rule (`None`: both have one).
pub fn missing(base: &ResultsFile, new: &ResultsFile) -> Option<String> {
    let sides: Vec<&str> = [("BASE", base), ("NEW", new)]
        .into_iter()
        .filter(|(_, f)| !has_control(f))
        .map(|(s, _)| s)
        .collect();
    (!sides.is_empty()).then(|| {
        format!(
            "{} has no control measured beside its rows (results from before the control, or \
             run with --no-calibrate): the run-wide factor is divided out instead, which \
             cannot tell the machine from a change common to every algorithm",
            sides.join(" and ")
        )
    })
}

/// The time NEW's machine needed for BASE's work, over BASE's: the two runs' median controls
/// (`None`: a side without a control, or no figure in common).
pub fn machine_factor(base: &ResultsFile, new: &ResultsFile) -> Option<f64> {
    control::speed_factor(
        &base.control.as_ref()?.median(),
        &new.control.as_ref()?.median(),
    )
}

/// Puts both sides' `total_ms` samples on the scale of BASE's median control; `None` (and
/// nothing changed) unless both sides carry a control for every measured row.
pub fn normalise(base: &mut ResultsFile, new: &mut ResultsFile) -> Option<MachineDrift> {
    if missing(base, new).is_some() {
        return None;
    }
    let reference = base.control.as_ref()?.median();
    let new_median = new.control.as_ref()?.median();
    let factor = machine_factor(base, new)?;
    for f in [&mut *base, &mut *new] {
        let rounds = f.run.rounds.max(1) as usize;
        for row in &mut f.rows {
            scale_row(row, rounds, &reference);
        }
    }
    Some(MachineDrift {
        factor,
        figures: reference
            .keys()
            .filter(|f| new_median.contains_key(f))
            .map(|f| f.name().to_string())
            .collect(),
    })
}

/// Multiplies each round's `total_ms` samples of `row` by its round's control speed over
/// `reference`, and its summary columns with them.
fn scale_row(row: &mut Row, rounds: usize, reference: &Figures) {
    let samples = &mut row.samples.total_ms;
    if row.round_control.len() != rounds
        || samples.is_empty()
        || !samples.len().is_multiple_of(rounds)
    {
        return;
    }
    let per_round = samples.len() / rounds;
    for (chunk, figures) in samples.chunks_mut(per_round).zip(&row.round_control) {
        let k = control::speed_factor(figures, reference).unwrap_or(1.0);
        for t in chunk {
            *t *= k;
        }
    }
    if let Some(s) = summarize(samples) {
        (row.total_ms, row.total_ms_min, row.total_ms_max) =
            (Some(s.median), Some(s.min), Some(s.max));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::machine::Figure;

    fn figures(fill: f64, walk: f64) -> Figures {
        [
            (Figure::FillFragmentsPerSec, fill),
            (Figure::RayStepsPerSec, walk),
        ]
        .into()
    }

    #[test]
    fn a_round_on_a_slower_machine_counts_less_of_its_time() {
        let reference = figures(100.0, 10.0);
        let mut row = Row {
            total_ms: Some(20.0),
            ..Row::default()
        };
        row.samples.total_ms = vec![10.0, 20.0];
        // Round 0 at the reference speed, round 1 at half of it on both figures.
        row.round_control = vec![figures(100.0, 10.0), figures(50.0, 5.0)];
        scale_row(&mut row, 2, &reference);
        assert_eq!(row.samples.total_ms, vec![10.0, 10.0]);
        assert_eq!(row.total_ms, Some(10.0));
    }
}
