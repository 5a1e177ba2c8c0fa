//! Result rows and the two files that hold them: `results.csv` and `results.json`.
//!
//! Rows are written the moment they finish: the CSV gets a line and is flushed, and the JSON
//! file is rewritten atomically (written beside, then renamed), so a run that is interrupted —
//! killed, out of memory, power cut — keeps every finished row in both files.
//!
//! The CSV columns are the fields of [`Row`] in order. The first twenty are fixed by the
//! measurement-core issue and are never renamed; later algorithms add columns at the end.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use render_core::Settings;

pub use crate::results::csv_row::CsvRow;
pub use crate::results::description::{MergedRun, RunDescription, Shard, Viewpoints};
use crate::results::machine::MachineInfo;
pub use crate::results::named::NamedValues;
use crate::results::outcome::{opt_as_text, opt_from_text};
pub use crate::results::outcome::{Bound, Failure, Stage};
pub use crate::results::suspect::Suspect;

pub mod aggregate;
pub mod control;
pub mod csv_row;
pub mod description;
pub mod git_state;
pub mod machine;
pub mod metrics;
pub mod named;
pub mod names;
pub mod outcome;
pub mod samples;
pub mod stats;
pub mod suspect;
pub mod tile_counts;

/// Bumped whenever a field changes meaning or is removed (adding a field does not bump it).
/// Version 2 adds per-frame `samples`, the exact f32 image (`image_f32`, `image_hash`), the
/// roofline columns and the machine's calibration; version 1 files still load (the new fields
/// are then empty).
pub const SCHEMA_VERSION: u32 = 2;

/// The oldest schema [`ResultsFile::read`] still accepts.
pub const OLDEST_READABLE_SCHEMA: u32 = 1;

pub const CSV_FILE: &str = "results.csv";
pub const JSON_FILE: &str = "results.json";

