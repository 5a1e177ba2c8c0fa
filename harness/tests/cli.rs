//! The `tetbench` binary end to end: a tiny run writes results, images and the report; bad
//! arguments and missing data sets fail clearly; a killed run keeps its finished rows.
//! GPU work runs on whatever adapter there is (Mesa lavapipe on CI), on a 2k-tet mesh at 32².

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use harness::results::{ResultsFile, Row, REQUIRED_COLUMNS, SCHEMA_VERSION};

fn tetbench() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_tetbench"));
    c.env(
        "XDG_RUNTIME_DIR",
        std::env::var_os("XDG_RUNTIME_DIR").unwrap_or_else(|| "/tmp".into()),
    );
    c
}

fn run_ok(args: &[&str]) -> Output {
    let out = tetbench().args(args).output().expect("tetbench runs");
    assert!(
        out.status.success(),
        "tetbench {args:?} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn run_err(args: &[&str]) -> String {
    let out = tetbench().args(args).output().expect("tetbench runs");
    assert!(!out.status.success(), "tetbench {args:?} should fail");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// results.json and results.csv hold the same rows (floats to within parsing round-off:
/// serde_json's fast float parser may differ from the CSV's in the last bit).
fn assert_same_rows(json: &[Row], csv: &[Row]) {
    assert_eq!(json.len(), csv.len());
    let close = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() <= 1e-12 * a.abs().max(b.abs()),
        (a, b) => a == b,
    };
    for (j, c) in json.iter().zip(csv) {
        let key = |r: &Row| {
            (
                r.algorithm.clone(),
                // CSV holds the text; its values are typed by inference when read back.
                r.settings.to_string(),
                r.dataset.clone(),
                r.viewpoint.clone(),
                r.tets,
                r.image.clone(),
                r.error.clone(),
            )
        };
        assert_eq!(key(j), key(c));
        for (a, b) in [
            (j.total_ms, c.total_ms),
            (j.tets_per_sec, c.tets_per_sec),
            (j.psnr_db, c.psnr_db),
            (j.rmse, c.rmse),
            (j.gpu_ms, c.gpu_ms),
        ] {
            assert!(close(a, b), "{a:?} vs {b:?} in {j:?}");
        }
        assert_eq!(j.gpu_bytes, c.gpu_bytes);
    }
}

fn csv_rows(path: &Path) -> (Vec<String>, Vec<Row>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().iter().map(str::to_string).collect();
    let rows = r.deserialize().collect::<Result<Vec<Row>, _>>().unwrap();
    (header, rows)
}

#[test]
fn tiny_run_writes_results_images_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let cache = dir.path().join("cache");
    let (o, c) = (out.to_str().unwrap(), cache.to_str().unwrap());
    run_ok(&[
        "run",
        "--datasets",
        "box:2k",
        "--viewpoints",
        "orbit:2",
        "--resolution",
        "32",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--out",
        o,
        "--cache-dir",
        c,
    ]);

    let (header, rows) = csv_rows(&out.join("results.csv"));
    for col in REQUIRED_COLUMNS {
        assert!(
            header.iter().any(|h| h == col),
            "results.csv lacks column {col}"
        );
    }
    // Peers (VTK) run only with --peers.
    let algorithms = harness::algorithms::names();
    let variants: usize = algorithms
        .iter()
        .filter(|a| !harness::algorithms::is_peer(a))
        .map(|a| harness::algorithms::variants(a).unwrap().len())
        .sum();
    assert_eq!(
        rows.len(),
        2 * variants,
        "one row per variant and viewpoint"
    );
    for r in &rows {
        assert!(r.ok(), "row failed: {r:?}");
        assert_eq!(
            (r.width, r.height, r.dataset.as_str(), r.frames),
            (32, 32, "box:2k", 2)
        );
        assert!(r.tets > 1000, "{}", r.tets);
        assert!(r.tets_per_sec.unwrap() > 0.0 && r.fps.unwrap() > 0.0);
        let t = r.total_ms.unwrap();
        assert!(r.total_ms_min.unwrap() <= t && t <= r.total_ms_max.unwrap());
        assert!(r.gpu_bytes.unwrap() > 0 && r.bytes_per_tet.unwrap() > 0.0);
        let psnr = r.psnr_db.unwrap();
        assert!(psnr.is_finite() && psnr > 0.0, "{psnr}");
        assert!(r.rmse.unwrap() >= 0.0 && (0.0..=1.0).contains(&r.bad_pixel_share.unwrap()));
        assert!(!r.adapter.is_empty() && !r.backend.is_empty());
        for img in [&r.image, &r.heatmap, &r.reference_image] {
            let png = image::open(out.join(img)).unwrap_or_else(|e| panic!("{img}: {e}"));
            assert_eq!((png.width(), png.height()), (32, 32));
        }
    }
    for a in algorithms
        .iter()
        .filter(|a| !harness::algorithms::is_peer(a))
    {
        assert!(rows.iter().any(|r| &r.algorithm == a), "no rows for {a}");
    }

    let json = ResultsFile::read(&out).unwrap();
    assert_eq!(json.schema_version, SCHEMA_VERSION);
    assert_same_rows(&json.rows, &rows);
    assert!(json.finished_utc.is_some());
    assert!(json.machine.adapter.is_some() && json.machine.cpu_cores >= 1);
    // The control beside the rows: a sample before every round of the data set and one after
    // the last, each with a figure of every control probe, and every row priced by the control
    // of its own rounds.
    let control = json
        .control
        .as_ref()
        .expect("a calibrated run has a control");
    let rounds = json.run.rounds.max(1);
    let taken: Vec<u32> = control.samples.iter().map(|s| s.round).collect();
    if rounds > 1 {
        assert_eq!(taken, (0..=rounds).collect::<Vec<_>>());
    } else {
        assert!(taken.len() >= 2 && taken.last() == Some(&1), "{taken:?}");
    }
    let figures = control.samples[0].figures.len();
    assert!(figures >= 8, "{:?}", control.samples[0].figures);
    for r in &json.rows {
        assert_eq!(
            r.round_control.len(),
            rounds as usize,
            "{} {}",
            r.algorithm,
            r.settings
        );
        assert!(r.control_factor.is_some_and(|f| f > 0.0));
        assert!(
            r.priced_with.to_string().starts_with("control"),
            "{}: {}",
            r.algorithm,
            r.priced_with
        );
    }

    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for r in &rows {
        assert!(
            html.contains(&r.image)
                && html.contains(&r.heatmap)
                && html.contains(&r.reference_image)
        );
    }
    assert!(html.contains("charts/tets_per_sec.png") && html.contains("charts/psnr.png"));
    for chart in [
        "tets_per_sec.png",
        "tets_per_sec.svg",
        "psnr.png",
        "psnr.svg",
    ] {
        assert!(out.join("charts").join(chart).is_file(), "{chart}");
    }

    // `tetbench report` redoes the report from results.json alone.
    std::fs::remove_file(out.join("index.html")).unwrap();
    std::fs::remove_dir_all(out.join("charts")).unwrap();
    run_ok(&["report", o]);
    assert!(out.join("index.html").is_file() && out.join("charts/psnr.png").is_file());

    // `tetbench analyze summary` tabulates it.
    let s = run_ok(&["analyze", "summary", o]);
    assert!(String::from_utf8_lossy(&s.stdout).contains("| box:2k |"));
}

