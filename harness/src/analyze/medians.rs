//! `tetbench analyze medians [--of FIELD] LABEL=RUN…`: each algorithm's median of one row field
//! in each run, side by side, and each run's over the first's. With `--of limit-fraction`
//! (the default) a reader checks that fractions priced by the control stay the same when the
//! machine changes: one build idle and again beside a load (docs/roofline.md, "Priced at the
//! moment of the row"); with `--of tets-per-sec`, two adapters' speeds (docs/gpu.md).

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Context as _};

use crate::results::stats::median;
use crate::results::{ResultsFile, Row};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Runs to set side by side, each `LABEL=DIR` (a `tetbench run` output directory; its
    /// folder name labels it without `LABEL=`). The first is the one the others are divided by.
    #[arg(required = true)]
    pub runs: Vec<String>,
    /// The row field whose median is taken.
    #[arg(long, value_enum, default_value_t = Field::LimitFraction)]
    pub of: Field,
    /// Also write the Markdown to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// The row fields a median can be taken of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Field {
    LimitFraction,
    TetsPerSec,
    BytesPerTet,
    TotalMs,
    /// The time the row's bounding resource alone needs at the row's own control.
    RooflineMs,
    PsnrDb,
}

impl Field {
    fn of(self, row: &Row) -> Option<f64> {
        match self {
            Field::LimitFraction => row.limit_fraction,
            Field::TetsPerSec => row.tets_per_sec,
            Field::BytesPerTet => row.bytes_per_tet,
            Field::TotalMs => row.total_ms,
            Field::RooflineMs => row.roofline_ms,
            Field::PsnrDb => row.psnr_db,
        }
    }

    /// How a median prints: three significant digits for the large ones.
    fn format(self, v: f64) -> String {
        match self {
            Field::TetsPerSec | Field::BytesPerTet => format!("{v:.3e}"),
            _ => format!("{v:.3}"),
        }
    }
}

/// One run's figures the table shows.
#[derive(Debug, Clone, PartialEq)]
pub struct RunMedians {
    pub label: String,
    pub field: Field,
    /// (algorithm, median of the field over its rows that have it), in the order first met.
    pub medians: Vec<(String, f64)>,
    /// Rows with the field, and (for limit fractions) those above 1: a row faster than its
    /// bound, a defect.
    pub rows: usize,
    pub above_one: usize,
    pub largest: Option<f64>,
    /// Seconds the run's control took (preparation and samples), and its sample count.
    pub control: Option<(f64, usize)>,
    /// Where and from what it ran: adapter, CPU, build and commit, as the results name them.
    pub provenance: String,
}

impl RunMedians {
    pub fn of(label: &str, field: Field, file: &ResultsFile) -> RunMedians {
        let mut by_algorithm: Vec<(String, Vec<f64>)> = vec![];
        for row in &file.rows {
            let Some(f) = field.of(row) else {
                continue;
            };
            match by_algorithm.iter_mut().find(|(a, _)| *a == row.algorithm) {
                Some((_, v)) => v.push(f),
                None => by_algorithm.push((row.algorithm.clone(), vec![f])),
            }
        }
        let all: Vec<f64> = by_algorithm.iter().flat_map(|(_, v)| v.clone()).collect();
        RunMedians {
            label: label.to_string(),
            field,
            medians: by_algorithm
                .iter()
                .map(|(a, v)| (a.clone(), median(v)))
                .collect(),
            rows: all.len(),
            above_one: all.iter().filter(|f| **f > 1.0).count(),
            largest: all.iter().copied().reduce(f64::max),
            control: file
                .control
                .as_ref()
                .map(|c| (c.seconds(), c.samples.len())),
            provenance: provenance(file),
        }
    }

    fn median_of(&self, algorithm: &str) -> Option<f64> {
        self.medians
            .iter()
            .find(|(a, _)| a == algorithm)
            .map(|(_, m)| *m)
    }
}

fn provenance(file: &ResultsFile) -> String {
    let m = &file.machine;
    let adapter = m
        .adapter
        .as_ref()
        .map_or("no adapter named", |a| a.name.as_str());
    let commit = match (&m.git_commit, m.git_dirty) {
        (Some(c), Some(true)) => {
            format!("commit {} with uncommitted changes", &c[..c.len().min(7)])
        }
        (Some(c), _) => format!("commit {}", &c[..c.len().min(7)]),
        (None, _) => "no commit recorded".into(),
    };
    let load = m
        .load_average_start
        .map_or(String::new(), |l| format!(", load {l:.2} at the start"));
    format!(
        "{adapter} on {} ({} cores), {} build, {commit}, {}{load}",
        m.cpu_model,
        m.cpu_cores,
        m.build_profile.as_deref().unwrap_or("unknown"),
        m.date_utc
    )
}