/// One (algorithm, settings, data set, viewpoint) measurement. Times in ms, rates per second,
/// error metrics as defined in [`crate::results::metrics`]. `None` is an empty CSV cell / JSON null: no
/// timestamp queries (gpu_ms), no reference (error metrics), or a failed row (`error` set).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Row {
    pub algorithm: String,
    /// The variant's typed settings: a map in `results.json` (`{"k": 6, …}`; the text form
    /// of older files still loads), `key=value;…` text in `results.csv`.
    #[schemars(with = "SettingsSchema")]
    pub settings: Settings,
    pub dataset: String,
    pub tets: u64,
    pub viewpoint: String,
    pub width: u32,
    pub height: u32,
    #[schemars(required)]
    pub total_ms: Option<f64>,
    #[schemars(required)]
    pub cpu_ms: Option<f64>,
    #[schemars(required)]
    pub gpu_ms: Option<f64>,
    #[schemars(required)]
    pub fps: Option<f64>,
    #[schemars(required)]
    pub tets_per_sec: Option<f64>,
    #[schemars(required)]
    pub gpu_bytes: Option<u64>,
    #[schemars(required)]
    pub bytes_per_tet: Option<f64>,
    #[schemars(required)]
    pub rmse: Option<f64>,
    #[schemars(required)]
    pub psnr_db: Option<f64>,
    #[schemars(required)]
    pub max_abs_error: Option<f64>,
    #[schemars(required)]
    pub bad_pixel_share: Option<f64>,
    pub adapter: String,
    pub backend: String,
    // ---- extra columns (append new ones below, never rename the ones above) ----
    pub total_ms_min: Option<f64>,
    pub total_ms_max: Option<f64>,
    pub cpu_ms_min: Option<f64>,
    pub cpu_ms_max: Option<f64>,
    pub gpu_ms_min: Option<f64>,
    pub gpu_ms_max: Option<f64>,
    /// Timed frames over all rounds (each round's after `warmup` untimed ones): the number of
    /// samples.
    pub frames: u32,
    pub warmup: u32,
    /// GPU bytes that live as long as the mesh (bytes_per_tet = this / tets).
    pub gpu_bytes_persistent: Option<u64>,
    /// Largest per-frame allocation seen over the timed frames.
    pub gpu_bytes_frame: Option<u64>,
    /// Median stage timings (ms) by name, in pipeline order: a map in `results.json`, the text
    /// `name=ms;…` in `results.csv` (and in `results.json` files written before it was typed).
    pub stages: NamedValues,
    /// Median counters by name (fragments, triangles, ray steps, sort keys …), stored as
    /// `stages` is.
    pub counters: NamedValues,
    pub covered_pixels: Option<u64>,
    pub transfer_function: String,
    pub projection: String,
    pub device_type: String,
    pub driver: String,
    /// Paths relative to the output directory (empty when not written).
    pub image: String,
    pub reference_image: String,
    pub heatmap: String,
    /// Empty, or why the row's image error is out of line with the other algorithms on the
    /// same image ([`crate::results::suspect`]). Absent in files written before it existed.
    #[serde(
        default,
        serialize_with = "opt_as_text",
        deserialize_with = "opt_from_text"
    )]
    #[schemars(with = "String")]
    pub suspect: Option<Suspect>,
    /// The exact rendering (premultiplied linear RGBA f32, compressed, see [`crate::results::samples`]),
    /// relative to the output directory, and the blake3 hash of its pixels.
    #[serde(default)]
    pub image_f32: String,
    #[serde(default)]
    pub image_hash: String,
    /// Roofline against the backend's calibration (`tetbench calibrate`): the time the
    /// bounding resource alone needs, `roofline_ms / total_ms`, which resource that is, and
    /// `total_ms / roofline_ms` (the machine-independent figure `compare --normalised` uses).
    #[serde(default)]
    pub roofline_ms: Option<f64>,
    #[serde(default)]
    pub limit_fraction: Option<f64>,
    #[serde(
        default,
        serialize_with = "opt_as_text",
        deserialize_with = "opt_from_text"
    )]
    #[schemars(with = "String")]
    pub bound_by: Option<Bound>,
    #[serde(default)]
    pub normalized_time: Option<f64>,
    /// The machine's speed at this row's rounds against the whole run: the geometric mean over
    /// the control's figures of the row's control (the median of its rounds') over the run's
    /// median control (`results::control`). 0.8: the machine ran at 80 % of the
    /// run's typical speed while this row was measured. Empty without a control.
    #[serde(default)]
    pub control_factor: Option<f64>,
    /// What priced the roofline: `control` (the row's own rounds' control), `control, scaled
    /// FIGURE…` (figures the control did not measure, from the calibration times the
    /// control's factor), `calibration` (the cached calibration: results without a control).
    #[serde(default)]
    pub priced_with: crate::results::control::Pricing,
    /// Peak resident host memory of the process during the row (bytes): the kernel's VmHWM,
    /// reset before the row (the first row of a variant includes its prepare). On a software
    /// adapter (lavapipe) GPU buffers live in host memory and are counted here too. Empty where
    /// the mark cannot be reset (non-Linux) and in files written before it existed.
    #[serde(default)]
    pub host_peak_bytes: Option<u64>,
    /// Wall time (ms) the harness spent on this row outside its frames, summed over rounds:
    /// image readback, PNG and f32 image, hash, metrics and heatmap, bookkeeping between
    /// frames. Neither the warm-up frames nor the reference renderer's work (once per view,
    /// cached across runs) is in it. Empty in files written before it existed.
    #[serde(default)]
    pub harness_ms: Option<f64>,
    /// The renderer's counts per screen tile of the frame (`….NAME.json` beside the image,
    /// [`crate::results::tile_counts`]), relative to the output directory; empty where the
    /// renderer keeps none and in older files.
    #[serde(default)]
    pub tile_counts: String,
    /// Empty on success; otherwise what went wrong (the metrics are then empty).
    #[serde(serialize_with = "opt_as_text", deserialize_with = "opt_from_text")]
    #[schemars(with = "String")]
    pub error: Option<Failure>,
    /// Per-frame samples: in `results.json` only (`samples.csv` has them one per line).
    #[serde(default, skip_serializing_if = "FrameSamples::is_empty")]
    pub samples: FrameSamples,
    /// The control of each of the row's rounds (the best of the samples around it): in
    /// `results.json` only.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub round_control: Vec<crate::results::control::Figures>,
}

/// The settings as JSON Schema sees them: a map of integers and words, or the text form of
/// files written before settings were typed.
#[derive(JsonSchema)]
#[allow(dead_code)]
#[schemars(untagged)]
enum SettingsSchema {
    Map(std::collections::BTreeMap<String, SettingValueSchema>),
    Text(String),
}

#[derive(JsonSchema)]
#[allow(dead_code)]
#[schemars(untagged)]
enum SettingValueSchema {
    Int(i64),
    Text(String),
}

