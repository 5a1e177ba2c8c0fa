//! The ratio plots of `tetbench compare` (each row's or group's frame samples divided by BASE's
//! median, on a log axis); `regress::compare_report` passes the strips, already judged.

use std::path::Path;

use anyhow::{anyhow, Context};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::plot::draw::{register_font, FONT};
use crate::plot::style::{BASELINE_GREY, FASTER, NO_CHANGE, SLOWER};
use crate::results::write_file;

/// Which way a strip's verdict went, for its colour (the verdicts themselves are compare's).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    Slower,
    Faster,
    Neither,
}

/// One strip of a ratio plot.
pub struct Strip {
    pub label: String,
    pub base: Vec<f64>,
    pub new: Vec<f64>,
    /// The verdict's words, shown after the label.
    pub verdict: String,
    pub direction: Direction,
}

const LABEL_WIDTH: u32 = 560;
const STRIP: u32 = 22;

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    strips: &[Strip],
    threshold: f64,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing a ratio plot: {e:?}");
    root.fill(&WHITE).map_err(err)?;
    let all = strips
        .iter()
        .flat_map(|s| s.base.iter().chain(&s.new))
        .copied();
    let (mut lo, mut hi) = (1.0 / threshold, threshold);
    for v in all.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let (lo, hi) = (lo / 1.05, hi * 1.05);
    let n = strips.len().max(1);
    let (labels, plot) = root.split_horizontally(LABEL_WIDTH);
    let mut chart = ChartBuilder::on(&plot)
        .caption(title, (FONT, 18).into_font())
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(0)
        .build_cartesian_2d((lo..hi).log_scale(), 0f64..n as f64)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(0)
        .x_desc("sample / BASE median (log scale)")
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .bold_line_style(BLACK.mix(0.12))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;
    let line = |x: f64, style: ShapeStyle| PathElement::new(vec![(x, 0.0), (x, n as f64)], style);
    chart
        .draw_series([
            line(1.0, BLACK.stroke_width(1)),
            line(threshold, SLOWER.mix(0.5).stroke_width(1)),
            line(1.0 / threshold, FASTER.mix(0.5).stroke_width(1)),
        ])
        .map_err(err)?;
    let text = TextStyle::from((FONT, 12).into_font()).pos(Pos::new(HPos::Right, VPos::Center));
    for (i, s) in strips.iter().enumerate() {
        let y = (n - 1 - i) as f64 + 0.5;
        let colour = match s.direction {
            Direction::Slower => SLOWER,
            Direction::Faster => FASTER,
            Direction::Neither => NO_CHANGE,
        };
        chart
            .draw_series(
                s.base
                    .iter()
                    .map(|&x| Circle::new((x, y + 0.18), 3, BASELINE_GREY.filled())),
            )
            .map_err(err)?;
        chart
            .draw_series(
                s.new
                    .iter()
                    .map(|&x| Circle::new((x, y - 0.18), 3, colour.filled())),
            )
            .map_err(err)?;
        let (_, py) = chart.backend_coord(&(1.0, y));
        labels
            .draw(&Text::new(
                format!("{} [{}]", s.label, s.verdict),
                (LABEL_WIDTH as i32 - 8, py),
                text.clone(),
            ))
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// Writes `stem.png` and `stem.svg` into `dir`: grey dots BASE, coloured dots NEW (red slower,
/// green faster, blue no change), lines at 1 and at the threshold factors.
pub fn ratio_plot(
    dir: &Path,
    stem: &str,
    title: &str,
    strips: &[Strip],
    threshold: f64,
) -> anyhow::Result<()> {
    register_font();
    let size = (1300, 90 + STRIP * strips.len().max(1) as u32);
    let png = dir.join(format!("{stem}.png"));
    {
        let root = BitMapBackend::new(&png, size).into_drawing_area();
        draw(&root, title, strips, threshold)
            .with_context(|| format!("writing {}", png.display()))?;
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw(&root, title, strips, threshold)?;
    }
    let path = dir.join(format!("{stem}.svg"));
    write_file(&path, svg)
}
