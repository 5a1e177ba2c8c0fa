//! Scaling with mesh size: tets/s and GPU bytes against tets, log–log, one line per variant,
//! with the exponent of a least-squares power-law fit (tets/s ∝ tets^b: b = 0 means time grows
//! linearly with the mesh; b < 0 means worse than linear). Meshes are grouped into families
//! (`box:10k`, `box:1m` → `box`; named data sets together), one chart per family and viewport.

use std::path::Path;

use serde::Serialize;

use super::data::{distinct, write_csv, Inputs, Point, PointColumns};
use super::draw;
use super::lines::{save_parts, variants, Line, LineChart, LinePoint};
use super::speed_error::sort_by_style;
use super::style::StyleBook;
use super::{ChartFile, Kind};
use crate::results::stats::Spread;

/// A data set's family: a generator's name (`box:1m` → `box`), or `data sets` for files and
/// registry names, whose sizes differ too.
pub fn family(dataset: &str) -> String {
    match dataset.split_once(':') {
        Some((g, _)) => g.to_string(),
        None => "data sets".to_string(),
    }
}

/// Slope of the least-squares line through (ln x, ln y): the exponent of y ∝ x^b. `None` with
/// fewer than two distinct x.
pub fn power_law_exponent(xy: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = xy
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    linear_slope(&logs)
}

/// Slope of the least-squares line through (x, y): e.g. GPU bytes per extra tet, which the
/// log–log exponent hides when a fixed-size table dominates small meshes (HAVS's 3D
/// pre-integration table).
pub fn linear_slope(xy: &[(f64, f64)]) -> Option<f64> {
    let n = xy.len() as f64;
    if xy.len() < 2 {
        return None;
    }
    let mx = xy.iter().map(|p| p.0).sum::<f64>() / n;
    let my = xy.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The family column a scaling chart's CSV line opens with, before the [`PointColumns`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Family {
    pub family: String,
}

/// A scaling chart's own CSV columns, after the [`PointColumns`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Own {
    pub gpu_bytes: Option<u64>,
    pub bytes_per_tet: Option<f64>,
    pub error: String,
}

/// One CSV line: a variant at one mesh size.
pub type Record = (Family, PointColumns, Own);

/// One CSV line of the fits: a variant's exponents over the sizes it was measured at.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Fit {
    pub family: String,
    pub width: u32,
    pub height: u32,
    pub label: String,
    pub algorithm: String,
    pub settings: String,
    pub sizes_measured: usize,
    pub sizes_failed: usize,
    pub tets_per_sec_exponent: Option<f64>,
    pub gpu_bytes_exponent: Option<f64>,
    /// GPU bytes per additional tet (linear fit of bytes against tets).
    pub gpu_bytes_per_tet_marginal: Option<f64>,
}

/// What `write` made: the chart files and the fits (printed by `tetbench plot scaling`).
#[derive(Debug, Default)]
pub struct Output {
    pub files: Vec<ChartFile>,
    pub fits: Vec<Fit>,
}

fn exponent_text(b: Option<f64>) -> String {
    b.map(|b| format!("b = {b:+.2}"))
        .unwrap_or_else(|| "b: –".into())
}

/// Draws the scaling charts of every family with at least two mesh sizes.
pub fn write(
    dir: &Path,
    points: &[Point],
    inputs: &Inputs,
    book: &StyleBook,
) -> anyhow::Result<Output> {
    let mut out = Output::default();
    let groups = distinct(
        points
            .iter()
            .map(|p| (family(&p.dataset), p.width, p.height)),
    );
    let many_sizes = distinct(points.iter().map(|p| (p.width, p.height))).len() > 1;
    for (fam, width, height) in groups {
        let mut pts: Vec<&Point> = points
            .iter()
            .filter(|p| family(&p.dataset) == fam && p.width == width && p.height == height)
            .collect();
        if distinct(pts.iter().map(|p| p.tets)).len() < 2 {
            continue;
        }
        sort_by_style(&mut pts, book);
        pts.sort_by_key(|p| p.tets);
        let mut stem = format!(
            "scaling_{}",
            crate::results::names::slug(&fam.replace(' ', "_"))
        );
        if many_sizes {
            stem.push_str(&format!("_{width}x{height}"));
        }
        let records = records(&fam, &pts, book);
        let (mut speed_lines, mut byte_lines, mut fits) = (vec![], vec![], vec![]);
        for (a, s) in variants(&pts, book) {
            let mine: Vec<&Point> = pts
                .iter()
                .copied()
                .filter(|p| p.algorithm == a && p.settings == s)
                .collect();
            let fit = fit(&fam, (width, height), &mine, book);
            let (speed, bytes) = variant_lines(&mine, &fit);
            speed_lines.push(speed);
            byte_lines.push(bytes);
            fits.push(fit);
        }
        let notes = notes(&fam, (width, height), inputs);
        let charts = [
            (
                "tets_per_sec",
                "throughput",
                "tets per second (log)",
                speed_lines,
                inputs.bounds.clone(),
                "b: fitted exponent, tets/s ∝ tets^b",
                draw::si as fn(f64) -> String,
            ),
            (
                "gpu_bytes",
                "GPU memory",
                "GPU bytes (log)",
                byte_lines,
                vec![],
                "b: fitted exponent, bytes ∝ tets^b",
                draw::bytes as fn(f64) -> String,
            ),
        ];
        for (what, shows, y_desc, lines, bounds, fit_note, y_fmt) in charts {
            let stem = format!("{stem}_{what}");
            let made = save_parts(dir, (&stem, Kind::Scaling), lines, &records, |alg, part| {
                LineChart {
                    title: format!("Scaling with mesh size — {fam}{alg}: {shows}"),
                    x_desc: "tets in the mesh (log)".into(),
                    y_desc: y_desc.into(),
                    x_log: true,
                    x_fmt: draw::si,
                    y_fmt,
                    lines: part,
                    bounds: bounds.clone(),
                    notes: std::iter::once(fit_note.to_string())
                        .chain(notes.iter().cloned())
                        .collect(),
                    book,
                }
            })?;
            out.files.extend(made);
        }
        write_csv(dir, &format!("{stem}_fit"), &fits)?;
        out.fits.extend(fits);
    }
    Ok(out)
}

