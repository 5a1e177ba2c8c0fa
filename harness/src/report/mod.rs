//! The report of a run, written into its output directory from `results.json` alone (so
//! `tetbench report OUT` can redo it): the charts of [`crate::plot`] (speed vs error first) in
//! `charts/`, and an `index.html` with the machine, the charts and their key, the summary and
//! full tables (peers and suspect rows marked), and every image beside its reference and error
//! heatmap.

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use crate::algorithms::is_peer;
use crate::results::metrics::{HEATMAP_MAX_ERROR, ONE_STEP, PSNR_CAP_DB};
use crate::results::{write_file, ResultsFile, Row};

pub mod control;
pub mod html;
pub mod progress;

pub use crate::results::names::series_label;
pub use crate::results::stats::{spread, Spread};

pub use crate::results::aggregate::{aggregate, Aggregate};

/// Writes the charts (see [`crate::plot`]) and `index.html` into `out` for the results in
/// `file`.
pub fn write(out: &Path, file: &ResultsFile) -> anyhow::Result<()> {
    let mut inputs = crate::plot::data::Inputs::default();
    inputs.add(file, crate::plot::raw_results(out).as_ref());
    let charts = crate::plot::write_charts(&out.join("charts"), &inputs, crate::plot::Kind::All)?;
    let aggs = aggregate(&file.rows);
    let html = html(
        file,
        &aggs,
        &crate::plot::ChartsPage::new(&charts, "charts"),
        &Images::in_dir(out),
    )?;
    let path = out.join("index.html");
    write_file(&path, html)
}

/// Re-renders the report of an earlier run (`tetbench report OUT`).
pub fn rewrite(out: &Path) -> anyhow::Result<()> {
    let file = ResultsFile::read(out)?;
    write(out, &file)
}

/// Which of the images a run's rows name are in the report's directory. A baseline keeps its
/// results but not its images (a report re-rendered from one named 198 files that were not
/// there): an absent image is counted and said so on the page, never linked.
struct Images<'a> {
    dir: &'a Path,
    /// The distinct absent paths asked about.
    absent: std::cell::RefCell<std::collections::BTreeSet<String>>,
}

impl<'a> Images<'a> {
    fn in_dir(dir: &'a Path) -> Self {
        Images {
            dir,
            absent: Default::default(),
        }
    }

    /// `path` when it names a file in the directory; empty (and counted) when it names one that
    /// is not there; empty when it names none.
    fn present(&self, path: &str) -> String {
        if path.is_empty() {
            return String::new();
        }
        if self.dir.join(path).is_file() {
            path.to_string()
        } else {
            self.absent.borrow_mut().insert(path.to_string());
            String::new()
        }
    }
}

/// CSS classes of a table row: failed, suspect (`results::suspect`'s rule) and peer rows are marked.
fn row_classes(failed: bool, suspect: bool, algorithm: &str) -> Vec<&'static str> {
    let mut c = vec![];
    if failed {
        c.push("failed");
    }
    if suspect {
        c.push("suspect");
    }
    if crate::plot::style::is_peer(algorithm) {
        c.push("peer");
    }
    c
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map(|v| format!("{v:.digits$}"))
        .unwrap_or_else(|| "–".into())
}

fn mb(v: Option<u64>) -> String {
    v.map(|b| format!("{:.2}", b as f64 / (1 << 20) as f64))
        .unwrap_or_else(|| "–".into())
}

/// A summary cell: mean with min–max, already formatted.
#[derive(Serialize)]
struct SpreadCell {
    mean: String,
    min: String,
    max: String,
}

fn spread_cell(s: Option<Spread>, k: f64, digits: usize) -> Option<SpreadCell> {
    s.map(|s| SpreadCell {
        mean: format!("{:.digits$}", s.mean * k),
        min: format!("{:.digits$}", s.min * k),
        max: format!("{:.digits$}", s.max * k),
    })
}

