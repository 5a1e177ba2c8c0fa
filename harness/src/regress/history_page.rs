//! What `tetbench history` writes from a [`History`]: pages that lead with what changed, one
//! chart per algorithm × data set, and the per-run numbers as data files.
//!
//! - `history.html`: the steps found, newest first, each with its run's commit and date, its
//!   ratio, its series and a link to its chart; then the charts (those with a step first), each
//!   an SVG of `crate::plot::history` (every series, the steps as dashed bars, each run's
//!   commit and values on hover); then one line per series (first and latest time, pairs
//!   flagged by compare, steps). No per-run number is in the page: its size grows with the
//!   series, not the runs.
//! - `history.md`: the same steps and series lines.
//! - `history.csv` (one line per run and series) and `history.json` (the [`History`],
//!   `docs/history.schema.json`): every number, for download.
//! - `charts/history_ALGORITHM_DATASET.svg`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::Serialize;

use crate::plot::history::{Change, Line, LinePoint, RunTick};
use crate::regress::history::{History, Series};
use crate::results::names::slug;
use crate::results::write_file;

/// One step of a series, as the pages list it.
#[derive(Debug, Clone, Serialize)]
pub struct StepLine {
    /// Index of the run where the new level starts.
    pub run: usize,
    /// That run's start date (`YYYY-MM-DD`) and commit (10 characters).
    pub date: String,
    pub commit: String,
    /// The new level over the one before.
    pub ratio: f64,
    /// `×1.30`.
    pub ratio_text: String,
    /// `slower` or `faster`.
    pub change: &'static str,
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    /// The id of its chart in history.html.
    pub chart: String,
}

/// The id (and file stem) of the chart of `algorithm` on `dataset`.
pub fn chart_id(algorithm: &str, dataset: &str) -> String {
    format!("history_{}_{}", slug(algorithm), slug(dataset))
}

/// Every step of every series, newest first (then in the order of the series).
pub fn steps(h: &History) -> Vec<StepLine> {
    let mut v: Vec<StepLine> = h
        .series
        .iter()
        .flat_map(|s| {
            s.points.iter().filter_map(move |p| {
                let ratio = p.step?;
                let run = &h.runs[p.run];
                Some(StepLine {
                    run: p.run,
                    date: run.date_utc.get(..10).unwrap_or("?").to_string(),
                    commit: run.commit.chars().take(10).collect(),
                    ratio,
                    ratio_text: format!("×{ratio:.2}"),
                    change: if ratio > 1.0 { "slower" } else { "faster" },
                    algorithm: s.algorithm.clone(),
                    settings: s.label(h),
                    dataset: s.dataset.clone(),
                    chart: chart_id(&s.algorithm, &s.dataset),
                })
            })
        })
        .collect();
    v.sort_by_key(|c| std::cmp::Reverse(c.run));
    v
}

/// `×1.480 at bbb1234 2026-01-04` for each step of `s`.
fn step_labels(h: &History, s: &Series) -> Vec<String> {
    s.points
        .iter()
        .filter_map(|p| {
            p.step
                .map(|r| format!("×{r:.3} at {}", h.runs[p.run].label))
        })
        .collect()
}

/// The algorithm × data set pairs of `h`, in the order of its series.
fn chart_pairs(h: &History) -> Vec<(String, String)> {
    let mut pairs: Vec<(String, String)> = vec![];
    for s in &h.series {
        let k = (s.algorithm.clone(), s.dataset.clone());
        if !pairs.contains(&k) {
            pairs.push(k);
        }
    }
    pairs
}

/// What compare found against the run before, as a chart marks it: slower, faster, or another
/// change (PSNR, memory, work). A pair it could not judge (`too few rounds`, `too noisy`) is
/// no change and gets no marker; its tooltip still says so.
fn marker(changes: &[String]) -> Option<Change> {
    let any = |p: &str| changes.iter().any(|c| c.starts_with(p));
    if any("slower") {
        Some(Change::Slower)
    } else if any("faster") {
        Some(Change::Faster)
    } else if any("psnr") || any("memory") || any("work") {
        Some(Change::Other)
    } else {
        None
    }
}

