//! `tetbench analyze summary INPUT [--out FILE.md]`: the means over viewpoints of a finished run
//! (its directory, or a results CSV) as Markdown and CSV (`INPUT/summary.md`, `INPUT/summary.csv`),
//! printed too; with `--out`, the Markdown only, to that file.

use std::path::PathBuf;

use anyhow::Context as _;

use crate::plot::data::distinct;
use crate::report::{aggregate, markdown_summary, Spread};
use crate::results::write_file;

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
    /// A `tetbench run` output directory (holds results.json), or a results CSV file.
    pub input: PathBuf,
    /// Write only the Markdown, to this file, instead of INPUT/summary.md and
    /// INPUT/summary.csv (a CSV input needs it).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: Args, _ctx: &super::Context) -> anyhow::Result<()> {
    let rows = super::peers::read_rows(&args.input)?;
    let aggs = aggregate(&rows);
    let sizes = distinct(rows.iter().map(|r| format!("{}×{}", r.width, r.height)));
    let md = format!(
        "Means over viewpoints ({} viewpoints), {}, adapter {}.\n\n{}{}",
        distinct(rows.iter().map(|r| r.viewpoint.as_str())).len(),
        sizes.join(", "),
        distinct(rows.iter().map(|r| r.adapter.as_str())).join(", "),
        markdown_summary(&aggs),
        paper_markdown(&aggs)
    );
    if let Some(out) = &args.out {
        write_file(out, &md)?;
        print!("{md}");
        return Ok(());
    }
    if !args.input.is_dir() {
        anyhow::bail!(
            "{}: a results CSV has no run directory to write summary.md into; name a file with --out",
            args.input.display()
        );
    }
    let md_path = args.input.join("summary.md");
    write_file(&md_path, &md)?;

    let csv_path = args.input.join("summary.csv");
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
