//! Grouped bar charts of one metric (tets/s, PSNR): a group per data set, a bar per variant
//! (mean over viewpoints, whiskers min–max), in the variants' colours, legend beside.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde::Serialize;

use super::data::{distinct, write_csv, Point};
use super::draw::{self, err, Chart, LegendEntry, FONT, PLOT_WIDTH};
use super::speed_error::sort_by_style;
use super::style::{Style, StyleBook};
use super::{ChartFile, Kind};
use crate::results::stats::Spread;

/// One CSV line: a bar.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Record {
    pub group: String,
    pub label: String,
    pub algorithm: String,
    pub settings: String,
    pub rows: usize,
    pub failed: usize,
    pub mean: Option<f64>,
    pub min: Option<f64>,
    pub max: Option<f64>,
}

struct Bars<'a> {
    title: String,
    y_desc: String,
    scale: f64,
    groups: Vec<String>,
    /// (algorithm, settings), legend order.
    series: Vec<(String, String)>,
    records: Vec<Record>,
    book: &'a StyleBook,
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

impl Bars<'_> {
    fn heading() -> Vec<String> {
        vec!["mean over viewpoints,".into(), "whiskers min–max".into()]
    }

    fn entries(&self) -> Vec<LegendEntry> {
        self.series
            .iter()
            .map(|(a, s)| LegendEntry {
                style: self.book.get(a, s),
                line: false,
                extra: String::new(),
            })
            .collect()
    }
}

impl Chart for Bars<'_> {
    fn size(&self) -> (u32, u32) {
        (
            PLOT_WIDTH + draw::legend_width(&Self::heading(), &self.entries()),
            draw::height_for_legend(self.series.len(), 2, 480),
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let (plot, legend) = root.split_horizontally(PLOT_WIDTH);
        let g = self.groups.len().max(1);
        let s = self.series.len().max(1);
        let ymax = self
            .records
            .iter()
            .filter_map(|r| r.max.or(r.mean))
            .fold(0.0f64, f64::max)
            * self.scale;
        let ymax = if ymax > 0.0 { ymax * 1.12 } else { 1.0 };
        let mut chart = ChartBuilder::on(&plot)
            .caption(&self.title, (FONT, 21).into_font())
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
            // Group names are drawn below at the group centres.
            .x_labels(0)
            .y_desc(&self.y_desc)
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 15))
            .draw()
            .map_err(err)?;
        let bar = 0.8 / s as f64;
        let label_bars = g * s <= 24;
        for (si, (a, st)) in self.series.iter().enumerate() {
            let style = self.book.get(a, st);
            for (gi, group) in self.groups.iter().enumerate() {
                let Some(r) = self
                    .records
                    .iter()
                    .find(|r| &r.group == group && &r.algorithm == a && &r.settings == st)
                else {
                    continue;
                };
                let x0 = gi as f64 + 0.1 + si as f64 * bar;
                let label_at = label_bars.then_some(ymax * 0.01);
                draw_bar(
                    &mut chart,
                    &plot,
                    (x0, x0 + bar * 0.9),
                    r,
                    self.scale,
                    &style,
                    label_at,
                )?;
            }
        }
        let name_style =
            TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
        for (gi, name) in self.groups.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(gi as f64 + 0.5, 0.0));
            plot.draw(&Text::new(name.clone(), (px, py + 8), name_style.clone()))
                .map_err(err)?;
        }
        draw::legend(&legend, &Self::heading(), &self.entries())?;
        root.present().map_err(err)?;
        Ok(())
    }
}

