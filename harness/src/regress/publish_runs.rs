//! The runs of a site `tetbench publish` writes, kept from one publish to the next.
//!
//! Each run's folder `runs/NAME/` holds its page and, beside it, [`RECORD`]: the hash of the
//! run's files and of the tetbench build that drew it, what the page was drawn as, the run's
//! summary for the history ([`crate::regress::history::RunSummary`]) and compare's findings
//! against the run before it. A publish reads every run's files (to hash them) but parses,
//! summarises, compares and redraws only the runs whose record no longer matches: adding one
//! run to a site of a thousand redraws the new run and the one before it (whose page gains a
//! "next" link) and compares one pair.
//!
//! Pages come in two kinds. The latest run of each adapter gets the full report
//! ([`crate::report::write`]: charts, tables, images, data files). Every earlier run gets a
//! brief page: its machine and commit, one line per group, links to the runs before and after
//! and to the history, and its results as `results.json.gz` and `results.csv.gz` — from which
//! `tetbench report` draws the full report again. A site of a year of nightly runs thus grows
//! by what a run measured, not by its charts.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::Context;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::regress::history::{PairFindings, RunSummary};
use crate::results::{read_bytes, read_text, write_file, ResultsFile, JSON_FILE};

/// The record beside each run's page.
pub const RECORD: &str = ".tetbench-run.json";

/// The files of a run the input hash covers (those that exist), besides its `images/`.
const RUN_FILES: [&str; 4] = [JSON_FILE, "results.csv", "samples.csv", "calibration.json"];

/// What the front page and the page kinds need of a run, besides its summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunMeta {
    pub adapter: String,
    /// The adapter's own name (the history's folder is named after it).
    pub adapter_name: Option<String>,
    pub started: String,
    pub commit: Option<String>,
    pub dirty: Option<bool>,
    pub rows: usize,
    pub failed: usize,
}

/// compare's findings on the run before this one and this one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairRecord {
    /// The input hash of the run before.
    pub previous: String,
    pub threshold: f64,
    pub alpha: f64,
    pub findings: PairFindings,
}

/// [`RECORD`]: what a run's page was drawn from.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Record {
    pub build: String,
    pub input: String,
    /// The hash of what the page shows besides the run: its kind and its neighbours' links.
    pub page: String,
    pub meta: RunMeta,
    pub summary: RunSummary,
    pub pair: Option<PairRecord>,
}

/// One run of the inputs.
pub struct SiteRun {
    pub dir: PathBuf,
    /// Its folder in the site (`runs/NAME`).
    pub name: String,
    /// The hash of its files and of this build.
    pub input: String,
    pub meta: RunMeta,
    pub summary: RunSummary,
    /// The record found beside its page, when it was drawn from the same input.
    pub kept: Option<Record>,
}

/// What identifies the tetbench build: its version and commit, and the executable's size and
/// time (a rebuild of a dirty tree changes the code but not the commit).
pub fn build_id() -> &'static str {
    static ID: OnceLock<String> = OnceLock::new();
    ID.get_or_init(|| {
        let exe = std::env::current_exe()
            .ok()
            .and_then(|p| std::fs::metadata(p).ok())
            .map(|m| format!("{} {:?}", m.len(), m.modified().ok()))
            .unwrap_or_default();
        format!(
            "{} {} {} {exe}",
            env!("CARGO_PKG_VERSION"),
            env!("TETBENCH_GIT_COMMIT"),
            env!("TETBENCH_GIT_DIRTY")
        )
    })
}

/// The hash of a run's files (see [`RUN_FILES`]; images by path, size and time) and the build.
fn input_hash(dir: &Path) -> anyhow::Result<String> {
    let mut h = blake3::Hasher::new();
    h.update(build_id().as_bytes());
    for f in RUN_FILES {
        let path = dir.join(f);
        if path.is_file() {
            let bytes = read_bytes(&path)?;
            h.update(f.as_bytes());
            h.update(&(bytes.len() as u64).to_le_bytes());
            h.update(&bytes);
        }
    }
    let mut images = vec![];
    list_files(&dir.join("images"), &mut images);
    images.sort();
    for p in images {
        let m = std::fs::metadata(&p).with_context(|| format!("cannot read {}", p.display()))?;
        h.update(p.to_string_lossy().as_bytes());
        h.update(format!(" {} {:?}\n", m.len(), m.modified().ok()).as_bytes());
    }
    Ok(h.finalize().to_hex().to_string())
}

fn list_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            list_files(&p, out);
        } else {
            out.push(p);
        }
    }
}

fn read_record(page_dir: &Path) -> Option<Record> {
    let text = std::fs::read_to_string(page_dir.join(RECORD)).ok()?;
    serde_json::from_str(&text).ok()
}

fn meta_of(file: &ResultsFile) -> RunMeta {
    let m = &file.machine;
    RunMeta {
        adapter: crate::regress::compare::adapter_of(file),
        adapter_name: m.adapter.as_ref().map(|a| a.name.clone()),
        started: m.date_utc.clone(),
        commit: m.git_commit.clone(),
        dirty: m.git_dirty,
        rows: file.rows.len(),
        failed: file.rows.iter().filter(|r| !r.ok()).count(),
    }
}