/// The Markdown table: one line per algorithm of the first run, one column per run, then each
/// later run over the first; and under it the rows above 1 and the control's cost per run.
pub fn markdown(runs: &[RunMedians]) -> String {
    let Some(first) = runs.first() else {
        return String::new();
    };
    let mut md = String::from("| algorithm |");
    let mut rule = String::from("|---|");
    for r in runs {
        let _ = write!(md, " {} |", r.label);
        rule.push_str("---:|");
    }
    for r in &runs[1..] {
        let _ = write!(md, " {} / {} |", r.label, first.label);
        rule.push_str("---:|");
    }
    let _ = writeln!(md, "\n{rule}");
    let field = first.field;
    let dash = || "–".to_string();
    for (algorithm, base) in &first.medians {
        let _ = write!(md, "| {algorithm} |");
        for r in runs {
            let v = r
                .median_of(algorithm)
                .map_or_else(dash, |v| field.format(v));
            let _ = write!(md, " {v} |");
        }
        for r in &runs[1..] {
            let ratio = r
                .median_of(algorithm)
                .map_or_else(dash, |m| format!("{:.3}", m / base));
            let _ = write!(md, " {ratio} |");
        }
        md.push('\n');
    }
    md.push('\n');
    for r in runs {
        let rows = if field == Field::LimitFraction {
            let largest = r.largest.map_or_else(dash, |v| format!("{v:.3}"));
            format!(
                "{} rows priced, {} above 1 (largest {largest})",
                r.rows, r.above_one
            )
        } else {
            format!("{} rows", r.rows)
        };
        let control = r.control.map_or("no control".to_string(), |(s, n)| {
            format!("control {s:.1} s ({n} samples and its preparation)")
        });
        let _ = writeln!(md, "- {}: {rows}; {control}; {}.", r.label, r.provenance);
    }
    md
}

pub fn parse_run(arg: &str) -> anyhow::Result<(String, PathBuf)> {
    let (label, dir) = match arg.split_once('=') {
        Some((label, dir)) if !label.is_empty() => (label.to_string(), PathBuf::from(dir)),
        Some(_) => bail!("{arg}: an empty label before '='"),
        None => {
            let dir = PathBuf::from(arg);
            let label = dir
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .with_context(|| format!("{arg}: no folder name to label it with"))?;
            (label, dir)
        }
    };
    Ok((label, dir))
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut runs = vec![];
    for arg in &args.runs {
        let (label, dir) = parse_run(arg)?;
        let file = ResultsFile::read(&dir)?;
        let medians = RunMedians::of(&label, args.of, &file);
        if medians.rows == 0 {
            let name =
                clap::ValueEnum::to_possible_value(&args.of).map(|v| v.get_name().to_string());
            bail!(
                "{}: no row has a value of {}",
                dir.display(),
                name.unwrap_or_default()
            );
        }
        runs.push(medians);
    }
    let md = markdown(&runs);
    crate::analyze::emit(&md, args.out.as_deref())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(label: &str, medians: &[(&str, f64)], largest: f64) -> RunMedians {
        RunMedians {
            label: label.into(),
            field: Field::LimitFraction,
            medians: medians.iter().map(|(a, m)| (a.to_string(), *m)).collect(),
            rows: 4,
            above_one: usize::from(largest > 1.0),
            largest: Some(largest),
            control: Some((3.84, 8)),
            provenance: "here".into(),
        }
    }

    #[test]
    fn each_later_run_is_divided_by_the_first() {
        let md = markdown(&[
            run("idle", &[("havs", 0.25), ("splat", 0.5)], 0.6),
            run("busy", &[("havs", 0.2), ("splat", 0.55)], 1.2),
        ]);
        assert!(md.starts_with("| algorithm | idle | busy | busy / idle |\n|---|---:|---:|---:|\n"));
        assert!(md.contains("| havs | 0.250 | 0.200 | 0.800 |"), "{md}");
        assert!(md.contains("| splat | 0.500 | 0.550 | 1.100 |"), "{md}");
        assert!(md.contains("- busy: 4 rows priced, 1 above 1 (largest 1.200); control 3.8 s"));
    }

    #[test]
    fn an_algorithm_missing_from_a_run_reads_a_dash() {
        let md = markdown(&[run("a", &[("havs", 0.25)], 0.3), run("b", &[], 0.3)]);
        assert!(md.contains("| havs | 0.250 | – | – |"), "{md}");
    }

    #[test]
    fn labels_come_from_the_argument_or_the_folder() {
        assert_eq!(
            parse_run("idle=x/y").unwrap(),
            ("idle".into(), PathBuf::from("x/y"))
        );
        assert_eq!(
            parse_run("x/busy").unwrap(),
            ("busy".into(), PathBuf::from("x/busy"))
        );
        assert!(parse_run("=x").is_err());
    }
}
