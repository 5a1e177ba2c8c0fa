//! `tetbench history DIR…`: each algorithm × settings × data set over a series of runs (e.g.
//! the committed baselines), ordered by the date each run started, labelled by commit and date.
//!
//! - Per run and group the time is the median over viewpoints of the rows' median `total_ms`;
//!   the band is the 10–90 % range of all the group's frames, each divided by its row's median
//!   and multiplied by that time (the frame-to-frame noise, comparable across groups).
//! - Each adjacent pair of runs is judged by **compare's own test** ([`crate::regress::compare`]: one
//!   value per round, the run-wide factor divided out, Holm over the groups, PSNR and memory
//!   exact), so history and compare never disagree about a pair.
//! - Over the whole series, **steps** are found by a piecewise-constant fit with a penalty per
//!   step, as asv's step detection does (its `step_detect`: an L1 fit of log times, segments
//!   found by dynamic programming); [`detect_steps`] is our own, smaller version. No step is
//!   placed between runs of the same commit (they measured the same code), and a step smaller
//!   than the threshold factor is not one.
//! - Runs of different adapters are refused: a step between two machines is not a change.
//!
//! Each run is read once and reduced to a [`RunSummary`], each pair to [`PairFindings`];
//! [`build`] makes the history from those alone, so `tetbench publish` can keep them beside a
//! run's page and compare only the pair a new run adds. The pages, charts and data files are
//! `history_page.rs`'s.

