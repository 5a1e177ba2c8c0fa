//! Shards and merge, for spreading one run matrix over several machines: `tetbench run --shard
//! i/N` runs the i-th of N disjoint parts, `tetbench report --merge DIR… --out OUT` puts the
//! parts (or runs of the same matrix on different machines) back into one results set.
//!
//! The unit of a shard is one (data set, algorithm, settings) — a prepared renderer with all
//! its viewpoints — so no shard prepares a variant another shard also prepares. The split is
//! stable: units are ranked by a fixed hash of their names (FNV-1a, the same on every machine
//! and in every order the command line lists them), and rank r goes to shard r mod N + 1, so
//! shard sizes differ by at most one unit.

use render_core::Settings;
use std::collections::{HashMap, HashSet};
use std::fmt;
use std::path::{Path, PathBuf};

use anyhow::Context;

use crate::algorithms::describe;
use crate::results::names::stable_hash;
use crate::results::{self, ResultsFile, Row, RunDescription};
pub use crate::results::{MergedRun, Shard};

/// One unit of the run matrix: (data set label, algorithm, settings).
pub type Unit = (String, String, render_core::Settings);

/// The shard (1-based) of every unit, in the order given.
pub fn assign(units: &[Unit], count: usize) -> Vec<usize> {
    let key = |u: &Unit| format!("{}\u{1f}{}\u{1f}{}", u.0, u.1, u.2);
    let mut ranked: Vec<(u64, String, usize)> = units
        .iter()
        .enumerate()
        .map(|(i, u)| (stable_hash(&key(u)), key(u), i))
        .collect();
    ranked.sort();
    let mut out = vec![0; units.len()];
    for (rank, (_, _, i)) in ranked.into_iter().enumerate() {
        out[i] = rank % count.max(1) + 1;
    }
    out
}

/// The units of `units` that belong to `shard`.
pub fn select(shard: Shard, units: &[Unit]) -> HashSet<Unit> {
    assign(units, shard.count)
        .into_iter()
        .zip(units)
        .filter(|(s, _)| *s == shard.index)
        .map(|(_, u)| u.clone())
        .collect()
}

/// The parts of a run description that must agree for results to be merged.
fn matrix_of(r: &RunDescription) -> RunDescription {
    RunDescription {
        command_line: vec![],
        shard: None,
        merged_from: vec![],
        ..r.clone()
    }
}

/// The matrix without its algorithms: runs that agree on it but measured other algorithms
/// (e.g. a slow peer run on its own) complete each other when they ran on one adapter.
fn matrix_but_algorithms(r: &RunDescription) -> RunDescription {
    RunDescription {
        algorithms: vec![],
        ..matrix_of(r)
    }
}

/// The adapter a file's rows ran on (name, driver and — for software adapters — the CPU),
/// for the same-machine check.
fn adapter_of(f: &ResultsFile) -> Option<(String, String, String)> {
    f.machine.adapter.as_ref().map(|a| {
        (
            a.name.clone(),
            a.driver.clone(),
            f.machine.cpu_model.clone(),
        )
    })
}

/// A row's identity in the matrix (one per adapter: runs of several machines sit side by side).
fn row_key(r: &Row) -> (String, Settings, String, String, u32, u32, String) {
    (
        r.algorithm.clone(),
        r.settings.clone(),
        r.dataset.clone(),
        r.viewpoint.clone(),
        r.width,
        r.height,
        r.adapter.clone(),
    )
}

/// How a merged results set's `errors` begin for each [`Gap`] merged with `--allow-missing`.
pub const INCOMPLETE: &str = "incomplete merge: ";

/// A part of the matrix that did not arrive: a shard no directory holds, or a run that did
/// not finish (its task was killed or crashed) and so lacks some of its units.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// What is missing and why, naming the shard (`i/N`) or the directory.
    pub what: String,
    /// The (data set, algorithm, settings) units it should have measured and did not.
    pub units: Vec<Unit>,
}

impl fmt::Display for Gap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.what)?;
        if !self.units.is_empty() {
            let units: Vec<String> = self
                .units
                .iter()
                .map(|(d, a, s)| format!("{d} {a} {s}").trim_end().to_string())
                .collect();
            write!(f, "; missing units: {}", units.join(", "))?;
        }
        Ok(())
    }
}

