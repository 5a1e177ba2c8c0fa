//! `tetbench plot KIND RESULTS… --out DIR [--sweep SPEC …]`: draws charts from results
//! already measured, or runs a sweep first (mesh sizes for `scaling`, viewport sizes for
//! `resolution`) with the run loop of `tetbench run` and then draws them.

use std::path::{Path, PathBuf};

use anyhow::Context;

use crate::plot::data::Inputs;
use crate::plot::Kind;
use crate::results::write_file;
use crate::run::matrix::MatrixArgs;
use crate::run::plan::RunPlan;

/// The matrix options' help names the sweep's defaults, not `run`'s.
#[derive(Debug, clap::Args)]
#[command(
    mut_arg("algorithms", |a| a.help("Sweep: comma-separated algorithms (default: all)")),
    mut_arg("datasets", |a| a.help("Sweep (resolution): data sets (default box:100k)")),
    mut_arg("viewpoints", |a| a.help("Sweep: viewpoints, as `tetbench run --viewpoints` (default +x,+x+y+z,-x+y-z)")),
    mut_arg("resolution", |a| a.help("Sweep (scaling): square viewport in pixels (default 128)")),
    mut_arg("frames", |a| a.help("Sweep: timed frames per viewpoint (default 3)")),
    mut_arg("warmup", |a| a.help("Sweep: warm-up frames (default 1)")),
)]
pub struct PlotArgs {
    /// Which charts: speed-error, scaling, resolution, bars or all.
    #[arg(value_enum)]
    pub kind: Kind,
    /// Results to draw from: run directories, results.json files, or directories whose
    /// sub-directories hold runs (shards, sweeps). Optional with --sweep.
    pub results: Vec<PathBuf>,
    /// Output directory for the charts (PNG, SVG, CSV) and key.csv.
    #[arg(long, value_name = "DIR", default_value = "plots")]
    pub out: PathBuf,
    /// Measure first, then plot: for `scaling` the mesh sizes (`box:10k,100k,1m,5m`: sizes
    /// after the first keep its generator; names and files also allowed), for `resolution`
    /// the square viewport sizes (`128,256,512`). Runs go to OUT/sweep/; the matrix options
    /// apply to the sweep.
    #[arg(long, value_name = "SPEC")]
    pub sweep: Option<String>,
    /// The sweep's matrix (as `tetbench run`'s).
    #[command(flatten)]
    pub matrix: MatrixArgs,
}

/// `box:10k,100k,1m` → `box:10k`, `box:100k`, `box:1m`; names and paths are kept as given.
pub fn expand_sizes(spec: &str) -> Vec<String> {
    let mut generator: Option<String> = None;
    let mut out = vec![];
    for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        if let Some((g, _)) = item.split_once(':') {
            generator = Some(g.to_string());
            out.push(item.to_string());
        } else if let (Some(g), true) = (&generator, item.starts_with(|c: char| c.is_ascii_digit()))
        {
            out.push(format!("{g}:{item}"));
        } else {
            generator = None;
            out.push(item.to_string());
        }
    }
    out
}

impl PlotArgs {
    /// One sweep step: the given matrix options, the sweep's defaults for those left out
    /// (the suite's number of samples, in one round: a sweep's large meshes should not all
    /// stay prepared at once), and the step's data sets and viewport.
    fn run_args(&self, datasets: Vec<String>, resolution: u32, out: PathBuf) -> RunPlan {
        let suite = &crate::run::suite::DEFAULT_SUITE;
        let mut matrix = self.matrix.or(MatrixArgs {
            viewpoints: Some(suite.viewpoints.to_string()),
            frames: Some(suite.frames * suite.rounds),
            warmup: Some(suite.warmup),
            ..MatrixArgs::default()
        });
        matrix.datasets = datasets;
        matrix.resolution = Some(resolution);
        matrix.plan(out)
    }
}

/// Runs one sweep step; failures of rows are reported and kept (they are plotted as missing).
fn measure(
    args: RunPlan,
    data_dir: Option<PathBuf>,
    command_line: &[String],
) -> anyhow::Result<PathBuf> {
    let out = args.out.clone();
    let config = args.to_config(data_dir, command_line.to_vec())?;
    let filter = config.settings_filter.clone();
    let outcome = crate::run::run(&config, &|name: &str| args.matrix.variants(name, &filter))?;
    if !outcome.all_ok() {
        eprintln!(
            "tetbench plot: {} of {} rows failed in {} (plotted as missing){}",
            outcome.failed_rows,
            outcome.rows,
            out.display(),
            outcome
                .errors
                .iter()
                .map(|e| format!("\n  {e}"))
                .collect::<String>()
        );
    }
    Ok(out)
}

