//! `tetbench history DIR…`: each algorithm × settings × data set over a series of runs (given
//! in commit order, e.g. the committed baselines), with the noise band and the points where
//! `compare`'s pooled test finds a change against the run before.
//!
//! Per run and group the time is the median over viewpoints of the rows' median `total_ms`;
//! the band is the 10–90 % range of all of the group's frames, each divided by its row's median
//! and multiplied by that time (the frame-to-frame noise, comparable across groups). PSNR is
//! the mean over viewpoints; a change > 0.1 dB is marked as well.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context};
use plotters::prelude::*;
use serde::Serialize;

use crate::compare::{time_test, Verdict, PSNR_TOLERANCE_DB};
use crate::plot::draw::{register_font, FONT};
use crate::results::{ResultsFile, Row};
use crate::stats::{median, quantile};

#[derive(Debug, Clone, Serialize)]
pub struct Point {
    pub run: usize,
    pub total_ms: f64,
    pub band_lo: f64,
    pub band_hi: f64,
    pub psnr_db: Option<f64>,
    pub gpu_bytes: Option<u64>,
    /// Against the previous run of this group: `slower`, `faster`, `psnr ±x dB`, `memory`.
    pub changes: Vec<String>,
}

#[derive(Debug, Clone, Serialize)]
pub struct Series {
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    pub points: Vec<Point>,
}

#[derive(Debug, Clone, Serialize)]
pub struct History {
    /// Label per run: short commit and date.
    pub runs: Vec<String>,
    pub series: Vec<Series>,
}

fn group_rows<'a>(f: &'a ResultsFile, g: &(String, String, String)) -> Vec<&'a Row> {
    f.rows
        .iter()
        .filter(|r| (&r.algorithm, &r.settings, &r.dataset) == (&g.0, &g.1, &g.2) && r.ok())
        .collect()
}

/// Pooled frames of a group, each divided by `scale(row)`.
fn pooled(rows: &[&Row], scale: impl Fn(&Row) -> Option<f64>) -> Vec<f64> {
    rows.iter()
        .filter_map(|r| scale(r).map(|m| r.samples.total_ms.iter().map(move |x| x / m)))
        .flatten()
        .collect()
}

pub fn history(dirs: &[PathBuf], threshold: f64, alpha: f64) -> anyhow::Result<History> {
    let files: Vec<ResultsFile> = dirs
        .iter()
        .map(|d| ResultsFile::read(d))
        .collect::<anyhow::Result<_>>()?;
    let runs = files
        .iter()
        .zip(dirs)
        .map(|(f, d)| {
            let c = f.machine.git_commit.as_deref().unwrap_or("?");
            format!(
                "{} {}",
                &c[..c.len().min(7)],
                d.file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default()
            )
        })
        .collect();
    let mut groups: Vec<(String, String, String)> = vec![];
    for f in &files {
        for r in &f.rows {
            let g = (r.algorithm.clone(), r.settings.clone(), r.dataset.clone());
            if !groups.contains(&g) {
                groups.push(g);
            }
        }
    }
    let mut series = vec![];
    for g in groups {
        let mut points: Vec<Point> = vec![];
        let mut prev: Option<usize> = None;
        for (i, f) in files.iter().enumerate() {
            let rows = group_rows(f, &g);
            let medians: Vec<f64> = rows.iter().filter_map(|r| r.total_ms).collect();
            if medians.is_empty() {
                continue;
            }
            let t = median(&medians);
            let noise = pooled(&rows, |r| r.total_ms);
            let (lo, hi) = if noise.is_empty() {
                (t, t)
            } else {
                (t * quantile(&noise, 0.1), t * quantile(&noise, 0.9))
            };
            let psnr: Vec<f64> = rows.iter().filter_map(|r| r.psnr_db).collect();
            let mut p = Point {
                run: i,
                total_ms: t,
                band_lo: lo,
                band_hi: hi,
                psnr_db: (!psnr.is_empty()).then(|| psnr.iter().sum::<f64>() / psnr.len() as f64),
                gpu_bytes: rows.iter().filter_map(|r| r.gpu_bytes).max(),
                changes: vec![],
            };
            if let Some(j) = prev {
                let before = group_rows(&files[j], &g);
                // Each viewpoint normalised by the earlier run's median, as compare's group test.
                let base_median = |r: &Row| {
                    before
                        .iter()
                        .find(|b| (&b.viewpoint, b.width) == (&r.viewpoint, r.width))
                        .and_then(|b| b.total_ms)
                };
                let b = pooled(&before, |r| base_median(r));
                let n = pooled(&rows, |r| base_median(r));
                match time_test("total_ms", &b, &n, threshold, alpha).verdict {
                    Verdict::Slower => p.changes.push("slower".into()),
                    Verdict::Faster => p.changes.push("faster".into()),
                    _ => {}
                }
                let last = &points[points.len() - 1];
                if let (Some(a), Some(b)) = (last.psnr_db, p.psnr_db) {
                    if (b - a).abs() > PSNR_TOLERANCE_DB {
                        p.changes.push(format!("psnr {:+.2} dB", b - a));
                    }
                }
                if last.gpu_bytes != p.gpu_bytes {
                    p.changes.push("memory".into());
                }
            }
            prev = Some(i);
            points.push(p);
        }
        series.push(Series {
            algorithm: g.0,
            settings: g.1,
            dataset: g.2,
            points,
        });
    }
    Ok(History { runs, series })
}

