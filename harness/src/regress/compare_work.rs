//! compare's exact gate on **work**: every counter a row reports (fragments, triangles,
//! covering tets, ray steps, passes, k-buffer overflows, splat fragments, sort keys …) and its
//! GPU bytes (in all, persistent, per frame) are compared for equality, without statistics.
//!
//! Why exactly: a renderer's work on one adapter is a function of the mesh, the view and the
//! code, not of the machine's load, so a count that moved by one is a change of the code (or
//! of the data), however busy the machine was — where a 2 % change of time is lost in the
//! scatter of a shared 2-core VM (docs/regression.md, "Power"). A count that grew is a
//! regression, one that shrank an improvement; a counter only one side reports is a change.
//!
//! The exception is declared, not guessed: a counter the algorithm's description
//! ([`render_core::AlgorithmDescription::nondeterministic_counters`]) names for the row's
//! variant on the row's kind of adapter (HAVS's racy single pass on a GPU) is decided by a race
//! and differs between frames. Rows keep only its median over the frames, so it is judged by
//! compare's factor threshold instead (a change needs NEW/BASE ≥ `--threshold` or
//! ≤ 1/`--threshold`), and the change names that rule.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use render_core::Shading;

use crate::results::Row;

/// How a work figure was judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum WorkRule {
    /// Any difference is a change.
    Exact,
    /// Declared nondeterministic on this adapter: a change needs the factor threshold.
    Threshold,
}

/// Which way a work figure moved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum WorkVerdict {
    /// NEW does more: a regression.
    More,
    /// NEW does less: an improvement.
    Less,
    /// Only NEW reports it: a change.
    Added,
    /// Only BASE reports it: a change.
    Removed,
}

impl WorkVerdict {
    pub fn label(self) -> &'static str {
        match self {
            WorkVerdict::More => "more",
            WorkVerdict::Less => "less",
            WorkVerdict::Added => "added",
            WorkVerdict::Removed => "removed",
        }
    }
}

/// One work counter or byte figure of a row that NEW changed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WorkChange {
    /// The counter (`fragments`, `ray_steps` …) or byte figure (`gpu_bytes`,
    /// `gpu_bytes_persistent`, `gpu_bytes_frame`).
    pub counter: String,
    /// `None`: that side does not report it.
    pub base: Option<f64>,
    pub new: Option<f64>,
    /// NEW / BASE (`None` where a side lacks it or BASE is 0).
    pub ratio: Option<f64>,
    pub rule: WorkRule,
    pub verdict: WorkVerdict,
}

impl WorkChange {
    /// `fragments 1200 → 1224 (×1.020)`.
    pub fn describe(&self) -> String {
        let v = |x: Option<f64>| x.map_or("-".to_string(), crate::results::named::trim_float);
        let mut s = format!("{} {} → {}", self.counter, v(self.base), v(self.new));
        if let Some(r) = self.ratio {
            s.push_str(&format!(" (×{r:.4})"));
        }
        if self.rule == WorkRule::Threshold {
            s.push_str(" [nondeterministic on this adapter: judged by the threshold]");
        }
        s
    }
}

/// The byte figures of a row, by column name.
fn byte_figures(r: &Row) -> [(&'static str, Option<u64>); 3] {
    [
        ("gpu_bytes", r.gpu_bytes),
        ("gpu_bytes_persistent", r.gpu_bytes_persistent),
        ("gpu_bytes_frame", r.gpu_bytes_frame),
    ]
}

/// The counters the row's algorithm declares nondeterministic for its variant on its adapter.
fn nondeterministic(r: &Row) -> &'static [&'static str] {
    crate::algorithms::describe(&r.algorithm).map_or(&[], |d| {
        (d.nondeterministic_counters)(&r.settings, Shading::of_device_type(&r.device_type))
    })
}

