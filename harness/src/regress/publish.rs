//! `tetbench publish DIR… --out SITE`: one static site over baselines, runs and reproduced
//! papers, as asv's `publish` makes one over its results — our own, smaller version.
//!
//! - `index.html`: per adapter its latest run (by the date it started) and how many runs it
//!   has, the papers reproduced with their verdicts, every run, and the speed–error charts
//!   across adapters (the latest run of each);
//! - `runs/NAME/`: the latest run of each adapter with its full report ([`crate::report::write`],
//!   its results and the images it kept — a baseline keeps none, and its page says so instead
//!   of linking them), every earlier run with a brief page and its results compressed
//!   ([`crate::regress::publish_runs`]);
//! - `history/ADAPTER/`: per adapter with two runs or more, `tetbench history` over them: per
//!   group the time across commits and the steps found;
//! - `papers/SOURCE/PAPER/`: each reproduced paper's report as `tetbench reproduce` wrote it.
//!
//! Publishing is incremental: an existing site keeps its run folders, and a run whose files, page
//! kind and neighbours are those its folder's record names is not read again nor redrawn; its
//! summary and compare's findings against the run before come from that record
//! ([`crate::regress::publish_runs`]). The histories, the papers and the front page are
//! written anew each time.
//!
//! Every page is written through the escaping templates ([`crate::report::html`]) and links
//! only files of the site by relative paths: it works from the file system and from any static
//! host, with no server and no network. `scripts/check-site.sh` walks it in headless Chromium.

use std::path::{Path, PathBuf};

use anyhow::Context;
use rayon::prelude::*;
use serde::Serialize;

use crate::papers::reproduce::{PaperSummary, SUMMARY_FILE};
use crate::plot::speed_error::SpeedAxis;
use crate::regress::compare::adapter_of;
use crate::regress::history_page::StepLine;
use crate::regress::publish_runs::{copy_file, link_pages_to_front, PageKind, PairRecord, SiteRun};
use crate::results::control::Pricing;
use crate::results::names::slug;
use crate::results::{read_text, write_file, ResultsFile, JSON_FILE};

/// The file marking a directory as a site `publish` wrote (and may therefore replace).
pub const SITE_MARKER: &str = ".tetbench-site";

#[derive(Debug, Clone, clap::Args)]
pub struct PublishArgs {
    /// Result directories: a run (holding results.json), a directory of runs (e.g.
    /// reports/baselines), a paper reproduced (holding summary.json) or a directory of them
    /// (e.g. reports/reproduced). A run's `reproduce/` directory joins as its papers.
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Where the site goes (updated when it is a site publish wrote: runs drawn from unchanged
    /// files are kept, the rest replaced; refused when it is another non-empty directory).
    #[arg(long, value_name = "SITE", default_value = "site")]
    pub out: PathBuf,
    /// Factor a median must move by to count as a change in the histories.
    #[arg(long, default_value_t = 1.10)]
    pub threshold: f64,
}

/// One paper reproduced found in the inputs.
struct PaperInput {
    dir: PathBuf,
    summary: PaperSummary,
    /// Where the reproduction comes from (`reproduced`, or the run holding it).
    source: String,
    adapter: String,
}

#[derive(Default)]
struct Inputs {
    /// Each run's directory and its folder in the site (`runs/NAME`).
    runs: Vec<(PathBuf, String)>,
    papers: Vec<PaperInput>,
}

fn has(dir: &Path, file: &str) -> bool {
    dir.join(file).is_file()
}

fn sub_dirs(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    v.sort();
    Ok(v)
}

fn dir_name(dir: &Path) -> String {
    dir.canonicalize()
        .ok()
        .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| dir.display().to_string())
}

/// The adapter of a reproduction: that of its first run with results.
fn paper_adapter(dir: &Path) -> String {
    sub_dirs(&dir.join("runs"))
        .unwrap_or_default()
        .iter()
        .find(|d| has(d, JSON_FILE))
        .and_then(|d| ResultsFile::read(d).ok())
        .map(|f| adapter_of(&f))
        .unwrap_or_else(|| "unknown adapter".into())
}

