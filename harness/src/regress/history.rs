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
//! [`crate::regress::history_page`]'s.

use std::collections::BinaryHeap;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
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

/// A group as history follows it across runs: compare's key, the settings as text.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SeriesKey {
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    pub width: u32,
    pub height: u32,
    pub projection: String,
}

impl SeriesKey {
    pub fn of(g: &GroupKey) -> SeriesKey {
        SeriesKey {
            algorithm: g.algorithm.clone(),
            settings: g.settings.to_string(),
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
        },
        adapter: adapter_of(file),
        groups,
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
    pub settings: String,
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
            let mut changes = vec![];
            // Only a pair of adjacent runs is judged: a group missing from a run starts afresh.
            if let Some(pf) = pairs
                .get(i)
                .and_then(|p| p.as_ref())
                .filter(|_| points.last().is_some_and(|p| p.run + 1 == i))
            {
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
                let last = points.last().expect("checked above");
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
            }
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
        series.push(Series {
            algorithm: g.algorithm.clone(),
            settings: g.settings.clone(),
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

fn psnr_mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// `tetbench history`: history.json, history.csv, history.md, history.html and one chart per
/// algorithm × data set in `out`.
pub fn run_command(dirs: &[PathBuf], out: &Path, threshold: f64, alpha: f64) -> anyhow::Result<()> {
    let (_, md) = write_files(dirs, out, threshold, alpha)?;
    print!("{md}");
    println!("wrote {}/history.{{md,html,json,csv}}", out.display());
    Ok(())
}

/// Writes what `tetbench history` writes; returns the history and its Markdown.
pub fn write_files(
    dirs: &[PathBuf],
    out: &Path,
    threshold: f64,
    alpha: f64,
) -> anyhow::Result<(History, String)> {
    let h = history(dirs, out, threshold, alpha)?;
    let md = crate::regress::history_page::write(out, &h)?;
    Ok((h, md))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ×1.3 level change in a noisy series is one step at the right place; the same series
    /// without it has none; a step between two runs of one commit is not allowed.
    #[test]
    fn steps_are_found_where_the_level_changes() {
        let wobble = [1.0, 1.03, 0.98, 1.01, 0.97, 1.02, 1.0, 0.99];
        let flat: Vec<f64> = wobble.iter().chain(&wobble).map(|w| 10.0 * w).collect();
        let none = vec![false; flat.len()];
        let p = step_penalty(&flat, 1.10);
        assert!(detect_steps(&flat, &none, p, 1.10).is_empty());
        let stepped: Vec<f64> = flat
            .iter()
            .enumerate()
            .map(|(i, v)| if i >= 8 { v * 1.3 } else { *v })
            .collect();
        let p = step_penalty(&stepped, 1.10);
        assert_eq!(detect_steps(&stepped, &none, p, 1.10), [8]);
        // Run 8 measured the same commit as run 7: the step moves to where the code changed.
        let mut same = none.clone();
        same[8] = true;
        let at = detect_steps(&stepped, &same, p, 1.10);
        assert!(!at.contains(&8), "{at:?}");
        // All one commit: no step at all.
        assert!(detect_steps(&stepped, &vec![true; stepped.len()], p, 1.10).is_empty());
    }

    /// The DP grown backwards with running heaps finds what the direct one (every segment's
    /// cost from a sorted copy) finds, exact ties included (case 14 has one), on noisy series
    /// with and without steps.
    #[test]
    fn the_fast_fit_finds_what_the_direct_one_finds() {
        fn direct(values: &[f64], same: &[bool], penalty: f64, threshold: f64) -> Vec<usize> {
            let y: Vec<f64> = values.iter().map(|v| v.max(1e-12).ln()).collect();
            let n = y.len();
            let cost = |a: usize, b: usize| {
                let m = median(&y[a..b]);
                y[a..b].iter().map(|v| (v - m).abs()).sum::<f64>()
            };
            let (mut best, mut from) = (vec![0.0f64; n + 1], vec![0usize; n + 1]);
            for j in 1..=n {
                let costs: Vec<f64> = (0..j)
                    .map(|i| {
                        if i > 0 && same[i] {
                            f64::INFINITY
                        } else {
                            best[i] + cost(i, j) + penalty
                        }
                    })
                    .collect();
                (best[j], from[j]) = least(&costs);
            }
            let mut starts = vec![];
            let mut j = n;
            while j > 0 {
                starts.push(from[j]);
                j = from[j];
            }
            starts.reverse();
            let (mut steps, mut seg) = (vec![], 0);
            for (k, &s) in starts.iter().enumerate().skip(1) {
                let end = starts.get(k + 1).copied().unwrap_or(n);
                if (median(&y[s..end]) - median(&y[seg..s])).abs() >= threshold.ln() {
                    steps.push(s);
                    seg = s;
                }
            }
            steps
        }
        // A fixed pseudo-random sequence (an LCG): noise of ±10 %, levels ×1.3 and ×0.7.
        let mut state = 12345u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut found = 0;
        for case in 0..40 {
            let n = 20 + case * 3;
            let values: Vec<f64> = (0..n)
                .map(|i| {
                    let level = match case % 4 {
                        0 => 1.0,
                        1 if i >= n / 3 => 1.3,
                        2 if i >= n / 2 => 0.7,
                        3 if i >= n / 4 && i < 3 * n / 4 => 1.5,
                        _ => 1.0,
                    };
                    // Every fifth case rounds to few distinct values: ties in the costs.
                    let v = 10.0 * level * (0.9 + 0.2 * uniform());
                    if case % 5 == 0 {
                        v.round()
                    } else {
                        v
                    }
                })
                .collect();
            let same: Vec<bool> = (0..n).map(|i| i % 7 == 3).collect();
            for threshold in [1.05, 1.10] {
                let p = step_penalty(&values, threshold);
                let fast = detect_steps(&values, &same, p, threshold);
                assert_eq!(fast, direct(&values, &same, p, threshold), "case {case}");
                found += fast.len();
            }
        }
        assert!(found > 20, "the cases hold steps to find: {found}");
    }

    /// Six runs of two groups; the code changes at run 3 (a new commit) and makes alg0 ×1.5
    /// slower: compare's test marks the pair, the fit puts one step at run 3 for alg0 and
    /// none for alg1; the same six runs all of one commit have no step at all. The runs are
    /// given out of order and put in order by date.
    #[test]
    fn history_marks_the_step_where_the_code_changed() {
        let tmp = tempfile::tempdir().unwrap();
        let write = |name: &str, k: usize, commit: &str, slow: f64| {
            let dir = tmp.path().join(name);
            std::fs::create_dir_all(&dir).unwrap();
            let mut rows = vec![];
            // alg0 at two sizes, only the 64² one made slower: one variant, two groups.
            for (g, f, size) in [(0, slow, 64), (0, 1.0, 128), (1, 1.0, 64)] {
                for (v, vp) in ["+x", "-x", "+y"].iter().enumerate() {
                    let mut row = Row {
                        algorithm: format!("alg{g}"),
                        settings: "k=2".parse().unwrap(),
                        dataset: "box:1k".into(),
                        viewpoint: vp.to_string(),
                        width: size,
                        height: size,
                        ..Default::default()
                    };
                    row.samples.total_ms = (0..5)
                        .map(|r| 10.0 * f * (1.0 + 0.01 * (((k + v + r) * 7) % 5) as f64))
                        .collect();
                    row.total_ms = Some(median(&row.samples.total_ms));
                    rows.push(row);
                }
            }
            let mut machine = crate::results::machine::MachineInfo::collect();
            machine.git_commit = Some(commit.into());
            machine.date_utc = format!("2026-01-0{}T00:00:00Z", k + 1);
            let file = ResultsFile {
                control: None,
                schema_version: crate::results::SCHEMA_VERSION,
                machine,
                run: crate::results::RunDescription {
                    rounds: 5,
                    frames: 1,
                    ..Default::default()
                },
                finished_utc: None,
                rows,
                errors: vec![],
            };
            crate::results::write_json(&dir, &file).unwrap();
            dir
        };
        let mut changed = vec![];
        let mut same = vec![];
        for k in (0..6).rev() {
            let (commit, slow) = if k < 3 { ("aaa", 1.0) } else { ("bbb", 1.5) };
            changed.push(write(&format!("c{k}"), k, commit, slow));
            same.push(write(&format!("s{k}"), k, "aaa", 1.0));
        }
        let out = tmp.path().join("out");
        let h = history(&changed, &out, 1.10, 0.05).unwrap();
        assert_eq!(h.runs[0].date_utc, "2026-01-01T00:00:00Z");
        assert_eq!(h.runs[3].label, "bbb 2026-01-04");
        let alg0 = &h.series[0];
        assert_eq!(alg0.algorithm, "alg0");
        let steps: Vec<usize> = alg0
            .points
            .iter()
            .filter(|p| p.step.is_some())
            .map(|p| p.run)
            .collect();
        assert_eq!(steps, [3]);
        assert!((alg0.points[3].step.unwrap() - 1.5).abs() < 0.05);
        assert!(
            alg0.points[3]
                .changes
                .iter()
                .any(|c| c.starts_with("slower")),
            "{:?}",
            alg0.points[3]
        );
        // The same variant at 128² did not change: no step, and not the 64² group's verdict.
        assert_eq!(
            (h.series[1].algorithm.as_str(), h.series[1].width),
            ("alg0", 128)
        );
        assert!(h.series[1]
            .points
            .iter()
            .all(|p| p.step.is_none() && p.changes.is_empty()));
        assert!(h.series[2].points.iter().all(|p| p.step.is_none()));
        let flat = history(&same, &out, 1.10, 0.05).unwrap();
        assert!(flat.series.iter().all(|s| s
            .points
            .iter()
            .all(|p| p.step.is_none() && p.changes.is_empty())));

        // Another adapter in the series is refused.
        let mut other = ResultsFile::read(&changed[0]).unwrap();
        other.machine.cpu_model = "another CPU".into();
        other.machine.adapter = Some(render_core::AdapterDescription {
            name: "Other GPU".into(),
            backend: "vulkan".into(),
            device_type: "DiscreteGpu".into(),
            driver: String::new(),
            driver_info: String::new(),
        });
        crate::results::write_json(&changed[0], &other).unwrap();
        let e = history(&changed, &out, 1.10, 0.05).unwrap_err().to_string();
        assert!(e.contains("another adapter"), "{e}");
    }
}
