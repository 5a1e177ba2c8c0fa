//! `tetbench reproduce havs|gator|fragment-pt|raycast|splat|all [--quick] [--out DIR]`: runs
//! every measurement a paper's tables need (its data sets, viewpoints, settings and
//! resolution, from the transcription in `reports/papers/`), then writes `OUT/<paper>/report.md`
//! and `report.html`: each table in the paper's shape with paper | ours | ours/paper, the
//! conditions of both, bar charts, and the paper's claims (`reports/papers/claims.csv`), each
//! with a verdict of [`crate::papers::verdict`] and the numbers and variants it rests on.
//!
//! Each paper is one folder implementing [`PaperModule`]: its CPU analyses and run plan
//! (measured here, on the run loop [`crate::run`]) and its table writer (`tables`, a pure
//! function of what was measured, so tests can check it without a GPU). Algorithms a plan
//! names that this build lacks (derived from [`crate::algorithms::names`]) leave their cells
//! empty with the reason.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;

use super::cells::CellCounts;
use super::claims::ClaimResult;
use super::claims_report;
pub use super::session::SourceState;
use super::session::{
    not_built_reason, Figure, Measured, Report, Session, FULL_FRAMES, FULL_WARMUP, QUICK_FRAMES,
    QUICK_RESOLUTION_DIVISOR, QUICK_VIEWPOINTS, QUICK_WARMUP,
};
use super::{table, Paper, PaperModule, PAPERS};
use crate::report::progress::Progress;
use crate::results::machine::MachineInfo;

#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// `havs`, `gator`, `fragment-pt`, `raycast`, `splat` or `all`.
    pub paper: String,
    /// Fewer viewpoints and frames, no reference images, only the variants the paper's tables
    /// and claims compare: minutes on a 2-core machine without a GPU. The report says what
    /// was shrunk.
    #[arg(long)]
    pub quick: bool,
    /// Output directory; each paper writes OUT/<paper>/ (replaced).
    #[arg(long, value_name = "DIR", default_value = "out/repro")]
    pub out: PathBuf,
    /// Use another data set in place of one of the plan's, e.g. `fighter=shell:20k` (for
    /// trying the pipeline quickly; the report lists every substitution).
    #[arg(long, value_delimiter = ',', value_name = "NAME=SPEC")]
    pub substitute: Vec<String>,
    /// Override the viewport size of every run (the report says so).
    #[arg(long, value_name = "PIXELS")]
    pub resolution: Option<u32>,
    /// Reference image cache (as `tetbench run --cache-dir`).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// External renderers measured in every run beside the paper's algorithms (as
    /// `tetbench run --external`).
    #[command(flatten)]
    pub external: crate::run::matrix::ExternalArgs,
    /// Rounds per row: each variant's frames are taken this many times, seconds apart, so a
    /// timing claim compares samples from separate moments (default: 5 in the full mode, the
    /// rounds a GPU timing claim needs; 1 in the quick mode). `scripts/gpu.sh` runs the quick
    /// mode with 5.
    #[arg(long, value_name = "N")]
    pub rounds: Option<u32>,
    /// Run although the working tree has uncommitted changes (the reports then say so; by
    /// default `reproduce` refuses, so every report names the one commit it came from).
    #[arg(long)]
    pub allow_dirty: bool,
}