impl Inputs {
    /// Registers a run (read later, by [`crate::regress::publish_runs::scan`]).
    fn add_run(&mut self, dir: &Path) -> anyhow::Result<()> {
        let mut name = slug(&dir_name(dir));
        let base = name.clone();
        let mut n = 1;
        while self.runs.iter().any(|(_, r)| *r == name) {
            n += 1;
            name = format!("{base}-{n}");
        }
        self.runs.push((dir.to_path_buf(), name));
        let reproduce = dir.join("reproduce");
        if reproduce.is_dir() {
            self.add_papers(&reproduce, &dir_name(dir))?;
        }
        Ok(())
    }

    fn add_paper(&mut self, dir: &Path, source: &str) -> anyhow::Result<()> {
        let path = dir.join(SUMMARY_FILE);
        let text = read_text(&path)?;
        let summary: PaperSummary = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a paper summary", path.display()))?;
        anyhow::ensure!(
            has(dir, "report.html"),
            "{}: a paper reproduced without its report.html",
            dir.display()
        );
        self.papers.push(PaperInput {
            dir: dir.to_path_buf(),
            adapter: paper_adapter(dir),
            summary,
            source: source.to_string(),
        });
        Ok(())
    }

    fn add_papers(&mut self, dir: &Path, source: &str) -> anyhow::Result<()> {
        for d in sub_dirs(dir)? {
            if has(&d, SUMMARY_FILE) {
                self.add_paper(&d, source)?;
            }
        }
        Ok(())
    }

    /// Sorts one argument into runs and papers; an argument holding neither is an error.
    fn add(&mut self, dir: &Path) -> anyhow::Result<()> {
        anyhow::ensure!(dir.is_dir(), "{}: no such directory", dir.display());
        if has(dir, JSON_FILE) {
            return self.add_run(dir);
        }
        if has(dir, SUMMARY_FILE) {
            let source = dir
                .parent()
                .map(dir_name)
                .unwrap_or_else(|| "reproduced".into());
            return self.add_paper(dir, &source);
        }
        let subs = sub_dirs(dir)?;
        let (papers, runs): (Vec<&PathBuf>, Vec<&PathBuf>) = (
            subs.iter().filter(|d| has(d, SUMMARY_FILE)).collect(),
            subs.iter().filter(|d| has(d, JSON_FILE)).collect(),
        );
        anyhow::ensure!(
            !papers.is_empty() || !runs.is_empty(),
            "{}: holds no {JSON_FILE} (a run) nor {SUMMARY_FILE} (a paper reproduced), nor do \
             its sub-directories",
            dir.display()
        );
        for d in runs {
            self.add_run(d)?;
        }
        if !papers.is_empty() {
            self.add_papers(dir, &dir_name(dir))?;
        }
        Ok(())
    }
}

/// Copies `from` into `to` (files and folders, recursively).
fn copy_tree(from: &Path, to: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(to).with_context(|| format!("cannot create {}", to.display()))?;
    for e in std::fs::read_dir(from).with_context(|| format!("cannot read {}", from.display()))? {
        let e = e?;
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if src.is_dir() {
            copy_tree(&src, &dst)?;
        } else {
            std::fs::copy(&src, &dst)
                .with_context(|| format!("cannot copy {} to {}", src.display(), dst.display()))?;
        }
    }
    Ok(())
}

/// What the front page says of one adapter.
#[derive(Serialize)]
struct AdapterLine {
    adapter: String,
    latest: RunLine,
    runs: usize,
    /// `history/NAME/history.html`, or empty with one run.
    history: String,
    /// Series with a step, of all series, in the history.
    series_with_steps: usize,
    series: usize,
    /// The newest steps of the history (at most [`FRONT_STEPS`]), linked to their charts.
    steps: Vec<SiteStep>,
    /// All the steps of the history.
    steps_total: usize,
}

/// How many of an adapter's newest steps the front page lists.
const FRONT_STEPS: usize = 12;

/// A step of a history as the front page lists it.
#[derive(Serialize)]
struct SiteStep {
    #[serde(flatten)]
    step: StepLine,
    /// Its chart: `history/NAME/history.html#ID`.
    link: String,
}

#[derive(Serialize, Clone)]
struct RunLine {
    name: String,
    link: String,
    adapter: String,
    started: String,
    commit: String,
    rows: usize,
    failed: usize,
}

#[derive(Serialize)]
struct PaperLine {
    paper: String,
    source: String,
    adapter: String,
    mode: String,
    /// The cells of its tables within their rules (or what an older summary says instead).
    cells: String,
    claims: String,
    commit: String,
    link: String,
}