/// The lines of the chart of `alg` on `dataset`: one per series on that pair.
fn chart_lines(h: &History, alg: &str, dataset: &str) -> Vec<Line> {
    h.series
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
                    step: p.step,
                    change: marker(&p.changes),
                    note: p.changes.join(", "),
                })
                .collect(),
        })
        .collect()
}

/// One chart as the page embeds it.
#[derive(Debug, Clone, Serialize)]
pub struct ChartFile {
    pub id: String,
    pub title: String,
    /// Relative to the history's folder.
    pub file: String,
    pub width: u32,
    pub height: u32,
    /// Steps in its series.
    pub steps: usize,
}

/// Writes the charts into `out/charts/`, those with a step first.
fn write_charts(out: &Path, h: &History) -> anyhow::Result<Vec<ChartFile>> {
    let dir = out.join("charts");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let ticks: Vec<RunTick> = h
        .runs
        .iter()
        .map(|r| RunTick {
            label: r.label.clone(),
            date: r.date_utc.get(..10).unwrap_or("?").to_string(),
        })
        .collect();
    let mut charts = vec![];
    for (alg, ds) in chart_pairs(h) {
        let lines = chart_lines(h, &alg, &ds);
        let title = format!("{alg} on {ds}");
        let chart =
            crate::plot::history::svg_chart(&format!("{title}: total ms per run"), &ticks, &lines);
        let id = chart_id(&alg, &ds);
        let file = format!("charts/{id}.svg");
        let svg =
            crate::report::html::render("history_chart.svg", serde_json::json!({ "c": chart }))?;
        write_file(&out.join(&file), svg)?;
        charts.push(ChartFile {
            id,
            title,
            file,
            width: chart.width,
            height: chart.height,
            steps: lines
                .iter()
                .map(|l| l.points.iter().filter(|p| p.step.is_some()).count())
                .sum(),
        });
    }
    // Stable: the charts with a step first, each group in the order of the series.
    charts.sort_by_key(|c| c.steps == 0);
    Ok(charts)
}

/// One series as the pages' table shows it.
#[derive(Debug, Clone, Serialize)]
struct SeriesLine {
    algorithm: String,
    settings: String,
    dataset: String,
    size: String,
    chart: String,
    runs: usize,
    first_ms: String,
    last_ms: String,
    /// Latest over first.
    ratio: String,
    /// Pairs in which compare found a change ([`marker`]).
    flagged: usize,
    steps: Vec<String>,
}

fn series_lines(h: &History) -> Vec<SeriesLine> {
    h.series
        .iter()
        .map(|s| {
            let (first, last) = (s.points.first(), s.points.last());
            let ms = |p: Option<&crate::regress::history::Point>| {
                p.map_or("–".to_string(), |p| format!("{:.2}", p.total_ms))
            };
            SeriesLine {
                algorithm: s.algorithm.clone(),
                settings: s.label(h),
                dataset: s.dataset.clone(),
                size: format!("{}×{}", s.width, s.height),
                chart: chart_id(&s.algorithm, &s.dataset),
                runs: s.points.len(),
                first_ms: ms(first),
                last_ms: ms(last),
                ratio: match (first, last) {
                    (Some(a), Some(b)) if a.total_ms > 0.0 => {
                        format!("×{:.2}", b.total_ms / a.total_ms)
                    }
                    _ => "–".into(),
                },
                flagged: s
                    .points
                    .iter()
                    .filter(|p| marker(&p.changes).is_some())
                    .count(),
                steps: step_labels(h, s),
            }
        })
        .collect()
}

