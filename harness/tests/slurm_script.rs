//! `scripts/slurm-run.sh` without a cluster: its refusals (no sbatch, an output
//! directory that is not shared) flip with their input; the jobs it submits (stand-in `sbatch`
//! and `sinfo` that record their arguments); and its merge job run by hand over shard
//! directories: a missing, a killed and a failed shard are each named, and nothing incomplete
//! is merged. The real one-node Slurm run is `scripts/ci-slurm.sh`.

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use harness::results::machine::MachineInfo;
use harness::results::{self, ResultsFile, Row, RunDescription};
use harness::run::shard::{select, units_of, Shard};

const TETBENCH: &str = env!("CARGO_BIN_EXE_tetbench");

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/slurm-run.sh")
}

fn write_exe(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap();
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// A PATH directory holding the tools the script needs and, when `slurm`, stand-ins for
/// `sbatch` (prints job ids 101, 102; appends its arguments to `calls`) and `sinfo` (prints
/// the node names in `nodes`) — but never the machine's own Slurm commands.
fn fake_path(dir: &Path, slurm: bool) -> PathBuf {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    for tool in [
        "bash", "env", "mkdir", "dirname", "basename", "cat", "rm", "chmod", "findmnt", "stat",
        "hostname", "sort", "grep", "tr", "sed", "seq", "tail", "head", "wc",
    ] {
        let found = Command::new("bash")
            .args(["-c", &format!("command -v {tool}")])
            .output()
            .unwrap();
        let found = String::from_utf8_lossy(&found.stdout).trim().to_string();
        if !found.is_empty() && !bin.join(tool).exists() {
            std::os::unix::fs::symlink(found, bin.join(tool)).unwrap();
        }
    }
    if slurm {
        let d = dir.display();
        write_exe(
            &bin.join("sbatch"),
            &format!(
                "#!/bin/bash\necho \"$*\" >>{d}/calls\nn=$(wc -l <{d}/calls 2>/dev/null || echo 1)\n\
                 echo $((100 + n))\n"
            ),
        );
        write_exe(&bin.join("sinfo"), &format!("#!/bin/bash\ncat {d}/nodes\n"));
        write_exe(&bin.join("scancel"), "#!/bin/bash\nexit 0\n");
    }
    bin
}

fn slurm_run(dir: &Path, path: &Path, args: &[&str]) -> Output {
    Command::new(path.join("bash"))
        .arg(script())
        .args(args)
        .env_clear()
        .env("PATH", path)
        .current_dir(dir)
        .output()
        .unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "status {:?}\n{}{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn this_host() -> String {
    let o = Command::new("hostname").arg("-s").output().unwrap();
    String::from_utf8_lossy(&o.stdout).trim().to_string()
}

/// No sbatch: refused before anything is written. With one: submitted.
#[test]
fn refuses_without_sbatch() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let args = [
        "--shards",
        "2",
        "--out",
        out.to_str().unwrap(),
        "--tetbench",
        TETBENCH,
    ];
    let args = [&args[..], &["--shared-ok", "--", "--datasets", "box:1k"]].concat();
    let o = slurm_run(
        tmp.path(),
        &fake_path(&tmp.path().join("none"), false),
        &args,
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("sbatch not found"), "{}", text(&o));
    assert!(!out.exists());

    let with = tmp.path().join("with");
    std::fs::create_dir_all(&with).unwrap();
    std::fs::write(with.join("nodes"), this_host()).unwrap();
    let o = slurm_run(tmp.path(), &fake_path(&with, true), &args);
    assert!(o.status.success(), "{}", text(&o));
}