/// Every (data set, algorithm, settings) unit `run` asks for, in the order it runs them (the
/// units `--shard` deals out).
pub fn units_of(run: &RunDescription) -> Vec<Unit> {
    let mut units = vec![];
    for spec in &run.datasets {
        let label = crate::results::names::dataset_label(spec);
        // An external renderer (`--external`) is not in the registry: the file does not
        // say its variants, so it has no units here.
        for d in run.algorithms.iter().filter_map(|a| describe(a)) {
            for settings in d.select(&run.settings_filter) {
                units.push((label.clone(), d.name.to_string(), settings));
            }
        }
    }
    units
}

/// What `files` (read from `dirs`) lack of the matrices they are parts of: every run that did
/// not finish (no `finished_utc`: it was killed or crashed), with the units it has no row
/// for, and every shard `i/N` of a split (same algorithms and N) that fewer files hold than
/// another shard of that split — none, or once where the others came from two machines.
/// Empty when the parts are complete.
pub fn gaps(files: &[ResultsFile], dirs: &[PathBuf]) -> Vec<Gap> {
    let mut gaps = vec![];
    // Split (algorithms, N) → how many files hold each shard, and one of its files. Not keyed
    // by adapter: the shards of one split may run on different GPUs of a cluster.
    type Split<'f> = ((Vec<String>, usize), HashMap<usize, usize>, &'f ResultsFile);
    let mut splits: Vec<Split> = vec![];
    for (f, d) in files.iter().zip(dirs) {
        let shard = f.run.shard;
        if f.finished_utc.is_none() {
            let own: Vec<Unit> = match shard {
                Some(s) => {
                    let all = units_of(&f.run);
                    let mine = select(s, &all);
                    all.into_iter().filter(|u| mine.contains(u)).collect()
                }
                None => units_of(&f.run),
            };
            let measured: HashSet<Unit> = f
                .rows
                .iter()
                .map(|r| (r.dataset.clone(), r.algorithm.clone(), r.settings.clone()))
                .collect();
            let name = shard.map(|s| format!("shard {s} in ")).unwrap_or_default();
            gaps.push(Gap {
                what: format!(
                    "{name}{} did not finish (results.json has no finished_utc: the run was \
                     killed or crashed)",
                    d.display()
                ),
                units: own.into_iter().filter(|u| !measured.contains(u)).collect(),
            });
        }
        let Some(shard) = shard else { continue };
        let key = (f.run.algorithms.clone(), shard.count);
        match splits.iter_mut().find(|(k, _, _)| *k == key) {
            Some((_, held, _)) => *held.entry(shard.index).or_default() += 1,
            None => splits.push((key, HashMap::from([(shard.index, 1)]), f)),
        }
    }
    for ((_, count), held, f) in &splits {
        let most = held.values().copied().max().unwrap_or(0);
        let all = units_of(&f.run);
        for index in 1..=*count {
            let times = held.get(&index).copied().unwrap_or(0);
            if times == most {
                continue;
            }
            let shard = Shard {
                index,
                count: *count,
            };
            let what = if times == 0 {
                format!("shard {shard} is missing: none of the directories given holds it")
            } else {
                format!(
                    "shard {shard} is missing from a machine: {times} of the directories hold \
                     it, {most} hold another shard of the split"
                )
            };
            let mine = select(shard, &all);
            gaps.push(Gap {
                what,
                units: all.iter().filter(|u| mine.contains(*u)).cloned().collect(),
            });
        }
    }
    gaps
}

