//! The options of every command that runs a matrix: [`MatrixArgs`] (what is measured, flattened
//! into `run`, `plot --sweep`, `analyze resolution`, `ab` and `bisect`) and [`ExternalArgs`]
//! (external renderers on the command line, `--external NAME=COMMAND`, the protocol of
//! `docs/external-renderers.md`; also `reproduce`'s). A [`RunPlan`](crate::run::plan::RunPlan) is built from them in
//! `plan.rs` (`MatrixArgs::plan`), which imports this module and not the other way round.
//!
//! It lives in `run`, not `cli`, so that the commands' argument structs in other wings
//! (`papers`, `regress`) can flatten it without depending on the command line.

use std::path::PathBuf;
use std::time::Duration;

use external_peer::ExternalSpec;
use render_core::Renderer;

use crate::algorithms::{self, SettingsFilter};

/// `--external` and `--external-timeout`, flattened into every command that runs a matrix.
#[derive(Debug, Clone, Default, PartialEq, clap::Args)]
pub struct ExternalArgs {
    /// Add a renderer in another process, speaking the external renderer protocol
    /// (docs/external-renderers.md): `NAME=COMMAND` or `NAME[key=value;…]=COMMAND`, e.g.
    /// `mine="python3 examples/external/python/renderer.py"`. Repeatable; its rows are marked
    /// as peers (`peer=external`).
    #[arg(long = "external", value_name = "NAME=COMMAND")]
    pub specs: Vec<String>,
    /// Seconds an external renderer may take to answer one request (prepare: five times this)
    /// before its row fails and the process is stopped.
    #[arg(long = "external-timeout", value_name = "SECONDS")]
    pub timeout_s: Option<f64>,
}

impl ExternalArgs {
    /// The parsed specs; each name is registered as an external peer for the reports.
    pub fn specs(&self) -> anyhow::Result<Vec<ExternalSpec>> {
        let timeout = timeout(self.timeout_s)?;
        let builtin = crate::algorithms::names();
        self.specs
            .iter()
            .map(|text| {
                let mut spec = ExternalSpec::parse(text)?;
                if builtin.contains(&spec.name.as_str()) {
                    anyhow::bail!(
                        "--external {text:?}: {} is one of tetbench's algorithms; choose another \
                         name",
                        spec.name
                    );
                }
                spec.timeout = timeout;
                crate::algorithms::note_external(&spec.name);
                Ok(spec)
            })
            .collect()
    }
}

pub(crate) fn timeout(seconds: Option<f64>) -> anyhow::Result<Duration> {
    let s = seconds.unwrap_or(external_peer::DEFAULT_TIMEOUT_S);
    if !(s.is_finite() && s > 0.0) {
        anyhow::bail!("--external-timeout {s}: must be a positive number of seconds");
    }
    Ok(Duration::from_secs_f64(s))
}

/// What a run measures: the matrix options every command that runs one shares (`run`, `plot
/// --sweep`, `analyze resolution`, `ab`, `bisect`), flattened into each. A value left out is
/// `None` or empty: the command's default, filled in by [`MatrixArgs::or`] with typed values,
/// then the run's in [`RunPlan::to_config`] (the default suite's when no data set is named,
/// the papers' standard otherwise). [`RunPlan`](crate::run::plan::RunPlan) is built from it in one place,
/// [`MatrixArgs::plan`].
#[derive(Debug, Clone, Default, PartialEq, clap::Args)]
pub struct MatrixArgs {
    /// Comma-separated algorithms (default: all of tetbench's own).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub algorithms: Vec<String>,
    /// Comma-separated data set names, generator specs (box:200k, shell:1m) or files
    /// (default: the embedded suite, box:10k and shell:10k).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub datasets: Vec<String>,
    /// `14` (the HAVS tables' fixed viewpoints), `axes`, `diagonals`, `orbit:N`, or names
    /// such as `+x,-y,+x+y-z` (default 14; the default suite uses 3).
    #[arg(long, value_name = "SPEC")]
    pub viewpoints: Option<String>,
    /// Square viewport size in pixels (default 512; the default suite uses 128).
    #[arg(long, value_name = "PIXELS")]
    pub resolution: Option<u32>,
    /// Transfer function: a preset (low-opacity, high-opacity) or a ParaView colormap JSON file
    /// (default low-opacity).
    #[arg(long, value_name = "NAME|FILE")]
    pub tf: Option<String>,
    /// Timed frames per viewpoint in each round (default 10; the default suite uses 1).
    #[arg(long, value_name = "N")]
    pub frames: Option<u32>,
    /// Untimed warm-up frames before them, in each round (default 2; the default suite uses 1).
    #[arg(long, value_name = "N")]
    pub warmup: Option<u32>,
    /// Passes over each data set's variants, so that a row's samples come from separate
    /// moments (default 1; the default suite uses 3). With more than 1, all variants of a
    /// data set stay prepared at once.
    #[arg(long, value_name = "N")]
    pub rounds: Option<u32>,
    /// Keep only variants whose settings match, e.g. `variant=linear` or `k=2|6;sort=radix`
    /// (keys an algorithm lacks are ignored for it).
    #[arg(long, value_name = "FILTER")]
    pub settings: Option<String>,
    /// Run every variant each algorithm offers (what `--settings` selects from) instead of
    /// the defaults; with `--settings`, every variant that matches it (settings the filter does
    /// not name are not held to their defaults).
    #[arg(long)]
    pub all_variants: bool,
    /// Skip the reference and the error metrics (timing only).
    #[arg(long)]
    pub no_reference: bool,
    /// Where reference images are cached (default: $TETBENCH_CACHE, else
    /// $XDG_CACHE_HOME/tetbench, else ~/.cache/tetbench).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Orthographic instead of perspective (30° vertical field of view) projection.
    #[arg(long)]
    pub orthographic: bool,
    /// Point array to use as the scalar (default: the file's first).
    #[arg(long, value_name = "NAME")]
    pub scalar: Option<String>,
    /// Skip the backend calibration (and the rows' roofline columns).
    #[arg(long)]
    pub no_calibrate: bool,
    /// Add other packages' renderers as peers: `vtk` (vtk-pt, vtk-raycast, vtk-zsweep through
    /// VTK's Python package; see scripts/setup-vtk.sh).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub peers: Vec<String>,
    #[command(flatten)]
    pub external: ExternalArgs,
}

