//! External renderers (docs/external-renderers.md): both examples pass the conformance check
//! and render the default suite's meshes in a run; deliberately wrong variants fail the check
//! with the right words; a renderer that crashes and one that hangs fail their rows within the
//! timeout while the run goes on.
//!
//! The Python example needs numpy: it runs under VTK's Python (`.venv-vtk`, which has numpy;
//! `scripts/test.sh` installs it, see `ensure_numpy_python` in scripts/common.sh). The C example
//! is built here with the system `cc`.

use std::path::{Path, PathBuf};
use std::time::Duration;

use external_peer::conformance::{self, CheckReport};
use external_peer::{ExternalRenderer, ExternalSpec};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn gpu() -> render_core::Gpu {
    std::env::set_var(
        "XDG_RUNTIME_DIR",
        std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| "/tmp".into()),
    );
    render_core::Gpu::new().expect("a wgpu adapter (lavapipe: apt-get install mesa-vulkan-drivers)")
}

/// Python with numpy: VTK's (see the module doc).
fn python() -> String {
    let py = vtk_peer::process::python_interpreter();
    let ok = std::process::Command::new(&py)
        .args(["-c", "import numpy"])
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        ok,
        "{} cannot import numpy: run scripts/setup-vtk.sh (the Python example needs numpy)",
        py.display()
    );
    py.to_string_lossy().into_owned()
}

fn python_example(flags: &str) -> String {
    let script = root().join("examples/external/python/renderer.py");
    format!("'{}' '{}' {flags}", python(), script.display())
}

/// Builds the C example with `cc` into a fresh directory (kept alive by the returned guard).
fn c_example() -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    let exe = dir.path().join("renderer");
    let src = root().join("examples/external/c/renderer.c");
    let out = std::process::Command::new("cc")
        .args(["-O2", "-Wall", "-Werror", "-o"])
        .arg(&exe)
        .arg(&src)
        .arg("-lm")
        .output()
        .expect("the system C compiler `cc` (apt-get install gcc libc6-dev)");
    assert!(
        out.status.success(),
        "cc failed on {}:\n{}",
        src.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let cmd = format!("'{}'", exe.display());
    (dir, cmd)
}

fn check(command: &str) -> CheckReport {
    let mut spec = ExternalSpec::parse(&format!("checked={command}")).unwrap();
    spec.timeout = Duration::from_secs(120);
    let mut r = ExternalRenderer::new(spec);
    let report = conformance::check(&mut r, &gpu(), None).unwrap();
    eprintln!("{command}:\n{report}");
    report
}

#[test]
fn both_examples_pass_the_conformance_check() {
    let report = check(&python_example(""));
    assert!(report.passed(), "{report}");
    let (_dir, c) = c_example();
    let report = check(&c);
    assert!(report.passed(), "{report}");
    // Every view was compared (5 views and the timing line).
    assert_eq!(report.cases.len(), 6);
}

/// Each deliberately broken convention fails the check, and the check names that one; also
/// when the renderer declares the lowest accuracy the protocol allows (20 dB), which excuses
/// approximation, never a convention.
#[test]
fn wrong_examples_fail_with_the_right_message() {
    for (flag, words) in [
        ("--flip-rows", "image is upside down"),
        ("--straight-alpha", "colour is not premultiplied"),
        ("--mirror", "image is mirrored left-right"),
        ("--flip-rows --declare-accuracy", "image is upside down"),
        (
            "--straight-alpha --declare-accuracy",
            "colour is not premultiplied",
        ),
        (
            "--mirror --declare-accuracy",
            "image is mirrored left-right",
        ),
    ] {
        let report = check(&python_example(flag));
        assert!(!report.passed(), "{flag} passed:\n{report}");
        let named = report
            .failures()
            .filter(|c| c.message.starts_with(words))
            .count();
        // Every view with an image that shows the mistake names it (not the empty view).
        assert!(named >= 3, "{flag}: expected {words:?}:\n{report}");
    }
}

/// The correct example under the same declaration still passes, and says it was judged at it.
#[test]
fn a_declared_accuracy_is_reported_and_the_right_example_passes_under_it() {
    let report = check(&python_example("--declare-accuracy"));
    assert!(report.passed(), "{report}");
    assert!(report
        .cases
        .iter()
        .any(|c| c.name == "declared accuracy" && c.message.starts_with("20.0 dB")));
}

/// `tetbench run ARGS` in process; a run either fails or is done (it has no other outcome).
fn run_tetbench(args: &[&str]) -> anyhow::Result<()> {
    let mut all = vec!["tetbench", "run"];
    all.extend_from_slice(args);
    let outcome = harness::cli::main_with_args(all)?;
    assert_eq!(outcome, harness::cli::Outcome::Done);
    Ok(())
}