/// `tetbench reproduce …`.
pub fn run(args: Args, data_dir: Option<PathBuf>) -> anyhow::Result<()> {
    let all = args.paper == "all";
    let chosen: Vec<&dyn PaperModule> = if all {
        PAPERS.to_vec()
    } else {
        let p = super::find(&args.paper).ok_or_else(|| {
            anyhow::anyhow!(
                "unknown paper {:?}; known: {}, all",
                args.paper,
                super::ids().join(", ")
            )
        })?;
        if let Some(why) = not_built_reason(p.paper().algorithm) {
            anyhow::bail!("cannot reproduce {}: {why}", p.paper().id);
        }
        vec![p]
    };
    let mut substitutes = vec![];
    for s in &args.substitute {
        let (a, b) = s
            .split_once('=')
            .ok_or_else(|| anyhow::anyhow!("--substitute {s:?}: expected NAME=SPEC"))?;
        substitutes.push((a.trim().to_string(), b.trim().to_string()));
    }
    if args.rounds == Some(0) {
        anyhow::bail!("--rounds 0: need at least one round");
    }
    let mut source = SourceState::read();
    source.check(args.allow_dirty)?;
    let started = Instant::now();
    // Lines only (each run shows its own bar); the ETA counts runs, which differ in size.
    let runs: usize = chosen.iter().map(|m| m.plan().len()).sum();
    let mut progress = Progress::lines("tetbench reproduce", runs as u64);
    for module in chosen {
        let p = module.paper();
        let t0 = Instant::now();
        let dir = args.out.join(p.id);
        if dir.exists() {
            std::fs::remove_dir_all(&dir)
                .with_context(|| format!("cannot replace {}", dir.display()))?;
        }
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        let mut session = Session {
            dir: dir.clone(),
            quick: args.quick,
            data_dir: data_dir.clone(),
            cache_dir: args.cache_dir.clone(),
            substitutes: substitutes.clone(),
            resolution: args.resolution,
            rounds: args.rounds,
            machine: None,
            log: vec![],
            external: args.external.clone(),
            source: source.clone(),
            from_run: None,
        };
        eprintln!("tetbench reproduce: {} ({})", p.id, p.title);
        let report = measure_and_tabulate(module, &mut session, &mut progress)?;
        let seconds = t0.elapsed().as_secs_f64();
        write_report(p, &session, &report, seconds)?;
        let summary = summary_of(p, &session, &report, seconds);
        write_file(
            &dir.join(SUMMARY_FILE),
            &serde_json::to_string_pretty(&summary)?,
        )?;
        eprintln!(
            "{}: {seconds:.0} s, report {}",
            p.id,
            dir.join("report.md").display()
        );
    }
    eprintln!("total: {:.0} s", started.elapsed().as_secs_f64());
    // Rebuilt after every command from the summaries of every paper under OUT, so README.md
    // and index.html come from the same data as the reports beside them.
    let index = index_markdown(&args.out)?;
    write_file(&args.out.join("README.md"), &index)?;
    write_file(
        &args.out.join("index.html"),
        &table::markdown_to_html(&index, "Papers reproduced")?,
    )?;
    print!("{index}");
    Ok(())
}

/// A paper's CPU analyses, then its plan's runs, then its tables from what they measured.
fn measure_and_tabulate(
    paper: &dyn PaperModule,
    session: &mut Session,
    progress: &mut Progress,
) -> anyhow::Result<Report> {
    let mut measured = Measured::default();
    let extra = paper.analyses(session, &mut measured)?;
    for spec in paper.plan() {
        progress.begin(&format!("{}: run {}", paper.paper().id, spec.name));
        session.run(&spec, &mut measured)?;
        progress.skip(1);
    }
    Ok(paper.tables(&measured, &extra))
}

/// What the index says of one paper's report (`OUT/<paper>/summary.json`).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct PaperSummary {
    pub paper: String,
    pub mode: String,
    pub seconds: f64,
    /// The commit sentence of [`SourceState::describe`].
    pub source: String,
    /// Each table's count of cells within its rule (an older summary: the exact tables'
    /// verdicts, which counted no cell).
    #[serde(alias = "exact_tables")]
    pub tables: String,
    /// Every table's cells by verdict, the headline beside the claims (`None`: a summary
    /// written before cells were counted).
    #[serde(default)]
    pub cells: Option<CellCounts>,
    /// The measured claims' verdicts (the headline).
    pub claims: String,
    /// The claims by construction and the derived ones, with their own words.
    #[serde(default)]
    pub not_measured: String,
}

pub const SUMMARY_FILE: &str = "summary.json";

impl PaperSummary {
    /// The cells' headline, or what an older summary says instead.
    pub fn cells_text(&self) -> String {
        match &self.cells {
            Some(n) => n.headline(),
            None => format!(
                "not counted (an older summary; exact tables: {})",
                self.tables
            ),
        }
    }

