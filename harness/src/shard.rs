//! Shards and merge, for spreading one run matrix over several machines: `tetbench run --shard
//! i/N` runs the i-th of N disjoint parts, `tetbench report --merge DIR… --out OUT` puts the
//! parts (or runs of the same matrix on different machines) back into one results set.
//!
//! The unit of a shard is one (data set, algorithm, settings) — a prepared renderer with all
//! its viewpoints — so no shard prepares a variant another shard also prepares. The split is
//! stable: units are ranked by a fixed hash of their names (FNV-1a, the same on every machine
//! and in every order the command line lists them), and rank r goes to shard r mod N + 1, so
//! shard sizes differ by at most one unit.

use std::collections::{HashMap, HashSet};
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use anyhow::{anyhow, Context};

pub use crate::results::MergedRun;
use crate::results::{self, ResultsFile, Row, RunDescription};

/// Shard `index` (1-based) of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl FromStr for Shard {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> anyhow::Result<Shard> {
        let bad = || anyhow!("--shard {s:?}: expected i/N with 1 ≤ i ≤ N, e.g. 2/4");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// One unit of the run matrix: (data set label, algorithm, settings string).
pub type Unit = (String, String, String);

fn fnv1a(s: &str) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for b in s.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// The shard (1-based) of every unit, in the order given.
pub fn assign(units: &[Unit], count: usize) -> Vec<usize> {
    let key = |u: &Unit| format!("{}\u{1f}{}\u{1f}{}", u.0, u.1, u.2);
    let mut ranked: Vec<(u64, String, usize)> = units
        .iter()
        .enumerate()
        .map(|(i, u)| (fnv1a(&key(u)), key(u), i))
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
fn row_key(r: &Row) -> (String, String, String, String, u32, u32, String) {
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

/// Merges the results in `dirs` into one set written to `out` (results, samples, copied
/// images), ordered as one unsharded run would order them, machines side by side.
pub fn merge(dirs: &[PathBuf], out: &Path) -> anyhow::Result<ResultsFile> {
    anyhow::ensure!(
        !dirs.is_empty(),
        "report --merge needs at least one directory"
    );
    let files: Vec<ResultsFile> = dirs
        .iter()
        .map(|d| ResultsFile::read(d))
        .collect::<anyhow::Result<_>>()?;
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
            for rel in [&r.image, &r.reference_image, &r.heatmap, &r.image_f32] {
                copy_file(d, out, rel)?;
            }
            rows.push(r.clone());
        }
        merged_from.push(MergedRun {
            dir: d.display().to_string(),
            shard: f.run.shard.clone(),
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
    let merged = ResultsFile {
        schema_version: results::SCHEMA_VERSION,
        machine: first.machine.clone(),
        run,
        finished_utc: finished.and_then(|f| f.into_iter().max()),
        rows,
        errors: files.iter().flat_map(|f| f.errors.clone()).collect(),
    };
    results::write_csv(out, &merged.rows)?;
    results::write_json(out, &merged)?;
    crate::samples::write_samples_csv(out, &merged.rows)?;
    Ok(merged)
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
        .map(|d| crate::names::dataset_label(d))
        .collect();
    let viewpoints: Vec<String> = crate::suite::parse_viewpoints(&run.viewpoints)
        .map(|v| v.into_iter().map(|v| v.name).collect())
        .unwrap_or_default();
    let filter = crate::algorithms::SettingsFilter::parse(&run.settings_filter).ok();
    let mut variant_order: HashMap<String, Vec<String>> = HashMap::new();
    for a in &run.algorithms {
        let order = filter
            .as_ref()
            .and_then(|f| crate::algorithms::selected_variants(a, f).ok())
            .map(|v| {
                v.iter()
                    .map(|r| render_core::settings_string(&r.settings()))
                    .collect()
            })
            .unwrap_or_default();
        variant_order.insert(a.clone(), order);
    }
    rows.sort_by_cached_key(|r| {
        (
            pos(&labels, &r.dataset),
            pos(&run.algorithms, &r.algorithm),
            variant_order
                .get(&r.algorithm)
                .map(|v| pos(v, &r.settings))
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
                    u.push((d.to_string(), a.to_string(), format!("v={i}")));
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

    #[test]
    fn shard_syntax() {
        assert_eq!(
            "2/4".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 4 }
        );
        for bad in ["0/2", "3/2", "x", "1/", "/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }
}
