//! Reproductions of Marroquim, Maximo, Farias and Esperança (2006), "GPU-based cell projection
//! for interactive volume rendering":
//!
//! * `tetbench analyze resolution …` — Fig. 8: average K tets/s against viewport size (256²,
//!   512², 768², 1024² by default), one `tetbench run` per size (timing only), plotted as
//!   `fig8.png` / `fig8.svg` with `fig8.md` and `fig8.csv`.
//!
//! The paper's figures come from its transcribed tables (`reports/papers/fragment-pt_table*.csv`,
//! provenance in `reports/papers/fragment-pt.md`); Fig. 8 is a plot whose numbers the text does
//! not give. Tables 1–2 are `tetbench reproduce fragment-pt` (or `tetbench analyze fragment-pt
//! RUN_DIR` for finished runs), written once, in `papers/fragment_pt/mod.rs`.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;

pub use crate::plot::fig8::{write_fig8, SweepPoint};
use crate::report::aggregate;
use crate::results::{ResultsFile, Row};
use crate::run::matrix::MatrixArgs;

fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.digits$}"),
        _ => "–".to_string(),
    }
}

/// `tetbench analyze resolution`: Fig. 8, performance against viewport size. The matrix
/// options' help names Fig. 8's defaults, not `run`'s.
#[derive(Debug, clap::Args)]
#[command(
    mut_arg("algorithms", |a| a.help("Comma-separated algorithms (default: fragment-pt)")),
    mut_arg("datasets", |a| a.help("Comma-separated data sets (default: the paper's spx, bluntfin, comb, post)")),
    mut_arg("viewpoints", |a| a.help("Viewpoints per size, as `tetbench run --viewpoints` (default 14)")),
    mut_arg("frames", |a| a.help("Timed frames per viewpoint (default 5)")),
    mut_arg("warmup", |a| a.help("Untimed warm-up frames (default 1)")),
    mut_arg("resolution", |a| a.hide(true)),
    mut_arg("no_reference", |a| a.hide(true)),
)]
pub struct ResolutionArgs {
    /// Square viewport sizes in pixels (the paper's Fig. 8: 256, 512, 768, 1024).
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "LIST",
        default_value = "256,512,768,1024"
    )]
    pub resolutions: Vec<u32>,
    /// The sweep's matrix (as `tetbench run`'s; left out: fragment-pt on the paper's spx,
    /// bluntfin, comb and post, 14 viewpoints, 5 timed frames after 1 warm-up; always timing
    /// only, and the viewport is --resolutions').
    #[command(flatten)]
    pub matrix: MatrixArgs,
    /// Output directory: one sub-directory per size, and the figure.
    #[arg(long, value_name = "DIR", default_value = "out-resolution")]
    pub out: PathBuf,
}

impl ResolutionArgs {
    /// The matrix of every size: the options given, Fig. 8's defaults for the others.
    fn matrix(&self) -> MatrixArgs {
        self.matrix.or(MatrixArgs {
            algorithms: vec!["fragment-pt".into()],
            datasets: ["spx", "bluntfin", "comb", "post"]
                .map(String::from)
                .to_vec(),
            viewpoints: Some("14".into()),
            frames: Some(5),
            warmup: Some(1),
            // Fig. 8 is about speed: no reference images (they dominate at 1024²).
            no_reference: true,
            ..MatrixArgs::default()
        })
    }
}

/// Averages one run's rows per series (algorithm + settings) over viewpoints, then data sets.
pub fn sweep_points(rows: &[Row], resolution: u32) -> Vec<SweepPoint> {
    let aggs = aggregate(rows);
    let mut out: Vec<SweepPoint> = vec![];
    for a in &aggs {
        let Some(t) = a.tets_per_sec else { continue };
        let series = a.series();
        match out.iter_mut().find(|p| p.series == series) {
            Some(p) => {
                p.k_tets_per_sec += t.mean / 1e3;
                p.datasets += 1;
            }
            None => out.push(SweepPoint {
                series,
                resolution,
                k_tets_per_sec: t.mean / 1e3,
                datasets: 1,
            }),
        }
    }
    for p in &mut out {
        p.k_tets_per_sec /= p.datasets as f64;
    }
    out
}

