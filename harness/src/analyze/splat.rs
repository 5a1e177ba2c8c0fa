//! `tetbench analyze splat OUT`: Grau & Tost (2007) Table 1 — per volume its size, effective
//! voxels, fps with CPU-built buckets, fps with GPU-built buckets and their ratio — from the
//! `splat` rows of a finished run, with the paper's figures (`reports/papers/splat_table1.csv`)
//! beside ours.
//!
//! The paper's six volumes are not available: the stand-ins `lobster` … `stagbeetle` (also
//! spelled `standin:NAME`; generated, see `datasets::standins`) have the same grid dimensions and effective-voxel counts (under a
//! transfer function with κ(0) = 0), so only the amount of work stands in, not the pictures.
//! ironProt and HeadMRVolume are real volumes the paper did not use.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;

use crate::results::{ResultsFile, Row};

/// The paper's Table 1, as transcribed into the project.
const PAPER_CSV: &str = include_str!("../../../reports/papers/splat_table1.csv");

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output directory of a finished `tetbench run --algorithms splat …`.
    pub out: PathBuf,
}

/// One row of the paper's Table 1.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct PaperRow {
    pub dataset: String,
    pub dim_x_voxels: u32,
    pub dim_y_voxels: u32,
    pub dim_z_voxels: u32,
    pub effective_voxels: u64,
    pub cpu_buckets_fps: f64,
    pub gpu_buckets_fps: f64,
}

pub fn paper_table() -> anyhow::Result<Vec<PaperRow>> {
    let mut r = csv::Reader::from_reader(PAPER_CSV.as_bytes());
    r.deserialize()
        .collect::<Result<Vec<PaperRow>, _>>()
        .context("reports/papers/splat_table1.csv")
}

pub fn run(args: Args, _ctx: &super::Context) -> anyhow::Result<()> {
    let file = ResultsFile::read(&args.out)?;
    let md = write_table(&file.rows, &args.out)?;
    print!("{md}");
    Ok(())
}

/// The settings of a row other than the bucket site and the sort: rows that differ only there
/// are compared.
fn common_settings(r: &Row) -> String {
    r.settings
        .split(';')
        .filter(|kv| !kv.starts_with("buckets=") && !kv.starts_with("sort="))
        .collect::<Vec<_>>()
        .join(";")
}

fn mean(v: impl Iterator<Item = f64>) -> Option<f64> {
    let v: Vec<f64> = v.filter(|x| x.is_finite()).collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn fmt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |x| format!("{x:.digits$}"))
}

/// The paper's row for a stand-in's data set name (`lobster`, `standin:lobster`, `teapot` ↔
/// BostonTeapot): both sides go through the stand-ins' own name lookup.
fn paper_row<'a>(paper: &'a [PaperRow], dataset: &str) -> Option<&'a PaperRow> {
    let ours = datasets::standins::find(dataset)?;
    paper
        .iter()
        .find(|p| datasets::standins::find(&p.dataset).is_some_and(|s| s.name == ours.name))
}

/// One line of our table.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    pub dataset: String,
    pub settings: String,
    pub dims: Option<[u64; 3]>,
    pub effective: Option<f64>,
    pub cpu_fps: Option<f64>,
    pub gpu_fps: Option<f64>,
    pub gpu_radix_fps: Option<f64>,
    pub psnr: Option<f64>,
    pub bytes_per_voxel: Option<f64>,
}

impl Line {
    pub fn ratio(&self) -> Option<f64> {
        Some(self.gpu_fps? / self.cpu_fps?)
    }
}

/// Groups the splat rows by data set and common settings; means over viewpoints.
pub fn lines(rows: &[Row]) -> Vec<Line> {
    let ok: Vec<&Row> = rows
        .iter()
        .filter(|r| r.algorithm == "splat" && r.error.is_empty() && r.fps.is_some())
        .collect();
    let mut keys: Vec<(String, String)> = vec![];
    for r in &ok {
        let k = (r.dataset.clone(), common_settings(r));
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(dataset, settings)| {
            let g: Vec<&Row> = ok
                .iter()
                .copied()
                .filter(|r| r.dataset == dataset && common_settings(r) == settings)
                .collect();
            let fps = |b: &str, s: Option<&str>| {
                mean(
                    g.iter()
                        .filter(|r| {
                            r.setting("buckets") == Some(b)
                                && s.is_none_or(|s| r.setting("sort") == Some(s))
                        })
                        .filter_map(|r| r.fps),
                )
            };
            let first = g[0];
            let dims = match (
                first.counter("grid_x"),
                first.counter("grid_y"),
                first.counter("grid_z"),
            ) {
                (Some(x), Some(y), Some(z)) => Some([x as u64, y as u64, z as u64]),
                _ => None,
            };
            Line {
                dataset,
                settings,
                dims,
                effective: first.counter("effective_voxels"),
                cpu_fps: fps("cpu", None),
                gpu_fps: fps("gpu", Some("bitonic")).or_else(|| fps("gpu", Some("radix"))),
                gpu_radix_fps: fps("gpu", Some("radix")),
                psnr: mean(g.iter().filter_map(|r| r.psnr_db)),
                bytes_per_voxel: first.counter("bytes_per_voxel"),
            }
        })
        .collect()
}