    /// The claims' headline; an older summary (no cells counted) is labelled as such, because
    /// its verdicts were given in the words of its day: before evidence kinds, "too few
    /// frames", "not discriminating" and positive controls, a hold there may rest on one frame,
    /// a layout constant or a pair that cannot differ.
    pub fn claims_text(&self) -> String {
        match &self.cells {
            Some(_) => self.claims.clone(),
            None => format!(
                "{} (an older summary, in the verdict words of its day: its holds were not yet \
                 checked for evidence kind, enough frames, a pair that can differ or a positive \
                 control)",
                self.claims
            ),
        }
    }
}

/// The summary of one paper's report: its tables' cells and its claims, counted.
fn summary_of(p: &Paper, session: &Session, report: &Report, seconds: f64) -> PaperSummary {
    let judged = judged(p, report);
    let tables: Vec<String> = judged.iter().map(|j| j.summary()).collect();
    PaperSummary {
        paper: p.id.to_string(),
        mode: if session.quick { "quick" } else { "full" }.into(),
        seconds,
        source: session.source.describe(),
        tables: if tables.is_empty() {
            "–".into()
        } else {
            tables.join(". ")
        },
        cells: Some(cell_counts(&judged)),
        claims: tally_text(&report.claims),
        not_measured: tally_apart_text(&report.claims),
    }
}

/// Every table of a report judged by its cell rules.
fn judged<'a>(p: &Paper, report: &'a Report) -> Vec<table::Judged<'a, 'static>> {
    report.comparisons.iter().map(|c| c.judge(p.id)).collect()
}

/// The cells of every table of a report, by verdict.
fn cell_counts(judged: &[table::Judged]) -> CellCounts {
    let mut n = CellCounts::default();
    for j in judged {
        n.merge(&j.counts());
    }
    n
}

/// The index of every paper reproduced under `out`, from their summaries.
pub fn index_markdown(out: &Path) -> anyhow::Result<String> {
    let mut md = String::from("# Papers reproduced\n\nWritten by `tetbench reproduce` from each paper's `summary.json`; nothing here is edited by hand.\n\n| paper | mode | seconds | commit | cells (every table's, by its rule in `reports/papers/cell_rules.csv`) | measured claims (verdicts per data set) | by construction, derived | report |\n|---|---|---:|---|---|---|---|---|\n");
    let mut total = 0.0;
    let mut cells = Some(CellCounts::default());
    let mut sources = vec![];
    for p in PAPERS.iter().map(|p| p.paper()) {
        let path = out.join(p.id).join(SUMMARY_FILE);
        if !path.exists() {
            continue;
        }
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let s: PaperSummary = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a paper summary", path.display()))?;
        total += s.seconds;
        cells = cells.zip(s.cells).map(|(mut all, one)| {
            all.merge(&one);
            all
        });
        if !sources.contains(&s.source) {
            sources.push(s.source.clone());
        }
        let _ = writeln!(
            md,
            "| {} | {} | {:.0} | {} | {} | {} | {} | [{0}/report.md]({0}/report.md) |",
            s.paper,
            s.mode,
            s.seconds,
            sources
                .iter()
                .position(|x| *x == s.source)
                .map_or(0, |i| i + 1),
            s.cells_text(),
            s.claims_text(),
            if s.not_measured.is_empty() {
                "–"
            } else {
                &s.not_measured
            }
        );
    }
    let _ = writeln!(
        md,
        "\nTotal: {total:.0} s. Cells of every paper: {}.\n",
        cells.map_or("not counted by every summary".into(), |n| n.headline())
    );
    for (i, s) in sources.iter().enumerate() {
        let _ = writeln!(md, "Commit {}: {s}\n", i + 1);
    }
    if sources.len() > 1 {
        md.push_str("**These reports come from more than one build**: regenerate them with one `tetbench reproduce all` to compare like with like.\n");
    }
    Ok(md)
}

