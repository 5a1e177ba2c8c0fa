//! Regression hunting across builds: `tetbench ab BASE NEW` runs two builds
//! interleaved on one machine and compares them with compare's test ([`ab`]); `tetbench bisect
//! GOOD BAD` searches the commits between for the first one an A/B calls a regression
//! ([`bisect`]). A side is a tetbench binary or a git revision, built in a worktree and cached
//! by commit ([`build`]).
//!
//! Why interleave: on the shared development VM two runs of one binary a minute apart differed
//! as a whole by ×0.53–×1.98 (docs/notes/2026-12-02-compare-gate-detection.md), far more than the changes worth catching.
//! Rounds of the two builds taken in turns (A B B A A B …) see the same stretches of that drift,
//! so it falls on both sides alike instead of on one.

use std::path::PathBuf;

use anyhow::Context;

pub mod ab;
pub mod bisect;
pub mod build;
pub mod compare;
pub mod compare_across;
pub mod compare_control;
pub mod compare_findings;
pub mod compare_image;
pub mod compare_model;
pub mod compare_report;
pub mod compare_rounds;
pub mod compare_setup;
pub mod compare_time;
pub mod compare_work;
pub mod export;
pub mod history;
pub mod history_page;
pub mod publish;
pub mod publish_runs;

// The run matrix of `ab` and `bisect` is `tetbench run`'s, handed on to every side's `run` as
// `MatrixArgs::run_args` (only the options given, so an older build that lacks a newer option
// still runs a matrix that does not use it); each side adds `--rounds 1 --no-report --out DIR`.
use crate::run::matrix::MatrixArgs;

/// compare's options as `ab` and `bisect` take them.
#[derive(Debug, Clone, clap::Args)]
pub struct JudgeArgs {
    /// Factor a group's median must move by (and p < alpha) to count as slower / faster.
    #[arg(long, default_value_t = 1.10)]
    pub threshold: f64,
    /// Significance level of the Mann–Whitney U test.
    #[arg(long, default_value_t = 0.05)]
    pub alpha: f64,
    /// Test NEW's absolute times, without dividing out the run-wide factor.
    #[arg(long)]
    pub no_drift_correction: bool,
    /// A run-wide factor beyond this (either way) is itself a regression or an improvement.
    #[arg(long, default_value_t = 1.5)]
    pub drift_limit: f64,
}

impl JudgeArgs {
    pub fn check(&self) -> anyhow::Result<()> {
        anyhow::ensure!(self.threshold >= 1.0, "--threshold must be at least 1");
        anyhow::ensure!(self.drift_limit >= 1.0, "--drift-limit must be at least 1");
        anyhow::ensure!(
            self.alpha > 0.0 && self.alpha < 1.0,
            "--alpha must lie between 0 and 1"
        );
        Ok(())
    }
}

/// `tetbench ab BASE NEW`.
#[derive(Debug, Clone, clap::Args)]
pub struct AbArgs {
    /// The reference build: a tetbench binary, or a git revision to build.
    pub base: String,
    /// The build to judge: a tetbench binary, or a git revision to build.
    pub new: String,
    /// Rounds per side, run in pairs A B, B A, … (at least 3: compare's minimum).
    #[arg(long, default_value_t = 5)]
    pub pairs: u32,
    /// Output directory: each side's rounds and merged results, compare's files, ab.json.
    #[arg(long, value_name = "DIR", default_value = "ab")]
    pub out: PathBuf,
    /// Exit with status 3 on a regression (default) or on any change; `never`: always 0.
    #[arg(long, value_enum, default_value = "regression")]
    pub fail_on: crate::regress::compare::FailOn,
    #[command(flatten)]
    pub judge: JudgeArgs,
    #[command(flatten)]
    pub matrix: MatrixArgs,
    #[command(flatten)]
    pub build: build::BuildArgs,
}

/// `tetbench bisect GOOD BAD`.
#[derive(Debug, Clone, clap::Args)]
pub struct BisectArgs {
    /// A revision without the regression.
    pub good: String,
    /// A later revision with it (a descendant of GOOD).
    pub bad: String,
    /// Rounds per side in each step's A/B.
    #[arg(long, default_value_t = 5)]
    pub pairs: u32,
    /// Output directory: one A/B folder per step, bisect.json.
    #[arg(long, value_name = "DIR", default_value = "bisect")]
    pub out: PathBuf,
    #[command(flatten)]
    pub judge: JudgeArgs,
    #[command(flatten)]
    pub matrix: MatrixArgs,
    #[command(flatten)]
    pub build: build::BuildArgs,
}

