//! Regression tracking from the command line: `compare`'s exit status, the CI gate
//! (0 no regression, 3 a regression with `--fail-on regression`, 1 an error or a refused
//! comparison) and its stdout formats, `export`, and one run per output directory.
//! The compare and export tests use synthetic results sets (no GPU): eight groups of three
//! viewpoints, 5 rounds, one group made ×1.5 slower.

use std::path::Path;
use std::process::Command;

use harness::results::machine::MachineInfo;
use harness::results::{ResultsFile, Row, RunDescription, SCHEMA_VERSION};

/// A deterministic wobble of ±3 % (no RNG crate needed for a fixed pattern).
fn wobble(i: usize) -> f64 {
    1.0 + 0.03 * ((i * 7919 % 13) as f64 / 6.0 - 1.0)
}

fn results(dir: &Path, factors: &[f64], rounds: u32, adapter_cpu: &str) {
    std::fs::create_dir_all(dir).unwrap();
    let mut rows = vec![];
    let mut k = 0;
    for (i, f) in factors.iter().enumerate() {
        for vp in ["+x", "+x+y+z", "-x+y-z"] {
            let mut row = Row {
                algorithm: format!("alg{i}"),
                settings: "k=2".parse().unwrap(),
                dataset: "box:1k".into(),
                viewpoint: vp.into(),
                frames: rounds,
                ..Default::default()
            };
            for _ in 0..rounds {
                k += 1;
                row.samples.total_ms.push(10.0 * f * wobble(k));
            }
            row.total_ms = Some(row.samples.total_ms[0]);
            rows.push(row);
        }
    }
    let mut machine = MachineInfo::collect();
    machine.cpu_model = adapter_cpu.into();
    let file = ResultsFile {
        control: None,
        schema_version: SCHEMA_VERSION,
        machine,
        run: RunDescription {
            rounds,
            frames: 1,
            ..Default::default()
        },
        finished_utc: None,
        rows,
        errors: vec![],
    };
    harness::results::write_json(dir, &file).unwrap();
}

fn compare(base: &Path, new: &Path, out: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_tetbench"))
        .args(["compare", "--fail-on", "regression", "--out"])
        .arg(out)
        .arg(base)
        .arg(new)
        .output()
        .expect("tetbench runs")
}

#[test]
fn exit_status_tells_regression_from_error() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |s: &str| tmp.path().join(s);
    let mut slow = [1.0; 8];
    slow[2] = 1.5;
    results(&p("base"), &[1.0; 8], 5, "cpu A");
    results(&p("same"), &[1.0; 8], 5, "cpu A");
    results(&p("slow"), &slow, 5, "cpu A");
    results(&p("slow1"), &slow, 1, "cpu A");
    results(&p("base1"), &[1.0; 8], 1, "cpu A");

    let o = compare(&p("base"), &p("same"), &p("c0"));
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let o = compare(&p("base"), &p("slow"), &p("c3"));
    assert_eq!(o.status.code(), Some(3), "{o:?}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("REGRESSION"));
    // The same slowdown in one round: too few independent samples, no time gate.
    let o = compare(&p("base1"), &p("slow1"), &p("c1"));
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("too few independent samples (1 rounds"));
    // A missing results set is an error: 1, with a message naming it.
    let o = compare(&p("base"), &p("nowhere"), &p("ce"));
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("nowhere"));
    // A bad option is an error too: 1, as docs/regression.md says (clap's own would be 2).
    let o = Command::new(env!("CARGO_BIN_EXE_tetbench"))
        .args(["compare", "--fail-on", "sometimes"])
        .arg(p("base"))
        .arg(p("same"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("sometimes"));
    let o = Command::new(env!("CARGO_BIN_EXE_tetbench"))
        .args(["compare", "--no-such-option"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{o:?}");
}

/// `--version` names the commit the binary was built from and whether the tree was dirty.
#[test]
fn version_names_the_commit_and_the_dirty_flag() {
    let o = Command::new(env!("CARGO_BIN_EXE_tetbench"))
        .arg("--version")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let line = String::from_utf8_lossy(&o.stdout).to_string();
    let machine = MachineInfo::collect();
    let commit = machine.git_commit.expect("built in a git checkout");
    assert!(line.contains(&format!("commit {commit}")), "{line}");
    let state = if machine.git_dirty == Some(true) {
        "dirty"
    } else {
        "clean"
    };
    assert!(line.contains(state), "{line}");
}

/// A work counter one higher in NEW is a regression named by its counter, whatever the
/// times say; equal counters stay clean.
#[test]
fn one_more_fragment_fails_the_gate_and_equal_counts_pass() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |s: &str| tmp.path().join(s);
    for (name, fragments) in [("base", 1000.0), ("same", 1000.0), ("more", 1001.0)] {
        results(&p(name), &[1.0; 8], 5, "cpu A");
        let mut f = ResultsFile::read(&p(name)).unwrap();
        for r in &mut f.rows {
            r.counters.insert("fragments", fragments);
            r.counters.insert("triangles", 50.0);
        }
        harness::results::write_json(&p(name), &f).unwrap();
    }
    let o = compare(&p("base"), &p("same"), &p("c0"));
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let o = compare(&p("base"), &p("more"), &p("c3"));
    assert_eq!(o.status.code(), Some(3), "{o:?}");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("fragments 1000 → 1001 (×1.0010)"), "{out}");
}

