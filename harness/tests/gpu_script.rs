//! `scripts/gpu.sh --allow-software` runs the scale and floor steps at reduced sizes on
//! lavapipe, and its output has the shape a GPU run's will have: a scale run per
//! resolution with every default algorithm on every data set, a floor per resolution with
//! every step, every algorithm on the tiny mesh, and gpu.md's tables of both.

use std::path::Path;
use std::process::Command;

use harness::calibrate::floor::Floor;
use harness::results::ResultsFile;

const TETBENCH: &str = env!("CARGO_BIN_EXE_tetbench");

#[test]
fn the_software_scale_and_floor_steps_have_their_shape() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("gpu");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let o = Command::new("bash")
        .arg(repo.join("scripts/gpu.sh"))
        .args([
            "--allow-software",
            "--bin",
            TETBENCH,
            "--quick",
            "--skip-peers",
        ])
        .args(["--skip-suite", "--rounds", "1", "--out"])
        .arg(&out)
        .env("TETBENCH_CACHE", dir.path().join("cache"))
        .current_dir(&repo)
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "gpu.sh failed:\n{log}");

    let algorithms: Vec<&str> = harness::algorithms::names()
        .into_iter()
        .filter(|a| !harness::algorithms::is_peer(a))
        .collect();
    let gpu_md = std::fs::read_to_string(out.join("gpu.md")).unwrap();
    for res in ["32", "64"] {
        // The scale run: every algorithm on both reduced data sets, measured, with a report.
        let run = out.join("scale").join(res);
        let file = ResultsFile::read(&run).unwrap();
        for a in &algorithms {
            for d in ["box:1k", "box:2k"] {
                assert!(
                    file.rows
                        .iter()
                        .any(|r| r.algorithm == *a && r.dataset == d && r.ok()),
                    "scale {res}: no row of {a} on {d}"
                );
            }
        }
        assert!(file.rows.iter().all(|r| r.width.to_string() == res));
        assert!(run.join("index.html").is_file(), "scale {res}: no report");
        // The floor: every step, and every algorithm on the tiny mesh.
        let floor: Floor = serde_json::from_str(
            &std::fs::read_to_string(out.join(format!("floor/floor-{res}.json"))).unwrap(),
        )
        .unwrap();
        assert_eq!(floor.width.to_string(), res);
        let steps: Vec<&str> = floor.steps.iter().map(|s| s.step.as_str()).collect();
        for s in [
            "submit",
            "submit + wait",
            "clear + wait",
            "64 empty render passes + wait",
            "64 empty compute passes + wait",
            "readback, reused buffer",
        ] {
            assert!(steps.contains(&s), "floor {res}: no {s} in {steps:?}");
        }
        let tiny = ResultsFile::read(&out.join(format!("floor/tiny-{res}"))).unwrap();
        for a in &algorithms {
            assert!(
                tiny.rows.iter().any(|r| r.algorithm == *a && r.ok()),
                "floor {res}: no tiny-mesh row of {a}"
            );
        }
        assert!(gpu_md.contains(&format!("at {res}², ")), "{gpu_md}");
        assert!(gpu_md.contains(&format!("| {res}² |")), "{gpu_md}");
    }
    assert!(gpu_md.contains("## Scale"), "{gpu_md}");
    assert!(gpu_md.contains("## Per-frame floor"), "{gpu_md}");
    assert!(gpu_md.contains("One empty pass: render "), "{gpu_md}");
    assert!(gpu_md.contains("| scale 32 |"), "{gpu_md}");
    assert!(!gpu_md.contains("failed"), "{gpu_md}");
}
