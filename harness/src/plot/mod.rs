//! Comparison charts that answer the questions users bring: speed vs error per
//! data set, scaling with mesh size, throughput vs viewport size, and bar charts per metric.
//!
//! Every chart is written as PNG and SVG with its data as CSV beside it (`STEM.{png,svg,csv}`),
//! and every variant keeps one style (colour family per algorithm, shade + marker per variant,
//! see [`style`]) across all charts; `key.csv` maps the short legend labels to full settings.
//! `tetbench plot KIND RESULTS… --out DIR` draws them from any results (one run, shards,
//! several runs, a sweep); the HTML report of a run embeds them, speed vs error first.

use std::path::Path;

use crate::results::write_file;
use anyhow::Context;
use serde::Serialize;

pub mod bars;

pub mod data;
pub mod draw;
pub mod fig8;
pub mod history;
pub mod lines;
pub mod paper_bars;
pub mod ratio;
pub mod resolution;
pub mod scaling;
pub mod speed_error;
pub mod style;
pub mod tile_map;

use data::{Inputs, Point};
use style::StyleBook;

/// The kinds of chart `tetbench plot` draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// Per data set: tets/s (log) against PSNR, whiskers over viewpoints, Pareto front.
    SpeedError,
    /// tets/s and GPU bytes against mesh size (log–log), fitted exponent per variant.
    Scaling,
    /// tets/s against viewport size (the fragment PT paper's Fig. 8, every algorithm).
    Resolution,
    /// Bars of tets/s and PSNR per variant and data set.
    Bars,
    /// All of the above that the results allow.
    All,
}

impl Kind {
    fn includes(self, k: Kind) -> bool {
        self == Kind::All || self == k
    }

    pub fn heading(self) -> &'static str {
        match self {
            Kind::SpeedError => "Speed vs error",
            Kind::Scaling => "Scaling with mesh size",
            Kind::Resolution => "Throughput vs viewport size",
            Kind::Bars => "Per-metric bars",
            Kind::All => "Charts",
        }
    }
}

/// One chart written: `stem.png`, `stem.svg`, `stem.csv` in the chart directory.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartFile {
    pub kind: Kind,
    pub title: String,
    pub stem: String,
    pub note: String,
}

/// Everything one call drew.
#[derive(Debug, Default)]
pub struct Charts {
    pub files: Vec<ChartFile>,
    pub book: StyleBook,
    pub fits: Vec<scaling::Fit>,
    /// Why a kind that was asked for drew nothing.
    pub skipped: Vec<(Kind, String)>,
}

/// The style book of every variant in `rows`.
pub fn book_of(points: &[Point]) -> StyleBook {
    StyleBook::new(
        points
            .iter()
            .map(|p| (p.algorithm.as_str(), p.settings.as_str())),
    )
}

/// Draws the charts of `kind` from `inputs` into `dir` (with `key.csv`).
pub fn write_charts(dir: &Path, inputs: &Inputs, kind: Kind) -> anyhow::Result<Charts> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let points = data::points(&inputs.rows);
    let book = book_of(&points);
    let mut charts = Charts::default();
    if kind.includes(Kind::SpeedError) {
        if points.iter().any(|p| p.psnr_db.is_some()) {
            charts
                .files
                .extend(speed_error::write(dir, &points, &book)?);
        } else {
            charts.skipped.push((
                Kind::SpeedError,
                "no row has an image error (run without --no-reference)".into(),
            ));
        }
    }
    if kind.includes(Kind::Scaling) {
        let s = scaling::write(dir, &points, inputs, &book)?;
        if s.files.is_empty() {
            let sizes = data::distinct(points.iter().map(|p| p.dataset.clone()));
            charts.skipped.push((
                Kind::Scaling,
                format!(
                    "needs at least two mesh sizes of one family (have: {}); e.g. \
                     `tetbench plot scaling --sweep box:10k,100k,1m --no-reference --out DIR`",
                    sizes.join(", ")
                ),
            ));
        }
        charts.files.extend(s.files);
        charts.fits = s.fits;
    }
    if kind.includes(Kind::Resolution) {
        let r = resolution::write(dir, &points, inputs, &book)?;
        if r.is_empty() {
            let sizes = data::distinct(points.iter().map(|p| format!("{}×{}", p.width, p.height)));
            charts.skipped.push((
                Kind::Resolution,
                format!(
                    "needs at least two viewport sizes of one data set (have: {}); e.g. \
                     `tetbench plot resolution --sweep 128,256,512 --datasets box:100k --out DIR`",
                    sizes.join(", ")
                ),
            ));
        }
        charts.files.extend(r);
    }
    if kind.includes(Kind::Bars) {
        charts.files.extend(bars::write(dir, &points, &book)?);
    }
    let key = dir.join("key.csv");
    write_file(&key, book.key_csv())?;
    charts.book = book;
    Ok(charts)
}

/// The charts and their key as the data of `templates/charts.html` (the run report and the
/// reproduced papers' pages include it); image paths are relative to `prefix`.
#[derive(Debug, Serialize)]
pub struct ChartsPage {
    pub prefix: String,
    pub kinds: Vec<ChartsOfKind>,
    pub key: Vec<style::KeyEntry>,
}

