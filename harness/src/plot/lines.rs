//! The line chart the scaling and resolution charts share: one line per variant through its
//! measured points (whiskers min–max over viewpoints), failed points marked on the bottom edge
//! rather than dropped, optional backend bounds as dashed horizontal lines.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::data::Bound;
use super::draw::{self, err, Chart, LegendEntry, FONT, LEGEND_WIDTH};
use super::style::{Marker, StyleBook};
use crate::report::Spread;

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
    fn heading(&self) -> Vec<String> {
        let mut h = self.notes.clone();
        h.push("whiskers: min–max over viewpoints".into());
        if self
            .lines
            .iter()
            .any(|l| l.points.iter().any(|p| p.y.is_none()))
        {
            h.push("× on the bottom edge: failed there".into());
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
            1200,
            draw::height_for_legend(self.lines.len(), self.heading().len(), 620),
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let (w, _) = root.dim_in_pixel();
        let (plot, legend) = root.split_horizontally(w - LEGEND_WIDTH);
        let (xlo, xhi) = self.x_range();
        let (ylo, yhi) = self.y_range();
        // Both axis kinds go through one closure each way, so the drawing code below does
        // not depend on which scale the x axis has.
        let mut points_px: Vec<(
            usize,
            Vec<(Option<(i32, i32)>, (i32, i32), Option<(i32, i32)>)>,
        )> = vec![];
        let mut bound_px: Vec<(i32, i32, i32, String)> = vec![];
        macro_rules! body {
            ($chart:expr) => {{
                let chart = $chart;
                for (li, l) in self.lines.iter().enumerate() {
                    let mut v = vec![];
                    for p in &l.points {
                        match p.y {
                            Some(s) => v.push((
                                Some(chart.backend_coord(&(p.x, s.min))),
                                chart.backend_coord(&(p.x, s.mean)),
                                Some(chart.backend_coord(&(p.x, s.max))),
                            )),
                            None => v.push((None, chart.backend_coord(&(p.x, ylo)), None)),
                        }
                    }
                    points_px.push((li, v));
                }
                for b in &self.bounds {
                    let (x0, y) = chart.backend_coord(&(xlo, b.per_sec));
                    let (x1, _) = chart.backend_coord(&(xhi, b.per_sec));
                    bound_px.push((
                        x0,
                        x1,
                        y,
                        format!(
                            "calibrated bound: {} {}/s ({})",
                            b.name,
                            draw::si(b.per_sec),
                            b.adapter
                        ),
                    ));
                }
            }};
        }
        fn builder<'a, 'b, DB: DrawingBackend>(
            area: &'a DrawingArea<DB, Shift>,
            title: &str,
        ) -> ChartBuilder<'a, 'b, DB> {
            let mut b = ChartBuilder::on(area);
            b.caption(title, (FONT, 21).into_font())
                .margin(14)
                .x_label_area_size(52)
                .y_label_area_size(72);
            b
        }
        if self.x_log {
            let mut chart = builder(&plot, &self.title)
                .build_cartesian_2d((xlo..xhi).log_scale(), (ylo..yhi).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .bold_line_style(BLACK.mix(0.12))
                .light_line_style(BLACK.mix(0.04))
                .x_desc(&self.x_desc)
                .y_desc(&self.y_desc)
                .x_label_formatter(&|v| (self.x_fmt)(*v))
                .y_label_formatter(&|v| (self.y_fmt)(*v))
                .label_style((FONT, 14))
                .axis_desc_style((FONT, 15))
                .draw()
                .map_err(err)?;
            body!(&chart);
        } else {
            let mut chart = builder(&plot, &self.title)
                .build_cartesian_2d(xlo..xhi, (ylo..yhi).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .bold_line_style(BLACK.mix(0.12))
                .light_line_style(BLACK.mix(0.04))
                .x_desc(&self.x_desc)
                .y_desc(&self.y_desc)
                .x_label_formatter(&|v| (self.x_fmt)(*v))
                .y_label_formatter(&|v| (self.y_fmt)(*v))
                .label_style((FONT, 14))
                .axis_desc_style((FONT, 15))
                .draw()
                .map_err(err)?;
            body!(&chart);
        }
        for (x0, x1, y, text) in &bound_px {
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
        for (li, pts) in &points_px {
            let st = self
                .book
                .get(&self.lines[*li].algorithm, &self.lines[*li].settings);
            let line_style = st.color.stroke_width(2);
            // Lines join consecutive measured points only; a failure breaks the line.
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
                plot.draw(&PathElement::new(r, line_style)).map_err(err)?;
            }
            for (lo, mid, hi) in pts {
                match (lo, hi) {
                    (Some(lo), Some(hi)) => {
                        if lo != hi {
                            plot.draw(&PathElement::new(vec![*lo, *hi], st.color.stroke_width(1)))
                                .map_err(err)?;
                        }
                        draw::marker(&plot, *mid, 6, &st)?;
                    }
                    _ => {
                        let mut failed = st.clone();
                        failed.marker = Marker::Cross;
                        draw::marker(&plot, (mid.0, mid.1 - 8), 6, &failed)?;
                    }
                }
            }
        }
        let entries: Vec<LegendEntry> = self
            .lines
            .iter()
            .map(|l| LegendEntry {
                style: self.book.get(&l.algorithm, &l.settings),
                line: true,
                extra: l.extra.clone(),
            })
            .collect();
        draw::legend(&legend, &self.heading(), &entries)?;
        root.present().map_err(err)?;
        Ok(())
    }
}
