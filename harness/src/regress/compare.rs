//! `tetbench compare BASE NEW`: did NEW get slower, less exact, bigger or busier than BASE?
//!
//! Rows are matched by (algorithm, settings, data set, viewpoint, size). Per row:
//! - **work** ([`crate::regress::compare_work`]): every counter (fragments, triangles, ray
//!   steps, sort keys …) and GPU byte figure is compared exactly, without statistics; a count
//!   that grew is a regression, whatever the machine's load. Counters an algorithm declares
//!   nondeterministic on the row's adapter are judged by the factor threshold instead.
//! - **time** (`total_ms`, `cpu_ms`, `gpu_ms`, [`crate::regress::compare_rounds`]): the
//!   Mann–Whitney U test plus asv's factor threshold ([`crate::results::stats`] says why) on
//!   one value per **round** (frames of one round share the machine's moment: one sample);
//!   with fewer than [`MIN_ROUNDS`] rounds on either side no time verdict is given. The
//!   decision that gates is the **group** test (algorithm × settings × data set × viewport,
//!   viewpoints pooled), Holm-adjusted over the groups; only `total_ms` gates. Separate runs
//!   whose groups scatter around the run-wide factor by more than half the threshold are
//!   **too noisy** to gate on time ([`time_noise`]): time verdicts are withheld and the
//!   command fails with that reason.
//! - **image** ([`crate::regress::compare_image`]): any changed f32 pixel is reported; a PSNR
//!   drop > 0.1 dB is a regression.
//!
//! Runs on different adapters are refused unless `--normalised`: then every sample is divided
//! by its row's roofline time (from that machine's calibration, [`crate::calibrate`]), images
//! are not compared pixel by pixel (adapters legitimately differ), and every output says so.
//! What the comparison found is a list of [`Finding`]s ([`crate::regress::compare_findings`]).

use std::path::Path;

use crate::regress::compare_image::{image_change, image_note};
pub use crate::regress::compare_image::{
    image_difference, ImageChange, ImageDifference, ImageVerdict, PSNR_TOLERANCE_DB,
};
pub use crate::regress::compare_model::{
    json_schema, Comparison, Finding, FindingVerdict, RowComparison, RowStatus, SCHEMA_VERSION,
};
use crate::regress::compare_rounds::{group_pair_ratios, group_tests, round_test};
pub use crate::regress::compare_rounds::{round_values, GroupComparison, Rounds, MIN_ROUNDS};
pub use crate::regress::compare_setup::{key, CompareOptions, FailOn, Key, EXIT_REGRESSION};
pub use crate::regress::compare_time::{
    adjust_family, fmt_p, pair_factors, pooled_t_tests, run_wide_factor, scaled, time_test,
    TimeTest, Verdict, MIN_GROUPS_FOR_DRIFT,
};
pub use crate::regress::compare_work::{WorkChange, WorkRule, WorkVerdict};
use crate::results::aggregate::GroupKey;
use crate::results::stats::{holm_adjust, mann_whitney_p, median};
use crate::results::{ResultsFile, Row};

/// The adapter a results set ran on, as compare matches them (a software rasteriser with its CPU).
pub fn adapter_of(f: &ResultsFile) -> String {
    let Some(a) = f.machine.adapter.as_ref() else {
        return "unknown adapter".into();
    };
    let name = format!("{} ({} {})", a.name, a.driver, a.driver_info)
        .trim()
        .to_string();
    // A software rasteriser (lavapipe, WARP, SwiftShader) runs on the CPU, which is then the
    // GPU: one name on two CPUs is two different devices.
    if a.device_type.eq_ignore_ascii_case("cpu") {
        format!("{name} on {}", f.machine.cpu_model)
    } else {
        name
    }
}

