//! The bar charts of the papers' tables, paper vs ours (`papers::table` picks the metrics and
//! rows).

use std::path::Path;

use anyhow::anyhow;
use plotters::prelude::*;

use crate::plot::draw::{register_font, FONT};
use crate::plot::style::{OUR_VALUE, PAPER_VALUE};

/// An axis value in few characters: 1.5M, 230k, 12, 0.05.
fn compact(v: f64) -> String {
    let a = v.abs();
    if a >= 1e6 {
        format!("{}M", trim(v / 1e6))
    } else if a >= 1e3 {
        format!("{}k", trim(v / 1e3))
    } else {
        trim(v)
    }
}

fn trim(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

fn err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing a chart: {e:?}")
}

/// One bar chart of a paper's table: per row, the paper's value (grey) beside ours (blue),
/// on a log axis; `bars` are (row label, paper, ours), values > 0.
pub fn draw(
    path: &Path,
    title: &str,
    y_desc: &str,
    bars: &[(String, Option<f64>, Option<f64>)],
) -> anyhow::Result<()> {
    let values = bars.iter().flat_map(|(_, p, o)| [*p, *o]).flatten();
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
    let (lo, hi) = (lo / 2.0, hi * 2.0);
    let width = (160 + 90 * bars.len()).clamp(500, 1400) as u32;
    register_font();
    let root = BitMapBackend::new(path, (width, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let short: String = title.chars().take(90).collect();
    let n = bars.len() as f64;
    // Group i is centred on x = i, so the axis' integer ticks carry the row labels.
    let mut chart = ChartBuilder::on(&root)
        .caption(short, (FONT, 16).into_font())
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5..n - 0.5, (lo..hi).log_scale())
        .map_err(err)?;
    let labels: Vec<String> = bars.iter().map(|b| b.0.clone()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .light_line_style(WHITE)
        .x_labels(bars.len() + 1)
        .x_label_formatter(&|x| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .y_labels(8)
        .y_label_formatter(&|y| compact(*y))
        .y_desc(y_desc)
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 13))
        .draw()
        .map_err(err)?;
    let (paper_color, ours_color) = (PAPER_VALUE, OUR_VALUE);
    for (i, (_, p, o)) in bars.iter().enumerate() {
        let x = i as f64;
        if let Some(p) = p {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x - 0.4, lo), (x - 0.02, *p)],
                    paper_color.filled(),
                )))
                .map_err(err)?;
        }
        if let Some(o) = o {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x + 0.02, lo), (x + 0.4, *o)],
                    ours_color.filled(),
                )))
                .map_err(err)?;
        }
    }
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(0.0, lo), (0.0, lo)],
            paper_color.filled(),
        )))
        .map_err(err)?
        .label("paper")
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], paper_color.filled()));
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(0.0, lo), (0.0, lo)],
            ours_color.filled(),
        )))
        .map_err(err)?
        .label("ours")
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], ours_color.filled()));
    chart
        .configure_series_labels()
        .label_font((FONT, 12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_values_are_compact() {
        assert_eq!(compact(1_500_000.0), "1.5M");
        assert_eq!(compact(230_000.0), "230k");
        assert_eq!(compact(0.05), "0.05");
    }
}
