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

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::regress::compare::{adapter_of, CompareOptions, FailOn, ImageVerdict, Verdict};
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

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
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

fn group_rows<'a>(f: &'a ResultsFile, g: &GroupKey) -> Vec<&'a Row> {
    f.rows.iter().filter(|r| g.matches(r) && r.ok()).collect()
}

/// Pooled frames of a group, each divided by `scale(row)`.
fn pooled(rows: &[&Row], scale: impl Fn(&Row) -> Option<f64>) -> Vec<f64> {
    rows.iter()
        .filter_map(|r| scale(r).map(|m| r.samples.total_ms.iter().map(move |x| x / m)))
        .flatten()
        .collect()
}

/// The change points of `values` (indices where a new level starts) by an L1 piecewise-constant
/// fit of their logarithms: minimise Σ over segments of Σ|ln v − median| plus `penalty` per
/// segment, by dynamic programming over every segmentation (O(n³), n is a few hundred runs at
/// most). `same_as_previous[i]`: run i measured the same code as run i−1, so no step may start
/// there. Steps whose levels differ by less than `threshold` (a factor) are merged away.
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
    let cost = |a: usize, b: usize| {
        let m = median(&y[a..b]);
        y[a..b].iter().map(|v| (v - m).abs()).sum::<f64>()
    };
    // best[j]: the least cost of y[..j]; from[j]: where its last segment starts.
    let mut best = vec![0.0f64; n + 1];
    let mut from = vec![0usize; n + 1];
    for j in 1..=n {
        best[j] = f64::INFINITY;
        for i in 0..j {
            if i > 0 && same_as_previous.get(i).copied().unwrap_or(false) {
                continue; // no step between two runs of one commit
            }
            let c = best[i] + cost(i, j) + penalty;
            if c < best[j] {
                best[j] = c;
                from[j] = i;
            }
        }
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

pub fn history(
    dirs: &[PathBuf],
    out: &Path,
    threshold: f64,
    alpha: f64,
) -> anyhow::Result<History> {
    let mut files: Vec<(PathBuf, ResultsFile)> = dirs
        .iter()
        .map(|d| ResultsFile::read(d).map(|f| (d.clone(), f)))
        .collect::<anyhow::Result<_>>()?;
    anyhow::ensure!(
        !files.is_empty(),
        "history needs at least one results directory"
    );
    let adapter = adapter_of(&files[0].1);
    let others: Vec<String> = files
        .iter()
        .filter(|(_, f)| adapter_of(f) != adapter)
        .map(|(d, f)| format!("{} ({})", d.display(), adapter_of(f)))
        .collect();
    if !others.is_empty() {
        anyhow::bail!(
            "history: {} ran on {adapter}, but {} on another adapter; a change between two \
             machines is not a change of the code. Give the runs of one adapter only (e.g. \
             reports/baselines/llvmpipe-*)",
            files[0].0.display(),
            others.join(", ")
        );
    }
    // The x-axis is time: the date each run started (then the order given, for equal dates).
    files.sort_by(|a, b| a.1.machine.date_utc.cmp(&b.1.machine.date_utc));
    let runs: Vec<Run> = files
        .iter()
        .map(|(d, f)| {
            let commit = f.machine.git_commit.clone().unwrap_or_else(|| "?".into());
            let date = f.machine.date_utc.get(..10).unwrap_or("?").to_string();
            Run {
                dir: d.display().to_string(),
                label: format!("{} {date}", &commit[..commit.len().min(7)]),
                commit,
                date_utc: f.machine.date_utc.clone(),
            }
        })
        .collect();
    // compare's verdicts for each adjacent pair.
    let mut pairs = vec![None];
    for (k, w) in files.windows(2).enumerate() {
        let opt = CompareOptions {
            threshold,
            alpha,
            normalised: false,
            drift_correction: true,
            paired: false,
            drift_limit: 1.5,
            fail_on: FailOn::Never,
            out: out.join("pairs").join(format!("{}-{}", k, k + 1)),
        };
        pairs.push(Some(crate::regress::compare::compare(
            &w[0].0, &w[1].0, &opt,
        )?));
    }
    // The reports' groups (variant × data set × viewport), matched across the runs.
    let groups = GroupKey::distinct(files.iter().flat_map(|(_, f)| &f.rows));
    let mut series = vec![];
    for g in groups {
        let mut points: Vec<Point> = vec![];
        for (i, (_, f)) in files.iter().enumerate() {
            let rows = group_rows(f, &g);
            let medians: Vec<f64> = rows.iter().filter_map(|r| r.total_ms).collect();
            if medians.is_empty() {
                continue;
            }
            let t = median(&medians);
            let noise = pooled(&rows, |r| r.total_ms);
            let (lo, hi) = if noise.is_empty() {
                (t, t)
            } else {
                (t * quantile(&noise, 0.1), t * quantile(&noise, 0.9))
            };
            let psnr: Vec<f64> = rows.iter().filter_map(|r| r.psnr_db).collect();
            let mut changes = vec![];
            // Only a pair of adjacent runs is judged: a group missing from a run starts afresh.
            if let Some(cmp) = pairs[i]
                .as_ref()
                .filter(|_| points.last().is_some_and(|p| p.run + 1 == i))
            {
                if let Some(gc) = cmp.groups.iter().find(|c| c.is(&g)) {
                    match gc.total.verdict {
                        Verdict::Slower => changes.push(format!("slower ×{:.3}", gc.total.ratio)),
                        Verdict::Faster => changes.push(format!("faster ×{:.3}", gc.total.ratio)),
                        Verdict::TooFewSamples => changes.push("too few rounds".into()),
                        Verdict::TooNoisy => changes.push("too noisy".into()),
                        Verdict::NoChange => {}
                    }
                }
                let rows_here = cmp.rows.iter().filter(|r| r.in_group(&g));
                let mut psnr_moved = false;
                let mut memory = false;
                let mut work: Vec<&str> = vec![];
                for r in rows_here {
                    psnr_moved |= r.image.as_ref().is_some_and(|i| {
                        matches!(i.verdict, ImageVerdict::Worse | ImageVerdict::Better)
                    });
                    for w in &r.work {
                        if w.counter.starts_with("gpu_bytes") {
                            memory = true;
                        } else if !work.contains(&w.counter.as_str()) {
                            work.push(&w.counter);
                        }
                    }
                }
                let last = points.last().expect("checked above");
                if psnr_moved {
                    if let (Some(a), Some(b)) = (last.psnr_db, psnr_mean(&psnr)) {
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
                total_ms: t,
                band_lo: lo,
                band_hi: hi,
                psnr_db: psnr_mean(&psnr),
                gpu_bytes: rows.iter().filter_map(|r| r.gpu_bytes).max(),
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
                    && runs[points[k - 1].run].commit == runs[p.run].commit
                    && runs[p.run].commit != "?"
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
            settings: g.settings.to_string(),
            dataset: g.dataset.clone(),
            width: g.width,
            height: g.height,
            points,
        });
    }
    Ok(History {
        schema_version: SCHEMA_VERSION,
        adapter,
        runs,
        series,
    })
}

fn psnr_mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// One chart per algorithm × data set (drawn by [`crate::plot::history`]): a line per
/// settings variant of `h`'s series on that pair.
fn chart(path: &Path, h: &History, alg: &str, dataset: &str) -> anyhow::Result<()> {
    use crate::plot::history::{Change, Line, LinePoint};
    let lines: Vec<Line> = h
        .series
        .iter()
        .filter(|s| s.algorithm == alg && s.dataset == dataset)
        .map(|s| Line {
            label: s.label(h),
            points: s
                .points
                .iter()
                .map(|p| LinePoint {
                    run: p.run,
                    total_ms: p.total_ms,
                    band_lo: p.band_lo,
                    band_hi: p.band_hi,
                    step: p.step.is_some(),
                    change: if p.changes.is_empty() {
                        None
                    } else if p.changes.iter().any(|c| c.starts_with("slower")) {
                        Some(Change::Slower)
                    } else if p.changes.iter().any(|c| c.starts_with("faster")) {
                        Some(Change::Faster)
                    } else {
                        Some(Change::Other)
                    },
                })
                .collect(),
        })
        .collect();
    let runs: Vec<String> = h.runs.iter().map(|r| r.label.clone()).collect();
    crate::plot::history::chart(
        path,
        &format!("{alg} on {dataset}: total ms per run"),
        &runs,
        &lines,
    )
}

#[derive(Serialize)]
struct PageSeries<'a> {
    algorithm: &'a str,
    settings: String,
    dataset: &'a str,
    points: &'a [Point],
    steps: Vec<String>,
}

#[derive(Serialize)]
struct PageChart {
    title: String,
    file: String,
}

fn step_labels(h: &History, s: &Series) -> Vec<String> {
    s.points
        .iter()
        .filter_map(|p| {
            p.step
                .map(|r| format!("×{r:.3} at {}", h.runs[p.run].label))
        })
        .collect()
}

/// history.html: the runs, each series with its changes and steps, and the charts.
pub fn page(h: &History, charts: &[(String, String)]) -> anyhow::Result<String> {
    let series: Vec<PageSeries> = h
        .series
        .iter()
        .map(|s| PageSeries {
            algorithm: &s.algorithm,
            settings: s.label(h),
            dataset: &s.dataset,
            points: &s.points,
            steps: step_labels(h, s),
        })
        .collect();
    let charts: Vec<PageChart> = charts
        .iter()
        .map(|(title, file)| PageChart {
            title: title.clone(),
            file: file.clone(),
        })
        .collect();
    #[derive(Serialize)]
    struct Page<'a> {
        adapter: &'a str,
        runs: &'a [Run],
        series: Vec<PageSeries<'a>>,
        charts: Vec<PageChart>,
    }
    let page = Page {
        adapter: &h.adapter,
        runs: &h.runs,
        series,
        charts,
    };
    // templates/history.html: every value HTML-escaped (crate::report::html).
    crate::report::html::render("history.html", &page)
}

/// `tetbench history`: history.json, history.md, history.html and one chart per algorithm ×
/// data set in `out`.
pub fn run_command(dirs: &[PathBuf], out: &Path, threshold: f64, alpha: f64) -> anyhow::Result<()> {
    let (_, md) = write_files(dirs, out, threshold, alpha)?;
    print!("{md}");
    println!("wrote {}/history.{{md,html,json}}", out.display());
    Ok(())
}

/// Writes what `tetbench history` writes (also for `tetbench publish`); returns the history and
/// its Markdown.
pub fn write_files(
    dirs: &[PathBuf],
    out: &Path,
    threshold: f64,
    alpha: f64,
) -> anyhow::Result<(History, String)> {
    let h = history(dirs, out, threshold, alpha)?;
    let charts_dir = out.join("charts");
    std::fs::create_dir_all(&charts_dir)
        .with_context(|| format!("cannot create {}", charts_dir.display()))?;
    let mut md = format!(
        "# tetbench history\n\nAdapter: {}\n\nRuns (by start date): ",
        h.adapter
    );
    md.push_str(
        &h.runs
            .iter()
            .map(|r| r.label.as_str())
            .collect::<Vec<_>>()
            .join(" → "),
    );
    md.push_str(
        "\n\n| algorithm | settings | data set | ms per run (changes against the run before) | steps |\n|---|---|---|---|---|\n",
    );
    let mut pairs: Vec<(String, String)> = vec![];
    for s in &h.series {
        let cells: Vec<String> = s
            .points
            .iter()
            .map(|p| {
                if p.changes.is_empty() {
                    format!("{:.2}", p.total_ms)
                } else {
                    format!("**{:.2} ({})**", p.total_ms, p.changes.join(", "))
                }
            })
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} |",
            s.algorithm,
            s.label(&h),
            s.dataset,
            cells.join(" → "),
            step_labels(&h, s).join(", ")
        );
        let k = (s.algorithm.clone(), s.dataset.clone());
        if !pairs.contains(&k) {
            pairs.push(k);
        }
    }
    let mut charts = vec![];
    for (alg, ds) in &pairs {
        let name = format!(
            "history_{}_{}.png",
            crate::results::names::slug(alg),
            crate::results::names::slug(ds)
        );
        chart(&charts_dir.join(&name), &h, alg, ds)?;
        charts.push((format!("{alg} on {ds}"), name));
    }
    std::fs::write(out.join("history.md"), &md).context("writing history.md")?;
    std::fs::write(out.join("history.html"), page(&h, &charts)?).context("writing history.html")?;
    std::fs::write(out.join("history.json"), serde_json::to_string_pretty(&h)?)
        .context("writing history.json")?;
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

    /// history.html escapes everything: a data set named with markup lands as text.
    #[test]
    fn the_page_escapes_names() {
        let hostile = "<img src=x onerror=alert(1)>";
        let h = History {
            schema_version: SCHEMA_VERSION,
            adapter: hostile.into(),
            runs: vec![Run {
                dir: hostile.into(),
                commit: "abc".into(),
                date_utc: "2026-01-01T00:00:00Z".into(),
                label: hostile.into(),
            }],
            series: vec![Series {
                algorithm: hostile.into(),
                settings: hostile.into(),
                dataset: hostile.into(),
                width: 64,
                height: 64,
                points: vec![Point {
                    run: 0,
                    total_ms: 1.0,
                    band_lo: 1.0,
                    band_hi: 1.0,
                    psnr_db: None,
                    gpu_bytes: None,
                    changes: vec![hostile.into()],
                    step: Some(1.5),
                }],
            }],
        };
        let html = page(&h, &[(hostile.into(), hostile.into())]).unwrap();
        assert!(!html.contains("<img src=x"), "{html}");
        assert!(
            html.contains("&lt;img src=x onerror=alert(1)&gt;"),
            "{html}"
        );
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
