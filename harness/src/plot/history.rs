//! The charts of `tetbench history` (`regress::history` computes the series and steps): one SVG
//! per algorithm × data set, laid out here and written by `templates/history_chart.svg`.
//!
//! A chart holds every settings variant's line with its noise band, a dashed bar where a step
//! of the fit starts (labelled with its ratio), a marker where compare's test found a change
//! against the run before (▲ slower, ✕ faster, ● other), and over each run an invisible column
//! whose `<title>` is the run's commit and date and every line's value there: hovering shows it
//! in any browser, with no script. Plotters draws no `<title>` per element, hence the layout is
//! computed here and the markup comes from an escaping template (docs/dependencies.md).

use serde::Serialize;

use crate::plot::style::{categorical, FASTER, SLOWER};

/// What compare's test found against the previous run, for the marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Change {
    Slower,
    Faster,
    /// PSNR, memory or work.
    Other,
}

/// One run of a line.
#[derive(Debug, Clone)]
pub struct LinePoint {
    /// Index into the runs.
    pub run: usize,
    pub total_ms: f64,
    pub band_lo: f64,
    pub band_hi: f64,
    /// A step of the piecewise-constant fit starts here, with this ratio to the level before.
    pub step: Option<f64>,
    pub change: Option<Change>,
    /// compare's findings against the run before, as the tooltip says them (empty: none).
    pub note: String,
}

/// One settings variant's line.
#[derive(Debug, Clone)]
pub struct Line {
    pub label: String,
    pub points: Vec<LinePoint>,
}

/// One run on the x axis.
#[derive(Debug, Clone)]
pub struct RunTick {
    /// `commit date`, as the tooltips name the run.
    pub label: String,
    /// The date alone, as the axis shows it.
    pub date: String,
}

/// A tick of an axis: its position and label.
#[derive(Debug, Clone, Serialize)]
pub struct Tick {
    pub at: String,
    /// Where the label's baseline (y ticks) or its centre's baseline (x ticks) stands.
    pub label_at: String,
    pub label: String,
    /// The label's `text-anchor` on the x axis: the last one ends at its tick, so that it
    /// stays inside the chart.
    pub anchor: &'static str,
}

/// A run of consecutive points of a line (a run missing from the series breaks it).
#[derive(Debug, Clone, Serialize)]
pub struct Segment {
    /// `x,y x,y …` of the line.
    pub line: String,
    /// The noise band's outline, upper edge then lower edge backwards.
    pub band: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct SvgLine {
    pub color: String,
    pub label: String,
    pub segments: Vec<Segment>,
    /// The legend entry's baseline and its swatch's height.
    pub legend_y: String,
    pub swatch_y: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct StepBar {
    pub x: String,
    pub color: String,
    /// `×1.30`, drawn beside the bar.
    pub label: String,
    pub label_x: String,
    pub label_y: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct Marker {
    /// `slower` (a triangle), `faster` (a cross) or `other` (a dot at x, y).
    pub kind: &'static str,
    pub x: String,
    pub y: String,
    /// The triangle's or the cross's outline.
    pub path: String,
    pub stroke: &'static str,
    pub color: String,
}

/// The hover column of one run.
#[derive(Debug, Clone, Serialize)]
pub struct Column {
    pub x: String,
    pub title: String,
}

/// Everything `templates/history_chart.svg` draws, positions already in pixels.
#[derive(Debug, Clone, Serialize)]
pub struct SvgChart {
    pub width: u32,
    pub height: u32,
    pub title: String,
    /// The plot's corners, size and middle.
    pub x0: String,
    pub y0: String,
    pub x1: String,
    pub y1: String,
    pub plot_w: String,
    pub plot_h: String,
    pub x_mid: String,
    pub y_mid: String,
    /// Where the y labels end and the x axis title stands.
    pub y_label_x: String,
    pub x_title_y: String,
    pub column_w: String,
    /// The legend's swatch end and text start.
    pub legend_swatch_x: String,
    pub legend_text_x: String,
    pub y_ticks: Vec<Tick>,
    pub x_ticks: Vec<Tick>,
    pub lines: Vec<SvgLine>,
    pub steps: Vec<StepBar>,
    pub markers: Vec<Marker>,
    pub columns: Vec<Column>,
}

const WIDTH: f64 = 960.0;
const LEFT: f64 = 64.0;
const RIGHT: f64 = 16.0;
const TOP: f64 = 30.0;
const PLOT_H: f64 = 250.0;
const LEGEND_LINE: f64 = 16.0;

fn px(v: f64) -> String {
    format!("{v:.1}")
}

fn hex(c: plotters::style::RGBColor) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

/// 1, 2 or 5 × 10ᵏ, the smallest at least `raw`.
fn nice_step(raw: f64) -> f64 {
    if raw.is_nan() || raw <= 0.0 || !raw.is_finite() {
        return 1.0;
    }
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|s| *s >= raw * (1.0 - 1e-9))
        .unwrap_or(10.0 * p)
}

/// Tick labels with as many decimals as the step needs.
fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    };
    format!("{v:.decimals$}")
}

