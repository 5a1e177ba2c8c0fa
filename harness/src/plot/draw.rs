//! Drawing pieces every chart shares: the embedded font, PNG + SVG output, marker shapes,
//! the legend panel and number formatting.
//!
//! Charts use plotters' pure-Rust text path (ab_glyph) with DejaVu Sans compiled in, so they
//! render on machines without any font installed. The SVGs name the family "DejaVu Sans" and
//! load it with `@font-face` from `DejaVuSans.ttf`, written beside them.

use std::path::Path;
use std::sync::Once;

use anyhow::{anyhow, Context};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

use super::style::{Marker, Style};
use crate::results::write_file;

pub const FONT: &str = "DejaVu Sans";

pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in, so failure would be a corrupt build: nothing to recover.
        plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular())
            .unwrap_or_else(|_| panic!("embedded DejaVu Sans is not a valid font"));
        plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold())
            .unwrap_or_else(|_| panic!("embedded DejaVu Sans Bold is not a valid font"));
    });
}

/// A chart that can draw itself on any plotters backend.
pub trait Chart {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static;
}

/// Turns a plotters error into an anyhow one.
pub fn err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing a chart: {e:?}")
}

/// Writes `stem.png` and `stem.svg` into `dir` (and the font the SVG loads).
pub fn save(chart: &impl Chart, dir: &Path, stem: &str) -> anyhow::Result<()> {
    register_font();
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let font = dir.join("DejaVuSans.ttf");
    if !font.exists() {
        write_file(&font, dejavu::sans::regular())?;
    }
    let size = chart.size();
    let png = dir.join(format!("{stem}.png"));
    {
        let root = BitMapBackend::new(&png, size).into_drawing_area();
        chart
            .draw(&root)
            .with_context(|| format!("writing {}", png.display()))?;
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        chart.draw(&root)?;
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
    write_file(&path, svg)
}

/// Draws a marker of `style` centred at pixel `(x, y)` with radius `r`.
pub fn marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    r: i32,
    style: &Style,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let c = style.color;
    let fill: ShapeStyle = if style.hollow {
        c.stroke_width(2)
    } else {
        c.filled()
    };
    let line = c.stroke_width(if style.hollow { 2 } else { 3 });
    let poly = |pts: Vec<(f64, f64)>| -> Vec<(i32, i32)> {
        pts.into_iter()
            .map(|(dx, dy)| {
                (
                    x + (dx * r as f64).round() as i32,
                    y + (dy * r as f64).round() as i32,
                )
            })
            .collect()
    };
    let shape = |pts: Vec<(f64, f64)>| -> anyhow::Result<()> {
        let p = poly(pts);
        if style.hollow {
            let mut closed = p.clone();
            closed.push(p[0]);
            area.draw(&PathElement::new(closed, fill)).map_err(err)
        } else {
            area.draw(&Polygon::new(p, fill)).map_err(err)
        }
    };
    match style.marker {
        Marker::Circle => area.draw(&Circle::new((x, y), r, fill)).map_err(err),
        Marker::Square => shape(vec![
            (-0.85, -0.85),
            (0.85, -0.85),
            (0.85, 0.85),
            (-0.85, 0.85),
        ]),
        Marker::TriangleUp => shape(vec![(0.0, -1.15), (1.0, 0.75), (-1.0, 0.75)]),
        Marker::TriangleDown => shape(vec![(0.0, 1.15), (1.0, -0.75), (-1.0, -0.75)]),
        Marker::Diamond => shape(vec![(0.0, -1.2), (1.0, 0.0), (0.0, 1.2), (-1.0, 0.0)]),
        Marker::Hexagon => shape(
            (0..6)
                .map(|i| {
                    let a = std::f64::consts::PI / 3.0 * i as f64;
                    (a.cos(), a.sin())
                })
                .collect(),
        ),
        Marker::Cross => {
            area.draw(&PathElement::new(
                poly(vec![(-1.0, -1.0), (1.0, 1.0)]),
                line,
            ))
            .map_err(err)?;
            area.draw(&PathElement::new(
                poly(vec![(-1.0, 1.0), (1.0, -1.0)]),
                line,
            ))
            .map_err(err)
        }
        Marker::Plus => {
            area.draw(&PathElement::new(poly(vec![(-1.1, 0.0), (1.1, 0.0)]), line))
                .map_err(err)?;
            area.draw(&PathElement::new(poly(vec![(0.0, -1.1), (0.0, 1.1)]), line))
                .map_err(err)
        }
    }
}