#[derive(Serialize)]
struct SummaryLine {
    classes: Vec<&'static str>,
    algorithm: String,
    peer: bool,
    settings: String,
    dataset: String,
    tets: u64,
    rows: usize,
    failed: usize,
    /// total, CPU, GPU ms, fps, M tets/s, PSNR, bad pixels %.
    spreads: Vec<Option<SpreadCell>>,
    bytes_per_tet: String,
    gpu_mib: String,
}

#[derive(Serialize)]
struct Picture {
    path: String,
    alt: &'static str,
}

#[derive(Serialize)]
struct SuspectFigure {
    images: Vec<Picture>,
    algorithm: String,
    settings: String,
    dataset: String,
    viewpoint: String,
    why: String,
}

#[derive(Serialize)]
struct ViewFigure {
    image: String,
    heatmap: String,
    label: String,
    psnr: String,
    mtets: String,
}

#[derive(Serialize)]
struct View {
    dataset: String,
    viewpoint: String,
    reference: String,
    figures: Vec<ViewFigure>,
}

#[derive(Serialize)]
struct RowLine {
    classes: Vec<&'static str>,
    algorithm: String,
    peer: bool,
    settings: String,
    dataset: String,
    viewpoint: String,
    cells: Vec<String>,
    stages: String,
    error: String,
}

/// Everything `templates/report.html` shows.
#[derive(Serialize)]
struct ReportPage<'a> {
    machine: Vec<(&'static str, String)>,
    errors: &'a [String],
    charts: &'a crate::plot::ChartsPage,
    suspects: Vec<SuspectFigure>,
    any_peer: bool,
    summary: Vec<SummaryLine>,
    heatmap_max_error: f64,
    psnr_cap_db: f64,
    one_step: String,
    views: Vec<View>,
    /// The control over the run (absent without one).
    control: Option<control::ControlView>,
    /// Images the rows name that are not in the report's directory (not linked).
    images_absent: usize,
    /// The run's data files that are in the report's directory (linked).
    raw_files: Vec<&'static str>,
    rows: Vec<RowLine>,
}

/// The 1-minute load average at the start and the end of the run, against the cores.
fn load_line(m: &crate::results::machine::MachineInfo) -> String {
    let f = |v: Option<f64>| v.map_or("unknown".to_string(), |v| format!("{v:.2}"));
    format!(
        "{} at the start, {} at the end, on {} logical cores",
        f(m.load_average_start),
        f(m.load_average_end),
        m.cpu_cores
    )
}

/// The calibration's headline figures (what the roofline columns divide by), or why there is
/// none.
fn calibration_line(m: &crate::results::machine::MachineInfo) -> String {
    let Some(c) = &m.calibration else {
        return "none (run with --no-calibrate, or a file written before calibration)".into();
    };
    format!(
        "{} on {} ({}): {:.3e} triangles/s, {:.3e} fill fragments/s ({}), {:.1} GFLOP/s, \
         {:.3e} copy bytes/s, {:.3e} sort keys/s, {:.3e} ray steps/s, {:.3e} splat \
         fragments/s, {:.3e} GPU sort keys/s",
        c.date_utc,
        c.adapter,
        c.driver,
        c.triangles_per_sec,
        c.fill_fragments_per_sec,
        c.fill_format,
        c.compute_gflops,
        c.copy_bytes_per_sec,
        c.sort_keys_per_sec,
        c.ray_steps_per_sec,
        c.splat_fragments_per_sec,
        c.gpu_sort_keys_per_sec
    )
}