/// The CSV lines of one family's points.
fn records(fam: &str, pts: &[&Point], book: &StyleBook) -> Vec<Record> {
    pts.iter()
        .map(|p| {
            let family = Family {
                family: fam.to_string(),
            };
            let own = Own {
                gpu_bytes: p.gpu_bytes,
                bytes_per_tet: p.bytes_per_tet,
                error: p.error.clone(),
            };
            (family, PointColumns::new(p, book), own)
        })
        .collect()
}

/// One variant's exponents over the sizes of `mine` (its points, smallest mesh first).
fn fit(fam: &str, (width, height): (u32, u32), mine: &[&Point], book: &StyleBook) -> Fit {
    let tps: Vec<(f64, f64)> = mine
        .iter()
        .filter_map(|p| Some((p.tets as f64, p.tets_per_sec?.mean)))
        .collect();
    let gb: Vec<(f64, f64)> = mine
        .iter()
        .filter_map(|p| Some((p.tets as f64, p.gpu_bytes? as f64)))
        .collect();
    let (a, s) = (&mine[0].algorithm, &mine[0].settings);
    Fit {
        family: fam.to_string(),
        width,
        height,
        label: book.get(a, s).label,
        algorithm: a.clone(),
        settings: s.clone(),
        sizes_measured: tps.len(),
        sizes_failed: mine.iter().filter(|p| p.tets_per_sec.is_none()).count(),
        tets_per_sec_exponent: power_law_exponent(&tps),
        gpu_bytes_exponent: power_law_exponent(&gb),
        gpu_bytes_per_tet_marginal: linear_slope(&gb),
    }
}

/// A variant's throughput line and its GPU bytes line, each labelled with its exponent and
/// the sizes it failed at.
fn variant_lines(mine: &[&Point], fit: &Fit) -> (Line, Line) {
    let failed_sizes: Vec<String> = mine
        .iter()
        .filter(|p| p.tets_per_sec.is_none())
        .map(|p| draw::si(p.tets as f64))
        .collect();
    let failed_note = if failed_sizes.is_empty() {
        String::new()
    } else {
        format!(", failed at {}", failed_sizes.join(", "))
    };
    let line = |y: fn(&Point) -> Option<Spread>, exponent: Option<f64>| Line {
        algorithm: fit.algorithm.clone(),
        settings: fit.settings.clone(),
        points: mine
            .iter()
            .map(|p| LinePoint {
                x: p.tets as f64,
                y: y(p),
            })
            .collect(),
        extra: exponent_text(exponent) + &failed_note,
    };
    (
        line(|p| p.tets_per_sec, fit.tets_per_sec_exponent),
        line(
            |p| p.gpu_bytes.map(|b| Spread::single(b as f64)),
            fit.gpu_bytes_exponent,
        ),
    )
}

/// The lines of text above a family's legend: its viewport, a run without reference, and the
/// family's data sets that did not load.
fn notes(fam: &str, (width, height): (u32, u32), inputs: &Inputs) -> Vec<String> {
    let mut notes = vec![format!("viewport {width}×{height}")];
    if inputs.without_reference {
        notes.push("timing only (--no-reference):".into());
        notes.push("image error not checked".into());
    }
    for (d, _) in inputs
        .missing_datasets
        .iter()
        .filter(|(d, _)| family(d) == fam)
    {
        notes.push(format!("{d}: not loaded, no rows"));
    }
    notes
}

/// The fits as a Markdown table.
pub fn fits_markdown(fits: &[Fit]) -> String {
    let mut s = String::from(
        "| family | viewport | label | algorithm | settings | sizes | failed | tets/s exponent | bytes exponent | bytes per extra tet |\n\
         |---|---|---|---|---|---:|---:|---:|---:|---:|\n",
    );
    let f = |v: Option<f64>| v.map(|v| format!("{v:+.3}")).unwrap_or_else(|| "–".into());
    for x in fits {
        s.push_str(&format!(
            "| {} | {}×{} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            x.family,
            x.width,
            x.height,
            x.label,
            x.algorithm,
            x.settings,
            x.sizes_measured,
            x.sizes_failed,
            f(x.tets_per_sec_exponent),
            f(x.gpu_bytes_exponent),
            x.gpu_bytes_per_tet_marginal
                .map(|v| format!("{v:.1}"))
                .unwrap_or_else(|| "–".into())
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponent_of_a_power_law() {
        let xy: Vec<(f64, f64)> = [1e4, 1e5, 1e6]
            .iter()
            .map(|&x: &f64| (x, 3.0 * x.powf(0.8)))
            .collect();
        assert!((power_law_exponent(&xy).unwrap() - 0.8).abs() < 1e-12);
        assert_eq!(power_law_exponent(&xy[..1]), None);
        let lin = [(1e4, 5e6 + 20.0 * 1e4), (1e6, 5e6 + 20.0 * 1e6)];
        assert!((linear_slope(&lin).unwrap() - 20.0).abs() < 1e-9);
        assert_eq!(family("box:10k"), "box");
        assert_eq!(family("spx"), "data sets");
    }
}