/// Writes one row to `results.csv`: its flat view ([`CsvRow`]).
fn serialize_csv_row<W: Write>(csv: &mut csv::Writer<W>, row: &Row) -> csv::Result<()> {
    csv.serialize(CsvRow(row))
}

impl Row {
    /// Gives the settings read back from a file the types their algorithm declares (a file
    /// holds every value as text).
    pub fn retype_settings(&mut self) {
        let settings = std::mem::take(&mut self.settings);
        self.settings = crate::algorithms::retype(&self.algorithm, settings);
    }

    /// A counter of the row, if present.
    pub fn counter(&self, name: &str) -> Option<f64> {
        self.counters.get(name)
    }

    /// A stage's median time in ms, if present.
    pub fn stage_ms(&self, name: &str) -> Option<f64> {
        self.stages.get(name)
    }

    pub fn ok(&self) -> bool {
        self.error.is_none()
    }

    /// The failure's text (empty for a row that did not fail).
    pub fn error_text(&self) -> String {
        self.error
            .as_ref()
            .map(Failure::to_string)
            .unwrap_or_default()
    }
}

/// The whole of `results.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ResultsFile {
    pub schema_version: u32,
    pub machine: MachineInfo,
    pub run: RunDescription,
    /// ISO 8601 UTC; `None` while the run is still going (or was interrupted).
    pub finished_utc: Option<String>,
    pub rows: Vec<Row>,
    /// Failures that are not one row: a data set that could not be loaded, a renderer that
    /// could not be prepared (its rows are also recorded, with `error` set).
    pub errors: Vec<String>,
    /// The control measured beside the rows ([`crate::calibrate::control`]); absent in
    /// results without one (`--no-calibrate`, files written before it existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub control: Option<crate::results::control::Control>,
}

impl ResultsFile {
    pub fn read(dir: &Path) -> anyhow::Result<ResultsFile> {
        let path = dir.join(JSON_FILE);
        let text = read_text(&path)?;
        // The version alone first (every other field skipped, not built into a value: a
        // history reads a thousand of these files).
        #[derive(Deserialize)]
        struct Version {
            schema_version: Option<serde_json::Value>,
        }
        let version = match serde_json::from_str::<Version>(&text) {
            Ok(v) => v.schema_version.and_then(|v| v.as_u64()),
            // Valid JSON but not an object (or without a usable field): no version.
            Err(e) if e.is_data() => None,
            Err(e) => return Err(e).with_context(|| format!("{} is not JSON", path.display())),
        };
        if !version
            .is_some_and(|v| (OLDEST_READABLE_SCHEMA as u64..=SCHEMA_VERSION as u64).contains(&v))
        {
            anyhow::bail!(
                "{}: schema_version {:?}, this tetbench reads versions \
                 {OLDEST_READABLE_SCHEMA} to {SCHEMA_VERSION}",
                path.display(),
                version
            );
        }
        // From the text, not the parsed value: a value's maps are sorted, and a row's settings
        // keep their declared order.
        let mut file: ResultsFile = serde_json::from_str(&text)
            .with_context(|| format!("{}: unexpected layout", path.display()))?;
        for row in &mut file.rows {
            row.retype_settings();
        }
        Ok(file)
    }
}

/// The JSON Schema of `results.json`, generated from these types (`docs/results.schema.json`
/// is this, checked by a test).
pub fn json_schema() -> serde_json::Value {
    serde_json::to_value(schemars::schema_for!(ResultsFile)).expect("a schema is JSON")
}

/// Writes rows to `results.csv` and `results.json` as they finish.
pub struct ResultsWriter {
    dir: PathBuf,
    csv: csv::Writer<File>,
    samples: SamplesWriter,
    pub file: ResultsFile,
}

impl ResultsWriter {
    /// Starts fresh result files in `dir` (replacing earlier ones).
    pub fn create(
        dir: &Path,
        machine: MachineInfo,
        run: RunDescription,
    ) -> anyhow::Result<ResultsWriter> {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let csv_path = dir.join(CSV_FILE);
        let f = File::create(&csv_path)
            .with_context(|| format!("cannot create {}", csv_path.display()))?;
        let mut csv = csv::WriterBuilder::new().has_headers(false).from_writer(f);
        // The header is written by hand so that a run with no rows still has it.
        csv.write_record(csv_header())?;
        csv.flush()?;
        let w = ResultsWriter {
            dir: dir.to_path_buf(),
            csv,
            samples: SamplesWriter::create(dir)?,
            file: ResultsFile {
                control: None,
                schema_version: SCHEMA_VERSION,
                machine,
                run,
                finished_utc: None,
                rows: vec![],
                errors: vec![],
            },
        };
        w.write_json()?;
        Ok(w)
    }