/// Lays out one chart: `runs` is the x axis (one column per run), `lines` the variants.
pub fn svg_chart(title: &str, runs: &[RunTick], lines: &[Line]) -> SvgChart {
    let n = runs.len().max(1);
    let plot_w = WIDTH - LEFT - RIGHT;
    let col = plot_w / n as f64;
    let top = lines
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.band_hi.max(p.total_ms)))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let step = nice_step(top * 1.05 / 5.0);
    let place = Place {
        col,
        ymax: ((top * 1.05 / step).ceil() * step).max(step),
    };
    let y_ticks = place.y_ticks(step);
    let x_ticks = place.x_ticks(runs);
    let legend_top = TOP + PLOT_H + 48.0;
    let mut svg_lines = vec![];
    let mut steps = vec![];
    let mut markers = vec![];
    for (k, l) in lines.iter().enumerate() {
        let color = hex(categorical(k));
        let segments = place.segments(&l.points);
        for p in &l.points {
            if let Some(r) = p.step {
                let at = LEFT + p.run as f64 * col;
                steps.push(StepBar {
                    x: px(at),
                    color: color.clone(),
                    label: format!("×{r:.2}"),
                    label_x: px(at + 3.0),
                    label_y: px(TOP + 12.0 + 12.0 * (k % 6) as f64),
                });
            }
            if let Some(c) = p.change {
                markers.push(change_marker(c, place.x(p.run), place.y(p.total_ms)));
            }
        }
        svg_lines.push(SvgLine {
            color,
            label: l.label.clone(),
            segments,
            legend_y: px(legend_top + LEGEND_LINE * k as f64),
            swatch_y: px(legend_top + LEGEND_LINE * k as f64 - 4.0),
        });
    }
    let columns = column_titles(runs, lines)
        .into_iter()
        .map(|(i, title)| Column {
            x: px(LEFT + i as f64 * col),
            title,
        })
        .collect();
    SvgChart {
        width: WIDTH as u32,
        height: (legend_top + LEGEND_LINE * lines.len() as f64) as u32,
        title: title.to_string(),
        x0: px(LEFT),
        y0: px(TOP),
        x1: px(LEFT + plot_w),
        y1: px(TOP + PLOT_H),
        plot_w: px(plot_w),
        plot_h: px(PLOT_H),
        x_mid: px(LEFT + plot_w / 2.0),
        y_mid: px(TOP + PLOT_H / 2.0),
        y_label_x: px(LEFT - 4.0),
        x_title_y: px(TOP + PLOT_H + 32.0),
        column_w: px(col),
        legend_swatch_x: px(LEFT + 18.0),
        legend_text_x: px(LEFT + 24.0),
        y_ticks,
        x_ticks,
        lines: svg_lines,
        steps,
        markers,
        columns,
    }
}

/// Where a run's column and a time sit on the chart.
#[derive(Clone, Copy)]
struct Place {
    /// A run's column width.
    col: f64,
    /// The time at the top of the plot.
    ymax: f64,
}

impl Place {
    fn x(&self, run: usize) -> f64 {
        LEFT + (run as f64 + 0.5) * self.col
    }

    fn y(&self, v: f64) -> f64 {
        TOP + PLOT_H - (v.clamp(0.0, self.ymax) / self.ymax) * PLOT_H
    }

    /// A tick every `step` ms from 0 to the top.
    fn y_ticks(&self, step: f64) -> Vec<Tick> {
        (0..)
            .map(|k| k as f64 * step)
            .take_while(|v| *v <= self.ymax * (1.0 + 1e-9))
            .map(|v| Tick {
                at: px(self.y(v)),
                label_at: px(self.y(v) + 4.0),
                label: tick_label(v, step),
                anchor: "end",
            })
            .collect()
    }

    /// The dates of up to eight runs spread evenly, the last one's label ending at its tick.
    fn x_ticks(&self, runs: &[RunTick]) -> Vec<Tick> {
        let n = runs.len().max(1);
        let shown = n.min(8);
        let mut ticks = vec![];
        for k in 0..shown {
            let i = if shown == 1 {
                0
            } else {
                (k as f64 * (n - 1) as f64 / (shown - 1) as f64).round() as usize
            };
            if let Some(r) = runs.get(i) {
                ticks.push(Tick {
                    at: px(self.x(i)),
                    label_at: px(TOP + PLOT_H + 16.0),
                    label: r.date.clone(),
                    anchor: if k + 1 == shown && shown > 1 {
                        "end"
                    } else {
                        "middle"
                    },
                });
            }
        }
        ticks
    }