/// history.html: what changed first, then the charts, then the series.
pub fn page(h: &History, charts: &[ChartFile]) -> anyhow::Result<String> {
    #[derive(Serialize)]
    struct Page<'a> {
        adapter: &'a str,
        runs: usize,
        first: &'a str,
        last: &'a str,
        steps: Vec<StepLine>,
        series_with_steps: usize,
        charts: &'a [ChartFile],
        series: Vec<SeriesLine>,
    }
    let page = Page {
        adapter: &h.adapter,
        runs: h.runs.len(),
        first: h.runs.first().map_or("", |r| r.label.as_str()),
        last: h.runs.last().map_or("", |r| r.label.as_str()),
        steps: steps(h),
        series_with_steps: h
            .series
            .iter()
            .filter(|s| s.points.iter().any(|p| p.step.is_some()))
            .count(),
        charts,
        series: series_lines(h),
    };
    // templates/history.html: every value HTML-escaped (crate::report::html).
    crate::report::html::render("history.html", &page)
}

/// history.md: the steps, newest first, and one line per series.
fn markdown(h: &History) -> String {
    let mut md = format!("# tetbench history\n\nAdapter: {}\n\n", h.adapter);
    if let (Some(a), Some(b)) = (h.runs.first(), h.runs.last()) {
        let _ = writeln!(
            md,
            "{} runs, from {} to {}.\n",
            h.runs.len(),
            a.label,
            b.label
        );
    }
    let steps = steps(h);
    md.push_str("## What changed\n\n");
    if steps.is_empty() {
        md.push_str("No step in any series.\n\n");
    } else {
        md.push_str("| date | commit | change | algorithm | settings | data set |\n|---|---|---|---|---|---|\n");
        for s in &steps {
            let _ = writeln!(
                md,
                "| {} | {} | {} {} | {} | {} | {} |",
                s.date, s.commit, s.change, s.ratio_text, s.algorithm, s.settings, s.dataset
            );
        }
        md.push('\n');
    }
    md.push_str(
        "## Series\n\n| algorithm | settings | data set | runs | first ms | latest ms | latest/first | pairs flagged | steps |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for s in series_lines(h) {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            s.algorithm,
            s.settings,
            s.dataset,
            s.runs,
            s.first_ms,
            s.last_ms,
            s.ratio,
            s.flagged,
            s.steps.join(", ")
        );
    }
    md
}

/// history.csv: one line per run and series, every number of the history.
fn csv(h: &History) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(vec![]);
    w.write_record([
        "run",
        "commit",
        "date_utc",
        "algorithm",
        "settings",
        "dataset",
        "width",
        "height",
        "total_ms",
        "band_lo",
        "band_hi",
        "psnr_db",
        "gpu_bytes",
        "step",
        "changes",
    ])?;
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
    for s in &h.series {
        for p in &s.points {
            let r = &h.runs[p.run];
            w.write_record([
                p.run.to_string(),
                r.commit.clone(),
                r.date_utc.clone(),
                s.algorithm.clone(),
                s.settings.clone(),
                s.dataset.clone(),
                s.width.to_string(),
                s.height.to_string(),
                p.total_ms.to_string(),
                p.band_lo.to_string(),
                p.band_hi.to_string(),
                opt(p.psnr_db),
                p.gpu_bytes.map_or(String::new(), |b| b.to_string()),
                opt(p.step),
                p.changes.join("; "),
            ])?;
        }
    }
    w.into_inner().context("writing history.csv")
}