use std::collections::BinaryHeap;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use render_core::Settings;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::regress::compare::{
    adapter_of, CompareOptions, FailOn, GroupComparison, ImageVerdict, Verdict,
};
use crate::results::aggregate::GroupKey;
use crate::results::stats::{median, quantile};
use crate::results::{ResultsFile, Row};

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Point {
    pub run: usize,
    pub total_ms: f64,
    pub band_lo: f64,
    pub band_hi: f64,
    pub psnr_db: Option<f64>,
    pub gpu_bytes: Option<u64>,
    /// Against the previous run, by compare's test: `slower ×r`, `faster ×r`, `psnr ±x dB`,
    /// `memory`, `work: fragments, …` (counters that changed exactly), `too few rounds`,
    /// `too noisy`.
    pub changes: Vec<String>,
    /// A step of the piecewise-constant fit starts at this run (`×r` against the level before).
    pub step: Option<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Series {
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    /// The group's viewport: one variant at two sizes is two series.
    pub width: u32,
    pub height: u32,
    pub points: Vec<Point>,
}

impl Series {
    /// The settings as charts and tables name the series, with the size when the same
    /// variant and data set appear at more than one size in `h`.
    pub fn label(&self, h: &History) -> String {
        let sizes = h.series.iter().any(|o| {
            (&o.algorithm, &o.settings, &o.dataset)
                == (&self.algorithm, &self.settings, &self.dataset)
                && (o.width, o.height) != (self.width, self.height)
        });
        if sizes {
            format!("{} @ {}×{}", self.settings, self.width, self.height)
        } else {
            self.settings.clone()
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Run {
    pub dir: String,
    pub commit: String,
    pub date_utc: String,
    /// `commit date` as the x-axis shows it.
    pub label: String,
    /// The machine's speed during this run against the first run of the history with a
    /// control (the geometric mean over the control's figures of the two runs' median
    /// controls): every time of the run was multiplied by it before the steps were sought.
    /// Absent for a run without a control, whose times are as measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub machine: Option<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct History {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    pub adapter: String,
    pub runs: Vec<Run>,
    pub series: Vec<Series>,
}

/// The layout of `history.json` (`docs/history.schema.json`).
pub const SCHEMA_VERSION: u32 = 1;

/// The JSON Schema of `history.json`.
pub fn json_schema() -> serde_json::Value {
    serde_json::to_value(schemars::schema_for!(History)).expect("a schema is JSON")
}

/// A group as history follows it across runs: compare's key.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SeriesKey {
    pub algorithm: String,
    pub settings: Settings,
    pub dataset: String,
    pub width: u32,
    pub height: u32,
    pub projection: String,
}

impl SeriesKey {
    pub fn of(g: &GroupKey) -> SeriesKey {
        SeriesKey {
            algorithm: g.algorithm.clone(),
            settings: g.settings.clone(),
            dataset: g.dataset.clone(),
            width: g.width,
            height: g.height,
            projection: g.projection.clone(),
        }
    }

    fn of_group_comparison(g: &GroupComparison) -> SeriesKey {
        SeriesKey {
            algorithm: g.algorithm.clone(),
            settings: g.settings.clone(),
            dataset: g.dataset.clone(),
            width: g.width,
            height: g.height,
            projection: g.projection.clone(),
        }
    }
}

/// One group's numbers in one run (see the module's notes).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroupValues {
    pub total_ms: f64,
    pub band_lo: f64,
    pub band_hi: f64,
    pub psnr_db: Option<f64>,
    pub gpu_bytes: Option<u64>,
}

/// What history keeps of one run: which run it is, and per group (in the order its rows name
/// them) its numbers, `None` when no row of the group measured a time. The rows themselves
/// are not kept, so a history of a thousand runs holds a thousand of these, not the runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    pub run: Run,
    pub adapter: String,
    /// The run's median control, where every measured row has one.
    pub control: Option<crate::results::control::Figures>,
    pub groups: Vec<(SeriesKey, Option<GroupValues>)>,
}

/// The summary of the run `file` read from `dir`.
pub fn summarise(dir: &Path, file: &ResultsFile) -> RunSummary {
    let commit = file
        .machine
        .git_commit
        .clone()
        .unwrap_or_else(|| "?".into());
    let date = file.machine.date_utc.get(..10).unwrap_or("?").to_string();
    let groups = GroupKey::distinct(&file.rows)
        .into_iter()
        .map(|g| {
            let rows: Vec<&Row> = file
                .rows
                .iter()
                .filter(|r| g.matches(r) && r.ok())
                .collect();
            (SeriesKey::of(&g), group_values(&rows))
        })
        .collect();
    RunSummary {
        run: Run {
            dir: dir.display().to_string(),
            label: format!("{} {date}", &commit[..commit.len().min(7)]),
            commit,
            date_utc: file.machine.date_utc.clone(),
            machine: None,
        },
        adapter: adapter_of(file),
        control: crate::regress::compare_control::has_control(file)
            .then(|| file.control.as_ref().map(|c| c.median()))
            .flatten(),
        groups,
    }
}

/// Puts every run with a control on the scale of the first such run: its group times times its
/// machine's speed over that run's (a run measured on a machine half as fast counts half its
/// time), as compare does for a pair, so that a step is the code and not the hour. Runs
/// without a control keep their times, and their `machine` stays empty.
pub fn divide_out_the_machine(runs: &mut [RunSummary]) {
    let Some(reference) = runs.iter().find_map(|r| r.control.clone()) else {
        return;
    };
    for run in runs.iter_mut() {
        let Some(k) = run
            .control
            .as_ref()
            .and_then(|c| crate::results::control::speed_factor(c, &reference))
        else {
            continue;
        };
        run.run.machine = Some(k);
        for v in run.groups.iter_mut().filter_map(|(_, v)| v.as_mut()) {
            v.total_ms *= k;
            v.band_lo *= k;
            v.band_hi *= k;
        }
    }
}

fn group_values(rows: &[&Row]) -> Option<GroupValues> {
    let medians: Vec<f64> = rows.iter().filter_map(|r| r.total_ms).collect();
    if medians.is_empty() {
        return None;
    }
    let t = median(&medians);
    let noise = pooled(rows, |r| r.total_ms);
    let (lo, hi) = if noise.is_empty() {
        (t, t)
    } else {
        (t * quantile(&noise, 0.1), t * quantile(&noise, 0.9))
    };
    let psnr: Vec<f64> = rows.iter().filter_map(|r| r.psnr_db).collect();
    Some(GroupValues {
        total_ms: t,
        band_lo: lo,
        band_hi: hi,
        psnr_db: psnr_mean(&psnr),
        gpu_bytes: rows.iter().filter_map(|r| r.gpu_bytes).max(),
    })
}

/// Pooled frames of a group, each divided by `scale(row)`.
fn pooled(rows: &[&Row], scale: impl Fn(&Row) -> Option<f64>) -> Vec<f64> {
    rows.iter()
        .filter_map(|r| scale(r).map(|m| r.samples.total_ms.iter().map(move |x| x / m)))
        .flatten()
        .collect()
}

/// What compare's test found in one row of a pair of runs, as history shows it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RowFinding {
    pub algorithm: String,
    pub settings: Settings,
    pub dataset: String,
    pub width: u32,
    pub height: u32,
    /// The image got better or worse.
    pub psnr_moved: bool,
    /// A GPU byte figure changed.
    pub memory: bool,
    /// The work counters that changed exactly, in compare's order.
    pub work: Vec<String>,
}