    /// Appends a row to both files; both are on disk when this returns.
    pub fn push(&mut self, row: Row) -> anyhow::Result<()> {
        // The samples go to samples.csv; results.csv keeps one flat line per row.
        serialize_csv_row(&mut self.csv, &row)?;
        self.csv.flush().context("writing results.csv")?;
        self.samples.push(&row)?;
        self.file.rows.push(row);
        self.write_json()
    }

    /// Appends rows of an earlier run (`run --resume`) to both files, with one JSON write.
    pub fn push_restored(&mut self, rows: Vec<Row>) -> anyhow::Result<()> {
        if rows.is_empty() {
            return Ok(());
        }
        for row in rows {
            serialize_csv_row(&mut self.csv, &row)?;
            self.samples.push(&row)?;
            self.file.rows.push(row);
        }
        self.csv.flush().context("writing results.csv")?;
        self.write_json()
    }

    pub fn push_error(&mut self, message: String) -> anyhow::Result<()> {
        self.file.errors.push(message);
        self.write_json()
    }

    pub fn finish(&mut self) -> anyhow::Result<()> {
        self.file.finished_utc = Some(crate::results::machine::iso8601_utc(
            std::time::SystemTime::now(),
        ));
        self.write_json()
    }

    /// Rewrites `results.csv` from the rows held (after [`crate::calibrate::annotate`] filled
    /// in columns that need every row), then `results.json`.
    pub fn rewrite_all(&mut self) -> anyhow::Result<()> {
        write_csv(&self.dir, &self.file.rows)?;
        self.write_json()
    }

    fn write_json(&self) -> anyhow::Result<()> {
        write_json(&self.dir, &self.file)
    }
}

/// Writes `results.csv` for a whole set of rows (replacing the file).
pub fn write_csv(dir: &Path, rows: &[Row]) -> anyhow::Result<()> {
    let path = dir.join(CSV_FILE);
    let f = File::create(&path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut csv = csv::WriterBuilder::new().has_headers(false).from_writer(f);
    csv.write_record(csv_header())?;
    for r in rows {
        serialize_csv_row(&mut csv, r)?;
    }
    csv.flush()
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Writes `contents` to `path`; the error names the file.
pub fn write_file(path: &Path, contents: impl AsRef<[u8]>) -> anyhow::Result<()> {
    std::fs::write(path, contents).with_context(|| format!("cannot write {}", path.display()))
}

/// Reads `path` as text; the error names the file.
pub fn read_text(path: &Path) -> anyhow::Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

/// Reads `path`'s bytes; the error names the file.
pub fn read_bytes(path: &Path) -> anyhow::Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))
}

/// Writes `results.json` atomically.
pub fn write_json(dir: &Path, file: &ResultsFile) -> anyhow::Result<()> {
    write_atomic(&dir.join(JSON_FILE), |f| {
        serde_json::to_writer_pretty(&mut *f, file)?;
        f.write_all(b"\n")
    })
}

/// Writes `path` atomically: into a temporary file beside it, then renamed over it
/// (`tempfile`'s `persist`), so a reader never sees half a file and an interrupted write
/// leaves the old one. The file gets the usual 0644 permissions (a temporary file's are 0600).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut File) -> std::io::Result<()>,
) -> anyhow::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".tetbench-")
        .suffix(".tmp")
        .permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644))
        .tempfile_in(dir)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    write(tmp.as_file_mut()).with_context(|| format!("cannot write {}", path.display()))?;
    tmp.as_file().sync_all().ok();
    tmp.persist(path)
        .map_err(|e| e.error)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// The CSV header: [`Row`]'s field names in order (taken from serde so they cannot drift).
pub fn csv_header() -> Vec<String> {
    let mut w = csv::Writer::from_writer(vec![]);
    serialize_csv_row(&mut w, &Row::default()).expect("row serialises");
    let bytes = w.into_inner().expect("in-memory writer");
    let text = String::from_utf8(bytes).expect("utf-8");
    text.lines()
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_string)
        .collect()
}

