//! The line chart the scaling and resolution charts share: one line per variant through its
//! measured points (whiskers min–max over viewpoints), failed points marked on the bottom edge
//! rather than dropped, optional backend bounds as dashed horizontal lines.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

use super::data::{distinct, write_csv, Bound, Point};
use super::draw::{self, err, Chart, LegendEntry, FONT, PLOT_WIDTH};
use super::style::{Marker, Style, StyleBook};
use super::{ChartFile, Kind};
use crate::results::stats::Spread;

/// One measured (or failed) point of a line.
#[derive(Debug, Clone)]
pub struct LinePoint {
    pub x: f64,
    /// `None`: no measurement at this x (the row failed).
    pub y: Option<Spread>,
}

#[derive(Debug, Clone)]
pub struct Line {
    pub algorithm: String,
    pub settings: String,
    pub points: Vec<LinePoint>,
    /// Shown after the label in the legend (e.g. the fitted exponent).
    pub extra: String,
}

pub struct LineChart<'a> {
    pub title: String,
    pub x_desc: String,
    pub y_desc: String,
    pub x_log: bool,
    pub x_fmt: fn(f64) -> String,
    pub y_fmt: fn(f64) -> String,
    pub lines: Vec<Line>,
    pub bounds: Vec<Bound>,
    /// Lines of text above the legend.
    pub notes: Vec<String>,
    pub book: &'a StyleBook,
}

impl LineChart<'_> {
    fn entries(&self) -> Vec<LegendEntry> {
        self.lines
            .iter()
            .map(|l| LegendEntry {
                style: self.book.get(&l.algorithm, &l.settings),
                line: true,
                extra: l.extra.clone(),
            })
            .collect()
    }

    fn heading(&self) -> Vec<String> {
        let mut h = self.notes.clone();
        h.push("whiskers: min–max over viewpoints".into());
        if self
            .lines
            .iter()
            .any(|l| l.points.iter().any(|p| p.y.is_none()))
        {
            h.push("crossed out on the bottom edge:".into());
            h.push("failed there (no measurement)".into());
        }
        h
    }

    fn x_range(&self) -> (f64, f64) {
        let xs: Vec<f64> = self
            .lines
            .iter()
            .flat_map(|l| l.points.iter().map(|p| p.x))
            .collect();
        let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = xs.iter().copied().fold(0.0f64, f64::max);
        if self.x_log {
            draw::log_range(lo, hi)
        } else if lo.is_finite() {
            let pad = ((hi - lo) * 0.06).max(hi * 0.05).max(1.0);
            ((lo - pad).max(0.0), hi + pad)
        } else {
            (0.0, 1.0)
        }
    }

    fn y_range(&self) -> (f64, f64) {
        let ys = self
            .lines
            .iter()
            .flat_map(|l| l.points.iter().filter_map(|p| p.y))
            .flat_map(|s| [s.min, s.max]);
        let (mut lo, mut hi) = ys.fold((f64::INFINITY, 0.0f64), |(a, b), y| {
            if y > 0.0 {
                (a.min(y), b.max(y))
            } else {
                (a, b)
            }
        });
        for b in &self.bounds {
            lo = lo.min(b.per_sec);
            hi = hi.max(b.per_sec);
        }
        draw::log_range(lo, hi)
    }
}

impl Chart for LineChart<'_> {
    fn size(&self) -> (u32, u32) {
        (
            PLOT_WIDTH + draw::legend_width(&self.heading(), &self.entries()),
            draw::height_for_legend(self.lines.len(), self.heading().len(), 620),
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let (plot, legend) = root.split_horizontally(PLOT_WIDTH);
        let (xlo, xhi) = self.x_range();
        let (ylo, yhi) = self.y_range();
        let xa = draw::Axis {
            log: self.x_log,
            lo: xlo,
            hi: xhi,
        };
        let ya = draw::Axis {
            log: true,
            lo: ylo,
            hi: yhi,
        };
        let chart = draw::Axes {
            title: &self.title,
            x: xa,
            y: ya,
            x_desc: &self.x_desc,
            y_desc: &self.y_desc,
            x_fmt: self.x_fmt,
            y_fmt: self.y_fmt,
            y_label_area: 72,
        }
        .draw(&plot)?;
        let px = |x: f64, y: f64| chart.backend_coord(&(xa.at(x), ya.at(y)));
        // Per line, per point: (whisker bottom, centre, whisker top) in pixels; a failed
        // point has no whisker and sits on the bottom edge.
        let points_px: Vec<(usize, Vec<Px>)> = self
            .lines
            .iter()
            .enumerate()
            .map(|(li, l)| {
                let v = l
                    .points
                    .iter()
                    .map(|p| match p.y {
                        Some(s) => (Some(px(p.x, s.min)), px(p.x, s.mean), Some(px(p.x, s.max))),
                        None => (None, px(p.x, ylo), None),
                    })
                    .collect();
                (li, v)
            })
            .collect();
        let bound_px: Vec<(i32, i32, i32, String)> = self
            .bounds
            .iter()
            .map(|b| {
                let (x0, y) = px(xlo, b.per_sec);
                let (x1, _) = px(xhi, b.per_sec);
                (
                    x0,
                    x1,
                    y,
                    format!(
                        "calibrated bound: {} {}/s ({})",
                        b.name,
                        draw::si(b.per_sec),
                        b.adapter
                    ),
                )
            })
            .collect();
        draw_bounds(&plot, &bound_px)?;
        // Failed points sit on the bottom edge, stacked upwards where several share an x.
        let mut failed_at: Vec<(i32, i32)> = vec![];
        for (li, pts) in &points_px {
            let line = &self.lines[*li];
            let st = self.book.get(&line.algorithm, &line.settings);
            draw_line(&plot, pts, &st, &mut failed_at)?;
        }
        let entries = self.entries();
        draw::legend(&legend, &self.heading(), &entries)?;
        root.present().map_err(err)?;
        Ok(())
    }
}