/// Writes `splat_table1.md` and `splat_table1.csv` into `out` from finished rows and returns
/// the Markdown.
pub fn write_table(rows: &[Row], out: &Path) -> anyhow::Result<String> {
    let paper = paper_table()?;
    let ours = lines(rows);
    let adapter = rows
        .iter()
        .find(|r| r.algorithm == "splat")
        .map(|r| format!("{} ({})", r.adapter, r.device_type))
        .unwrap_or_else(|| "no splat rows".into());
    let sample = rows.iter().find(|r| r.algorithm == "splat");
    let mut md = String::new();
    let _ = writeln!(
        md,
        "### Grau & Tost 2007, Table 1 — CPU-built vs GPU-built buckets\n\n\
         Ours: means over viewpoints{}, adapter {adapter}. GPU fps is the bitonic sort (the \
         paper's); `GPU radix` uses render-core's radix sort instead. Paper: Pentium Dual Core \
         3.2 GHz, GeForce 7900 GTX, camera moving, viewport not stated.\n",
        sample
            .map(|r| format!(" at {}×{}, {} timed frames", r.width, r.height, r.frames))
            .unwrap_or_default()
    );
    let _ = writeln!(
        md,
        "| data set | size | effective voxels | CPU fps | GPU fps | GPU/CPU | GPU radix fps | PSNR dB | B/voxel | paper size | paper eff. voxels | paper CPU fps | paper GPU fps | paper GPU/CPU | settings |"
    );
    let _ = writeln!(
        md,
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---|"
    );
    let mut csv = String::from(
        "dataset,standin,dim_x,dim_y,dim_z,effective_voxels,cpu_fps,gpu_fps,gpu_over_cpu,gpu_radix_fps,psnr_db,bytes_per_voxel,paper_effective_voxels,paper_cpu_fps,paper_gpu_fps,paper_gpu_over_cpu,settings\n",
    );
    let mut ratios = vec![];
    for l in &ours {
        let p = paper_row(&paper, &l.dataset);
        let standin = p.is_some();
        let name = if standin {
            format!("{} (stand-in, generated)", l.dataset)
        } else {
            l.dataset.clone()
        };
        let size = l
            .dims
            .map_or("–".into(), |d| format!("{}×{}×{}", d[0], d[1], d[2]));
        if let Some(r) = l.ratio() {
            ratios.push(r);
        }
        let (psize, peff, pcpu, pgpu, pratio) = match p {
            Some(p) => (
                format!("{}×{}×{}", p.dim_x_voxels, p.dim_y_voxels, p.dim_z_voxels),
                p.effective_voxels.to_string(),
                format!("{:.1}", p.cpu_buckets_fps),
                format!("{:.1}", p.gpu_buckets_fps),
                format!("{:.2}", p.gpu_buckets_fps / p.cpu_buckets_fps),
            ),
            None => (
                "not in paper".into(),
                "–".into(),
                "–".into(),
                "–".into(),
                "–".into(),
            ),
        };
        let _ = writeln!(
            md,
            "| {name} | {size} | {} | {} | {} | {} | {} | {} | {} | {psize} | {peff} | {pcpu} | {pgpu} | {pratio} | {} |",
            fmt(l.effective, 0),
            fmt(l.cpu_fps, 2),
            fmt(l.gpu_fps, 2),
            fmt(l.ratio(), 2),
            fmt(l.gpu_radix_fps, 2),
            fmt(l.psnr, 1),
            fmt(l.bytes_per_voxel, 1),
            l.settings
        );
        let d = l.dims.unwrap_or([0; 3]);
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\"",
            l.dataset,
            standin,
            d[0],
            d[1],
            d[2],
            fmt(l.effective, 0),
            fmt(l.cpu_fps, 4),
            fmt(l.gpu_fps, 4),
            fmt(l.ratio(), 4),
            fmt(l.gpu_radix_fps, 4),
            fmt(l.psnr, 2),
            fmt(l.bytes_per_voxel, 2),
            p.map_or(String::new(), |p| p.effective_voxels.to_string()),
            p.map_or(String::new(), |p| p.cpu_buckets_fps.to_string()),
            p.map_or(String::new(), |p| p.gpu_buckets_fps.to_string()),
            p.map_or(String::new(), |p| format!(
                "{:.4}",
                p.gpu_buckets_fps / p.cpu_buckets_fps
            )),
            l.settings
        );
    }
    if ours.is_empty() {
        let _ = writeln!(md, "| (no splat rows in this run) |||||||||||||||");
    }
    let paper_ratios: Vec<f64> = paper
        .iter()
        .map(|p| p.gpu_buckets_fps / p.cpu_buckets_fps)
        .collect();
    let _ = writeln!(
        md,
        "\nGPU/CPU bucket ratio: ours {} (mean over the lines above); paper {:.2}–{:.2} (mean {:.2}; \
         §5 states 2–2.5). Stand-ins are generated volumes with the paper volumes' grid size and \
         effective-voxel count; their pictures are not the originals'. The paper's volumes \
         whose stand-ins do not appear were not run.",
        fmt(mean(ratios.iter().copied()), 2),
        paper_ratios.iter().copied().fold(f64::INFINITY, f64::min),
        paper_ratios.iter().copied().fold(0.0, f64::max),
        paper_ratios.iter().sum::<f64>() / paper_ratios.len() as f64
    );
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let md_path = out.join("splat_table1.md");
    std::fs::write(&md_path, &md).with_context(|| format!("cannot write {}", md_path.display()))?;
    let csv_path = out.join("splat_table1.csv");
    std::fs::write(&csv_path, &csv)
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_table_parses() {
        let p = paper_table().unwrap();
        assert_eq!(p.len(), 6);
        assert_eq!(p[0].dataset, "Lobster");
        assert!((p[0].gpu_buckets_fps / p[0].cpu_buckets_fps - 2.68).abs() < 0.01);
        assert!(paper_row(&p, "standin:stagbeetle").is_some());
        assert_eq!(paper_row(&p, "teapot").unwrap().dataset, "BostonTeapot");
        assert_eq!(paper_row(&p, "lobster").unwrap().dataset, "Lobster");
        assert!(paper_row(&p, "ironprot").is_none());
    }
}