/// The columns the measurement-core issue fixes, in order.
pub const REQUIRED_COLUMNS: [&str; 20] = [
    "algorithm",
    "settings",
    "dataset",
    "tets",
    "viewpoint",
    "width",
    "height",
    "total_ms",
    "cpu_ms",
    "gpu_ms",
    "fps",
    "tets_per_sec",
    "gpu_bytes",
    "bytes_per_tet",
    "rmse",
    "psnr_db",
    "max_abs_error",
    "bad_pixel_share",
    "adapter",
    "backend",
];

// ---------------------------------------------------------------------------------------------
// Per-frame samples (`results.json` rows and `samples.csv`); here rather than in `samples.rs`
// so that the results schema depends on nothing that depends on it.
// ---------------------------------------------------------------------------------------------

pub const SAMPLES_CSV: &str = "samples.csv";

/// Per-frame measurements of one row, in frame order. `gpu_ms` is empty when the adapter has no
/// timestamp queries.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FrameSamples {
    pub total_ms: Vec<f64>,
    pub cpu_ms: Vec<f64>,
    #[serde(default)]
    pub gpu_ms: Vec<f64>,
    /// Per frame, each counter the row's algorithm declares nondeterministic on the row's
    /// adapter (`AlgorithmDescription::nondeterministic_counters`: HAVS's racy pass on a GPU),
    /// so that `compare` tests it across rounds as it tests time. Exact counters are not kept
    /// here: every frame counts them alike.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub counters: BTreeMap<String, Vec<f64>>,
}

impl FrameSamples {
    pub fn is_empty(&self) -> bool {
        self.total_ms.is_empty() && self.cpu_ms.is_empty() && self.gpu_ms.is_empty()
    }

    /// The samples of `frames`, with the per-frame values of the counters named in
    /// `nondeterministic` (a frame that lacks one leaves it out).
    pub fn from_frames(
        frames: &[render_core::FrameStats],
        nondeterministic: &[&str],
    ) -> FrameSamples {
        let gpu: Option<Vec<f64>> = frames.iter().map(|f| f.gpu_ms).collect();
        let counters = nondeterministic
            .iter()
            .map(|name| {
                let per_frame = frames
                    .iter()
                    .filter_map(|f| f.counters.iter().find(|(n, _)| n == name).map(|(_, v)| *v));
                (name.to_string(), per_frame.collect::<Vec<f64>>())
            })
            .filter(|(_, v)| !v.is_empty())
            .collect();
        FrameSamples {
            total_ms: frames.iter().map(|f| f.total_ms).collect(),
            cpu_ms: frames.iter().map(|f| f.cpu_ms).collect(),
            gpu_ms: gpu.unwrap_or_default(),
            counters,
        }
    }

    /// The samples of a time metric by its column name (`total_ms`, `cpu_ms`, `gpu_ms`), or of
    /// a nondeterministic counter by its name (empty for any other name).
    pub fn metric(&self, name: &str) -> &[f64] {
        match name {
            "total_ms" => &self.total_ms,
            "cpu_ms" => &self.cpu_ms,
            "gpu_ms" => &self.gpu_ms,
            counter => self.counters.get(counter).map_or(&[], Vec::as_slice),
        }
    }
}

/// One line of `samples.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SampleLine {
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    pub viewpoint: String,
    pub width: u32,
    pub height: u32,
    pub adapter: String,
    /// 0-based index of the timed frame.
    pub frame: u32,
    /// `total_ms`, `cpu_ms` or `gpu_ms`.
    pub metric: String,
    pub ms: f64,
}

/// The long-format lines of one row.
pub fn sample_lines(row: &Row) -> Vec<SampleLine> {
    let mut out = vec![];
    for metric in ["total_ms", "cpu_ms", "gpu_ms"] {
        for (i, &ms) in row.samples.metric(metric).iter().enumerate() {
            out.push(SampleLine {
                algorithm: row.algorithm.clone(),
                settings: row.settings.to_string(),
                dataset: row.dataset.clone(),
                viewpoint: row.viewpoint.clone(),
                width: row.width,
                height: row.height,
                adapter: row.adapter.clone(),
                frame: i as u32,
                metric: metric.to_string(),
                ms,
            });
        }
    }
    out
}

/// Appends to `samples.csv` as rows finish (header written on creation).
pub struct SamplesWriter {
    csv: csv::Writer<File>,
}