/// One bar of `r` over `x0..x1`: at its mean (filled, or outlined for a hollow style), a
/// whisker over the viewpoints' range, the variant's marker on top (shades repeat within a
/// family; the marker tells variants apart) and, with `label_gap`, its value that far above.
fn draw_bar<DB: DrawingBackend>(
    chart: &mut draw::Chart2d<DB>,
    plot: &DrawingArea<DB, Shift>,
    (x0, x1): (f64, f64),
    r: &Record,
    scale: f64,
    style: &Style,
    label_gap: Option<f64>,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let Some(mean) = r.mean else { return Ok(()) };
    let (height, low, high) = (
        mean * scale,
        r.min.unwrap_or(mean) * scale,
        r.max.unwrap_or(mean) * scale,
    );
    let xc = 0.5 * (x0 + x1);
    let fill = if style.hollow {
        style.color.stroke_width(2)
    } else {
        style.color.filled()
    };
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(x0, 0.0), (x1, height)],
            fill,
        )))
        .map_err(err)?;
    if high > low {
        let cap = (x1 - x0) / 0.9 * 0.2;
        let k = BLACK.stroke_width(1);
        chart
            .draw_series([
                PathElement::new(vec![(xc, low), (xc, high)], k),
                PathElement::new(vec![(xc - cap, low), (xc + cap, low)], k),
                PathElement::new(vec![(xc - cap, high), (xc + cap, high)], k),
            ])
            .map_err(err)?;
    }
    let top = chart.backend_coord(&(xc, height));
    let radius =
        ((chart.backend_coord(&(x1, 0.0)).0 - chart.backend_coord(&(x0, 0.0)).0) / 3).clamp(3, 7);
    plot.draw(&Circle::new(top, radius + 3, WHITE.filled()))
        .map_err(err)?;
    draw::marker(plot, top, radius, style)?;
    if let Some(gap) = label_gap {
        let ts = TextStyle::from((FONT, 12).into_font()).pos(Pos::new(HPos::Center, VPos::Bottom));
        chart
            .draw_series(std::iter::once(Text::new(
                short_number(height),
                (xc, high.max(height) + gap),
                ts,
            )))
            .map_err(err)?;
    }
    Ok(())
}

/// Writes `stem.{png,svg,csv}` for one metric (split per algorithm when the legend would not
/// fit: `stem_ALGORITHM.*`).
#[allow(clippy::too_many_arguments)]
fn write_metric(
    dir: &Path,
    points: &[Point],
    book: &StyleBook,
    stem: &str,
    title: &str,
    y_desc: &str,
    scale: f64,
    pick: impl Fn(&Point) -> Option<Spread>,
) -> anyhow::Result<Vec<ChartFile>> {
    let many_sizes = distinct(points.iter().map(|p| (p.width, p.height))).len() > 1;
    let group = |p: &Point| {
        if many_sizes {
            format!("{} {}×{}", p.dataset, p.width, p.height)
        } else {
            p.dataset.clone()
        }
    };
    let mut sorted: Vec<&Point> = points.iter().collect();
    sort_by_style(&mut sorted, book);
    let series = distinct(
        sorted
            .iter()
            .map(|p| (p.algorithm.clone(), p.settings.clone())),
    );
    let groups = distinct(points.iter().map(group));
    let records: Vec<Record> = sorted
        .iter()
        .map(|p| {
            let v = pick(p);
            Record {
                group: group(p),
                label: book.get(&p.algorithm, &p.settings).label,
                algorithm: p.algorithm.clone(),
                settings: p.settings.clone(),
                rows: p.rows,
                failed: p.failed,
                mean: v.map(|s| s.mean),
                min: v.map(|s| s.min),
                max: v.map(|s| s.max),
            }
        })
        .collect();
    let parts = draw::legend_parts(series, |(a, _)| a);
    let mut files = vec![];
    for (alg, part) in parts {
        let stem = if alg.is_empty() {
            stem.to_string()
        } else {
            format!("{stem}_{}", crate::results::names::slug(&alg))
        };
        let title = if alg.is_empty() {
            title.to_string()
        } else {
            format!("{title} — {alg}")
        };
        let recs: Vec<Record> = records
            .iter()
            .filter(|r| {
                part.iter()
                    .any(|(a, s)| *a == r.algorithm && *s == r.settings)
            })
            .cloned()
            .collect();
        let chart = Bars {
            title: title.clone(),
            y_desc: y_desc.into(),
            scale,
            groups: groups.clone(),
            series: part,
            records: recs.clone(),
            book,
        };
        draw::save(&chart, dir, &stem)?;
        write_csv(dir, &stem, &recs)?;
        files.push(ChartFile {
            kind: Kind::Bars,
            title,
            stem,
            note: String::new(),
        });
    }
    Ok(files)
}

/// The two bar charts: tets/s and PSNR per variant and data set.
pub fn write(dir: &Path, points: &[Point], book: &StyleBook) -> anyhow::Result<Vec<ChartFile>> {
    let mut files = write_metric(
        dir,
        points,
        book,
        "tets_per_sec",
        "Throughput per variant and data set",
        "million tets / s",
        1e-6,
        |p| p.tets_per_sec,
    )?;
    if points.iter().any(|p| p.psnr_db.is_some()) {
        files.extend(write_metric(
            dir,
            points,
            book,
            "psnr",
            "Image error against the exact reference (higher is better)",
            "PSNR (dB)",
            1.0,
            |p| p.psnr_db,
        )?);
    }
    Ok(files)
}
