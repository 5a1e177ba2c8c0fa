//! Timing invariants of every row a run writes: a small run of every algorithm's default
//! variants (tiny mesh, 32², 2 timed frames) through the harness's run loop, then every row of
//! `results.json`, `results.csv` and `samples.csv` is checked:
//!
//! - `total_ms` and `cpu_ms` present, finite and non-negative, per frame and as medians;
//! - `cpu_ms ≤ total_ms` (the CPU part is measured inside the frame's wall interval);
//! - `gpu_ms ≤ total_ms · (1 + GPU_CLOCK_TOLERANCE)` where the GPU time exists (the timestamp
//!   queries are written inside the same interval; see [`GPU_CLOCK_TOLERANCE`]);
//! - min ≤ median ≤ max for each series; no NaN or infinity in any numeric column.
//!
//! A second test wraps a renderer that reports a negative, a NaN and an inconsistent time and
//! checks that these checks (or the harness itself) catch each: the invariant test can fail.

use clap::Parser;
use datasets::TetMesh;
use harness::cli::{Cli, Command};
use harness::results::{ResultsFile, Row};
use render_core::{Camera, FrameStats, Gpu, Image, Optics, Prepared, Renderer};

/// Relative slack of `gpu_ms` over `total_ms`. The GPU time is timestamp ticks × the
/// adapter's `timestamp_period` (an f32, relative rounding 2⁻²⁴ ≈ 6·10⁻⁸) and the GPU clock
/// is another oscillator than the CPU's monotonic clock (drift of crystal clocks is below
/// 10⁻⁴). 10⁻³ covers both with a tenfold margin, while a real defect (GPU time taken over a
/// longer interval than the frame, or in the wrong unit: ×10³, ×10⁶) is far outside it.
const GPU_CLOCK_TOLERANCE: f64 = 1e-3;

fn config(args: &[String]) -> harness::run::RunConfig {
    let cli = Cli::try_parse_from(args).unwrap();
    let Command::Run(run) = cli.command else {
        panic!("not a run")
    };
    run.to_config(cli.data_dir, args.to_vec()).unwrap()
}

/// `tetbench run` of `algorithms`' default variants on a 1k-tet box, two viewpoints, 32²,
/// one warm-up and two timed frames, no calibration and no report.
fn small_run(out: &std::path::Path, cache: &std::path::Path, algorithms: &str) -> Vec<String> {
    let out = out.to_str().unwrap();
    let cache = cache.to_str().unwrap();
    [
        "tetbench",
        "run",
        "--algorithms",
        algorithms,
        "--datasets",
        "box:1k",
        "--viewpoints",
        "+x,+x+y+z",
        "--resolution",
        "32",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--no-report",
        "--no-calibrate",
        "--out",
        out,
        "--cache-dir",
        cache,
    ]
    .map(String::from)
    .to_vec()
}

/// What is wrong with one row's times (empty: nothing).
fn violations(r: &Row) -> Vec<String> {
    let mut v = vec![];
    let mut finite_non_negative = |name: &str, x: f64| {
        if !x.is_finite() || x < 0.0 {
            v.push(format!("{name} = {x}"));
        }
    };
    match (r.total_ms, r.cpu_ms) {
        (Some(t), Some(c)) => {
            finite_non_negative("total_ms", t);
            finite_non_negative("cpu_ms", c);
            if c > t {
                v.push(format!("cpu_ms {c} > total_ms {t}"));
            }
            if let Some(g) = r.gpu_ms {
                if !g.is_finite() || g < 0.0 {
                    v.push(format!("gpu_ms = {g}"));
                } else if g > t * (1.0 + GPU_CLOCK_TOLERANCE) {
                    v.push(format!("gpu_ms {g} > total_ms {t}"));
                }
            }
        }
        (t, c) => v.push(format!(
            "total_ms {t:?}, cpu_ms {c:?}: both must be measured"
        )),
    }
    for (name, min, med, max) in [
        ("total_ms", r.total_ms_min, r.total_ms, r.total_ms_max),
        ("cpu_ms", r.cpu_ms_min, r.cpu_ms, r.cpu_ms_max),
        ("gpu_ms", r.gpu_ms_min, r.gpu_ms, r.gpu_ms_max),
    ] {
        match (min, med, max) {
            (Some(a), Some(b), Some(c)) if a <= b && b <= c => {}
            (None, None, None) if name == "gpu_ms" => {}
            other => v.push(format!("{name} min/median/max {other:?}")),
        }
    }
    let s = &r.samples;
    if s.total_ms.len() != r.frames as usize || s.cpu_ms.len() != r.frames as usize {
        v.push(format!(
            "{} total and {} cpu samples for {} frames",
            s.total_ms.len(),
            s.cpu_ms.len(),
            r.frames
        ));
    }
    if !s.gpu_ms.is_empty() && s.gpu_ms.len() != s.total_ms.len() {
        v.push(format!(
            "{} gpu samples for {} frames",
            s.gpu_ms.len(),
            s.total_ms.len()
        ));
    }
    for (i, (&t, &c)) in s.total_ms.iter().zip(&s.cpu_ms).enumerate() {
        if !(t.is_finite() && c.is_finite() && t >= 0.0 && c >= 0.0 && c <= t) {
            v.push(format!("frame {i}: total {t}, cpu {c}"));
        }
        if let Some(&g) = s.gpu_ms.get(i) {
            if !(g.is_finite() && g >= 0.0 && g <= t * (1.0 + GPU_CLOCK_TOLERANCE)) {
                v.push(format!("frame {i}: gpu {g}, total {t}"));
            }
        }
    }
    v
}

