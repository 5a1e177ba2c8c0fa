//! The options of every command that runs a matrix (`run`, `reproduce`, `analyze`, `plot
//! --sweep`, `regress ab`/`bisect`): external renderers on the command line (`--external
//! NAME=COMMAND`, the protocol of `docs/external-renderers.md`).
//!
//! It lives in `run`, not `cli`, so that the commands' argument structs in other wings
//! (`reproduce`, `regress`) can flatten it without depending on the command line.

use std::time::Duration;

use external_peer::ExternalSpec;

/// `--external` and `--external-timeout`, flattened into every command that runs a matrix.
#[derive(Debug, Clone, Default, clap::Args)]
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
