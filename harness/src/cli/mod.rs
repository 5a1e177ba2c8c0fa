//! The `tetbench` command line (clap derive) and its dispatch.

use std::path::PathBuf;

pub mod datasets;
pub mod external;
pub mod plot;

use anyhow::Context;
use clap::{Parser, Subcommand};

use self::datasets::DatasetsCommand;
use crate::analyze::{self, AnalyzeCommand};
use crate::run::matrix::MatrixArgs;
pub use crate::run::plan::default_cache_dir;
use crate::run::plan::RunPlan;
use crate::run::shard::INCOMPLETE;
use crate::run::{self, RunConfig};

#[derive(Debug, Parser)]
#[command(
    name = "tetbench",
    version = env!("TETBENCH_VERSION_LINE"),
    about = "Benchmarks GPU volume renderers for tetrahedral meshes against an exact CPU reference",
    long_about = None
)]
pub struct Cli {
    /// Directory of the real data sets (default: $TETBENCH_DATA, else ../shared/datasets).
    #[arg(long, global = true, value_name = "DIR")]
    pub data_dir: Option<PathBuf>,

    #[command(subcommand)]
    pub command: Command,
}

/// `tetbench analyze`: the CPU analyses and summaries, and one subcommand per paper.
#[derive(Debug, Subcommand)]
pub enum AnalyzeAny {
    #[command(flatten)]
    Tool(AnalyzeCommand),
    #[command(flatten)]
    Paper(crate::papers::from_run::PaperAnalysis),
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Measure algorithms over data sets and viewpoints; write results.csv, results.json,
    /// images and index.html. With no options: the embedded default suite on generated meshes.
    Run(RunArgs),
    /// Inspect, list and convert data sets.
    #[command(subcommand)]
    Datasets(DatasetsCommand),
    /// Analyses that reproduce the papers' tables: `analyze PAPER RUN_DIR` writes a paper's
    /// tables and claims from finished runs (the same code as `reproduce`); the others are the
    /// CPU analyses and summaries.
    #[command(subcommand)]
    Analyze(AnalyzeAny),
    /// Reproduce a paper's tables with one command: runs what they need, then writes
    /// OUT/<paper>/report.md and report.html with the paper's values beside ours.
    Reproduce(crate::papers::reproduce::Args),
    /// Re-render the report (charts, index.html) of an earlier run from its results.json, or
    /// merge shards / runs of several machines: `report --merge DIR… --out OUT`.
    Report {
        /// The run's output directory (not with --merge).
        #[arg(required_unless_present = "merge", conflicts_with = "merge")]
        dir: Option<PathBuf>,
        /// Result directories to merge (shards of one run, or one run on several machines).
        #[arg(long, num_args = 1.., value_name = "DIR", requires = "out")]
        merge: Vec<PathBuf>,
        /// Where the merged results and report go.
        #[arg(long, value_name = "OUT")]
        out: Option<PathBuf>,
        /// Merge even when a shard is missing or a run did not finish; the missing units are
        /// listed in the merged results' errors (without it such a merge is refused).
        #[arg(long, requires = "merge")]
        allow_missing: bool,
    },
    /// Compare two runs: faster / slower / no change per row and group (Mann–Whitney U and a
    /// factor threshold), image and memory changes; writes compare.{md,json,html}.
    Compare(CompareArgs),
    /// Measure the backend (triangle setup, fill, rasterisation of small triangles, compute,
    /// storage copy, CPU and GPU radix sort, ray steps, splat fill) in under a minute; cached
    /// per adapter and driver, recorded in every run.
    Calibrate {
        /// Where the calibration is cached (default: the reference cache directory).
        #[arg(long, value_name = "DIR")]
        cache_dir: Option<PathBuf>,
        /// Measure even when a cached calibration exists.
        #[arg(long)]
        force: bool,
        /// Print JSON instead of the table.
        #[arg(long)]
        json: bool,
        /// Measure the per-frame floor instead (submit, wait, an empty frame's clear, empty
        /// passes, readbacks, timestamps; docs/gpu.md), not cached.
        #[arg(long)]
        floor: bool,
        /// The floor's square viewport in pixels.
        #[arg(long, value_name = "PIXELS", default_value_t = 512, requires = "floor")]
        resolution: u32,
    },
    /// Metrics over a series of runs of one adapter (ordered by date, e.g. the baselines) per
    /// algorithm × data set: compare's test for each adjacent pair and the steps of the whole
    /// series.
    History {
        /// Result directories (put in order by the date each run started).
        #[arg(required = true, value_name = "DIR")]
        dirs: Vec<PathBuf>,
        /// Output directory for history.{html,md,csv,json} and the SVG charts.
        #[arg(long, value_name = "DIR", default_value = "history")]
        out: PathBuf,
        /// Factor a median must move by to count as a change.
        #[arg(long, default_value_t = 1.10)]
        threshold: f64,
    },
    /// Print a results set for a continuous-benchmarking service: Bencher's BMF or
    /// github-action-benchmark's customSmallerIsBetter (docs/regression.md, "Exports").
    Export {
        #[arg(long, value_enum)]
        format: crate::regress::export::ExportFormat,
        /// The run's output directory (holding results.json).
        results: PathBuf,
    },
    /// Draw comparison charts (speed-error, scaling, resolution, bars, all) from any results,
    /// or run a sweep first (--sweep).
    Plot(crate::cli::plot::PlotArgs),
    /// Renderers in other processes and languages (docs/external-renderers.md): `check`.
    #[command(subcommand)]
    External(crate::cli::external::ExternalCommand),
    /// Run two builds (binaries or git revisions) in turns, A B B A …, over one matrix and
    /// compare them with compare's test (docs/regression.md, "A/B").
    Ab(crate::regress::AbArgs),
    /// Find the first commit between GOOD and BAD that an A/B against GOOD calls a regression.
    Bisect(crate::regress::BisectArgs),
    /// Write one static site over baselines, runs and reproduced papers (docs/commands.md,
    /// "publish"): per adapter the latest run, histories, verdicts, speed vs error.
    Publish(crate::regress::publish::PublishArgs),
}

