//! Throughput against viewport size for every algorithm: the fragment PT paper's Fig. 8
//! (Marroquim et al. 2006, §6: K tets/s at 256² … 1024² for one algorithm) generalised to
//! every variant of a run, one chart per data set with at least two viewport sizes.

use std::path::Path;

use serde::Serialize;

use super::data::{distinct, Inputs, Point, PointColumns};
use super::draw;
use super::lines::{save_parts, variants, Line, LineChart, LinePoint};
use super::speed_error::sort_by_style;
use super::style::StyleBook;
use super::{ChartFile, Kind};

/// A resolution chart's own CSV column, after the [`PointColumns`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Own {
    pub error: String,
}

fn pixels(v: f64) -> String {
    format!("{v:.0}")
}

pub fn write(
    dir: &Path,
    points: &[Point],
    inputs: &Inputs,
    book: &StyleBook,
) -> anyhow::Result<Vec<ChartFile>> {
    let mut files = vec![];
    for dataset in distinct(points.iter().map(|p| p.dataset.clone())) {
        let mut pts: Vec<&Point> = points.iter().filter(|p| p.dataset == dataset).collect();
        if distinct(pts.iter().map(|p| (p.width, p.height))).len() < 2 {
            continue;
        }
        sort_by_style(&mut pts, book);
        pts.sort_by_key(|p| (p.width, p.height));
        let square = pts.iter().all(|p| p.width == p.height);
        let records: Vec<(PointColumns, Own)> = pts
            .iter()
            .map(|p| {
                let own = Own {
                    error: p.error.clone(),
                };
                (PointColumns::new(p, book), own)
            })
            .collect();
        let lines: Vec<Line> = variants(&pts, book)
            .into_iter()
            .map(|(a, s)| Line {
                points: pts
                    .iter()
                    .filter(|p| p.algorithm == a && p.settings == s)
                    .map(|p| LinePoint {
                        // Square viewports by the side (as Fig. 8); others by √pixels.
                        x: if square {
                            p.width as f64
                        } else {
                            ((p.width as f64) * (p.height as f64)).sqrt()
                        },
                        y: p.tets_per_sec,
                    })
                    .collect(),
                algorithm: a,
                settings: s,
                extra: String::new(),
            })
            .collect();
        let mut notes = vec![format!("{} tets", draw::si(pts[0].tets as f64))];
        if inputs.without_reference {
            notes.push("timing only (--no-reference)".into());
        }
        let stem = format!("resolution_{}", crate::results::names::slug(&dataset));
        let made = save_parts(
            dir,
            (&stem, Kind::Resolution),
            lines,
            &records,
            |alg, part| LineChart {
                title: format!("Throughput vs viewport size — {dataset}{alg}"),
                x_desc: if square {
                    "viewport side (pixels, square)".into()
                } else {
                    "√(width × height) (pixels)".into()
                },
                y_desc: "tets per second (log)".into(),
                x_log: false,
                x_fmt: pixels,
                y_fmt: draw::si,
                lines: part,
                bounds: vec![],
                notes: notes.clone(),
                book,
            },
        )?;
        files.extend(made);
    }
    Ok(files)
}