/// The variants of `points` in legend order.
pub fn variants(points: &[&Point], book: &StyleBook) -> Vec<(String, String)> {
    let mut v = distinct(
        points
            .iter()
            .map(|p| (p.algorithm.clone(), p.settings.clone())),
    );
    v.sort_by_key(|(a, s)| super::style::order_key(book, a, s));
    v
}

/// Saves `lines` as `stem` (or, when the legend would not fit, as `stem_ALG` per algorithm)
/// with `records` as each chart's CSV. `chart(suffix, lines)` makes a chart, `suffix` being
/// `, ALG` for a per-algorithm part (for its title) and empty for the one chart.
pub fn save_parts<'b, R: Serialize>(
    dir: &Path,
    (stem, kind): (&str, Kind),
    lines: Vec<Line>,
    records: &[R],
    chart: impl Fn(&str, Vec<Line>) -> LineChart<'b>,
) -> anyhow::Result<Vec<ChartFile>> {
    let mut files = vec![];
    for (alg, part) in draw::legend_parts(lines, |l| &l.algorithm) {
        let (stem, suffix) = if alg.is_empty() {
            (stem.to_string(), String::new())
        } else {
            (
                format!("{stem}_{}", crate::results::names::slug(&alg)),
                format!(", {alg}"),
            )
        };
        let chart = chart(&suffix, part);
        draw::save(&chart, dir, &stem)?;
        write_csv(dir, &stem, records)?;
        files.push(ChartFile {
            kind,
            title: chart.title,
            stem,
            note: String::new(),
        });
    }
    Ok(files)
}

/// A point of a line in pixels: (whisker bottom, centre, whisker top); a failed point has no
/// whisker and sits on the bottom edge.
type Px = (Option<(i32, i32)>, (i32, i32), Option<(i32, i32)>);

/// The backend bounds: dashed horizontal lines, each labelled (`(x0, x1, y, label)`).
fn draw_bounds<DB: DrawingBackend>(
    plot: &DrawingArea<DB, Shift>,
    bounds: &[(i32, i32, i32, String)],
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    for (x0, x1, y, text) in bounds {
        plot.draw(&plotters::element::DashedPathElement::new(
            vec![(*x0, *y), (*x1, *y)],
            8,
            5,
            RED.mix(0.7).stroke_width(2),
        ))
        .map_err(err)?;
        plot.draw(&Text::new(
            text.clone(),
            (x0 + 6, y - 18),
            (FONT, 13).into_font(),
        ))
        .map_err(err)?;
    }
    Ok(())
}

/// One line: segments through consecutive measured points (a failure breaks the line), the
/// whiskers and markers, and each failed point crossed on the bottom edge, stacked above the
/// failed points already drawn at its x (`failed_at`).
fn draw_line<DB: DrawingBackend>(
    plot: &DrawingArea<DB, Shift>,
    pts: &[Px],
    st: &Style,
    failed_at: &mut Vec<(i32, i32)>,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let mut run: Vec<(i32, i32)> = vec![];
    let mut runs: Vec<Vec<(i32, i32)>> = vec![];
    for (lo, mid, _) in pts {
        if lo.is_some() {
            run.push(*mid);
        } else if !run.is_empty() {
            runs.push(std::mem::take(&mut run));
        }
    }
    runs.push(run);
    for r in runs.into_iter().filter(|r| r.len() > 1) {
        plot.draw(&PathElement::new(r, st.color.stroke_width(2)))
            .map_err(err)?;
    }
    for (lo, mid, hi) in pts {
        match (lo, hi) {
            (Some(lo), Some(hi)) => {
                if lo != hi {
                    plot.draw(&PathElement::new(vec![*lo, *hi], st.color.stroke_width(1)))
                        .map_err(err)?;
                }
                draw::marker(plot, *mid, 6, st)?;
            }
            _ => {
                let below = failed_at.iter().filter(|(x, _)| *x == mid.0).count() as i32;
                failed_at.push(*mid);
                let c = (mid.0, mid.1 - 10 - 18 * below);
                draw::marker(plot, c, 6, st)?;
                let cross = Style {
                    marker: Marker::Cross,
                    color: BLACK,
                    hollow: true,
                    ..st.clone()
                };
                draw::marker(plot, c, 5, &cross)?;
            }
        }
    }
    Ok(())
}