impl RowFinding {
    /// Whether the row belongs to series `g` (a row comparison keeps no projection).
    fn in_series(&self, g: &SeriesKey) -> bool {
        (
            &self.algorithm,
            &self.settings,
            &self.dataset,
            self.width,
            self.height,
        ) == (&g.algorithm, &g.settings, &g.dataset, g.width, g.height)
    }
}

/// compare's verdict on one adjacent pair of runs, reduced to what the history's points say:
/// each group's time verdict (`slower ×r`, `faster ×r`, `too few rounds`, `too noisy`; groups
/// with no change are left out) and the rows whose image, memory or work changed.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PairFindings {
    pub time: Vec<(SeriesKey, String)>,
    pub rows: Vec<RowFinding>,
}

/// `compare BASE NEW` as history runs it on each adjacent pair (its heatmaps, if the runs kept
/// images, in `out`).
pub fn pair_findings(
    base: &Path,
    new: &Path,
    out: &Path,
    threshold: f64,
    alpha: f64,
) -> anyhow::Result<PairFindings> {
    let opt = CompareOptions {
        threshold,
        alpha,
        normalised: false,
        drift_correction: true,
        paired: false,
        drift_limit: 1.5,
        fail_on: FailOn::Never,
        out: out.to_path_buf(),
    };
    let cmp = crate::regress::compare::compare(base, new, &opt)?;
    let time = cmp
        .groups
        .iter()
        .filter_map(|gc| {
            let text = match gc.total.verdict {
                Verdict::Slower => format!("slower ×{:.3}", gc.total.ratio),
                Verdict::Faster => format!("faster ×{:.3}", gc.total.ratio),
                Verdict::TooFewSamples => "too few rounds".into(),
                Verdict::TooNoisy => "too noisy".into(),
                Verdict::NoChange => return None,
            };
            Some((SeriesKey::of_group_comparison(gc), text))
        })
        .collect();
    let rows =
        cmp.rows
            .iter()
            .filter_map(|r| {
                let psnr_moved = r.image.as_ref().is_some_and(|i| {
                    matches!(i.verdict, ImageVerdict::Worse | ImageVerdict::Better)
                });
                let memory = r.work.iter().any(|w| w.counter.starts_with("gpu_bytes"));
                let work: Vec<String> = r
                    .work
                    .iter()
                    .filter(|w| !w.counter.starts_with("gpu_bytes"))
                    .map(|w| w.counter.clone())
                    .collect();
                (psnr_moved || memory || !work.is_empty()).then(|| RowFinding {
                    algorithm: r.algorithm.clone(),
                    settings: r.settings.clone(),
                    dataset: r.dataset.clone(),
                    width: r.width,
                    height: r.height,
                    psnr_moved,
                    memory,
                    work,
                })
            })
            .collect();
    Ok(PairFindings { time, rows })
}