/// Our side of the conditions: adapter, driver, CPU, commit, date.
fn our_conditions(machine: Option<&MachineInfo>) -> String {
    let m = machine.cloned().unwrap_or_else(MachineInfo::collect);
    let adapter = m
        .adapter
        .as_ref()
        .map(|a| {
            format!(
                "{} ({}, {}; driver {} {})",
                a.name, a.backend, a.device_type, a.driver, a.driver_info
            )
        })
        .unwrap_or_else(|| "none opened (no run needed a GPU)".into());
    format!(
        "adapter {adapter}; CPU {} ({} logical cores); {}; tetbench {} commit {}{}; {}",
        m.cpu_model,
        m.cpu_cores,
        m.os,
        m.tetbench_version,
        m.git_commit.as_deref().unwrap_or("unknown"),
        if m.git_dirty == Some(true) {
            " (uncommitted changes)"
        } else {
            ""
        },
        m.date_utc
    )
}

/// Counts of each verdict of the measured claims, as one line (the headline).
pub fn tally_text(results: &[ClaimResult]) -> String {
    let parts: Vec<String> = claims_report::tally(results)
        .into_iter()
        .filter(|(_, n)| *n > 0)
        .map(|(v, n)| format!("{n} {}", v.label()))
        .collect();
    if parts.is_empty() {
        "none".into()
    } else {
        parts.join(", ")
    }
}

/// Counts of the claims that are not measured, by kind, as one line (`–` when none).
pub fn tally_apart_text(results: &[ClaimResult]) -> String {
    let parts: Vec<String> = claims_report::tally_apart(results)
        .into_iter()
        .map(|(kind, words)| {
            let w: Vec<String> = words.iter().map(|(w, n)| format!("{n} {w}")).collect();
            format!("{kind}: {}", w.join(", "))
        })
        .collect();
    if parts.is_empty() {
        "–".into()
    } else {
        parts.join("; ")
    }
}