impl SamplesWriter {
    pub fn create(dir: &Path) -> anyhow::Result<SamplesWriter> {
        let path = dir.join(SAMPLES_CSV);
        let f = File::create(&path).with_context(|| format!("cannot create {}", path.display()))?;
        let mut csv = csv::WriterBuilder::new().has_headers(false).from_writer(f);
        csv.write_record([
            "algorithm",
            "settings",
            "dataset",
            "viewpoint",
            "width",
            "height",
            "adapter",
            "frame",
            "metric",
            "ms",
        ])?;
        csv.flush()?;
        Ok(SamplesWriter { csv })
    }

    pub fn push(&mut self, row: &Row) -> anyhow::Result<()> {
        for line in sample_lines(row) {
            self.csv.serialize(line)?;
        }
        self.csv.flush().context("writing samples.csv")
    }
}

/// Writes `samples.csv` for a whole results set (used by `report --merge`).
pub fn write_samples_csv(dir: &Path, rows: &[Row]) -> anyhow::Result<()> {
    let mut w = SamplesWriter::create(dir)?;
    for r in rows {
        w.push(r)?;
    }
    Ok(())
}

#[cfg(test)]
pub(crate) fn test_row(i: u32) -> Row {
    Row {
        algorithm: "test".into(),
        settings: "variant=a;sort=radix".parse().unwrap(),
        dataset: "box:1k".into(),
        tets: 1000,
        viewpoint: format!("v{i}"),
        width: 8,
        height: 8,
        total_ms: Some(2.0),
        tets_per_sec: Some(500_000.0),
        adapter: "llvmpipe, \"quoted\"".into(),
        backend: "vulkan".into(),
        ..Row::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_starts_with_the_required_columns() {
        let h = csv_header();
        assert_eq!(&h[..20], &REQUIRED_COLUMNS[..]);
        assert_eq!(h.last().map(String::as_str), Some("error"));
    }

    /// Every row is on disk, in both files, as soon as `push` returns: an interrupted run
    /// keeps what it finished.
    #[test]
    fn rows_are_on_disk_after_each_push() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = ResultsWriter::create(
            dir.path(),
            MachineInfo::collect(),
            RunDescription::default(),
        )
        .unwrap();
        assert_eq!(ResultsFile::read(dir.path()).unwrap().rows.len(), 0);
        for i in 0..3 {
            w.push(test_row(i)).unwrap();
            let json = ResultsFile::read(dir.path()).unwrap();
            assert_eq!(json.rows.len(), i as usize + 1);
            assert_eq!(json.rows[i as usize], test_row(i));
            assert_eq!(json.finished_utc, None);
            let mut r = csv::Reader::from_path(dir.path().join(CSV_FILE)).unwrap();
            let rows: Vec<Row> = r.deserialize().collect::<Result<_, _>>().unwrap();
            assert_eq!(rows.len(), i as usize + 1);
            assert_eq!(rows[i as usize], test_row(i));
        }
        // Dropping the writer without `finish` (as a crash would) leaves both files readable.
        drop(w);
        assert_eq!(ResultsFile::read(dir.path()).unwrap().rows.len(), 3);
    }

    /// A results.json written by schema version 1 (before samples, f32 images and the
    /// roofline existed) still loads, with those fields empty; so does its CSV.
    #[test]
    fn version_1_results_still_load() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/results-v1");
        let file = ResultsFile::read(&dir).unwrap();
        assert_eq!(file.schema_version, 1);
        assert_eq!(file.rows.len(), 1);
        let row = &file.rows[0];
        assert_eq!(row.algorithm, "havs");
        assert!(row.total_ms.is_some() && row.psnr_db.is_some());
        assert!(row.samples.is_empty() && row.image_hash.is_empty());
        assert_eq!(row.roofline_ms, None);
        assert_eq!(file.machine.calibration, None);
        let mut r = csv::Reader::from_path(dir.join(CSV_FILE)).unwrap();
        let rows: Vec<Row> = r.deserialize().collect::<Result<_, _>>().unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0].total_ms, row.total_ms);
    }

    #[test]
    fn wrong_schema_version_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(JSON_FILE), r#"{"schema_version": 999}"#).unwrap();
        let e = ResultsFile::read(dir.path()).unwrap_err().to_string();
        assert!(e.contains("schema_version"), "{e}");
    }
}