#[derive(Debug, Clone, clap::Args)]
pub struct CompareArgs {
    /// The reference run's output directory (e.g. reports/baselines/ADAPTER-DATE).
    pub base: PathBuf,
    /// The run to judge.
    pub new: PathBuf,
    /// Factor the median must move by (and p < alpha) to count as slower / faster.
    #[arg(long, default_value_t = 1.10)]
    pub threshold: f64,
    /// Significance level of the Mann–Whitney U test.
    #[arg(long, default_value_t = 0.05)]
    pub alpha: f64,
    /// Exit with status 3 on a regression (or on any change); 1 means an error or a refused
    /// comparison, 0 neither (docs/regression.md, "Exit codes").
    #[arg(long, value_enum, default_value = "never")]
    pub fail_on: crate::regress::compare::FailOn,
    /// Compare runs from different adapters on calibration-normalised times.
    #[arg(long)]
    pub normalised: bool,
    /// Test NEW's absolute times, without dividing out the run-wide factor (the median
    /// change over all groups): for a dedicated machine whose speed does not drift.
    #[arg(long)]
    pub no_drift_correction: bool,
    /// A run-wide factor beyond this (either way) is itself reported as a regression or an
    /// improvement of every group (default 1.5: the largest drift measured between two runs
    /// on the 2-core development VM was ×1.25).
    #[arg(long, default_value_t = 1.5)]
    pub drift_limit: f64,
    /// BASE's round i and NEW's round i ran side by side (the merged sides of `tetbench ab`):
    /// divide each pair's own drift out instead of the run-wide factor.
    #[arg(long)]
    pub paired: bool,
    /// Output directory (default: NEW/compare).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// What goes to stdout: the terminal table, compare.json, or compare.md (for a pull
    /// request comment). The files are written to --out in every case.
    #[arg(long, value_enum, default_value = "text")]
    pub format: crate::regress::compare_report::CompareFormat,
}

#[derive(Debug, Clone, clap::Args)]
pub struct RunArgs {
    /// What is measured (shared with `plot --sweep`, `analyze resolution`, `ab` and `bisect`).
    #[command(flatten)]
    pub matrix: MatrixArgs,
    /// Output directory (results, images, report). Earlier results there are replaced
    /// (unless --resume). One run at a time: a second run into a busy directory refuses.
    #[arg(long, value_name = "DIR", default_value = "out")]
    pub out: PathBuf,
    /// Continue an interrupted run: keep the finished (data set, algorithm, settings) units of
    /// the results already in --out and measure the rest; refused if the plan differs.
    #[arg(long)]
    pub resume: bool,
    /// Do not write the HTML report and charts.
    #[arg(long)]
    pub no_report: bool,
    /// Exit non-zero when a row is suspect (its PSNR far below the best algorithm's on the same
    /// image, or below 20 dB); without it suspect rows are flagged and the run still succeeds.
    #[arg(long)]
    pub strict: bool,
    /// Run only the i-th of N disjoint parts of the run matrix (e.g. 2/4), for CI matrices and
    /// job arrays; merge the parts with `report --merge`.
    #[arg(long, value_name = "i/N")]
    pub shard: Option<String>,
}

