//! compare's exact gate on **work**: every counter a row reports (fragments, triangles,
//! covering tets, ray steps, passes, k-buffer overflows, splat fragments, sort keys …) and its
//! GPU bytes (in all, persistent, per frame) are compared for equality, without statistics.
//!
//! Why exactly: a renderer's work on one adapter is a function of the mesh, the view and the
//! code, not of the machine's load, so a count that moved by one is a change of the code (or
//! of the data), however busy the machine was — where a 2 % change of time is lost in the
//! scatter of a shared 2-core VM (docs/regression.md, "Power"). A count that grew is a
//! regression, one that shrank an improvement; a counter only one side reports is a change.
//! Fractions (means, bytes per tet) are compared as the row's text form writes them (4
//! decimals), and rates among the counters (`…_per_sec`) are time, so not compared here.
//!
//! The exception is declared, not guessed: a counter the algorithm's description
//! ([`render_core::AlgorithmDescription::nondeterministic_counters`]) names for the row's
//! variant on the row's kind of adapter (HAVS's racy single pass on a GPU) is decided by a race
//! and differs between frames. Such a counter is compared **statistically**, as time is: the
//! row keeps its per-frame values (`samples.counters`), one value per round is their median,
//! and asv's rule decides (Mann–Whitney p < α and a ratio of medians beyond `--threshold`,
//! [`crate::regress::compare_time::time_test`]). Where either side has fewer than
//! [`MIN_ROUNDS`] rounds of such values (rows written before they were kept, or a one-round
//! run), only the factor threshold decides, and the change says which rule judged it.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::regress::compare_rounds::{round_values, Rounds, MIN_ROUNDS};
use crate::regress::compare_time::{time_test, Verdict};
use crate::results::Row;

/// How a work figure was judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum WorkRule {
    /// Any difference is a change.
    Exact,
    /// Declared nondeterministic on this adapter, with too few rounds of per-frame values to
    /// test: a change needs the factor threshold.
    Threshold,
    /// Declared nondeterministic on this adapter: asv's rule on one value per round (p < α
    /// and the factor threshold), as for time.
    Statistical,
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
    /// [`WorkRule::Statistical`]: the Mann–Whitney p of the per-round values.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub p_value: Option<f64>,
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
        match (self.rule, self.p_value) {
            (WorkRule::Exact, _) => {}
            (WorkRule::Threshold, _) => {
                s.push_str(" [nondeterministic on this adapter: judged by the threshold]")
            }
            (WorkRule::Statistical, p) => s.push_str(&format!(
                " [nondeterministic on this adapter: per-round values, p = {}]",
                p.map_or("-".into(), |p| format!("{p:.3}"))
            )),
        }
        s
    }
}

/// Counters that are rates (`voxels_per_sec`: the splatter's work over its frame time) are
/// time, not work: the time tests judge them, the exact gate does not.
fn is_rate(counter: &str) -> bool {
    counter.ends_with("_per_sec")
}

/// Whether two values of a work figure are the same: equal as the row's text form writes them
/// (integers exactly, fractions such as `steps_mean` to 4 decimals,
/// [`crate::results::named::trim_float`]). Results written in that form before the rows kept
/// full precision would otherwise differ from their own recomputation in the last bits.
fn same_figure(a: f64, b: f64) -> bool {
    use crate::results::named::trim_float;
    a == b || trim_float(a) == trim_float(b)
}

