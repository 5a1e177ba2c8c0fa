//! `tetbench bisect GOOD BAD`: which commit between GOOD and BAD made things worse?
//!
//! The candidates are `git rev-list --first-parent GOOD..BAD` (a merge is one step, as asv's
//! `find` does along the first parent), oldest first. BAD is tried first: when an A/B of GOOD
//! against BAD finds no regression there is nothing to search for, and the search says so
//! instead of naming a commit. Then a binary search, each step an A/B of GOOD against the
//! candidate ([`super::ab`], compare's test and its verdict), ends at the first commit whose
//! A/B is a regression — assuming, as any bisection does, that once bad the series stays bad.

use std::path::PathBuf;

use anyhow::Context;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::ab::{self, AbOptions};
use super::build::{self, BuildArgs};
use crate::report::progress::Progress;
use crate::results::write_file;

/// The first-parent commits after `good` up to and including `bad`, oldest first.
pub fn candidates(repo: &std::path::Path, good: &str, bad: &str) -> anyhow::Result<Vec<String>> {
    let (g, b) = (build::commit_of(repo, good)?, build::commit_of(repo, bad)?);
    let list = build::git(
        repo,
        &[
            "rev-list",
            "--first-parent",
            "--reverse",
            &format!("{g}..{b}"),
        ],
    )?;
    let commits: Vec<String> = list.lines().map(str::to_string).collect();
    anyhow::ensure!(
        !commits.is_empty(),
        "no commits between {good} and {bad} along the first parent (is {bad} a descendant of \
         {good}?)"
    );
    Ok(commits)
}

/// The most candidates [`first_bad`] asks about among `n`: the last, then ⌈log2 n⌉.
pub fn max_steps(n: usize) -> usize {
    if n == 0 {
        0
    } else {
        1 + (usize::BITS - (n - 1).leading_zeros()) as usize
    }
}

/// The binary search: index of the first of `n` candidates for which `is_bad` holds, given
/// that all after it are bad too; `None` when the last one is not bad. Asks for the last one
/// first, then about log2(n) more.
pub fn first_bad(
    n: usize,
    mut is_bad: impl FnMut(usize) -> anyhow::Result<bool>,
) -> anyhow::Result<Option<usize>> {
    if n == 0 || !is_bad(n - 1)? {
        return Ok(None);
    }
    // Invariant: lo is good (-1 stands for GOOD itself), hi is bad.
    let (mut lo, mut hi) = (-1isize, n as isize - 1);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if is_bad(mid as usize)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(Some(hi as usize))
}

/// One A/B of the search.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Step {
    pub commit: String,
    pub subject: String,
    pub regression: bool,
    /// compare's regressions (empty: none).
    pub regressions: Vec<crate::regress::compare::Finding>,
    /// The A/B's output directory.
    pub dir: String,
}

/// The layout of `bisect.json` (`docs/bisect.schema.json`).
pub const SCHEMA_VERSION: u32 = 1;

/// The JSON Schema of `bisect.json`.
pub fn json_schema() -> serde_json::Value {
    serde_json::to_value(schemars::schema_for!(BisectReport)).expect("a schema is JSON")
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BisectReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    pub good: String,
    pub bad: String,
    pub candidates: usize,
    pub steps: Vec<Step>,
    pub first_bad: Option<String>,
    pub first_bad_subject: Option<String>,
}

pub struct BisectOptions {
    pub good: String,
    pub bad: String,
    pub build: BuildArgs,
    /// The A/B of each step; its `out` is the bisection's directory (each step gets a folder
    /// in it) and its compare options decide every step.
    pub ab: AbOptions,
}

