//! What to run, before checking: the matrix ([`MatrixArgs`], built by every command that runs
//! one) plus where and how to write it, turned into a checked [`RunConfig`] by
//! [`RunPlan::to_config`]. [`MatrixArgs::plan`] is the one place a plan is built.
//!
//! It lives outside `cli` so that the analyses and the paper runs do not depend on the command
//! line's argument struct (which depends on them to dispatch).

use std::path::PathBuf;

use external_peer::ExternalSpec;
use render_core::{Projection, TransferFunction};

use crate::algorithms::{self, SettingsFilter};
use crate::results::Viewpoints;
use crate::run::matrix::{MatrixArgs, DEFAULT_TF};
use crate::run::suite::{self, DEFAULT_SUITE};
use crate::run::RunConfig;

/// A run as asked for: in the matrix, `None` and empty lists mean "the default" (the default
/// suite's when no data set is named, the papers' standard otherwise).
#[derive(Debug, Clone, PartialEq)]
pub struct RunPlan {
    /// What is measured.
    pub matrix: MatrixArgs,
    pub out: PathBuf,
    pub no_report: bool,
    pub strict: bool,
    /// `i/N` as `--shard`.
    pub shard: Option<String>,
}

/// The reference cache: `--cache-dir`, `$TETBENCH_CACHE`, `$XDG_CACHE_HOME/tetbench`,
/// `~/.cache/tetbench`, or (no home) `OUT/.reference-cache`.
pub fn default_cache_dir(out: &std::path::Path) -> PathBuf {
    let env = |k: &str| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    env("TETBENCH_CACHE")
        .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("tetbench")))
        .or_else(|| env("HOME").map(|d| d.join(".cache").join("tetbench")))
        .unwrap_or_else(|| out.join(".reference-cache"))
}

impl MatrixArgs {
    /// The run these options ask for, written to `out`, without a report (the one place a
    /// [`RunPlan`] is built; `tetbench run` then sets its own output options). It is here, not
    /// in `matrix.rs`, so that the imports run one way: the plan holds the matrix.
    pub fn plan(&self, out: PathBuf) -> RunPlan {
        RunPlan {
            matrix: self.clone(),
            out,
            no_report: true,
            strict: false,
            shard: None,
        }
    }
}

impl RunPlan {
    /// Checks the plan and fills in defaults: the default suite's when no data set is
    /// named, the papers' standard otherwise. Errors name the `tetbench run` option at fault.
    pub fn to_config(
        &self,
        data_dir: Option<PathBuf>,
        command_line: Vec<String>,
    ) -> anyhow::Result<RunConfig> {
        let m = &self.matrix;
        let suite_mode = m.datasets.is_empty();
        let datasets: Vec<String> = if suite_mode {
            DEFAULT_SUITE
                .datasets
                .iter()
                .map(|s| s.to_string())
                .collect()
        } else {
            named(&m.datasets)
        };
        if datasets.is_empty() {
            anyhow::bail!("--datasets is empty");
        }
        let pick = |given: Option<u32>, suite: u32, standard: u32| {
            given.unwrap_or(if suite_mode { suite } else { standard })
        };
        let standard = if suite_mode {
            DEFAULT_SUITE.viewpoints
        } else {
            suite::STANDARD_VIEWPOINTS
        };
        let viewpoints: Viewpoints = flag("--viewpoints", m.viewpoints.as_deref(), standard)?;
        let resolution = pick(
            m.resolution,
            DEFAULT_SUITE.resolution,
            suite::STANDARD_RESOLUTION,
        );
        if !(1..=16384).contains(&resolution) {
            anyhow::bail!("--resolution {resolution}: must be between 1 and 16384 pixels");
        }
        let frames = pick(m.frames, DEFAULT_SUITE.frames, suite::STANDARD_FRAMES);
        if frames == 0 {
            anyhow::bail!("--frames must be at least 1");
        }
        let warmup = pick(m.warmup, DEFAULT_SUITE.warmup, suite::STANDARD_WARMUP);
        let rounds = pick(m.rounds, DEFAULT_SUITE.rounds, suite::STANDARD_ROUNDS);
        if rounds == 0 {
            anyhow::bail!("--rounds must be at least 1");
        }

        let externals = m.external.specs()?;
        let algorithms = algorithm_list(m, &externals)?;

        let tf_spec = m.tf.clone().unwrap_or_else(|| DEFAULT_TF.to_string());
        let tf = TransferFunction::load(&tf_spec)
            .map_err(|e| anyhow::anyhow!("--tf {tf_spec:?}: {e:#}"))?;
        let settings_filter = SettingsFilter::parse(m.settings.as_deref().unwrap_or(""))?;
        Ok(RunConfig {
            algorithms,
            datasets,
            viewpoints,
            width: resolution,
            height: resolution,
            frames,
            warmup,
            rounds,
            tf_spec,
            tf,
            projection: if m.orthographic {
                Projection::Orthographic
            } else {
                Projection::default()
            },
            cache_dir: m
                .cache_dir
                .clone()
                .unwrap_or_else(|| default_cache_dir(&self.out)),
            out: self.out.clone(),
            data_dir,
            reference: !m.no_reference,
            settings_filter,
            scalar: m.scalar.clone(),
            command_line,
            report: !self.no_report,
            strict: self.strict,
            shard: self
                .shard
                .as_deref()
                .map(|s| flag("--shard", Some(s), ""))
                .transpose()?,
            calibrate: !m.no_calibrate,
            resume: false,
            externals,
        })
    }
}

