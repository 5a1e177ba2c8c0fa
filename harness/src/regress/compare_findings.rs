//! What a comparison found, as objects a machine reads: each regression, improvement and other
//! change names its group (and row), the metric, the ratio, the p-values and the verdict, with
//! the sentence the reports print beside them.

use render_core::Settings;

use crate::regress::compare_image::ImageVerdict;
use crate::regress::compare_model::{
    Comparison, Finding, FindingVerdict, RowComparison, RowStatus,
};
use crate::regress::compare_time::{TimeTest, Verdict};
use crate::regress::compare_work::WorkVerdict;

fn group_label(algorithm: &str, settings: &Settings, dataset: &str) -> String {
    format!("{algorithm} {settings} on {dataset}")
}

impl Finding {
    fn of_row(r: &RowComparison, metric: &str, verdict: FindingVerdict, text: String) -> Finding {
        Finding {
            group: group_label(&r.algorithm, &r.settings, &r.dataset),
            viewpoint: Some(r.viewpoint.clone()),
            metric: metric.into(),
            ratio: None,
            p: None,
            p_holm: None,
            verdict,
            text: format!(
                "{} {} {} {}: {text}",
                r.algorithm, r.settings, r.dataset, r.viewpoint
            ),
        }
    }

    fn with_time(mut self, t: &TimeTest) -> Finding {
        self.ratio = Some(t.ratio);
        self.p = t.p_value;
        self.p_holm = t.p_adjusted;
        self
    }
}

/// The run-wide finding, if the run as a whole moved. With the machine divided out by the
/// control, what remains of the run-wide factor is the code: beyond the threshold (and with
/// time judged at all) it is a change common to every algorithm. Without a control the old
/// rule stands: a run-wide factor beyond `drift_limit` (machine drift, or a common change).
fn run_wide(cmp: &Comparison, f: f64, drift_limit: f64) -> Option<(FindingVerdict, Finding)> {
    let (limit, text) = match &cmp.machine {
        Some(m) if cmp.time_refused.is_none() => (
            cmp.threshold,
            format!(
                "common to every algorithm: every group's total_ms ×{f:.3} (median over {} \
                 groups) with the machine's drift (×{:.3}, the control measured beside the \
                 rows) divided out, beyond --threshold {}",
                cmp.groups.len(),
                m.factor,
                cmp.threshold
            ),
        ),
        Some(_) => return None,
        None => (
            drift_limit,
            format!(
                "run-wide: every group's total_ms ×{f:.3} (median over {} groups; machine \
                 drift or a change common to all algorithms, beyond --drift-limit \
                 {drift_limit}; no control to tell them apart)",
                cmp.groups.len(),
            ),
        ),
    };
    let verdict = if f >= limit {
        FindingVerdict::Slower
    } else if f <= 1.0 / limit {
        FindingVerdict::Faster
    } else {
        return None;
    };
    Some((
        verdict,
        Finding {
            group: "run-wide".into(),
            viewpoint: None,
            metric: "total_ms".into(),
            ratio: Some(f),
            p: None,
            p_holm: None,
            verdict,
            text,
        },
    ))
}

/// Fills the comparison's regressions, improvements and changes from its run-wide factor,
/// groups and rows.
pub fn collect(cmp: &mut Comparison, drift_limit: f64) {
    let (mut worse, mut better, mut other) = (vec![], vec![], vec![]);
    if let Some(f) = cmp.run_factor {
        if let Some((verdict, finding)) = run_wide(cmp, f, drift_limit) {
            match verdict {
                FindingVerdict::Slower => worse.push(finding),
                _ => better.push(finding),
            }
        }
    }
    for g in &cmp.groups {
        let verdict = match g.total.verdict {
            Verdict::Slower => FindingVerdict::Slower,
            Verdict::Faster => FindingVerdict::Faster,
            _ => continue,
        };
        let f = Finding {
            group: group_label(&g.algorithm, &g.settings, &g.dataset),
            viewpoint: None,
            metric: "total_ms".into(),
            ratio: None,
            p: None,
            p_holm: None,
            verdict,
            text: format!(
                "{}: {} {} on {}: total_ms ×{:.3} (p = {})",
                g.total.verdict.label(),
                g.algorithm,
                g.settings,
                g.dataset,
                g.total.ratio,
                g.total.p_label()
            ),
        }
        .with_time(&g.total);
        if verdict == FindingVerdict::Slower {
            worse.push(f);
        } else {
            better.push(f);
        }
    }
    for r in &cmp.rows {
        for f in row_findings(r) {
            match f.verdict {
                FindingVerdict::Slower
                | FindingVerdict::More
                | FindingVerdict::Worse
                | FindingVerdict::FailsNow => worse.push(f),
                FindingVerdict::Faster
                | FindingVerdict::Less
                | FindingVerdict::Better
                | FindingVerdict::NoLongerFails => better.push(f),
                _ => other.push(f),
            }
        }
    }
    cmp.regressions = worse;
    cmp.improvements = better;
    cmp.changes = other;
}

/// The findings of one row: its error, each work change, its `total_ms` verdict, its image.
fn row_findings(r: &RowComparison) -> Vec<Finding> {
    let mut out = vec![];
    match r.status {
        RowStatus::OnlyInBase => {
            return vec![Finding::of_row(
                r,
                "row",
                FindingVerdict::OnlyInBase,
                "only in base".into(),
            )]
        }
        RowStatus::OnlyInNew => {
            return vec![Finding::of_row(
                r,
                "row",
                FindingVerdict::OnlyInNew,
                "only in new".into(),
            )]
        }
        _ => {}
    }
    for note in &r.notes {
        if note.starts_with("failed now") {
            out.push(Finding::of_row(
                r,
                "error",
                FindingVerdict::FailsNow,
                note.clone(),
            ));
        } else if note == "no longer fails" {
            out.push(Finding::of_row(
                r,
                "error",
                FindingVerdict::NoLongerFails,
                note.clone(),
            ));
        }
    }
    for w in &r.work {
        let verdict = match w.verdict {
            WorkVerdict::More => FindingVerdict::More,
            WorkVerdict::Less => FindingVerdict::Less,
            WorkVerdict::Added => FindingVerdict::Added,
            WorkVerdict::Removed => FindingVerdict::Removed,
        };
        let mut f = Finding::of_row(r, &w.counter, verdict, w.describe());
        f.ratio = w.ratio;
        out.push(f);
    }
    if let Some(t) = r.times.iter().find(|t| t.metric == "total_ms") {
        let verdict = match t.verdict {
            Verdict::Slower => Some(FindingVerdict::Slower),
            Verdict::Faster => Some(FindingVerdict::Faster),
            _ => None,
        };
        if let Some(v) = verdict {
            let text = format!(
                "{} ×{:.3} (p = {})",
                t.verdict.label(),
                t.ratio,
                t.p_label()
            );
            out.push(Finding::of_row(r, "total_ms", v, text).with_time(t));
        }
    }
    if let Some(img) = &r.image {
        let verdict = match img.verdict {
            ImageVerdict::Worse => Some(FindingVerdict::Worse),
            ImageVerdict::Better => Some(FindingVerdict::Better),
            ImageVerdict::Changed => Some(FindingVerdict::Changed),
            ImageVerdict::Same => None,
        };
        if let Some(v) = verdict {
            let text = crate::regress::compare_image::image_note(img);
            out.push(Finding::of_row(r, "image", v, text));
        }
    }
    out
}
