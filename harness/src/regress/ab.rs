//! `tetbench ab BASE NEW`: two builds run in turns over one matrix on this machine, then
//! compared with compare's own test.
//!
//! Each invocation is one round (`run --rounds 1`) into a directory of its own,
//! `OUT/base/round-NN` and `OUT/new/round-NN`, in the order A B, B A, A B, … (pair by pair,
//! each pair's order reversed from the last, so neither side always runs first after the
//! other). Separate directories rather than one directory with `--resume`: resume keeps
//! finished units and measures the rest, which is the opposite of adding a round to each; and
//! a directory per round keeps each round's own provenance and load average, and what a
//! failed invocation leaves is that round alone. The rounds of a side are then merged into
//! `OUT/base/results.json` and `OUT/new/results.json` — a row's samples are its rounds' frames
//! one round after the other, `run.rounds` the number of rounds, exactly the layout of one run
//! with `--rounds N` — and [`crate::regress::compare::compare`] judges them: one value per round, each
//! round divided by its own control (the run-wide factor where a side has none), Holm over the
//! groups. The rounds' controls are merged with them: invocation i's samples are round i's. Its outputs go to `OUT/compare`, the
//! drift each pair saw to `OUT/ab.json` and the terminal.

use crate::regress::compare::{key, Key};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::Context;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::build::Binary;
use crate::regress::compare::{adapter_of, CompareOptions, Comparison, Finding};
use crate::report::progress::Progress;
use crate::results::metrics::summarize;
use crate::results::stats::median;
use crate::results::{write_file, MergedRun, ResultsFile, Row};

/// Which build an invocation ran.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Base,
    New,
}

impl Side {
    fn dir_name(self) -> &'static str {
        match self {
            Side::Base => "base",
            Side::New => "new",
        }
    }

    fn label(self) -> &'static str {
        match self {
            Side::Base => "BASE",
            Side::New => "NEW",
        }
    }
}

/// The order of the invocations: pair by pair, BASE first in even pairs and NEW first in odd
/// ones (A B B A A B …), so a drift over the session falls on both sides alike.
pub fn schedule(pairs: u32) -> Vec<(u32, Side)> {
    (0..pairs)
        .flat_map(|p| {
            let order = if p % 2 == 0 {
                [Side::Base, Side::New]
            } else {
                [Side::New, Side::Base]
            };
            order.map(|s| (p, s))
        })
        .collect()
}

pub struct AbOptions {
    pub pairs: u32,
    pub out: PathBuf,
    /// Options before the `run` subcommand (`--data-dir`).
    pub global_args: Vec<String>,
    /// The matrix: options of `run` passed to both sides.
    pub run_args: Vec<String>,
    /// compare's options; `out` is where compare's files go.
    pub compare: CompareOptions,
}

/// What one pair saw: NEW / BASE of each row's median frame time, its median over the rows,
/// and each side against its own first round (the machine's drift over the session).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PairDrift {
    /// From 1.
    pub pair: u32,
    /// `BASE, NEW` or `NEW, BASE`.
    pub order: String,
    pub rows: usize,
    pub ratio: Option<f64>,
    pub lowest_row_ratio: Option<f64>,
    pub highest_row_ratio: Option<f64>,
    pub base_vs_first_round: Option<f64>,
    pub new_vs_first_round: Option<f64>,
}

/// The layout of `ab.json` (`docs/ab.schema.json`).
pub const SCHEMA_VERSION: u32 = 1;

/// The JSON Schema of `ab.json`.
pub fn json_schema() -> serde_json::Value {
    serde_json::to_value(schemars::schema_for!(AbReport)).expect("a schema is JSON")
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AbReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    pub base: String,
    pub new: String,
    pub base_binary: String,
    pub new_binary: String,
    pub pairs: u32,
    pub run_args: Vec<String>,
    pub drift: Vec<PairDrift>,
    pub outcome: String,
    /// compare's regressions (its `compare.json` has the improvements and other changes).
    pub regressions: Vec<Finding>,
    pub seconds: f64,
}

pub struct AbOutcome {
    pub comparison: Comparison,
    pub report: AbReport,
    /// Whether compare's `--fail-on` condition was met.
    pub fail: bool,
}

fn round_dir(out: &Path, side: Side, pair: u32) -> PathBuf {
    out.join(side.dir_name())
        .join(format!("round-{:02}", pair + 1))
}