/// An L1 cost kept as values arrive: Σ|v − median| of the values pushed so far, from two heaps
/// split at the median and their sums (so a segment's cost costs O(log n) to extend, not a sort).
#[derive(Default)]
struct L1Cost {
    /// The lower half (with the median when the count is odd), largest on top.
    lo: BinaryHeap<Total>,
    hi: BinaryHeap<std::cmp::Reverse<Total>>,
    sum_lo: f64,
    sum_hi: f64,
}

/// An f64 ordered by `total_cmp`, as [`median`] sorts.
#[derive(PartialEq, Clone, Copy)]
struct Total(f64);

impl Eq for Total {}

impl PartialOrd for Total {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Total {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

impl L1Cost {
    fn push(&mut self, v: f64) {
        if self.lo.peek().is_none_or(|m| Total(v) <= *m) {
            self.lo.push(Total(v));
            self.sum_lo += v;
        } else {
            self.hi.push(std::cmp::Reverse(Total(v)));
            self.sum_hi += v;
        }
        if self.lo.len() > self.hi.len() + 1 {
            let Total(m) = self.lo.pop().expect("not empty");
            self.sum_lo -= m;
            self.sum_hi += m;
            self.hi.push(std::cmp::Reverse(Total(m)));
        } else if self.hi.len() > self.lo.len() {
            let std::cmp::Reverse(Total(m)) = self.hi.pop().expect("not empty");
            self.sum_hi -= m;
            self.sum_lo += m;
            self.lo.push(Total(m));
        }
    }

