//! What the charts are drawn from: rows read from any number of results (one run, shards,
//! several runs), as points — [`crate::results::aggregate`]'s groups, one per algorithm ×
//! settings × data set × viewport, over its viewpoints — and the flags the charts show (peers, suspect rows).

use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::Serialize;

use crate::results::aggregate::{aggregate, Aggregate};
use crate::results::stats::Spread;
use crate::results::{read_text, write_file, ResultsFile, Row, JSON_FILE};

/// Rows of every input, with what the charts need from the runs' headers.
#[derive(Debug, Clone, Default)]
pub struct Inputs {
    pub rows: Vec<Row>,
    /// The runs' adapters, distinct, in input order (`name (backend)`).
    pub adapters: Vec<String>,
    /// Whether any run skipped the reference (`--no-reference`).
    pub without_reference: bool,
    /// Data sets a run asked for that have no row (not loaded), with the run's error message.
    pub missing_datasets: Vec<(String, String)>,
    /// Calibrated bounds of the backends (see [`calibrated_bounds`]).
    pub bounds: Vec<Bound>,
    /// The files read.
    pub sources: Vec<PathBuf>,
}

/// A backend limit measured by `tetbench calibrate`, drawn as a horizontal line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Bound {
    pub adapter: String,
    pub name: String,
    /// In the unit of the chart it is drawn on (tets/s).
    pub per_sec: f64,
}