/// The last lines of a log, for an error message.
fn tail(path: &Path, lines: usize) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let all: Vec<&str> = text.lines().collect();
    all[all.len().saturating_sub(lines)..].join("\n")
}

/// One round of one side: `BIN [global] run MATRIX --rounds 1 --no-report --out DIR`.
fn invoke(bin: &Binary, dir: &Path, log: &Path, opt: &AbOptions) -> anyhow::Result<()> {
    if dir.exists() {
        std::fs::remove_dir_all(dir)
            .with_context(|| format!("cannot clear {} for a new round", dir.display()))?;
    }
    let file =
        std::fs::File::create(log).with_context(|| format!("cannot create {}", log.display()))?;
    let status = Command::new(&bin.path)
        .args(&opt.global_args)
        .arg("run")
        .args(&opt.run_args)
        .args(["--rounds", "1", "--no-report", "--out"])
        .arg(dir)
        .stdin(Stdio::null())
        .stdout(file.try_clone()?)
        .stderr(file)
        .status()
        .with_context(|| format!("cannot start {}", bin.path.display()))?;
    if status.success() {
        return Ok(());
    }
    // A run with failed rows still wrote them: compare judges a row failing on one side.
    match ResultsFile::read(dir) {
        Ok(f) if !f.rows.is_empty() => {
            eprintln!(
                "tetbench ab: {} exited with {status} (log {}); its {} rows are compared, \
                 failed ones as failures",
                bin.label(),
                log.display(),
                f.rows.len()
            );
            Ok(())
        }
        _ => anyhow::bail!(
            "{} run failed ({status}) and left no results in {}; the end of {}:\n{}",
            bin.label(),
            dir.display(),
            log.display(),
            tail(log, 20)
        ),
    }
}

/// A row's own median frame time (`None`: failed or no samples).
fn row_median(r: &Row) -> Option<f64> {
    (r.ok() && !r.samples.total_ms.is_empty()).then(|| median(&r.samples.total_ms))
}

/// The median over matched rows of `new`'s median frame time over `base`'s, with the lowest and
/// highest row ratio and the number of rows.
fn ratio_of(
    base: &ResultsFile,
    new: &ResultsFile,
) -> (usize, Option<f64>, Option<f64>, Option<f64>) {
    let by_key: HashMap<Key, &Row> = base.rows.iter().map(|r| (key(r), r)).collect();
    let ratios: Vec<f64> = new
        .rows
        .iter()
        .filter_map(|n| {
            let b = by_key.get(&key(n))?;
            let (b, n) = (row_median(b)?, row_median(n)?);
            (b > 0.0).then(|| n / b)
        })
        .filter(|r| r.is_finite())
        .collect();
    match summarize(&ratios) {
        Some(s) => (ratios.len(), Some(s.median), Some(s.min), Some(s.max)),
        None => (0, None, None, None),
    }
}

/// The drift of every pair, from the rounds of both sides (index = pair).
pub fn pair_drift(base: &[ResultsFile], new: &[ResultsFile]) -> Vec<PairDrift> {
    base.iter()
        .zip(new)
        .enumerate()
        .map(|(p, (b, n))| {
            let (rows, ratio, lo, hi) = ratio_of(b, n);
            PairDrift {
                pair: p as u32 + 1,
                order: if p % 2 == 0 { "BASE, NEW" } else { "NEW, BASE" }.into(),
                rows,
                ratio,
                lowest_row_ratio: lo,
                highest_row_ratio: hi,
                base_vs_first_round: ratio_of(&base[0], b).1,
                new_vs_first_round: ratio_of(&new[0], n).1,
            }
        })
        .collect()
}

