//! Fig. 8 of the fragment PT paper reproduced: K tets/s against the viewport side, a line per
//! variant (`papers::fragment_pt::fig8` measures the points).

use std::path::Path;

use anyhow::{anyhow, Context as _};
use plotters::prelude::*;

use crate::plot::draw::{register_font, FONT};
use crate::plot::style::categorical;

/// One point of Fig. 8: a series at one viewport size.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepPoint {
    pub series: String,
    pub resolution: u32,
    /// Mean over data sets of the mean over viewpoints of tets/s, in K tets/s.
    pub k_tets_per_sec: f64,
    pub datasets: usize,
}

fn draw_fig8<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    points: &[SweepPoint],
    adapter: &str,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing Fig. 8: {e:?}");
    root.fill(&WHITE).map_err(err)?;
    let xmax = points.iter().map(|p| p.resolution).max().unwrap_or(1024) as f64 * 1.08;
    let xmin = points.iter().map(|p| p.resolution).min().unwrap_or(256) as f64 * 0.8;
    let ymax = points
        .iter()
        .map(|p| p.k_tets_per_sec)
        .fold(0.0, f64::max)
        .max(1e-3)
        * 1.15;
    let caption = format!("Fig. 8 reproduction: K tets/s vs viewport ({adapter})");
    let mut chart = ChartBuilder::on(root)
        .caption(caption, (FONT, 20).into_font())
        .margin(14)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(xmin..xmax, 0.0..ymax)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("viewport side (pixels; image is side²)")
        .y_desc("K tets/s (mean over data sets)")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 15))
        .draw()
        .map_err(err)?;
    let mut series: Vec<&str> = vec![];
    for p in points {
        if !series.contains(&p.series.as_str()) {
            series.push(&p.series);
        }
    }
    for (i, s) in series.iter().enumerate() {
        let color = categorical(i);
        let mut pts: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.series == *s)
            .map(|p| (p.resolution as f64, p.k_tets_per_sec))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(err)?
            .label(s.to_string())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Writes `fig8.png` and `fig8.svg` (the SVG loads DejaVu Sans from `DejaVuSans.ttf` beside it).
pub fn write_fig8(dir: &Path, points: &[SweepPoint], adapter: &str) -> anyhow::Result<()> {
    register_font();
    let size = (1000, 640);
    let png = dir.join("fig8.png");
    {
        let root = BitMapBackend::new(&png, size).into_drawing_area();
        draw_fig8(&root, points, adapter).with_context(|| format!("writing {}", png.display()))?;
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_fig8(&root, points, adapter)?;
    }
    let style = format!("<style>@font-face {{ font-family: \"{FONT}\"; src: url(\"DejaVuSans.ttf\") format(\"truetype\"); }}</style>");
    if let Some(end) = svg
        .find("<svg")
        .and_then(|i| svg[i..].find('>').map(|j| i + j + 1))
    {
        svg.insert_str(end, &style);
    }
    std::fs::write(dir.join("DejaVuSans.ttf"), dejavu::sans::regular())?;
    let path = dir.join("fig8.svg");
    crate::results::write_file(&path, svg)
}