#[test]
fn examples_render_the_default_suite_meshes_in_a_run() {
    let out = tempfile::tempdir().unwrap();
    let (_dir, c) = c_example();
    let py = format!("py={}", python_example(""));
    let c = format!("c={c}");
    let datasets = harness::run::suite::DEFAULT_SUITE.datasets.join(",");
    let outdir = out.path().to_str().unwrap();
    let args = [
        "--external",
        &py,
        "--external",
        &c,
        "--algorithms",
        "py,c",
        "--datasets",
        &datasets,
        "--viewpoints",
        "+x+y+z",
        "--resolution",
        "64",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--rounds",
        "1",
        "--no-calibrate",
        "--no-report",
        "--out",
        outdir,
    ];
    run_tetbench(&args).unwrap();
    let file = harness::results::ResultsFile::read(out.path()).unwrap();
    assert_eq!(
        file.rows.len(),
        2 * harness::run::suite::DEFAULT_SUITE.datasets.len()
    );
    for row in &file.rows {
        assert!(
            row.ok(),
            "{} {}: {}",
            row.algorithm,
            row.dataset,
            row.error_text()
        );
        assert!(
            row.settings.keys().next() == Some("peer") && row.settings.is("peer", "external"),
            "{}",
            row.settings
        );
        let psnr = row.psnr_db.unwrap();
        eprintln!("{} on {}: PSNR {psnr:.1} dB", row.algorithm, row.dataset);
        assert!(
            psnr >= 35.0,
            "{} on {}: PSNR {psnr:.1} dB",
            row.algorithm,
            row.dataset
        );
        assert!(harness::algorithms::is_peer(&row.algorithm));
    }
}

/// A renderer that answers hello and prepare, then crashes or hangs on `render`.
const FAULTY: &str = r#"
import json, sys, time
mode = sys.argv[1]
for line in sys.stdin:
    kind = json.loads(line)["type"]
    if kind == "hello":
        out = {"type": "hello", "protocol": 1, "settings": {}}
    elif kind == "prepare":
        out = {"type": "prepared"}
    elif kind == "render" and mode == "crash":
        print("boom: a simulated crash", file=sys.stderr, flush=True)
        sys.exit(3)
    elif kind == "render":
        print("about to hang", file=sys.stderr, flush=True)
        time.sleep(3600)
    else:
        out = {"type": "bye"}
    print(json.dumps(out), flush=True)
"#;

#[test]
fn a_crash_and_a_hang_fail_their_rows_and_the_run_goes_on() {
    let out = tempfile::tempdir().unwrap();
    let script = out.path().join("faulty.py");
    std::fs::write(&script, FAULTY).unwrap();
    let (_dir, c) = c_example();
    let crash = format!("crash=python3 '{}' crash", script.display());
    let hang = format!("hang=python3 '{}' hang", script.display());
    let good = format!("c={c}");
    let runs = out.path().join("run");
    let result = run_tetbench(&[
        "--external",
        &crash,
        "--external",
        &hang,
        "--external",
        &good,
        "--algorithms",
        "crash,hang,c",
        "--datasets",
        "box:1k",
        "--viewpoints",
        "+x,-y",
        "--resolution",
        "32",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--rounds",
        "1",
        "--no-calibrate",
        "--no-report",
        // Long enough for python3 to start and answer `hello` on a loaded 2-core machine: with
        // 2 s the crash case once failed its `hello` while a build ran beside the tests.
        "--external-timeout",
        "8",
        "--out",
        runs.to_str().unwrap(),
    ]);
    let err = result
        .expect_err("failed rows make the run's exit status non-zero")
        .to_string();
    assert!(err.contains("4 of 6 rows failed"), "{err}");
    let file = harness::results::ResultsFile::read(&runs).unwrap();
    assert_eq!(file.rows.len(), 6);
    for row in &file.rows {
        match row.algorithm.as_str() {
            "crash" => {
                assert!(
                    row.error_text().contains("exited (exit status: 3)"),
                    "{}",
                    row.error_text()
                );
                assert!(
                    row.error_text().contains("boom: a simulated crash"),
                    "{}",
                    row.error_text()
                );
            }
            "hang" => {
                assert!(
                    row.error_text()
                        .contains("did not answer `render` within 8 s"),
                    "{}",
                    row.error_text()
                );
                assert!(
                    row.error_text().contains("about to hang"),
                    "{}",
                    row.error_text()
                );
            }
            _ => assert!(row.ok() && row.psnr_db.is_some(), "{}", row.error_text()),
        }
    }
}