#[derive(Serialize)]
struct ChartLine {
    file: String,
    title: String,
}

#[derive(Serialize)]
struct SitePage {
    adapters: Vec<AdapterLine>,
    papers: Vec<PaperLine>,
    runs: Vec<RunLine>,
    charts: Vec<ChartLine>,
    /// The charts' short labels with their full settings.
    key: Vec<crate::plot::style::KeyEntry>,
    /// How the across-adapters charts measure speed.
    charts_axis: String,
    /// Why there are no charts, or rows left out of them.
    charts_note: String,
}

fn run_line(run: &SiteRun) -> RunLine {
    let m = &run.meta;
    let commit = m.commit.clone().unwrap_or_else(|| "unknown".into());
    RunLine {
        name: run.name.clone(),
        link: format!("runs/{}/index.html", run.name),
        adapter: m.adapter.clone(),
        started: m.started.clone(),
        commit: format!(
            "{}{}",
            &commit[..commit.len().min(10)],
            if m.dirty == Some(true) {
                " (dirty)"
            } else {
                ""
            }
        ),
        rows: m.rows,
        failed: m.failed,
    }
}

/// A short name of a run's adapter for chart labels (`llvmpipe`, `H200`): its name up to the
/// driver in brackets, last word; made unique among `taken` (two CPUs' llvmpipe) by a number.
fn adapter_tag(file: &ResultsFile, taken: &[String]) -> String {
    let name = file
        .machine
        .adapter
        .as_ref()
        .map(|a| a.name.as_str())
        .unwrap_or("unknown");
    let name = name.split(" (").next().unwrap_or(name);
    let base = name
        .split_whitespace()
        .last()
        .unwrap_or("unknown")
        .to_string();
    let mut tag = base.clone();
    let mut n = 1;
    while taken.contains(&tag) {
        n += 1;
        tag = format!("{base}-{n}");
    }
    tag
}

/// A readable, file-safe folder name: lowercase letters and digits, runs of anything else as
/// one `-` (`llvmpipe (LLVM 15.0.6, 256 bits)` → `llvmpipe-llvm-15-0-6-256-bits`).
fn url_name(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') {
            out.push('-');
        }
    }
    let out = out.trim_matches('-').to_string();
    if out.is_empty() {
        "unnamed".into()
    } else {
        out
    }
}

/// The speed–error charts over the latest run of each adapter. With one adapter the speed is
/// tets/s; with several it is the calibration-normalised speed (the share of the row's
/// calibrated roofline reached, `100 / normalized_time` %), the one measure that compares
/// adapters of different kinds; rows without a calibration are left out, and counted.
fn cross_adapter_charts(site: &Path, latest: &[&SiteRun]) -> anyhow::Result<SitePage> {
    let several = latest.len() > 1;
    let mut rows = vec![];
    let mut left_out = 0;
    // How the charted rows' rooflines were priced: by their own rounds' control, or (results
    // without one) by their adapter's cached calibration.
    let (mut by_control, mut by_calibration) = (0, 0);
    let mut tags: Vec<String> = vec![];
    for run in latest {
        let file = ResultsFile::read(&run.dir)?;
        let short = adapter_tag(&file, &tags);
        tags.push(short.clone());
        for row in &file.rows {
            let mut row = row.clone();
            if several {
                row.settings = row.settings.clone().with("adapter", short.as_str());
                match row.normalized_time.filter(|n| *n > 0.0) {
                    Some(n) => {
                        row.tets_per_sec = Some(100.0 / n);
                        match row.priced_with {
                            Pricing::Control { .. } => by_control += 1,
                            _ => by_calibration += 1,
                        }
                    }
                    None => {
                        left_out += 1;
                        continue;
                    }
                }
            }
            rows.push(row);
        }
    }
    let axis = if several {
        SpeedAxis {
            desc: "share of the calibrated roofline reached, % (log scale)".into(),
            stem: "across_adapters".into(),
            title: "Speed vs error across adapters".into(),
        }
    } else {
        SpeedAxis {
            stem: "across_adapters".into(),
            ..SpeedAxis::default()
        }
    };
    let dir = site.join("charts");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let points = crate::plot::data::points(&rows);
    let mut charts = vec![];
    let mut key = vec![];
    if points.iter().any(|p| p.psnr_db.is_some()) {
        let book = crate::plot::book_of(&points);
        key = book.key_entries();
        crate::plot::draw::register_font();
        for f in crate::plot::speed_error::write_with(&dir, &points, &book, &axis)? {
            charts.push(ChartLine {
                file: format!("charts/{}.png", f.stem),
                title: f.title,
            });
        }
        std::fs::write(dir.join("key.csv"), book.key_csv()).context("writing charts/key.csv")?;
    }
    let mut note = String::new();
    if charts.is_empty() {
        note = "No chart: no run has an image error (runs without a reference).".into();
    }
    if left_out > 0 {
        note.push_str(&format!(
            " {left_out} row(s) without a calibration (no normalized_time) are left out."
        ));
    }
    Ok(SitePage {
        adapters: vec![],
        papers: vec![],
        runs: vec![],
        charts,
        key,
        charts_axis: if several {
            format!(
                "Each point is one variant on one adapter (the setting adapter=… names it; the \
                 key below gives every label's settings). Adapters differ, so speed is the share \
                 of the row's roofline it reached, 100 / normalized_time, where 100 % is the \
                 adapter's measured limit for the row's work. The scale: {by_control} row(s) \
                 priced by the control their run measured beside them (the machine of the same \
                 moment), {by_calibration} by their adapter's cached calibration (results \
                 without a control: the best that adapter ever measured, at another hour)."
            )
        } else {
            "One adapter: speed in tets per second.".into()
        },
        charts_note: note.trim().to_string(),
    })
}