fn machine_lines(file: &ResultsFile) -> Vec<(&'static str, String)> {
    let m = &file.machine;
    let r = &file.run;
    let mem = m
        .memory_bytes
        .map(|b| format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64))
        .unwrap_or_else(|| "unknown".into());
    let adapter = m
        .adapter
        .as_ref()
        .map(|a| {
            format!(
                "{} ({}, {}, driver {} {})",
                a.name, a.backend, a.device_type, a.driver, a.driver_info
            )
        })
        .unwrap_or_else(|| "unknown".into());
    let commit = match (&m.git_commit, m.git_dirty) {
        (Some(c), Some(true)) => format!("{c} (with uncommitted changes)"),
        (Some(c), _) => c.clone(),
        _ => "unknown".into(),
    };
    vec![
        ("GPU adapter", adapter),
        (
            "CPU",
            format!("{} ({} logical cores)", m.cpu_model, m.cpu_cores),
        ),
        ("memory", mem),
        (
            "OS",
            format!("{} {}", m.os, m.kernel.as_deref().unwrap_or("")),
        ),
        (
            "tetbench",
            format!("{} at commit {commit}", m.tetbench_version),
        ),
        (
            "build",
            format!(
                "{} profile, {}",
                m.build_profile.as_deref().unwrap_or("unknown"),
                m.rustc_version.as_deref().unwrap_or("rustc unknown")
            ),
        ),
        (
            "host",
            m.host_name.clone().unwrap_or_else(|| "unknown".into()),
        ),
        ("load (1 min)", load_line(m)),
        ("calibration", calibration_line(m)),
        ("started", m.date_utc.clone()),
        (
            "finished",
            file.finished_utc
                .clone()
                .unwrap_or_else(|| "not finished (interrupted?)".into()),
        ),
        ("command", r.command_line.join(" ")),
        ("viewpoints", r.viewpoints.to_string()),
        (
            "viewport",
            format!("{}×{}, {}", r.width, r.height, r.projection),
        ),
        (
            "frames",
            format!("{} timed after {} warm-up", r.frames, r.warmup),
        ),
        ("transfer function", r.transfer_function.clone()),
    ]
}

fn summary_lines(aggs: &[Aggregate]) -> Vec<SummaryLine> {
    aggs.iter()
        .map(|a| {
            let any_suspect = a.suspect > 0;
            let peer = is_peer(&a.algorithm);
            SummaryLine {
                classes: row_classes(a.failed > 0, any_suspect, &a.algorithm),
                algorithm: a.algorithm.clone(),
                peer,
                settings: a.settings.to_string(),
                dataset: a.place(aggs),
                tets: a.tets,
                rows: a.rows,
                failed: a.failed,
                spreads: vec![
                    spread_cell(a.total_ms, 1.0, 2),
                    spread_cell(a.cpu_ms, 1.0, 2),
                    spread_cell(a.gpu_ms, 1.0, 2),
                    spread_cell(a.fps, 1.0, 1),
                    spread_cell(a.tets_per_sec, 1e-6, 3),
                    spread_cell(a.psnr_db, 1.0, 2),
                    spread_cell(a.bad_pixel_share, 100.0, 2),
                ],
                // Peers report no GPU memory of their own (VTK's mappers).
                bytes_per_tet: opt(a.bytes_per_tet.filter(|_| !peer), 1),
                gpu_mib: mb(a.gpu_bytes.filter(|_| !peer)),
            }
        })
        .collect()
}

/// Rows flagged by [`crate::results::suspect`], each with its heatmap first, then the rendering and the
/// reference, so a broken renderer is the first picture a reader sees after the charts.
fn suspect_figures(file: &ResultsFile, images: &Images) -> Vec<SuspectFigure> {
    file.rows
        .iter()
        .filter(|r| r.suspect.is_some())
        .map(|row| SuspectFigure {
            images: [
                (&row.heatmap, "error heatmap"),
                (&row.image, "image"),
                (&row.reference_image, "reference"),
            ]
            .into_iter()
            .map(|(path, alt)| Picture {
                path: images.present(path),
                alt,
            })
            .filter(|p| !p.path.is_empty())
            .collect(),
            algorithm: row.algorithm.clone(),
            settings: row.settings.to_string(),
            dataset: row.dataset.clone(),
            viewpoint: row.viewpoint.clone(),
            why: row
                .suspect
                .as_ref()
                .map(ToString::to_string)
                .unwrap_or_default(),
        })
        .collect()
}