/// Runs the sweep `spec` for `kind`; returns the run directories.
fn sweep(
    args: &PlotArgs,
    spec: &str,
    data_dir: Option<PathBuf>,
    command_line: &[String],
) -> anyhow::Result<Vec<PathBuf>> {
    let root = args.out.join("sweep");
    match args.kind {
        Kind::Scaling => {
            let datasets = expand_sizes(spec);
            if datasets.len() < 2 {
                anyhow::bail!("--sweep {spec:?}: a scaling sweep needs at least two mesh sizes");
            }
            let res = args
                .matrix
                .resolution
                .unwrap_or(crate::run::suite::DEFAULT_SUITE.resolution);
            Ok(vec![measure(
                args.run_args(datasets, res, root.join("scaling")),
                data_dir,
                command_line,
            )?])
        }
        Kind::Resolution => {
            let sizes: Vec<u32> = spec
                .split(',')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(|s| {
                    s.parse::<u32>().map_err(|_| {
                        anyhow::anyhow!("--sweep {spec:?}: {s:?} is not a viewport size in pixels")
                    })
                })
                .collect::<anyhow::Result<_>>()?;
            if sizes.len() < 2 {
                anyhow::bail!("--sweep {spec:?}: a resolution sweep needs at least two sizes");
            }
            let datasets = if args.matrix.datasets.is_empty() {
                vec!["box:100k".to_string()]
            } else {
                args.matrix.datasets.clone()
            };
            sizes
                .iter()
                .map(|&n| {
                    eprintln!("tetbench plot: viewport {n}×{n}");
                    measure(
                        args.run_args(datasets.clone(), n, root.join(format!("res-{n}"))),
                        data_dir.clone(),
                        command_line,
                    )
                })
                .collect()
        }
        k => anyhow::bail!(
            "--sweep works with `scaling` (mesh sizes) or `resolution` (viewport sizes), not {:?}",
            k
        ),
    }
}

/// `tetbench plot …`.
pub fn run(
    args: PlotArgs,
    data_dir: Option<PathBuf>,
    command_line: Vec<String>,
) -> anyhow::Result<()> {
    let mut sources = args.results.clone();
    if let Some(spec) = &args.sweep {
        sources.extend(sweep(&args, spec, data_dir, &command_line)?);
    } else if !args.matrix.datasets.is_empty()
        || args.matrix.resolution.is_some()
        || args.matrix.no_reference
    {
        anyhow::bail!("--datasets, --resolution and --no-reference only apply with --sweep");
    }
    let inputs = Inputs::read(&sources)?;
    let charts = crate::plot::write_charts(&args.out, &inputs, args.kind)
        .with_context(|| format!("drawing charts into {}", args.out.display()))?;
    for (k, why) in &charts.skipped {
        eprintln!(
            "tetbench plot: no {} chart: {why}",
            k.heading().to_lowercase()
        );
    }
    if charts.files.is_empty() {
        anyhow::bail!("nothing to plot from {} row(s)", inputs.rows.len());
    }
    if !charts.fits.is_empty() {
        let md = crate::plot::scaling::fits_markdown(&charts.fits);
        let path = args.out.join("scaling_fits.md");
        write_file(&path, &md)?;
        print!("{md}");
    }
    print_files(&args.out, &charts.files);
    Ok(())
}

fn print_files(dir: &Path, files: &[crate::plot::ChartFile]) {
    for f in files {
        println!(
            "{}  {}.{{png,svg,csv}}",
            f.title,
            dir.join(&f.stem).display()
        );
    }
    println!("key: {}", dir.join("key.csv").display());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweep_sizes_inherit_the_generator() {
        assert_eq!(
            expand_sizes("box:10k,100k, 1m,spx,shell:20k,50k"),
            [
                "box:10k",
                "box:100k",
                "box:1m",
                "spx",
                "shell:20k",
                "shell:50k"
            ]
        );
    }
}
