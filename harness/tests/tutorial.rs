//! docs/tutorial.md, run as written. Every block fenced ```` ```sh ```` runs, in the page's
//! order, as its own `bash -euo pipefail` script in one fresh temporary directory that holds
//! the clone's `examples/` (a link, as a fresh clone has it), with this build's `tetbench` and
//! a `python3` that has numpy first on the PATH; then each step's output is checked.
//!
//! Blocks fenced ```` ```sh setup ```` are not run: they build `tetbench` and make a Python
//! environment, and this test brings both — Cargo's `CARGO_BIN_EXE_tetbench`, and VTK's
//! Python, which has numpy (`scripts/test.sh` installs it: `ensure_numpy_python`), or
//! `TETBENCH_VTK_PYTHON`. The last set-up block opens the site in a browser.
//!
//! The compare of two runs of the same code may exit 0, 3 (time judged slower: the machine's
//! noise) or 1 when compare says the runs are too noisy to gate on time, as the page and
//! docs/regression.md's exit codes allow; the compare against the broken renderer must exit 3.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use harness::results::ResultsFile;

/// One fenced block of the page: its info string and its text.
struct Block {
    info: String,
    body: String,
    line: usize,
}

fn page() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/tutorial.md")
}

/// The page's fenced blocks (``` fences; the info string is what follows the opening one).
fn blocks(text: &str) -> Vec<Block> {
    let mut out = vec![];
    let mut open: Option<Block> = None;
    for (i, line) in text.lines().enumerate() {
        match (&mut open, line.strip_prefix("```")) {
            (None, Some(info)) => {
                open = Some(Block {
                    info: info.trim().to_string(),
                    body: String::new(),
                    line: i + 1,
                })
            }
            (Some(_), Some(_)) => out.push(open.take().unwrap()),
            (Some(b), None) => {
                b.body.push_str(line);
                b.body.push('\n');
            }
            (None, None) => {}
        }
    }
    assert!(
        open.is_none(),
        "docs/tutorial.md: a code block is not closed"
    );
    out
}

/// Python with numpy, as tests/external_renderers.rs finds it.
fn python() -> PathBuf {
    let py = vtk_peer::process::python_interpreter();
    let ok = Command::new(&py)
        .args(["-c", "import numpy"])
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        ok,
        "{} cannot import numpy: run scripts/setup-vtk.sh (the tutorial's renderer needs numpy)",
        py.display()
    );
    py
}

/// A directory for the PATH with `tetbench` (this build) and `python3` (with numpy).
fn bin_dir(root: &Path) -> PathBuf {
    let bin = root.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_tetbench"), bin.join("tetbench")).unwrap();
    let wrapper = bin.join("python3");
    let script = format!("#!/bin/sh\nexec '{}' \"$@\"\n", python().display());
    std::fs::write(&wrapper, script).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&wrapper, std::fs::Permissions::from_mode(0o755)).unwrap();
    bin
}

/// What one block printed, stdout and stderr together.
struct Ran {
    output: String,
}

fn run_block(block: &Block, dir: &Path, path: &str, cache: &Path) -> Ran {
    let start = Instant::now();
    let out = Command::new("bash")
        .args(["-euo", "pipefail", "-c", &block.body])
        .current_dir(dir)
        .env("PATH", path)
        .env("TETBENCH_CACHE", cache)
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var_os("XDG_RUNTIME_DIR").unwrap_or_else(|| "/tmp".into()),
        )
        .output()
        .expect("bash runs");
    let output = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    eprintln!(
        "docs/tutorial.md:{}: {:.1} s\n{}",
        block.line,
        start.elapsed().as_secs_f64(),
        block.body
    );
    assert!(
        out.status.success(),
        "docs/tutorial.md:{}: the block exited with {}:\n{}\n--- output ---\n{output}",
        block.line,
        out.status,
        block.body
    );
    Ran { output }
}

