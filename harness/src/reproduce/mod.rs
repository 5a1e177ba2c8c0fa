//! `tetbench reproduce havs|gator|fragment-pt|raycast|splat|all [--quick] [--out DIR]`: runs
//! every measurement a paper's tables need (its data sets, viewpoints, settings and
//! resolution, from the transcription in `reports/papers/`), then writes `OUT/<paper>/report.md`
//! and `report.html`: each table in the paper's shape with paper | ours | ours/paper, the
//! conditions of both, bar charts, and the paper's claims (`reports/papers/claims.csv`), each
//! with a verdict of [`crate::papers::verdict`] and the numbers and variants it rests on.
//!
//! Each paper is one module with (a) its run plan (`measure`, built on the run loop
//! [`crate::run`] and the analyses of [`crate::analyze`]) and (b) its table writer (`tables`,
//! a pure function of what was measured, so tests can check it without a GPU). Algorithms a
//! plan names that this build lacks (derived from [`crate::algorithms::names`]) leave their
//! cells empty with the reason.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;

use crate::report::{aggregate, Aggregate};
use crate::results::machine::MachineInfo;
use crate::results::{ResultsFile, Row};

pub mod evidence;
pub mod fragment_pt;
pub mod from_run;
pub mod gator;
pub mod havs;
pub use crate::papers;
pub mod raycast;
pub mod splat;
pub mod table;

use crate::papers::claims::{self, ClaimResult};
pub use evidence::evaluate_claims;
use table::Comparison;

#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// `havs`, `gator`, `fragment-pt`, `raycast`, `splat` or `all`.
    pub paper: String,
    /// Fewer viewpoints and frames, no reference images: minutes on a 2-core machine without
    /// a GPU. The report says what was shrunk.
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
    /// Run although the working tree has uncommitted changes (the reports then say so; by
    /// default `reproduce` refuses, so every report names the one commit it came from).
    #[arg(long)]
    pub allow_dirty: bool,
}

/// One paper: what it is, on what it was measured, and how to reproduce it.
pub struct Paper {
    /// Name on the command line and output folder.
    pub id: &'static str,
    pub title: &'static str,
    pub citation: &'static str,
    /// The paper's test machine, from the transcription.
    pub hardware: &'static str,
    /// The tetbench algorithm the paper describes (must be built in to reproduce it alone).
    pub algorithm: &'static str,
    /// Every data set the plan loads (registry names): the rows a claim may name.
    pub datasets: &'static [&'static str],
    /// The places of the paper a claim may cite (its numbered sections, tables, abstract,
    /// captions), from its source text.
    pub sections: &'static [&'static str],
    pub reproduce: fn(&mut Session) -> anyhow::Result<Report>,
    /// Its tables and claims from what was measured: the one writer, shared by `reproduce` and
    /// `analyze PAPER RUN_DIR`.
    pub tables: fn(&Measured, &Extra) -> Report,
}

/// Every paper, in the order `all` runs them.
pub fn papers() -> [&'static Paper; 5] {
    [
        &havs::PAPER,
        &gator::PAPER,
        &fragment_pt::PAPER,
        &raycast::PAPER,
        &splat::PAPER,
    ]
}

/// What a paper module's table writer returns.
#[derive(Debug, Clone, Default)]
pub struct Report {
    pub comparisons: Vec<Comparison>,
    /// The paper's claims (`reports/papers/claims.csv`), one verdict per data set.
    pub claims: Vec<ClaimResult>,
    pub notes: Vec<String>,
}

/// Whether this build has an algorithm (from the algorithm table).
pub fn built_in(algorithm: &str) -> bool {
    crate::algorithms::names().contains(&algorithm)
}

/// Why an algorithm has no rows: not built in (which issue adds it), or `None` if built.
pub fn not_built_reason(algorithm: &str) -> Option<String> {
    (!built_in(algorithm)).then(|| {
        format!(
            "algorithm {algorithm} is not built in (this build has: {})",
            crate::algorithms::names().join(", ")
        )
    })
}

/// One `tetbench run` of a plan.
#[derive(Debug, Clone)]
pub struct RunSpec {
    /// Sub-folder of OUT/<paper>/runs/.
    pub name: String,
    pub algorithms: Vec<String>,
    pub datasets: Vec<String>,
    /// Viewpoints in the full run (the quick run uses [`QUICK_VIEWPOINTS`]).
    pub viewpoints: String,
    pub resolution: u32,
    /// The transfer function (a preset name); `None` is the suite's `low-opacity`.
    pub tf: Option<&'static str>,
    pub settings: Option<String>,
}