/// The transfer function when none is named.
pub const DEFAULT_TF: &str = "low-opacity";

impl MatrixArgs {
    /// These options, with every one left out taken from `defaults` (a command's own
    /// defaults, as typed values).
    pub fn or(&self, defaults: MatrixArgs) -> MatrixArgs {
        let list = |given: &Vec<String>, default: Vec<String>| {
            if given.is_empty() {
                default
            } else {
                given.clone()
            }
        };
        let mut external = self.external.clone();
        if external.specs.is_empty() {
            external.specs = defaults.external.specs;
        }
        external.timeout_s = external.timeout_s.or(defaults.external.timeout_s);
        MatrixArgs {
            algorithms: list(&self.algorithms, defaults.algorithms),
            datasets: list(&self.datasets, defaults.datasets),
            viewpoints: self.viewpoints.clone().or(defaults.viewpoints),
            resolution: self.resolution.or(defaults.resolution),
            tf: self.tf.clone().or(defaults.tf),
            frames: self.frames.or(defaults.frames),
            warmup: self.warmup.or(defaults.warmup),
            rounds: self.rounds.or(defaults.rounds),
            settings: self.settings.clone().or(defaults.settings),
            all_variants: self.all_variants || defaults.all_variants,
            no_reference: self.no_reference || defaults.no_reference,
            cache_dir: self.cache_dir.clone().or(defaults.cache_dir),
            orthographic: self.orthographic || defaults.orthographic,
            scalar: self.scalar.clone().or(defaults.scalar),
            no_calibrate: self.no_calibrate || defaults.no_calibrate,
            peers: list(&self.peers, defaults.peers),
            external,
        }
    }

    /// The `tetbench run` options these stand for, only those given (so an older build that
    /// lacks a newer option still runs a matrix that does not use it): `ab` and `bisect` hand
    /// them to each side's binary.
    pub fn run_args(&self) -> Vec<String> {
        let mut out = vec![];
        let mut value = |flag: &str, v: Option<String>| {
            if let Some(v) = v {
                out.push(format!("--{flag}"));
                out.push(v);
            }
        };
        let list = |v: &[String]| (!v.is_empty()).then(|| v.join(","));
        value("algorithms", list(&self.algorithms));
        value("datasets", list(&self.datasets));
        value("viewpoints", self.viewpoints.clone());
        value("resolution", self.resolution.map(|v| v.to_string()));
        value("tf", self.tf.clone());
        value("frames", self.frames.map(|v| v.to_string()));
        value("warmup", self.warmup.map(|v| v.to_string()));
        value("rounds", self.rounds.map(|v| v.to_string()));
        value("settings", self.settings.clone());
        value(
            "cache-dir",
            self.cache_dir.as_ref().map(|p| p.display().to_string()),
        );
        value("scalar", self.scalar.clone());
        value("peers", list(&self.peers));
        for spec in &self.external.specs {
            value("external", Some(spec.clone()));
        }
        value(
            "external-timeout",
            self.external.timeout_s.map(|v| v.to_string()),
        );
        for (flag, on) in [
            ("--all-variants", self.all_variants),
            ("--no-reference", self.no_reference),
            ("--orthographic", self.orthographic),
            ("--no-calibrate", self.no_calibrate),
        ] {
            if on {
                out.push(flag.to_string());
            }
        }
        out
    }

    /// The variants a run starts from for algorithm `name`: every one it offers with
    /// `--all-variants` (the run then keeps those `filter` accepts), else `filter`'s selection.
    pub fn variants(
        &self,
        name: &str,
        filter: &SettingsFilter,
    ) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
        if self.all_variants {
            algorithms::all_variants(name)
        } else {
            algorithms::selected_variants(name, filter)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A command's defaults fill only what the user left out.
    #[test]
    fn defaults_fill_only_what_was_left_out() {
        let given = MatrixArgs {
            frames: Some(3),
            datasets: vec!["box:1k".into()],
            ..Default::default()
        };
        let m = given.or(MatrixArgs {
            frames: Some(5),
            warmup: Some(1),
            datasets: vec!["spx".into()],
            algorithms: vec!["fragment-pt".into()],
            no_reference: true,
            ..Default::default()
        });
        assert_eq!(m.frames, Some(3));
        assert_eq!(m.warmup, Some(1));
        assert_eq!(m.datasets, ["box:1k"]);
        assert_eq!(m.algorithms, ["fragment-pt"]);
        assert!(m.no_reference);
    }
}