#[test]
fn bad_arguments_fail_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (
            &["run", "--algorithms", "no-such-algo", "--out", o],
            "unknown algorithm \"no-such-algo\"",
        ),
        (&["run", "--resolution", "0", "--out", o], "--resolution"),
        (&["run", "--frames", "0", "--out", o], "--frames"),
        (
            &["run", "--frames", "many", "--out", o],
            "invalid value 'many'",
        ),
        (&["run", "--viewpoints", "orbit:x", "--out", o], "orbit:N"),
        (
            &["run", "--viewpoints", "+w", "--out", o],
            "unknown viewpoint",
        ),
        (&["run", "--tf", "/no/such/tf.json", "--out", o], "--tf"),
        (&["run", "--settings", "variant", "--out", o], "key=value"),
        (
            &["run", "--settings", "colour=red", "--out", o],
            "no algorithm has the setting",
        ),
        (&["report", "/no/such/dir"], "results.json"),
        (&["frobnicate"], "unrecognized subcommand"),
    ];
    for (args, want) in cases {
        let err = run_err(args);
        assert!(
            err.contains(want),
            "tetbench {args:?}: expected {want:?} in:\n{err}"
        );
        assert!(
            !err.contains("panicked"),
            "tetbench {args:?} panicked:\n{err}"
        );
    }
}