    /// Below the median the values sit under it, above it over it: the sum of distances is
    /// the upper sum minus the lower one, plus the median once when the lower half holds it.
    fn value(&self) -> f64 {
        let odd = self.lo.len() > self.hi.len();
        let m = self.lo.peek().map_or(0.0, |t| t.0);
        self.sum_hi - self.sum_lo + if odd { m } else { 0.0 }
    }
}

/// The least of `costs` and where it is; costs within [`TIE`] of it are equal to it and the
/// earliest wins (an L1 fit often has exact ties, which rounding would otherwise break either
/// way).
fn least(costs: &[f64]) -> (f64, usize) {
    let min = costs.iter().copied().fold(f64::INFINITY, f64::min);
    let at = costs
        .iter()
        .position(|c| *c <= min + TIE * (1.0 + min.abs()))
        .unwrap_or(0);
    (costs[at], at)
}

/// Relative difference under which two segmentation costs are a tie.
const TIE: f64 = 1e-9;

/// The change points of `values` (indices where a new level starts) by an L1 piecewise-constant
/// fit of their logarithms: minimise Σ over segments of Σ|ln v − median| plus `penalty` per
/// segment, by dynamic programming over every segmentation (O(n² log n): for each end, the
/// segments ending there are grown backwards with [`L1Cost`]; among equal costs the earliest
/// start wins, [`least`]). `same_as_previous[i]`: run i measured the same code as run i−1, so no step may
/// start there. Steps whose levels differ by less than `threshold` (a factor) are merged away.
pub fn detect_steps(
    values: &[f64],
    same_as_previous: &[bool],
    penalty: f64,
    threshold: f64,
) -> Vec<usize> {
    let y: Vec<f64> = values.iter().map(|v| v.max(1e-12).ln()).collect();
    let n = y.len();
    if n < 2 {
        return vec![];
    }
    // best[j]: the least cost of y[..j]; from[j]: where its last segment starts.
    let mut best = vec![0.0f64; n + 1];
    let mut from = vec![0usize; n + 1];
    let mut total = vec![f64::INFINITY; n];
    for j in 1..=n {
        let mut cost = L1Cost::default();
        for i in (0..j).rev() {
            cost.push(y[i]);
            total[i] = if i > 0 && same_as_previous.get(i).copied().unwrap_or(false) {
                f64::INFINITY // no step between two runs of one commit
            } else {
                best[i] + cost.value() + penalty
            };
        }
        (best[j], from[j]) = least(&total[..j]);
    }
    let mut starts = vec![];
    let mut j = n;
    while j > 0 {
        starts.push(from[j]);
        j = from[j];
    }
    starts.reverse();
    // Keep a step only if the levels either side differ by the threshold factor.
    let mut steps: Vec<usize> = vec![];
    let mut seg_start = 0;
    for (k, &s) in starts.iter().enumerate().skip(1) {
        let end = starts.get(k + 1).copied().unwrap_or(n);
        let before = median(&y[seg_start..s]);
        let after = median(&y[s..end]);
        if (after - before).abs() >= threshold.ln() {
            steps.push(s);
            seg_start = s;
        }
    }
    steps
}

/// The step penalty: a step must pay for itself against the series' own run-to-run noise
/// (a robust estimate from adjacent differences), and never costs less than a threshold-sized
/// step over two runs.
fn step_penalty(values: &[f64], threshold: f64) -> f64 {
    let y: Vec<f64> = values.iter().map(|v| v.max(1e-12).ln()).collect();
    let diffs: Vec<f64> = y.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let sigma = if diffs.is_empty() {
        0.0
    } else {
        median(&diffs) / 0.6745 / std::f64::consts::SQRT_2
    };
    (3.0 * sigma).max(2.0 * threshold.ln()) * ((values.len() as f64).ln().max(1.0))
}

/// Refuses runs of more than one adapter, naming them; `first` is the run given first.
pub fn check_one_adapter(first: &RunSummary, runs: &[RunSummary]) -> anyhow::Result<()> {
    let adapter = &first.adapter;
    let others: Vec<String> = runs
        .iter()
        .filter(|r| &r.adapter != adapter)
        .map(|r| format!("{} ({})", r.run.dir, r.adapter))
        .collect();
    if !others.is_empty() {
        anyhow::bail!(
            "history: {} ran on {adapter}, but {} on another adapter; a change between two \
             machines is not a change of the code. Give the runs of one adapter only (e.g. \
             reports/baselines/llvmpipe-*)",
            first.run.dir,
            others.join(", ")
        );
    }
    Ok(())
}

/// Puts runs in the order they started (the order given for equal dates).
pub fn sort_by_date(runs: &mut [RunSummary]) {
    runs.sort_by(|a, b| a.run.date_utc.cmp(&b.run.date_utc));
}

pub fn history(
    dirs: &[PathBuf],
    out: &Path,
    threshold: f64,
    alpha: f64,
) -> anyhow::Result<History> {
    anyhow::ensure!(
        !dirs.is_empty(),
        "history needs at least one results directory"
    );
    // Each run is read and reduced on its own (in parallel), so memory holds summaries only.
    let mut runs: Vec<RunSummary> = dirs
        .par_iter()
        .map(|d| ResultsFile::read(d).map(|f| summarise(d, &f)))
        .collect::<anyhow::Result<_>>()?;
    check_one_adapter(&runs[0], &runs)?;
    // The x-axis is time: the date each run started (then the order given, for equal dates).
    sort_by_date(&mut runs);
    divide_out_the_machine(&mut runs);
    // compare's verdicts for each adjacent pair.
    let pairs: Vec<Option<PairFindings>> = std::iter::once(Ok(None))
        .chain(
            (1..runs.len())
                .into_par_iter()
                .map(|k| {
                    pair_findings(
                        Path::new(&runs[k - 1].run.dir),
                        Path::new(&runs[k].run.dir),
                        &out.join("pairs").join(format!("{}-{}", k - 1, k)),
                        threshold,
                        alpha,
                    )
                    .map(Some)
                })
                .collect::<Vec<_>>(),
        )
        .collect::<anyhow::Result<_>>()?;
    Ok(build(runs, &pairs, threshold))
}

/// The history of `runs` (one adapter, in date order) from their summaries and compare's
/// findings on each adjacent pair (`pairs[i]`: run i−1 against run i; `pairs[0]` is `None`).
pub fn build(runs: Vec<RunSummary>, pairs: &[Option<PairFindings>], threshold: f64) -> History {
    let adapter = runs.first().map(|r| r.adapter.clone()).unwrap_or_default();
    // The reports' groups (variant × data set × viewport), matched across the runs in the
    // order they first appear.
    let mut groups: Vec<&SeriesKey> = vec![];
    for r in &runs {
        for (g, _) in &r.groups {
            if !groups.contains(&g) {
                groups.push(g);
            }
        }
    }
    let mut series = vec![];
    for g in groups {
        let mut points: Vec<Point> = vec![];
        for (i, r) in runs.iter().enumerate() {
            let Some(v) = r
                .groups
                .iter()
                .find(|(k, _)| k == g)
                .and_then(|(_, v)| v.as_ref())
            else {
                continue;
            };
            // Only a pair of adjacent runs is judged: a group missing from a run starts afresh.
            let changes = match (pairs.get(i).and_then(|p| p.as_ref()), points.last()) {
                (Some(pf), Some(last)) if last.run + 1 == i => pair_changes(pf, g, last, v),
                _ => vec![],
            };
            points.push(Point {
                run: i,
                total_ms: v.total_ms,
                band_lo: v.band_lo,
                band_hi: v.band_hi,
                psnr_db: v.psnr_db,
                gpu_bytes: v.gpu_bytes,
                changes,
                step: None,
            });
        }
        mark_steps(&mut points, &runs, threshold);
        series.push(Series {
            algorithm: g.algorithm.clone(),
            settings: g.settings.to_string(),
            dataset: g.dataset.clone(),
            width: g.width,
            height: g.height,
            points,
        });
    }
    History {
        schema_version: SCHEMA_VERSION,
        adapter,
        runs: runs.into_iter().map(|r| r.run).collect(),
        series,
    }
}

/// What compare found between the previous run and this one for group `g` (its point `v`
/// after the point `last`): the time's finding, the PSNR's move, memory, the work counters.
fn pair_changes(pf: &PairFindings, g: &SeriesKey, last: &Point, v: &GroupValues) -> Vec<String> {
    let mut changes = vec![];
    if let Some((_, t)) = pf.time.iter().find(|(k, _)| k == g) {
        changes.push(t.clone());
    }
    let mut psnr_moved = false;
    let mut memory = false;
    let mut work: Vec<&str> = vec![];
    for f in pf.rows.iter().filter(|f| f.in_series(g)) {
        psnr_moved |= f.psnr_moved;
        memory |= f.memory;
        for w in &f.work {
            if !work.contains(&w.as_str()) {
                work.push(w);
            }
        }
    }
    if psnr_moved {
        if let (Some(a), Some(b)) = (last.psnr_db, v.psnr_db) {
            changes.push(format!("psnr {:+.2} dB", b - a));
        }
    }
    if memory {
        changes.push("memory".into());
    }
    if !work.is_empty() {
        changes.push(format!("work: {}", work.join(", ")));
    }
    changes
}

/// Marks the steps of a series' times (a lasting change between runs of different commits)
/// with the ratio of the medians after and before each.
fn mark_steps(points: &mut [Point], runs: &[RunSummary], threshold: f64) {
    let values: Vec<f64> = points.iter().map(|p| p.total_ms).collect();
    let same: Vec<bool> = points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            k > 0
                && runs[points[k - 1].run].run.commit == runs[p.run].run.commit
                && runs[p.run].run.commit != "?"
        })
        .collect();
    let penalty = step_penalty(&values, threshold);
    let steps = detect_steps(&values, &same, penalty, threshold);
    for (k, &s) in steps.iter().enumerate() {
        let prev_start = if k == 0 { 0 } else { steps[k - 1] };
        let end = steps.get(k + 1).copied().unwrap_or(values.len());
        points[s].step = Some(median(&values[s..end]) / median(&values[prev_start..s]));
    }
}

fn psnr_mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

#[cfg(test)]
#[path = "history_tests.rs"]
mod tests;