/// Reads the runs `(dir, name)` for the site `site`: each one's hash, and its summary from its
/// record when that was drawn from the same input, else from its results (in parallel; the
/// rows are dropped once summarised).
pub fn scan(site: &Path, runs: &[(PathBuf, String)]) -> anyhow::Result<Vec<SiteRun>> {
    runs.par_iter()
        .map(|(dir, name)| {
            let input = input_hash(dir)?;
            let kept = read_record(&site.join("runs").join(name))
                .filter(|r| r.input == input && r.build == build_id());
            let (meta, mut summary) = match &kept {
                Some(r) => (r.meta.clone(), r.summary.clone()),
                None => {
                    let file = ResultsFile::read(dir)?;
                    (
                        meta_of(&file),
                        crate::regress::history::summarise(dir, &file),
                    )
                }
            };
            // The same files may be published from another place.
            summary.run.dir = dir.display().to_string();
            Ok(SiteRun {
                dir: dir.clone(),
                name: name.clone(),
                input,
                meta,
                summary,
                kept,
            })
        })
        .collect()
}

/// compare's findings for each adjacent pair of `runs` (one adapter, in date order): kept from
/// the newer run's record when it was made against the same run before with the same options,
/// else computed (in parallel). `pairs[0]` is `None`.
pub fn pair_findings(
    runs: &[&SiteRun],
    scratch: &Path,
    threshold: f64,
    alpha: f64,
) -> anyhow::Result<Vec<Option<PairRecord>>> {
    let found: Vec<Option<PairRecord>> = (0..runs.len())
        .into_par_iter()
        .map(|k| {
            if k == 0 {
                return Ok(None);
            }
            let previous = &runs[k - 1].input;
            let kept = runs[k]
                .kept
                .as_ref()
                .and_then(|r| r.pair.clone())
                .filter(|p| {
                    &p.previous == previous && p.threshold == threshold && p.alpha == alpha
                });
            if let Some(p) = kept {
                return Ok(Some(p));
            }
            let findings = crate::regress::history::pair_findings(
                &runs[k - 1].dir,
                &runs[k].dir,
                &scratch.join(format!("{}-{}", k - 1, k)),
                threshold,
                alpha,
            )?;
            Ok(Some(PairRecord {
                previous: previous.clone(),
                threshold,
                alpha,
                findings,
            }))
        })
        .collect::<anyhow::Result<_>>()?;
    Ok(found)
}

/// How a run's page is drawn.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum PageKind {
    /// The full report (the latest run of its adapter).
    Report,
    /// The brief page, with its neighbours' folders and the history's path from the site
    /// (nothing that changes when a later run arrives, but for the run just before it).
    Brief {
        previous: Option<String>,
        next: Option<String>,
        history: Option<String>,
    },
}

impl PageKind {
    fn hash(&self, input: &str) -> String {
        blake3::hash(format!("{input} {self:?}").as_bytes())
            .to_hex()
            .to_string()
    }
}

/// Draws the page of `run` as `kind` unless its record says it was drawn so from the same
/// input; then writes its record. Returns whether the page was drawn.
pub fn write_run(
    site: &Path,
    run: &SiteRun,
    kind: &PageKind,
    pair: Option<PairRecord>,
) -> anyhow::Result<bool> {
    let out = site.join("runs").join(&run.name);
    let page = kind.hash(&run.input);
    let unchanged = run
        .kept
        .as_ref()
        .is_some_and(|r| r.page == page && out.join("index.html").is_file());
    if !unchanged {
        if out.exists() {
            std::fs::remove_dir_all(&out)
                .with_context(|| format!("cannot replace {}", out.display()))?;
        }
        std::fs::create_dir_all(&out)
            .with_context(|| format!("cannot create {}", out.display()))?;
        let file = ResultsFile::read(&run.dir)?;
        match kind {
            PageKind::Report => write_report(&out, run, &file)?,
            PageKind::Brief { .. } => write_brief(&out, run, &file, kind)?,
        }
        link_pages_to_front(site, &out)?;
    }
    let record = Record {
        build: build_id().to_string(),
        input: run.input.clone(),
        page,
        meta: run.meta.clone(),
        summary: run.summary.clone(),
        pair,
    };
    let path = out.join(RECORD);
    write_file(&path, serde_json::to_string(&record)?)?;
    Ok(!unchanged)
}

pub fn copy_file(from: &Path, to: &Path) -> anyhow::Result<()> {
    if let Some(parent) = to.parent() {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create {}", parent.display()))?;
    }
    std::fs::copy(from, to)
        .with_context(|| format!("cannot copy {} to {}", from.display(), to.display()))?;
    Ok(())
}

/// Whether a path a row names stays inside its run's directory (no `..`, not absolute).
pub fn is_inside(path: &str) -> bool {
    let p = Path::new(path);
    !path.is_empty()
        && p.components()
            .all(|c| matches!(c, std::path::Component::Normal(_)))
}

