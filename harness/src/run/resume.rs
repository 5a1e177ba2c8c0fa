//! `run --resume`: an interrupted run continues where it stopped.
//!
//! Rows are on disk the moment they finish (`results/mod.rs`), so an interrupted run leaves every
//! finished row in `OUT/results.json`. With `--resume` the new run keeps the rows of every
//! (data set, algorithm, settings) unit whose viewpoints all finished and measures only the
//! rest; a unit cut off halfway is measured again whole (its rounds must come from one
//! session). The plan must be the same — another frame count, viewpoint list or build would
//! mix two experiments in one file — else the run refuses and says what differs.

use std::path::Path;

use crate::results::machine::MachineInfo;
use crate::results::{ResultsFile, Row, RunDescription, Shard, JSON_FILE};

/// A unit of the run matrix: (data set label, algorithm, settings).
pub type Unit = (String, String, render_core::Settings);

/// What of the plan differs between an earlier run and this one (empty: the same plan).
pub fn plan_differences(old: &RunDescription, new: &RunDescription) -> Vec<String> {
    let mut out = vec![];
    let mut check = |what: &str, a: String, b: String| {
        if a != b {
            out.push(format!("{what}: {a} before, {b} now"));
        }
    };
    check(
        "algorithms",
        old.algorithms.join(","),
        new.algorithms.join(","),
    );
    check("data sets", old.datasets.join(","), new.datasets.join(","));
    check(
        "viewpoints",
        old.viewpoints.to_string(),
        new.viewpoints.to_string(),
    );
    check(
        "size",
        format!("{}x{}", old.width, old.height),
        format!("{}x{}", new.width, new.height),
    );
    check("frames", old.frames.to_string(), new.frames.to_string());
    check("warmup", old.warmup.to_string(), new.warmup.to_string());
    check("rounds", old.rounds.to_string(), new.rounds.to_string());
    check(
        "transfer function",
        old.transfer_function.clone(),
        new.transfer_function.clone(),
    );
    check("projection", old.projection.clone(), new.projection.clone());
    check(
        "settings filter",
        old.settings_filter.to_string(),
        new.settings_filter.to_string(),
    );
    check(
        "reference",
        old.reference.to_string(),
        new.reference.to_string(),
    );
    let shard = |s: Option<Shard>| s.map_or("none".to_string(), |s| s.to_string());
    check("shard", shard(old.shard), shard(new.shard));
    out
}

/// The rows of `dir`'s earlier run that this run keeps: those of the units whose
/// `viewpoints` rows are all there. No results there: nothing (the run starts afresh).
pub fn finished_rows(
    dir: &Path,
    plan: &RunDescription,
    machine: &MachineInfo,
    viewpoints: usize,
) -> anyhow::Result<Vec<Row>> {
    if !dir.join(JSON_FILE).is_file() {
        return Ok(vec![]);
    }
    let old = ResultsFile::read(dir)?;
    let mut differences = plan_differences(&old.run, plan);
    let adapter = |m: &MachineInfo| m.adapter.as_ref().map(|a| a.name.clone());
    if adapter(&old.machine) != adapter(machine) {
        differences.push(format!(
            "adapter: {:?} before, {:?} now",
            adapter(&old.machine),
            adapter(machine)
        ));
    }
    if (&old.machine.git_commit, old.machine.git_dirty) != (&machine.git_commit, machine.git_dirty)
    {
        differences.push(format!(
            "build: commit {:?} (dirty {:?}) before, {:?} (dirty {:?}) now",
            old.machine.git_commit, old.machine.git_dirty, machine.git_commit, machine.git_dirty
        ));
    }
    if !differences.is_empty() {
        anyhow::bail!(
            "--resume: {} was written by another plan, so its rows cannot be continued:\n  {}\n\
             Run without --resume to replace them, or choose another --out",
            dir.join(JSON_FILE).display(),
            differences.join("\n  ")
        );
    }
    let unit = |r: &Row| (r.dataset.clone(), r.algorithm.clone(), r.settings.clone());
    let complete = |u: &Unit| old.rows.iter().filter(|r| unit(r) == *u).count() == viewpoints;
    Ok(old
        .rows
        .iter()
        .filter(|r| complete(&unit(r)))
        .cloned()
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan() -> RunDescription {
        RunDescription {
            algorithms: vec!["havs".into()],
            datasets: vec!["box:1k".into()],
            viewpoints: "+x,-x".parse().unwrap(),
            frames: 3,
            rounds: 3,
            ..Default::default()
        }
    }

    fn row(alg: &str, vp: &str) -> Row {
        Row {
            algorithm: alg.into(),
            settings: "k=2".parse().unwrap(),
            dataset: "box:1k".into(),
            viewpoint: vp.into(),
            ..Default::default()
        }
    }

    /// Complete units are kept, a half-finished one is dropped; another plan or another
    /// build is refused, naming what differs; no earlier results is a fresh start.
    #[test]
    fn finished_units_are_kept_and_another_plan_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let machine = MachineInfo::collect();
        assert!(finished_rows(dir, &plan(), &machine, 2).unwrap().is_empty());
        let file = ResultsFile {
            control: None,
            schema_version: crate::results::SCHEMA_VERSION,
            machine: machine.clone(),
            run: plan(),
            finished_utc: None,
            rows: vec![row("havs", "+x"), row("havs", "-x"), row("gator-pt", "+x")],
            errors: vec![],
        };
        crate::results::write_json(dir, &file).unwrap();
        let kept = finished_rows(dir, &plan(), &machine, 2).unwrap();
        assert_eq!(kept, [row("havs", "+x"), row("havs", "-x")]);

        let mut other = plan();
        other.frames = 10;
        let e = finished_rows(dir, &other, &machine, 2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("frames: 3 before, 10 now"), "{e}");
        let mut rebuilt = machine.clone();
        rebuilt.git_commit = Some("0".repeat(40));
        let e = finished_rows(dir, &plan(), &rebuilt, 2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("build: commit"), "{e}");
    }
}
