//! The report of a run, written into its output directory from `results.json` alone (so
//! `tetbench report OUT` can redo it): charts of tets/sec and PSNR per algorithm × data set
//! (PNG and SVG) and an `index.html` with the machine, the summary and full tables, the charts,
//! and every image beside its reference and error heatmap.
//!
//! Charts use plotters' pure-Rust text path (ab_glyph) with DejaVu Sans compiled in, so they
//! render on machines without any font installed. The SVGs name the family "DejaVu Sans" and
//! load it with `@font-face` from `charts/DejaVuSans.ttf`, written beside them.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::Once;

use anyhow::{anyhow, Context};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::FontStyle;

use crate::algorithms::is_peer;
use crate::metrics::{HEATMAP_MAX_ERROR, ONE_STEP, PSNR_CAP_DB};
use crate::results::{ResultsFile, Row};

const FONT: &str = "DejaVu Sans";

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in, so failure would be a corrupt build: nothing to recover.
        plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular())
            .unwrap_or_else(|_| panic!("embedded DejaVu Sans is not a valid font"));
        plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold())
            .unwrap_or_else(|_| panic!("embedded DejaVu Sans Bold is not a valid font"));
    });
}

/// Mean, minimum and maximum over the viewpoints of a group.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    pub mean: f64,
    pub min: f64,
    pub max: f64,
}

fn spread(values: impl Iterator<Item = f64>) -> Option<Spread> {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    Some(Spread {
        mean: v.iter().sum::<f64>() / v.len() as f64,
        min: v.iter().copied().fold(f64::INFINITY, f64::min),
        max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    })
}

/// One algorithm × settings × data set, over its viewpoints (the papers average over the 14
/// fixed viewpoints, HAVS §6).
#[derive(Debug, Clone, PartialEq)]
pub struct Aggregate {
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    pub tets: u64,
    pub rows: usize,
    pub failed: usize,
    pub total_ms: Option<Spread>,
    pub cpu_ms: Option<Spread>,
    pub gpu_ms: Option<Spread>,
    pub fps: Option<Spread>,
    pub tets_per_sec: Option<Spread>,
    pub psnr_db: Option<Spread>,
    pub rmse: Option<Spread>,
    pub bad_pixel_share: Option<Spread>,
    pub bytes_per_tet: Option<f64>,
    pub gpu_bytes: Option<u64>,
}

impl Aggregate {
    /// `algorithm settings` as one label.
    pub fn series(&self) -> String {
        series_label(&self.algorithm, &self.settings)
    }
}

pub fn series_label(algorithm: &str, settings: &str) -> String {
    if settings.is_empty() {
        algorithm.to_string()
    } else {
        format!("{algorithm} {settings}")
    }
}

/// Groups rows by (algorithm, settings, data set), in order of first appearance.
pub fn aggregate(rows: &[Row]) -> Vec<Aggregate> {
    let mut keys: Vec<(String, String, String)> = vec![];
    for r in rows {
        let k = (r.algorithm.clone(), r.settings.clone(), r.dataset.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(algorithm, settings, dataset)| {
            let g: Vec<&Row> = rows
                .iter()
                .filter(|r| {
                    r.algorithm == algorithm && r.settings == settings && r.dataset == dataset
                })
                .collect();
            Aggregate {
                tets: g[0].tets,
                rows: g.len(),
                failed: g.iter().filter(|r| !r.ok()).count(),
                total_ms: spread(g.iter().filter_map(|r| r.total_ms)),
                cpu_ms: spread(g.iter().filter_map(|r| r.cpu_ms)),
                gpu_ms: spread(g.iter().filter_map(|r| r.gpu_ms)),
                fps: spread(g.iter().filter_map(|r| r.fps)),
                tets_per_sec: spread(g.iter().filter_map(|r| r.tets_per_sec)),
                psnr_db: spread(g.iter().filter_map(|r| r.psnr_db)),
                rmse: spread(g.iter().filter_map(|r| r.rmse)),
                bad_pixel_share: spread(g.iter().filter_map(|r| r.bad_pixel_share)),
                bytes_per_tet: g.iter().find_map(|r| r.bytes_per_tet),
                gpu_bytes: g.iter().filter_map(|r| r.gpu_bytes).max(),
                algorithm,
                settings,
                dataset,
            }
        })
        .collect()
}

/// A grouped bar chart: one group per data set, one bar per series, whiskers min–max.
struct BarChart<'a> {
    title: &'a str,
    y_desc: &'a str,
    groups: Vec<String>,
    series: Vec<(String, Vec<Option<Spread>>)>,
}

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

