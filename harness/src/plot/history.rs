//! The charts of `tetbench history` (`regress::history` computes the series and steps).

use std::path::Path;

use anyhow::anyhow;
use plotters::prelude::*;

use crate::plot::draw::{register_font, FONT};
use crate::plot::style::{categorical, FASTER, SLOWER};

/// What compare's test found against the previous run, for the marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Change {
    Slower,
    Faster,
    /// PSNR, memory or too few rounds.
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
    /// A step of the piecewise-constant fit starts here.
    pub step: bool,
    pub change: Option<Change>,
}

/// One settings variant's line.
#[derive(Debug, Clone)]
pub struct Line {
    pub label: String,
    pub points: Vec<LinePoint>,
}

/// One chart of `tetbench history`: a line per settings variant, its noise band, and a
/// marker where a change was found (red ▲ slower, green ✕ faster, black ● other); `runs` are
/// the x-axis labels.
pub fn chart(path: &Path, title: &str, runs: &[String], series: &[Line]) -> anyhow::Result<()> {
    register_font();
    let ymax = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.band_hi.max(p.total_ms)))
        .fold(0.0, f64::max)
        * 1.15;
    let root = BitMapBackend::new(path, (1100, 460)).into_drawing_area();
    let err = |e| anyhow!("drawing {}: {e:?}", path.display());
    root.fill(&WHITE).map_err(err)?;
    let n = runs.len().max(2);
    let mut c = ChartBuilder::on(&root)
        .caption(title, (FONT, 18).into_font())
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(-0.3f64..(n - 1) as f64 + 0.3, 0f64..ymax.max(1e-3))
        .map_err(err)?;
    let labels = runs;
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
        let col = categorical(k);
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
        .label(s.label.clone())
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], col.stroke_width(2)));
        // A step of the fit: a vertical bar at the run where the new level starts.
        for p in s.points.iter().filter(|p| p.step) {
            let x = p.run as f64 - 0.5;
            c.draw_series(std::iter::once(PathElement::new(
                vec![(x, 0.0), (x, ymax)],
                col.mix(0.6).stroke_width(2),
            )))
            .map_err(err)?;
        }
        for p in &s.points {
            let at = (p.run as f64, p.total_ms);
            match p.change {
                Some(Change::Slower) => {
                    c.draw_series(std::iter::once(TriangleMarker::new(at, 8, SLOWER.filled())))
                        .map_err(err)?;
                }
                Some(Change::Faster) => {
                    c.draw_series(std::iter::once(Cross::new(at, 7, FASTER.stroke_width(3))))
                        .map_err(err)?;
                }
                Some(Change::Other) => {
                    c.draw_series(std::iter::once(Circle::new(at, 5, BLACK.filled())))
                        .map_err(err)?;
                }
                None => {}
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