/// The quick mode's viewpoint (one diagonal of the 14), frames and warm-up.
pub const QUICK_VIEWPOINTS: &str = "+x+y+z";
pub const QUICK_FRAMES: u32 = 1;
/// The quick mode divides the paper's viewport side by this (fragments, and so the time of
/// every rasterising algorithm on a CPU adapter, scale with the pixels).
pub const QUICK_RESOLUTION_DIVISOR: u32 = 2;
pub const QUICK_WARMUP: u32 = 1;
/// The full mode's frames and warm-up (tetbench's standard).
pub const FULL_FRAMES: u32 = crate::run::suite::STANDARD_FRAMES;
pub const FULL_WARMUP: u32 = crate::run::suite::STANDARD_WARMUP;

/// Measured rows of one paper plus what could not be measured.
#[derive(Debug, Clone, Default)]
pub struct Measured {
    pub rows: Vec<Row>,
    /// Per run, the failures that are not one row (a data set that did not load).
    pub errors: Vec<String>,
}

impl Measured {
    pub fn aggregates(&self) -> Vec<Aggregate> {
        aggregate(&self.rows)
    }

    /// A counter of the first row of `algorithm` on `dataset` that has it.
    pub fn counter(&self, algorithm: &str, dataset: &str, name: &str) -> Option<f64> {
        self.rows
            .iter()
            .filter(|r| r.algorithm == algorithm && r.dataset == dataset)
            .find_map(|r| r.counter(name))
    }

    /// Why `algorithm` has no value on `dataset`: not built, a failed row's error, a data set
    /// that did not load, or not measured.
    pub fn why(&self, algorithm: &str, dataset: &str) -> String {
        if let Some(r) = not_built_reason(algorithm) {
            return r;
        }
        if let Some(r) = self
            .rows
            .iter()
            .find(|r| r.algorithm == algorithm && r.dataset == dataset && !r.error.is_empty())
        {
            return format!("failed: {}", r.error);
        }
        if let Some(e) = self
            .errors
            .iter()
            .find(|e| e.contains(&format!("\"{dataset}\"")))
        {
            return e.clone();
        }
        "not measured in this run".into()
    }
}

pub use crate::results::value_of;

/// The aggregate of `algorithm` on `dataset` whose settings include every `want` pair, if
/// exactly one does: where several variants match, none is taken (the first one found must
/// never stand for the algorithm silently; the table's plan names the variant).
pub fn find<'a>(
    aggs: &'a [Aggregate],
    algorithm: &str,
    dataset: &str,
    pins: &[(&str, &str)],
) -> Option<&'a Aggregate> {
    let want = pins
        .iter()
        .fold(render_core::Settings::new(), |s, (k, v)| s.with(k, *v));
    find_including(
        aggs,
        algorithm,
        dataset,
        &want.retyped(|k| crate::algorithms::describe(algorithm).and_then(|d| d.kind_of(k))),
    )
}

/// The one aggregate of `algorithm` on `dataset` whose settings include `want` (`None` when
/// none or several do).
pub fn find_including<'a>(
    aggs: &'a [Aggregate],
    algorithm: &str,
    dataset: &str,
    want: &render_core::Settings,
) -> Option<&'a Aggregate> {
    let mut hits = aggs
        .iter()
        .filter(|a| a.algorithm == algorithm && a.dataset == dataset && a.settings.includes(want));
    let first = hits.next()?;
    hits.next().is_none().then_some(first)
}

/// The state of one paper's reproduction: where it writes, the mode, and what it ran.
pub struct Session {
    pub dir: PathBuf,
    pub quick: bool,
    pub data_dir: Option<PathBuf>,
    pub cache_dir: Option<PathBuf>,
    pub substitutes: Vec<(String, String)>,
    pub resolution: Option<u32>,
    /// The machine of the first run (adapter included), for the conditions.
    pub machine: Option<MachineInfo>,
    /// The equivalent `tetbench run` command of every run, and its outcome.
    pub log: Vec<String>,
    /// External renderers added to every run (`--external`).
    pub external: crate::run::matrix::ExternalArgs,
    /// The commit the binary was built from and whether the tree was clean.
    pub source: SourceState,
    /// Set by `tetbench analyze PAPER RUN_DIR`: the runs the tables come from.
    pub from_run: Option<PathBuf>,
}