/// Runs the search, printing each step's verdict; writes `OUT/bisect.json`.
pub fn run_command(opt: &BisectOptions) -> anyhow::Result<BisectReport> {
    let repo = &opt.build.repo;
    let commits = candidates(repo, &opt.good, &opt.bad)?;
    println!(
        "bisect: {} commit(s) after {} up to {} (first parent); each step an A/B of {} pairs \
         against {}",
        commits.len(),
        opt.good,
        opt.bad,
        opt.ab.pairs,
        opt.good
    );
    let good = build::resolve(&opt.good, &opt.build)?;
    let mut steps: Vec<Step> = vec![];
    // Lines only: each step's A/B shows its own bar. The total is the search's bound (the last
    // commit, then a binary search), so the ETA is an upper bound too.
    let mut progress = Progress::lines("bisect", max_steps(commits.len()) as u64);
    let found = first_bad(commits.len(), |i| {
        let commit = &commits[i];
        let subject = build::git(repo, &["log", "-1", "--format=%s", commit]).unwrap_or_default();
        progress.begin(&format!(
            "A/B of {} against {}: {subject}",
            &commit[..12.min(commit.len())],
            opt.good
        ));
        let candidate = build::resolve(commit, &opt.build)?;
        let dir = opt.ab.out.join(format!(
            "step-{:02}-{}",
            steps.len() + 1,
            &commit[..12.min(commit.len())]
        ));
        let step_opt = AbOptions {
            out: dir.clone(),
            global_args: opt.ab.global_args.clone(),
            run_args: opt.ab.run_args.clone(),
            pairs: opt.ab.pairs,
            compare: crate::regress::compare::CompareOptions {
                out: dir.join("compare"),
                ..opt.ab.compare.clone()
            },
        };
        let outcome = ab::run_ab(&good, &candidate, &step_opt)
            .with_context(|| format!("the A/B of {} against {}", opt.good, commit))?;
        let regressions = outcome.comparison.regressions.clone();
        let step = Step {
            commit: commit.clone(),
            subject,
            regression: !regressions.is_empty(),
            regressions,
            dir: dir.display().to_string(),
        };
        println!(
            "step {}: {} {} — {}",
            steps.len() + 1,
            &step.commit[..12.min(step.commit.len())],
            step.subject,
            if step.regression {
                format!(
                    "REGRESSION ({})",
                    step.regressions
                        .iter()
                        .map(|f| f.text.as_str())
                        .collect::<Vec<_>>()
                        .join("; ")
                )
            } else {
                "no regression".into()
            }
        );
        let bad = step.regression;
        steps.push(step);
        progress.skip(1);
        Ok(bad)
    })?;
    let subject = |c: &str| build::git(repo, &["log", "-1", "--format=%s", c]).unwrap_or_default();
    let report = BisectReport {
        schema_version: SCHEMA_VERSION,
        good: opt.good.clone(),
        bad: opt.bad.clone(),
        candidates: commits.len(),
        first_bad: found.map(|i| commits[i].clone()),
        first_bad_subject: found.map(|i| subject(&commits[i])),
        steps,
    };
    match (&report.first_bad, &report.first_bad_subject) {
        (Some(c), Some(s)) => println!("first bad commit: {c} {s}"),
        _ => println!(
            "no regression: {} is not worse than {} by compare's test, nothing to bisect",
            opt.bad, opt.good
        ),
    }
    std::fs::create_dir_all(&opt.ab.out)
        .with_context(|| format!("cannot create {}", opt.ab.out.display()))?;
    let path: PathBuf = opt.ab.out.join("bisect.json");
    write_file(&path, serde_json::to_string_pretty(&report)? + "\n")?;
    println!("wrote {}", path.display());
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The search finds the first bad index for every position of the change, asking about
    /// ⌈log2 n⌉ + 1 candidates at most, and says None when the last one is fine.
    #[test]
    fn first_bad_finds_every_position() {
        for n in 1..=20usize {
            for k in 0..n {
                let mut asked = 0;
                let got = first_bad(n, |i| {
                    asked += 1;
                    Ok(i >= k)
                })
                .unwrap();
                assert_eq!(got, Some(k), "n={n} k={k}");
                let bound = (n as f64).log2().ceil() as usize + 1;
                assert!(asked <= bound, "n={n} k={k}: asked {asked} > {bound}");
                assert_eq!(max_steps(n), bound, "n={n}");
            }
            assert_eq!(first_bad(n, |_| Ok(false)).unwrap(), None);
        }
        assert_eq!(first_bad(0, |_| Ok(true)).unwrap(), None);
    }

    /// An error in a step ends the search with that error.
    #[test]
    fn a_failing_step_is_an_error() {
        let e = first_bad(8, |i| {
            if i == 3 {
                anyhow::bail!("build of step 3 failed")
            }
            Ok(i >= 2)
        });
        assert!(e.unwrap_err().to_string().contains("step 3"));
    }
}