fn views(file: &ResultsFile, images: &Images) -> Vec<View> {
    let mut keys: Vec<(&str, &str)> = vec![];
    for row in &file.rows {
        let k = (row.dataset.as_str(), row.viewpoint.as_str());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(dataset, viewpoint)| {
            let rows: Vec<&Row> = file
                .rows
                .iter()
                .filter(|r| r.dataset == dataset && r.viewpoint == viewpoint)
                .collect();
            View {
                dataset: dataset.to_string(),
                viewpoint: viewpoint.to_string(),
                reference: rows
                    .iter()
                    .find(|r| !r.reference_image.is_empty())
                    .map(|r| images.present(&r.reference_image))
                    .unwrap_or_default(),
                figures: rows
                    .iter()
                    .filter_map(|row| {
                        let image = images.present(&row.image);
                        let heatmap = images.present(&row.heatmap);
                        (!image.is_empty()).then(|| ViewFigure {
                            image,
                            heatmap,
                            label: series_label(&row.algorithm, &row.settings.to_string()),
                            psnr: opt(row.psnr_db, 2),
                            mtets: opt(row.tets_per_sec.map(|v| v * 1e-6), 3),
                        })
                    })
                    .collect(),
            }
        })
        .filter(|v| !v.reference.is_empty() || !v.figures.is_empty())
        .collect()
}

fn row_lines(file: &ResultsFile, suspect: &[bool]) -> Vec<RowLine> {
    file.rows
        .iter()
        .zip(suspect)
        .map(|(row, suspect)| RowLine {
            classes: row_classes(!row.ok(), *suspect, &row.algorithm),
            algorithm: row.algorithm.clone(),
            peer: is_peer(&row.algorithm),
            settings: row.settings.to_string(),
            dataset: row.dataset.clone(),
            viewpoint: row.viewpoint.clone(),
            cells: vec![
                opt(row.total_ms, 2),
                opt(row.cpu_ms, 2),
                opt(row.gpu_ms, 2),
                opt(row.fps, 1),
                opt(row.tets_per_sec.map(|v| v * 1e-6), 3),
                mb(row.gpu_bytes),
                opt(row.bytes_per_tet, 1),
                opt(row.rmse, 5),
                opt(row.psnr_db, 2),
                opt(row.max_abs_error, 4),
                opt(row.bad_pixel_share.map(|v| v * 100.0), 2),
            ],
            stages: row.stages.to_string(),
            error: match &row.suspect {
                Some(why) => format!("SUSPECT: {why}"),
                None => row.error_text(),
            },
        })
        .collect()
}

/// Seconds from the run's start to its end, where both are known.
fn run_seconds(file: &ResultsFile) -> Option<f64> {
    let parse = |t: &str| humantime::parse_rfc3339(t).ok();
    let start = parse(&file.machine.date_utc)?;
    let end = parse(file.finished_utc.as_deref()?)?;
    end.duration_since(start).ok().map(|d| d.as_secs_f64())
}

fn html(
    file: &ResultsFile,
    aggs: &[Aggregate],
    charts: &crate::plot::ChartsPage,
    images: &Images,
) -> anyhow::Result<String> {
    let suspect = crate::results::suspect::flags(&file.rows);
    let suspects = suspect_figures(file, images);
    let views = views(file, images);
    crate::report::html::render(
        "report.html",
        ReportPage {
            machine: machine_lines(file),
            errors: &file.errors,
            charts,
            suspects,
            any_peer: file.rows.iter().any(|r| is_peer(&r.algorithm)),
            summary: summary_lines(aggs),
            heatmap_max_error: HEATMAP_MAX_ERROR,
            psnr_cap_db: PSNR_CAP_DB,
            one_step: format!("{ONE_STEP:.4}"),
            views,
            control: file
                .control
                .as_ref()
                .and_then(|c| control::view(c, run_seconds(file))),
            images_absent: images.absent.borrow().len(),
            raw_files: [
                crate::results::CSV_FILE,
                crate::results::JSON_FILE,
                "samples.csv",
            ]
            .into_iter()
            .filter(|f| images.dir.join(f).is_file())
            .collect(),
            rows: row_lines(file, &suspect),
        },
    )
}