pub(crate) fn write_report(
    paper: &Paper,
    session: &Session,
    report: &Report,
    seconds: f64,
) -> anyhow::Result<()> {
    let dir = &session.dir;
    let mut md = format!("# {} — reproduced\n\n{}\n\n", paper.title, paper.citation);
    let mode = if let Some(dir) = &session.from_run {
        format!(
            "**From finished runs** (`tetbench analyze {} {}`): their viewpoints, viewport and frames as run. The CPU analyses (sorts, k-buffer, classifier, data set sizes) are not part of a run: their cells and claims are left empty, with why.",
            paper.id,
            dir.display()
        )
    } else if session.quick {
        format!(
            "**Quick mode**: viewpoint(s) {QUICK_VIEWPOINTS} instead of the paper's, the viewport side divided by {QUICK_RESOLUTION_DIVISOR} (e.g. 256² for the papers' 512²), {QUICK_FRAMES} timed frame after {QUICK_WARMUP} warm-up, no reference images (no PSNR); data sets at the papers' sizes; only the variants the paper's tables and claims compare where a plan adds others (each run's settings are under Runs); {} round(s) per row. Counts that do not depend on the GPU (HAVS Table 2, GATOR's classifier, the ray caster's passes, fragment PT's device bytes on Brain) are measured at the paper's size in this mode too. Figures of time are indicative only.",
            session.rounds()
        )
    } else {
        format!(
            "**Full mode**: the paper's viewpoints and viewport, {FULL_FRAMES} timed frames after {FULL_WARMUP} warm-up in each of {} rounds per row (seconds apart), reference images and PSNR.",
            session.rounds()
        )
    };
    if session.from_run.is_some() {
        let _ = writeln!(md, "{mode}\n");
    } else {
        let _ = writeln!(md, "{mode} Took {seconds:.0} s.\n");
    }
    let _ = writeln!(md, "{}\n", session.source.describe());
    let judged = judged(paper, report);
    let _ = writeln!(
        md,
        "**Headline.** Measured claims: {}. Cells of the paper's tables: {}.\n",
        tally_text(&report.claims),
        cell_counts(&judged).headline()
    );
    if let Some(r) = session.resolution {
        let _ = writeln!(md, "Viewport overridden: {r}×{r} (`--resolution`).\n");
    }
    if !session.substitutes.is_empty() {
        let subs: Vec<String> = session
            .substitutes
            .iter()
            .map(|(a, b)| format!("{a} → `{b}`"))
            .collect();
        let _ = writeln!(
            md,
            "Data sets substituted (`--substitute`): {}.\n",
            subs.join(", ")
        );
    }
    let _ = writeln!(md, "## Conditions\n");
    let _ = writeln!(md, "- Paper: {}", paper.hardware);
    let _ = writeln!(md, "- Ours: {}\n", our_conditions(session.machine.as_ref()));
    let _ = writeln!(md, "## The paper's claims\n");
    if report.claims.is_empty() {
        let _ = writeln!(md, "(none listed in reports/papers/claims.csv)\n");
    } else {
        let _ = writeln!(
            md,
            "From `reports/papers/claims.csv`; one verdict per data set. Measured claims: {}. Not measured, and so never counted as holds: {} (*by construction*: an input chosen to equal the paper's, read *as constructed*; *derived*: arithmetic on other claims' numbers, read *follows*). Each claim's rule (expectation, tolerance, normalisation) is written in the file before the run; an earlier rule is shown beside the verdict with the verdict it gives. The rule (`harness/src/papers/verdict.rs`): a difference inside the samples' spread (frames' range) or the claim's tolerance is *within noise*, and one frame per side never orders two sides; a pair whose sides cannot differ on a data set by our own analysis of it is *not discriminating* there; a hold whose positive control (a known perturbation, printed beside the verdict) passes the rule too is *insensitive*; a claim about GPU speed measured on a software rasteriser is *not testable on this adapter* (its numbers are still shown), *not checkable* says what is missing.\n",
            tally_text(&report.claims),
            tally_apart_text(&report.claims)
        );
        md.push_str(&claims_report::markdown(&report.claims));
        md.push('\n');
    }
    md.push_str(&findings_markdown(paper, &judged));
    let _ = writeln!(md, "## Tables\n");
    let charts = dir.join("charts");
    for j in &judged {
        md.push_str(&table::markdown(j));
        md.push('\n');
        for f in table::write_charts(&charts, j)? {
            let _ = writeln!(md, "![{} {f}](charts/{f})\n", j.comparison.key);
        }
    }
    md.push_str(&figures_markdown(&charts, &report.figures)?);
    if !report.notes.is_empty() {
        let _ = writeln!(md, "## Notes\n");
        for n in &report.notes {
            let _ = writeln!(md, "- {n}");
        }
        md.push('\n');
    }
    let _ = writeln!(md, "## Runs\n");
    if session.log.is_empty() {
        let _ = writeln!(md, "(no GPU run)");
    }
    for l in &session.log {
        let _ = writeln!(md, "- {l}");
    }
    write_file(&dir.join("report.md"), &md)?;
    write_file(
        &dir.join("report.html"),
        &table::markdown_to_html(&md, paper.title)?,
    )
}

/// The paper's figures drawn from measured data: each one's heading and text, then per panel
/// its heat map (written into `charts`) and caption, or why it has none.
fn figures_markdown(charts: &Path, figures: &[Figure]) -> anyhow::Result<String> {
    let mut md = String::new();
    if !figures.is_empty() {
        md.push_str("## Figures\n\n");
    }
    for f in figures {
        let _ = writeln!(md, "### {}\n\n{}\n", f.title, f.text);
        for p in &f.panels {
            match &p.grid {
                Ok(grid) => {
                    let stem = format!("{}_{}", f.key, crate::results::names::slug(&p.label));
                    let png = crate::plot::tile_map::save(charts, &stem, &p.title, grid)?;
                    let _ = writeln!(md, "![{}](charts/{png})\n\n{}\n", p.title, p.caption);
                }
                Err(why) => {
                    let _ = writeln!(md, "{}: no heat map: {why}\n", p.label);
                }
            }
        }
    }
    Ok(md)
}

