//! compare across machines: two adapters, or two hosts of one adapter. What the rows' times
//! say there is the machines as much as the code, so compare prints them as information,
//! never as a gate: per group, the raw ratio NEW/BASE beside the same ratio with the machines
//! divided out by the controls both runs measured beside their rows.
//!
//! Why the control and not the cached calibration: each run's control was taken within
//! seconds of its rows, on its own machine, by none of the renderers' code; its ratio between
//! the runs is what the same work cost on the two machines at those moments. Dividing it out
//! leaves how the two runs' code fared against the same probes — a ratio two machines can
//! share, but not a verdict: the probes price the work, not every way two devices differ
//! (caches, a driver's shader compiler), so a change on one adapter is never judged against
//! a run on another.

use std::path::Path;

use render_core::Settings;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::regress::compare_control::{has_control, machine_factor};
use crate::regress::compare_setup::key;
use crate::results::aggregate::GroupKey;
use crate::results::description::as_text;
use crate::results::{ResultsFile, Row};

/// compare.json's `across`: the two runs' machines differ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AcrossMachines {
    /// How the machines differ (adapters, or hosts of one adapter).
    pub reason: String,
    /// The time NEW's machine needed for the control's work, over BASE's (the two runs'
    /// median controls): 0.5 means NEW's machine did the probes' work twice as fast.
    pub machine_factor: f64,
    /// Whether this comparison is information only: adapters differ and nothing normalised
    /// them into a verdict (no `--normalised`), so no time, image or work finding gates.
    pub information_only: bool,
    pub groups: Vec<AcrossGroup>,
}

/// One algorithm × settings × data set × viewport across the two machines.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AcrossGroup {
    pub algorithm: String,
    #[serde(serialize_with = "as_text")]
    #[schemars(with = "String")]
    pub settings: Settings,
    pub dataset: String,
    pub width: u32,
    pub height: u32,
    /// Rows matched on both sides.
    pub rows: usize,
    /// NEW/BASE: the geometric mean over the matched rows of their median `total_ms` ratio.
    pub raw_ratio: f64,
    /// `raw_ratio` over the machine factor: NEW/BASE on the scale of one machine.
    pub control_ratio: f64,
}

/// How the two runs' machines differ (`None`: one adapter on one host, or a side whose host
/// is unknown).
pub fn difference(base: &ResultsFile, new: &ResultsFile, adapters: (&str, &str)) -> Option<String> {
    if adapters.0 != adapters.1 {
        return Some(format!(
            "two adapters: BASE on {}, NEW on {}",
            adapters.0, adapters.1
        ));
    }
    match (&base.machine.host_name, &new.machine.host_name) {
        (Some(b), Some(n)) if b != n => {
            Some(format!("two hosts of one adapter: BASE on {b}, NEW on {n}"))
        }
        _ => None,
    }
}

/// compare's first step for two machines: two adapters without `--normalised` are compared
/// as information only where both runs measured a control (the control divides the machines
/// out as on one adapter, but nothing gates), and refused otherwise; the table, where the
/// machines differ and both have a control.
pub fn across_or_refuse(
    (base, new): (&ResultsFile, &ResultsFile),
    (base_dir, new_dir): (&Path, &Path),
    (ba, na): (&str, &str),
    normalised: bool,
) -> anyhow::Result<Option<AcrossMachines>> {
    let information_only = ba != na && !normalised;
    let table =
        difference(base, new, (ba, na)).and_then(|why| across(base, new, why, information_only));
    if information_only && table.is_none() {
        anyhow::bail!(
            "{} ran on {ba} but {} on {na}: times from two adapters say nothing about a change. \
             Pass --normalised to compare calibration-normalised figures instead (or compare \
             two runs that both measured a control, for ratios printed as information)",
            base_dir.display(),
            new_dir.display()
        );
    }
    Ok(table)
}

/// The across-machines table, where the machines differ and both runs carry a control
/// (`None` otherwise). Reads the rows as measured: call it before any normalisation.
pub fn across(
    base: &ResultsFile,
    new: &ResultsFile,
    reason: String,
    information_only: bool,
) -> Option<AcrossMachines> {
    if !(has_control(base) && has_control(new)) {
        return None;
    }
    let machine_factor = machine_factor(base, new)?;
    let groups = GroupKey::distinct(base.rows.iter())
        .into_iter()
        .filter_map(|g| group(&g, &base.rows, &new.rows, machine_factor))
        .collect();
    Some(AcrossMachines {
        reason,
        machine_factor,
        information_only,
        groups,
    })
}