/// The rounds of one side as one results set with `run.rounds` = their number: a row's samples
/// are its frames of every round in turn (what `run --rounds N` writes), its summary columns
/// those of all its frames, its images those of the first round it succeeded in. A row missing
/// from a round or failing there keeps the other rounds' samples and says which rounds failed.
/// `side_dir` is where the merged file will live (image paths are made relative to it).
pub fn merge_rounds(dirs: &[PathBuf], side_dir: &Path) -> anyhow::Result<ResultsFile> {
    anyhow::ensure!(!dirs.is_empty(), "no rounds to merge");
    let files: Vec<ResultsFile> = dirs
        .iter()
        .map(|d| ResultsFile::read(d))
        .collect::<anyhow::Result<_>>()?;
    rounds_agree(&files, dirs)?;
    let first = &files[0];
    let mut keys: Vec<Key> = vec![];
    for f in &files {
        for r in &f.rows {
            if !keys.contains(&key(r)) {
                keys.push(key(r));
            }
        }
    }
    let mut errors: Vec<String> = files.iter().flat_map(|f| f.errors.clone()).collect();
    let mut rows = vec![];
    for k in &keys {
        let (row, error) = merge_key(k, &files, dirs, side_dir);
        errors.extend(error);
        rows.push(row);
    }
    let last = files.last().expect("not empty");
    let mut machine = first.machine.clone();
    machine.load_average_end = last.machine.load_average_end;
    let control = merged_control(&files);
    if let Some(c) = &control {
        crate::calibrate::set_control_factors(&mut rows, &c.median());
    }
    // Each row priced again with all its rounds' control.
    if let Some(cal) = &machine.calibration {
        crate::calibrate::annotate(&mut rows, cal);
    }
    Ok(ResultsFile {
        control,
        schema_version: crate::results::SCHEMA_VERSION,
        machine,
        run: merged_run(&files, dirs),
        finished_utc: last.finished_utc.clone(),
        rows,
        errors,
    })
}

/// The rounds of one side must share an adapter and a number of frames a round.
fn rounds_agree(files: &[ResultsFile], dirs: &[PathBuf]) -> anyhow::Result<()> {
    let first = &files[0];
    for (f, d) in files.iter().zip(dirs).skip(1) {
        anyhow::ensure!(
            adapter_of(f) == adapter_of(first),
            "{} ran on {} but {} on {}: the rounds of one side must share an adapter",
            d.display(),
            adapter_of(f),
            dirs[0].display(),
            adapter_of(first)
        );
        anyhow::ensure!(
            f.run.frames == first.run.frames,
            "{} timed {} frames per round but {} {}: rounds of one side must match",
            d.display(),
            f.run.frames,
            dirs[0].display(),
            first.run.frames
        );
    }
    Ok(())
}

/// The row of key `k` over every round: the samples and round controls of all of them, the
/// first measured round's other columns (its image paths made relative to `side_dir`), the
/// failures and missing rounds in its error; and an error of the merged set when its image
/// differs between rounds.
fn merge_key(
    k: &Key,
    files: &[ResultsFile],
    dirs: &[PathBuf],
    side_dir: &Path,
) -> (Row, Option<String>) {
    let prefix = |d: &Path| -> PathBuf {
        match (d.parent(), d.file_name()) {
            (Some(p), Some(name)) if p == side_dir => PathBuf::from(name),
            _ => std::path::absolute(d).unwrap_or_else(|_| d.to_path_buf()),
        }
    };
    let mut merged: Option<Row> = None;
    let mut failures = vec![];
    let mut samples = crate::results::FrameSamples::default();
    let mut round_control = vec![];
    let mut frames = 0;
    let mut hashes = vec![];
    for (i, (f, d)) in files.iter().zip(dirs).enumerate() {
        let Some(r) = f.rows.iter().find(|r| key(r) == *k) else {
            failures.push(format!("round {}: missing", i + 1));
            continue;
        };
        if !r.ok() {
            failures.push(format!("round {}: {}", i + 1, r.error_text()));
            merged.get_or_insert_with(|| r.clone());
            continue;
        }
        samples.total_ms.extend(&r.samples.total_ms);
        samples.cpu_ms.extend(&r.samples.cpu_ms);
        samples.gpu_ms.extend(&r.samples.gpu_ms);
        round_control.extend(r.round_control.iter().cloned());
        frames += r.frames;
        hashes.push(r.image_hash.clone());
        if merged.as_ref().is_none_or(|m| !m.ok()) {
            let mut m = r.clone();
            let base = prefix(d);
            for p in [
                &mut m.image,
                &mut m.image_f32,
                &mut m.reference_image,
                &mut m.heatmap,
                &mut m.tile_counts,
            ] {
                if !p.is_empty() {
                    *p = base.join(&*p).display().to_string();
                }
            }
            merged = Some(m);
        }
    }
    let mut row = merged.expect("every key comes from some round");
    let error = hashes.iter().any(|h| *h != hashes[0]).then(|| {
        format!(
            "{} {} {} {}: the image differs between rounds of one build",
            row.algorithm, row.settings, row.dataset, row.viewpoint
        )
    });
    // A round's control only where every round has one (the rounds then line up).
    let complete = failures.is_empty() && round_control.len() == files.len();
    row.round_control = if complete { round_control } else { vec![] };
    row.error = (!failures.is_empty())
        .then(|| crate::results::Failure::new(crate::results::Stage::Rounds, failures.join("; ")));
    row.frames = frames;
    summarise_samples(&mut row, samples);
    (row, error)
}