impl Session {
    /// The data set the plan calls `name` (or its substitute).
    pub fn dataset(&self, name: &str) -> String {
        self.substitutes
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, s)| s.clone())
            .unwrap_or_else(|| name.to_string())
    }

    /// The viewport of a run: `--resolution`, else the paper's (halved in quick mode).
    pub fn resolution(&self, paper: u32) -> u32 {
        self.resolution.unwrap_or(if self.quick {
            paper / QUICK_RESOLUTION_DIVISOR
        } else {
            paper
        })
    }

    /// Runs one plan entry with the built-in algorithms it names; rows keep the plan's data
    /// set names (substitutes are renamed back so the tables find them).
    pub fn run(&mut self, spec: &RunSpec, measured: &mut Measured) -> anyhow::Result<()> {
        let algorithms: Vec<String> = spec
            .algorithms
            .iter()
            .filter(|a| built_in(a))
            .cloned()
            .collect();
        for a in spec.algorithms.iter().filter(|a| !built_in(a)) {
            self.log.push(format!(
                "run {}: {a} skipped ({})",
                spec.name,
                not_built_reason(a).unwrap_or_default()
            ));
        }
        if algorithms.is_empty() {
            return Ok(());
        }
        let viewpoints = if self.quick {
            QUICK_VIEWPOINTS.to_string()
        } else {
            spec.viewpoints.clone()
        };
        let datasets: Vec<String> = spec.datasets.iter().map(|d| self.dataset(d)).collect();
        let out = self.dir.join("runs").join(&spec.name);
        let args = crate::run::plan::RunPlan {
            algorithms: algorithms.clone(),
            datasets: datasets.clone(),
            viewpoints: Some(viewpoints.clone()),
            resolution: Some(self.resolution(spec.resolution)),
            tf: spec.tf.unwrap_or("low-opacity").into(),
            frames: Some(if self.quick {
                QUICK_FRAMES
            } else {
                FULL_FRAMES
            }),
            warmup: Some(if self.quick {
                QUICK_WARMUP
            } else {
                FULL_WARMUP
            }),
            rounds: None,
            out: out.clone(),
            settings: spec.settings.clone(),
            no_reference: self.quick,
            cache_dir: self.cache_dir.clone(),
            orthographic: false,
            scalar: None,
            no_report: true,
            strict: false,
            shard: None,
            no_calibrate: false,
            peers: vec![],
            external: self.external.clone(),
        };
        let command = format!(
            "tetbench run --algorithms {} --datasets {} --viewpoints {viewpoints} --resolution {}{}{}{}",
            algorithms.join(","),
            datasets.join(","),
            self.resolution(spec.resolution),
            spec.tf.map(|t| format!(" --tf {t}")).unwrap_or_default(),
            spec.settings
                .as_ref()
                .map(|s| format!(" --settings '{s}'"))
                .unwrap_or_default(),
            if self.quick {
                format!(" --frames {QUICK_FRAMES} --warmup {QUICK_WARMUP} --no-reference")
            } else {
                String::new()
            }
        );
        let config = args.to_config(self.data_dir.clone(), vec![command.clone()])?;
        let filter = config.settings_filter.clone();
        let t0 = Instant::now();
        let outcome = crate::run::run(&config, &|name: &str| {
            crate::algorithms::selected_variants(name, &filter)
        })
        .with_context(|| format!("run {}", spec.name))?;
        let file = ResultsFile::read(&out)?;
        if self.machine.is_none() {
            self.machine = Some(file.machine.clone());
        }
        self.log.push(format!(
            "run {}: `{command}` — {} rows, {} failed, {:.0} s",
            spec.name,
            outcome.rows,
            outcome.failed_rows,
            t0.elapsed().as_secs_f64()
        ));
        measured.errors.extend(outcome.errors.iter().cloned());
        for mut row in file.rows {
            if let Some((plan, _)) = self.substitutes.iter().find(|(_, s)| {
                crate::results::names::slug(s) == crate::results::names::slug(&row.dataset)
                    || *s == row.dataset
            }) {
                row.dataset = plan.clone();
            }
            measured.rows.push(row);
        }
        Ok(())
    }
}