const LEGEND_WIDTH: u32 = 400;

/// Shortens long series names for the legend (the full names are in the tables).
fn ellipsize(s: &str, max_chars: usize) -> String {
    if s.chars().count() <= max_chars {
        s.to_string()
    } else {
        let mut t: String = s.chars().take(max_chars - 1).collect();
        t.push('…');
        t
    }
}

fn short_number(v: f64) -> String {
    let a = v.abs();
    if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

impl BarChart<'_> {
    fn size(&self) -> (u32, u32) {
        (1200, (90 + 22 * self.series.len() as u32).max(460))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing a chart: {e:?}");
        root.fill(&WHITE).map_err(err)?;
        let (w, _) = root.dim_in_pixel();
        let (plot, legend) = root.split_horizontally(w - LEGEND_WIDTH);
        let g = self.groups.len().max(1);
        let s = self.series.len().max(1);
        let ymax = self
            .series
            .iter()
            .flat_map(|(_, v)| v.iter().flatten().map(|p| p.max.max(p.mean)))
            .fold(0.0f64, f64::max);
        let ymax = if ymax > 0.0 { ymax * 1.12 } else { 1.0 };
        let mut chart = ChartBuilder::on(&plot)
            .caption(self.title, (FONT, 22).into_font())
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0f64..g as f64, 0f64..ymax)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .bold_line_style(BLACK.mix(0.12))
            .light_line_style(WHITE.mix(0.0))
            // Group names are drawn below at the group centres; plotters' own x labels would
            // fall at "nice" numbers instead.
            .x_labels(0)
            .y_desc(self.y_desc)
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 15))
            .draw()
            .map_err(err)?;
        let bar = 0.8 / s as f64;
        let label_bars = g * s <= 24;
        for (si, (_, values)) in self.series.iter().enumerate() {
            let color = PALETTE[si % PALETTE.len()];
            for (gi, v) in values.iter().enumerate() {
                let Some(v) = v else { continue };
                let x0 = gi as f64 + 0.1 + si as f64 * bar;
                let x1 = x0 + bar * 0.9;
                let xc = 0.5 * (x0 + x1);
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(x0, 0.0), (x1, v.mean)],
                        color.filled(),
                    )))
                    .map_err(err)?;
                if v.max > v.min {
                    let cap = bar * 0.2;
                    chart
                        .draw_series([
                            PathElement::new(vec![(xc, v.min), (xc, v.max)], BLACK.stroke_width(1)),
                            PathElement::new(
                                vec![(xc - cap, v.min), (xc + cap, v.min)],
                                BLACK.stroke_width(1),
                            ),
                            PathElement::new(
                                vec![(xc - cap, v.max), (xc + cap, v.max)],
                                BLACK.stroke_width(1),
                            ),
                        ])
                        .map_err(err)?;
                }
                if label_bars {
                    let style = TextStyle::from((FONT, 12).into_font())
                        .pos(Pos::new(HPos::Center, VPos::Bottom));
                    chart
                        .draw_series(std::iter::once(Text::new(
                            short_number(v.mean),
                            (xc, v.max.max(v.mean) + ymax * 0.01),
                            style,
                        )))
                        .map_err(err)?;
                }
            }
        }
        let name_style =
            TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
        for (gi, name) in self.groups.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(gi as f64 + 0.5, 0.0));
            root.draw(&Text::new(name.clone(), (px, py + 8), name_style.clone()))
                .map_err(err)?;
        }
        // The legend in its own panel, so it never hides a bar however many series there are.
        legend
            .draw(&Text::new(
                "mean over viewpoints,",
                (8, 40),
                (FONT, 13).into_font(),
            ))
            .map_err(err)?;
        legend
            .draw(&Text::new(
                "whiskers min–max",
                (8, 56),
                (FONT, 13).into_font(),
            ))
            .map_err(err)?;
        for (si, (name, _)) in self.series.iter().enumerate() {
            let y = 80 + 22 * si as i32;
            let color = PALETTE[si % PALETTE.len()];
            legend
                .draw(&Rectangle::new([(8, y), (24, y + 14)], color.filled()))
                .map_err(err)?;
            legend
                .draw(&Text::new(
                    ellipsize(name, 52),
                    (30, y),
                    (FONT, 12).into_font(),
                ))
                .map_err(err)?;
        }
        root.present().map_err(err)?;
        Ok(())
    }

    /// Writes `stem.png` and `stem.svg` into `dir`.
    fn write(&self, dir: &Path, stem: &str) -> anyhow::Result<()> {
        register_font();
        let size = self.size();
        let png = dir.join(format!("{stem}.png"));
        {
            let root = BitMapBackend::new(&png, size).into_drawing_area();
            self.draw(&root)
                .with_context(|| format!("writing {}", png.display()))?;
        }
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
            self.draw(&root)?;
        }
        // Let viewers without DejaVu installed load it from beside the SVG.
        let style = format!(
            "<style>@font-face {{ font-family: \"{FONT}\"; src: url(\"DejaVuSans.ttf\") format(\"truetype\"); }}</style>"
        );
        if let Some(end) = svg
            .find("<svg")
            .and_then(|i| svg[i..].find('>').map(|j| i + j + 1))
        {
            svg.insert_str(end, &style);
        }
        let path = dir.join(format!("{stem}.svg"));
        std::fs::write(&path, svg).with_context(|| format!("cannot write {}", path.display()))
    }
}

