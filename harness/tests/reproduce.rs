//! `tetbench reproduce` end to end: GATOR's quick plan on small generated meshes (substituted
//! for the paper's data sets) writes a report with the paper's values beside ours, the exact
//! truth-table verdict, the claims with their verdicts, every table's cells counted, the charts
//! and the index; a paper whose
//! algorithm is not built in fails clearly.

use std::process::Command;

fn tetbench() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_tetbench"));
    c.env(
        "XDG_RUNTIME_DIR",
        std::env::var_os("XDG_RUNTIME_DIR").unwrap_or_else(|| "/tmp".into()),
    );
    c
}

#[test]
fn quick_gator_reproduction_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let out = tetbench()
        .args([
            "reproduce",
            "gator",
            "--quick",
            "--resolution",
            "32",
            "--substitute",
            "bluntfin=box:2k,post=shell:2k,deltawing=box:3k",
            // A developer's tree may be dirty; the report must then say so.
            "--allow-dirty",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let report = std::fs::read_to_string(dir.path().join("gator/report.md")).unwrap();
    // The paper's values are printed (Table 3's rates, Table 2's counts) ...
    for v in ["937000", "493000", "1005675", "40960"] {
        assert!(report.contains(v), "paper value {v} missing:\n{report}");
    }
    // ... the truth table is compared exactly and matches ...
    assert!(
        report.contains("Every observed outcome fits exactly one paper row"),
        "{report}"
    );
    // ... ours is measured on every data set (no empty GATOR cell) ...
    assert!(!report.contains("not measured"), "{report}");
    assert!(
        report.contains("llvmpipe") || report.contains("adapter "),
        "{report}"
    );
    // ... the claims are listed with verdicts and the commit is named, and the HTML, charts
    // and the index (written from the same summaries) exist.
    assert!(
        report.contains("**G1**") && report.contains("| holds"),
        "{report}"
    );
    assert!(report.contains("Linear cells are slower"), "{report}");
    assert!(report.contains("commit `"), "{report}");
    // ... every table's cells are counted beside the claims, in the report, its typed summary
    // and the index ...
    assert!(
        report.contains("Cells of the paper's tables: ")
            && report.contains("## Cells outside their rule"),
        "{report}"
    );
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("gator/summary.json")).unwrap(),
    )
    .unwrap();
    let cells = &summary["cells"];
    assert!(
        cells["within"].as_u64().unwrap() + cells["outside"].as_u64().unwrap() > 0
            && cells["on_this_adapter"].as_u64().unwrap() > 0,
        "{summary}"
    );
    let index = std::fs::read_to_string(dir.path().join("README.md")).unwrap();
    assert!(index.contains("| gator | quick |"), "{index}");
    assert!(index.contains("cells within the rule"), "{index}");
    assert!(dir.path().join("index.html").is_file());
    let html = std::fs::read_to_string(dir.path().join("gator/report.html")).unwrap();
    assert!(html.contains("<table>"));
    assert!(dir
        .path()
        .join("gator/charts/table3_constant_tets_s.png")
        .is_file());
    assert!(dir.path().join("gator/runs/gator/results.csv").is_file());
}

#[test]
fn a_paper_whose_algorithm_is_missing_fails_clearly() {
    // Whichever paper's algorithm this build lacks (from the algorithm table); none: nothing
    // to check.
    let Some(paper) = harness::papers::PAPERS
        .iter()
        .map(|p| p.paper())
        .find(|p| !harness::papers::session::built_in(p.algorithm))
    else {
        return;
    };
    let out = tetbench()
        .args(["reproduce", paper.id, "--quick", "--out", "/nonexistent/x"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    let want = format!("algorithm {} is not built in", paper.algorithm);
    assert!(err.contains(&want) && err.contains("gator-pt"), "{err}");
}