/// The byte figures of a row, by column name.
fn byte_figures(r: &Row) -> [(&'static str, Option<u64>); 3] {
    [
        ("gpu_bytes", r.gpu_bytes),
        ("gpu_bytes_persistent", r.gpu_bytes_persistent),
        ("gpu_bytes_frame", r.gpu_bytes_frame),
    ]
}

/// How compare judges the work of two matched rows: its factor threshold and α, and the
/// rounds each side holds (a nondeterministic counter's samples split into them).
#[derive(Debug, Clone, Copy)]
pub struct WorkJudge {
    pub threshold: f64,
    pub alpha: f64,
    pub rounds: Rounds,
}

/// A nondeterministic counter's rule, p and direction (`None`: no change; `Some(true)`: NEW
/// counts more): asv's rule on per-round values where both sides hold enough rounds of them,
/// else the factor threshold on the rows' medians `(base, new)`.
fn judge_nondeterministic(
    (b, n): (&Row, &Row),
    counter: &str,
    (base, new): (f64, f64),
    judge: &WorkJudge,
) -> (WorkRule, Option<f64>, Option<bool>) {
    let per_round =
        |r: &Row, rounds: u32| round_values(r, counter, rounds, false).unwrap_or_default();
    let (bs, ns) = (
        per_round(b, judge.rounds.base),
        per_round(n, judge.rounds.new),
    );
    let enough = MIN_ROUNDS as usize;
    if judge.rounds.enough() && bs.len() >= enough && ns.len() >= enough {
        let t = time_test(counter, &bs, &ns, judge.threshold, judge.alpha);
        let more = match t.verdict {
            Verdict::Slower => Some(true),
            Verdict::Faster => Some(false),
            _ => None,
        };
        return (WorkRule::Statistical, t.p_value, more);
    }
    let beyond =
        base == 0.0 || new / base >= judge.threshold || new / base <= 1.0 / judge.threshold;
    (
        WorkRule::Threshold,
        None,
        (beyond && base != new).then_some(new > base),
    )
}

/// Every work figure of two matched rows that differs (in BASE's order, then those only NEW
/// reports). Rows where either side failed compare nothing: a failed row counted nothing.
pub fn work_changes(b: &Row, n: &Row, judge: &WorkJudge) -> Vec<WorkChange> {
    if !b.ok() || !n.ok() {
        return vec![];
    }
    let racy =
        crate::algorithms::nondeterministic_counters(&n.algorithm, &n.settings, &n.device_type);
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
        .filter(|(counter, ..)| !is_rate(counter))
        .filter_map(|(counter, base, new)| {
            let ratio = base.zip(new).filter(|(b, _)| *b != 0.0).map(|(b, n)| n / b);
            let (rule, p_value, verdict) = match (base, new) {
                (None, None) => return None,
                (Some(_), None) => (WorkRule::Exact, None, WorkVerdict::Removed),
                (None, Some(_)) => (WorkRule::Exact, None, WorkVerdict::Added),
                // NaN (a median that could not be taken) equals nothing: left alone.
                (Some(b), Some(n)) if b.is_nan() || n.is_nan() => return None,
                (Some(bv), Some(nv)) if racy.contains(&counter.as_str()) => {
                    let (rule, p, more) = judge_nondeterministic((b, n), &counter, (bv, nv), judge);
                    let verdict = if more? {
                        WorkVerdict::More
                    } else {
                        WorkVerdict::Less
                    };
                    (rule, p, verdict)
                }
                (Some(b), Some(n)) if same_figure(b, n) => return None,
                (Some(b), Some(n)) => {
                    let verdict = if n > b {
                        WorkVerdict::More
                    } else {
                        WorkVerdict::Less
                    };
                    (WorkRule::Exact, None, verdict)
                }
            };
            Some(WorkChange {
                counter,
                base,
                new,
                ratio,
                rule,
                p_value,
                verdict,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// compare's defaults on one-round runs: nondeterministic counters by the threshold.
    const ONE_ROUND: WorkJudge = WorkJudge {
        threshold: 1.10,
        alpha: 0.01,
        rounds: Rounds { base: 1, new: 1 },
    };

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
        assert!(work_changes(&base, &base.clone(), &ONE_ROUND).is_empty());
        let more = row("fragments=1001;triangles=50", 4096);
        let c = work_changes(&base, &more, &ONE_ROUND);
        assert_eq!(c.len(), 1, "{c:?}");
        assert_eq!(c[0].counter, "fragments");
        assert_eq!(c[0].verdict, WorkVerdict::More);
        assert_eq!(c[0].rule, WorkRule::Exact);
        assert_eq!(c[0].ratio, Some(1.001));
        let smaller = row("fragments=1000;triangles=50", 4000);
        let c = work_changes(&base, &smaller, &ONE_ROUND);
        assert_eq!(c.len(), 2, "{c:?}");
        assert!(c.iter().all(|c| c.verdict == WorkVerdict::Less));
        let added = row("fragments=1000;triangles=50;passes=3", 4096);
        assert_eq!(
            work_changes(&base, &added, &ONE_ROUND)[0].verdict,
            WorkVerdict::Added
        );
    }

    /// HAVS's racy pass declares its race-decided counters nondeterministic on a GPU: there a
    /// small change of `fragments` is noise, a change beyond the threshold still counts, and
    /// on lavapipe (in-order shading) the same +1 is exact.
    #[test]
    fn declared_racy_counters_of_one_round_runs_are_judged_by_the_threshold_on_a_gpu_only() {
        let on = |device: &str, counters: &str| Row {
            device_type: device.into(),
            ..row(counters, 4096)
        };
        let base = on("DiscreteGpu", "fragments=1000;triangles=50");
        let plus_one = on("DiscreteGpu", "fragments=1001;triangles=50");
        assert!(work_changes(&base, &plus_one, &ONE_ROUND).is_empty());
        let far = on("DiscreteGpu", "fragments=1200;triangles=50");
        let c = work_changes(&base, &far, &ONE_ROUND);
        assert_eq!(c[0].rule, WorkRule::Threshold);
        assert_eq!(c[0].verdict, WorkVerdict::More);
        // triangles are not racy: exact on a GPU too.
        let tri = on("DiscreteGpu", "fragments=1000;triangles=51");
        assert_eq!(
            work_changes(&base, &tri, &ONE_ROUND)[0].rule,
            WorkRule::Exact
        );
        let cpu = work_changes(
            &on("Cpu", "fragments=1000;triangles=50"),
            &on("Cpu", "fragments=1001;triangles=50"),
            &ONE_ROUND,
        );
        assert_eq!(cpu[0].rule, WorkRule::Exact);
    }

    /// A racy row of `rounds` rounds of 3 frames whose per-frame `fragments` are `per_frame`
    /// (its median the row's counter), on a GPU.
    fn racy_on_gpu(per_frame: &[f64]) -> Row {
        let mut r = Row {
            device_type: "DiscreteGpu".into(),
            ..row("triangles=50", 4096)
        };
        r.counters
            .insert("fragments", crate::results::stats::median(per_frame));
        r.samples
            .counters
            .insert("fragments".into(), per_frame.to_vec());
        r
    }

    /// With five rounds a side of per-frame values, asv's rule judges a racy counter: the
    /// same scatter is no change, the same scatter 20 % higher is a regression with its p, and
    /// 20 % higher on only one round of five is not (the rows' medians alone moved ×1.2 in
    /// none of them: the test needs the rounds to agree).
    #[test]
    fn racy_counters_with_rounds_are_judged_statistically() {
        let judge = WorkJudge {
            rounds: Rounds { base: 5, new: 5 },
            ..ONE_ROUND
        };
        // 5 rounds × 3 frames, a race's scatter of a few per cent.
        let scatter: Vec<f64> = (0..15).map(|i| 1000.0 + ((i * 37) % 50) as f64).collect();
        let base = racy_on_gpu(&scatter);
        let same: Vec<f64> = scatter.iter().rev().copied().collect();
        assert!(work_changes(&base, &racy_on_gpu(&same), &judge).is_empty());
        let more: Vec<f64> = scatter.iter().map(|v| v * 1.2).collect();
        let c = work_changes(&base, &racy_on_gpu(&more), &judge);
        assert_eq!(c.len(), 1, "{c:?}");
        assert_eq!(c[0].rule, WorkRule::Statistical);
        assert_eq!(c[0].verdict, WorkVerdict::More);
        assert!(c[0].p_value.is_some_and(|p| p < 0.01), "{c:?}");
        assert!(c[0].describe().contains("p = "), "{}", c[0].describe());
        let less: Vec<f64> = scatter.iter().map(|v| v / 1.2).collect();
        assert_eq!(
            work_changes(&base, &racy_on_gpu(&less), &judge)[0].verdict,
            WorkVerdict::Less
        );
        // One round of five 20 % higher: its median is one sample of five, not a change.
        let mut one_round = scatter.clone();
        for v in &mut one_round[..3] {
            *v *= 1.2;
        }
        assert!(work_changes(&base, &racy_on_gpu(&one_round), &judge).is_empty());
        // The same pair judged as one-round runs falls back to the threshold.
        let c = work_changes(&base, &racy_on_gpu(&more), &ONE_ROUND);
        assert_eq!(c[0].rule, WorkRule::Threshold);
    }

    /// A rate among the counters is time, not work; a mean written at the text form's four
    /// decimals equals its full-precision recomputation, and one that moved past them does not.
    #[test]
    fn rates_are_not_work_and_fractions_compare_at_the_written_precision() {
        let base = row("steps_mean=32.4484;voxels_per_sec=154530.7", 4096);
        let same = row("steps_mean=32.448431;voxels_per_sec=26367.1", 4096);
        assert!(work_changes(&base, &same, &ONE_ROUND).is_empty());
        let moved = row("steps_mean=32.4491;voxels_per_sec=154530.7", 4096);
        let c = work_changes(&base, &moved, &ONE_ROUND);
        assert_eq!(c.len(), 1, "{c:?}");
        assert_eq!(c[0].counter, "steps_mean");
        assert_eq!(c[0].verdict, WorkVerdict::More);
    }
}
