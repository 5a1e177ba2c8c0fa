//! `tetbench analyze peers INPUT…`: every variant's speed against each peer's, on the same data
//! set and in the same run, and targets judged on those ratios by rules read from a file written
//! before the runs (`--targets`, e.g. `docs/targets/lavapipe-vs-vtk.json`).
//!
//! A ratio is the median over viewpoints of the variant's tets/s divided by the peer's median in
//! the same input: the two sides met the same machine at the same moment, which is what a ratio
//! between runs cannot say. Beside each target the bound says how far the target is from what
//! the backend allows at all: the variant's tets/s at its roofline (`tets / roofline_ms`, its
//! median over viewpoints) against the peer's gives the highest ratio any implementation doing
//! the variant's counted work could read on that backend, and the target over that ceiling is
//! the limit fraction the variant must reach to meet it (docs/roofline.md).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};
use serde::Deserialize;

use crate::plot::data::distinct;
use crate::results::aggregate::{aggregate, Aggregate};
use crate::results::{read_text, ResultsFile, Row};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Results to read: run directories (results.json) or results CSV files; each is one run,
    /// and ratios are taken within one input only.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Rules to judge (JSON: `source`, and `targets`, each with `name`, `ours` and `peer`
    /// (`algorithm`, `settings` filter), `datasets` and `at_least`).
    #[arg(long)]
    pub targets: Option<PathBuf>,
    /// Also write the Markdown to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print only the judged targets (with `--targets`), not each input's table of ratios.
    #[arg(long, requires = "targets")]
    pub targets_only: bool,
}

/// A rule file: targets on the ratio of one variant's speed to one peer's.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetFile {
    /// Where the rules come from and when they were written (shown with the verdicts).
    pub source: String,
    pub targets: Vec<Target>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Target {
    pub name: String,
    pub ours: Side,
    pub peer: Side,
    /// The data sets the target covers (its cells).
    pub datasets: Vec<String>,
    /// Met when ours / peer ≥ this.
    pub at_least: f64,
}

/// One side of a ratio: an algorithm and a settings filter (`--settings` syntax) that must
/// select exactly one of its variants in a run.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Side {
    pub algorithm: String,
    #[serde(default)]
    pub settings: String,
}

impl TargetFile {
    pub fn read(path: &Path) -> anyhow::Result<TargetFile> {
        let text = read_text(path)?;
        let file: TargetFile = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a target file", path.display()))?;
        for t in &file.targets {
            if !(t.at_least.is_finite() && t.at_least > 0.0) || t.datasets.is_empty() {
                bail!(
                    "{}: target {:?} needs a positive `at_least` and at least one data set",
                    path.display(),
                    t.name
                );
            }
            for side in [&t.ours, &t.peer] {
                side.filter().with_context(|| {
                    format!("{}: target {:?}: bad settings", path.display(), t.name)
                })?;
            }
        }
        Ok(file)
    }
}

impl Side {
    fn filter(&self) -> anyhow::Result<render_core::SettingsFilter> {
        Ok(render_core::SettingsFilter::parse(&self.settings)?)
    }

    /// The one group of `aggs` on `dataset` this side selects; `None` when none does.
    fn pick<'a>(
        &self,
        aggs: &'a [Aggregate],
        dataset: &str,
    ) -> anyhow::Result<Option<&'a Aggregate>> {
        let filter = self.filter()?;
        let found: Vec<&Aggregate> = aggs
            .iter()
            .filter(|a| {
                a.dataset == dataset && a.algorithm == self.algorithm && filter.accepts(&a.settings)
            })
            .collect();
        match found.as_slice() {
            [] => Ok(None),
            [one] => Ok(Some(one)),
            many => bail!(
                "{} {:?} selects {} variants on {dataset} ({}); a target names one",
                self.algorithm,
                self.settings,
                many.len(),
                many.iter()
                    .map(|a| a.settings.to_string())
                    .collect::<Vec<_>>()
                    .join(" | ")
            ),
        }
    }
}

/// A target's verdict on one data set of one run.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    Met,
    Missed,
    /// No verdict: a side has no rows, or some of its rows failed.
    NoEvidence(String),
}

impl Verdict {
    pub fn word(&self) -> String {
        match self {
            Verdict::Met => "**met**".into(),
            Verdict::Missed => "missed".into(),
            Verdict::NoEvidence(why) => format!("no verdict ({why})"),
        }
    }
}

/// One cell of a target: the ratio, its verdict and where it stands against the bound.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    pub target: String,
    pub input: String,
    pub dataset: String,
    /// Median tets/s of our variant and of the peer.
    pub ours: Option<f64>,
    pub peer: Option<f64>,
    pub ratio: Option<f64>,
    pub at_least: f64,
    pub verdict: Verdict,
    /// The ratio our variant would read at its roofline (None without a calibration).
    pub ceiling: Option<f64>,
}