/// Merges the results in `dirs` into one set written to `out` (results, samples, copied
/// images), ordered as one unsharded run would order them, machines side by side. A missing
/// shard or an unfinished run (see [`gaps`]) is an error naming it, unless `allow_missing`:
/// then the merge goes on and records each gap, with its missing units, in `errors`.
pub fn merge(dirs: &[PathBuf], out: &Path, allow_missing: bool) -> anyhow::Result<ResultsFile> {
    anyhow::ensure!(
        !dirs.is_empty(),
        "report --merge needs at least one directory"
    );
    let files: Vec<ResultsFile> = dirs
        .iter()
        .map(|d| ResultsFile::read(d))
        .collect::<anyhow::Result<_>>()?;
    let gaps = gaps(&files, dirs);
    if !gaps.is_empty() && !allow_missing {
        let list: Vec<String> = gaps.iter().map(|g| format!("  {g}")).collect();
        anyhow::bail!(
            "the results to merge are incomplete:\n{}\nrerun what is missing, or merge anyway \
             with --allow-missing (the missing units are then listed in the merged errors)",
            list.join("\n")
        );
    }
    let first = &files[0];
    let matrix = merged_matrix(&files, dirs)?;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut seen: HashMap<_, PathBuf> = HashMap::new();
    let mut rows: Vec<Row> = vec![];
    let mut merged_from = vec![];
    for (f, d) in files.iter().zip(dirs) {
        for r in &f.rows {
            if let Some(other) = seen.insert(row_key(r), d.clone()) {
                anyhow::bail!(
                    "row {} {} {} {} is in both {} and {}: overlapping shards",
                    r.algorithm,
                    r.settings,
                    r.dataset,
                    r.viewpoint,
                    other.display(),
                    d.display()
                );
            }
            for rel in [
                &r.image,
                &r.reference_image,
                &r.heatmap,
                &r.image_f32,
                &r.tile_counts,
            ] {
                copy_file(d, out, rel)?;
            }
            rows.push(r.clone());
        }
        merged_from.push(MergedRun {
            dir: d.display().to_string(),
            shard: f.run.shard,
            adapter: f.machine.adapter.as_ref().map(|a| a.name.clone()),
            git_commit: f.machine.git_commit.clone(),
            date_utc: f.machine.date_utc.clone(),
            rows: f.rows.len(),
        });
    }
    sort_like_a_run(&mut rows, &matrix);
    let mut run = matrix;
    run.command_line = first.run.command_line.clone();
    run.merged_from = merged_from;
    let finished = files
        .iter()
        .map(|f| f.finished_utc.clone())
        .collect::<Option<Vec<_>>>();
    // Each shard's control stays beside its rows (each row already holds its rounds').
    let control = files
        .iter()
        .filter_map(|f| f.control.clone())
        .reduce(|mut a, b| {
            a.samples.extend(b.samples);
            a
        });
    let merged = ResultsFile {
        control,
        schema_version: results::SCHEMA_VERSION,
        machine: first.machine.clone(),
        run,
        finished_utc: finished.and_then(|f| f.into_iter().max()),
        rows,
        errors: files
            .iter()
            .flat_map(|f| f.errors.clone())
            .chain(gaps.iter().map(|g| format!("{INCOMPLETE}{g}")))
            .collect(),
    };
    results::write_csv(out, &merged.rows)?;
    results::write_json(out, &merged)?;
    crate::results::samples::write_samples_csv(out, &merged.rows)?;
    Ok(merged)
}

/// The matrix the merged runs share: one run's (shards, machines), or one machine's runs of
/// other algorithms put together; any other difference is an error naming the two runs.
fn merged_matrix(files: &[ResultsFile], dirs: &[PathBuf]) -> anyhow::Result<RunDescription> {
    let first = &files[0];
    let mut matrix = matrix_of(&first.run);
    for (f, d) in files.iter().zip(dirs).skip(1) {
        if matrix_of(&f.run) == matrix {
            continue;
        }
        if matrix_but_algorithms(&f.run) == matrix_but_algorithms(&matrix) {
            // Complementary algorithms: only meaningful side by side on one adapter.
            anyhow::ensure!(
                adapter_of(f) == adapter_of(first),
                "{} measured other algorithms than {} on another adapter ({:?} vs {:?}); runs of \
                 different algorithms can be merged only from one machine",
                d.display(),
                dirs[0].display(),
                adapter_of(f),
                adapter_of(first)
            );
            for a in &f.run.algorithms {
                if !matrix.algorithms.contains(a) {
                    matrix.algorithms.push(a.clone());
                }
            }
            continue;
        }
        anyhow::bail!(
            "{} was run with a different matrix than {} (data sets, viewpoints, size, frames, \
             transfer function or settings differ); only shards of one run, the same run on \
             several machines, or runs of other algorithms on one machine can be merged",
            d.display(),
            dirs[0].display()
        );
    }
    Ok(matrix)
}