/// Separate runs whose groups scatter around the run-wide factor as a busy machine's do:
/// compare says they are too noisy to gate on time and exits 1 (not 3) under `--fail-on
/// regression`; with `--fail-on never` it reports the same and exits 0. The same scatter
/// at a quarter of the size is judged.
#[test]
fn runs_too_noisy_to_gate_on_time_exit_1_with_the_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |s: &str| tmp.path().join(s);
    let scatter = [0.85, 1.2, 0.9, 1.15, 0.8, 1.25, 1.0, 1.1];
    let calm: Vec<f64> = scatter.iter().map(|f| 1.0 + (f - 1.0) / 4.0).collect();
    results(&p("base"), &[1.0; 8], 5, "cpu A");
    results(&p("busy"), &scatter, 5, "cpu A");
    results(&p("calm"), &calm, 5, "cpu A");
    let o = compare(&p("base"), &p("busy"), &p("c1"));
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("too noisy to gate on time"), "{err}");
    let o = Command::new(env!("CARGO_BIN_EXE_tetbench"))
        .args(["compare", "--out"])
        .arg(p("c0"))
        .arg(p("base"))
        .arg(p("busy"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("too noisy to gate on time"));
    let o = compare(&p("base"), &p("calm"), &p("c2"));
    assert_ne!(o.status.code(), Some(1), "{o:?}");
    assert!(!String::from_utf8_lossy(&o.stdout).contains("too noisy"));
}

/// `compare --format json|md` put the comparison itself on stdout; `export` prints BMF and
/// customSmallerIsBetter, one entry per row.
#[test]
fn compare_formats_and_exports_go_to_stdout() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |s: &str| tmp.path().join(s);
    let mut slow = [1.0; 8];
    slow[2] = 1.5;
    results(&p("base"), &[1.0; 8], 5, "cpu A");
    results(&p("slow"), &slow, 5, "cpu A");
    let out = |format: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_tetbench"))
            .args(["compare", "--format", format, "--out"])
            .arg(p(format))
            .arg(p("base"))
            .arg(p("slow"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{o:?}");
        String::from_utf8(o.stdout).unwrap()
    };
    let json: serde_json::Value = serde_json::from_str(&out("json")).unwrap();
    assert!(json["regressions"].as_array().unwrap().iter().any(|r| {
        r["group"] == "alg2 k=2 on box:1k" && r["metric"] == "total_ms" && r["verdict"] == "slower"
    }));
    let md = out("md");
    assert!(md.starts_with("# tetbench compare"), "{md}");
    assert!(
        md.contains("## Regressions") && md.contains("| alg2 |"),
        "{md}"
    );

    let export = |format: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_tetbench"))
            .args(["export", "--format", format])
            .arg(p("base"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{o:?}");
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()
    };
    let bmf = export("bmf");
    assert_eq!(bmf.as_object().unwrap().len(), 24);
    assert!(
        bmf["alg0/k=2/box:1k/+x/0x0"]["latency"]["value"]
            .as_f64()
            .unwrap()
            > 1e6
    );
    let gab = export("github-action-benchmark");
    assert_eq!(gab.as_array().unwrap().len(), 24);
    assert_eq!(gab[0]["unit"], "ms");
}

/// Two runs into one directory at once: the second refuses, naming the first by
/// its pid, and the first finishes with all its rows.
#[test]
fn a_second_run_into_a_busy_directory_refuses_and_nothing_is_lost() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let run = |frames: &str| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_tetbench"));
        c.env(
            "XDG_RUNTIME_DIR",
            std::env::var_os("XDG_RUNTIME_DIR").unwrap_or_else(|| "/tmp".into()),
        )
        .args([
            "run",
            "--algorithms",
            "gator-pt",
            "--settings",
            "sort=radix",
            "--datasets",
            "box:1k",
            "--viewpoints",
            "14",
            "--resolution",
            "16",
            "--frames",
            frames,
            "--warmup",
            "0",
            "--no-reference",
            "--no-report",
            "--no-calibrate",
            "--out",
        ])
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped());
        c
    };
    let mut first = run("400")
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Wait until the first run has taken the directory (its record is in the lock file).
    let lock = out.join(".tetbench-run.lock");
    let t0 = std::time::Instant::now();
    while !std::fs::read_to_string(&lock).is_ok_and(|s| s.contains("\"pid\"")) {
        assert!(
            t0.elapsed().as_secs() < 120,
            "the first run never took the lock"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let second = run("1").output().unwrap();
    let still_running = first.try_wait().unwrap().is_none();
    let err = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(1), "{err}");
    assert!(err.contains("in use by another tetbench run"), "{err}");
    assert!(err.contains(&format!("pid {}", first.id())), "{err}");
    assert!(
        still_running,
        "the first run ended before the second was tried"
    );
    let status = first.wait().unwrap();
    assert!(status.success());
    let f = harness::results::ResultsFile::read(&out).unwrap();
    let variants: std::collections::HashSet<String> =
        f.rows.iter().map(|r| r.settings.to_string()).collect();
    assert_eq!(
        f.rows.len(),
        14 * variants.len(),
        "every row of the first run"
    );
    assert!(f.rows.iter().all(|r| r.samples.total_ms.len() == 400));
    assert!(f.machine.load_average_end.is_some() || !Path::new("/proc/loadavg").exists());
}