fn ab_options(
    out: PathBuf,
    pairs: u32,
    judge: &JudgeArgs,
    fail_on: crate::regress::compare::FailOn,
    matrix: &MatrixArgs,
    data_dir: Option<PathBuf>,
) -> anyhow::Result<ab::AbOptions> {
    judge.check()?;
    anyhow::ensure!(
        matrix.rounds.is_none(),
        "--rounds: each side runs one round per invocation; --pairs sets how many"
    );
    Ok(ab::AbOptions {
        pairs,
        global_args: data_dir
            .map(|d| vec!["--data-dir".to_string(), d.display().to_string()])
            .unwrap_or_default(),
        run_args: matrix.run_args(),
        compare: crate::regress::compare::CompareOptions {
            threshold: judge.threshold,
            alpha: judge.alpha,
            normalised: false,
            drift_correction: !judge.no_drift_correction,
            drift_limit: judge.drift_limit,
            // BASE's round i and NEW's round i run back to back: the pairs are real.
            paired: true,
            fail_on,
            out: out.join("compare"),
        },
        out,
    })
}

/// `tetbench ab`; returns whether to exit with status 3.
pub fn run_ab_command(args: AbArgs, data_dir: Option<PathBuf>) -> anyhow::Result<bool> {
    let opt = ab_options(
        args.out.clone(),
        args.pairs,
        &args.judge,
        args.fail_on,
        &args.matrix,
        data_dir,
    )?;
    let base = build::resolve(&args.base, &args.build).context("resolving BASE")?;
    let new = build::resolve(&args.new, &args.build).context("resolving NEW")?;
    ab::run_command(&base, &new, &opt)
}

/// `tetbench bisect`.
pub fn run_bisect_command(args: BisectArgs, data_dir: Option<PathBuf>) -> anyhow::Result<()> {
    let ab = ab_options(
        args.out.clone(),
        args.pairs,
        &args.judge,
        crate::regress::compare::FailOn::Regression,
        &args.matrix,
        data_dir,
    )?;
    let _lock = crate::run::lock::acquire(&args.out, &["tetbench".into(), "bisect".into()])?;
    bisect::run_command(&bisect::BisectOptions {
        good: args.good,
        bad: args.bad,
        build: args.build,
        ab,
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    /// history puts each run with a control on the first such run's scale: a run on a machine
    /// half as fast with twice the times reads as the first run; a run without a control keeps
    /// its times; and with the control at the first run's speed the doubled times stand.
    #[test]
    fn history_divides_out_the_machine_run_by_run() {
        use crate::regress::history::{divide_out_the_machine, GroupValues, Run, RunSummary};
        use crate::results::machine::Figure;
        let run = |ms: f64, control: Option<f64>| RunSummary {
            run: Run {
                dir: String::new(),
                commit: String::new(),
                date_utc: String::new(),
                label: String::new(),
                machine: None,
            },
            adapter: String::new(),
            control: control.map(|speed| {
                [
                    (Figure::FillFragmentsPerSec, 100.0 * speed),
                    (Figure::RayStepsPerSec, 10.0 * speed),
                ]
                .into()
            }),
            groups: vec![(
                crate::regress::history::SeriesKey {
                    algorithm: "a".into(),
                    settings: String::new(),
                    dataset: "d".into(),
                    width: 1,
                    height: 1,
                    projection: String::new(),
                },
                Some(GroupValues {
                    total_ms: ms,
                    band_lo: ms,
                    band_hi: ms,
                    psnr_db: None,
                    gpu_bytes: None,
                }),
            )],
        };
        let time = |r: &RunSummary| r.groups[0].1.as_ref().unwrap().total_ms;
        let mut runs = vec![run(10.0, Some(1.0)), run(20.0, Some(0.5)), run(20.0, None)];
        divide_out_the_machine(&mut runs);
        assert_eq!(
            runs.iter().map(time).collect::<Vec<_>>(),
            [10.0, 10.0, 20.0]
        );
        assert_eq!(runs[1].run.machine, Some(0.5));
        assert_eq!(runs[2].run.machine, None);
        let mut same_machine = vec![run(10.0, Some(1.0)), run(20.0, Some(1.0))];
        divide_out_the_machine(&mut same_machine);
        assert_eq!(time(&same_machine[1]), 20.0);
    }

    use super::*;

    /// Only the options given travel to the sides' `run`, flags without a value.
    #[test]
    fn matrix_args_pass_only_what_was_given() {
        assert!(MatrixArgs::default().run_args().is_empty());
        let m = MatrixArgs {
            algorithms: vec!["gator-pt".into(), "havs".into()],
            resolution: Some(64),
            no_reference: true,
            ..Default::default()
        };
        assert_eq!(
            m.run_args(),
            [
                "--algorithms",
                "gator-pt,havs",
                "--resolution",
                "64",
                "--no-reference"
            ]
        );
    }
}