#[derive(Debug, Serialize)]
pub struct ChartsOfKind {
    pub heading: &'static str,
    pub files: Vec<ChartLink>,
    /// Why a kind that was asked for drew nothing (empty when it drew).
    pub skipped: String,
}

#[derive(Debug, Serialize)]
pub struct ChartLink {
    pub stem: String,
    pub title: String,
}

impl ChartsPage {
    pub fn new(charts: &Charts, prefix: &str) -> ChartsPage {
        let kinds = [
            Kind::SpeedError,
            Kind::Scaling,
            Kind::Resolution,
            Kind::Bars,
        ]
        .into_iter()
        .filter_map(|kind| {
            let files: Vec<ChartLink> = charts
                .files
                .iter()
                .filter(|f| f.kind == kind)
                .map(|f| ChartLink {
                    stem: f.stem.clone(),
                    title: f.title.clone(),
                })
                .collect();
            let skipped = charts.skipped.iter().find(|(k, _)| *k == kind);
            if files.is_empty() && skipped.is_none() {
                return None;
            }
            Some(ChartsOfKind {
                heading: kind.heading(),
                files,
                skipped: skipped.map(|(_, why)| why.clone()).unwrap_or_default(),
            })
        })
        .collect();
        ChartsPage {
            prefix: prefix.to_string(),
            kinds,
            key: charts.book.key_entries(),
        }
    }
}