/// Every work figure of two matched rows that differs (in BASE's order, then those only NEW
/// reports). Rows where either side failed compare nothing: a failed row counted nothing.
pub fn work_changes(b: &Row, n: &Row, threshold: f64) -> Vec<WorkChange> {
    if !b.ok() || !n.ok() {
        return vec![];
    }
    let racy = nondeterministic(n);
    let mut figures: Vec<(String, Option<f64>, Option<f64>)> = vec![];
    for ((name, bv), (_, nv)) in byte_figures(b).into_iter().zip(byte_figures(n)) {
        figures.push((name.into(), bv.map(|v| v as f64), nv.map(|v| v as f64)));
    }
    for (name, bv) in b.counters.iter() {
        figures.push((name.into(), Some(bv), n.counters.get(name)));
    }
    for (name, nv) in n.counters.iter() {
        if b.counters.get(name).is_none() {
            figures.push((name.into(), None, Some(nv)));
        }
    }
    figures
        .into_iter()
        .filter_map(|(counter, base, new)| {
            let rule = if racy.contains(&counter.as_str()) {
                WorkRule::Threshold
            } else {
                WorkRule::Exact
            };
            let ratio = base.zip(new).filter(|(b, _)| *b != 0.0).map(|(b, n)| n / b);
            let verdict = match (base, new) {
                (None, None) => return None,
                (Some(_), None) => WorkVerdict::Removed,
                (None, Some(_)) => WorkVerdict::Added,
                // NaN (a median that could not be taken) equals nothing: left alone.
                (Some(b), Some(n)) if b.is_nan() || n.is_nan() || b == n => return None,
                (Some(b), Some(n)) => {
                    if rule == WorkRule::Threshold
                        && ratio.is_some_and(|r| r < threshold && r > 1.0 / threshold)
                    {
                        return None;
                    }
                    if n > b {
                        WorkVerdict::More
                    } else {
                        WorkVerdict::Less
                    }
                }
            };
            Some(WorkChange {
                counter,
                base,
                new,
                ratio,
                rule,
                verdict,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(counters: &str, bytes: u64) -> Row {
        Row {
            algorithm: "havs".into(),
            settings: crate::algorithms::parse_settings(
                "havs",
                "k=2;sort=cpu-radix;tags=two;mode=fragment-race;et=true",
            )
            .unwrap(),
            counters: counters.into(),
            gpu_bytes: Some(bytes),
            gpu_bytes_persistent: Some(bytes),
            device_type: "Cpu".into(),
            ..Row::default()
        }
    }

    /// One fragment more is a regression naming the counter and its ratio; equal counts are
    /// no change; a byte figure that shrank is an improvement.
    #[test]
    fn a_count_one_higher_is_a_change_and_equal_counts_are_not() {
        let base = row("fragments=1000;triangles=50", 4096);
        assert!(work_changes(&base, &base.clone(), 1.10).is_empty());
        let more = row("fragments=1001;triangles=50", 4096);
        let c = work_changes(&base, &more, 1.10);
        assert_eq!(c.len(), 1, "{c:?}");
        assert_eq!(c[0].counter, "fragments");
        assert_eq!(c[0].verdict, WorkVerdict::More);
        assert_eq!(c[0].rule, WorkRule::Exact);
        assert_eq!(c[0].ratio, Some(1.001));
        let smaller = row("fragments=1000;triangles=50", 4000);
        let c = work_changes(&base, &smaller, 1.10);
        assert_eq!(c.len(), 2, "{c:?}");
        assert!(c.iter().all(|c| c.verdict == WorkVerdict::Less));
        let added = row("fragments=1000;triangles=50;passes=3", 4096);
        assert_eq!(
            work_changes(&base, &added, 1.10)[0].verdict,
            WorkVerdict::Added
        );
    }

    /// HAVS's racy pass declares its race-decided counters nondeterministic on a GPU: there a
    /// small change of `fragments` is noise, a change beyond the threshold still counts, and
    /// on lavapipe (in-order shading) the same +1 is exact.
    #[test]
    fn declared_racy_counters_are_judged_by_the_threshold_on_a_gpu_only() {
        let on = |device: &str, counters: &str| Row {
            device_type: device.into(),
            ..row(counters, 4096)
        };
        let base = on("DiscreteGpu", "fragments=1000;triangles=50");
        let plus_one = on("DiscreteGpu", "fragments=1001;triangles=50");
        assert!(work_changes(&base, &plus_one, 1.10).is_empty());
        let far = on("DiscreteGpu", "fragments=1200;triangles=50");
        let c = work_changes(&base, &far, 1.10);
        assert_eq!(c[0].rule, WorkRule::Threshold);
        assert_eq!(c[0].verdict, WorkVerdict::More);
        // triangles are not racy: exact on a GPU too.
        let tri = on("DiscreteGpu", "fragments=1000;triangles=51");
        assert_eq!(work_changes(&base, &tri, 1.10)[0].rule, WorkRule::Exact);
        let cpu = work_changes(
            &on("Cpu", "fragments=1000;triangles=50"),
            &on("Cpu", "fragments=1001;triangles=50"),
            1.10,
        );
        assert_eq!(cpu[0].rule, WorkRule::Exact);
    }
}