/// /tmp is node-local: refused on a cluster with other nodes than this host, accepted on a
/// one-node cluster whose node is this host (CI's own: a clone under /tmp). A local
/// disk is likewise refused when the cluster has other nodes, accepted when this host is the
/// only one; --shared-ok accepts anything.
#[test]
fn refuses_an_output_directory_other_nodes_cannot_see() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fake_path(tmp.path(), true);
    let nodes = |list: &str| std::fs::write(tmp.path().join("nodes"), list).unwrap();
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec!["--shards", "2", "--out", out.to_str().unwrap()];
        args.extend(["--tetbench", TETBENCH]);
        args.extend(extra);
        args.extend(["--", "--datasets", "box:1k"]);
        slurm_run(tmp.path(), &path, &args)
    };
    let in_tmp = Path::new("/tmp").join(format!("slurm-script-{}", std::process::id()));
    nodes(&format!("{}\nnode2\n", this_host()));
    let o = run(&in_tmp, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("under /tmp, which is local to each node"),
        "{}",
        text(&o)
    );
    let o = run(&in_tmp, &["--shared-ok"]);
    assert!(o.status.success(), "{}", text(&o));
    // The same directory when this host is the cluster's only node.
    nodes(&this_host());
    let o = run(&in_tmp, &[]);
    assert!(o.status.success(), "one-node cluster, /tmp: {}", text(&o));
    // ... unless Slurm gives each job a private /tmp.
    write_exe(
        &path.join("scontrol"),
        "#!/bin/bash\necho 'JobContainerType        = job_container/tmpfs'\n",
    );
    let o = run(&in_tmp, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("private /tmp"), "{}", text(&o));
    std::fs::remove_file(path.join("scontrol")).unwrap();
    std::fs::remove_dir_all(&in_tmp).unwrap();

    // A local disk: the target directory's scratch space, when it is one.
    let local = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).unwrap();
    let fstype = Command::new("findmnt")
        .args(["-n", "-o", "FSTYPE", "-T"])
        .arg(local.path())
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let tmp_dirs = ["/tmp/", "/var/tmp/", "/dev/shm/"];
    let under_tmp = tmp_dirs
        .iter()
        .any(|t| local.path().to_str().unwrap().starts_with(t));
    if under_tmp || !["ext4", "xfs", "btrfs", "overlay", "zfs"].contains(&fstype.as_str()) {
        eprintln!("skipping the local-disk case: the target directory is on {fstype:?}");
        return;
    }
    let out = local.path().join("out");
    let o = run(&out, &[]);
    assert!(o.status.success(), "one-node cluster: {}", text(&o));
    nodes(&format!("{}\nnode2\n", this_host()));
    let o = run(&out, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("local file system") && text(&o).contains("other nodes"),
        "{}",
        text(&o)
    );
}