/// The algorithms to run: those named (all of tetbench's own when none is), the peer groups'
/// and the external renderers; an unknown name is an error listing the known ones.
fn algorithm_list(m: &MatrixArgs, externals: &[ExternalSpec]) -> anyhow::Result<Vec<String>> {
    let known = algorithms::names();
    let mut algorithms: Vec<String> = if m.algorithms.is_empty() {
        // "All" means tetbench's own; peers come with --peers or by name.
        known
            .iter()
            .filter(|n| !algorithms::is_peer(n))
            .map(|s| s.to_string())
            .collect()
    } else {
        named(&m.algorithms)
    };
    for a in &algorithms {
        if !known.contains(&a.as_str()) && !externals.iter().any(|s| s.name == *a) {
            anyhow::bail!(
                "--algorithms: unknown algorithm {a:?}; known: {}",
                known.join(", ")
            );
        }
    }
    for group in m.peers.iter().map(|s| s.trim()).filter(|s| !s.is_empty()) {
        for name in algorithms::peer_group(group).map_err(|e| anyhow::anyhow!("--peers: {e}"))? {
            if !algorithms.iter().any(|a| a == name) {
                algorithms.push(name.to_string());
            }
        }
    }
    for spec in externals {
        if !algorithms.contains(&spec.name) {
            algorithms.push(spec.name.clone());
        }
    }
    if algorithms.is_empty() {
        anyhow::bail!("--algorithms is empty; known: {}", known.join(", "));
    }
    Ok(algorithms)
}

/// The names a list flag gave, trimmed, the empty ones left out.
fn named(list: &[String]) -> Vec<String> {
    list.iter()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .collect()
}

/// A flag's text (`given`, else `default`) parsed into its type; a failure names the flag
/// and the text.
fn flag<T>(name: &str, given: Option<&str>, default: &str) -> anyhow::Result<T>
where
    T: std::str::FromStr<Err = anyhow::Error>,
{
    let text = given.unwrap_or(default);
    text.parse()
        .map_err(|e| anyhow::anyhow!("{name} {text:?}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A matrix's plan holds the matrix and writes no report until `run` asks for one.
    #[test]
    fn a_matrix_plans_without_a_report() {
        let m = MatrixArgs {
            frames: Some(3),
            datasets: vec!["box:1k".into()],
            ..Default::default()
        };
        let plan = m.plan(PathBuf::from("out"));
        assert_eq!(plan.matrix, m);
        assert_eq!(plan.out, PathBuf::from("out"));
        assert!(plan.no_report && !plan.strict && plan.shard.is_none());
    }
}