/// The cells outside their rule, each a finding with its explanation or "unexplained", and
/// the cell rules' history for this paper.
fn findings_markdown(paper: &Paper, judged: &[table::Judged]) -> String {
    let mut md = String::from("## Cells outside their rule\n\n");
    let findings: Vec<String> = judged.iter().flat_map(|j| j.findings()).collect();
    if findings.is_empty() {
        md.push_str("None: every cell the rules compare is within its rule.\n");
    }
    for f in &findings {
        let _ = writeln!(md, "- {f}");
    }
    md.push_str("\nEach table's rule (`reports/papers/cell_rules.csv`, written before the run) says which columns are compared, how (exact, rounded as the paper prints it, or within a relative tolerance) and in which direction; times and rates of the paper's hardware are not compared on this adapter, and columns that follow from a layout are not compared either. Rows on stand-ins are not compared. Each is counted apart.\n");
    for h in super::rules::cell_rule_changes(paper.id) {
        if let Some(old) = &h.old_cell {
            let _ = writeln!(
                md,
                "\n- {} {}: until {} (commit {}) the rule was {}. Why it changed: {}",
                h.paper,
                h.id,
                h.date,
                h.commit,
                old.describe(),
                h.reason
            );
        }
    }
    md.push('\n');
    md
}

fn write_file(path: &Path, text: &str) -> anyhow::Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every numeric cell of every paper CSV appears as a paper value in that paper's tables,
    /// even with nothing measured (the paper column is filled wherever the transcription has
    /// a value).
    #[test]
    fn every_paper_value_is_printed() {
        use crate::papers::session::Extra;
        use crate::papers::transcription;
        for paper in PAPERS {
            // A paper's transcribed tables are named after its id (`fragment-pt_table1`).
            let prefix = paper.paper().id;
            let report = paper.tables(&Measured::default(), &Extra::default());
            let printed: Vec<f64> = report
                .comparisons
                .iter()
                .flat_map(|c| {
                    c.rows
                        .iter()
                        .flat_map(|r| r.cells.iter().filter_map(|c| c.paper))
                })
                .collect();
            for (name, _) in transcription::CSVS
                .iter()
                .filter(|(n, _)| n.starts_with(&format!("{prefix}_")))
            {
                let t = transcription::table(name).unwrap();
                for key in t.keys() {
                    for col in t.header.iter().filter(|c| !transcription::is_key_column(c)) {
                        if let Some(v) = t.value(&key, col) {
                            assert!(
                                printed.contains(&v),
                                "{name} {key} {col} = {v} is not printed"
                            );
                        }
                    }
                }
            }
            // Every table's markdown renders.
            for c in &report.comparisons {
                assert!(table::markdown(&c.judge(prefix)).contains("paper"));
            }
        }
    }

    /// Every column of every paper's tables has its rule in `reports/papers/cell_rules.csv`,
    /// and every line of the file names a table and a column (or `*`) that exist.
    #[test]
    fn every_column_has_a_cell_rule_and_every_rule_a_column() {
        use crate::papers::cells::{self, EVERY_OTHER_COLUMN};
        use crate::papers::session::Extra;
        let mut columns: Vec<(&str, String, String)> = vec![];
        for paper in PAPERS {
            let id = paper.paper().id;
            for c in paper
                .tables(&Measured::default(), &Extra::default())
                .comparisons
            {
                let judged = c.judge(id);
                for (m, r) in c.metrics.iter().zip(&judged.rules) {
                    assert!(r.is_some(), "{id} {} {:?} has no cell rule", c.key, m.name);
                    columns.push((id, c.key.clone(), m.name.clone()));
                }
            }
        }
        for r in cells::rules() {
            assert!(
                columns.iter().any(|(p, t, c)| *p == r.paper
                    && *t == r.table
                    && (r.column == EVERY_OTHER_COLUMN || *c == r.column)),
                "{}: {} {} {:?} names no column of the paper's tables",
                cells::CELL_RULES_FILE,
                r.paper,
                r.table,
                r.column
            );
        }
    }

    /// HAVS Table 2 on spx2 at the paper's own values, then with 314 pixels needing k > 6 (as
    /// measured): the cell flips to outside its rule, the report's headline and the summary's
    /// typed count flip with it, and the report lists the cell as a finding.
    #[test]
    fn one_changed_cell_flips_the_reports_headline_and_is_a_finding() {
        use crate::papers::havs::{self, analysis};
        use crate::papers::session::Extra;
        let t = crate::papers::transcription::table("havs_table2").unwrap();
        let paper = |c: &str| t.value("spx2", c).unwrap();
        let report = |k_gt6: u64| {
            let x = Extra::with_own(analysis::HavsAnalyses {
                kbuffer: vec![analysis::KbufferRow {
                    dataset: "spx2".into(),
                    fragments: paper("fragments_count") as u64,
                    max_list: paper("max_abuffer_list_length") as u32,
                    max_k: paper("max_k") as u32,
                    pixels_k_gt2: paper("pixels_needing_k_gt_2") as u64,
                    pixels_k_gt6: k_gt6,
                    ..Default::default()
                }],
                kbuffer_views: 14,
                kbuffer_resolution: 512,
                ..Default::default()
            });
            havs::tables(&Measured::default(), &x)
        };
        let dir = tempfile::tempdir().unwrap();
        let session = Session {
            dir: dir.path().to_path_buf(),
            quick: true,
            data_dir: None,
            cache_dir: None,
            substitutes: vec![],
            resolution: None,
            rounds: None,
            machine: None,
            log: vec![],
            external: Default::default(),
            source: SourceState::default(),
            from_run: None,
        };
        let p = havs::PAPER;
        for (k_gt6, within, finding) in [(512, 5, false), (314, 4, true)] {
            let r = report(k_gt6);
            let s = summary_of(&p, &session, &r, 1.0);
            let n = s.cells.unwrap();
            assert_eq!((n.within, n.outside), (within, 5 - within), "{s:?}");
            write_report(&p, &session, &r, 1.0).unwrap();
            let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
            let head = format!("Cells of the paper's tables: {within} of 5 cells within the rule;");
            assert!(md.contains(&head), "{md}");
            let line = "- table2 spx2, pixels k>6: ours 314, paper 512 (-38.7 %); rule exact, two-sided: unexplained";
            assert_eq!(md.contains(line), finding, "{md}");
        }
    }

    /// The index counts every paper's cells from its typed summary; a summary written before
    /// cells were counted still loads and says so.
    #[test]
    fn the_index_counts_cells_and_reads_older_summaries() {
        let dir = tempfile::tempdir().unwrap();
        let write = |paper: &str, json: serde_json::Value| {
            std::fs::create_dir_all(dir.path().join(paper)).unwrap();
            std::fs::write(dir.path().join(paper).join(SUMMARY_FILE), json.to_string()).unwrap();
        };
        let cells = CellCounts {
            within: 3,
            outside: 2,
            on_this_adapter: 7,
            ..Default::default()
        };
        write(
            "havs",
            serde_json::json!({"paper": "havs", "mode": "quick", "seconds": 1.0, "source": "s",
                "tables": "table2: …", "cells": cells, "claims": "1 holds"}),
        );
        let md = index_markdown(dir.path()).unwrap();
        assert!(md.contains("| 3 of 5 cells within the rule; not compared: 7 on this adapter (timings) | 1 holds |"), "{md}");
        assert!(
            md.contains("Cells of every paper: 3 of 5 cells within the rule"),
            "{md}"
        );
        write(
            "gator",
            serde_json::json!({"paper": "gator", "mode": "quick", "seconds": 1.0, "source": "s",
                "exact_tables": "table1: test1 match", "claims": "2 holds"}),
        );
        let md = index_markdown(dir.path()).unwrap();
        assert!(
            md.contains("not counted (an older summary; exact tables: table1: test1 match)"),
            "{md}"
        );
        assert!(
            md.contains("Cells of every paper: not counted by every summary"),
            "{md}"
        );
        assert!(
            md.contains("| 1 holds |"),
            "a current summary's claims unlabelled: {md}"
        );
        assert!(
            md.contains("| 2 holds (an older summary, in the verdict words of its day"),
            "{md}"
        );
    }

    #[test]
    fn unbuilt_algorithms_are_named_from_the_algorithm_table() {
        assert!(not_built_reason("havs").is_none());
        let why = not_built_reason("no-such-algorithm").unwrap();
        assert!(
            why.contains("not built in") && why.contains("gator-pt"),
            "{why}"
        );
    }
}
