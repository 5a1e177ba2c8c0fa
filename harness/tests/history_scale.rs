//! The site at scale, in small: synthetic nightly runs made by `scripts/synthetic-history.sh`
//! from the committed lavapipe baseline (each row's time × U(0.9, 1.1), HAVS ×1.3 from run 5).
//!
//! - Published over 4 and over 8 runs, the site grows by less than 150 KB a run (the bound
//!   that keeps a thousand runs under 150 MB), and history.html holds no per-run number.
//! - The history finds the HAVS step at run 5 and lists it first; no other series has one.
//! - Publishing the same 8 runs again draws no page and compares no pair; a ninth run draws
//!   two pages (itself and the run before, which loses the full report) and compares one pair;
//!   the front page names the step.

use std::path::{Path, PathBuf};
use std::process::Command;

const TETBENCH: &str = env!("CARGO_BIN_EXE_tetbench");

/// The bound a run may add to the site.
const BYTES_PER_RUN: u64 = 150 * 1024;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn size(dir: &Path) -> u64 {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            if e.file_type().unwrap().is_dir() {
                size(&e.path())
            } else {
                e.metadata().unwrap().len()
            }
        })
        .sum()
}

/// `tetbench publish RUNS… --out SITE`; returns its last line.
fn publish(runs: &[PathBuf], site: &Path) -> String {
    let o = Command::new(TETBENCH)
        .arg("publish")
        .args(runs)
        .arg("--out")
        .arg(site)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "publish failed: {stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    stdout.trim().lines().last().unwrap_or_default().to_string()
}

#[test]
fn the_site_grows_by_less_than_the_bound_a_run_and_redraws_only_what_changed() {
    let tmp = Path::new(env!("CARGO_TARGET_TMPDIR")).join("history-scale");
    let _ = std::fs::remove_dir_all(&tmp);
    let runs_dir = tmp.join("runs");
    let o = Command::new("bash")
        .arg(repo().join("scripts/synthetic-history.sh"))
        .arg(repo().join("reports/baselines/llvmpipe-llvm-15-0-6-256-bits-2026-12-03"))
        .arg(&runs_dir)
        .args(["9", "--seed", "7", "--step-at", "5"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let runs: Vec<PathBuf> = (0..9)
        .map(|k| runs_dir.join(format!("run-{k:04}")))
        .collect();

    let (small, large) = (tmp.join("site-4"), tmp.join("site-8"));
    publish(&runs[..4], &small);
    let first = publish(&runs[..8], &large);
    assert!(first.contains("8 runs, 8 page(s) drawn"), "{first}");
    let per_run = (size(&large) - size(&small)) / 4;
    assert!(
        per_run <= BYTES_PER_RUN,
        "the site grows by {per_run} bytes a run (bound {BYTES_PER_RUN})"
    );
    let page = |site: &Path| {
        let dir = std::fs::read_dir(site.join("history"))
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .path();
        std::fs::read_to_string(dir.join("history.html")).unwrap()
    };
    // history.html holds no per-run number: no run is named but the first, the last and the
    // one where the step starts (the charts and the data files hold the rest).
    let page8 = page(&large);
    assert!(
        page8.len() < 64 * 1024,
        "history.html is {} bytes",
        page8.len()
    );

    // The step: in the HAVS series at run 5 (its commit), listed before any chart.
    let json_path = std::fs::read_dir(large.join("history"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path()
        .join("history.json");
    let h: harness::regress::history::History =
        serde_json::from_str(&std::fs::read_to_string(json_path).unwrap()).unwrap();
    let mut with_step = 0;
    for s in &h.series {
        let steps: Vec<usize> = s
            .points
            .iter()
            .filter(|p| p.step.is_some())
            .map(|p| p.run)
            .collect();
        if s.algorithm == "havs" {
            with_step += (steps == [5]) as usize;
        } else {
            assert!(
                steps.is_empty(),
                "{} {}: {steps:?}",
                s.algorithm,
                s.settings
            );
        }
    }
    assert!(
        with_step >= 6,
        "only {with_step} of 8 HAVS series have the step"
    );
    let commit5 = &h.runs[5].commit[..10];
    let (listed, chart) = (page8.find(commit5).unwrap(), page8.find("<object").unwrap());
    assert!(listed < chart);
    for k in [1, 2, 3, 4, 6] {
        let c = &h.runs[k].commit[..7];
        assert!(!page8.contains(c), "history.html names run {k} ({c})");
    }

    // Incremental: the same runs again, then one more.
    let again = publish(&runs[..8], &large);
    assert!(
        again.contains("0 page(s) drawn") && again.contains("0 pair(s) compared"),
        "{again}"
    );
    let more = publish(&runs, &large);
    assert!(
        more.contains("9 runs, 2 page(s) drawn, 7 kept; 1 pair(s) compared"),
        "{more}"
    );
    let front = std::fs::read_to_string(large.join("index.html")).unwrap();
    let changes = front.find("What changed").unwrap();
    assert!(
        front[changes..].contains(commit5),
        "the front page does not name the step"
    );
    // Run 7 lost its full report for a brief page; run 8 has the report.
    let brief = std::fs::read_to_string(large.join("runs/run-0007/index.html")).unwrap();
    assert!(brief.contains("results.json.gz") && brief.contains("../run-0008/index.html"));
    assert!(large.join("runs/run-0008/charts").is_dir());
    assert!(!large.join("runs/run-0007/charts").exists());
    // Fewer runs again: the folders of runs no longer given go.
    let fewer = publish(&runs[..3], &large);
    assert!(fewer.contains("6 old run folder(s) removed"), "{fewer}");
    assert!(!large.join("runs/run-0005").exists());
}
