//! `tetbench analyze summary OUT`: the means over viewpoints of a finished run as Markdown and
//! CSV (`OUT/summary.md`, `OUT/summary.csv`), printed too.

use std::path::PathBuf;

use anyhow::Context as _;

use crate::report::{aggregate, markdown_summary, Spread};
use crate::results::ResultsFile;

/// The papers' tets/s beside ours for the series a paper table covers (GATOR Table 3, HAVS
/// Table 4, fragment PT Table 1); empty when none does.
pub fn paper_markdown(aggs: &[crate::report::Aggregate]) -> String {
    let mut md = String::new();
    for a in aggs {
        let Some((source, paper)) =
            crate::papers::transcription::paper_tets_per_sec(&a.algorithm, &a.settings, &a.dataset)
        else {
            continue;
        };
        if md.is_empty() {
            md.push_str(
                "\nThe papers' rates on the same data sets (their GPUs: reports/papers/*.md):\n\n\
                 | algorithm | settings | data set | M tets/s (ours) | M tets/s (paper) | ours/paper | paper table |\n\
                 |---|---|---|---:|---:|---:|---|\n",
            );
        }
        let ours = a.tets_per_sec.map(|s| s.mean);
        md.push_str(&format!(
            "| {} | {} | {} | {} | {:.3} | {} | {source} |\n",
            a.algorithm,
            a.settings,
            a.dataset,
            ours.map(|v| format!("{:.3}", v / 1e6))
                .unwrap_or("–".into()),
            paper / 1e6,
            ours.map(|v| format!("{:.3}", v / paper))
                .unwrap_or("–".into()),
        ));
    }
    md
}

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output directory of a `tetbench run` (holds results.json).
    pub out: PathBuf,
}

pub fn run(args: Args, _ctx: &super::Context) -> anyhow::Result<()> {
    let file = ResultsFile::read(&args.out)?;
    let aggs = aggregate(&file.rows);
    let adapter = file
        .machine
        .adapter
        .as_ref()
        .map(|a| format!("{} ({})", a.name, a.backend))
        .unwrap_or_default();
    let md = format!(
        "Means over viewpoints ({}), {}×{}, adapter {adapter}.\n\n{}{}",
        file.run.viewpoints,
        file.run.width,
        file.run.height,
        markdown_summary(&aggs),
        paper_markdown(&aggs)
    );
    let md_path = args.out.join("summary.md");
    std::fs::write(&md_path, &md).with_context(|| format!("cannot write {}", md_path.display()))?;

    let csv_path = args.out.join("summary.csv");
    let mut w = csv::Writer::from_path(&csv_path)
        .with_context(|| format!("cannot create {}", csv_path.display()))?;
    w.write_record([
        "algorithm",
        "settings",
        "dataset",
        "tets",
        "rows",
        "failed",
        "suspect",
        "total_ms",
        "cpu_ms",
        "gpu_ms",
        "fps",
        "tets_per_sec",
        "psnr_db",
        "psnr_db_min",
        "bad_pixel_share",
        "bytes_per_tet",
    ])?;
    let mean = |s: Option<Spread>| s.map(|s| s.mean.to_string()).unwrap_or_default();
    for a in &aggs {
        w.write_record([
            a.algorithm.clone(),
            a.settings.to_string(),
            a.dataset.clone(),
            a.tets.to_string(),
            a.rows.to_string(),
            a.failed.to_string(),
            a.suspect.to_string(),
            mean(a.total_ms),
            mean(a.cpu_ms),
            mean(a.gpu_ms),
            mean(a.fps),
            mean(a.tets_per_sec),
            mean(a.psnr_db),
            a.psnr_db.map(|s| s.min.to_string()).unwrap_or_default(),
            mean(a.bad_pixel_share),
            a.bytes_per_tet.map(|b| b.to_string()).unwrap_or_default(),
        ])?;
    }
    w.flush()?;
    print!("{md}");
    eprintln!("wrote {} and {}", md_path.display(), csv_path.display());
    Ok(())
}