fn copy_file(from: &Path, to: &Path, rel: &str) -> anyhow::Result<()> {
    if rel.is_empty() || Path::new(rel).is_absolute() || rel.contains("..") {
        return Ok(());
    }
    let (src, dst) = (from.join(rel), to.join(rel));
    if !src.is_file() || dst.is_file() {
        return Ok(());
    }
    if let Some(p) = dst.parent() {
        std::fs::create_dir_all(p).with_context(|| format!("cannot create {}", p.display()))?;
    }
    std::fs::copy(&src, &dst)
        .map(|_| ())
        .with_context(|| format!("cannot copy {} to {}", src.display(), dst.display()))
}

/// Orders rows as `run` produces them: data set, algorithm, variant (in the algorithm table's
/// order), viewpoint, then adapter.
pub fn sort_like_a_run(rows: &mut [Row], run: &RunDescription) {
    let pos = |list: &[String], x: &str| list.iter().position(|s| s == x).unwrap_or(usize::MAX);
    let labels: Vec<String> = run
        .datasets
        .iter()
        .map(|d| crate::results::names::dataset_label(d))
        .collect();
    let viewpoints = run.viewpoints.names();
    let variant_order: HashMap<&str, Vec<Settings>> = run
        .algorithms
        .iter()
        .filter_map(|a| describe(a))
        .map(|d| (d.name, d.select(&run.settings_filter)))
        .collect();
    rows.sort_by_cached_key(|r| {
        (
            pos(&labels, &r.dataset),
            pos(&run.algorithms, &r.algorithm),
            variant_order
                .get(r.algorithm.as_str())
                .map(|v| {
                    v.iter()
                        .position(|s| *s == r.settings)
                        .unwrap_or(usize::MAX)
                })
                .unwrap_or(usize::MAX),
            r.settings.clone(),
            pos(&viewpoints, &r.viewpoint),
            r.viewpoint.clone(),
            r.adapter.clone(),
        )
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn units() -> Vec<Unit> {
        let mut u = vec![];
        for d in ["box:10k", "shell:10k", "spx"] {
            for (a, n) in [("gator-pt", 2), ("havs", 4), ("fragment-pt", 6)] {
                for i in 0..n {
                    u.push((
                        d.to_string(),
                        a.to_string(),
                        format!("v={i}").parse().unwrap(),
                    ));
                }
            }
        }
        u
    }

    /// Every unit is in exactly one shard, for every N, and shard sizes differ by at most one.
    #[test]
    fn shards_partition_the_matrix() {
        let u = units();
        for n in 1..=7 {
            let mut union: Vec<Unit> = vec![];
            let mut sizes = vec![];
            for i in 1..=n {
                let s = select(Shard { index: i, count: n }, &u);
                sizes.push(s.len());
                union.extend(s);
            }
            assert_eq!(union.len(), u.len(), "N={n}: overlap or loss");
            let set: HashSet<_> = union.into_iter().collect();
            assert_eq!(set, u.iter().cloned().collect::<HashSet<_>>());
            assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1);
        }
    }

    /// The split does not depend on the order the units are listed in.
    #[test]
    fn the_split_is_stable() {
        let u = units();
        let mut r = u.clone();
        r.reverse();
        let s = Shard { index: 2, count: 3 };
        assert_eq!(select(s, &u), select(s, &r));
    }

    /// A finished shard `i/n` of a one-algorithm matrix over two meshes: one row per unit.
    fn shard_file(i: usize, n: usize) -> ResultsFile {
        let run = RunDescription {
            algorithms: vec!["gator-pt".into()],
            datasets: vec!["box:1k".into(), "shell:1k".into()],
            viewpoints: "+x".parse().unwrap(),
            width: 8,
            height: 8,
            frames: 1,
            rounds: 1,
            shard: Some(Shard { index: i, count: n }),
            ..RunDescription::default()
        };
        let mine = select(Shard { index: i, count: n }, &units_of(&run));
        let rows = units_of(&run)
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
        ResultsFile {
            control: None,
            schema_version: results::SCHEMA_VERSION,
            machine: crate::results::machine::MachineInfo::collect(),
            run,
            finished_utc: Some("2026-01-01T00:00:00Z".into()),
            rows,
            errors: vec![],
        }
    }

    fn dirs(names: &[usize]) -> Vec<PathBuf> {
        names
            .iter()
            .map(|i| PathBuf::from(format!("out/shard-{i}")))
            .collect()
    }

    /// All shards: complete. One left out: a gap naming it and exactly its units.
    #[test]
    fn a_missing_shard_is_named_with_its_units() {
        let all: Vec<ResultsFile> = (1..=3).map(|i| shard_file(i, 3)).collect();
        assert!(units_of(&all[0].run).len() >= 3, "every shard has a unit");
        assert_eq!(gaps(&all, &dirs(&[1, 2, 3])), vec![]);

        let some = vec![all[0].clone(), all[2].clone()];
        let found = gaps(&some, &dirs(&[1, 3]));
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0].what.contains("shard 2/3"), "{}", found[0]);
        let expected = select(Shard { index: 2, count: 3 }, &units_of(&all[0].run));
        assert_eq!(found[0].units.len(), expected.len());
        assert!(found[0].units.iter().all(|u| expected.contains(u)));
        assert!(found[0].to_string().contains("missing units: "));
    }

    /// A shard whose task was killed (no finished_utc) is a gap listing the units it has no
    /// row for; the same file finished is not.
    #[test]
    fn an_unfinished_shard_is_a_gap() {
        let mut files: Vec<ResultsFile> = (1..=2).map(|i| shard_file(i, 2)).collect();
        let lost = files[1].rows.pop().unwrap();
        assert_eq!(gaps(&files, &dirs(&[1, 2])), vec![]);
        files[1].finished_utc = None;
        let found = gaps(&files, &dirs(&[1, 2]));
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0]
            .what
            .contains("shard 2/2 in out/shard-2 did not finish"));
        assert_eq!(
            found[0].units,
            vec![(lost.dataset, lost.algorithm, lost.settings)]
        );
    }

    /// The same split on two machines: shard 2 from only one of them is a gap.
    #[test]
    fn a_shard_missing_from_one_machine_is_a_gap() {
        let mut other: Vec<ResultsFile> = (1..=2).map(|i| shard_file(i, 2)).collect();
        for f in &mut other {
            f.machine.cpu_model = "another CPU".into();
        }
        let mut files: Vec<ResultsFile> = (1..=2).map(|i| shard_file(i, 2)).collect();
        files.extend(other.clone());
        assert_eq!(gaps(&files, &dirs(&[1, 2, 3, 4])), vec![]);
        files.pop();
        let found = gaps(&files, &dirs(&[1, 2, 3]));
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0]
            .what
            .starts_with("shard 2/2 is missing from a machine"));
    }

    /// Splits are told apart by N: shards 1/2 and 2/2 are complete beside a whole 1/1.
    #[test]
    fn splits_of_different_sizes_are_checked_apart() {
        let files = vec![shard_file(1, 2), shard_file(2, 2), shard_file(1, 1)];
        assert_eq!(gaps(&files, &dirs(&[1, 2, 3])), vec![]);
        let files = vec![shard_file(1, 2), shard_file(1, 1)];
        let found = gaps(&files, &dirs(&[1, 3]));
        assert_eq!(found.len(), 1);
        assert!(found[0].what.starts_with("shard 2/2 is missing"));
    }

    /// `merge` refuses a missing shard, naming it, and with `allow_missing` merges what
    /// arrived and lists the gap in the merged errors.
    #[test]
    fn merge_refuses_a_missing_shard_unless_allowed() {
        let tmp = tempfile::tempdir().unwrap();
        let mut dirs = vec![];
        for i in [1, 3] {
            let d = tmp.path().join(format!("shard-{i}"));
            std::fs::create_dir_all(&d).unwrap();
            results::write_json(&d, &shard_file(i, 3)).unwrap();
            dirs.push(d);
        }
        let out = tmp.path().join("merged");
        let err = merge(&dirs, &out, false).unwrap_err().to_string();
        assert!(err.contains("shard 2/3 is missing"), "{err}");
        assert!(err.contains("--allow-missing"), "{err}");
        assert!(!out.join("results.json").exists());

        let merged = merge(&dirs, &out, true).unwrap();
        let gaps: Vec<&String> = merged
            .errors
            .iter()
            .filter(|e| e.starts_with(INCOMPLETE))
            .collect();
        assert_eq!(gaps.len(), 1, "{:?}", merged.errors);
        assert!(gaps[0].contains("shard 2/3"));
        assert_eq!(ResultsFile::read(&out).unwrap().errors, merged.errors);
    }
}