/// Finds the `results.json` files an argument stands for: the file itself, a directory holding
/// one, or a directory whose sub-directories hold them (a sweep, shards).
pub fn result_files(arg: &Path) -> anyhow::Result<Vec<PathBuf>> {
    if arg.is_file() {
        return Ok(vec![arg.to_path_buf()]);
    }
    if arg.join(JSON_FILE).is_file() {
        return Ok(vec![arg.join(JSON_FILE)]);
    }
    if !arg.is_dir() {
        anyhow::bail!("{}: no such file or directory", arg.display());
    }
    let mut found: Vec<PathBuf> = std::fs::read_dir(arg)
        .with_context(|| format!("cannot read {}", arg.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.path().join(JSON_FILE))
        .filter(|p| p.is_file())
        .collect();
    found.sort();
    if found.is_empty() {
        anyhow::bail!(
            "{}: holds no {JSON_FILE}, nor do its sub-directories",
            arg.display()
        );
    }
    Ok(found)
}

impl Inputs {
    /// Reads every results file the arguments stand for.
    pub fn read(args: &[PathBuf]) -> anyhow::Result<Inputs> {
        if args.is_empty() {
            anyhow::bail!("no results given (directories or results.json files)");
        }
        let mut inputs = Inputs::default();
        for arg in args {
            for path in result_files(arg)? {
                let dir = path.parent().unwrap_or(Path::new("."));
                let file = ResultsFile::read(dir)?;
                let text = read_text(&path)?;
                let raw: serde_json::Value = serde_json::from_str(&text)
                    .with_context(|| format!("{} is not JSON", path.display()))?;
                inputs.add(&file, Some(&raw));
                inputs.sources.push(path);
            }
        }
        Ok(inputs)
    }

    /// Adds one run (its raw JSON, when at hand, for fields this version does not know).
    pub fn add(&mut self, file: &ResultsFile, raw: Option<&serde_json::Value>) {
        // Rows of external renderers (`peer=external`) are peers in every chart and table.
        crate::algorithms::note_external_rows(
            file.rows
                .iter()
                .map(|r| (r.algorithm.as_str(), &r.settings)),
        );
        let adapter = file
            .machine
            .adapter
            .as_ref()
            .map(|a| format!("{} ({})", a.name, a.backend))
            .unwrap_or_else(|| "unknown adapter".into());
        if !self.adapters.contains(&adapter) {
            self.adapters.push(adapter.clone());
        }
        if !file.run.reference && !file.rows.is_empty() {
            self.without_reference = true;
        }
        for d in &file.run.datasets {
            let label = crate::results::names::dataset_label(d);
            if !file.rows.iter().any(|r| r.dataset == label) {
                let why = file
                    .errors
                    .iter()
                    .find(|e| e.contains(&format!("{d:?}")))
                    .cloned()
                    .unwrap_or_else(|| "no rows".into());
                self.missing_datasets.push((label, why));
            }
        }
        if let Some(raw) = raw {
            for b in calibrated_bounds(raw, &adapter) {
                if !self.bounds.contains(&b) {
                    self.bounds.push(b);
                }
            }
        }
        self.rows.extend(file.rows.iter().cloned());
    }
}

/// Rates in the run's machine record (`machine.calibration`, written by `tetbench calibrate`)
/// that bound tets/s: any numeric field whose name ends in `tets_per_sec`, else the backend's
/// small-triangle rate (`…triangles_per_sec`), which bounds every algorithm that rasterises at
/// least one triangle per tet. Runs without a calibration have none.
pub fn calibrated_bounds(raw: &serde_json::Value, adapter: &str) -> Vec<Bound> {
    let Some(cal) = raw.get("machine").and_then(|m| m.get("calibration")) else {
        return vec![];
    };
    let mut flat: Vec<(String, f64)> = vec![];
    fn walk(prefix: &str, v: &serde_json::Value, out: &mut Vec<(String, f64)>) {
        match v {
            serde_json::Value::Object(m) => {
                for (k, v) in m {
                    let key = if prefix.is_empty() {
                        k.clone()
                    } else {
                        format!("{prefix}.{k}")
                    };
                    walk(&key, v, out);
                }
            }
            serde_json::Value::Number(n) => {
                if let Some(x) = n.as_f64().filter(|x| x.is_finite() && *x > 0.0) {
                    out.push((prefix.to_string(), x));
                }
            }
            _ => {}
        }
    }
    walk("", cal, &mut flat);
    let pick = |suffix: &str| -> Vec<Bound> {
        flat.iter()
            .filter(|(k, _)| k.ends_with(suffix))
            .map(|(k, v)| Bound {
                adapter: adapter.to_string(),
                name: k.clone(),
                per_sec: *v,
            })
            .collect()
    };
    let tets = pick("tets_per_sec");
    if !tets.is_empty() {
        return tets;
    }
    pick("triangles_per_sec")
}

/// One algorithm × settings × data set × viewport, over its viewpoints.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    pub tets: u64,
    pub width: u32,
    pub height: u32,
    pub rows: usize,
    pub failed: usize,
    /// The first failed row's error (what a chart says instead of a value).
    pub error: String,
    pub tets_per_sec: Option<Spread>,
    pub psnr_db: Option<Spread>,
    /// Largest GPU bytes over the viewpoints.
    pub gpu_bytes: Option<u64>,
    pub bytes_per_tet: Option<f64>,
    /// Any of its rows is suspect (see [`crate::results::suspect::flags`]).
    pub suspect: bool,
}

impl Point {
    pub fn peer(&self) -> bool {
        super::style::is_peer(&self.algorithm)
    }
}

impl From<&Aggregate> for Point {
    fn from(a: &Aggregate) -> Point {
        Point {
            algorithm: a.algorithm.clone(),
            settings: a.settings.to_string(),
            dataset: a.dataset.clone(),
            tets: a.tets,
            width: a.width,
            height: a.height,
            rows: a.rows,
            failed: a.failed,
            error: a.error.clone(),
            tets_per_sec: a.tets_per_sec,
            psnr_db: a.psnr_db,
            gpu_bytes: a.gpu_bytes,
            bytes_per_tet: a.bytes_per_tet,
            suspect: a.suspect > 0,
        }
    }
}

/// The CSV columns a per-variant chart's line opens with: the variant, its data set and
/// viewport, its rows and its throughput. A chart writes its line as the tuple
/// `(PointColumns, Own)`, `Own` its own columns (the csv crate writes a tuple of structs as
/// one flat line under one header).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointColumns {
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
}

