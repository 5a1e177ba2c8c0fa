//! `tetbench ab` and `tetbench bisect` from the command line.
//!
//! Most sides are stand-in "binaries": a Python script that answers `run … --out DIR` with a
//! results.json made from a template, its frame times multiplied by a chosen slowdown for one
//! algorithm (and ±3 % of noise), so an A/B or a whole bisection takes a second or two. One
//! test runs the real tetbench binary on both sides of a tiny matrix. The bisection runs on a
//! scratch git repository whose commits hold such scripts, slow from commit k on.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use harness::results::machine::MachineInfo;
use harness::results::{ResultsFile, Row, RunDescription, SCHEMA_VERSION};

const GROUPS: usize = 8;

/// One round of eight algorithms × three viewpoints, one frame each.
fn template(dir: &Path) -> PathBuf {
    let mut rows = vec![];
    for i in 0..GROUPS {
        for vp in ["+x", "+x+y+z", "-x+y-z"] {
            let mut row = Row {
                algorithm: format!("alg{i}"),
                settings: "k=2".parse().unwrap(),
                dataset: "box:1k".into(),
                viewpoint: vp.into(),
                frames: 1,
                total_ms: Some(10.0 + i as f64),
                ..Default::default()
            };
            row.samples.total_ms = vec![10.0 + i as f64];
            rows.push(row);
        }
    }
    let file = ResultsFile {
        control: None,
        schema_version: SCHEMA_VERSION,
        machine: MachineInfo::collect(),
        run: RunDescription {
            rounds: 1,
            frames: 1,
            ..Default::default()
        },
        finished_utc: None,
        rows,
        errors: vec![],
    };
    harness::results::write_json(dir, &file).unwrap();
    dir.join("results.json")
}

/// The stand-in binary: `alg2`'s frames × `slowdown`, every frame ±3 %; it records its
/// arguments beside the results.
fn fake_binary_text(template: &Path, slowdown: f64) -> String {
    format!(
        r#"#!/usr/bin/env python3
import json, os, random, sys
args = sys.argv[1:]
assert args[0] == "run", args
out = args[args.index("--out") + 1]
t = json.load(open({template:?}))
for r in t["rows"]:
    f = {slowdown} if r["algorithm"] == "alg2" else 1.0
    r["samples"]["total_ms"] = [x * f * random.uniform(0.97, 1.03) for x in r["samples"]["total_ms"]]
os.makedirs(out, exist_ok=True)
json.dump(t, open(os.path.join(out, "results.json"), "w"))
open(os.path.join(out, "args.txt"), "w").write("\n".join(args))
"#,
        template = template.display().to_string()
    )
}

fn write_executable(path: &Path, text: &str) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::write(path, text).unwrap();
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

fn tetbench(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tetbench"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("tetbench runs")
}

/// Validates a written JSON output against its committed schema (`docs/NAME.schema.json`).
fn assert_valid(name: &str, value: &serde_json::Value) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../docs/{name}.schema.json"));
    let schema: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let url = format!("file:///{name}.schema.json");
    let (mut compiler, mut schemas) = (boon::Compiler::new(), boon::Schemas::new());
    compiler.add_resource(&url, schema).unwrap();
    let index = compiler.compile(&url, &mut schemas).unwrap();
    if let Err(e) = schemas.validate(value, index) {
        panic!("{name}.json does not fit docs/{name}.schema.json: {e:#}");
    }
}

