//! The paper layer: one folder per reproduced paper (`havs/`, `gator/`, `fragment_pt/`,
//! `raycast/`, `splat/`), each implementing [`PaperModule`]: its plan (data sets, viewpoints,
//! variants and viewport, from the transcription), the CPU analyses its tables need besides
//! runs, and its tables and claims from what was measured. `tetbench reproduce PAPER`
//! ([`reproduce`]) runs the plan and then the tables; `tetbench analyze PAPER RUN_DIR`
//! ([`from_run`]) runs the same tables over finished runs, so every table has one writer.
//!
//! Beside them: [`transcription`] (the one reader of the papers' tables as CSV), [`claims`]
//! (the papers' claims as data) and [`verdict`] (the one rule that decides them), [`cells`]
//! (each table cell's rule and verdict), [`table`] (paper | ours | verdict or ours/paper as
//! Markdown, HTML and charts), [`session`] (what a reproduction
//! works with) and [`evidence`] (the numbers behind the claims).
//!
//! To add a paper: its transcription in `reports/papers/`, its folder here with a type
//! implementing [`PaperModule`], and one line in [`PAPERS`].

pub mod cells;
pub mod claims;
pub mod claims_report;
pub mod evidence;
pub mod from_run;
pub mod hardware;
pub mod reproduce;
pub mod rules;
pub mod session;
pub mod sides;
pub mod spec;
pub mod table;
pub mod transcription;
pub mod verdict;

pub mod fragment_pt;
pub mod gator;
pub mod havs;
pub mod raycast;
pub mod splat;

use session::{Extra, Measured, Report, RunSpec, Session};

/// Every paper, in the order `reproduce all` runs them and the index lists them.
pub static PAPERS: &[&dyn PaperModule] = &[
    &havs::Havs,
    &gator::Gator,
    &fragment_pt::FragmentPt,
    &raycast::Raycast,
    &splat::Splat,
];

/// One reproduced paper, as its folder implements it.
pub trait PaperModule: Sync {
    /// What the paper is and on what it was measured.
    fn paper(&self) -> &'static Paper;

    /// The runs its tables need: data sets, viewpoints, variants named in full and viewport,
    /// as the transcription gives them (`reports/papers/<paper>.md`).
    fn plan(&self) -> Vec<RunSpec>;

    /// The CPU analyses its tables need besides the runs (sorts, the k-buffer model, the
    /// classifier's twin, data set sizes), run before them; failures that are not one row go
    /// to `measured.errors`. None by default.
    fn analyses(&self, _session: &mut Session, _measured: &mut Measured) -> anyhow::Result<Extra> {
        Ok(Extra::default())
    }

    /// Its tables and claims from what was measured: the one writer, shared by `reproduce`
    /// and `analyze PAPER RUN_DIR`.
    fn tables(&self, measured: &Measured, extra: &Extra) -> Report;
}

/// The paper with this id (its name on the command line and its output folder).
pub fn find(id: &str) -> Option<&'static dyn PaperModule> {
    PAPERS.iter().copied().find(|p| p.paper().id == id)
}

/// The ids of every paper, in [`PAPERS`]' order.
pub fn ids() -> Vec<&'static str> {
    PAPERS.iter().map(|p| p.paper().id).collect()
}

/// One paper: what it is and on what it was measured.
pub struct Paper {
    /// Name on the command line and output folder.
    pub id: &'static str,
    pub title: &'static str,
    pub citation: &'static str,
    /// The paper's test machine, from the transcription.
    pub hardware: &'static str,
    /// The tetbench algorithm the paper describes (must be built in to reproduce it alone).
    pub algorithm: &'static str,
    /// Every data set the plan loads (registry names): the rows a claim may name.
    pub datasets: &'static [&'static str],
    /// The places of the paper a claim may cite (its numbered sections, tables, abstract,
    /// captions), from its source text.
    pub sections: &'static [&'static str],
    /// What `tetbench analyze PAPER RUN_DIR` says it writes (its help line).
    pub analyze_about: &'static str,
}

#[cfg(test)]
mod claims_control_tests;
#[cfg(test)]
mod claims_flip_tests;
#[cfg(test)]
mod claims_paper_figure_tests;
#[cfg(test)]
mod claims_tests;
#[cfg(test)]
mod rule_history_tests;
#[cfg(test)]
mod sides_tests;
