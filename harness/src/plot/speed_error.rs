//! Speed vs error, the chart users look at first: per data set (and viewport), each variant a
//! point at (mean tets/s, mean PSNR) over the viewpoints, whiskers min–max both ways, the
//! Pareto front (variants nothing else beats on both speed and exactness), speed on a log axis.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

use super::data::{distinct, write_csv, Point};
use super::draw::{self, err, Chart, LegendEntry, FONT, PLOT_WIDTH};
use super::style::{Marker, Style, StyleBook};
use super::ChartFile;
use crate::results::metrics::PSNR_CAP_DB;

/// One CSV line: a variant's point on one data set's chart.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Record {
    pub dataset: String,
    pub tets: u64,
    pub width: u32,
    pub height: u32,
    pub label: String,
    pub algorithm: String,
    pub settings: String,
    pub rows: usize,
    pub failed: usize,
    pub tets_per_sec_mean: Option<f64>,
    pub tets_per_sec_min: Option<f64>,
    pub tets_per_sec_max: Option<f64>,
    pub psnr_db_mean: Option<f64>,
    pub psnr_db_min: Option<f64>,
    pub psnr_db_max: Option<f64>,
    pub pareto: bool,
    pub peer: bool,
    pub suspect: bool,
    pub error: String,
}

/// Which of `xy` (higher is better on both axes) no other point beats on both: the Pareto
/// front. Ties on both coordinates keep both.
pub fn pareto_front(xy: &[(f64, f64)]) -> Vec<bool> {
    xy.iter()
        .map(|&(x, y)| {
            !xy.iter()
                .any(|&(ox, oy)| ox >= x && oy >= y && (ox > x || oy > y))
        })
        .collect()
}

fn records(points: &[&Point], book: &StyleBook) -> Vec<Record> {
    let xy: Vec<Option<(f64, f64)>> = points
        .iter()
        .map(|p| Some((p.tets_per_sec?.mean, p.psnr_db?.mean)))
        .collect();
    let plotted: Vec<(f64, f64)> = xy.iter().flatten().copied().collect();
    let front = pareto_front(&plotted);
    let mut k = 0;
    points
        .iter()
        .zip(&xy)
        .map(|(p, xy)| {
            let on_front = xy.is_some() && {
                k += 1;
                front[k - 1]
            };
            Record {
                dataset: p.dataset.clone(),
                tets: p.tets,
                width: p.width,
                height: p.height,
                label: book.get(&p.algorithm, &p.settings).label,
                algorithm: p.algorithm.clone(),
                settings: p.settings.clone(),
                rows: p.rows,
                failed: p.failed,
                tets_per_sec_mean: p.tets_per_sec.map(|s| s.mean),
                tets_per_sec_min: p.tets_per_sec.map(|s| s.min),
                tets_per_sec_max: p.tets_per_sec.map(|s| s.max),
                psnr_db_mean: p.psnr_db.map(|s| s.mean),
                psnr_db_min: p.psnr_db.map(|s| s.min),
                psnr_db_max: p.psnr_db.map(|s| s.max),
                pareto: on_front,
                peer: p.peer(),
                suspect: p.suspect,
                error: p.error.clone(),
            }
        })
        .collect()
}

struct SpeedError<'a> {
    title: String,
    records: Vec<Record>,
    book: &'a StyleBook,
    viewpoints: usize,
    /// What the x axis measures.
    x_desc: &'a str,
    /// Every variant of every algorithm on one chart, one legend line and one style per
    /// algorithm, no whiskers: drawn when the per-variant legend is too long for one chart, so
    /// that tetbench's algorithms and the peers (VTK's, `--external` ones) still share a chart.
    overview: bool,
}