/// The status a block printed as "compare exit status: N".
fn compare_status(ran: &Ran) -> i32 {
    let line = ran
        .output
        .lines()
        .find_map(|l| l.strip_prefix("compare exit status: "))
        .unwrap_or_else(|| panic!("no \"compare exit status\" line in:\n{}", ran.output));
    line.trim().parse().unwrap()
}

/// A run of the tutorial: HAVS's and GATOR's default variants and `mine`, one viewpoint, every
/// row measured with its image error.
fn check_run(dir: &Path) {
    let results = ResultsFile::read(dir).unwrap();
    let algorithms: std::collections::BTreeSet<&str> =
        results.rows.iter().map(|r| r.algorithm.as_str()).collect();
    assert_eq!(
        algorithms.into_iter().collect::<Vec<_>>(),
        ["gator-pt", "havs", "mine"],
        "{}",
        dir.display()
    );
    for row in &results.rows {
        assert!(row.ok(), "{}: {}", row.algorithm, row.error_text());
        assert!(
            row.tets_per_sec.is_some_and(|v| v > 0.0),
            "{}: no speed",
            row.algorithm
        );
        assert!(row.psnr_db.is_some(), "{}: no image error", row.algorithm);
        assert_eq!(row.dataset, "my-mesh.vtu");
    }
    assert!(results.errors.is_empty(), "{:?}", results.errors);
    assert!(dir.join("results.csv").is_file() && dir.join("index.html").is_file());
}

#[test]
fn the_tutorial_runs_as_written() {
    let text = std::fs::read_to_string(page()).unwrap();
    let all = blocks(&text);
    let setup = all.iter().filter(|b| b.info == "sh setup").count();
    assert_eq!(setup, 3, "the set-up blocks this test stands in for");
    let steps: Vec<&Block> = all.iter().filter(|b| b.info == "sh").collect();
    assert_eq!(
        steps.len(),
        8,
        "docs/tutorial.md has {} sh blocks; this test checks 8 steps: update both together",
        steps.len()
    );

    let tmp = tempfile::tempdir().unwrap();
    let work = tmp.path().join("clone");
    std::fs::create_dir(&work).unwrap();
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
    std::os::unix::fs::symlink(examples.canonicalize().unwrap(), work.join("examples")).unwrap();
    let bin = bin_dir(tmp.path());
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let cache = tmp.path().join("cache");
    let t = work.join("tutorial");
    let run = |i: usize| run_block(steps[i], &work, &path, &cache);

    // 1. The conformance check passes.
    let check = run(0);
    assert!(
        check.output.contains("conformance checks passed"),
        "{}",
        check.output
    );
    assert!(t.join("check").is_dir());

    // 2. The mesh as a .vtu, and its statistics.
    let info = run(1);
    let vtu = std::fs::metadata(t.join("my-mesh.vtu")).unwrap();
    assert!(vtu.len() > 0);
    assert!(info.output.contains("tets"), "{}", info.output);

    // 3. The run beside HAVS and GATOR, and its summary.
    run(2);
    check_run(&t.join("run-a"));
    run(3);
    let summary = std::fs::read_to_string(t.join("run-a/summary.md")).unwrap();
    assert!(summary.contains("mine") && summary.contains("havs"));

    // 4. The speed–error chart.
    run(4);
    assert!(t.join("charts/speed_error_my-mesh.vtu.png").is_file());

    // 5. Two runs of the same code: 0, or what the documented rule allows for time.
    let same = run(5);
    check_run(&t.join("run-b"));
    let status = compare_status(&same);
    assert!(
        status == 0 || status == 3 || (status == 1 && same.output.contains("too noisy")),
        "compare of two runs of the same code exited {status}:\n{}",
        same.output
    );
    assert!(t.join("run-b/compare/compare.json").is_file());
    // The broken renderer: its image is a regression, whatever the machine's load.
    let broken = run(6);
    assert_eq!(compare_status(&broken), 3, "{}", broken.output);
    assert!(
        broken
            .output
            .lines()
            .any(|l| l.contains("regression mine") && l.contains("image worse")),
        "{}",
        broken.output
    );

    // 6. The site.
    run(7);
    assert!(t.join("site/index.html").is_file());
}