fn series_and_groups(aggs: &[Aggregate]) -> (Vec<(String, String)>, Vec<String>) {
    let mut series: Vec<(String, String)> = vec![];
    let mut groups: Vec<String> = vec![];
    for a in aggs {
        let k = (a.algorithm.clone(), a.settings.clone());
        if !series.contains(&k) {
            series.push(k);
        }
        if !groups.contains(&a.dataset) {
            groups.push(a.dataset.clone());
        }
    }
    (series, groups)
}

fn chart_of(
    aggs: &[Aggregate],
    title: &'static str,
    y_desc: &'static str,
    pick: impl Fn(&Aggregate) -> Option<Spread>,
) -> BarChart<'static> {
    let (series, groups) = series_and_groups(aggs);
    let series = series
        .iter()
        .map(|(alg, set)| {
            let v = groups
                .iter()
                .map(|d| {
                    aggs.iter()
                        .find(|a| &a.algorithm == alg && &a.settings == set && &a.dataset == d)
                        .and_then(&pick)
                })
                .collect();
            (series_label(alg, set), v)
        })
        .collect();
    BarChart {
        title,
        y_desc,
        groups,
        series,
    }
}

/// Writes the charts and `index.html` into `out` for the results in `file`.
pub fn write(out: &Path, file: &ResultsFile) -> anyhow::Result<()> {
    let charts = out.join("charts");
    std::fs::create_dir_all(&charts)
        .with_context(|| format!("cannot create {}", charts.display()))?;
    std::fs::write(charts.join("DejaVuSans.ttf"), dejavu::sans::regular())?;
    let aggs = aggregate(&file.rows);
    let scale = |s: Spread| Spread {
        mean: s.mean * 1e-6,
        min: s.min * 1e-6,
        max: s.max * 1e-6,
    };
    chart_of(
        &aggs,
        "Throughput per algorithm and data set",
        "million tets / s",
        |a| a.tets_per_sec.map(scale),
    )
    .write(&charts, "tets_per_sec")?;
    chart_of(
        &aggs,
        "Image error against the exact reference (higher is better)",
        "PSNR (dB)",
        |a| a.psnr_db,
    )
    .write(&charts, "psnr")?;
    let html = html(file, &aggs);
    let path = out.join("index.html");
    std::fs::write(&path, html).with_context(|| format!("cannot write {}", path.display()))
}