impl PointColumns {
    pub fn new(p: &Point, book: &super::style::StyleBook) -> PointColumns {
        PointColumns {
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
        }
    }
}

/// The points of [`crate::results::aggregate`] (one per variant × data set × viewport), in
/// order of first appearance (charts order their series by style, not by this order).
pub fn points(rows: &[Row]) -> Vec<Point> {
    aggregate(rows).iter().map(Point::from).collect()
}

/// Distinct values in order of first appearance.
pub fn distinct<T: PartialEq + Clone>(items: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut v: Vec<T> = vec![];
    for x in items {
        if !v.contains(&x) {
            v.push(x);
        }
    }
    v
}

/// The CSV text of `records` (header from the struct's fields).
pub fn csv_text<T: Serialize>(records: &[T]) -> anyhow::Result<String> {
    let mut w = csv::Writer::from_writer(vec![]);
    for r in records {
        w.serialize(r)?;
    }
    Ok(String::from_utf8(
        w.into_inner().map_err(|e| anyhow::anyhow!("{e}"))?,
    )?)
}

/// Writes `records` as `dir/stem.csv`.
pub fn write_csv<T: Serialize>(dir: &Path, stem: &str, records: &[T]) -> anyhow::Result<()> {
    let path = dir.join(format!("{stem}.csv"));
    write_file(&path, csv_text(records)?)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::results::test_row;

    /// Rows of two variants × two data sets × two viewpoints, with one failure.
    pub fn rows() -> Vec<Row> {
        let mut rows = vec![];
        for (a, s) in [
            ("havs", "k=2;sort=cpu-radix"),
            ("gator-pt", "variant=linear"),
        ] {
            for (d, tets) in [("box:10k", 10_000u64), ("box:100k", 100_000)] {
                for v in 0..2u32 {
                    let mut r = test_row(v);
                    r.algorithm = a.into();
                    r.settings = s.parse().unwrap();
                    r.dataset = d.into();
                    r.tets = tets;
                    let f = if a == "havs" { 1.0 } else { 2.0 };
                    r.tets_per_sec = Some(f * tets as f64 * (1.0 + v as f64));
                    r.psnr_db = Some(if a == "havs" { 15.0 + v as f64 } else { 50.0 });
                    r.gpu_bytes = Some(100 * tets);
                    rows.push(r);
                }
            }
        }
        let mut failed = test_row(2);
        failed.algorithm = "havs".into();
        failed.settings = "k=2;sort=cpu-radix".parse().unwrap();
        failed.dataset = "box:100k".into();
        failed.tets = 100_000;
        failed.tets_per_sec = None;
        failed.error = Some(crate::results::Failure::new(
            crate::results::Stage::Render,
            "out of memory",
        ));
        rows.push(failed);
        rows
    }

    #[test]
    fn points_group_by_variant_data_set_and_viewport() {
        let p = points(&rows());
        assert_eq!(p.len(), 4);
        let h = &p[1];
        assert_eq!(
            (h.algorithm.as_str(), h.dataset.as_str()),
            ("havs", "box:100k")
        );
        assert_eq!((h.rows, h.failed), (3, 1));
        assert_eq!(h.error, "out of memory");
        let t = h.tets_per_sec.unwrap();
        assert_eq!((t.mean, t.min, t.max), (150_000.0, 100_000.0, 200_000.0));
        // HAVS's 15–16 dB is below 20 dB: suspect; GATOR's 50 dB is not.
        assert!(h.suspect);
        assert!(!p[3].suspect);
    }

    #[test]
    fn calibration_bounds_are_read_when_present() {
        let raw: serde_json::Value = serde_json::json!({
            "machine": {"calibration": {"raster": {"triangles_per_sec": 2.0e8}, "copy_bytes_per_sec": 1e10}}
        });
        let b = calibrated_bounds(&raw, "llvmpipe");
        assert_eq!(b.len(), 1);
        assert_eq!(b[0].name, "raster.triangles_per_sec");
        assert!(calibrated_bounds(&serde_json::json!({"machine": {}}), "x").is_empty());
    }
}