impl SpeedError<'_> {
    /// The style a record is drawn with: its own, or in the overview its algorithm's (the style
    /// of the algorithm's first variant, named after the algorithm).
    fn style(&self, r: &Record) -> Style {
        if !self.overview {
            return self.book.get(&r.algorithm, &r.settings);
        }
        let first = self
            .records
            .iter()
            .find(|o| o.algorithm == r.algorithm)
            .unwrap_or(r);
        let mut style = Style {
            label: r.algorithm.clone(),
            ..self.book.get(&first.algorithm, &first.settings)
        };
        // Peers share one grey family and their first variants may share a marker shape:
        // here each peer algorithm gets a shape of its own.
        if crate::plot::style::is_peer(&r.algorithm) {
            let peers = distinct(
                self.records
                    .iter()
                    .filter(|o| crate::plot::style::is_peer(&o.algorithm))
                    .map(|o| o.algorithm.clone()),
            );
            let i = peers.iter().position(|a| *a == r.algorithm).unwrap_or(0);
            style.marker = Marker::ALL[i % Marker::ALL.len()];
        }
        style
    }

    fn entries(&self) -> Vec<LegendEntry> {
        if self.overview {
            return distinct(self.records.iter().map(|r| r.algorithm.clone()))
                .into_iter()
                .map(|a| {
                    let of: Vec<&Record> =
                        self.records.iter().filter(|r| r.algorithm == a).collect();
                    let plotted = of
                        .iter()
                        .filter(|r| r.tets_per_sec_mean.is_some() && r.psnr_db_mean.is_some())
                        .count();
                    let mut extra = format!("{plotted} of {} variant(s) plotted", of.len());
                    if crate::plot::style::is_peer(&a) {
                        extra.push_str(" (peer)");
                    }
                    LegendEntry {
                        style: self.style(of[0]),
                        line: false,
                        extra,
                    }
                })
                .collect();
        }
        self.records
            .iter()
            .map(|r| LegendEntry {
                style: self.book.get(&r.algorithm, &r.settings),
                line: false,
                extra: if r.tets_per_sec_mean.is_none() {
                    "(failed: not plotted)".into()
                } else if r.psnr_db_mean.is_none() {
                    "(no PSNR: not plotted)".into()
                } else if r.suspect {
                    "(suspect)".into()
                } else {
                    String::new()
                },
            })
            .collect()
    }

    fn heading(&self) -> Vec<String> {
        let spread = if self.overview {
            "every variant; whiskers: per-algorithm charts"
        } else {
            "whiskers: min–max over viewpoints"
        };
        vec![
            "up and right is better".into(),
            format!("point: mean over {} viewpoint(s)", self.viewpoints),
            spread.into(),
            "dashed: Pareto front".into(),
            "red ring: suspect row(s)".into(),
            "hollow grey: outside peers".into(),
            format!("PSNR capped at {PSNR_CAP_DB:.0} dB"),
        ]
    }
}