/// Readies `site` when it is empty, absent or a site publish wrote (everything but its run
/// folders removed: [`crate::regress::publish_runs`] keeps or replaces each); refuses
/// otherwise.
fn prepare(site: &Path) -> anyhow::Result<()> {
    if site.exists() {
        let entries: Vec<PathBuf> = std::fs::read_dir(site)
            .with_context(|| format!("cannot read {}", site.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        anyhow::ensure!(
            entries.is_empty() || site.join(SITE_MARKER).is_file(),
            "{}: not empty and not a site tetbench publish wrote (no {SITE_MARKER}); give \
             another --out",
            site.display()
        );
        for p in entries {
            if p == site.join("runs") && p.is_dir() {
                continue;
            }
            if p.is_dir() {
                std::fs::remove_dir_all(&p)
            } else {
                std::fs::remove_file(&p)
            }
            .with_context(|| format!("cannot replace {}", p.display()))?;
        }
    }
    std::fs::create_dir_all(site.join("runs"))
        .with_context(|| format!("cannot create {}", site.display()))?;
    std::fs::write(
        site.join(SITE_MARKER),
        "written by tetbench publish; the next publish keeps the runs drawn from unchanged files \
         and replaces everything else\n",
    )
    .context("writing the site marker")
}

/// What a publish did, for its last line.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Published {
    pub runs: usize,
    /// Run pages drawn (the others were kept).
    pub drawn: usize,
    /// Pairs compared (the others' findings were kept).
    pub compared: usize,
    /// Run folders of an earlier publish that no run owns any more.
    pub removed: usize,
}

/// `tetbench publish`: writes the site and returns the path of its front page.
pub fn publish(args: &PublishArgs) -> anyhow::Result<(PathBuf, Published)> {
    anyhow::ensure!(args.threshold >= 1.0, "--threshold must be at least 1");
    let mut inputs = Inputs::default();
    for d in &args.dirs {
        inputs.add(d)?;
    }
    let site = &args.out;
    prepare(site)?;
    let runs = crate::regress::publish_runs::scan(site, &inputs.runs)?;
    let mut done = Published {
        runs: runs.len(),
        ..Default::default()
    };
    let adapters = by_adapter(&runs);
    let mut lines = vec![];
    let mut latest = vec![];
    let mut pages: Vec<(&SiteRun, PageKind, Option<PairRecord>)> = vec![];
    for adapter_runs in &adapters {
        let (line, pairs) = write_history(site, adapter_runs, args.threshold, &lines, &mut done)?;
        let last = adapter_runs[adapter_runs.len() - 1];
        latest.push(last);
        for (k, (run, pair)) in adapter_runs.iter().zip(pairs).enumerate() {
            let kind = if k + 1 == adapter_runs.len() {
                PageKind::Report
            } else {
                PageKind::Brief {
                    previous: k.checked_sub(1).map(|p| adapter_runs[p].name.clone()),
                    next: Some(adapter_runs[k + 1].name.clone()),
                    history: (!line.history.is_empty()).then(|| line.history.clone()),
                }
            };
            pages.push((run, kind, pair));
        }
        lines.push(line);
    }
    // Brief pages in parallel; full reports (charts through plotters) one at a time.
    let (reports, briefs): (Vec<_>, Vec<_>) = pages
        .into_iter()
        .partition(|(_, kind, _)| *kind == PageKind::Report);
    let drawn: Vec<bool> = briefs
        .into_par_iter()
        .map(|(run, kind, pair)| crate::regress::publish_runs::write_run(site, run, &kind, pair))
        .collect::<anyhow::Result<_>>()?;
    done.drawn = drawn.iter().filter(|d| **d).count();
    for (run, kind, pair) in reports {
        done.drawn += crate::regress::publish_runs::write_run(site, run, &kind, pair)? as usize;
    }
    let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
    done.removed = crate::regress::publish_runs::remove_stale(site, &names)?;
    let papers = inputs
        .papers
        .iter()
        .map(|p| write_paper(site, p))
        .collect::<anyhow::Result<Vec<_>>>()?;
    if site.join("papers").is_dir() {
        link_pages_to_front(site, &site.join("papers"))?;
    }
    let mut page = cross_adapter_charts(site, &latest)?;
    page.adapters = lines;
    page.papers = papers;
    page.runs = runs.iter().map(run_line).collect();
    let html = crate::report::html::render("site.html", &page)?;
    let index = site.join("index.html");
    write_file(&index, html)?;
    Ok((index, done))
}

/// The runs per adapter (adapters in order of first appearance), each adapter's by the date
/// they started (the order given for equal dates).
fn by_adapter(runs: &[SiteRun]) -> Vec<Vec<&SiteRun>> {
    let mut adapters: Vec<&str> = vec![];
    for r in runs {
        if !adapters.contains(&r.meta.adapter.as_str()) {
            adapters.push(&r.meta.adapter);
        }
    }
    adapters
        .into_iter()
        .map(|a| {
            let mut v: Vec<&SiteRun> = runs.iter().filter(|r| r.meta.adapter == a).collect();
            v.sort_by(|a, b| a.summary.run.date_utc.cmp(&b.summary.run.date_utc));
            v
        })
        .collect()
}

/// One adapter's line on the front page and, with two runs or more, its history in
/// `history/NAME/` (`tetbench history` over its runs, from their summaries and compare's
/// findings, kept or new). Returns the line and each run's findings against the run before.
fn write_history(
    site: &Path,
    runs: &[&SiteRun],
    threshold: f64,
    earlier: &[AdapterLine],
    done: &mut Published,
) -> anyhow::Result<(AdapterLine, Vec<Option<PairRecord>>)> {
    let last = runs[runs.len() - 1];
    let adapter = last.meta.adapter.as_str();
    let mut line = AdapterLine {
        adapter: adapter.to_string(),
        latest: run_line(last),
        runs: runs.len(),
        history: String::new(),
        series_with_steps: 0,
        series: 0,
        steps: vec![],
        steps_total: 0,
    };
    if runs.len() < 2 {
        return Ok((line, vec![None]));
    }
    let base = url_name(last.meta.adapter_name.as_deref().unwrap_or(adapter));
    let (mut name, mut n) = (base.clone(), 1);
    while earlier
        .iter()
        .any(|a| a.history == format!("history/{name}/history.html"))
    {
        n += 1;
        name = format!("{base}-{n}");
    }
    let out = site.join("history").join(&name);
    let pairs =
        crate::regress::publish_runs::pair_findings(runs, &out.join("pairs"), threshold, 0.05)
            .with_context(|| format!("the history of {adapter}"))?;
    done.compared += runs
        .iter()
        .zip(&pairs)
        .filter(|(r, p)| p.is_some() && r.kept.as_ref().and_then(|k| k.pair.as_ref()) != p.as_ref())
        .count();
    let findings: Vec<Option<crate::regress::history::PairFindings>> = pairs
        .iter()
        .map(|p| p.as_ref().map(|p| p.findings.clone()))
        .collect();
    let summaries = runs.iter().map(|r| r.summary.clone()).collect();
    let h = crate::regress::history::build(summaries, &findings, threshold);
    crate::regress::history_page::write(&out, &h)
        .with_context(|| format!("the history of {adapter}"))?;
    link_pages_to_front(site, &out)?;
    line.history = format!("history/{name}/history.html");
    line.series = h.series.len();
    line.series_with_steps = h
        .series
        .iter()
        .filter(|s| s.points.iter().any(|p| p.step.is_some()))
        .count();
    let steps = crate::regress::history_page::steps(&h);
    line.steps_total = steps.len();
    line.steps = steps
        .into_iter()
        .take(FRONT_STEPS)
        .map(|step| SiteStep {
            link: format!("{}#{}", line.history, step.chart),
            step,
        })
        .collect();
    Ok((line, pairs))
}

/// A reproduced paper's report, charts and summary in `papers/SOURCE/PAPER/`.
fn write_paper(site: &Path, p: &PaperInput) -> anyhow::Result<PaperLine> {
    let rel = format!("papers/{}/{}", slug(&p.source), slug(&p.summary.paper));
    let out = site.join(&rel);
    anyhow::ensure!(
        !out.exists(),
        "{}: paper {} of {} given twice",
        p.dir.display(),
        p.summary.paper,
        p.source
    );
    for f in ["report.html", "report.md", SUMMARY_FILE] {
        if has(&p.dir, f) {
            copy_file(&p.dir.join(f), &out.join(f))?;
        }
    }
    if p.dir.join("charts").is_dir() {
        copy_tree(&p.dir.join("charts"), &out.join("charts"))?;
    }
    Ok(PaperLine {
        paper: p.summary.paper.clone(),
        source: p.source.clone(),
        adapter: p.adapter.clone(),
        mode: p.summary.mode.clone(),
        cells: p.summary.cells_text(),
        claims: p.summary.claims_text(),
        // The summary's sentence is Markdown (`commit` in backticks): shown as text.
        commit: p.summary.source.replace('`', ""),
        link: format!("{rel}/report.html"),
    })
}

/// `tetbench publish …` from the command line.
pub fn run_command(args: &PublishArgs) -> anyhow::Result<()> {
    let (index, done) = publish(args)?;
    println!(
        "wrote the site {} (open {}): {} runs, {} page(s) drawn, {} kept; {} pair(s) compared; \
         {} old run folder(s) removed",
        args.out.display(),
        index.display(),
        done.runs,
        done.drawn,
        done.runs - done.drawn,
        done.compared,
        done.removed
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_tags() {
        assert_eq!(
            url_name("llvmpipe (LLVM 15.0.6, 256 bits)"),
            "llvmpipe-llvm-15-0-6-256-bits"
        );
        assert_eq!(url_name("<b>"), "b");
        assert_eq!(url_name("///"), "unnamed");
        use crate::regress::publish_runs::is_inside;
        assert!(is_inside("images/a/b.png"));
        assert!(!is_inside("../secret.png") && !is_inside("/etc/passwd") && !is_inside(""));
    }

    /// A directory holding neither a run nor a paper is refused by name; a non-empty directory
    /// that is not a site is never replaced.
    #[test]
    fn bad_inputs_and_outputs_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let empty = dir.path().join("empty");
        std::fs::create_dir_all(empty.join("sub")).unwrap();
        let e = Inputs::default().add(&empty).unwrap_err().to_string();
        assert!(
            e.contains("empty") && e.contains("holds no results.json"),
            "{e}"
        );
        let e = Inputs::default()
            .add(&dir.path().join("absent"))
            .unwrap_err();
        assert!(e.to_string().contains("no such directory"));
        std::fs::write(empty.join("keep.txt"), "mine").unwrap();
        let e = prepare(&empty).unwrap_err().to_string();
        assert!(e.contains("not a site"), "{e}");
        assert!(empty.join("keep.txt").is_file());
        let site = dir.path().join("site");
        prepare(&site).unwrap();
        std::fs::write(site.join("old.html"), "old").unwrap();
        std::fs::create_dir_all(site.join("runs/a")).unwrap();
        prepare(&site).unwrap();
        assert!(!site.join("old.html").exists() && site.join(SITE_MARKER).is_file());
        // The run folders stay, for the runs to keep or replace.
        assert!(site.join("runs/a").is_dir());
    }
}