/// The array job and the merge job after it, with the run's options passed through.
#[test]
fn submits_an_array_and_a_dependent_merge() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("nodes"), this_host()).unwrap();
    let out = tmp.path().join("out");
    let o = slurm_run(
        tmp.path(),
        &fake_path(tmp.path(), true),
        &[
            "--shards",
            "3",
            "--out",
            out.to_str().unwrap(),
            "--tetbench",
            TETBENCH,
            "--shared-ok",
            "--gpu",
            "--sbatch",
            "--partition=gpu",
            "--",
            "--datasets",
            "box:1k,shell:1k",
            "--settings",
            "sort=radix|bucket",
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    let printed = text(&o);
    assert!(printed.contains("array job 101: 3 shards"), "{printed}");
    assert!(
        printed.contains(&format!(
            "merge job 102 (after all of them): merged report in {}/merged",
            out.display()
        )),
        "{printed}"
    );
    let calls = std::fs::read_to_string(tmp.path().join("calls")).unwrap();
    let calls: Vec<&str> = calls.lines().collect();
    assert!(
        calls[0].contains("--array=1-3") && calls[0].ends_with("slurm/shard.sh"),
        "{calls:?}"
    );
    assert!(calls[1].contains("--dependency=afterany:101"), "{calls:?}");
    assert!(calls[1].ends_with("slurm/merge.sh 101"), "{calls:?}");
    let shard = std::fs::read_to_string(out.join("slurm/shard.sh")).unwrap();
    assert!(shard.contains("#SBATCH --gres=gpu:1"), "{shard}");
    assert!(shard.contains("#SBATCH --partition=gpu"), "{shard}");
    assert!(shard.contains(r"sort=radix\|bucket --shard"), "{shard}");
    assert!(shard.contains(r#"--shard "$i/3" --out "$dir""#), "{shard}");
    let merge = std::fs::read_to_string(out.join("slurm/merge.sh")).unwrap();
    assert!(merge.contains("report --merge"), "{merge}");
    assert!(
        !merge.contains("#SBATCH --gres"),
        "the merge needs no GPU: {merge}"
    );
    let env = std::fs::read_to_string(out.join("slurm/jobs.env")).unwrap();
    assert!(env.contains("ARRAY_JOB=101\nMERGE_JOB=102\n"), "{env}");

    // The options it sets itself are refused when passed through.
    let o = slurm_run(
        tmp.path(),
        &fake_path(tmp.path(), true),
        &[
            "--shards",
            "3",
            "--out",
            "o",
            "--tetbench",
            TETBENCH,
            "--",
            "--shard",
            "1/3",
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("do not pass --shard"), "{}", text(&o));
}

/// Shard `i/3` of a one-algorithm matrix, finished or not.
fn write_shard(out: &Path, i: usize, finished: bool, exit_status: Option<i32>) {
    let run = RunDescription {
        algorithms: vec!["gator-pt".into()],
        datasets: vec!["box:1k".into(), "shell:1k".into()],
        viewpoints: "+x".parse().unwrap(),
        width: 8,
        height: 8,
        frames: 1,
        rounds: 1,
        shard: Some(Shard { index: i, count: 3 }),
        ..RunDescription::default()
    };
    let all = units_of(&run);
    let mine = select(Shard { index: i, count: 3 }, &all);
    let rows = all
        .into_iter()
        .filter(|u| mine.contains(u))
        .map(|(dataset, algorithm, settings)| Row {
            algorithm,
            settings,
            dataset,
            viewpoint: "+x".into(),
            width: 8,
            height: 8,
            ..Row::default()
        })
        .collect();
    let file = ResultsFile {
        control: None,
        schema_version: results::SCHEMA_VERSION,
        machine: MachineInfo::collect(),
        run,
        finished_utc: finished.then(|| "2026-01-01T00:00:00Z".to_string()),
        rows,
        errors: vec![],
    };
    let dir = out.join(format!("shard-{i}"));
    std::fs::create_dir_all(&dir).unwrap();
    results::write_json(&dir, &file).unwrap();
    if let Some(s) = exit_status {
        std::fs::write(dir.join("exit-status"), format!("{s}\n")).unwrap();
    }
}

/// The merge job, run by hand: all shards → merged; each kind of failure → named, and only a
/// failure with complete results (failed rows) is merged (the job still fails).
#[test]
fn the_merge_job_names_a_failed_shard() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("nodes"), this_host()).unwrap();
    let out = tmp.path().join("out");
    let path = fake_path(tmp.path(), true);
    let o = slurm_run(
        tmp.path(),
        &path,
        &[
            "--shards",
            "3",
            "--out",
            out.to_str().unwrap(),
            "--tetbench",
            TETBENCH,
            "--shared-ok",
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    let merge = || {
        let _ = std::fs::remove_dir_all(out.join("merged"));
        let o = Command::new(path.join("bash"))
            .arg(out.join("slurm/merge.sh"))
            .env("PATH", &path)
            .output()
            .unwrap();
        (
            o.status.success(),
            text(&o),
            out.join("merged/results.json").is_file(),
        )
    };
    std::fs::create_dir_all(out.join("logs")).unwrap();
    std::fs::write(
        out.join("logs/shard-2.out"),
        "loading box:1k\nout of memory: boom\n",
    )
    .unwrap();
    write_shard(&out, 1, true, Some(0));
    write_shard(&out, 3, true, Some(0));

    // Shard 2 never ran.
    let (ok, said, merged) = merge();
    assert!(!ok && !merged, "{said}");
    assert!(said.contains("shard 2/3 failed: it never ran"), "{said}");
    assert!(
        said.contains("out of memory: boom"),
        "the log's tail: {said}"
    );
    assert!(said.contains("--array=2 "), "how to rerun it: {said}");

    // Killed mid-run: its results.json unfinished, no exit status.
    write_shard(&out, 2, false, None);
    let (ok, said, merged) = merge();
    assert!(!ok && !merged, "{said}");
    assert!(
        said.contains("shard 2/3 failed: it was killed while running"),
        "{said}"
    );
    assert!(
        said.contains("shard 2/3 in ") && said.contains("did not finish"),
        "{said}"
    );

    // Exited 1 with its results finished (failed rows): merged, and the job fails.
    write_shard(&out, 2, true, Some(1));
    let (ok, said, merged) = merge();
    assert!(!ok && merged, "{said}");
    assert!(
        said.contains("shard 2/3 failed: it exited with status 1"),
        "{said}"
    );

    // All three succeeded.
    write_shard(&out, 2, true, Some(0));
    let (ok, said, merged) = merge();
    assert!(ok && merged, "{said}");
    let file = ResultsFile::read(&out.join("merged")).unwrap();
    assert_eq!(file.run.merged_from.len(), 3);
    assert!(file.errors.is_empty(), "{:?}", file.errors);
}
