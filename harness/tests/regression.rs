//! Regression tracking end to end: two shards merged give the rows of one unsharded
//! run (timings aside), the shards partition the rows exactly, `compare` of the two finds no
//! image or memory change, and runs from different adapters are refused unless normalised.
//! Tiny meshes at 16² with the deterministic cell-projection algorithms, on any adapter.

use std::path::Path;
use std::process::Command;

use harness::results::{ResultsFile, Row};

fn tetbench(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_tetbench"))
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var_os("XDG_RUNTIME_DIR").unwrap_or_else(|| "/tmp".into()),
        )
        .args(args)
        .output()
        .expect("tetbench runs")
}

fn ok(args: &[&str]) -> String {
    let o = tetbench(args);
    assert!(
        o.status.success(),
        "tetbench {args:?} failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Everything of a row that does not depend on timing.
fn untimed(r: &Row) -> String {
    format!(
        "{} {} {} {} {} {}x{} hash={} psnr={:?} rmse={:?} bytes={:?}/{:?} counters={} err={}",
        r.algorithm,
        r.settings,
        r.dataset,
        r.tets,
        r.viewpoint,
        r.width,
        r.height,
        r.image_hash,
        r.psnr_db,
        r.rmse,
        r.gpu_bytes_persistent,
        r.gpu_bytes_frame,
        r.counters,
        r.error_text()
    )
}

#[test]
fn merged_shards_equal_one_run_and_compare_finds_no_change() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |s: &str| tmp.path().join(s).to_str().unwrap().to_string();
    let run = |out: &str, shard: Option<&str>| {
        let mut args = vec![
            "run",
            "--algorithms",
            "gator-pt,fragment-pt",
            "--settings",
            "sort=radix|bucket",
            "--datasets",
            "box:1k,shell:1k",
            "--viewpoints",
            "+x,-x-y+z",
            "--resolution",
            "16",
            "--frames",
            "2",
            "--warmup",
            "0",
            "--no-report",
            "--no-calibrate",
        ];
        let (o, c) = (p(out), p("cache"));
        args.extend(["--out", &o, "--cache-dir", &c]);
        if let Some(s) = shard {
            args.extend(["--shard", s]);
        }
        ok(&args);
        ResultsFile::read(Path::new(&o)).unwrap()
    };
    let full = run("full", None);
    let s1 = run("s1", Some("1/2"));
    let s2 = run("s2", Some("2/2"));
    assert!(full.rows.len() >= 16, "{}", full.rows.len());
    assert!(!s1.rows.is_empty() && !s2.rows.is_empty());
    assert_eq!(s1.run.shard.map(|s| s.to_string()).as_deref(), Some("1/2"));
    // Exact partition: every row of the full run in exactly one shard.
    let mut union: Vec<String> = s1.rows.iter().chain(&s2.rows).map(untimed).collect();
    let mut all: Vec<String> = full.rows.iter().map(untimed).collect();
    union.sort();
    all.sort();
    assert_eq!(union, all);
    for r in &full.rows {
        assert_eq!(r.samples.total_ms.len(), 2, "per-frame samples kept");
        assert!(!r.image_hash.is_empty() && !r.image_f32.is_empty());
    }

    // Rounds: the same rows in the same order, each with one sample per round.
    let rounds = {
        let (o, c) = (p("rounds"), p("cache"));
        ok(&[
            "run",
            "--algorithms",
            "gator-pt,fragment-pt",
            "--settings",
            "sort=radix|bucket",
            "--datasets",
            "box:1k,shell:1k",
            "--viewpoints",
            "+x,-x-y+z",
            "--resolution",
            "16",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--rounds",
            "3",
            "--no-report",
            "--no-calibrate",
            "--out",
            &o,
            "--cache-dir",
            &c,
        ]);
        ResultsFile::read(Path::new(&o)).unwrap()
    };
    assert_eq!(rounds.run.rounds, 3);
    assert_eq!(
        rounds.rows.iter().map(untimed).collect::<Vec<_>>(),
        full.rows.iter().map(untimed).collect::<Vec<_>>()
    );
    for r in &rounds.rows {
        assert_eq!(r.samples.total_ms.len(), 3, "one sample per round");
        assert_eq!(r.frames, 3);
    }

    let out = ok(&[
        "report",
        "--merge",
        &p("s1"),
        &p("s2"),
        "--out",
        &p("merged"),
    ]);
    assert!(out.contains("merged"), "{out}");
    let merged = ResultsFile::read(&tmp.path().join("merged")).unwrap();
    // Same rows in the same order as the unsharded run.
    let m: Vec<String> = merged.rows.iter().map(untimed).collect();
    let f: Vec<String> = full.rows.iter().map(untimed).collect();
    assert_eq!(m, f);
    assert_eq!(merged.run.merged_from.len(), 2);
    for r in &merged.rows {
        assert!(tmp.path().join("merged").join(&r.image_f32).is_file());
    }
    assert!(tmp.path().join("merged/samples.csv").is_file());
    assert!(tmp.path().join("merged/index.html").is_file());

    // compare: identical images, work counters and memory (timings may differ on a busy
    // machine; the gate here is on what is exact).
    let text = ok(&["compare", &p("full"), &p("merged"), "--out", &p("cmp")]);
    let cmp: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(tmp.path().join("cmp/compare.json")).unwrap(),
    )
    .unwrap();
    for row in cmp["rows"].as_array().unwrap() {
        assert_eq!(row["image"]["changed_pixels"], 0, "{text}");
        assert!(row["work"].as_array().unwrap().is_empty(), "{text}");
    }

    // Another adapter: refused unless normalised (and normalising needs a calibration).
    let mut other = merged.clone();
    other.machine.adapter.as_mut().unwrap().name = "Some Other GPU".into();
    std::fs::create_dir_all(tmp.path().join("other")).unwrap();
    harness::results::write_json(&tmp.path().join("other"), &other).unwrap();
    let o = tetbench(&["compare", &p("full"), &p("other"), "--out", &p("cmp2")]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--normalised"), "{err}");
    let o = tetbench(&[
        "compare",
        &p("full"),
        &p("other"),
        "--normalised",
        "--out",
        &p("cmp2"),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("calibration"));
}

/// A slow algorithm (a VTK peer, say) run on its own completes a run of the others: same data
/// sets, viewpoints, size, frames and transfer function on one machine merge into one matrix.
#[test]
fn runs_of_other_algorithms_on_one_machine_merge() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |s: &str| tmp.path().join(s).to_str().unwrap().to_string();
    let run = |out: &str, algorithm: &str, viewpoints: &str| {
        let (o, c) = (p(out), p("cache"));
        ok(&[
            "run",
            "--algorithms",
            algorithm,
            "--datasets",
            "box:1k",
            "--viewpoints",
            viewpoints,
            "--resolution",
            "16",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--no-report",
            "--no-calibrate",
            "--out",
            &o,
            "--cache-dir",
            &c,
        ]);
        ResultsFile::read(Path::new(&o)).unwrap()
    };
    let gator = run("gator", "gator-pt", "+x");
    let fpt = run("fpt", "fragment-pt", "+x");
    ok(&[
        "report",
        "--merge",
        &p("gator"),
        &p("fpt"),
        "--out",
        &p("both"),
    ]);
    let both = ResultsFile::read(&tmp.path().join("both")).unwrap();
    assert_eq!(both.run.algorithms, ["gator-pt", "fragment-pt"]);
    assert_eq!(both.rows.len(), gator.rows.len() + fpt.rows.len());
    let mut want: Vec<String> = gator.rows.iter().chain(&fpt.rows).map(untimed).collect();
    let mut got: Vec<String> = both.rows.iter().map(untimed).collect();
    want.sort();
    got.sort();
    assert_eq!(got, want);

    // Other viewpoints are another matrix: refused, naming both directories.
    run("other-view", "fragment-pt", "+y");
    let o = tetbench(&[
        "report",
        "--merge",
        &p("gator"),
        &p("other-view"),
        "--out",
        &p("bad"),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("different matrix") && err.contains("other-view"),
        "{err}"
    );

    // Other algorithms from another machine: refused.
    let mut elsewhere = fpt.clone();
    elsewhere.machine.cpu_model = "Some Other CPU".into();
    std::fs::create_dir_all(tmp.path().join("elsewhere")).unwrap();
    harness::results::write_json(&tmp.path().join("elsewhere"), &elsewhere).unwrap();
    let o = tetbench(&[
        "report",
        "--merge",
        &p("gator"),
        &p("elsewhere"),
        "--out",
        &p("bad2"),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("one machine"));
}