/// One legend line.
pub struct LegendEntry {
    pub style: Style,
    /// Draw a line through the marker (for line charts).
    pub line: bool,
    /// Text after the label, e.g. a fitted exponent.
    pub extra: String,
}

pub const LEGEND_ROW: i32 = 22;
/// Width of the plot panel; the legend panel beside it is as wide as its longest line.
pub const PLOT_WIDTH: u32 = 860;

impl LegendEntry {
    pub fn text(&self) -> String {
        if self.extra.is_empty() {
            self.style.label.clone()
        } else {
            format!("{}  {}", self.style.label, self.extra)
        }
    }
}

/// Pixel width of `text` in the legend font (measured with the embedded font, so a legend
/// is never cut).
pub fn text_width(text: &str, size: f64) -> u32 {
    register_font();
    (FONT, size)
        .into_font()
        .box_size(text)
        .map(|(w, _)| w)
        .unwrap_or((text.chars().count() as f64 * size * 0.62) as u32)
}

/// Width of a legend panel holding `heading` and `entries`, margins included.
pub fn legend_width(heading: &[String], entries: &[LegendEntry]) -> u32 {
    let h = heading.iter().map(|t| 8 + text_width(t, 13.0));
    let e = entries.iter().map(|e| 40 + text_width(&e.text(), 13.0));
    h.chain(e).max().unwrap_or(0).max(200) + 16
}
/// Legend rows that fit beside a chart of the minimum height; beyond this charts are split.
pub const MAX_LEGEND_ROWS: usize = 18;

/// Draws the legend panel: a heading (lines of text), then one row per entry.
pub fn legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    heading: &[String],
    entries: &[LegendEntry],
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let mut y = 40;
    for line in heading {
        area.draw(&Text::new(line.clone(), (8, y), (FONT, 13).into_font()))
            .map_err(err)?;
        y += 17;
    }
    y += 8;
    for e in entries {
        let cy = y + 7;
        if e.line {
            area.draw(&PathElement::new(
                vec![(6, cy), (34, cy)],
                e.style.color.stroke_width(2),
            ))
            .map_err(err)?;
        }
        marker(area, (20, cy), 6, &e.style)?;
        area.draw(&Text::new(e.text(), (40, y), (FONT, 13).into_font()))
            .map_err(err)?;
        y += LEGEND_ROW;
    }
    Ok(())
}

/// `items` on one chart, or, when its legend would not fit, one chart per algorithm (in order
/// of first appearance): each part with its algorithm, empty for the one chart.
pub fn legend_parts<T: Clone>(items: Vec<T>, algorithm: fn(&T) -> &str) -> Vec<(String, Vec<T>)> {
    if items.len() <= MAX_LEGEND_ROWS {
        return vec![(String::new(), items)];
    }
    super::data::distinct(items.iter().map(algorithm))
        .into_iter()
        .map(|a| {
            let part = items.iter().filter(|i| algorithm(i) == a).cloned();
            (a.to_string(), part.collect())
        })
        .collect()
}

/// Height that fits `rows` legend rows below a heading of `heading` lines.
pub fn height_for_legend(rows: usize, heading: usize, min: u32) -> u32 {
    (70 + 17 * heading as u32 + LEGEND_ROW as u32 * rows as u32).max(min)
}