/// Separate runs of a busy machine: the groups of one unchanged build scatter around the
/// run-wide factor (×0.8–×1.25 on the 2-core VM with a compile beside it), and a group's
/// ×1.13 there is the machine, not the code. The spread is the median over the groups of
/// |ln(group ratio / run-wide factor)| — robust to the few groups a real change moves — given
/// as a factor; when it reaches √threshold (a typical unchanged group already moved half way
/// to the threshold, on the log scale) time cannot gate, and the reason says so. Only for
/// unpaired runs with a run-wide factor: `ab`'s paired rounds are judged by a t-test whose
/// variance is pooled over the groups, with or without each pair's drift divided out.
/// Returns (spread, reason when too noisy).
pub fn time_noise(
    groups: &[GroupComparison],
    run_factor: Option<f64>,
    threshold: f64,
) -> (Option<f64>, Option<String>) {
    let Some(factor) = run_factor else {
        return (None, None);
    };
    let logs: Vec<f64> = groups
        .iter()
        .filter(|g| g.total.verdict != Verdict::TooFewSamples && g.total.ratio > 0.0)
        .map(|g| (g.total.ratio / factor).ln().abs())
        .collect();
    if logs.len() < MIN_GROUPS_FOR_DRIFT {
        return (None, None);
    }
    let spread = median(&logs).exp();
    let limit = threshold.sqrt();
    let reason = (spread >= limit).then(|| {
        format!(
            "time: the runs are too noisy to gate on time: the groups scatter around the \
             run-wide factor ×{factor:.3} by ×{spread:.3} (median over {} groups), at or beyond \
             ×{limit:.3} (half of --threshold {threshold} on the log scale), so a group's \
             ratio beyond the threshold cannot be told from the machine. Work, images and \
             memory are still compared exactly. To gate on time use `tetbench ab`, which \
             interleaves the two builds",
            logs.len()
        )
    });
    (Some(spread), reason)
}

/// Why one side's numbers may not be what its commit does: built from a dirty tree (the commit
/// is not the code), or a debug build (times of another program).
pub fn provenance_warnings(side: &str, f: &ResultsFile) -> Vec<String> {
    let m = &f.machine;
    let mut out = vec![];
    if m.git_dirty == Some(true) {
        out.push(format!(
            "{side} was built from a dirty tree (commit {} plus uncommitted changes)",
            m.git_commit.as_deref().unwrap_or("?")
        ));
    }
    if m.build_profile.as_deref() == Some("debug") {
        out.push(format!(
            "{side} is a debug build: its times are not those of a release build"
        ));
    }
    out
}

/// Compares two result directories; writes nothing (see
/// [`crate::regress::compare_report::write_outputs`]).
pub fn compare(
    base_dir: &Path,
    new_dir: &Path,
    opt: &CompareOptions,
) -> anyhow::Result<Comparison> {
    let mut base = ResultsFile::read(base_dir)?;
    let mut new = ResultsFile::read(new_dir)?;
    let (ba, na) = (adapter_of(&base), adapter_of(&new));
    let across = crate::regress::compare_across::across_or_refuse(
        (&base, &new),
        (base_dir, new_dir),
        (&ba, &na),
        opt.normalised,
    )?;
    if opt.normalised {
        require_calibration(&base, base_dir)?;
        require_calibration(&new, new_dir)?;
    }
    let rounds = Rounds::of(&base, &new);
    // The machine divided out by the control measured beside the rows, where both runs have
    // one (compare_control.rs); otherwise the run-wide factor, as before.
    let control_missing = crate::regress::compare_control::missing(&base, &new);
    let by_drift = opt.drift_correction && !opt.normalised;
    let machine = by_drift
        .then(|| crate::regress::compare_control::normalise(&mut base, &mut new))
        .flatten();
    let by_rows = opt.drift_correction && machine.is_none();
    let unscaled = group_tests(&base.rows, &new.rows, opt, &[1.0], rounds)?;
    let run_factor = run_wide_factor(unscaled.iter().map(|g| &g.total));
    let paired = opt.paired && rounds.base == rounds.new && rounds.base > 1;
    let pair_factors = (paired && by_rows)
        .then(|| pair_factors(&group_pair_ratios(&base.rows, &new.rows, rounds, opt).ok()?))
        .flatten();
    let scale = time_scale(
        pair_factors.as_deref(),
        run_factor.filter(|_| by_rows),
        paired,
        rounds,
    );
    let paired_test = scale.len() > 1;
    let drift_per_pair = pair_factors.is_some();
    // The groups' scatter around the run-wide factor measures the noise of separate runs
    // only: in paired rounds the test's own pooled variance does, and a change to half the
    // groups would read as scatter.
    let (group_spread, noise) = match (paired_test, rounds.enough()) {
        (false, true) => time_noise(&unscaled, run_factor, opt.threshold),
        _ => (None, None),
    };
    let time_judged = rounds.enough() && noise.is_none();
    let groups = judged_groups((&base, &new), opt, &scale, rounds, noise.is_some())?;
    let rows = compare_all_rows(
        (&base, &new),
        (base_dir, new_dir),
        (&scale, rounds, time_judged),
        opt,
    )?;
    let mut cmp = Comparison {
        schema_version: SCHEMA_VERSION,
        base: base_dir.display().to_string(),
        new: new_dir.display().to_string(),
        base_adapter: ba,
        new_adapter: na,
        base_commit: base.machine.git_commit.clone(),
        new_commit: new.machine.git_commit.clone(),
        normalised: opt.normalised,
        threshold: opt.threshold,
        alpha: opt.alpha,
        rounds,
        warnings: [
            provenance_warnings("BASE", &base),
            provenance_warnings("NEW", &new),
        ]
        .concat(),
        time_refused: rounds.refusal().or(noise.clone()),
        group_spread,
        too_noisy: noise.is_some(),
        run_factor,
        drift_corrected: by_rows && scale != [1.0],
        control_missing: control_missing.filter(|_| machine.is_none() && by_drift),
        machine,
        across,
        pair_factors,
        test: test_description(opt, paired_test, drift_per_pair),
        groups,
        rows,
        regressions: vec![],
        improvements: vec![],
        changes: vec![],
    };
    crate::regress::compare_findings::collect(&mut cmp, opt.drift_limit);
    Ok(cmp)
}