/// `run --resume` after an interruption: the finished unit's rows are kept as they were (not
/// measured again), the missing unit is measured; another plan is refused, naming what differs.
#[test]
fn resume_keeps_finished_units_and_refuses_another_plan() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let run = |frames: &str, resume: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_tetbench"));
        c.env(
            "XDG_RUNTIME_DIR",
            std::env::var_os("XDG_RUNTIME_DIR").unwrap_or_else(|| "/tmp".into()),
        )
        .args([
            "run",
            "--algorithms",
            "gator-pt,fragment-pt",
            "--settings",
            "sort=radix",
            "--datasets",
            "box:1k",
            "--viewpoints",
            "+x,-y",
            "--resolution",
            "16",
            "--frames",
            frames,
            "--warmup",
            "0",
            "--no-reference",
            "--no-report",
            "--no-calibrate",
            "--out",
        ])
        .arg(&out);
        if resume {
            c.arg("--resume");
        }
        c.output().unwrap()
    };
    let first = run("1", false);
    assert!(first.status.success(), "{first:?}");
    let full = harness::results::ResultsFile::read(&out).unwrap();
    assert!(
        full.rows.len() >= 4 && full.rows.len().is_multiple_of(2),
        "{}",
        full.rows.len()
    );
    // An interrupted run: only the first unit (data set, algorithm, settings) finished, and
    // one row of the second.
    let unit = |r: &harness::results::Row| (r.algorithm.clone(), r.settings.clone());
    let mut cut = full.clone();
    cut.rows.truncate(3);
    assert_eq!(unit(&cut.rows[0]), unit(&cut.rows[1]));
    assert_ne!(unit(&cut.rows[1]), unit(&cut.rows[2]));
    cut.finished_utc = None;
    harness::results::write_json(&out, &cut).unwrap();

    let resumed = run("1", true);
    assert!(resumed.status.success(), "{resumed:?}");
    let err = String::from_utf8_lossy(&resumed.stderr);
    assert!(
        err.contains("--resume keeps 1 finished unit(s) (2 rows)"),
        "{err}"
    );
    let after = harness::results::ResultsFile::read(&out).unwrap();
    assert_eq!(after.rows.len(), full.rows.len());
    assert_eq!(
        after.rows[..2],
        cut.rows[..2],
        "kept rows are not measured again"
    );
    assert_ne!(
        after.rows[2], cut.rows[2],
        "a half-finished unit is measured again"
    );
    let units = |f: &[harness::results::Row]| {
        let mut u: Vec<_> = f.iter().map(|r| (unit(r), r.viewpoint.clone())).collect();
        u.sort();
        u
    };
    assert_eq!(units(&after.rows), units(&full.rows));
    assert!(after.rows.iter().all(|r| r.ok()));

    let other = run("2", true);
    assert_eq!(other.status.code(), Some(1));
    let err = String::from_utf8_lossy(&other.stderr);
    assert!(err.contains("frames: 1 before, 2 now"), "{err}");
    // Refused before touching anything.
    assert_eq!(
        harness::results::ResultsFile::read(&out).unwrap().rows,
        after.rows
    );
}