/// The merged set's run description: the first round's, with every round counted and named.
fn merged_run(files: &[ResultsFile], dirs: &[PathBuf]) -> crate::results::RunDescription {
    let mut run = files[0].run.clone();
    run.rounds = files.iter().map(|f| f.run.rounds.max(1)).sum();
    run.merged_from = files
        .iter()
        .zip(dirs)
        .map(|(f, d)| MergedRun {
            dir: d.display().to_string(),
            shard: None,
            adapter: Some(adapter_of(f)),
            git_commit: f.machine.git_commit.clone(),
            date_utc: f.machine.date_utc.clone(),
            rows: f.rows.len(),
        })
        .collect();
    run
}

/// The rounds' controls as one: invocation i's samples become round i's (before it) and
/// round i + 1's (after it), so that the merged set reads as one run of as many rounds.
fn merged_control(files: &[ResultsFile]) -> Option<crate::calibrate::control::Control> {
    let mut out: Option<crate::calibrate::control::Control> = None;
    for (i, f) in files.iter().enumerate() {
        let Some(c) = &f.control else { continue };
        let merged = out.get_or_insert_with(|| crate::calibrate::control::Control {
            probes: c.probes.clone(),
            setup_seconds: c.setup_seconds,
            samples: vec![],
        });
        merged.samples.extend(c.samples.iter().map(|s| {
            let mut s = s.clone();
            s.round += i as u32;
            s
        }));
    }
    out
}

/// Sets a merged row's samples and the summary columns of all of them.
fn summarise_samples(row: &mut Row, samples: crate::results::FrameSamples) {
    let total = summarize(&samples.total_ms);
    let cpu = summarize(&samples.cpu_ms);
    let gpu = summarize(&samples.gpu_ms);
    if let Some(t) = total {
        (row.total_ms, row.total_ms_min, row.total_ms_max) =
            (Some(t.median), Some(t.min), Some(t.max));
        if t.median > 0.0 {
            row.fps = Some(1000.0 / t.median);
            row.tets_per_sec = Some(row.tets as f64 / (t.median * 1e-3));
        }
        // The roofline is the first round's (the counters are the same in every round); its
        // fraction is of the merged median.
        crate::calibrate::set_fraction(row);
    }
    if let Some(c) = cpu {
        (row.cpu_ms, row.cpu_ms_min, row.cpu_ms_max) = (Some(c.median), Some(c.min), Some(c.max));
    }
    if let Some(g) = gpu {
        (row.gpu_ms, row.gpu_ms_min, row.gpu_ms_max) = (Some(g.median), Some(g.min), Some(g.max));
    }
    row.samples = samples;
}

