//! `tetbench analyze havs|gator|fragment-pt|raycast|splat RUN_DIR`: a paper's tables and
//! claims from runs already made, written by the same table code as `tetbench reproduce`
//! (one writer per table: the paper's [`super::PaperModule::tables`]). `RUN_DIR` is a `tetbench run` output (it holds `results.json`), or
//! a folder of such outputs (e.g. a reproduce folder's `runs/`), read whole.

use std::path::{Path, PathBuf};

use anyhow::Context as _;

use super::reproduce::write_report;
use super::session::{Extra, Measured, Session, SourceState};
use crate::results::ResultsFile;

/// `tetbench analyze PAPER RUN_DIR`: one subcommand per paper of [`super::PAPERS`] (flattened
/// into `tetbench analyze`), built from the registry so that a new paper needs no line here.
#[derive(Debug, Clone)]
pub struct PaperAnalysis {
    /// The paper's id (its subcommand's name).
    pub paper: &'static str,
    pub args: FromRunArgs,
}

impl clap::FromArgMatches for PaperAnalysis {
    fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let (name, sub) = matches.subcommand().ok_or_else(|| {
            clap::Error::raw(
                clap::error::ErrorKind::MissingSubcommand,
                "name a paper or an analysis",
            )
        })?;
        let paper = super::find(name).ok_or_else(|| {
            clap::Error::raw(
                clap::error::ErrorKind::InvalidSubcommand,
                format!("{name} is not a paper; known: {}", super::ids().join(", ")),
            )
        })?;
        Ok(PaperAnalysis {
            paper: paper.paper().id,
            args: FromRunArgs::from_arg_matches(sub)?,
        })
    }

    fn update_from_arg_matches(&mut self, matches: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl clap::Subcommand for PaperAnalysis {
    fn augment_subcommands(mut cmd: clap::Command) -> clap::Command {
        for p in super::PAPERS {
            let paper = p.paper();
            let sub = clap::Command::new(paper.id).about(paper.analyze_about.trim_end_matches('.'));
            cmd = cmd.subcommand(<FromRunArgs as clap::Args>::augment_args(sub));
        }
        cmd
    }

    fn augment_subcommands_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_subcommands(cmd)
    }

    fn has_subcommand(name: &str) -> bool {
        super::find(name).is_some()
    }
}

#[derive(Debug, Clone, clap::Args)]
pub struct FromRunArgs {
    /// A `tetbench run` output directory, or a folder holding several.
    pub run_dir: PathBuf,
    /// Where report.md and report.html go (default: RUN_DIR/analysis-PAPER).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// Every results file under `dir` (itself, or its immediate sub-folders), in name order, with
/// its folder.
fn results_files(dir: &Path) -> anyhow::Result<Vec<(PathBuf, ResultsFile)>> {
    if dir.join(crate::results::JSON_FILE).exists() {
        return Ok(vec![(dir.to_path_buf(), ResultsFile::read(dir)?)]);
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
    subdirs
        .into_iter()
        .map(|d| Ok((d.clone(), ResultsFile::read(&d)?)))
        .collect()
}

pub fn run(cmd: PaperAnalysis) -> anyhow::Result<()> {
    let PaperAnalysis { paper: id, args } = cmd;
    let paper = super::find(id).expect("every subcommand is a paper");
    let files = results_files(&args.run_dir)?;
    let mut measured = Measured::default();
    for (dir, f) in &files {
        measured.push_run(dir, f.rows.iter().cloned());
        if measured.calibration.is_none() {
            measured.calibration = f.machine.calibration.clone();
        }
    }
    let report = paper.tables(&measured, &Extra::default());
    let out = args
        .out
        .unwrap_or_else(|| args.run_dir.join(format!("analysis-{id}")));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let commits: Vec<String> = files
        .iter()
        .map(|(_, f)| {
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
        rounds: None,
        machine: files.first().map(|(_, f)| f.machine.clone()),
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
    write_report(paper.paper(), &session, &report, 0.0)?;
    let md = std::fs::read_to_string(out.join("report.md"))?;
    print!("{md}");
    eprintln!("wrote {}", out.join("report.md").display());
    Ok(())
}