    /// A line's runs of consecutive points, each as its polyline and its band's polygon.
    fn segments(&self, points: &[LinePoint]) -> Vec<Segment> {
        let mut segments = vec![];
        let mut start = 0;
        for i in 1..=points.len() {
            if i == points.len() || points[i].run != points[i - 1].run + 1 {
                let pts = &points[start..i];
                let at = |(r, v): (usize, f64)| format!("{},{}", px(self.x(r)), px(self.y(v)));
                let line: Vec<String> = pts.iter().map(|p| at((p.run, p.total_ms))).collect();
                let band: Vec<String> = pts
                    .iter()
                    .map(|p| (p.run, p.band_hi))
                    .chain(pts.iter().rev().map(|p| (p.run, p.band_lo)))
                    .map(at)
                    .collect();
                segments.push(Segment {
                    line: line.join(" "),
                    band: band.join(" "),
                });
                start = i;
            }
        }
        segments
    }
}

/// The marker of compare's finding at a point (`mx`, `my`): a triangle for slower, a cross
/// for faster.
fn change_marker(c: Change, mx: f64, my: f64) -> Marker {
    let (kind, path, stroke, color) = match c {
        Change::Slower => (
            "slower",
            format!("M{},{}l4.5,8h-9z", px(mx), px(my - 5.0)),
            "0",
            hex(SLOWER),
        ),
        Change::Faster => (
            "faster",
            format!("M{},{}l8,8m0,-8l-8,8", px(mx - 4.0), px(my - 4.0)),
            "2",
            hex(FASTER),
        ),
        Change::Other => (
            "other",
            String::new(),
            "0",
            hex(plotters::style::colors::BLACK),
        ),
    };
    Marker {
        kind,
        x: px(mx),
        y: px(my),
        path,
        stroke,
        color,
    }
}

/// Per run that any line has a point at: the run's label, then each line's value there, its
/// step and compare's findings.
fn column_titles(runs: &[RunTick], lines: &[Line]) -> Vec<(usize, String)> {
    let mut text: Vec<Option<String>> = vec![None; runs.len()];
    for l in lines {
        for p in &l.points {
            let Some(slot) = text.get_mut(p.run) else {
                continue;
            };
            let t = slot.get_or_insert_with(|| runs[p.run].label.clone());
            t.push_str(&format!("\n{}: {:.2} ms", l.label, p.total_ms));
            if let Some(r) = p.step {
                t.push_str(&format!(", step ×{r:.2} starts here"));
            }
            if !p.note.is_empty() {
                t.push_str(&format!(" ({})", p.note));
            }
        }
    }
    text.into_iter()
        .enumerate()
        .filter_map(|(i, t)| t.map(|t| (i, t)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(run: usize, ms: f64) -> LinePoint {
        LinePoint {
            run,
            total_ms: ms,
            band_lo: ms * 0.9,
            band_hi: ms * 1.1,
            step: None,
            change: None,
            note: String::new(),
        }
    }

    /// Steps become bars at the boundary before their run, every run with a point gets a
    /// column naming its commit and values, a run missing from a line breaks the line, and the
    /// y axis covers the highest band with round ticks.
    #[test]
    fn the_layout_marks_steps_and_names_every_run() {
        let runs: Vec<RunTick> = (0..10)
            .map(|i| RunTick {
                label: format!("c{i} 2026-01-{:02}", i + 1),
                date: format!("2026-01-{:02}", i + 1),
            })
            .collect();
        let mut a: Vec<LinePoint> = (0..10)
            .map(|i| point(i, if i < 6 { 10.0 } else { 13.0 }))
            .collect();
        a[6].step = Some(1.3);
        a[6].change = Some(Change::Slower);
        a[6].note = "slower ×1.300".into();
        let b: Vec<LinePoint> = (0..10).filter(|i| *i != 4).map(|i| point(i, 5.0)).collect();
        let c = svg_chart(
            "t",
            &runs,
            &[
                Line {
                    label: "k=2".into(),
                    points: a,
                },
                Line {
                    label: "k=6".into(),
                    points: b,
                },
            ],
        );
        assert_eq!(c.steps.len(), 1);
        let col = (WIDTH - LEFT - RIGHT) / 10.0;
        assert_eq!(c.steps[0].x, px(LEFT + 6.0 * col));
        assert_eq!(c.steps[0].label, "×1.30");
        assert_eq!(c.markers.len(), 1);
        assert_eq!(c.markers[0].kind, "slower");
        assert_eq!(c.columns.len(), 10);
        let t = &c.columns[6].title;
        assert!(t.starts_with("c6 2026-01-07\nk=2: 13.00 ms, step ×1.30 starts here (slower ×1.300)\nk=6: 5.00 ms"), "{t}");
        assert!(!c.columns[4].title.contains("k=6"));
        assert_eq!(c.lines[0].segments.len(), 1);
        assert_eq!(c.lines[1].segments.len(), 2);
        assert_eq!(c.x_ticks.len(), 8);
        assert_eq!(c.x_ticks[0].label, "2026-01-01");
        assert_eq!(c.x_ticks[7].label, "2026-01-10");
        // The top band, 13 × 1.1, with 5 % room: 15.0, so a step of 5 up to 20.
        let labels: Vec<&str> = c.y_ticks.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(labels, ["0", "5", "10", "15", "20"]);
        assert_eq!(nice_step(0.013), 0.02);
        assert_eq!(tick_label(0.04, 0.02), "0.04");
    }
}