fn text(o: &Output) -> String {
    format!(
        "status {:?}\n--- stdout\n{}\n--- stderr\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Two binaries: the same code gives exit 0, alg2 made ×1.5 slower exit 3 naming it (its
/// group and its rows); the output shows each pair's drift; the matrix options and
/// `--rounds 1` reach every round; too few pairs and an unknown side are errors (1).
#[test]
fn ab_of_two_binaries_gates_like_compare() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |s: &str| tmp.path().join(s);
    let t = template(tmp.path());
    write_executable(&p("a.py"), &fake_binary_text(&t, 1.0));
    write_executable(&p("b.py"), &fake_binary_text(&t, 1.0));
    write_executable(&p("slow.py"), &fake_binary_text(&t, 1.5));

    let same = tetbench(
        &[
            "ab",
            "a.py",
            "b.py",
            "--pairs",
            "4",
            "--out",
            "same",
            "--algorithms",
            "alg0,alg2",
        ],
        tmp.path(),
    );
    assert_eq!(same.status.code(), Some(0), "{}", text(&same));
    let out = String::from_utf8_lossy(&same.stdout);
    assert!(out.contains("pair  1 (BASE, NEW): NEW/BASE ×"), "{out}");
    assert!(out.contains("pair  4 (NEW, BASE)"), "{out}");
    // Piped: a line per round with its count, the ETA until the last.
    let err = String::from_utf8_lossy(&same.stderr);
    assert!(err.contains("tetbench ab: [1/8, ETA "), "{err}");
    assert!(err.contains("tetbench ab: [8/8] pair 4"), "{err}");
    assert!(
        out.contains("samples: one per round (4 rounds in BASE, 4 in NEW)"),
        "{out}"
    );
    let args = std::fs::read_to_string(p("same/new/round-03/args.txt")).unwrap();
    assert_eq!(
        args.lines().collect::<Vec<_>>(),
        [
            "run",
            "--algorithms",
            "alg0,alg2",
            "--rounds",
            "1",
            "--no-report",
            "--out",
            "same/new/round-03"
        ]
    );
    let merged = ResultsFile::read(&p("same/base")).unwrap();
    assert_eq!(merged.run.rounds, 4);
    assert!(merged.rows.iter().all(|r| r.samples.total_ms.len() == 4));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("same/ab.json")).unwrap()).unwrap();
    assert_eq!(report["drift"].as_array().unwrap().len(), 4);
    assert_valid("ab", &report);
    assert!(p("same/compare/compare.html").is_file());

    let slow = tetbench(
        &["ab", "a.py", "slow.py", "--pairs", "4", "--out", "slow"],
        tmp.path(),
    );
    assert_eq!(slow.status.code(), Some(3), "{}", text(&slow));
    let out = String::from_utf8_lossy(&slow.stdout);
    assert!(
        out.contains("regression: slower: alg2 k=2 on box:1k"),
        "{out}"
    );
    // The group and its three rows (paired rounds judge rows by the paired t-test too), and
    // nothing of the unchanged algorithms.
    assert_eq!(out.matches("regression: ").count(), 4, "{out}");
    assert_eq!(
        out.matches("regression: alg2 k=2 box:1k ").count(),
        3,
        "{out}"
    );
    // --fail-on never reports it and exits 0.
    let never = tetbench(
        &[
            "ab",
            "a.py",
            "slow.py",
            "--pairs",
            "3",
            "--out",
            "never",
            "--fail-on",
            "never",
        ],
        tmp.path(),
    );
    assert_eq!(never.status.code(), Some(0), "{}", text(&never));
    assert!(String::from_utf8_lossy(&never.stdout).contains("REGRESSION"));

    let few = tetbench(
        &["ab", "a.py", "b.py", "--pairs", "2", "--out", "few"],
        tmp.path(),
    );
    assert_eq!(few.status.code(), Some(1), "{}", text(&few));
    assert!(String::from_utf8_lossy(&few.stderr).contains("--pairs 2"));
    let unknown = tetbench(
        &[
            "ab",
            "a.py",
            "no-such-thing",
            "--repo",
            ".",
            "--out",
            "unknown",
        ],
        tmp.path(),
    );
    assert_eq!(unknown.status.code(), Some(1), "{}", text(&unknown));
    assert!(String::from_utf8_lossy(&unknown.stderr)
        .contains("no-such-thing is neither a tetbench binary"));
}

/// A side whose run fails without results stops the A/B with status 1 and the end of its log.
#[test]
fn a_side_that_fails_is_an_error_with_its_log() {
    let tmp = tempfile::tempdir().unwrap();
    let t = template(tmp.path());
    write_executable(&tmp.path().join("a.py"), &fake_binary_text(&t, 1.0));
    write_executable(
        &tmp.path().join("broken.sh"),
        "#!/bin/sh\necho 'unknown option --rounds' >&2\nexit 2\n",
    );
    let o = tetbench(&["ab", "a.py", "broken.sh", "--pairs", "3"], tmp.path());
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("left no results") && err.contains("unknown option --rounds"),
        "{err}"
    );
}