/// Re-renders the report of an earlier run (`tetbench report OUT`).
pub fn rewrite(out: &Path) -> anyhow::Result<()> {
    let file = ResultsFile::read(out)?;
    write(out, &file)
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map(|v| format!("{v:.digits$}"))
        .unwrap_or_else(|| "–".into())
}

fn mb(v: Option<u64>) -> String {
    v.map(|b| format!("{:.2}", b as f64 / (1 << 20) as f64))
        .unwrap_or_else(|| "–".into())
}

fn html(file: &ResultsFile, aggs: &[Aggregate]) -> String {
    let m = &file.machine;
    let r = &file.run;
    let mut h = String::new();
    let _ = write!(
        h,
        r#"<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>tetbench report</title>
<style>
body {{ font-family: "DejaVu Sans", sans-serif; margin: 1.5em; color: #222; }}
@font-face {{ font-family: "DejaVu Sans"; src: url("charts/DejaVuSans.ttf") format("truetype"); }}
table {{ border-collapse: collapse; font-size: 13px; margin: 0.5em 0 1.5em; }}
th, td {{ border: 1px solid #ccc; padding: 2px 6px; text-align: right; }}
th {{ background: #eee; }} td.l, th.l {{ text-align: left; }}
tr.failed td {{ background: #fdd; }}
dl {{ display: grid; grid-template-columns: max-content auto; gap: 2px 12px; font-size: 14px; }}
dt {{ font-weight: bold; }} dd {{ margin: 0; }}
.charts img {{ max-width: 100%; border: 1px solid #ddd; margin-bottom: 8px; }}
.view {{ margin: 0 0 1.2em; }}
.strip {{ display: flex; flex-wrap: wrap; gap: 10px; }}
figure {{ margin: 0; font-size: 11px; text-align: center; }}
figure img {{ width: 160px; height: 160px; object-fit: contain; background: #000; display: block; image-rendering: pixelated; }}
.pair {{ display: flex; gap: 2px; }}
</style></head><body>
<h1>tetbench report</h1>
"#
    );
    let mem = m
        .memory_bytes
        .map(|b| format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64))
        .unwrap_or_else(|| "unknown".into());
    let adapter = m
        .adapter
        .as_ref()
        .map(|a| {
            format!(
                "{} ({}, {}, driver {} {})",
                a.name, a.backend, a.device_type, a.driver, a.driver_info
            )
        })
        .unwrap_or_else(|| "unknown".into());
    let commit = match (&m.git_commit, m.git_dirty) {
        (Some(c), Some(true)) => format!("{c} (with uncommitted changes)"),
        (Some(c), _) => c.clone(),
        _ => "unknown".into(),
    };
    let _ = writeln!(
        h,
        "<h2>Machine and run</h2><dl>\
         <dt>GPU adapter</dt><dd>{}</dd><dt>CPU</dt><dd>{} ({} logical cores)</dd><dt>memory</dt><dd>{}</dd>\
         <dt>OS</dt><dd>{} {}</dd><dt>tetbench</dt><dd>{} at commit {}</dd><dt>started</dt><dd>{}</dd>\
         <dt>finished</dt><dd>{}</dd><dt>command</dt><dd><code>{}</code></dd>\
         <dt>viewpoints</dt><dd>{}</dd><dt>viewport</dt><dd>{}×{}, {}</dd><dt>frames</dt><dd>{} timed after {} warm-up</dd>\
         <dt>transfer function</dt><dd>{}</dd></dl>",
        esc(&adapter),
        esc(&m.cpu_model),
        m.cpu_cores,
        mem,
        esc(&m.os),
        esc(m.kernel.as_deref().unwrap_or("")),
        esc(&m.tetbench_version),
        esc(&commit),
        esc(&m.date_utc),
        esc(file.finished_utc.as_deref().unwrap_or("not finished (interrupted?)")),
        esc(&r.command_line.join(" ")),
        esc(&r.viewpoints),
        r.width,
        r.height,
        esc(&r.projection),
        r.frames,
        r.warmup,
        esc(&r.transfer_function),
    );
    if !file.errors.is_empty() {
        h.push_str("<h2>Errors</h2><ul>");
        for e in &file.errors {
            let _ = write!(h, "<li>{}</li>", esc(e));
        }
        h.push_str("</ul>\n");
    }

    h.push_str(
        "<h2>Charts</h2><div class=\"charts\">\
         <img src=\"charts/tets_per_sec.png\" alt=\"tets per second per algorithm and data set\">\
         <p><a href=\"charts/tets_per_sec.svg\">SVG</a></p>\
         <img src=\"charts/psnr.png\" alt=\"PSNR per algorithm and data set\">\
         <p><a href=\"charts/psnr.svg\">SVG</a></p></div>\n",
    );

    h.push_str("<h2>Summary</h2><p>Mean over viewpoints (min–max in brackets).");
    if file.rows.iter().any(|r| is_peer(&r.algorithm)) {
        h.push_str(
            " <em>peer</em>: another package's renderer (VTK, through its Python package) \
             measured in the same run; VTK reports no GPU memory.",
        );
    }
    h.push_str(
        "</p><table><tr>\
         <th class=l>algorithm</th><th class=l>settings</th><th class=l>data set</th><th>tets</th><th>rows</th>\
         <th>total ms</th><th>CPU ms</th><th>GPU ms</th><th>fps</th><th>M tets/s</th><th>PSNR dB</th>\
         <th>bad pixels %</th><th>bytes/tet</th><th>GPU MiB</th></tr>\n",
    );
    for a in aggs {
        let sp = |s: Option<Spread>, k: f64, d: usize| {
            s.map(|s| {
                format!(
                    "{:.d$} <small>({:.d$}–{:.d$})</small>",
                    s.mean * k,
                    s.min * k,
                    s.max * k
                )
            })
            .unwrap_or_else(|| "–".into())
        };
        let _ = writeln!(
            h,
            "<tr{}><td class=l>{}</td><td class=l>{}</td><td class=l>{}</td><td>{}</td><td>{}{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            if a.failed > 0 { " class=failed" } else { "" },
            algorithm_cell(&a.algorithm),
            esc(&a.settings),
            esc(&a.dataset),
            a.tets,
            a.rows,
            if a.failed > 0 { format!(" ({} failed)", a.failed) } else { String::new() },
            sp(a.total_ms, 1.0, 2),
            sp(a.cpu_ms, 1.0, 2),
            sp(a.gpu_ms, 1.0, 2),
            sp(a.fps, 1.0, 1),
            sp(a.tets_per_sec, 1e-6, 3),
            sp(a.psnr_db, 1.0, 2),
            sp(a.bad_pixel_share, 100.0, 2),
            opt(a.bytes_per_tet.filter(|_| !is_peer(&a.algorithm)), 1),
            mb(a.gpu_bytes.filter(|_| !is_peer(&a.algorithm))),
        );
    }
    h.push_str("</table>\n");

    let _ = writeln!(
        h,
        "<h2>Images</h2><p>Each rendering beside its error heatmap (largest channel error per pixel: black ≤ 1/255, \
         then a log scale up to ≥ {HEATMAP_MAX_ERROR} in pale yellow); the exact reference first. PSNR over \
         premultiplied linear RGB, capped at {PSNR_CAP_DB} dB; “bad” pixels are covered pixels off by more than \
         1/255 ({ONE_STEP:.4}) in any channel.</p>"
    );
    let mut views: Vec<(String, String)> = vec![];
    for row in &file.rows {
        let k = (row.dataset.clone(), row.viewpoint.clone());
        if !views.contains(&k) {
            views.push(k);
        }
    }
    for (dataset, viewpoint) in &views {
        let rows: Vec<&Row> = file
            .rows
            .iter()
            .filter(|r| &r.dataset == dataset && &r.viewpoint == viewpoint)
            .collect();
        let _ = write!(
            h,
            "<div class=view><h3>{} — {}</h3><div class=strip>",
            esc(dataset),
            esc(viewpoint)
        );
        if let Some(reference) = rows
            .iter()
            .find(|r| !r.reference_image.is_empty())
            .map(|r| &r.reference_image)
        {
            let _ = write!(
                h,
                "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"reference\" loading=lazy></a><figcaption>exact reference</figcaption></figure>",
                esc(reference)
            );
        }
        for row in rows {
            if row.image.is_empty() {
                continue;
            }
            let _ = write!(
                h,
                "<figure><div class=pair><a href=\"{0}\"><img src=\"{0}\" alt=\"image\" loading=lazy></a>",
                esc(&row.image)
            );
            if !row.heatmap.is_empty() {
                let _ = write!(
                    h,
                    "<a href=\"{0}\"><img src=\"{0}\" alt=\"error heatmap\" loading=lazy></a>",
                    esc(&row.heatmap)
                );
            }
            let _ = write!(
                h,
                "</div><figcaption>{}<br>PSNR {} dB · {} M tets/s</figcaption></figure>",
                esc(&series_label(&row.algorithm, &row.settings)),
                opt(row.psnr_db, 2),
                opt(row.tets_per_sec.map(|v| v * 1e-6), 3)
            );
        }
        h.push_str("</div></div>\n");
    }

    h.push_str(
        "<h2>All rows</h2><table><tr><th class=l>algorithm</th><th class=l>settings</th><th class=l>data set</th>\
         <th class=l>viewpoint</th><th>total ms</th><th>CPU ms</th><th>GPU ms</th><th>fps</th><th>M tets/s</th>\
         <th>GPU MiB</th><th>bytes/tet</th><th>RMSE</th><th>PSNR dB</th><th>max err</th><th>bad %</th>\
         <th class=l>stages (ms)</th><th class=l>error</th></tr>\n",
    );
    for row in &file.rows {
        let _ = writeln!(
            h,
            "<tr{}><td class=l>{}</td><td class=l>{}</td><td class=l>{}</td><td class=l>{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td class=l>{}</td><td class=l>{}</td></tr>",
            if row.ok() { "" } else { " class=failed" },
            algorithm_cell(&row.algorithm),
            esc(&row.settings),
            esc(&row.dataset),
            esc(&row.viewpoint),
            opt(row.total_ms, 2),
            opt(row.cpu_ms, 2),
            opt(row.gpu_ms, 2),
            opt(row.fps, 1),
            opt(row.tets_per_sec.map(|v| v * 1e-6), 3),
            mb(row.gpu_bytes),
            opt(row.bytes_per_tet, 1),
            opt(row.rmse, 5),
            opt(row.psnr_db, 2),
            opt(row.max_abs_error, 4),
            opt(row.bad_pixel_share.map(|v| v * 100.0), 2),
            esc(&row.stages),
            esc(&row.error),
        );
    }
    h.push_str("</table>\n<p>Raw data: <a href=\"results.csv\">results.csv</a>, <a href=\"results.json\">results.json</a>.</p>\n</body></html>\n");
    h
}

/// The summary as a Markdown table (for `tetbench analyze summary` and notes).
pub fn markdown_summary(aggs: &[Aggregate]) -> String {
    let mut s = String::from(
        "| algorithm | settings | data set | tets | total ms | CPU ms | GPU ms | fps | M tets/s | PSNR dB (min) | bytes/tet |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let m = |v: Option<Spread>, k: f64, d: usize| {
        v.map(|v| format!("{:.d$}", v.mean * k))
            .unwrap_or_else(|| "–".into())
    };
    for a in aggs {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} ({}) | {} |",
            a.algorithm,
            a.settings,
            a.dataset,
            a.tets,
            m(a.total_ms, 1.0, 2),
            m(a.cpu_ms, 1.0, 2),
            m(a.gpu_ms, 1.0, 2),
            m(a.fps, 1.0, 1),
            m(a.tets_per_sec, 1e-6, 3),
            m(a.psnr_db, 1.0, 2),
            a.psnr_db
                .map(|p| format!("{:.2}", p.min))
                .unwrap_or_else(|| "–".into()),
            opt(a.bytes_per_tet, 1),
        );
    }
    s
}

/// The algorithm's name for the HTML tables, with peers (other packages' renderers) marked.
fn algorithm_cell(name: &str) -> String {
    if is_peer(name) {
        format!("{} <small class=peer>(peer)</small>", esc(name))
    } else {
        esc(name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::MachineInfo;
    use crate::results::{test_row, RunDescription, SCHEMA_VERSION};

    fn file() -> ResultsFile {
        let mut rows = vec![];
        for i in 0..3 {
            let mut r = test_row(i);
            r.tets_per_sec = Some(1e6 * (i + 1) as f64);
            r.psnr_db = Some(40.0 + i as f64);
            r.image = format!("images/box_1k/v{i}/test.png");
            r.heatmap = format!("images/box_1k/v{i}/test.error.png");
            r.reference_image = format!("images/box_1k/v{i}/reference.png");
            rows.push(r);
        }
        let mut failed = test_row(3);
        failed.error = "out of memory <boom>".into();
        failed.tets_per_sec = None;
        rows.push(failed);
        ResultsFile {
            schema_version: SCHEMA_VERSION,
            machine: MachineInfo::collect(),
            run: RunDescription::default(),
            finished_utc: None,
            rows,
            errors: vec!["data set \"x\" could not be loaded".into()],
        }
    }

    #[test]
    fn aggregates_average_over_viewpoints() {
        let a = aggregate(&file().rows);
        assert_eq!(a.len(), 1);
        let t = a[0].tets_per_sec.unwrap();
        assert_eq!((t.mean, t.min, t.max), (2e6, 1e6, 3e6));
        assert_eq!(a[0].rows, 4);
        assert_eq!(a[0].failed, 1);
        assert!(markdown_summary(&a).contains("| test | variant=a;sort=radix | box:1k | 1000 |"));
    }

    #[test]
    fn report_has_charts_table_and_images() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), &file()).unwrap();
        let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
        for needle in [
            "charts/tets_per_sec.png",
            "charts/psnr.png",
            "images/box_1k/v2/test.png",
            "images/box_1k/v2/test.error.png",
            "images/box_1k/v0/reference.png",
            "out of memory &lt;boom&gt;",
        ] {
            assert!(html.contains(needle), "index.html lacks {needle}");
        }
        for f in [
            "tets_per_sec.png",
            "tets_per_sec.svg",
            "psnr.png",
            "psnr.svg",
            "DejaVuSans.ttf",
        ] {
            assert!(
                dir.path().join("charts").join(f).metadata().unwrap().len() > 1000,
                "{f}"
            );
        }
        let png = image::open(dir.path().join("charts/psnr.png"))
            .unwrap()
            .to_rgb8();
        // Not blank: the bars and text drew something other than the white background.
        assert!(png.pixels().filter(|p| p.0 != [255, 255, 255]).count() > 1000);
        let svg = std::fs::read_to_string(dir.path().join("charts/psnr.svg")).unwrap();
        assert!(svg.contains("@font-face") && svg.contains("DejaVu Sans"));
    }
}