impl Chart for SpeedError<'_> {
    fn size(&self) -> (u32, u32) {
        (
            PLOT_WIDTH + draw::legend_width(&self.heading(), &self.entries()),
            draw::height_for_legend(self.records.len(), self.heading().len(), 640),
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(err)?;
        let (plot, legend) = root.split_horizontally(PLOT_WIDTH);
        let plotted: Vec<&Record> = self
            .records
            .iter()
            .filter(|r| r.tets_per_sec_mean.is_some() && r.psnr_db_mean.is_some())
            .collect();
        let (xa, ya) = speed_psnr_axes(&plotted);
        let ((xlo, _), (ylo, yhi)) = ((xa.lo, xa.hi), (ya.lo, ya.hi));
        let mut chart = draw::Axes {
            title: &self.title,
            x: xa,
            y: ya,
            x_desc: self.x_desc,
            y_desc: "PSNR against the exact reference (dB)",
            x_fmt: draw::si,
            y_fmt: |v| format!("{v:.0}"),
            y_label_area: 64,
        }
        .draw(&plot)?;
        let at = |x: f64, y: f64| (xa.at(x), ya.at(y));
        if plotted.is_empty() {
            let (px, py) = chart.backend_coord(&at(xlo * 1.2, 0.5 * (ylo + yhi)));
            plot.draw(&Text::new(
                "no variant has both a speed and an error here (failed, or run without reference)",
                (px, py),
                (FONT, 15).into_font(),
            ))
            .map_err(err)?;
        }
        // The Pareto front as a staircase from the fastest to the most exact.
        let mut front: Vec<(f64, f64)> = plotted
            .iter()
            .filter(|r| r.pareto)
            .filter_map(|r| Some((r.tets_per_sec_mean?, r.psnr_db_mean?)))
            .collect();
        front.sort_by(|a, b| b.0.total_cmp(&a.0));
        if front.len() > 1 {
            let mut stairs = vec![at(front[0].0, front[0].1)];
            for w in front.windows(2) {
                stairs.push(at(w[1].0, w[0].1));
                stairs.push(at(w[1].0, w[1].1));
            }
            chart
                .draw_series(std::iter::once(plotters::element::DashedPathElement::new(
                    stairs,
                    6,
                    4,
                    BLACK.mix(0.55).stroke_width(2),
                )))
                .map_err(err)?;
        }
        for r in plotted.iter().filter(|_| !self.overview) {
            let st = self.style(r);
            let (x, y) = (r.tets_per_sec_mean.unwrap(), r.psnr_db_mean.unwrap());
            let line = st.color.mix(0.8).stroke_width(2);
            if let (Some(a), Some(b)) = (r.tets_per_sec_min, r.tets_per_sec_max) {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![at(a, y), at(b, y)],
                        line,
                    )))
                    .map_err(err)?;
            }
            if let (Some(a), Some(b)) = (r.psnr_db_min, r.psnr_db_max) {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![at(x, a), at(x, b)],
                        line,
                    )))
                    .map_err(err)?;
            }
        }
        for r in &plotted {
            let st = self.style(r);
            let c = chart.backend_coord(&at(r.tets_per_sec_mean.unwrap(), r.psnr_db_mean.unwrap()));
            if r.suspect {
                plot.draw(&Circle::new(c, 13, RED.stroke_width(2)))
                    .map_err(err)?;
            }
            draw::marker(&plot, c, 7, &st)?;
        }
        let entries = self.entries();
        draw::legend(&legend, &self.heading(), &entries)?;
        root.present().map_err(err)?;
        Ok(())
    }
}

/// The speed axis (log) and the PSNR axis (padded, 0 at least) over the plotted records'
/// whiskers; without records, a PSNR axis up to the cap.
fn speed_psnr_axes(plotted: &[&Record]) -> (draw::Axis, draw::Axis) {
    let xs = plotted
        .iter()
        .flat_map(|r| [r.tets_per_sec_min, r.tets_per_sec_max])
        .flatten();
    let (xlo, xhi) = xs.fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    let (xlo, xhi) = draw::log_range(xlo, xhi);
    let ys = plotted
        .iter()
        .flat_map(|r| [r.psnr_db_min, r.psnr_db_max])
        .flatten();
    let (ylo, yhi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
        (a.min(y), b.max(y))
    });
    let (ylo, yhi) = if ylo.is_finite() {
        let pad = ((yhi - ylo) * 0.08).max(2.0);
        ((ylo - pad).max(0.0), yhi + pad)
    } else {
        (0.0, PSNR_CAP_DB + 1.0)
    };
    let xa = draw::Axis {
        log: true,
        lo: xlo,
        hi: xhi,
    };
    let ya = draw::Axis {
        log: false,
        lo: ylo,
        hi: yhi,
    };
    (xa, ya)
}

/// Orders a chart's points by algorithm, then style slot (the legend's order, the same in
/// every chart).
pub fn sort_by_style(points: &mut [&Point], book: &StyleBook) {
    points.sort_by_key(|p| super::style::order_key(book, &p.algorithm, &p.settings));
}