impl RunArgs {
    /// The plain run request these arguments describe.
    pub fn to_plan(&self) -> RunPlan {
        RunPlan {
            no_report: self.no_report,
            strict: self.strict,
            shard: self.shard.clone(),
            ..self.matrix.plan(self.out.clone())
        }
    }

    /// [`RunPlan::to_config`] of [`Self::to_plan`].
    pub fn to_config(
        &self,
        data_dir: Option<PathBuf>,
        command_line: Vec<String>,
    ) -> anyhow::Result<RunConfig> {
        let mut config = self.to_plan().to_config(data_dir, command_line)?;
        config.resume = self.resume;
        Ok(config)
    }
}

/// The exit status of an error, and of a bad option or argument: 1 (docs/regression.md, "Exit
/// codes"), so that 3 alone means a regression. clap's own usage status is 2.
pub const EXIT_ERROR: u8 = 1;

/// How a command ended when it did not fail; `main` turns it into the exit status (an error is
/// [`EXIT_ERROR`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Status 0; also `--help` and `--version`.
    Done,
    /// `compare --fail-on` or `ab` met its gate: status
    /// [`EXIT_REGRESSION`](crate::regress::compare::EXIT_REGRESSION), the documented CI gate.
    Regression,
    /// A bad option or argument, clap's message printed: status [`EXIT_ERROR`].
    Usage,
}

impl Outcome {
    /// [`Outcome::Regression`] when a command's gate was met, else [`Outcome::Done`].
    pub fn gate(met: bool) -> Outcome {
        if met {
            Outcome::Regression
        } else {
            Outcome::Done
        }
    }

    /// The process's exit status for this outcome.
    pub fn exit_code(self) -> std::process::ExitCode {
        std::process::ExitCode::from(match self {
            Outcome::Done => 0,
            Outcome::Regression => crate::regress::compare::EXIT_REGRESSION as u8,
            Outcome::Usage => EXIT_ERROR,
        })
    }
}

/// Parses `args` (program name first) and runs the command. `--help` and `--version` print and
/// are [`Outcome::Done`]; a bad option prints clap's message and is [`Outcome::Usage`].
pub fn main_with_args<I, T>(args: I) -> anyhow::Result<Outcome>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let args: Vec<std::ffi::OsString> = args.into_iter().map(Into::into).collect();
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) => {
            e.print()
                .context("printing the command line's help or error")?;
            return Ok(if e.use_stderr() {
                Outcome::Usage
            } else {
                Outcome::Done
            });
        }
    };
    let command_line = args
        .iter()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    execute(cli, command_line)
}

pub fn execute(cli: Cli, command_line: Vec<String>) -> anyhow::Result<Outcome> {
    let done = |r: anyhow::Result<()>| r.map(|()| Outcome::Done);
    match cli.command {
        Command::Run(args) => done(run_command(&args, cli.data_dir, command_line)),
        Command::Datasets(cmd) => done(self::datasets::run(cmd, cli.data_dir)),
        Command::Analyze(AnalyzeAny::Tool(cmd)) => done(analyze::run(
            cmd,
            &analyze::Context {
                data_dir: cli.data_dir,
            },
        )),
        Command::Analyze(AnalyzeAny::Paper(cmd)) => done(crate::papers::from_run::run(cmd)),
        Command::Reproduce(args) => done(crate::papers::reproduce::run(args, cli.data_dir)),
        Command::Report {
            dir,
            merge,
            out,
            allow_missing,
        } => done(report_command(dir, &merge, out, allow_missing)),
        Command::Compare(args) => compare_command(&args),
        Command::Calibrate {
            floor: true,
            resolution,
            json,
            ..
        } => done(crate::calibrate::floor::run_command(
            resolution,
            crate::calibrate::floor::FLOOR_REPS,
            json,
        )),
        Command::Calibrate {
            cache_dir,
            force,
            json,
            ..
        } => {
            let cache = cache_dir.unwrap_or_else(|| default_cache_dir(std::path::Path::new(".")));
            done(crate::calibrate::run_command(&cache, force, json))
        }
        Command::History {
            dirs,
            out,
            threshold,
        } => done(crate::regress::history_page::run_command(
            &dirs, &out, threshold, 0.05,
        )),
        Command::Export { format, results } => {
            print!("{}", crate::regress::export::run_command(&results, format)?);
            Ok(Outcome::Done)
        }
        Command::Plot(args) => done(crate::cli::plot::run(args, cli.data_dir, command_line)),
        Command::External(cmd) => done(crate::cli::external::run(cmd)),
        Command::Ab(args) => Ok(Outcome::gate(crate::regress::run_ab_command(
            args,
            cli.data_dir,
        )?)),
        Command::Bisect(args) => done(crate::regress::run_bisect_command(args, cli.data_dir)),
        Command::Publish(args) => done(crate::regress::publish::run_command(&args)),
    }
}