/// `tetbench reproduce …`.
pub fn run(args: Args, data_dir: Option<PathBuf>) -> anyhow::Result<()> {
    let all = args.paper == "all";
    let chosen: Vec<&Paper> = if all {
        papers().to_vec()
    } else {
        let p = papers()
            .into_iter()
            .find(|p| p.id == args.paper)
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "unknown paper {:?}; known: {}, all",
                    args.paper,
                    papers().map(|p| p.id).join(", ")
                )
            })?;
        if let Some(why) = not_built_reason(p.algorithm) {
            anyhow::bail!("cannot reproduce {}: {why}", p.id);
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
    let mut source = SourceState::read();
    source.check(args.allow_dirty)?;
    let started = Instant::now();
    for p in chosen {
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
            machine: None,
            log: vec![],
            external: args.external.clone(),
            source: source.clone(),
            from_run: None,
        };
        eprintln!("tetbench reproduce: {} ({})", p.id, p.title);
        let report = (p.reproduce)(&mut session)?;
        let seconds = t0.elapsed().as_secs_f64();
        write_report(p, &session, &report, seconds)?;
        let exact: Vec<String> = report
            .comparisons
            .iter()
            .filter_map(|c| {
                c.verdict()
                    .map(|v| format!("{}: {}", c.key, if v { "match" } else { "differ" }))
            })
            .collect();
        let summary = PaperSummary {
            paper: p.id.to_string(),
            mode: if args.quick { "quick" } else { "full" }.into(),
            seconds,
            source: session.source.describe(),
            exact_tables: if exact.is_empty() {
                "–".into()
            } else {
                exact.join(", ")
            },
            claims: tally_text(&report.claims),
        };
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

/// What the index says of one paper's report (`OUT/<paper>/summary.json`).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct PaperSummary {
    pub paper: String,
    pub mode: String,
    pub seconds: f64,
    /// The commit sentence of [`SourceState::describe`].
    pub source: String,
    pub exact_tables: String,
    pub claims: String,
}

pub const SUMMARY_FILE: &str = "summary.json";

/// The index of every paper reproduced under `out`, from their summaries.
pub fn index_markdown(out: &Path) -> anyhow::Result<String> {
    let mut md = String::from("# Papers reproduced\n\nWritten by `tetbench reproduce` from each paper's `summary.json`; nothing here is edited by hand.\n\n| paper | mode | seconds | commit | exact tables | claims (verdicts per data set) | report |\n|---|---|---:|---|---|---|---|\n");
    let mut total = 0.0;
    let mut sources = vec![];
    for p in papers() {
        let path = out.join(p.id).join(SUMMARY_FILE);
        if !path.exists() {
            continue;
        }
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let s: PaperSummary = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a paper summary", path.display()))?;
        total += s.seconds;
        if !sources.contains(&s.source) {
            sources.push(s.source.clone());
        }
        let _ = writeln!(
            md,
            "| {} | {} | {:.0} | {} | {} | {} | [{0}/report.md]({0}/report.md) |",
            s.paper,
            s.mode,
            s.seconds,
            sources
                .iter()
                .position(|x| *x == s.source)
                .map_or(0, |i| i + 1),
            s.exact_tables,
            s.claims
        );
    }
    let _ = writeln!(md, "\nTotal: {total:.0} s.\n");
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

/// Counts of each verdict, as one line.
pub fn tally_text(results: &[ClaimResult]) -> String {
    let parts: Vec<String> = claims::tally(results)
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

/// The commit `reproduce` runs from and whether the tree has uncommitted changes (read the
/// way the run's machine record reads it, [`MachineInfo::collect`]).
#[derive(Debug, Clone, Default)]
pub struct SourceState {
    pub commit: Option<String>,
    pub dirty: Option<bool>,
    /// `--allow-dirty` was given.
    pub allowed_dirty: bool,
}

impl SourceState {
    pub fn read() -> SourceState {
        let m = MachineInfo::collect();
        SourceState {
            commit: m.git_commit,
            dirty: m.git_dirty,
            allowed_dirty: false,
        }
    }

    /// Refuses a tree with uncommitted changes unless allowed.
    pub fn check(&mut self, allow_dirty: bool) -> anyhow::Result<()> {
        if self.dirty == Some(true) && !allow_dirty {
            anyhow::bail!(
                "the working tree has uncommitted changes: commit them so the reports name one commit, or pass --allow-dirty (the reports will say so)"
            );
        }
        self.allowed_dirty = allow_dirty && self.dirty == Some(true);
        Ok(())
    }

    /// One sentence for the reports.
    pub fn describe(&self) -> String {
        let commit = self.commit.as_deref().unwrap_or("unknown (no git)");
        match self.dirty {
            Some(true) => format!(
                "Built from commit `{commit}` **with uncommitted changes** (`--allow-dirty`): these figures are not reproducible from the commit alone."
            ),
            Some(false) => format!("Built from commit `{commit}`, clean tree."),
            None => format!("Commit `{commit}`; whether the tree was clean is unknown."),
        }
    }
}

fn write_report(
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
            "**Quick mode**: viewpoint(s) {QUICK_VIEWPOINTS} instead of the paper's, the viewport side divided by {QUICK_RESOLUTION_DIVISOR} (e.g. 256² for the papers' 512²), {QUICK_FRAMES} timed frame after {QUICK_WARMUP} warm-up, no reference images (no PSNR); data sets at the papers' sizes. Figures are indicative only."
        )
    } else {
        format!(
            "**Full mode**: the paper's viewpoints and viewport, {FULL_FRAMES} timed frames after {FULL_WARMUP} warm-up, reference images and PSNR."
        )
    };
    if session.from_run.is_some() {
        let _ = writeln!(md, "{mode}\n");
    } else {
        let _ = writeln!(md, "{mode} Took {seconds:.0} s.\n");
    }
    let _ = writeln!(md, "{}\n", session.source.describe());
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
            "From `reports/papers/claims.csv`; one verdict per data set: {}. The rule (`harness/src/papers/verdict.rs`): a difference inside the samples' spread (frames' range) or the claim's tolerance is *within noise*, and one frame per side never orders two sides; a claim about GPU speed measured on a software rasteriser is *not testable on this adapter* (its numbers are still shown); *not checkable* says what is missing.\n",
            tally_text(&report.claims)
        );
        md.push_str(&claims::markdown(&report.claims));
        md.push('\n');
    }
    let _ = writeln!(md, "## Tables\n");
    let charts = dir.join("charts");
    for c in &report.comparisons {
        md.push_str(&table::markdown(c));
        md.push('\n');
        for f in table::write_charts(&charts, c)? {
            let _ = writeln!(md, "![{} {f}](charts/{f})\n", c.key);
        }
    }
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