/// The full report in `out`: the run's results files, the images it kept, and the report
/// drawn from them.
fn write_report(out: &Path, run: &SiteRun, file: &ResultsFile) -> anyhow::Result<()> {
    for f in RUN_FILES {
        if run.dir.join(f).is_file() {
            copy_file(&run.dir.join(f), &out.join(f))?;
        }
    }
    for row in &file.rows {
        for image in [&row.image, &row.heatmap, &row.reference_image] {
            let src = run.dir.join(image);
            if is_inside(image) && src.is_file() && !out.join(image).exists() {
                copy_file(&src, &out.join(image))?;
            }
        }
    }
    crate::report::write(out, file)
        .with_context(|| format!("writing the report of {}", run.dir.display()))
}

fn gzip(from: &[u8], to: &Path) -> anyhow::Result<()> {
    let f = std::fs::File::create(to).with_context(|| format!("cannot create {}", to.display()))?;
    let mut z = flate2::write::GzEncoder::new(f, flate2::Compression::default());
    z.write_all(from)
        .and_then(|_| z.finish().map(|_| ()))
        .with_context(|| format!("cannot write {}", to.display()))
}

/// One group of a brief page.
#[derive(Serialize)]
struct BriefGroup {
    algorithm: String,
    settings: String,
    dataset: String,
    size: String,
    rows: usize,
    failed: usize,
    total_ms: String,
    range_ms: String,
    psnr_db: String,
    gpu_mib: String,
}

/// The brief page in `out`, with the results compressed beside it.
fn write_brief(
    out: &Path,
    run: &SiteRun,
    file: &ResultsFile,
    kind: &PageKind,
) -> anyhow::Result<()> {
    let PageKind::Brief {
        previous,
        next,
        history,
    } = kind
    else {
        unreachable!("write_brief draws brief pages");
    };
    let json = read_bytes(&run.dir.join(JSON_FILE))?;
    gzip(&json, &out.join("results.json.gz"))?;
    crate::results::write_csv(out, &file.rows)?;
    let csv_path = out.join(crate::results::CSV_FILE);
    let csv = read_bytes(&csv_path)?;
    gzip(&csv, &out.join("results.csv.gz"))?;
    std::fs::remove_file(&csv_path)
        .with_context(|| format!("cannot remove {}", csv_path.display()))?;
    let fmt = |v: Option<f64>, d: usize| v.map_or("–".to_string(), |v| format!("{v:.d$}"));
    let groups: Vec<BriefGroup> = crate::results::aggregate::aggregate(&file.rows)
        .into_iter()
        .map(|a| BriefGroup {
            size: format!("{}×{}", a.width, a.height),
            rows: a.rows,
            failed: a.failed,
            total_ms: fmt(a.total_ms.map(|s| s.median), 2),
            range_ms: a
                .total_ms
                .map_or("–".into(), |s| format!("{:.2}–{:.2}", s.min, s.max)),
            psnr_db: fmt(a.psnr_db.map(|s| s.median), 1),
            gpu_mib: fmt(a.gpu_bytes.map(|b| b as f64 / (1 << 20) as f64), 2),
            settings: a.settings.to_string(),
            algorithm: a.algorithm,
            dataset: a.dataset,
        })
        .collect();
    #[derive(Serialize)]
    struct Brief<'a> {
        name: &'a str,
        meta: &'a RunMeta,
        previous: &'a Option<String>,
        next: &'a Option<String>,
        history: Option<String>,
        groups: Vec<BriefGroup>,
        errors: &'a [String],
    }
    let html = crate::report::html::render(
        "run_brief.html",
        Brief {
            name: &run.name,
            meta: &run.meta,
            previous,
            next,
            history: history.as_ref().map(|h| format!("../../{h}")),
            groups,
            errors: &file.errors,
        },
    )?;
    let path = out.join("index.html");
    write_file(&path, html)
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
/// page exists, so the link is added here rather than in them. Called once on each folder
/// written anew (a kept run's page has its link already).
pub fn link_pages_to_front(site: &Path, dir: &Path) -> anyhow::Result<()> {
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
        let html = read_text(&path)?;
        let Some(at) = html.find("<body>").map(|i| i + "<body>".len()) else {
            continue;
        };
        let depth = rel.components().count() - 1;
        let linked = format!("{}\n{}{}", &html[..at], front_link(depth), &html[at..]);
        write_file(&path, linked)?;
    }
    Ok(())
}

/// Removes the folders of `runs/` that no run of this publish owns.
pub fn remove_stale(site: &Path, names: &[&str]) -> anyhow::Result<usize> {
    let dir = site.join("runs");
    let mut removed = 0;
    for e in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
        let keep = e.file_name().to_str().is_some_and(|n| names.contains(&n));
        if !keep {
            let p = e.path();
            if p.is_dir() {
                std::fs::remove_dir_all(&p)
            } else {
                std::fs::remove_file(&p)
            }
            .with_context(|| format!("cannot remove {}", p.display()))?;
            removed += 1;
        }
    }
    Ok(removed)
}
