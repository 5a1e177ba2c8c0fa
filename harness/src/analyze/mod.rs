//! `tetbench analyze …`: analyses that reproduce the papers' tables and figures.
//!
//! To add one: write `analyze/NAME.rs` with a `#[derive(clap::Args)] pub struct Args` and
//! `pub fn run(args: Args, ctx: &Context) -> anyhow::Result<()>`, then add a `mod NAME;` line,
//! a variant to [`AnalyzeCommand`] and an arm to [`run`].

use std::path::PathBuf;

use clap::Subcommand;

pub mod fragment_pt;
pub mod havs;
pub mod raycast;
pub mod splat;
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
    /// Fragment PT (Marroquim et al. 2006) Tables 1 and 2 from a finished run, as Markdown.
    FragmentPt(fragment_pt::TablesArgs),
    /// Fragment PT Fig. 8: K tets/s against viewport size (one timing run per size), plotted.
    Resolution(fragment_pt::ResolutionArgs),
    /// HAVS Table 1: sorting 1 M floats with shellsort, heapsort, quicksort, radix and std sort.
    Sort(havs::SortArgs),
    /// HAVS Table 2 and Fig. 6: exact A-buffer analysis of how large the k-buffer must be.
    Kbuffer(havs::KbufferArgs),
    /// HAVS Tables 3 and 4 from a finished `tetbench run --algorithms havs`.
    HavsTables(havs::TablesArgs),
    /// Tiled ray casting (Bernardon et al. 2005) Tables 3–6 from a finished
    /// `tetbench run --algorithms raycast`, beside the paper's.
    Raycast(raycast::Args),
    /// Grau & Tost 2007 Table 1 (CPU vs GPU buckets) from a finished `tetbench run --algorithms splat`.
    Splat(splat::Args),
}

pub fn run(cmd: AnalyzeCommand, ctx: &Context) -> anyhow::Result<()> {
    match cmd {
        AnalyzeCommand::Summary(args) => summary::run(args, ctx),
        AnalyzeCommand::FragmentPt(args) => fragment_pt::run_tables(args, ctx),
        AnalyzeCommand::Resolution(args) => fragment_pt::run_resolution(args, ctx),
        AnalyzeCommand::Sort(args) => havs::run_sort(args, ctx),
        AnalyzeCommand::Kbuffer(args) => havs::run_kbuffer(args, ctx),
        AnalyzeCommand::HavsTables(args) => havs::run_tables(args, ctx),
        AnalyzeCommand::Raycast(args) => raycast::run(args, ctx),
        AnalyzeCommand::Splat(args) => splat::run(args, ctx),
    }
}