impl Cell {
    /// The limit fraction our variant needs to meet the target (above 1: out of reach of any
    /// implementation doing the counted work on this backend).
    pub fn fraction_needed(&self) -> Option<f64> {
        self.ceiling.map(|c| self.at_least / c)
    }
}

fn median_rate(a: &Aggregate) -> Option<f64> {
    a.tets_per_sec.map(|s| s.median)
}

/// Judges `target` on `dataset` in one input's groups.
pub fn judge(
    target: &Target,
    input: &str,
    aggs: &[Aggregate],
    dataset: &str,
) -> anyhow::Result<Option<Cell>> {
    let ours = target.ours.pick(aggs, dataset)?;
    let peer = target.peer.pick(aggs, dataset)?;
    if ours.is_none() && peer.is_none() {
        return Ok(None);
    }
    let missing = |side: &Side| format!("no {} rows", side.algorithm);
    let failed = |a: &Aggregate| format!("{} of {} {} rows failed", a.failed, a.rows, a.algorithm);
    let verdict_of = |ratio: Option<f64>| -> Verdict {
        match (ours, peer) {
            (None, _) => Verdict::NoEvidence(missing(&target.ours)),
            (_, None) => Verdict::NoEvidence(missing(&target.peer)),
            (Some(a), _) if a.failed > 0 => Verdict::NoEvidence(failed(a)),
            (_, Some(p)) if p.failed > 0 => Verdict::NoEvidence(failed(p)),
            _ => match ratio {
                Some(r) if r >= target.at_least => Verdict::Met,
                Some(_) => Verdict::Missed,
                None => Verdict::NoEvidence("no timed rows".into()),
            },
        }
    };
    let ours_rate = ours.and_then(median_rate);
    let peer_rate = peer.and_then(median_rate);
    let ratio = ours_rate.zip(peer_rate).map(|(o, p)| o / p);
    let ceiling = ours
        .and_then(|a| a.bound_tets_per_sec)
        .zip(peer_rate)
        .map(|(b, p)| b.median / p);
    Ok(Some(Cell {
        target: target.name.clone(),
        input: input.to_string(),
        dataset: dataset.to_string(),
        ours: ours_rate,
        peer: peer_rate,
        ratio,
        at_least: target.at_least,
        verdict: verdict_of(ratio),
        ceiling,
    }))
}

/// Rows of a run directory (results.json) or of a results CSV file.
pub fn read_rows(path: &Path) -> anyhow::Result<Vec<Row>> {
    if path.is_dir() {
        return Ok(ResultsFile::read(path)?.rows);
    }
    let mut reader =
        csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
    let headers = reader
        .headers()
        .with_context(|| format!("{}: no header line", path.display()))?;
    if !headers.iter().any(|h| h == "algorithm") {
        bail!(
            "{}: not a results CSV (its header has no `algorithm` column)",
            path.display()
        );
    }
    let mut rows = vec![];
    for (i, row) in reader.deserialize::<Row>().enumerate() {
        let mut row: Row =
            row.with_context(|| format!("{}: row {} is not a result row", path.display(), i + 1))?;
        row.retype_settings();
        rows.push(row);
    }
    crate::algorithms::note_external_rows(rows.iter().map(|r| (r.algorithm.as_str(), &r.settings)));
    Ok(rows)
}

fn rate(v: Option<f64>) -> String {
    match v {
        Some(v) if v >= 1e6 => format!("{:.2} M", v / 1e6),
        Some(v) => format!("{:.1} K", v / 1e3),
        None => "–".into(),
    }
}

fn ratio(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{v:.2}"))
}

/// One input's table: every variant per data set, with its ratio to each peer present.
pub fn ratio_table(aggs: &[Aggregate]) -> String {
    let peers = distinct(
        aggs.iter()
            .map(|a| a.algorithm.as_str())
            .filter(|a| crate::algorithms::is_peer(a)),
    );
    let mut md = String::new();
    for d in distinct(aggs.iter().map(|a| a.dataset.as_str())) {
        let here: Vec<&Aggregate> = aggs.iter().filter(|a| a.dataset == d).collect();
        let _ = write!(
            md,
            "\n**{d}** (medians over viewpoints)\n\n| algorithm | settings | tets/s | PSNR dB | failed |"
        );
        for p in &peers {
            let _ = write!(md, " / `{p}` |");
        }
        md.push_str("\n|---|---|---:|---:|---:|");
        md.push_str(&"---:|".repeat(peers.len()));
        md.push('\n');
        for a in &here {
            let _ = write!(
                md,
                "| `{}` | {} | {} | {} | {} |",
                a.algorithm,
                a.settings,
                rate(median_rate(a)),
                a.psnr_db.map_or("–".into(), |p| format!("{:.1}", p.median)),
                a.failed
            );
            for p in &peers {
                let peer_rate = here
                    .iter()
                    .find(|g| g.algorithm == *p)
                    .and_then(|g| median_rate(g));
                let r = median_rate(a).zip(peer_rate).map(|(o, p)| o / p);
                let _ = write!(
                    md,
                    " {} |",
                    if a.algorithm == *p {
                        "—".into()
                    } else {
                        ratio(r)
                    }
                );
            }
            md.push('\n');
        }
    }
    md
}

