//! `tetbench publish DIR… --out SITE`: one static site over baselines, runs and reproduced
//! papers (issue 44), as asv's `publish` makes one over its results — our own, smaller version.
//!
//! - `index.html`: per adapter its latest run (by the date it started) and how many runs it
//!   has, the papers reproduced with their verdicts, every run, and the speed–error charts
//!   across adapters (the latest run of each);
//! - `runs/NAME/`: each run's report ([`crate::report::write`], its results and the images it
//!   kept — a baseline keeps none, and its page says so instead of linking them);
//! - `history/ADAPTER/`: per adapter with two runs or more, `tetbench history` over them: per
//!   group the time across commits and the steps found;
//! - `papers/SOURCE/PAPER/`: each reproduced paper's report as `tetbench reproduce` wrote it.
//!
//! Every page is written through the escaping templates ([`crate::report::html`]) and links
//! only files of the site by relative paths: it works from the file system and from any static
//! host, with no server and no network. `scripts/check-site.sh` walks it in headless Chromium.

use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::Serialize;

use crate::papers::reproduce::{PaperSummary, SUMMARY_FILE};
use crate::plot::speed_error::SpeedAxis;
use crate::regress::compare::adapter_of;
use crate::results::names::slug;
use crate::results::{ResultsFile, JSON_FILE};

/// The file marking a directory as a site `publish` wrote (and may therefore replace).
pub const SITE_MARKER: &str = ".tetbench-site";

#[derive(Debug, Clone, clap::Args)]
pub struct PublishArgs {
    /// Result directories: a run (holding results.json), a directory of runs (e.g.
    /// reports/baselines), a paper reproduced (holding summary.json) or a directory of them
    /// (e.g. reports/reproduced). A run's `reproduce/` directory joins as its papers.
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Where the site goes (replaced when it is a site publish wrote; refused when it is
    /// another non-empty directory).
    #[arg(long, value_name = "SITE", default_value = "site")]
    pub out: PathBuf,
    /// Factor a median must move by to count as a change in the histories.
    #[arg(long, default_value_t = 1.10)]
    pub threshold: f64,
}

/// One run found in the inputs.
struct RunInput {
    dir: PathBuf,
    file: ResultsFile,
    adapter: String,
    /// Its folder in the site (`runs/NAME`).
    name: String,
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
    runs: Vec<RunInput>,
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
    fn add_run(&mut self, dir: &Path) -> anyhow::Result<()> {
        let file = ResultsFile::read(dir)?;
        let mut name = slug(&dir_name(dir));
        let base = name.clone();
        let mut n = 1;
        while self.runs.iter().any(|r| r.name == name) {
            n += 1;
            name = format!("{base}-{n}");
        }
        self.runs.push(RunInput {
            dir: dir.to_path_buf(),
            adapter: adapter_of(&file),
            file,
            name,
        });
        let reproduce = dir.join("reproduce");
        if reproduce.is_dir() {
            self.add_papers(&reproduce, &dir_name(dir))?;
        }
        Ok(())
    }

