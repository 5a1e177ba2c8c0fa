//! `tetbench export --format bmf|github-action-benchmark RESULTS`: a results set in the
//! formats continuous-benchmarking services read, on stdout.
//!
//! - **bmf**: Bencher Metric Format (bencher.dev, "Bencher Metric Format"): an object of
//!   benchmarks, each an object of measures with `value` and optional `lower_value` /
//!   `upper_value`. `latency` is Bencher's built-in measure, in nanoseconds: the row's median
//!   `total_ms` with its smallest and largest frame. `psnr-db` and `gpu-bytes` are custom
//!   measures (Bencher creates them on first sight).
//! - **github-action-benchmark**: the `customSmallerIsBetter` tool's input, an array of
//!   `{name, unit, value, range, extra}`: `total_ms` in ms per row, the range as ± half the
//!   frames' spread, and the adapter, commit and rounds in `extra`.
//!
//! A benchmark is named `algorithm/settings/dataset/viewpoint/WxH`, unique within a run.
//! Failed rows are left out (they have no time); the count goes to stderr.

use std::path::Path;

use serde_json::{json, Map, Value};

use crate::results::{ResultsFile, Row};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ExportFormat {
    /// Bencher Metric Format (`bencher run --adapter json`).
    Bmf,
    /// github-action-benchmark's `customSmallerIsBetter`.
    GithubActionBenchmark,
}

/// The name a row goes by in every export.
pub fn benchmark_name(r: &Row) -> String {
    format!(
        "{}/{}/{}/{}/{}x{}",
        r.algorithm, r.settings, r.dataset, r.viewpoint, r.width, r.height
    )
}

fn measured(f: &ResultsFile) -> impl Iterator<Item = (&Row, f64)> {
    f.rows
        .iter()
        .filter(|r| r.ok())
        .filter_map(|r| r.total_ms.filter(|t| t.is_finite()).map(|t| (r, t)))
}

/// Bencher Metric Format.
pub fn bmf(f: &ResultsFile) -> Value {
    let mut out = Map::new();
    for (r, ms) in measured(f) {
        let ns = |v: f64| v * 1e6;
        let mut latency = json!({ "value": ns(ms) });
        if let (Some(lo), Some(hi)) = (r.total_ms_min, r.total_ms_max) {
            latency["lower_value"] = json!(ns(lo));
            latency["upper_value"] = json!(ns(hi));
        }
        let mut measures = Map::new();
        measures.insert("latency".into(), latency);
        if let Some(p) = r.psnr_db.filter(|p| p.is_finite()) {
            measures.insert("psnr-db".into(), json!({ "value": p }));
        }
        if let Some(b) = r.gpu_bytes {
            measures.insert("gpu-bytes".into(), json!({ "value": b as f64 }));
        }
        out.insert(benchmark_name(r), Value::Object(measures));
    }
    Value::Object(out)
}

/// github-action-benchmark, `tool: customSmallerIsBetter`.
pub fn github_action_benchmark(f: &ResultsFile) -> Value {
    let commit = f.machine.git_commit.as_deref().unwrap_or("unknown commit");
    let adapter = f
        .machine
        .adapter
        .as_ref()
        .map(|a| a.name.as_str())
        .unwrap_or("unknown adapter");
    let entries: Vec<Value> = measured(f)
        .map(|(r, ms)| {
            let mut e = json!({
                "name": benchmark_name(r),
                "unit": "ms",
                "value": ms,
                "extra": format!(
                    "{adapter}; commit {commit}; {} rounds, {} frames",
                    f.run.rounds.max(1),
                    r.frames
                ),
            });
            if let (Some(lo), Some(hi)) = (r.total_ms_min, r.total_ms_max) {
                e["range"] = json!(format!("± {:.4}", (hi - lo) / 2.0));
            }
            e
        })
        .collect();
    Value::Array(entries)
}

/// `tetbench export`: the export of `dir`'s results, pretty-printed.
pub fn run_command(dir: &Path, format: ExportFormat) -> anyhow::Result<String> {
    let f = ResultsFile::read(dir)?;
    let skipped = f.rows.len() - measured(&f).count();
    if skipped > 0 {
        eprintln!("tetbench export: {skipped} failed or untimed row(s) left out");
    }
    let v = match format {
        ExportFormat::Bmf => bmf(&f),
        ExportFormat::GithubActionBenchmark => github_action_benchmark(&f),
    };
    Ok(serde_json::to_string_pretty(&v)? + "\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file() -> ResultsFile {
        let row = |vp: &str, ms: Option<f64>, error: &str| Row {
            algorithm: "havs".into(),
            settings: "k=2".parse().unwrap(),
            dataset: "box:1k".into(),
            viewpoint: vp.into(),
            width: 16,
            height: 16,
            total_ms: ms,
            total_ms_min: ms.map(|m| m - 1.0),
            total_ms_max: ms.map(|m| m + 1.0),
            psnr_db: Some(50.0),
            gpu_bytes: Some(4096),
            frames: 3,
            error: (!error.is_empty())
                .then(|| crate::results::Failure::new(crate::results::Stage::Render, error)),
            ..Default::default()
        };
        ResultsFile {
            control: None,
            schema_version: crate::results::SCHEMA_VERSION,
            machine: crate::results::machine::MachineInfo::collect(),
            run: crate::results::RunDescription {
                rounds: 3,
                ..Default::default()
            },
            finished_utc: None,
            rows: vec![
                row("+x", Some(2.0), ""),
                row("-x", Some(4.0), ""),
                row("+y", None, "prepare failed"),
            ],
            errors: vec![],
        }
    }

    /// BMF: one benchmark per measured row, latency in ns with the frame range; a failed row
    /// is left out.
    #[test]
    fn bmf_has_latency_in_nanoseconds() {
        let v = bmf(&file());
        let o = v.as_object().unwrap();
        assert_eq!(o.len(), 2);
        let b = &o["havs/k=2/box:1k/-x/16x16"];
        assert_eq!(b["latency"]["value"], 4.0e6);
        assert_eq!(b["latency"]["lower_value"], 3.0e6);
        assert_eq!(b["latency"]["upper_value"], 5.0e6);
        assert_eq!(b["psnr-db"]["value"], 50.0);
        assert_eq!(b["gpu-bytes"]["value"], 4096.0);
    }

    /// customSmallerIsBetter: an array of name/unit/value with range and extra.
    #[test]
    fn github_action_benchmark_is_an_array_of_ms() {
        let v = github_action_benchmark(&file());
        let a = v.as_array().unwrap();
        assert_eq!(a.len(), 2);
        assert_eq!(a[0]["name"], "havs/k=2/box:1k/+x/16x16");
        assert_eq!(a[0]["unit"], "ms");
        assert_eq!(a[0]["value"], 2.0);
        assert_eq!(a[0]["range"], "± 1.0000");
        assert!(a[0]["extra"].as_str().unwrap().contains("3 rounds"));
    }
}