/// `tetbench run`: the run, then what it found that the user must see (suspect rows, a
/// recalibration, rows beating their bound); failed rows, or suspect ones with `--strict`,
/// are an error.
fn run_command(
    args: &RunArgs,
    data_dir: Option<PathBuf>,
    command_line: Vec<String>,
) -> anyhow::Result<()> {
    let config = args.to_config(data_dir, command_line)?;
    let filter = config.settings_filter.clone();
    let outcome = run::run(&config, &|name: &str| args.matrix.variants(name, &filter))?;
    println!(
        "{} rows in {:.1} s; results in {} (open {})",
        outcome.rows,
        outcome.seconds,
        config.out.join("results.csv").display(),
        config.out.join("index.html").display()
    );
    if !outcome.suspect_rows.is_empty() {
        eprintln!(
            "{} suspect row(s) — image error far out of line with the other algorithms \
             on the same image (see the `suspect` column and {}):",
            outcome.suspect_rows.len(),
            config.out.join("index.html").display()
        );
        for s in &outcome.suspect_rows {
            eprintln!("  {s}");
        }
    }
    if let Some(what) = &outcome.recalibrated {
        eprintln!("tetbench: {what}");
    }
    if !outcome.beaten_bounds.is_empty() {
        eprintln!(
            "{} row(s) beat their roofline bound — a defect of the bound (a calibrated \
             figure that is not the backend's peak, or a counter of work not done; \
             docs/roofline.md):",
            outcome.beaten_bounds.len()
        );
        for s in &outcome.beaten_bounds {
            eprintln!("  {s}");
        }
    }
    if outcome.rows == 0 && !outcome.errors.is_empty() {
        anyhow::bail!("nothing was measured:\n  {}", outcome.errors.join("\n  "));
    }
    if !outcome.all_ok() {
        let mut msg = format!("{} of {} rows failed", outcome.failed_rows, outcome.rows);
        for e in &outcome.errors {
            msg.push_str(&format!("\n  {e}"));
        }
        anyhow::bail!("{msg} (finished rows are in {})", config.out.display());
    }
    if config.strict && !outcome.suspect_rows.is_empty() {
        anyhow::bail!(
            "--strict: {} suspect row(s) (listed above)",
            outcome.suspect_rows.len()
        );
    }
    Ok(())
}

/// `tetbench report`: `--merge` shards or runs into `--out`, else re-render `DIR`'s report.
fn report_command(
    dir: Option<PathBuf>,
    merge: &[PathBuf],
    out: Option<PathBuf>,
    allow_missing: bool,
) -> anyhow::Result<()> {
    if !merge.is_empty() {
        let out = out.context("report --merge needs --out OUT")?;
        let merged = crate::run::shard::merge(merge, &out, allow_missing)?;
        for gap in merged.errors.iter().filter(|e| e.starts_with(INCOMPLETE)) {
            eprintln!("tetbench: {gap}");
        }
        crate::report::write(&out, &merged)
            .with_context(|| format!("writing the report in {}", out.display()))?;
        println!(
            "merged {} rows from {} directories into {}",
            merged.rows.len(),
            merge.len(),
            out.join("results.json").display()
        );
        return Ok(());
    }
    let out = dir.context("tetbench report needs a directory")?;
    crate::report::rewrite(&out)
        .with_context(|| format!("re-rendering the report in {}", out.display()))?;
    println!("wrote {}", out.join("index.html").display());
    Ok(())
}