/// The summary as a Markdown table (for `tetbench analyze summary` and notes).
pub fn markdown_summary(aggs: &[Aggregate]) -> String {
    let mut s = String::from(
        "| algorithm | settings | data set | tets | total ms | CPU ms | GPU ms | fps | M tets/s | PSNR dB (min) | bytes/tet |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let m = |v: Option<Spread>, k: f64, d: usize| {
        v.map(|v| format!("{:.d$}", v.mean * k))
            .unwrap_or_else(|| "–".into())
    };
    for a in aggs {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} ({}) | {} |",
            a.algorithm,
            a.settings,
            a.place(aggs),
            a.tets,
            m(a.total_ms, 1.0, 2),
            m(a.cpu_ms, 1.0, 2),
            m(a.gpu_ms, 1.0, 2),
            m(a.fps, 1.0, 1),
            m(a.tets_per_sec, 1e-6, 3),
            m(a.psnr_db, 1.0, 2),
            a.psnr_db
                .map(|p| format!("{:.2}", p.min))
                .unwrap_or_else(|| "–".into()),
            opt(a.bytes_per_tet, 1),
        );
    }
    let suspect: Vec<&Aggregate> = aggs.iter().filter(|a| a.suspect > 0).collect();
    if !suspect.is_empty() {
        s.push_str("\n**Suspect** (PSNR far below the best algorithm on the same image; see `suspect` in results.csv):\n\n");
        for a in suspect {
            let _ = writeln!(
                s,
                "- {} {} on {}: {} of {} views",
                a.algorithm,
                a.settings,
                a.place(aggs),
                a.suspect,
                a.rows
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::machine::MachineInfo;
    use crate::results::{test_row, RunDescription, SCHEMA_VERSION};

    fn file() -> ResultsFile {
        let mut rows = vec![];
        for i in 0..3 {
            let mut r = test_row(i);
            r.tets_per_sec = Some(1e6 * (i + 1) as f64);
            r.psnr_db = Some(40.0 + i as f64);
            r.image = format!("images/box_1k/v{i}/test.png");
            r.heatmap = format!("images/box_1k/v{i}/test.error.png");
            r.reference_image = format!("images/box_1k/v{i}/reference.png");
            rows.push(r);
        }
        let mut failed = test_row(3);
        failed.error = Some(crate::results::Failure::new(
            crate::results::Stage::Render,
            "out of memory <boom>",
        ));
        failed.tets_per_sec = None;
        rows.push(failed);
        ResultsFile {
            control: None,
            schema_version: SCHEMA_VERSION,
            machine: MachineInfo::collect(),
            run: RunDescription::default(),
            finished_utc: None,
            rows,
            errors: vec!["data set \"x\" could not be loaded".into()],
        }
    }

    #[test]
    fn aggregates_average_over_viewpoints() {
        let a = aggregate(&file().rows);
        assert_eq!(a.len(), 1);
        let t = a[0].tets_per_sec.unwrap();
        assert_eq!((t.mean, t.min, t.max), (2e6, 1e6, 3e6));
        assert_eq!(a[0].rows, 4);
        assert_eq!(a[0].failed, 1);
        assert!(markdown_summary(&a).contains("| test | variant=a;sort=radix | box:1k | 1000 |"));
    }

    /// markup in a data set's name, a setting, an error or the command line lands in
    /// the page as text.
    #[test]
    fn markup_in_names_is_escaped() {
        use crate::report::html::{assert_no_live_markup, HOSTILE_NAME};
        let mut f = file();
        for r in &mut f.rows {
            r.dataset = HOSTILE_NAME.into();
            r.settings = render_core::Settings::new().with("k", HOSTILE_NAME);
            r.image = format!("images/{HOSTILE_NAME}.png");
        }
        f.rows[3].error = Some(crate::results::Failure::new(
            crate::results::Stage::Render,
            HOSTILE_NAME,
        ));
        f.errors.push(HOSTILE_NAME.into());
        f.run.command_line = vec!["tetbench".into(), HOSTILE_NAME.into()];
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), &f).unwrap();
        let page = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
        assert_no_live_markup(&page);
    }

    /// The page shows the provenance results.json holds: build profile, rustc, host, load
    /// and calibration (or that there is none).
    #[test]
    fn the_page_shows_build_host_load_and_calibration() {
        let mut f = file();
        f.machine.build_profile = Some("release".into());
        f.machine.rustc_version = Some("rustc 9.99.0 (test)".into());
        f.machine.host_name = Some("bench-host-7".into());
        f.machine.load_average_start = Some(4.25);
        f.machine.load_average_end = Some(1.5);
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), &f).unwrap();
        let page = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
        for shown in [
            "release profile, rustc 9.99.0 (test)",
            "bench-host-7",
            "4.25 at the start, 1.50 at the end",
            "calibration",
        ] {
            assert!(page.contains(shown), "{shown} missing from the page");
        }
        f.machine.calibration = None;
        write(dir.path(), &f).unwrap();
        let page = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
        assert!(page.contains("none (run with --no-calibrate"));
    }

    #[test]
    fn report_has_charts_table_and_images() {
        let dir = tempfile::tempdir().unwrap();
        // The images of views 0 and 2 are there, view 1's are not (as in a baseline, which
        // keeps no images): those are counted and said, never linked.
        for v in [0, 2] {
            let d = dir.path().join(format!("images/box_1k/v{v}"));
            std::fs::create_dir_all(&d).unwrap();
            for f in ["test.png", "test.error.png", "reference.png"] {
                std::fs::write(d.join(f), b"png").unwrap();
            }
        }
        write(dir.path(), &file()).unwrap();
        let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
        for needle in [
            "charts/tets_per_sec.png",
            "charts/psnr.png",
            "images/box_1k/v2/test.png",
            "images/box_1k/v2/test.error.png",
            "images/box_1k/v0/reference.png",
            "out of memory &lt;boom&gt;",
            "3 image(s) named in results.json are not in this\ndirectory",
        ] {
            assert!(html.contains(needle), "index.html lacks {needle}");
        }
        assert!(
            !html.contains("images/box_1k/v1/"),
            "an absent image is linked"
        );
        // With every image there, the note goes.
        let d = dir.path().join("images/box_1k/v1");
        std::fs::create_dir_all(&d).unwrap();
        for f in ["test.png", "test.error.png", "reference.png"] {
            std::fs::write(d.join(f), b"png").unwrap();
        }
        write(dir.path(), &file()).unwrap();
        let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
        assert!(html.contains("images/box_1k/v1/test.png"));
        assert!(!html.contains("images-absent"));
        for f in [
            "tets_per_sec.png",
            "tets_per_sec.svg",
            "psnr.png",
            "psnr.svg",
            "DejaVuSans.ttf",
        ] {
            assert!(
                dir.path().join("charts").join(f).metadata().unwrap().len() > 1000,
                "{f}"
            );
        }
        let png = image::open(dir.path().join("charts/psnr.png"))
            .unwrap()
            .to_rgb8();
        // Not blank: the bars and text drew something other than the white background.
        assert!(png.pixels().filter(|p| p.0 != [255, 255, 255]).count() > 1000);
        let svg = std::fs::read_to_string(dir.path().join("charts/psnr.svg")).unwrap();
        assert!(svg.contains("@font-face") && svg.contains("DejaVu Sans"));
    }
}