/// The targets' cells as a Markdown table.
pub fn target_table(source: &str, cells: &[Cell]) -> String {
    let mut md = format!(
        "\nTargets ({source}). Ratio: median tets/s over viewpoints, ours / the peer's, in one run. \
         Ceiling: the ratio at our variant's roofline; needed: the limit fraction the target asks of it.\n\n\
         | target | data set | run | ours | peer | ratio | rule | verdict | ceiling | fraction needed |\n\
         |---|---|---|---:|---:|---:|---|---|---:|---:|\n"
    );
    for c in cells {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | ≥ {} | {} | {} | {} |",
            c.target,
            c.dataset,
            c.input,
            rate(c.ours),
            rate(c.peer),
            ratio(c.ratio),
            c.at_least,
            c.verdict.word(),
            ratio(c.ceiling),
            c.fraction_needed()
                .map_or("–".into(), |f| format!("{f:.2}")),
        );
    }
    md
}

/// Where several runs judged one target on one data set: how many met it, and the spread of
/// their ratios. Each run's verdict stands on its own; this says how far one run's verdict
/// can be trusted to repeat.
pub fn repeat_table(cells: &[Cell]) -> String {
    let mut md = String::new();
    for (target, dataset) in distinct(
        cells
            .iter()
            .map(|c| (c.target.as_str(), c.dataset.as_str())),
    ) {
        let runs: Vec<&Cell> = cells
            .iter()
            .filter(|c| c.target == target && c.dataset == dataset)
            .collect();
        if runs.len() < 2 {
            continue;
        }
        if md.is_empty() {
            md.push_str(
                "\nTargets judged in more than one run (each run's verdict above stands on its own):\n\n\
                 | target | data set | runs | met | ratio min–max |\n|---|---|---:|---:|---|\n",
            );
        }
        let ratios: Vec<f64> = runs.iter().filter_map(|c| c.ratio).collect();
        let (lo, hi) = ratios
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &r| {
                (l.min(r), h.max(r))
            });
        let spread = if ratios.is_empty() {
            "–".to_string()
        } else {
            format!("{lo:.2}–{hi:.2}")
        };
        let _ = writeln!(
            md,
            "| {target} | {dataset} | {} | {} | {spread} |",
            runs.len(),
            runs.iter().filter(|c| c.verdict == Verdict::Met).count()
        );
    }
    md
}

/// Every target's cells over the inputs: one cell per target, data set and input that holds
/// either side.
pub fn judge_all(
    file: &TargetFile,
    inputs: &[(String, Vec<Aggregate>)],
) -> anyhow::Result<Vec<Cell>> {
    let mut cells = vec![];
    for t in &file.targets {
        for d in &t.datasets {
            let before = cells.len();
            for (name, aggs) in inputs {
                if let Some(c) = judge(t, name, aggs, d)
                    .with_context(|| format!("{name}: target {:?}", t.name))?
                {
                    cells.push(c);
                }
            }
            if cells.len() == before {
                cells.push(Cell {
                    target: t.name.clone(),
                    input: "–".into(),
                    dataset: d.clone(),
                    ours: None,
                    peer: None,
                    ratio: None,
                    at_least: t.at_least,
                    verdict: Verdict::NoEvidence("no input has this data set".into()),
                    ceiling: None,
                });
            }
        }
    }
    Ok(cells)
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut inputs = vec![];
    let mut md = String::new();
    for path in &args.inputs {
        let rows = read_rows(path)?;
        if rows.is_empty() {
            bail!("{}: no rows", path.display());
        }
        let aggs = aggregate(&rows);
        let adapters: Vec<&str> = {
            let mut v: Vec<&str> = rows.iter().map(|r| r.adapter.as_str()).collect();
            v.sort();
            v.dedup();
            v
        };
        if !args.targets_only {
            let _ = write!(
                md,
                "\n### {} ({} rows, adapter {})\n{}",
                path.display(),
                rows.len(),
                adapters.join(", "),
                ratio_table(&aggs)
            );
        }
        inputs.push((path.display().to_string(), aggs));
    }
    if let Some(t) = &args.targets {
        let file = TargetFile::read(t)?;
        let cells = judge_all(&file, &inputs)?;
        md.push_str(&target_table(&file.source, &cells));
        md.push_str(&repeat_table(&cells));
    }
    crate::analyze::emit(&md, args.out.as_deref())
}

#[cfg(test)]
#[path = "peers_tests.rs"]
mod tests;