/// Runs the interleaved rounds, merges, compares; writes `OUT/{base,new}/results.json`,
/// `OUT/compare/` and `OUT/ab.json`.
pub fn run_ab(base: &Binary, new: &Binary, opt: &AbOptions) -> anyhow::Result<AbOutcome> {
    anyhow::ensure!(
        opt.pairs >= crate::regress::compare::MIN_ROUNDS,
        "--pairs {} gives each side {} rounds; compare judges time from {} rounds on",
        opt.pairs,
        opt.pairs,
        crate::regress::compare::MIN_ROUNDS
    );
    let started = Instant::now();
    let logs = opt.out.join("logs");
    std::fs::create_dir_all(&logs).with_context(|| format!("cannot create {}", logs.display()))?;
    let order = schedule(opt.pairs);
    // A bar with the ETA on a terminal, a line per round otherwise (rounds are of equal size).
    let mut progress = Progress::new("tetbench ab", order.len() as u64, "rounds");
    for (pair, side) in &order {
        let bin = if *side == Side::Base { base } else { new };
        let dir = round_dir(&opt.out, *side, *pair);
        let log = logs.join(format!("{}-round-{:02}.log", side.dir_name(), pair + 1));
        let what = format!("pair {} {} ({})", pair + 1, side.label(), bin.label());
        progress.activity(&what);
        let t = Instant::now();
        invoke(bin, &dir, &log, opt)?;
        progress.step(&format!("{what} {:.1} s", t.elapsed().as_secs_f64()));
    }
    progress.finish();
    let mut rounds = vec![];
    for side in [Side::Base, Side::New] {
        let side_dir = opt.out.join(side.dir_name());
        let dirs: Vec<PathBuf> = (0..opt.pairs)
            .map(|p| round_dir(&opt.out, side, p))
            .collect();
        let merged = merge_rounds(&dirs, &side_dir)?;
        crate::results::write_json(&side_dir, &merged)?;
        crate::results::write_csv(&side_dir, &merged.rows)?;
        rounds.push(
            dirs.iter()
                .map(|d| ResultsFile::read(d))
                .collect::<anyhow::Result<Vec<_>>>()?,
        );
    }
    let drift = pair_drift(&rounds[0], &rounds[1]);
    let comparison = crate::regress::compare::compare(
        &opt.out.join("base"),
        &opt.out.join("new"),
        &opt.compare,
    )?;
    std::fs::create_dir_all(&opt.compare.out)
        .with_context(|| format!("cannot create {}", opt.compare.out.display()))?;
    crate::regress::compare_report::write_outputs(&comparison, &opt.compare.out)?;
    let report = AbReport {
        schema_version: SCHEMA_VERSION,
        base: base.label(),
        new: new.label(),
        base_binary: base.path.display().to_string(),
        new_binary: new.path.display().to_string(),
        pairs: opt.pairs,
        run_args: opt.run_args.clone(),
        drift,
        outcome: comparison.outcome().to_string(),
        regressions: comparison.regressions.clone(),
        seconds: started.elapsed().as_secs_f64(),
    };
    let path = opt.out.join("ab.json");
    write_file(&path, serde_json::to_string_pretty(&report)? + "\n")?;
    let fail = crate::regress::compare_report::gate(&comparison, opt.compare.fail_on)?;
    Ok(AbOutcome {
        comparison,
        report,
        fail,
    })
}

fn ratio_text(r: Option<f64>) -> String {
    r.map_or("-".into(), |r| format!("×{r:.3}"))
}

/// The drift table as printed.
pub fn drift_text(drift: &[PairDrift]) -> String {
    let mut s = String::from(
        "drift per pair: NEW/BASE = the median over rows of each row's median frame time; \
         each side also against its own first round (the machine over the session)\n",
    );
    for d in drift {
        s.push_str(&format!(
            "  pair {:>2} ({}): NEW/BASE {} over {} rows (rows {}–{}); BASE vs round 1 {}, \
             NEW vs round 1 {}\n",
            d.pair,
            d.order,
            ratio_text(d.ratio),
            d.rows,
            ratio_text(d.lowest_row_ratio),
            ratio_text(d.highest_row_ratio),
            ratio_text(d.base_vs_first_round),
            ratio_text(d.new_vs_first_round),
        ));
    }
    s
}

/// `tetbench ab`: prints the sides, the drift and compare's table; returns whether to exit 3.
pub fn run_command(base: &Binary, new: &Binary, opt: &AbOptions) -> anyhow::Result<bool> {
    let _lock = crate::run::lock::acquire(&opt.out, &["tetbench".into(), "ab".into()])?;
    println!("BASE {} ({})", base.label(), base.path.display());
    println!("NEW  {} ({})", new.label(), new.path.display());
    let outcome = run_ab(base, new, opt)?;
    println!(
        "{} pairs interleaved (BASE, NEW / NEW, BASE …) in {:.0} s",
        opt.pairs, outcome.report.seconds
    );
    print!("{}", drift_text(&outcome.report.drift));
    println!();
    print!(
        "{}",
        crate::regress::compare_report::terminal(&outcome.comparison)
    );
    for r in &outcome.comparison.regressions {
        println!("regression: {}", r.text);
    }
    println!(
        "wrote {}/compare.{{md,json,html}} and {}",
        opt.compare.out.display(),
        opt.out.join("ab.json").display()
    );
    Ok(outcome.fail)
}

#[cfg(test)]
#[path = "ab_tests.rs"]
mod tests;