    fn add_paper(&mut self, dir: &Path, source: &str) -> anyhow::Result<()> {
        let path = dir.join(SUMMARY_FILE);
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("cannot read {}", path.display()))?;
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

fn copy_file(from: &Path, to: &Path) -> anyhow::Result<()> {
    if let Some(parent) = to.parent() {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create {}", parent.display()))?;
    }
    std::fs::copy(from, to)
        .with_context(|| format!("cannot copy {} to {}", from.display(), to.display()))?;
    Ok(())
}

/// Whether a path a row names stays inside its run's directory (no `..`, not absolute).
fn is_inside(path: &str) -> bool {
    let p = Path::new(path);
    !path.is_empty()
        && p.components()
            .all(|c| matches!(c, std::path::Component::Normal(_)))
}

/// The run's report in `site/runs/NAME/`: its results files, the images it kept, and the
/// report drawn from them.
fn write_run(site: &Path, run: &RunInput) -> anyhow::Result<()> {
    let out = site.join("runs").join(&run.name);
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    for f in [JSON_FILE, "results.csv", "samples.csv", "calibration.json"] {
        if has(&run.dir, f) {
            copy_file(&run.dir.join(f), &out.join(f))?;
        }
    }
    for row in &run.file.rows {
        for image in [&row.image, &row.heatmap, &row.reference_image] {
            let src = run.dir.join(image);
            if is_inside(image) && src.is_file() && !out.join(image).exists() {
                copy_file(&src, &out.join(image))?;
            }
        }
    }
    crate::report::write(&out, &run.file)
        .with_context(|| format!("writing the report of {}", run.dir.display()))
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
    exact_tables: String,
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

fn run_line(run: &RunInput) -> RunLine {
    let m = &run.file.machine;
    let commit = m.git_commit.clone().unwrap_or_else(|| "unknown".into());
    RunLine {
        name: run.name.clone(),
        link: format!("runs/{}/index.html", run.name),
        adapter: run.adapter.clone(),
        started: m.date_utc.clone(),
        commit: format!(
            "{}{}",
            &commit[..commit.len().min(10)],
            if m.git_dirty == Some(true) {
                " (dirty)"
            } else {
                ""
            }
        ),
        rows: run.file.rows.len(),
        failed: run.file.rows.iter().filter(|r| !r.ok()).count(),
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
fn cross_adapter_charts(site: &Path, latest: &[&RunInput]) -> anyhow::Result<SitePage> {
    let several = latest.len() > 1;
    let mut rows = vec![];
    let mut left_out = 0;
    let mut tags: Vec<String> = vec![];
    for run in latest {
        let short = adapter_tag(&run.file, &tags);
        tags.push(short.clone());
        for row in &run.file.rows {
            let mut row = row.clone();
            if several {
                row.settings = row.settings.clone().with("adapter", short.as_str());
                match row.normalized_time.filter(|n| *n > 0.0) {
                    Some(n) => row.tets_per_sec = Some(100.0 / n),
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
            "Each point is one variant on one adapter (the setting adapter=… names it; the key \
             below gives every label's settings). Adapters differ, so speed is normalised by \
             each adapter's calibration: the share of the calibrated roofline (tetbench \
             calibrate) the row reached, 100 / normalized_time, where 100 % is the adapter's \
             measured limit for the row's work."
                .into()
        } else {
            "One adapter: speed in tets per second.".into()
        },
        charts_note: note.trim().to_string(),
    })
}

/// Replaces `site` when it is empty, absent or a site publish wrote; refuses otherwise.
fn prepare(site: &Path) -> anyhow::Result<()> {
    if site.exists() {
        let empty = std::fs::read_dir(site)
            .with_context(|| format!("cannot read {}", site.display()))?
            .next()
            .is_none();
        anyhow::ensure!(
            empty || site.join(SITE_MARKER).is_file(),
            "{}: not empty and not a site tetbench publish wrote (no {SITE_MARKER}); give \
             another --out",
            site.display()
        );
        std::fs::remove_dir_all(site)
            .with_context(|| format!("cannot replace {}", site.display()))?;
    }
    std::fs::create_dir_all(site).with_context(|| format!("cannot create {}", site.display()))?;
    std::fs::write(
        site.join(SITE_MARKER),
        "written by tetbench publish; the whole directory is replaced by the next publish\n",
    )
    .context("writing the site marker")
}

/// `tetbench publish`: writes the site and returns the path of its front page.
pub fn publish(args: &PublishArgs) -> anyhow::Result<PathBuf> {
    anyhow::ensure!(args.threshold >= 1.0, "--threshold must be at least 1");
    let mut inputs = Inputs::default();
    for d in &args.dirs {
        inputs.add(d)?;
    }
    let site = &args.out;
    prepare(site)?;
    for run in &inputs.runs {
        write_run(site, run)?;
    }
    let (adapters, latest) = write_histories(site, &inputs.runs, args.threshold)?;
    let papers = inputs
        .papers
        .iter()
        .map(|p| write_paper(site, p))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut page = cross_adapter_charts(site, &latest)?;
    page.adapters = adapters;
    page.papers = papers;
    page.runs = inputs.runs.iter().map(run_line).collect();
    let html = crate::report::html::render("site.html", &page)?;
    let index = site.join("index.html");
    std::fs::write(&index, html).with_context(|| format!("cannot write {}", index.display()))?;
    link_pages_to_front(site, site)?;
    Ok(index)
}

/// The line every page below the front page gets after its `<body>`: a link back to
/// `index.html`, `depth` folders up. Made of constants only (no data set or file name).
fn front_link(depth: usize) -> String {
    format!(
        "<nav class=site><a href=\"{}index.html\">\u{2190} all results</a></nav>",
        "../".repeat(depth)
    )
}

/// Gives every page under `dir` (runs, histories, papers; not the front page itself) a link
/// back to the site's front page, so that a reader who arrived from a search or a shared link
/// can reach the rest. The pages' own templates serve stand-alone reports too, where no front
/// page exists, so the link is added here rather than in them.
fn link_pages_to_front(site: &Path, dir: &Path) -> anyhow::Result<()> {
    for e in std::fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))? {
        let path = e?.path();
        if path.is_dir() {
            link_pages_to_front(site, &path)?;
            continue;
        }
        let rel = path
            .strip_prefix(site)
            .expect("walked from the site's root");
        if path.extension().is_none_or(|x| x != "html") || rel == Path::new("index.html") {
            continue;
        }
        let html = std::fs::read_to_string(&path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let Some(at) = html.find("<body>").map(|i| i + "<body>".len()) else {
            continue;
        };
        let depth = rel.components().count() - 1;
        let linked = format!("{}\n{}{}", &html[..at], front_link(depth), &html[at..]);
        std::fs::write(&path, linked)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

/// Per adapter (in order of first appearance) its runs by the date they started: the front
/// page's line and, with two runs or more, `tetbench history` over them in `history/NAME/`.
/// Returns the lines and the latest run of each adapter.
fn write_histories<'a>(
    site: &Path,
    all: &'a [RunInput],
    threshold: f64,
) -> anyhow::Result<(Vec<AdapterLine>, Vec<&'a RunInput>)> {
    let mut adapters: Vec<&str> = vec![];
    for r in all {
        if !adapters.contains(&r.adapter.as_str()) {
            adapters.push(&r.adapter);
        }
    }
    let mut lines: Vec<AdapterLine> = vec![];
    let mut latest = vec![];
    for adapter in adapters {
        let mut runs: Vec<&RunInput> = all.iter().filter(|r| r.adapter == adapter).collect();
        runs.sort_by(|a, b| a.file.machine.date_utc.cmp(&b.file.machine.date_utc));
        let last = runs[runs.len() - 1];
        latest.push(last);
        let (mut history, mut with_steps, mut series) = (String::new(), 0, 0);
        if runs.len() > 1 {
            let base = url_name(
                last.file
                    .machine
                    .adapter
                    .as_ref()
                    .map_or(adapter, |a| a.name.as_str()),
            );
            let (mut name, mut n) = (base.clone(), 1);
            while lines
                .iter()
                .any(|a| a.history == format!("history/{name}/history.html"))
            {
                n += 1;
                name = format!("{base}-{n}");
            }
            let dirs: Vec<PathBuf> = runs.iter().map(|r| r.dir.clone()).collect();
            let out = site.join("history").join(&name);
            let (h, _) = crate::regress::history::write_files(&dirs, &out, threshold, 0.05)
                .with_context(|| format!("the history of {adapter}"))?;
            series = h.series.len();
            with_steps = h
                .series
                .iter()
                .filter(|s| s.points.iter().any(|p| p.step.is_some()))
                .count();
            history = format!("history/{name}/history.html");
        }
        lines.push(AdapterLine {
            adapter: adapter.to_string(),
            latest: run_line(last),
            runs: runs.len(),
            history,
            series_with_steps: with_steps,
            series,
        });
    }
    Ok((lines, latest))
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
        exact_tables: p.summary.exact_tables.clone(),
        claims: p.summary.claims.clone(),
        // The summary's sentence is Markdown (`commit` in backticks): shown as text.
        commit: p.summary.source.replace('`', ""),
        link: format!("{rel}/report.html"),
    })
}

/// `tetbench publish …` from the command line.
pub fn run_command(args: &PublishArgs) -> anyhow::Result<()> {
    let index = publish(args)?;
    println!(
        "wrote the site {} (open {})",
        args.out.display(),
        index.display()
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
        prepare(&site).unwrap();
        assert!(!site.join("old.html").exists() && site.join(SITE_MARKER).is_file());
    }
}