pub fn run_resolution(args: ResolutionArgs, data_dir: Option<PathBuf>) -> anyhow::Result<()> {
    if args.resolutions.is_empty() {
        anyhow::bail!("--resolutions is empty");
    }
    if args.matrix.resolution.is_some() {
        anyhow::bail!("--resolution: analyze resolution sweeps the viewport; give --resolutions");
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut points: Vec<SweepPoint> = vec![];
    let mut adapter = String::new();
    for &res in &args.resolutions {
        let mut matrix = args.matrix();
        matrix.resolution = Some(res);
        let plan = matrix.plan(args.out.join(format!("res-{res}")));
        let config =
            plan.to_config(data_dir.clone(), vec!["tetbench analyze resolution".into()])?;
        eprintln!("resolution sweep: {res}×{res}");
        let filter = config.settings_filter.clone();
        let outcome = crate::run::run(&config, &|name: &str| plan.matrix.variants(name, &filter))?;
        if !outcome.all_ok() {
            eprintln!(
                "WARNING: {} of {} rows failed at {res}²: {:?}",
                outcome.failed_rows, outcome.rows, outcome.errors
            );
        }
        let file = ResultsFile::read(&config.out)?;
        if let Some(a) = &file.machine.adapter {
            adapter = format!("{} ({})", a.name, a.backend);
        }
        points.extend(sweep_points(&file.rows, res));
    }
    write_fig8(&args.out, &points, &adapter)?;
    let md = fig8_markdown(&points, &adapter);
    std::fs::write(args.out.join("fig8.md"), &md)?;
    let mut w = csv::Writer::from_path(args.out.join("fig8.csv"))?;
    w.write_record(["series", "resolution", "k_tets_per_sec", "datasets"])?;
    for p in &points {
        w.write_record([
            p.series.clone(),
            p.resolution.to_string(),
            p.k_tets_per_sec.to_string(),
            p.datasets.to_string(),
        ])?;
    }
    w.flush()?;
    print!("{md}");
    eprintln!("wrote {}", args.out.join("fig8.png").display());
    Ok(())
}

/// Fig. 8 as a Markdown table: one row per series, one column per size.
pub fn fig8_markdown(points: &[SweepPoint], adapter: &str) -> String {
    let mut sizes: Vec<u32> = points.iter().map(|p| p.resolution).collect();
    sizes.sort();
    sizes.dedup();
    let mut series: Vec<&str> = vec![];
    for p in points {
        if !series.contains(&p.series.as_str()) {
            series.push(&p.series);
        }
    }
    let mut md = format!(
        "### Fig. 8 — average K tets/s against viewport size (Marroquim et al. 2006)\n\nAdapter {adapter}; \
         mean over data sets of the mean over viewpoints. The paper gives Fig. 8 as a plot only (no numbers in its text).\n\n| series |"
    );
    for s in &sizes {
        let _ = write!(md, " {s}² |");
    }
    md.push_str("\n|---|");
    for _ in &sizes {
        md.push_str("---:|");
    }
    md.push('\n');
    for s in &series {
        let _ = write!(md, "| {s} |");
        for r in &sizes {
            let v = points
                .iter()
                .find(|p| p.series == *s && p.resolution == *r)
                .map(|p| p.k_tets_per_sec);
            let _ = write!(md, " {} |", fmt_opt(v, 1));
        }
        md.push('\n');
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fig8_plot_and_table_are_written() {
        let dir = tempfile::tempdir().unwrap();
        let points = vec![
            SweepPoint {
                series: "fragment-pt shading=psi;sort=merge".into(),
                resolution: 256,
                k_tets_per_sec: 900.0,
                datasets: 2,
            },
            SweepPoint {
                series: "fragment-pt shading=psi;sort=merge".into(),
                resolution: 512,
                k_tets_per_sec: 600.0,
                datasets: 2,
            },
            SweepPoint {
                series: "fragment-pt shading=average;sort=gpu".into(),
                resolution: 256,
                k_tets_per_sec: 1200.0,
                datasets: 2,
            },
        ];
        write_fig8(dir.path(), &points, "test adapter").unwrap();
        let svg = std::fs::read_to_string(dir.path().join("fig8.svg")).unwrap();
        assert!(svg.contains("@font-face") && svg.contains("K tets/s"));
        assert!(
            std::fs::metadata(dir.path().join("fig8.png"))
                .unwrap()
                .len()
                > 1000
        );
        let md = fig8_markdown(&points, "test adapter");
        assert!(
            md.contains("| fragment-pt shading=psi;sort=merge | 900.0 | 600.0 |"),
            "{md}"
        );
        assert!(
            md.contains("| fragment-pt shading=average;sort=gpu | 1200.0 | – |"),
            "{md}"
        );
    }
}