/// The groups' tests on NEW divided by `scale`, Holm-adjusted over the groups; all too noisy
/// when the run's groups scatter beyond the threshold (`too_noisy`).
fn judged_groups(
    (base, new): (&ResultsFile, &ResultsFile),
    opt: &CompareOptions,
    scale: &[f64],
    rounds: Rounds,
    too_noisy: bool,
) -> anyhow::Result<Vec<GroupComparison>> {
    let mut groups = group_tests(&base.rows, &new.rows, opt, scale, rounds)?;
    adjust_family(
        groups.iter_mut().map(|g| &mut g.total),
        opt.threshold,
        opt.alpha,
    );
    if too_noisy {
        for g in &mut groups {
            g.total.verdict = Verdict::TooNoisy;
        }
    }
    Ok(groups)
}

/// What NEW's times are divided by: each pair's drift (`per_pair`), else the run-wide factor
/// (`run_factor`, where drift is divided out by the rows), else 1 — once per pair in paired
/// rounds, which keeps the paired test.
fn time_scale(
    per_pair: Option<&[f64]>,
    run_factor: Option<f64>,
    paired: bool,
    rounds: Rounds,
) -> Vec<f64> {
    match (per_pair, run_factor) {
        (Some(per_pair), _) => per_pair.to_vec(),
        (None, Some(f)) => vec![f],
        // Paired rounds on absolute or control-divided times (`ab --no-drift-correction`, or
        // both sides with a control): a factor of 1 per pair keeps the paired test.
        (None, None) if paired => vec![1.0; rounds.base as usize],
        _ => vec![1.0],
    }
}

/// `--normalised` needs each side's calibration.
fn require_calibration(f: &ResultsFile, dir: &Path) -> anyhow::Result<()> {
    anyhow::ensure!(
        f.machine.calibration.is_some(),
        "--normalised: {} has no calibration in its machine record (run it without \
         --no-calibrate)",
        dir.display()
    );
    Ok(())
}

/// The tests a comparison ran, in words (its `test` field).
fn test_description(opt: &CompareOptions, paired_test: bool, drift_per_pair: bool) -> String {
    format!(
        "work counters and GPU bytes exact; time: Mann–Whitney U (two-sided, α = {}, \
         Holm-adjusted over the groups and over the rows) and ratio of medians ≥ {} (asv's \
         rule){}",
        opt.alpha,
        opt.threshold,
        match (paired_test, drift_per_pair) {
            (true, true) => {
                "; groups and rows (paired rounds): a t-test of each one's per-pair \
                 ln(NEW/BASE), each pair's drift divided out, variance pooled over the \
                 groups (rows: over their group's rows); ratio = exp(mean)"
            }
            (true, false) => {
                "; groups and rows (paired rounds): a t-test of each one's per-pair \
                 ln(NEW/BASE) on absolute times (no drift divided out), variance pooled \
                 over the groups (rows: over their group's rows); ratio = exp(mean)"
            }
            _ => "",
        }
    )
}