fn group(g: &GroupKey, base: &[Row], new: &[Row], machine_factor: f64) -> Option<AcrossGroup> {
    let logs: Vec<f64> = base
        .iter()
        .filter(|b| g.matches(b))
        .filter_map(|b| {
            let n = new.iter().find(|n| key(n) == key(b))?;
            let (tb, tn) = (b.total_ms?, n.total_ms?);
            (tb > 0.0 && tn > 0.0).then(|| (tn / tb).ln())
        })
        .collect();
    if logs.is_empty() {
        return None;
    }
    let raw_ratio = (logs.iter().sum::<f64>() / logs.len() as f64).exp();
    Some(AcrossGroup {
        algorithm: g.algorithm.clone(),
        settings: g.settings.clone(),
        dataset: g.dataset.clone(),
        width: g.width,
        height: g.height,
        rows: logs.len(),
        raw_ratio,
        control_ratio: raw_ratio / machine_factor,
    })
}

/// The table's lines, for the terminal, compare.md and compare.html.
pub fn lines(a: &AcrossMachines) -> Vec<String> {
    let mut out = vec![format!(
        "across machines ({}), information only, never a gate: the control says NEW's \
         machine needed ×{:.3} of BASE's time for the same probes; NEW/BASE raw, then with \
         that divided out",
        a.reason, a.machine_factor
    )];
    for g in &a.groups {
        out.push(format!(
            "{} {} @ {} {}×{}: raw ×{:.3}, control-normalised ×{:.3} ({} rows)",
            g.algorithm,
            g.settings,
            g.dataset,
            g.width,
            g.height,
            g.raw_ratio,
            g.control_ratio,
            g.rows
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::control::{Control, ControlSample, Figures};
    use crate::results::machine::Figure;

    fn results(host: &str, ms: f64, fill: f64) -> ResultsFile {
        let figures: Figures = [(Figure::FillFragmentsPerSec, fill)].into();
        let mut machine = crate::results::machine::MachineInfo::collect();
        machine.host_name = Some(host.into());
        let mut row = Row {
            algorithm: "havs".into(),
            dataset: "box:1k".into(),
            viewpoint: "+x".into(),
            total_ms: Some(ms),
            ..Row::default()
        };
        row.samples.total_ms = vec![ms];
        row.round_control = vec![figures.clone()];
        ResultsFile {
            schema_version: crate::results::SCHEMA_VERSION,
            machine,
            run: crate::results::RunDescription {
                rounds: 1,
                ..Default::default()
            },
            finished_utc: None,
            rows: vec![row],
            errors: vec![],
            control: Some(Control {
                probes: vec!["fill".into()],
                setup_seconds: 0.0,
                samples: vec![ControlSample {
                    dataset: "box:1k".into(),
                    round: 0,
                    rows_before: 0,
                    at_s: 0.0,
                    utc: String::new(),
                    seconds: 0.01,
                    figures,
                }],
            }),
        }
    }

    /// NEW's machine twice as fast (its control twice the fill rate) and its rows twice as
    /// fast: raw ×0.5, the same code on the machines' common scale ×1.0; rows that did not
    /// speed up with the machine read ×2.0 once it is divided out.
    #[test]
    fn the_control_divides_the_machines_out_of_the_ratio() {
        let base = results("a", 10.0, 100.0);
        let new = results("b", 5.0, 200.0);
        let why = difference(&base, &new, ("x", "x")).unwrap();
        assert!(why.contains("two hosts"), "{why}");
        let a = across(&base, &new, why, false).unwrap();
        assert!((a.machine_factor - 0.5).abs() < 1e-12);
        let g = &a.groups[0];
        assert!((g.raw_ratio - 0.5).abs() < 1e-12);
        assert!((g.control_ratio - 1.0).abs() < 1e-12);
        let slow = results("b", 10.0, 200.0);
        let g = across(&base, &slow, "x".into(), false).unwrap().groups[0].clone();
        assert!((g.control_ratio - 2.0).abs() < 1e-12);
        // One host, one adapter: nothing across; a side without a control: no table.
        assert!(difference(&base, &results("a", 5.0, 200.0), ("x", "x")).is_none());
        let mut bare = new.clone();
        bare.control = None;
        assert!(across(&base, &bare, "x".into(), false).is_none());
    }
}