/// One chart per algorithm × data set: a line per settings variant, its noise band, and a
/// marker where a change was found (red ▲ slower, green ▼ faster, black ● other).
fn chart(path: &Path, h: &History, alg: &str, dataset: &str) -> anyhow::Result<()> {
    register_font();
    let series: Vec<&Series> = h
        .series
        .iter()
        .filter(|s| s.algorithm == alg && s.dataset == dataset)
        .collect();
    let ymax = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.band_hi.max(p.total_ms)))
        .fold(0.0, f64::max)
        * 1.15;
    let root = BitMapBackend::new(path, (1100, 460)).into_drawing_area();
    let err = |e| anyhow!("drawing {}: {e:?}", path.display());
    root.fill(&WHITE).map_err(err)?;
    let n = h.runs.len().max(2);
    let mut c = ChartBuilder::on(&root)
        .caption(
            format!("{alg} on {dataset}: total ms per run"),
            (FONT, 18).into_font(),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(-0.3f64..(n - 1) as f64 + 0.3, 0f64..ymax.max(1e-3))
        .map_err(err)?;
    let labels = h.runs.clone();
    c.configure_mesh()
        .x_labels(n)
        .x_label_formatter(&|x| {
            let i = x.round() as usize;
            if (x - i as f64).abs() < 1e-6 {
                labels.get(i).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .y_desc("total ms (median over viewpoints)")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 13))
        .draw()
        .map_err(err)?;
    for (k, s) in series.iter().enumerate() {
        let col = palette(k);
        let mut band: Vec<(f64, f64)> =
            s.points.iter().map(|p| (p.run as f64, p.band_hi)).collect();
        band.extend(s.points.iter().rev().map(|p| (p.run as f64, p.band_lo)));
        c.draw_series(std::iter::once(Polygon::new(band, col.mix(0.15))))
            .map_err(err)?;
        c.draw_series(LineSeries::new(
            s.points.iter().map(|p| (p.run as f64, p.total_ms)),
            col.stroke_width(2),
        ))
        .map_err(err)?
        .label(s.settings.clone())
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], col.stroke_width(2)));
        for p in s.points.iter().filter(|p| !p.changes.is_empty()) {
            let at = (p.run as f64, p.total_ms);
            if p.changes.iter().any(|c| c == "slower") {
                c.draw_series(std::iter::once(TriangleMarker::new(at, 8, RED.filled())))
                    .map_err(err)?;
            } else if p.changes.iter().any(|c| c == "faster") {
                c.draw_series(std::iter::once(Cross::new(at, 7, GREEN.stroke_width(3))))
                    .map_err(err)?;
            } else {
                c.draw_series(std::iter::once(Circle::new(at, 5, BLACK.filled())))
                    .map_err(err)?;
            }
        }
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .label_font((FONT, 11))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// `tetbench history`: history.json, history.md, history.html and one chart per algorithm ×
/// data set in `out`.
pub fn run_command(dirs: &[PathBuf], out: &Path, threshold: f64, alpha: f64) -> anyhow::Result<()> {
    let h = history(dirs, threshold, alpha)?;
    let charts = out.join("charts");
    std::fs::create_dir_all(&charts)
        .with_context(|| format!("cannot create {}", charts.display()))?;
    let mut md = String::from("# tetbench history\n\nRuns: ");
    md.push_str(&h.runs.join(" → "));
    md.push_str(
        "\n\n| algorithm | settings | data set | ms per run (changes) |\n|---|---|---|---|\n",
    );
    let mut html = String::from("<!doctype html><html><head><meta charset=\"utf-8\"><title>tetbench history</title></head><body style=\"font-family:sans-serif\"><h1>tetbench history</h1>");
    let _ = write!(html, "<p>Runs: {}</p>", h.runs.join(" → "));
    let mut pairs: Vec<(String, String)> = vec![];
    for s in &h.series {
        let cells: Vec<String> = s
            .points
            .iter()
            .map(|p| {
                if p.changes.is_empty() {
                    format!("{:.2}", p.total_ms)
                } else {
                    format!("**{:.2} ({})**", p.total_ms, p.changes.join(", "))
                }
            })
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} |",
            s.algorithm,
            s.settings,
            s.dataset,
            cells.join(" → ")
        );
        let k = (s.algorithm.clone(), s.dataset.clone());
        if !pairs.contains(&k) {
            pairs.push(k);
        }
    }
    for (alg, ds) in &pairs {
        let name = format!(
            "history_{}_{}.png",
            crate::names::slug(alg),
            crate::names::slug(ds)
        );
        chart(&charts.join(&name), &h, alg, ds)?;
        let _ = write!(html, "<h2>{alg} on {ds}</h2><img src=\"charts/{name}\">");
    }
    html.push_str("</body></html>\n");
    std::fs::write(out.join("history.md"), &md).context("writing history.md")?;
    std::fs::write(out.join("history.html"), html).context("writing history.html")?;
    std::fs::write(out.join("history.json"), serde_json::to_string_pretty(&h)?)
        .context("writing history.json")?;
    print!("{md}");
    println!("wrote {}/history.{{md,html,json}}", out.display());
    Ok(())
}

/// Line colours of the history charts (one per group; the comparison charts' per-variant styles
/// live in `crate::plot::style`).
fn palette(i: usize) -> RGBColor {
    const PALETTE: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
    PALETTE[i % PALETTE.len()]
}