#[test]
fn missing_dataset_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let err = run_err(&[
        "run",
        "--datasets",
        "box:1k,no-such-dataset-xyz",
        "--resolution",
        "16",
        "--frames",
        "1",
        "--out",
        out.to_str().unwrap(),
        "--no-reference",
    ]);
    assert!(err.contains("no-such-dataset-xyz"), "{err}");
    assert!(err.contains("tetbench datasets list"), "{err}");
    assert!(err.contains("nothing was measured"), "{err}");
    assert!(!err.contains("rows failed"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    // Refused before anything ran: not even box:1k was measured.
    assert!(!out.join("results.json").exists());
}

/// a `--settings` value that no variant of an asked-for algorithm has is an error
/// naming the algorithm, the key, the value and what it offers — never a silently dropped
/// algorithm.
#[test]
fn a_settings_typo_never_drops_an_algorithm() {
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().to_str().unwrap();
    for args in [
        &[
            "run",
            "--datasets",
            "box:1k",
            "--algorithms",
            "havs,gator-pt",
            "--settings",
            "k=7",
            "--out",
            o,
        ][..],
        &["run", "--settings", "k=abc", "--out", o][..],
        &[
            "run",
            "--datasets",
            "box:1k",
            "--algorithms",
            "havs",
            "--settings",
            "k=2|7",
            "--out",
            o,
        ][..],
    ] {
        let err = run_err(args);
        assert!(
            err.contains("havs has no variant with k="),
            "{args:?}: {err}"
        );
        assert!(
            err.contains("it offers k=1|2|3|4|5|6|8|16"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("rows failed"), "{args:?}: {err}");
        assert!(
            !dir.path().join("results.json").exists(),
            "{args:?} ran rows"
        );
    }
}

/// an allocation past the adapter's limits fails its rows with the bytes needed and
/// the limit (checked before wgpu sees it), and the run exits non-zero.
#[test]
fn an_oversized_viewport_fails_rows_with_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let err = run_err(&[
        "run",
        "--resolution",
        "9000",
        "--algorithms",
        "havs",
        "--settings",
        "k=2;sort=cpu-radix",
        "--datasets",
        "box:1k",
        "--viewpoints",
        "+x",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--no-reference",
        "--no-report",
        "--out",
        o,
    ]);
    assert!(err.contains("1 of 1 rows failed"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let json = ResultsFile::read(&out).unwrap();
    let e = json.rows[0].error_text();
    assert!(e.contains("needs 2592000000 bytes"), "{e}");
    assert!(e.contains("the adapter allows"), "{e}");
    assert!(!e.contains("panicked") && !e.contains("Validation"), "{e}");
}

/// A run killed in the middle (as by a crash or Ctrl-C) keeps every finished row, in both
/// files, readable.
#[test]
fn killed_run_keeps_finished_rows() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut child = tetbench()
        .args([
            "run",
            "--datasets",
            "box:2k",
            "--viewpoints",
            "orbit:5000",
            "--resolution",
            "16",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--no-reference",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let csv_path = out.join("results.csv");
    let start = Instant::now();
    loop {
        let lines = std::fs::read_to_string(&csv_path)
            .map(|s| s.lines().count())
            .unwrap_or(0);
        if lines >= 4 {
            break;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "run ended before it could be interrupted"
        );
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "no rows after 300 s"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();

    let (_, csv) = csv_rows(&csv_path);
    assert!(csv.len() >= 3);
    let json = ResultsFile::read(&out).unwrap();
    assert!(json.finished_utc.is_none(), "the run was interrupted");
    // JSON is rewritten right after each CSV line: at most the row in flight differs.
    assert!(json.rows.len() + 1 >= csv.len() && json.rows.len() <= csv.len());
    assert_same_rows(&json.rows, &csv[..json.rows.len()]);
    assert!(csv.iter().all(|r| r.ok() && r.tets_per_sec.unwrap() > 0.0));
}

/// on the default suite's non-convex mesh (`shell:10k`, rebuilt without slivers)
/// every default variant of every algorithm is at least 40 dB from the exact reference (RMSE ≤
/// 1 %: `suspect::FINE_DB`, so none is suspect), and the ray caster with the 3D table and no
/// early termination — exact order, exact segments — reaches 90 dB.
#[test]
fn every_algorithm_is_close_to_the_reference_on_the_non_convex_suite_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let cache = dir.path().join("cache");
    run_ok(&[
        "run",
        "--datasets",
        "shell:10k",
        "--viewpoints",
        "+x+y+z",
        "--resolution",
        "48",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--no-report",
        "--no-calibrate",
        "--strict",
        "--out",
        out.to_str().unwrap(),
        "--cache-dir",
        cache.to_str().unwrap(),
    ]);
    let json = ResultsFile::read(&out).unwrap();
    assert!(!json.rows.is_empty());
    for r in &json.rows {
        let p = r.psnr_db.unwrap_or(f64::NAN);
        eprintln!("{} {}: {p:.1} dB", r.algorithm, r.settings);
        assert!(
            p >= 40.0,
            "{} {}: {p} dB on shell:10k",
            r.algorithm,
            r.settings
        );
        assert!(r.suspect.is_none(), "{}: {:?}", r.algorithm, r.suspect);
        if r.algorithm == "raycast" && r.settings.is("table", "3d") && r.settings.is("et", "off") {
            assert!(p >= 90.0, "exact ray caster at {p} dB");
        }
    }
}