fn write_file(path: &Path, text: &str) -> anyhow::Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// Whether a data set name is a generated stand-in (its rows are marked).
pub fn is_standin(name: &str) -> bool {
    datasets::standins::is_generated(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every numeric cell of every paper CSV appears as a paper value in that paper's tables,
    /// even with nothing measured (the paper column is filled wherever the transcription has
    /// a value).
    #[test]
    fn every_paper_value_is_printed() {
        let prefixes = [
            ("havs", havs::tables as fn(&Measured, &Extra) -> Report),
            ("gator", gator::tables),
            ("fragment-pt", fragment_pt::tables),
            ("raycast", raycast::tables),
            ("splat", splat::tables),
        ];
        for (prefix, tables) in prefixes {
            let report = tables(&Measured::default(), &Extra::default());
            let printed: Vec<f64> = report
                .comparisons
                .iter()
                .flat_map(|c| {
                    c.rows
                        .iter()
                        .flat_map(|r| r.cells.iter().filter_map(|c| c.paper))
                })
                .collect();
            for (name, _) in papers::CSVS
                .iter()
                .filter(|(n, _)| n.starts_with(&format!("{prefix}_")))
            {
                let t = papers::table(name).unwrap();
                for key in t.keys() {
                    for col in t.header.iter().filter(|c| !papers::is_key_column(c)) {
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
                assert!(table::markdown(c).contains("paper"));
            }
        }
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

/// What a paper measured besides run rows (CPU analyses), shared shape so the tests can call
/// every table writer alike.
#[derive(Debug, Clone, Default)]
pub struct Extra {
    /// HAVS Table 1: each sort's median, fastest and slowest run.
    pub sorts: Vec<crate::analyze::havs::SortRow>,
    /// HAVS Table 2 rows.
    pub kbuffer: Vec<crate::analyze::havs::KbufferRow>,
    /// GATOR Table 1: the classifier's distinct outcomes (`None`: not run).
    pub truth_table: Option<Vec<gator::ObservedCase>>,
    /// Data set sizes: (plan name, points, tets).
    pub sizes: Vec<(String, u64, u64)>,
    /// Zero-volume tets the loader dropped, per data set (plan name, count).
    pub dropped: Vec<(String, u64)>,
    /// How many viewpoints and what viewport the k analysis used.
    pub kbuffer_views: usize,
    pub kbuffer_resolution: u32,
}

#[cfg(test)]
mod claims_tests;