/// Every BASE row against its NEW row (Holm over the rows' `total_ms` tests), then the rows
/// only NEW has. `time`: the drift NEW is divided by, the rounds, and whether time is judged
/// at all (enough rounds, not too noisy).
fn compare_all_rows(
    (base, new): (&ResultsFile, &ResultsFile),
    (base_dir, new_dir): (&Path, &Path),
    (scale, rounds, time_judged): (&[f64], Rounds, bool),
    opt: &CompareOptions,
) -> anyhow::Result<Vec<RowComparison>> {
    let heat_dir = opt.out.join("heatmaps");
    let pairs: Vec<(&Row, Option<&Row>)> = base
        .rows
        .iter()
        .map(|b| (b, new.rows.iter().find(|n| key(n) == key(b))))
        .collect();
    // The rows' total_ms tests are one family (Holm): their adjusted p decides each row.
    let mut raw_total_p = vec![];
    // Per row, its ln(NEW/BASE) in each pair of rounds (paired rounds only).
    let mut pair_logs: Vec<Option<Vec<f64>>> = vec![];
    for (b, n) in &pairs {
        let (mut p, mut logs) = (None, None);
        if let Some(n) = n {
            let bs = round_values(b, "total_ms", rounds.base, opt.normalised)?;
            let ns = scaled(
                round_values(n, "total_ms", rounds.new, opt.normalised)?,
                scale,
            );
            if rounds.enough() && bs.len() >= 2 && ns.len() >= 2 {
                p = mann_whitney_p(&bs, &ns);
            }
            let one_per_pair = bs.len() == scale.len() && ns.len() == scale.len();
            if scale.len() > 1 && one_per_pair && bs.iter().chain(&ns).all(|x| *x > 0.0) {
                logs = Some(bs.iter().zip(&ns).map(|(b, n)| (n / b).ln()).collect());
            }
        }
        raw_total_p.push(p);
        pair_logs.push(logs);
    }
    // Paired rounds: each row is judged as the groups are, by the t-test of its per-pair
    // ln(NEW/BASE), with the variance pooled over its group's rows (the viewpoints of one
    // variant: pooled over every row, a bimodal GATOR row of an unchanged build was called
    // faster beside HAVS rows whose pairs agree to 2 %). A rank test of 3 rounds against 3
    // cannot go below p = 0.1, so no row of an `ab` could be faster or slower before.
    let mut paired = vec![None; pairs.len()];
    if rounds.enough() {
        for group in GroupKey::distinct(base.rows.iter()) {
            let members: Vec<usize> = (0..pairs.len())
                .filter(|&i| pair_logs[i].is_some() && group.matches(pairs[i].0))
                .collect();
            let logs: Vec<Vec<f64>> = members
                .iter()
                .filter_map(|&i| pair_logs[i].clone())
                .collect();
            for (&i, (ratio, p)) in members
                .iter()
                .zip(pooled_t_tests(&logs).unwrap_or_default())
            {
                paired[i] = Some((ratio, p));
                raw_total_p[i] = p;
            }
        }
    }
    let mut rows = vec![];
    let adjusted = holm_adjust(&raw_total_p);
    for (((b, n), p_total), paired) in pairs.into_iter().zip(adjusted).zip(paired) {
        rows.push(match n {
            Some(n) => compare_rows(
                b,
                n,
                RowTime {
                    p_adjusted: p_total,
                    paired,
                    scale,
                    rounds,
                    judged: time_judged,
                },
                (base_dir, new_dir, &heat_dir),
                opt,
            )?,
            None => only(b, RowStatus::OnlyInBase),
        });
    }
    for n in &new.rows {
        if !base.rows.iter().any(|b| key(b) == key(n)) {
            rows.push(only(n, RowStatus::OnlyInNew));
        }
    }
    Ok(rows)
}

fn only(r: &Row, status: RowStatus) -> RowComparison {
    RowComparison {
        algorithm: r.algorithm.clone(),
        settings: r.settings.clone(),
        dataset: r.dataset.clone(),
        viewpoint: r.viewpoint.clone(),
        width: r.width,
        height: r.height,
        status,
        notes: vec![status.to_string()],
        times: vec![],
        image: None,
        work: vec![],
    }
}

/// Whether a row got worse, better or merely changed, as its parts are found.
#[derive(Default)]
struct Direction {
    worse: bool,
    better: bool,
    changed: bool,
}

