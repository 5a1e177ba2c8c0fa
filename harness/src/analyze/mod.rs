//! `tetbench analyze …`: the CPU analyses behind the papers' tables (HAVS's sorts and k-buffer,
//! fragment PT's Fig. 8) and the summary of any run. A paper's tables from finished runs are
//! `tetbench analyze PAPER RUN_DIR` (`reproduce::from_run`), written by the same code as
//! `tetbench reproduce`.
//!
//! To add one: write `analyze/NAME.rs` with a `#[derive(clap::Args)] pub struct Args` and
//! `pub fn run(args: Args, ctx: &Context) -> anyhow::Result<()>`, then add a `mod NAME;` line,
//! a variant to [`AnalyzeCommand`] and an arm to [`run`].

use std::path::PathBuf;

use clap::Subcommand;

pub mod fragment_pt;
pub mod havs;
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
    Resolution(fragment_pt::ResolutionArgs),
    /// HAVS Table 1: sorting 1 M floats with shellsort, heapsort, quicksort, radix and std sort.
    Sort(havs::SortArgs),
    /// HAVS Table 2 and Fig. 6: exact A-buffer analysis of how large the k-buffer must be.
    Kbuffer(havs::KbufferArgs),
}

pub fn run(cmd: AnalyzeCommand, ctx: &Context) -> anyhow::Result<()> {
    match cmd {
        AnalyzeCommand::Summary(args) => summary::run(args, ctx),
        AnalyzeCommand::Resolution(args) => fragment_pt::run_resolution(args, ctx),
        AnalyzeCommand::Sort(args) => havs::run_sort(args, ctx),
        AnalyzeCommand::Kbuffer(args) => havs::run_kbuffer(args, ctx),
    }
}