/// Writes history.{html,md,csv,json} and the charts into `out`; returns the Markdown.
pub fn write(out: &Path, h: &History) -> anyhow::Result<String> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let charts = write_charts(out, h)?;
    let md = markdown(h);
    std::fs::write(out.join("history.md"), &md).context("writing history.md")?;
    std::fs::write(out.join("history.html"), page(h, &charts)?).context("writing history.html")?;
    std::fs::write(out.join("history.csv"), csv(h)?).context("writing history.csv")?;
    std::fs::write(out.join("history.json"), serde_json::to_string(h)?)
        .context("writing history.json")?;
    Ok(md)
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
    let h = crate::regress::history::history(dirs, out, threshold, alpha)?;
    let md = write(out, &h)?;
    Ok((h, md))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regress::history::{Point, Run, Series, SCHEMA_VERSION};
    use crate::report::html::{assert_no_live_markup, HOSTILE_NAME};

    fn hostile_history() -> History {
        let run = |k: usize| Run {
            dir: HOSTILE_NAME.into(),
            commit: format!("c{k}"),
            date_utc: format!("2026-01-0{}T00:00:00Z", k + 1),
            label: HOSTILE_NAME.into(),
            machine: None,
        };
        let point = |k: usize, ms: f64, step: Option<f64>| Point {
            run: k,
            total_ms: ms,
            band_lo: ms,
            band_hi: ms,
            psnr_db: None,
            gpu_bytes: None,
            changes: vec![HOSTILE_NAME.into()],
            step,
        };
        History {
            schema_version: SCHEMA_VERSION,
            adapter: HOSTILE_NAME.into(),
            runs: (0..3).map(run).collect(),
            series: vec![
                Series {
                    algorithm: HOSTILE_NAME.into(),
                    settings: HOSTILE_NAME.into(),
                    dataset: HOSTILE_NAME.into(),
                    width: 64,
                    height: 64,
                    points: vec![
                        point(0, 1.0, None),
                        point(1, 1.0, None),
                        point(2, 1.5, Some(1.5)),
                    ],
                },
                Series {
                    algorithm: "calm".into(),
                    settings: "k=2".into(),
                    dataset: "box:1k".into(),
                    width: 64,
                    height: 64,
                    points: vec![point(0, 2.0, None), point(2, 2.0, None)],
                },
            ],
        }
    }

    /// The page, the chart and the Markdown lead with the step; the page and the chart escape
    /// every name; the chart with a step comes first; the data files hold every point.
    #[test]
    fn pages_lead_with_the_steps_and_escape_names() {
        let h = hostile_history();
        let dir = tempfile::tempdir().unwrap();
        let md = write(dir.path(), &h).unwrap();
        let html = std::fs::read_to_string(dir.path().join("history.html")).unwrap();
        assert_no_live_markup(&html);
        let changed = html.find("What changed").unwrap();
        let step = html.find("×1.50").unwrap();
        let charts = html.find("id=charts").unwrap();
        assert!(changed < step && step < charts, "{html}");
        let id = chart_id(HOSTILE_NAME, HOSTILE_NAME);
        assert!(html.contains(&format!("href=\"#{id}\"")), "{html}");
        assert!(html.contains(&format!("id=\"{id}\"")), "{html}");
        let (first, second) = (
            html.find(&format!("charts/{id}.svg")).unwrap(),
            html.find("charts/history_calm_box_1k.svg").unwrap(),
        );
        assert!(first < second);
        let svg = std::fs::read_to_string(dir.path().join(format!("charts/{id}.svg"))).unwrap();
        assert_no_live_markup(&svg);
        assert!(
            svg.contains("stroke-dasharray") && svg.contains("×1.50"),
            "{svg}"
        );
        let calm =
            std::fs::read_to_string(dir.path().join("charts/history_calm_box_1k.svg")).unwrap();
        assert!(!calm.contains("stroke-dasharray"), "{calm}");
        // One column per run with a point: 3 runs, and the calm series' gap breaks its line.
        assert_eq!(calm.matches("<rect class=\"run\"").count(), 2);
        assert_eq!(calm.matches("<polyline").count(), 2);
        assert!(md.find("What changed").unwrap() < md.find("×1.50").unwrap());
        let csv = std::fs::read_to_string(dir.path().join("history.csv")).unwrap();
        assert_eq!(csv.lines().count(), 1 + 5);
        let json: History = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join("history.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(json.series.len(), 2);
        assert_eq!(marker(&["too noisy".into()]), None);
        assert_eq!(
            marker(&["too noisy".into(), "work: fragments".into()]),
            Some(Change::Other)
        );
        assert_eq!(marker(&["faster ×0.800".into()]), Some(Change::Faster));
        // The same history without its step: nothing to list.
        let mut flat = h.clone();
        flat.series[0].points[2].step = None;
        assert!(steps(&flat).is_empty());
        assert!(markdown(&flat).contains("No step in any series."));
    }
}
