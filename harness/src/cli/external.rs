//! `tetbench external check`: the conformance suite of `external_peer::conformance` run on one
//! external renderer (or one of tetbench's own). The `--external NAME=COMMAND` option every
//! matrix command shares is [`crate::run::matrix::ExternalArgs`]. The protocol is
//! `docs/external-renderers.md`.

use std::path::PathBuf;

use external_peer::{ExternalRenderer, ExternalSpec};

use crate::run::matrix::timeout;

#[derive(Debug, clap::Subcommand)]
pub enum ExternalCommand {
    /// Conformance check of an external renderer against the exact reference: orientation,
    /// handedness, premultiplied colour, field of view, pixel centres, extinction units, an
    /// empty view and timing; names what is wrong and exits non-zero on any failure.
    Check(CheckArgs),
}

#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// The renderer's command line, e.g. "python3 examples/external/python/renderer.py".
    #[arg(required_unless_present = "peer", conflicts_with = "peer")]
    pub command: Option<String>,
    /// Check one of tetbench's algorithms or peers instead (`vtk-raycast`, `havs`…): its
    /// first default variant, or the first that --settings selects.
    #[arg(long, value_name = "ALGORITHM")]
    pub peer: Option<String>,
    /// Settings for the renderer, `key=value;key=value` (sent in its hello; with --peer, which
    /// variant, e.g. `readout=rays;et=off`).
    #[arg(long, value_name = "SETTINGS")]
    pub settings: Option<String>,
    /// Seconds the renderer may take per request.
    #[arg(long, value_name = "SECONDS")]
    pub timeout: Option<f64>,
    /// Write each view's image, reference and closest mistake as PNGs here.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// Runs `tetbench external …`; a failed check is an error listing what is wrong.
pub fn run(cmd: ExternalCommand) -> anyhow::Result<()> {
    let ExternalCommand::Check(args) = cmd;
    let mut renderer: Box<dyn render_core::Renderer> = match (&args.peer, &args.command) {
        (Some(name), _) => {
            let filter =
                crate::algorithms::SettingsFilter::parse(args.settings.as_deref().unwrap_or(""))?;
            crate::algorithms::selected_variants(name, &filter)?
                .into_iter()
                .next()
                .ok_or_else(|| anyhow::anyhow!("no variant of {name} has the settings {filter}"))?
        }
        (None, Some(command)) => {
            let settings = args.settings.as_deref().unwrap_or("");
            let mut spec = ExternalSpec::parse(&format!("checked[{settings}]={command}"))?;
            spec.timeout = timeout(args.timeout)?;
            Box::new(ExternalRenderer::new(spec))
        }
        (None, None) => anyhow::bail!("external check needs a COMMAND or --peer NAME"),
    };
    let gpu = render_core::Gpu::new()?;
    let report = external_peer::conformance::check(renderer.as_mut(), &gpu, args.out.as_deref())?;
    print!("{report}");
    drop(renderer);
    let failed = report.failures().count();
    if failed > 0 {
        anyhow::bail!(
            "{failed} of {} conformance checks failed (docs/external-renderers.md, \"The \
             conformance check\")",
            report.cases.len()
        );
    }
    println!("all {} conformance checks passed", report.cases.len());
    Ok(())
}