/// Compact numbers for axes: 10k, 2.5M, 1G, 0.5.
pub fn si(v: f64) -> String {
    let a = v.abs();
    let (x, suffix) = if a >= 1e9 {
        (v / 1e9, "G")
    } else if a >= 1e6 {
        (v / 1e6, "M")
    } else if a >= 1e3 {
        (v / 1e3, "k")
    } else {
        (v, "")
    };
    let t = if x.abs() >= 100.0 || x.fract() == 0.0 {
        format!("{x:.0}")
    } else if x.abs() >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    };
    let t = if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    };
    format!("{t}{suffix}")
}

/// Bytes in decimal units (B, kB, MB, GB), so that log-axis ticks at 1-2-5 read round.
pub fn bytes(v: f64) -> String {
    let t = si(v);
    match t.chars().last() {
        Some('k') | Some('M') | Some('G') => {
            let (n, u) = t.split_at(t.len() - 1);
            format!("{n} {}B", if u == "k" { "k" } else { u })
        }
        _ => format!("{t} B"),
    }
}

/// A log axis range covering `lo..hi` with a margin, snapped outwards to 1-2-5 steps so the
/// end labels are round.
pub fn log_range(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = if lo > 0.0 && hi >= lo {
        (lo, hi)
    } else {
        (1.0, 10.0)
    };
    let snap_down = |v: f64| {
        let d = 10f64.powf(v.log10().floor());
        [5.0, 2.0, 1.0]
            .into_iter()
            .map(|m| m * d)
            .find(|&c| c <= v)
            .unwrap_or(d)
    };
    let snap_up = |v: f64| {
        let d = 10f64.powf(v.log10().floor());
        [1.0, 2.0, 5.0, 10.0]
            .into_iter()
            .map(|m| m * d)
            .find(|&c| c >= v)
            .unwrap_or(10.0 * d)
    };
    let lo = snap_down(lo / 1.15);
    let mut hi = snap_up(hi * 1.15);
    if hi <= lo {
        hi = lo * 10.0;
    }
    (lo, hi)
}

/// One axis of a chart. Charts are built on linear coordinates; a log axis stores log10 of
/// its values, and draws its own ticks at 1, 2 and 5 × 10ⁿ (plotters' log axis labels every
/// integer multiple, and the labels collide).
#[derive(Debug, Clone, Copy)]
pub struct Axis {
    pub log: bool,
    /// Ends in data units.
    pub lo: f64,
    pub hi: f64,
}

impl Axis {
    /// Chart coordinate of a data value.
    pub fn at(&self, v: f64) -> f64 {
        if self.log {
            v.max(f64::MIN_POSITIVE).log10()
        } else {
            v
        }
    }

    pub fn range(&self) -> std::ops::Range<f64> {
        self.at(self.lo)..self.at(self.hi)
    }

    /// Tick values in data units.
    pub fn ticks(&self) -> Vec<f64> {
        let inside = |v: &f64| *v >= self.lo * (1.0 - 1e-9) && *v <= self.hi * (1.0 + 1e-9);
        if self.log {
            let (a, b) = (
                self.lo.log10().floor() as i32,
                self.hi.log10().ceil() as i32,
            );
            let decades = (b - a).max(1);
            let mantissas: &[f64] = if decades > 4 {
                &[1.0]
            } else {
                &[1.0, 2.0, 5.0]
            };
            (a..=b)
                .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
                .filter(inside)
                .collect()
        } else {
            let span = (self.hi - self.lo).max(1e-12);
            let raw = span / 6.0;
            let d = 10f64.powf(raw.log10().floor());
            let step = [1.0, 2.0, 5.0, 10.0]
                .into_iter()
                .map(|m| m * d)
                .find(|&s| s >= raw)
                .unwrap_or(10.0 * d);
            let first = (self.lo / step).ceil() as i64;
            let last = (self.hi / step).floor() as i64;
            (first..=last).map(|i| i as f64 * step).collect()
        }
    }
}