/// What decides one matched row's time ([`compare_rows`]).
struct RowTime<'a> {
    /// The Holm-adjusted p of its `total_ms` (over the rows).
    p_adjusted: Option<f64>,
    /// Paired rounds: its ratio, exp of the mean per-pair ln(NEW/BASE), and the raw p.
    paired: Option<(f64, Option<f64>)>,
    /// The drift NEW is divided by.
    scale: &'a [f64],
    rounds: Rounds,
    /// Whether time is judged at all (enough rounds, not too noisy).
    judged: bool,
}

/// One time `metric` of a matched row, BASE against NEW (`None` where neither has it): its
/// rounds' test; `total_ms` is NEW divided by the drift, paired, Holm-adjusted over the rows and
/// too noisy where time is not judged.
fn row_time_test(
    b: &Row,
    n: &Row,
    metric: &str,
    time: &RowTime<'_>,
    opt: &CompareOptions,
) -> anyhow::Result<Option<TimeTest>> {
    let rounds = time.rounds;
    let (bs, mut ns) = (
        round_values(b, metric, rounds.base, opt.normalised)?,
        round_values(n, metric, rounds.new, opt.normalised)?,
    );
    if bs.is_empty() && ns.is_empty() {
        return Ok(None);
    }
    if metric != "total_ms" {
        return Ok(Some(round_test(metric, &bs, &ns, opt, rounds)));
    }
    ns = scaled(ns, time.scale);
    let mut t = round_test(metric, &bs, &ns, opt, rounds);
    if let Some((ratio, p)) = time.paired {
        t = t.with_paired(ratio, p, opt.threshold, opt.alpha);
    }
    t = t.with_family_p(time.p_adjusted, opt.threshold, opt.alpha);
    if rounds.enough() && !time.judged {
        t.verdict = Verdict::TooNoisy;
    }
    Ok(Some(t))
}

/// One matched row; `dirs`: BASE, NEW and where heatmaps go.
fn compare_rows(
    b: &Row,
    n: &Row,
    time: RowTime<'_>,
    dirs: (&Path, &Path, &Path),
    opt: &CompareOptions,
) -> anyhow::Result<RowComparison> {
    let (base_dir, new_dir, heat_dir) = dirs;
    let mut out = only(b, RowStatus::NoChange);
    out.notes.clear();
    let mut d = Direction::default();
    match (b.ok(), n.ok()) {
        (true, false) => {
            d.worse = true;
            out.notes.push(format!("failed now: {}", n.error_text()));
        }
        (false, true) => {
            d.better = true;
            out.notes.push("no longer fails".into());
        }
        (false, false) => out.notes.push("fails in both".into()),
        (true, true) => {}
    }
    for change in crate::regress::compare_work::work_changes(
        b,
        n,
        &crate::regress::compare_work::WorkJudge {
            threshold: opt.threshold,
            alpha: opt.alpha,
            rounds: time.rounds,
        },
    ) {
        match change.verdict {
            WorkVerdict::More => d.worse = true,
            WorkVerdict::Less => d.better = true,
            WorkVerdict::Added | WorkVerdict::Removed => d.changed = true,
        }
        out.notes.push(change.describe());
        out.work.push(change);
    }
    for metric in ["total_ms", "cpu_ms", "gpu_ms"] {
        if let Some(t) = row_time_test(b, n, metric, &time, opt)? {
            match (metric, t.verdict) {
                ("total_ms", Verdict::Slower) => {
                    d.worse = true;
                    out.notes.push(format!("slower ×{:.3}", t.ratio));
                }
                ("total_ms", Verdict::Faster) => {
                    d.better = true;
                    out.notes.push(format!("faster ×{:.3}", t.ratio));
                }
                _ => {}
            }
            out.times.push(t);
        }
    }
    let img = image_change(b, n, base_dir, new_dir, heat_dir, opt)?;
    match img.verdict {
        ImageVerdict::Worse => d.worse = true,
        ImageVerdict::Better => d.better = true,
        ImageVerdict::Changed => d.changed = true,
        ImageVerdict::Same => {}
    }
    if img.verdict != ImageVerdict::Same {
        out.notes.push(image_note(&img));
    }
    out.image = Some(img);
    out.status = if d.worse {
        RowStatus::Regression
    } else if d.better {
        RowStatus::Improvement
    } else if d.changed {
        RowStatus::Changed
    } else {
        RowStatus::NoChange
    };
    Ok(out)
}

#[cfg(test)]
#[path = "compare_tests.rs"]
pub(crate) mod tests;