/// The real tetbench on both sides of a tiny matrix: three pairs, merged into three rounds per
/// side, no regression (one group, 3 vs 3 rounds, cannot be significant).
#[test]
fn ab_runs_the_real_binary() {
    let tmp = tempfile::tempdir().unwrap();
    let bin = env!("CARGO_BIN_EXE_tetbench");
    let o = Command::new(bin)
        .args(["ab", bin, bin, "--pairs", "3", "--out"])
        .arg(tmp.path().join("ab"))
        .args([
            "--algorithms",
            "havs",
            "--datasets",
            "box:1k",
            "--viewpoints",
            "+x",
            "--resolution",
            "32",
            "--frames",
            "2",
            "--warmup",
            "0",
            "--no-reference",
            "--no-calibrate",
        ])
        .env("TETBENCH_CACHE", tmp.path().join("cache"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    for side in ["base", "new"] {
        let merged = ResultsFile::read(&tmp.path().join("ab").join(side)).unwrap();
        assert_eq!(merged.run.rounds, 3, "{side}");
        assert!(!merged.rows.is_empty());
        for r in &merged.rows {
            assert!(r.ok(), "{r:?}");
            assert_eq!(r.samples.total_ms.len(), 6, "3 rounds × 2 frames");
        }
    }
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("pair  3 (BASE, NEW)"), "{out}");
    assert!(out.contains("outcome: NO CHANGE"), "{out}");
}

fn git(repo: &Path, args: &[&str]) -> String {
    let o = Command::new("git")
        .arg("-C")
        .arg(repo)
        .args(args)
        .env("GIT_AUTHOR_NAME", "t")
        .env("GIT_AUTHOR_EMAIL", "t@example.org")
        .env("GIT_COMMITTER_NAME", "t")
        .env("GIT_COMMITTER_EMAIL", "t@example.org")
        .output()
        .unwrap();
    assert!(o.status.success(), "git {args:?}: {}", text(&o));
    String::from_utf8_lossy(&o.stdout).trim().to_string()
}

/// A repository of `n` commits, each holding `bench.py`; alg2 is ×1.5 slower from commit
/// `slow_from` on (never, with `None`). Returns the commits, oldest first.
fn scratch_repo(dir: &Path, template: &Path, n: usize, slow_from: Option<usize>) -> Vec<String> {
    std::fs::create_dir_all(dir).unwrap();
    git(dir, &["init", "--quiet", "--initial-branch=main"]);
    (0..n)
        .map(|i| {
            let slow = slow_from.is_some_and(|k| i >= k);
            write_executable(
                &dir.join("bench.py"),
                &fake_binary_text(template, if slow { 1.5 } else { 1.0 }),
            );
            std::fs::write(dir.join("history.txt"), format!("commit {i}\n")).unwrap();
            git(dir, &["add", "bench.py", "history.txt"]);
            git(dir, &["commit", "--quiet", "-m", &format!("change {i}")]);
            git(dir, &["rev-parse", "HEAD"])
        })
        .collect()
}

fn bisect(repo: &Path, good: &str, bad: &str, out: &Path, cache: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tetbench"))
        .args([
            "bisect",
            good,
            bad,
            "--pairs",
            "3",
            "--build-command",
            "true",
        ])
        .args(["--build-output", "bench.py", "--repo"])
        .arg(repo)
        .arg("--build-cache")
        .arg(cache)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// The bisection names the commit the slowdown came in with, follows it when it moves, and
/// finds nothing in a history without one; every step prints its verdict.
#[test]
fn bisect_finds_the_first_slow_commit() {
    let tmp = tempfile::tempdir().unwrap();
    let t = template(tmp.path());
    for (name, slow_from) in [("k5", Some(5)), ("k2", Some(2)), ("never", None)] {
        let repo = tmp.path().join(name);
        let commits = scratch_repo(&repo, &t, 9, slow_from);
        let out = tmp.path().join(format!("out-{name}"));
        let cache = tmp.path().join(format!("cache-{name}"));
        let o = bisect(&repo, &commits[0], "main", &out, &cache);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", text(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(stdout.contains("bisect: 8 commit(s) after"), "{stdout}");
        // A line per step on stderr, out of at most ⌈log2 8⌉ + 1 = 4, with the ETA from the
        // second on (without a slow commit the first step, the last commit, ends the search).
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains("bisect: [1/4] A/B of "), "{stderr}");
        assert_eq!(
            stderr.contains("bisect: [2/4, ETA "),
            slow_from.is_some(),
            "{stderr}"
        );
        match slow_from {
            Some(k) => {
                let want = format!("first bad commit: {} change {k}", commits[k]);
                assert!(stdout.contains(&want), "{name}: want {want}\n{stdout}");
                assert!(stdout.contains("REGRESSION (slower: alg2"), "{stdout}");
                assert!(stdout.contains("— no regression") || k == 1, "{stdout}");
            }
            None => {
                assert!(
                    stdout.contains("no regression: main is not worse"),
                    "{stdout}"
                );
                assert!(!stdout.contains("first bad commit"), "{stdout}");
            }
        }
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("bisect.json")).unwrap())
                .unwrap();
        assert_eq!(
            report["first_bad"].as_str(),
            slow_from.map(|k| commits[k].as_str())
        );
        assert_valid("bisect", &report);
        if name != "k5" {
            continue;
        }
        // Each commit was built once: a second bisection over the same cache reuses them.
        let again = bisect(&repo, &commits[0], "main", &out.join("again"), &cache);
        assert_eq!(again.status.code(), Some(0), "{}", text(&again));
        let err = String::from_utf8_lossy(&again.stderr);
        assert!(
            !err.contains("building") && err.contains("already built"),
            "{err}"
        );
    }
    // GOOD after BAD: nothing between them, a clear error.
    let repo = tmp.path().join("k5");
    let o = bisect(
        &repo,
        "main",
        "main~3",
        &tmp.path().join("backwards"),
        &tmp.path().join("cache-k5"),
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no commits between main and main~3"));
}