/// The plot panel of a chart on two [`Axis`]: its title, the axes described, our grid and
/// tick labels in place of plotters' mesh.
pub struct Axes<'t> {
    pub title: &'t str,
    pub x: Axis,
    pub y: Axis,
    pub x_desc: &'t str,
    pub y_desc: &'t str,
    pub x_fmt: fn(f64) -> String,
    pub y_fmt: fn(f64) -> String,
    /// Room left of the plot for the widest y label.
    pub y_label_area: u32,
}

/// A chart on linear coordinates ([`Axis::at`] maps data values onto them).
pub type Chart2d<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

impl Axes<'_> {
    /// Draws the panel on `area` and returns the chart to draw the data on.
    pub fn draw<'a, DB: DrawingBackend>(
        &self,
        area: &'a DrawingArea<DB, Shift>,
    ) -> anyhow::Result<Chart2d<'a, DB>>
    where
        DB::ErrorType: 'static,
    {
        let mut chart = ChartBuilder::on(area)
            .caption(self.title, (FONT, 21).into_font())
            .margin(14)
            .x_label_area_size(52)
            .y_label_area_size(self.y_label_area)
            .build_cartesian_2d(self.x.range(), self.y.range())
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .light_line_style(WHITE.mix(0.0))
            .bold_line_style(WHITE.mix(0.0))
            .x_labels(0)
            .y_labels(0)
            .x_desc(self.x_desc)
            .y_desc(self.y_desc)
            .axis_desc_style((FONT, 15))
            .draw()
            .map_err(err)?;
        grid(&chart, area, self.x, self.y, self.x_fmt, self.y_fmt)?;
        Ok(chart)
    }
}

/// Grid lines and tick labels of both axes (the mesh of plotters is switched off).
fn grid<DB: DrawingBackend>(
    chart: &Chart2d<DB>,
    area: &DrawingArea<DB, Shift>,
    x: Axis,
    y: Axis,
    x_fmt: fn(f64) -> String,
    y_fmt: fn(f64) -> String,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let line = BLACK.mix(0.13).stroke_width(1);
    let (xr, yr) = (x.range(), y.range());
    let below = TextStyle::from((FONT, 14).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
    let left = TextStyle::from((FONT, 14).into_font()).pos(Pos::new(HPos::Right, VPos::Center));
    for t in x.ticks() {
        let c = x.at(t);
        let (p0, p1) = (
            chart.backend_coord(&(c, yr.start)),
            chart.backend_coord(&(c, yr.end)),
        );
        area.draw(&PathElement::new(vec![p0, p1], line))
            .map_err(err)?;
        area.draw(&Text::new(x_fmt(t), (p0.0, p0.1 + 6), below.clone()))
            .map_err(err)?;
    }
    for t in y.ticks() {
        let c = y.at(t);
        let (p0, p1) = (
            chart.backend_coord(&(xr.start, c)),
            chart.backend_coord(&(xr.end, c)),
        );
        area.draw(&PathElement::new(vec![p0, p1], line))
            .map_err(err)?;
        area.draw(&Text::new(y_fmt(t), (p0.0 - 6, p0.1), left.clone()))
            .map_err(err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_well() {
        assert_eq!(si(10_000.0), "10k");
        assert_eq!(si(2_500_000.0), "2.5M");
        assert_eq!(si(0.5), "0.5");
        assert_eq!(si(1e9), "1G");
        assert_eq!(bytes(3e6), "3 MB");
        assert_eq!(bytes(512.0), "512 B");
        let a = Axis {
            log: true,
            lo: 20_000.0,
            hi: 500_000.0,
        };
        assert_eq!(a.ticks(), [2e4, 5e4, 1e5, 2e5, 5e5]);
        let l = Axis {
            log: false,
            lo: 38.0,
            hi: 101.0,
        };
        assert_eq!(l.ticks(), [40.0, 60.0, 80.0, 100.0]);
        let (lo, hi) = log_range(3_000.0, 4.1e6);
        assert_eq!((lo, hi), (2_000.0, 5e6));
    }
}