/// Cells of a CSV file that read as a number but are not finite (`NaN`, `inf`), as
/// "line:column name = value".
fn non_finite_cells(path: &std::path::Path) -> Vec<String> {
    let mut rd = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let header = rd.headers().unwrap().clone();
    let mut bad = vec![];
    for (i, rec) in rd.records().enumerate() {
        let rec = rec.unwrap();
        for (name, cell) in header.iter().zip(rec.iter()) {
            if let Ok(x) = cell.trim().parse::<f64>() {
                if !x.is_finite() {
                    bad.push(format!("{}:{} {name} = {cell}", path.display(), i + 2));
                }
            }
        }
    }
    bad
}

/// Every check over a finished run directory: the rows' violations and non-finite cells.
fn run_violations(out: &std::path::Path) -> (Vec<Row>, Vec<String>) {
    let mut bad = vec![];
    // An unreadable results.json is a failure too (serde_json writes a NaN as null, which a
    // per-frame sample cannot hold).
    let rows = match ResultsFile::read(out) {
        Ok(f) => f.rows,
        Err(e) => {
            bad.push(format!("{e:#}"));
            vec![]
        }
    };
    for r in &rows {
        if !r.ok() {
            continue;
        }
        for v in violations(r) {
            bad.push(format!(
                "{} {} {} {}: {v}",
                r.algorithm, r.settings, r.dataset, r.viewpoint
            ));
        }
    }
    bad.extend(non_finite_cells(&out.join("results.csv")));
    bad.extend(non_finite_cells(
        &out.join(harness::results::samples::SAMPLES_CSV),
    ));
    (rows, bad)
}

#[test]
fn every_row_of_a_small_run_of_all_algorithms_has_consistent_times() {
    let dir = tempfile::tempdir().unwrap();
    let (out, cache) = (dir.path().join("out"), dir.path().join("cache"));
    let algorithms: Vec<&str> = harness::algorithms::names()
        .into_iter()
        .filter(|a| !harness::algorithms::is_peer(a))
        .collect();
    let cfg = config(&small_run(&out, &cache, &algorithms.join(",")));
    let filter = cfg.settings_filter.clone();
    let outcome = harness::run::run(&cfg, &|name: &str| {
        harness::algorithms::selected_variants(name, &filter)
    })
    .unwrap();
    assert!(outcome.all_ok(), "{outcome:?}");
    let (rows, bad) = run_violations(&out);
    for a in &algorithms {
        assert!(
            rows.iter().any(|r| r.algorithm == *a),
            "no row of {a} in the run"
        );
    }
    assert!(rows.iter().all(Row::ok));
    assert!(
        bad.is_empty(),
        "timing invariants broken:\n{}",
        bad.join("\n")
    );
    // The error columns were measured too (no NaN reached them: checked in the CSV above).
    assert!(rows.iter().all(|r| r.psnr_db.is_some_and(f64::is_finite)));
}

/// Makes one frame's reported times wrong.
type Fault = fn(&mut FrameStats);

/// A renderer whose reported times are wrong in one chosen way.
struct BadTimes {
    inner: Box<dyn Renderer>,
    fault: Fault,
}

impl Renderer for BadTimes {
    fn algorithm(&self) -> &'static str {
        self.inner.algorithm()
    }
    fn settings(&self) -> render_core::Settings {
        self.inner.settings()
    }
    fn prepare(
        &mut self,
        gpu: &Gpu,
        mesh: &std::sync::Arc<TetMesh>,
        optics: &Optics,
    ) -> anyhow::Result<Prepared> {
        self.inner.prepare(gpu, mesh, optics)
    }
    fn render(&mut self, gpu: &Gpu, camera: &Camera) -> anyhow::Result<FrameStats> {
        let mut s = self.inner.render(gpu, camera)?;
        (self.fault)(&mut s);
        Ok(s)
    }
    fn read_image(&mut self, gpu: &Gpu) -> anyhow::Result<Image> {
        self.inner.read_image(gpu)
    }
}

#[test]
fn a_negative_nan_or_inconsistent_time_is_caught() {
    let faults: [(&str, Fault); 5] = [
        ("negative cpu_ms", |s| s.cpu_ms = -1.0),
        ("NaN total_ms", |s| s.total_ms = f64::NAN),
        ("cpu_ms > total_ms", |s| s.cpu_ms = s.total_ms + 1.0),
        ("gpu_ms > total_ms", |s| {
            s.gpu_ms = Some(s.total_ms * 2.0 + 1.0)
        }),
        ("NaN gpu_ms", |s| s.gpu_ms = Some(f64::NAN)),
    ];
    for (what, fault) in faults {
        let dir = tempfile::tempdir().unwrap();
        let (out, cache) = (dir.path().join("out"), dir.path().join("cache"));
        let mut args = small_run(&out, &cache, "gator-pt");
        args.extend(["--settings", "variant=constant", "--no-reference"].map(String::from));
        let cfg = config(&args);
        let factory = move |name: &str| -> anyhow::Result<Vec<Box<dyn Renderer>>> {
            Ok(harness::algorithms::selected_variants(
                name,
                &harness::algorithms::SettingsFilter::parse("variant=constant")?,
            )?
            .into_iter()
            .map(|inner| Box::new(BadTimes { inner, fault }) as Box<dyn Renderer>)
            .collect())
        };
        let _ = harness::run::run(&cfg, &factory);
        let (rows, bad) = run_violations(&out);
        // Either the harness refused the row, or the checks above see the fault.
        let caught = !bad.is_empty() || (!rows.is_empty() && rows.iter().all(|r| !r.ok()));
        assert!(caught, "{what} went unnoticed: {rows:?}");
    }
}