/// What the x axis of a set of speed–error charts measures, and how the charts are named.
#[derive(Debug, Clone)]
pub struct SpeedAxis {
    /// The axis title.
    pub desc: String,
    /// The start of every chart's file stem.
    pub stem: String,
    /// The start of every chart's title.
    pub title: String,
}

impl Default for SpeedAxis {
    /// tets per second, as a run's report draws it.
    fn default() -> Self {
        SpeedAxis {
            desc: "tets per second (log scale)".into(),
            stem: "speed_error".into(),
            title: "Speed vs error".into(),
        }
    }
}

/// Draws one chart per data set × viewport (split per algorithm when the legend would not
/// fit) into `dir`, each with its CSV.
pub fn write(dir: &Path, points: &[Point], book: &StyleBook) -> anyhow::Result<Vec<ChartFile>> {
    write_with(dir, points, book, &SpeedAxis::default())
}

/// [`write`] with another x axis: the points' `tets_per_sec` holds what `axis` names (`tetbench
/// publish` draws calibration-normalised speeds across adapters this way).
pub fn write_with(
    dir: &Path,
    points: &[Point],
    book: &StyleBook,
    axis: &SpeedAxis,
) -> anyhow::Result<Vec<ChartFile>> {
    let mut files = vec![];
    let groups = distinct(
        points
            .iter()
            .map(|p| (p.dataset.clone(), p.width, p.height)),
    );
    let many_sizes = distinct(points.iter().map(|p| (p.width, p.height))).len() > 1;
    for (dataset, width, height) in groups {
        let mut pts: Vec<&Point> = points
            .iter()
            .filter(|p| p.dataset == dataset && p.width == width && p.height == height)
            .collect();
        sort_by_style(&mut pts, book);
        let parts = draw::legend_parts(pts.clone(), |p| &p.algorithm);
        let mut stem_base = format!("{}_{}", axis.stem, crate::results::names::slug(&dataset));
        if many_sizes {
            stem_base.push_str(&format!("_{width}x{height}"));
        }
        let tets = pts.first().map(|p| p.tets).unwrap_or(0);
        if parts.len() > 1 {
            // Too many variants for one legend: one chart of them all first, a legend line per
            // algorithm, so every algorithm and peer is compared on one chart.
            let stem = format!("{stem_base}_overview");
            let title = format!(
                "{} — {dataset} ({} tets, {width}×{height}), every algorithm",
                axis.title,
                draw::si(tets as f64)
            );
            let chart = SpeedError {
                title: title.clone(),
                records: records(&pts, book),
                book,
                viewpoints: pts.iter().map(|p| p.rows).max().unwrap_or(0),
                x_desc: &axis.desc,
                overview: true,
            };
            draw::save(&chart, dir, &stem)?;
            write_csv(dir, &stem, &chart.records)?;
            files.push(ChartFile {
                kind: super::Kind::SpeedError,
                title,
                stem,
                note: "every variant, one legend line per algorithm; the charts below split it \
                       per algorithm"
                    .into(),
            });
        }
        for (alg, part) in parts {
            let records = records(&part, book);
            let viewpoints = part.iter().map(|p| p.rows).max().unwrap_or(0);
            let mut stem = stem_base.clone();
            if !alg.is_empty() {
                stem.push_str(&format!("_{}", crate::results::names::slug(&alg)));
            }
            let title = format!(
                "{} — {dataset}{} ({} tets, {width}×{height})",
                axis.title,
                if alg.is_empty() {
                    String::new()
                } else {
                    format!(", {alg}")
                },
                draw::si(tets as f64)
            );
            let chart = SpeedError {
                title: title.clone(),
                records: records.clone(),
                book,
                viewpoints,
                x_desc: &axis.desc,
                overview: false,
            };
            draw::save(&chart, dir, &stem)?;
            write_csv(dir, &stem, &records)?;
            files.push(ChartFile {
                kind: super::Kind::SpeedError,
                title,
                stem,
                note: String::new(),
            });
        }
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_the_undominated() {
        let f = pareto_front(&[
            (1.0, 50.0),
            (2.0, 40.0),
            (0.5, 45.0),
            (2.0, 40.0),
            (3.0, 10.0),
        ]);
        assert_eq!(f, [true, true, false, true, true]);
    }

    fn point(algorithm: &str, settings: &str, speed: f64, psnr: f64) -> Point {
        let spread = crate::results::stats::Spread::single;
        Point {
            algorithm: algorithm.into(),
            settings: settings.into(),
            dataset: "spx".into(),
            tets: 12936,
            width: 64,
            height: 64,
            rows: 2,
            failed: 0,
            error: String::new(),
            tets_per_sec: Some(spread(speed)),
            psnr_db: Some(spread(psnr)),
            gpu_bytes: None,
            bytes_per_tet: None,
            suspect: false,
        }
    }

    /// More variants than one legend holds: the chart is split per algorithm, and an overview
    /// first puts every variant of every algorithm, peers included, on one chart with a legend
    /// line per algorithm; with few variants there is one chart and no overview.
    #[test]
    fn many_variants_get_an_overview_with_every_algorithm() {
        crate::algorithms::note_external("overview-test-mine");
        let mut points: Vec<Point> = (0..12)
            .map(|k| point("havs", &format!("k={k}"), 1e6 + k as f64, 40.0))
            .collect();
        points.extend((0..8).map(|k| point("raycast", &format!("step={k}"), 2e5, 60.0 + k as f64)));
        points.push(point("vtk-zsweep", "integrator=linear", 5e4, 50.0));
        points.push(point("overview-test-mine", "peer=external", 3e4, 99.0));
        let book = crate::plot::book_of(&points);
        let dir = tempfile::tempdir().unwrap();
        let files = write(dir.path(), &points, &book).unwrap();
        let stems: Vec<&str> = files.iter().map(|f| f.stem.as_str()).collect();
        assert_eq!(stems[0], "speed_error_spx_overview", "{stems:?}");
        assert!(stems.contains(&"speed_error_spx_havs"), "{stems:?}");
        assert!(
            stems.contains(&"speed_error_spx_overview-test-mine"),
            "{stems:?}"
        );
        let recs: Vec<Record> =
            csv::Reader::from_path(dir.path().join("speed_error_spx_overview.csv"))
                .unwrap()
                .deserialize()
                .map(Result::unwrap)
                .collect();
        assert_eq!(recs.len(), points.len());
        let peers: Vec<&str> = recs
            .iter()
            .filter(|r| r.peer)
            .map(|r| r.algorithm.as_str())
            .collect();
        assert_eq!(peers, ["vtk-zsweep", "overview-test-mine"]);
        // The external renderer is the most exact; the fastest HAVS variant the fastest.
        assert!(
            recs.iter()
                .find(|r| r.algorithm == "overview-test-mine")
                .unwrap()
                .pareto
        );
        let chart = SpeedError {
            title: String::new(),
            records: recs,
            book: &book,
            viewpoints: 2,
            x_desc: "",
            overview: true,
        };
        let legend: Vec<String> = chart.entries().iter().map(|e| e.text()).collect();
        assert_eq!(legend.len(), 4, "{legend:?}");
        assert!(legend[0].starts_with("havs  12 of 12"), "{legend:?}");
        assert!(legend[3].ends_with("(peer)"), "{legend:?}");
        let peer_markers: Vec<Marker> = chart.entries()[2..]
            .iter()
            .map(|e| e.style.marker)
            .collect();
        assert_ne!(peer_markers[0], peer_markers[1]);

        let few: Vec<Point> = points[10..].to_vec();
        let one = write(dir.path(), &few, &crate::plot::book_of(&few)).unwrap();
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].stem, "speed_error_spx");
    }
}
