//! `tetbench analyze …`: the CPU analyses behind the papers' tables (HAVS's sorts and k-buffer,
//! fragment PT's Fig. 8; they live in their paper's folder, `papers/havs/analysis.rs` and
//! `papers/fragment_pt/fig8.rs`) and the summary of any run. A paper's tables from finished
//! runs are `tetbench analyze PAPER RUN_DIR` (`papers::from_run`), written by the same code as
//! `tetbench reproduce`.
//!
//! To add one: its `#[derive(clap::Args)]` struct and its `run` function, a variant of
//! [`AnalyzeCommand`] and an arm of [`run`].

use std::path::PathBuf;

use clap::Subcommand;

use crate::papers::fragment_pt::fig8;
use crate::papers::havs::analysis;

pub mod control;
pub mod medians;
pub mod peers;
pub mod summary;

/// What every analysis may need from the global options.
#[derive(Debug, Clone, Default)]
pub struct Context {
    /// `--data-dir` (None: the registry's default, `TETBENCH_DATA` or `../shared/datasets`).
    pub data_dir: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
pub enum AnalyzeCommand {
    /// Per algorithm × settings × data set means over viewpoints of a finished run, as a
    /// Markdown table (the layout of the papers' timing tables: HAVS Tables 3–4, fragment PT
    /// Table 1).
    Summary(summary::Args),
    /// Fragment PT Fig. 8: K tets/s against viewport size (one timing run per size), plotted.
    Resolution(Box<fig8::ResolutionArgs>),
    /// HAVS Table 1: sorting 1 M floats with shellsort, heapsort, quicksort, radix and std sort.
    Sort(analysis::SortArgs),
    /// HAVS Table 2 and Fig. 6: exact A-buffer analysis of how large the k-buffer must be.
    Kbuffer(analysis::KbufferArgs),
    /// Every variant's tets/s against each peer's in the same run (one input a run: run
    /// directories or results CSVs), and targets on those ratios judged by a rule file
    /// (`--targets docs/targets/lavapipe-vs-vtk.json`), each beside the ratio its roofline allows.
    Peers(peers::Args),
    /// Each algorithm's median of one row field (limit fraction by default) in each of
    /// several runs, side by side, and each run's over the first's.
    Medians(medians::Args),
    /// Each control figure's median over a run's samples, in several runs side by side, and
    /// each run's speed over the first's: which of the machine's resources moved.
    Control(control::Args),
}

/// Prints an analysis's Markdown, and with `--out` also writes it to that file.
pub fn emit(md: &str, out: Option<&std::path::Path>) -> anyhow::Result<()> {
    if let Some(out) = out {
        crate::results::write_file(out, md)?;
    }
    print!("{md}");
    Ok(())
}

pub fn run(cmd: AnalyzeCommand, ctx: &Context) -> anyhow::Result<()> {
    match cmd {
        AnalyzeCommand::Summary(args) => summary::run(args, ctx),
        AnalyzeCommand::Resolution(args) => fig8::run_resolution(*args, ctx.data_dir.clone()),
        AnalyzeCommand::Sort(args) => analysis::run_sort(args),
        AnalyzeCommand::Kbuffer(args) => analysis::run_kbuffer(args, ctx.data_dir.clone()),
        AnalyzeCommand::Peers(args) => peers::run(args),
        AnalyzeCommand::Medians(args) => medians::run(args),
        AnalyzeCommand::Control(args) => control::run(args),
    }
}
