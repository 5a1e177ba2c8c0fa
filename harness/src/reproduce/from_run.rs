//! `tetbench analyze havs|gator|fragment-pt|raycast|splat RUN_DIR`: a paper's tables and
//! claims from runs already made, written by the same table code as `tetbench reproduce`
//! (one writer per table). `RUN_DIR` is a `tetbench run` output (it holds `results.json`), or
//! a folder of such outputs (e.g. a reproduce folder's `runs/`), read whole.

use std::path::{Path, PathBuf};

use anyhow::Context as _;

use super::{write_report, Extra, Measured, Session, SourceState};
use crate::results::ResultsFile;

/// The paper analyses, one subcommand per paper (flattened into `tetbench analyze`).
#[derive(Debug, clap::Subcommand)]
pub enum PaperAnalysis {
    /// HAVS (Callahan et al. 2005) Tables 1–5 and claims from finished runs (Tables 1–2 and the
    /// claims on them need `tetbench reproduce havs`: they are CPU analyses, not runs).
    Havs(FromRunArgs),
    /// GATOR (Wylie et al. 2002) Tables 1–3 and claims from finished runs.
    Gator(FromRunArgs),
    /// Fragment PT (Marroquim et al. 2006) Tables 1–2, bytes per tet and claims from finished
    /// runs.
    FragmentPt(FromRunArgs),
    /// Tiled ray casting (Bernardon et al.) Tables 3–6, bytes per tet and claims from finished
    /// runs.
    Raycast(FromRunArgs),
    /// Splatting (Grau & Tost 2007) Table 1 and claims from finished runs.
    Splat(FromRunArgs),
}

#[derive(Debug, Clone, clap::Args)]
pub struct FromRunArgs {
    /// A `tetbench run` output directory, or a folder holding several.
    pub run_dir: PathBuf,
    /// Where report.md and report.html go (default: RUN_DIR/analysis-PAPER).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// Every results file under `dir` (itself, or its immediate sub-folders), in name order.
fn results_files(dir: &Path) -> anyhow::Result<Vec<ResultsFile>> {
    if dir.join(crate::results::JSON_FILE).exists() {
        return Ok(vec![ResultsFile::read(dir)?]);
    }
    let mut subdirs: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join(crate::results::JSON_FILE).exists())
        .collect();
    subdirs.sort();
    anyhow::ensure!(
        !subdirs.is_empty(),
        "{}: no {} in it or in its sub-folders (give a `tetbench run` output)",
        dir.display(),
        crate::results::JSON_FILE
    );
    subdirs.iter().map(|d| ResultsFile::read(d)).collect()
}

pub fn run(cmd: PaperAnalysis) -> anyhow::Result<()> {
    let (id, args) = match cmd {
        PaperAnalysis::Havs(a) => ("havs", a),
        PaperAnalysis::Gator(a) => ("gator", a),
        PaperAnalysis::FragmentPt(a) => ("fragment-pt", a),
        PaperAnalysis::Raycast(a) => ("raycast", a),
        PaperAnalysis::Splat(a) => ("splat", a),
    };
    let paper = super::papers()
        .into_iter()
        .find(|p| p.id == id)
        .expect("every subcommand is a paper");
    let files = results_files(&args.run_dir)?;
    let mut measured = Measured::default();
    for f in &files {
        measured.rows.extend(f.rows.iter().cloned());
    }
    let report = (paper.tables)(&measured, &Extra::default());
    let out = args
        .out
        .unwrap_or_else(|| args.run_dir.join(format!("analysis-{id}")));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let commits: Vec<String> = files
        .iter()
        .map(|f| {
            format!(
                "{}{}",
                f.machine.git_commit.as_deref().unwrap_or("unknown"),
                if f.machine.git_dirty == Some(true) {
                    " (with uncommitted changes)"
                } else {
                    ""
                }
            )
        })
        .collect();
    let session = Session {
        dir: out.clone(),
        quick: false,
        data_dir: None,
        cache_dir: None,
        substitutes: vec![],
        resolution: None,
        machine: files.first().map(|f| f.machine.clone()),
        log: vec![format!(
            "analysed {} run(s) under {} ({} rows), measured by commit(s) {}",
            files.len(),
            args.run_dir.display(),
            measured.rows.len(),
            commits.join(", ")
        )],
        // An analysis measures nothing, so no external renderer joins it.
        external: Default::default(),
        source: SourceState::read(),
        from_run: Some(args.run_dir.clone()),
    };
    write_report(paper, &session, &report, 0.0)?;
    let md = std::fs::read_to_string(out.join("report.md"))?;
    print!("{md}");
    eprintln!("wrote {}", out.join("report.md").display());
    Ok(())
}