/// Reads `dir/results.json` as raw JSON, for fields this version does not model (a
/// calibration written by a newer tetbench).
pub fn raw_results(dir: &Path) -> Option<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join(crate::results::JSON_FILE)).ok()?;
    serde_json::from_str(&text).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::Row;

    fn inputs(rows: Vec<Row>) -> Inputs {
        Inputs {
            rows,
            ..Default::default()
        }
    }

    /// The columns of a line chart's CSV line (scaling, resolution) that these tests check.
    #[derive(Debug, serde::Deserialize)]
    struct LineRecord {
        dataset: String,
        width: u32,
        label: String,
        algorithm: String,
        settings: String,
        rows: usize,
        failed: usize,
        tets_per_sec_mean: Option<f64>,
        error: String,
    }

    fn read_csv<T: serde::de::DeserializeOwned>(path: &Path) -> Vec<T> {
        csv::Reader::from_path(path)
            .unwrap()
            .deserialize()
            .collect::<Result<_, _>>()
            .unwrap()
    }

    /// Mean, min and max of `f` over the rows of one variant × data set, computed here
    /// directly from the rows (not through `data::points`).
    fn direct(
        rows: &[Row],
        alg: &str,
        settings: &str,
        dataset: &str,
        f: fn(&Row) -> Option<f64>,
    ) -> Option<(f64, f64, f64)> {
        let v: Vec<f64> = rows
            .iter()
            .filter(|r| {
                r.algorithm == alg && r.settings.to_string() == settings && r.dataset == dataset
            })
            .filter_map(f)
            .collect();
        if v.is_empty() {
            return None;
        }
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let min = v.iter().copied().fold(f64::INFINITY, f64::min);
        let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Some((mean, min, max))
    }

    fn close(a: Option<f64>, b: Option<f64>) -> bool {
        match (a, b) {
            (Some(a), Some(b)) => (a - b).abs() <= 1e-9 * a.abs().max(1.0),
            (None, None) => true,
            _ => false,
        }
    }

    /// Every chart's CSV holds exactly the aggregates of the rows it was drawn from, and a
    /// variant has the same label (so the same style) in every chart and in the key.
    #[test]
    fn chart_csvs_equal_the_aggregates_of_the_rows() {
        let rows = data::tests::rows();
        let dir = tempfile::tempdir().unwrap();
        let charts = write_charts(dir.path(), &inputs(rows.clone()), Kind::All).unwrap();
        let stems: Vec<&str> = charts.files.iter().map(|f| f.stem.as_str()).collect();
        for s in [
            "speed_error_box_10k",
            "speed_error_box_100k",
            "scaling_box_tets_per_sec",
            "scaling_box_gpu_bytes",
            "tets_per_sec",
            "psnr",
        ] {
            assert!(stems.contains(&s), "{s} missing from {stems:?}");
            for ext in ["png", "svg", "csv"] {
                let p = dir.path().join(format!("{s}.{ext}"));
                assert!(p.metadata().unwrap().len() > 100, "{}", p.display());
            }
        }
        // Only one viewport size: no resolution chart, and the report says why.
        assert!(charts.skipped.iter().any(|(k, _)| *k == Kind::Resolution));

        let key: Vec<(String, String, String)> =
            read_csv::<(String, String, String, String, String, String)>(
                &dir.path().join("key.csv"),
            )
            .into_iter()
            .map(|k| (k.0, k.1, k.2))
            .collect();
        let label_of = |a: &str, s: &str| {
            key.iter()
                .find(|k| k.1 == a && k.2 == s)
                .map(|k| k.0.clone())
                .unwrap()
        };

        let mut n = 0;
        for d in ["box:10k", "box:100k"] {
            let recs: Vec<speed_error::Record> = read_csv(&dir.path().join(format!(
                "speed_error_{}.csv",
                crate::results::names::slug(d)
            )));
            for r in &recs {
                let t = direct(&rows, &r.algorithm, &r.settings, d, |r| r.tets_per_sec);
                let p = direct(&rows, &r.algorithm, &r.settings, d, |r| r.psnr_db);
                assert!(close(r.tets_per_sec_mean, t.map(|t| t.0)), "{r:?}");
                assert!(close(r.tets_per_sec_min, t.map(|t| t.1)), "{r:?}");
                assert!(close(r.tets_per_sec_max, t.map(|t| t.2)), "{r:?}");
                assert!(close(r.psnr_db_mean, p.map(|t| t.0)), "{r:?}");
                assert!(close(r.psnr_db_min, p.map(|t| t.1)), "{r:?}");
                assert!(close(r.psnr_db_max, p.map(|t| t.2)), "{r:?}");
                let count = rows
                    .iter()
                    .filter(|x| {
                        x.algorithm == r.algorithm
                            && x.settings.to_string() == r.settings
                            && x.dataset == d
                    })
                    .count();
                assert_eq!(r.rows, count);
                assert_eq!(r.label, label_of(&r.algorithm, &r.settings));
                n += 1;
            }
            // GATOR is faster and more exact than HAVS in these rows: alone on the front.
            assert!(recs.iter().all(|r| r.pareto == (r.algorithm == "gator-pt")));
        }
        assert_eq!(n, 4);

        let bars: Vec<bars::Record> = read_csv(&dir.path().join("tets_per_sec.csv"));
        assert_eq!(bars.len(), 4);
        for b in &bars {
            let t = direct(&rows, &b.algorithm, &b.settings, &b.group, |r| {
                r.tets_per_sec
            });
            assert!(
                close(b.mean, t.map(|t| t.0)) && close(b.max, t.map(|t| t.2)),
                "{b:?}"
            );
            assert_eq!(b.label, label_of(&b.algorithm, &b.settings));
        }

        let scal: Vec<LineRecord> = read_csv(&dir.path().join("scaling_box_tets_per_sec.csv"));
        assert_eq!(scal.len(), 4);
        for s in &scal {
            let t = direct(&rows, &s.algorithm, &s.settings, &s.dataset, |r| {
                r.tets_per_sec
            });
            assert!(close(s.tets_per_sec_mean, t.map(|t| t.0)), "{s:?}");
            assert_eq!(s.label, label_of(&s.algorithm, &s.settings));
        }
        // The failed HAVS row at 100k is kept (counted), not dropped.
        let h = scal
            .iter()
            .find(|s| s.algorithm == "havs" && s.dataset == "box:100k")
            .unwrap();
        assert_eq!((h.rows, h.failed), (3, 1));
        assert_eq!(h.error, "out of memory");
        // Throughput ∝ tets in these rows (tets/s = f·tets·(1+v)): exponent exactly 1;
        // bytes = 100·tets: exponent 1.
        let fits: Vec<scaling::Fit> = read_csv(&dir.path().join("scaling_box_fit.csv"));
        assert_eq!(fits.len(), 2);
        for f in &fits {
            assert!(
                (f.tets_per_sec_exponent.unwrap() - 1.0).abs() < 1e-9,
                "{f:?}"
            );
            assert!((f.gpu_bytes_exponent.unwrap() - 1.0).abs() < 1e-9, "{f:?}");
            assert!(
                (f.gpu_bytes_per_tet_marginal.unwrap() - 100.0).abs() < 1e-6,
                "{f:?}"
            );
        }
    }

    /// Rows at two viewport sizes give a resolution chart whose CSV has one line per variant
    /// and size; a variant that failed at one size keeps that line, empty.
    #[test]
    fn resolution_chart_from_two_viewports() {
        let mut rows = data::tests::rows();
        rows.retain(|r| r.dataset == "box:10k");
        let mut big: Vec<Row> = rows.clone();
        for r in &mut big {
            r.width = 64;
            r.height = 64;
            if r.algorithm == "havs" {
                r.tets_per_sec = None;
                r.psnr_db = None;
                r.error = Some(crate::results::Failure::new(
                    crate::results::Stage::Render,
                    "device lost",
                ));
            }
        }
        rows.extend(big);
        let dir = tempfile::tempdir().unwrap();
        let charts = write_charts(dir.path(), &inputs(rows), Kind::Resolution).unwrap();
        assert_eq!(charts.files.len(), 1);
        let recs: Vec<LineRecord> = read_csv(&dir.path().join("resolution_box_10k.csv"));
        assert_eq!(recs.len(), 4);
        let failed = recs
            .iter()
            .find(|r| r.algorithm == "havs" && r.width == 64)
            .unwrap();
        assert_eq!((failed.tets_per_sec_mean, failed.failed), (None, 2));
    }
}