/// `tetbench compare`: [`Outcome::Regression`] when its `--fail-on` gate is met.
fn compare_command(args: &CompareArgs) -> anyhow::Result<Outcome> {
    let opt = crate::regress::compare::CompareOptions {
        threshold: args.threshold,
        alpha: args.alpha,
        normalised: args.normalised,
        drift_correction: !args.no_drift_correction,
        drift_limit: args.drift_limit,
        paired: args.paired,
        fail_on: args.fail_on,
        out: args.out.clone().unwrap_or_else(|| args.new.join("compare")),
    };
    anyhow::ensure!(args.threshold >= 1.0, "--threshold must be at least 1");
    anyhow::ensure!(args.drift_limit >= 1.0, "--drift-limit must be at least 1");
    let regressed =
        crate::regress::compare_report::run_command(&args.base, &args.new, &opt, args.format)?;
    Ok(Outcome::gate(regressed))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithms;

    #[test]
    fn cli_definition_is_consistent() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }

    /// `--help` and `--version` are done (status 0); a bad option is a usage error (status 1,
    /// not clap's 2), and so is a bad option of a subcommand.
    #[test]
    fn help_is_done_and_a_bad_option_is_status_1() {
        use std::process::ExitCode;
        for (args, outcome, code) in [
            (&["tetbench", "--version"][..], Outcome::Done, 0),
            (&["tetbench", "compare", "--help"][..], Outcome::Done, 0),
            (&["tetbench", "--no-such-option"][..], Outcome::Usage, 1),
            (
                &["tetbench", "compare", "--threshold"][..],
                Outcome::Usage,
                1,
            ),
        ] {
            let got = main_with_args(args).unwrap();
            assert_eq!(got, outcome, "{args:?}");
            assert_eq!(got.exit_code(), ExitCode::from(code), "{args:?}");
        }
        assert_eq!(Outcome::gate(true).exit_code(), ExitCode::from(3));
        assert_eq!(Outcome::gate(false), Outcome::Done);
    }

    fn run_algorithms(args: &[&str]) -> anyhow::Result<Vec<String>> {
        let mut all = vec!["tetbench", "run", "--datasets", "box:1k"];
        all.extend_from_slice(args);
        let Command::Run(run) = Cli::try_parse_from(all).unwrap().command else {
            unreachable!()
        };
        Ok(run.to_config(None, vec![])?.algorithms)
    }

    /// `--all-variants` starts from every variant, `--settings` alone from the defaults'
    /// neighbourhood: HAVS offers more variants than it runs by default.
    #[test]
    fn all_variants_starts_from_every_variant() {
        let Command::Run(run) =
            Cli::try_parse_from(["tetbench", "run", "--all-variants", "--datasets", "box:1k"])
                .unwrap()
                .command
        else {
            unreachable!()
        };
        assert!(run.matrix.all_variants);
        let every_variant = run.matrix;
        let defaults = MatrixArgs::default();
        let none = algorithms::SettingsFilter::default();
        for name in algorithms::names() {
            let every = every_variant.variants(name, &none).unwrap().len();
            assert_eq!(every, algorithms::all_variants(name).unwrap().len());
            assert_eq!(
                defaults.variants(name, &none).unwrap().len(),
                algorithms::variants(name).unwrap().len()
            );
        }
        assert!(
            every_variant.variants("havs", &none).unwrap().len()
                > defaults.variants("havs", &none).unwrap().len()
        );
    }

    #[test]
    fn peers_join_a_run_only_when_asked_for() {
        let plain = run_algorithms(&[]).unwrap();
        assert!(!plain.is_empty() && plain.iter().all(|a| !algorithms::is_peer(a)));
        let with = run_algorithms(&["--peers", "vtk"]).unwrap();
        assert_eq!(with.len(), plain.len() + 3);
        assert!(with.ends_with(&["vtk-pt".into(), "vtk-raycast".into(), "vtk-zsweep".into()]));
        let one = run_algorithms(&["--algorithms", "vtk-pt", "--peers", "vtk"]).unwrap();
        assert_eq!(one, ["vtk-pt", "vtk-raycast", "vtk-zsweep"]);
        assert!(run_algorithms(&["--peers", "nope"]).is_err());
    }

    #[test]
    fn external_renderers_join_a_run_as_peers() {
        let plain = run_algorithms(&[]).unwrap();
        let with = run_algorithms(&[
            "--external",
            "ext-a=python3 r.py",
            "--external",
            "ext-a[step=0.5]=python3 r.py",
            "--external",
            "ext-b=./b",
        ])
        .unwrap();
        assert_eq!(with.len(), plain.len() + 2);
        assert!(with.ends_with(&["ext-a".into(), "ext-b".into()]));
        assert!(algorithms::is_peer("ext-a") && algorithms::is_peer("ext-b"));
        let only = run_algorithms(&["--algorithms", "ext-b", "--external", "ext-b=./b"]).unwrap();
        assert_eq!(only, ["ext-b"]);
        assert!(run_algorithms(&["--external", "havs=./b"]).is_err());
        assert!(run_algorithms(&["--external", "noequals"]).is_err());
        assert!(run_algorithms(&["--external", "x=./b", "--external-timeout", "0"]).is_err());
    }
}
