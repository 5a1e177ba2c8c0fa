//! The rule history against git: every committed version of `reports/papers/claims.csv`, and
//! the working tree against the last one, is diffed on the rule fields (metric, data sets,
//! sides, expectation, tolerance, evidence, normalisation, and ids that move), and each change
//! must have its row in `reports/papers/rule_history.csv` naming the claim, the old value and a
//! commit between the two versions. The table cells' rules (`reports/papers/cell_rules.csv`)
//! are walked the same way: a changed or removed rule of a column needs its row (id
//! `TABLE:COLUMN`, the old compare, tolerance and direction). A clone without the history (shallow, or no git) cannot be
//! checked: the test says so, and fails under `TETBENCH_REQUIRE_DATA=1` (CI's full clone).

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::papers::cells::{How, CELL_RULES_FILE};
use crate::papers::claims::{Discriminates, Metric, VariantSpec};
use crate::papers::rules::{self, Evidence, Normalise, RuleChange};

/// The rule fields compared between versions, as the claims file names its columns.
const FIELDS: [&str; 10] = [
    "metric",
    "datasets",
    "a",
    "b",
    "expect",
    "tolerance",
    "evidence",
    "normalise",
    "discriminates",
    "control",
];

type Key = (String, String);
/// One version of the claims file: each claim's rule fields, canonical, in the file's order.
type Version = Vec<(Key, BTreeMap<&'static str, String>)>;

/// A field's value in one canonical spelling, so that a respelling is not a change.
fn canon(field: &str, text: &str) -> String {
    let t = text.trim();
    match field {
        "metric" => Metric::parse(t).map_or(t.to_string(), |m| m.to_string()),
        "a" | "b" | "control" if !t.is_empty() => {
            VariantSpec::parse(t).map_or(t.to_string(), |v| v.to_string())
        }
        "datasets" => rules::split_datasets(t).join(";"),
        "expect" => t.replace(' ', ""),
        "discriminates" if !t.is_empty() => {
            Discriminates::parse(t).map_or(t.to_string(), |d| d.to_string())
        }
        "tolerance" => t.parse::<f64>().map_or(t.to_string(), |v| v.to_string()),
        "evidence" if t.is_empty() => "measured".into(),
        "evidence" => Evidence::parse(t).map_or(t.to_string(), |e| evidence_text(&e)),
        "normalise" => Normalise::parse(t).map_or(t.to_string(), |n| format!("{n:?}")),
        _ => t.to_string(),
    }
}

fn evidence_text(e: &Evidence) -> String {
    match e {
        Evidence::Measured => "measured".into(),
        Evidence::ByConstruction => "construction".into(),
        Evidence::Derived(ids) => format!("derived:{}", ids.join("+")),
    }
}

/// A version's rule fields by column name; a column the version did not have yet reads as its
/// default then (evidence `measured`, normalisation `none`).
fn read_version(text: &str) -> Result<Version, String> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(text.as_bytes());
    let header: Vec<String> = r
        .headers()
        .map_err(|e| e.to_string())?
        .iter()
        .map(String::from)
        .collect();
    let col = |rec: &csv::StringRecord, name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .and_then(|i| rec.get(i))
            .unwrap_or("")
            .to_string()
    };
    let mut out = vec![];
    for rec in r.records() {
        let rec = rec.map_err(|e| e.to_string())?;
        let fields = FIELDS
            .iter()
            .map(|f| (*f, canon(f, &col(&rec, f))))
            .collect();
        out.push(((col(&rec, "paper"), col(&rec, "id")), fields));
    }
    Ok(out)
}

/// The old value of `field` a history row records.
fn old_value(h: &RuleChange, field: &str) -> Option<String> {
    let o = h.old.as_ref()?;
    let text = match field {
        "metric" => o.metric.to_string(),
        "datasets" => o.datasets.join(";"),
        "a" => o.a.to_string(),
        "b" => o.b.as_ref().map_or(String::new(), |b| b.to_string()),
        "expect" => o.expect_text.clone(),
        "tolerance" => o.tolerance.to_string(),
        "evidence" => evidence_text(&o.evidence),
        "normalise" => format!("{:?}", o.normalise),
        "discriminates" => o
            .discriminates
            .as_ref()
            .map_or(String::new(), |d| d.to_string()),
        "control" => o.control.as_ref().map_or(String::new(), |c| c.to_string()),
        _ => return None,
    };
    Some(canon(field, &text))
}

/// The rule changes from `prev` to `cur` that no history row covers. `in_range` says whether a
/// row's commit lies between the two versions.
fn uncovered(
    prev: &Version,
    cur: &Version,
    history: &[RuleChange],
    in_range: &mut dyn FnMut(&str) -> bool,
) -> Vec<String> {
    let prev_map: HashMap<&Key, &BTreeMap<&str, String>> =
        prev.iter().map(|(k, f)| (k, f)).collect();
    let cur_map: HashMap<&Key, &BTreeMap<&str, String>> = cur.iter().map(|(k, f)| (k, f)).collect();
    let mut rows_of = |paper: &str, id: &str| -> Vec<&RuleChange> {
        history
            .iter()
            .filter(|h| h.paper == paper && h.id == id)
            .filter(|h| in_range(&h.commit))
            .collect()
    };
    let mut missing = vec![];
    let identity =
        |f: &BTreeMap<&str, String>| (f["metric"].clone(), f["a"].clone(), f["b"].clone());
    for (key, now) in cur {
        let (paper, id) = key;
        match prev_map.get(key) {
            Some(before) => {
                let rows = rows_of(paper, id);
                for f in FIELDS {
                    if before[f] == now[f] {
                        continue;
                    }
                    let covered = rows
                        .iter()
                        .any(|h| old_value(h, f).as_deref() == Some(before[f].as_str()));
                    if !covered {
                        missing.push(format!(
                            "{paper} {id}: {f} changed from {:?} to {:?} with no history row naming that old value",
                            before[f], now[f]
                        ));
                    }
                }
            }
            None => {
                // A new id carrying what another claim compared before, which no longer does:
                // the claim moved to a new id.
                let moved_from = prev.iter().find(|((p, other), f)| {
                    p == paper
                        && other != id
                        && identity(f) == identity(now)
                        && cur_map
                            .get(&(p.clone(), other.clone()))
                            .is_none_or(|c| identity(c) != identity(f))
                });
                if let Some(((_, old_id), _)) = moved_from {
                    let covered = rows_of(paper, id)
                        .iter()
                        .any(|h| h.old_id.as_deref() == Some(old_id.as_str()));
                    if !covered {
                        missing.push(format!(
                            "{paper} {id}: the claim that was {old_id} moved to {id} with no history row naming its old id"
                        ));
                    }
                }
            }
        }
    }
    for ((paper, id), _) in prev {
        if cur_map.contains_key(&(paper.clone(), id.clone())) {
            continue;
        }
        let covered = history
            .iter()
            .filter(|h| h.paper == *paper && h.old_id.as_deref() == Some(id.as_str()))
            .any(|h| in_range(&h.commit));
        if !covered {
            missing.push(format!(
                "{paper} {id}: removed with no history row naming it as an old id"
            ));
        }
    }
    missing
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn git(args: &[&str]) -> Result<String, String> {
    let out = Command::new("git")
        .args(args)
        .current_dir(repo())
        .output()
        .map_err(|e| format!("git {}: {e}", args.join(" ")))?;
    if !out.status.success() {
        return Err(format!(
            "git {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn is_ancestor(a: &str, b: &str) -> bool {
    git(&["merge-base", "--is-ancestor", a, b]).is_ok()
}

/// The committed versions of a rule file, oldest first, or why git cannot give them.
fn committed_versions(file: &str) -> Result<Vec<(String, String)>, String> {
    if git(&["rev-parse", "--is-shallow-repository"])?.trim() == "true" {
        return Err(format!(
            "the clone is shallow: {file}'s history is not here"
        ));
    }
    // The first-parent chain: branches merged in parallel each changed the file from its own
    // base, so the commits in date order would read one branch's change as undone by the
    // other's. A merge carries its branch's changes as one step.
    let log = git(&["log", "--first-parent", "--format=%H", "--", file])?;
    log.lines()
        .rev()
        .map(|c| Ok((c.to_string(), git(&["show", &format!("{c}:{file}")])?)))
        .collect()
}

/// `versions`, or skips the test where git cannot give them (fails under
/// `TETBENCH_REQUIRE_DATA=1`).
fn or_skip(versions: Result<Vec<(String, String)>, String>) -> Option<Vec<(String, String)>> {
    match versions {
        Ok(v) => Some(v),
        Err(why) => {
            let msg = format!(
                "the rule history cannot be checked against git: {why} (a full clone checks it)"
            );
            if std::env::var("TETBENCH_REQUIRE_DATA").is_ok_and(|v| v == "1") {
                panic!("TETBENCH_REQUIRE_DATA=1 but {msg}");
            }
            eprintln!("SKIPPED: {msg}");
            None
        }
    }
}

/// The uncovered changes from one version's text to the next's, given which commits lie
/// between them.
type Uncovered<'a> = &'a dyn Fn(&str, &str, &mut dyn FnMut(&str) -> bool) -> Vec<String>;

/// Walks the committed versions of `file` and the working tree against the last one, each
/// step's uncovered changes named with the two versions.
fn walk(file: &str, versions: &[(String, String)], uncovered: Uncovered) -> (usize, Vec<String>) {
    let working = std::fs::read_to_string(repo().join(file)).unwrap();
    let head = git(&["rev-parse", "HEAD"]).unwrap().trim().to_string();
    let mut missing = vec![];
    for i in 0..versions.len() {
        let (p_commit, p_text) = &versions[i];
        let (c_commit, c_text) = match versions.get(i + 1) {
            Some((c, t)) => (c.clone(), t.clone()),
            None => (head.clone(), working.clone()),
        };
        // A commit that came in with this step: in the new version's history, not in the old's
        // (on a merged branch it need not descend from the old version).
        let mut in_range = |h: &str| is_ancestor(h, &c_commit) && !is_ancestor(h, p_commit);
        for m in uncovered(p_text, &c_text, &mut in_range) {
            let to = if i + 1 < versions.len() {
                c_commit[..7].to_string()
            } else {
                "the working tree".to_string()
            };
            missing.push(format!("{} → {to}: {m}", &p_commit[..7]));
        }
    }
    (versions.len(), missing)
}

#[test]
fn every_rule_change_since_the_claims_file_began_has_its_history_row() {
    let Some(versions) = or_skip(committed_versions("reports/papers/claims.csv")) else {
        return;
    };
    let history = rules::history().unwrap();
    let (steps, missing) = walk("reports/papers/claims.csv", &versions, &|p, c, in_range| {
        uncovered(
            &read_version(p).unwrap(),
            &read_version(c).unwrap(),
            &history,
            in_range,
        )
    });
    assert!(steps >= 8, "only {steps} versions of the claims file");
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

/// One version of the cell rule file: each column's rule, canonical (`exact, two-sided`).
fn read_cell_version(text: &str) -> Result<Vec<(Key, String)>, String> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let header: Vec<String> = r
        .headers()
        .map_err(|e| e.to_string())?
        .iter()
        .map(String::from)
        .collect();
    let mut out = vec![];
    for rec in r.records() {
        let rec = rec.map_err(|e| e.to_string())?;
        let col = |name: &str| {
            let i = header.iter().position(|h| h == name);
            i.and_then(|i| rec.get(i)).unwrap_or("").to_string()
        };
        let tolerance = col("tolerance");
        let how = How::from_fields(&col("compare"), tolerance.parse().ok(), &col("direction"))
            .map_or(
                format!("{} {tolerance} {}", col("compare"), col("direction")),
                |h| h.describe(),
            );
        out.push((
            (col("paper"), format!("{}:{}", col("table"), col("column"))),
            how,
        ));
    }
    Ok(out)
}

/// The cell rule changes from `prev` to `cur` (a rule changed or removed) that no history row
/// covers: a row of the paper, with id `TABLE:COLUMN`, the old rule, at a commit in range.
fn uncovered_cells(
    prev: &[(Key, String)],
    cur: &[(Key, String)],
    history: &[RuleChange],
    in_range: &mut dyn FnMut(&str) -> bool,
) -> Vec<String> {
    let mut missing = vec![];
    for ((paper, id), before) in prev {
        let now = cur.iter().find(|(k, _)| k.0 == *paper && k.1 == *id);
        if now.is_some_and(|(_, now)| now == before) {
            continue;
        }
        let covered = history
            .iter()
            .filter(|h| h.paper == *paper && h.id == *id)
            .filter(|h| h.old_cell.is_some_and(|o| o.describe() == *before))
            .any(|h| in_range(&h.commit));
        if !covered {
            let what = now.map_or("removed".to_string(), |(_, n)| format!("changed to {n:?}"));
            missing.push(format!(
                "{paper} {id}: the cell rule {before:?} {what} with no history row naming it"
            ));
        }
    }
    missing
}

#[test]
fn every_cell_rule_change_has_its_history_row() {
    let Some(versions) = or_skip(committed_versions(CELL_RULES_FILE)) else {
        return;
    };
    let history = rules::history().unwrap();
    let (_, missing) = walk(CELL_RULES_FILE, &versions, &|p, c, in_range| {
        uncovered_cells(
            &read_cell_version(p).unwrap(),
            &read_cell_version(c).unwrap(),
            &history,
            in_range,
        )
    });
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

/// The cell rules' check must be able to fail: a changed tolerance or a removed rule without
/// its row is found, with its row (right old rule, commit in range) it is not; a cell row that
/// also fills a claim's fields fails the history's load.
#[test]
fn a_cell_rule_change_without_its_row_is_found() {
    let head = "paper,table,column,compare,tolerance,direction,why\n";
    let v = |rest: &str| read_cell_version(&format!("{head}{rest}")).unwrap();
    let two = v("havs,table2,*,relative,0.02,two-sided,x\n");
    let five = v("havs,table2,*,relative,0.05,two-sided,x\n");
    let none = v("");
    // A history row with these fields set (by column name), the others empty.
    let row_with = |set: &[(&str, &str)]| {
        let fields: Vec<&str> = rules::HISTORY_HEADER
            .iter()
            .map(|h| set.iter().find(|(k, _)| k == h).map_or("", |(_, v)| *v))
            .collect();
        rules::parse_history(
            &format!(
                "{}\n{}\n",
                rules::HISTORY_HEADER.join(","),
                fields.join(",")
            ),
            "h.csv",
        )
    };
    let row = |tol: &str, compare: &str| {
        row_with(&[
            ("paper", "havs"),
            ("id", "table2:*"),
            ("date", "2026-12-07"),
            ("commit", "c"),
            ("reason", "why"),
            ("old_tolerance", tol),
            ("old_compare", compare),
            ("old_direction", "two-sided"),
        ])
    };
    let two_row = row("0.02", "relative").unwrap();
    let exact_row = row("", "exact").unwrap();
    let (mut yes, mut never) = (|_: &str| true, |_: &str| false);
    assert_eq!(uncovered_cells(&two, &five, &[], &mut yes).len(), 1);
    assert!(uncovered_cells(&two, &five, &two_row, &mut yes).is_empty());
    assert_eq!(uncovered_cells(&two, &five, &exact_row, &mut yes).len(), 1);
    assert_eq!(uncovered_cells(&two, &five, &two_row, &mut never).len(), 1);
    assert_eq!(uncovered_cells(&two, &none, &[], &mut yes).len(), 1);
    assert!(uncovered_cells(&two, &none, &two_row, &mut yes).is_empty());
    assert!(uncovered_cells(&none, &two, &[], &mut yes).is_empty());
    assert!(uncovered_cells(&two, &two, &[], &mut yes).is_empty());
    // A cell row is not a claim's: it names TABLE:COLUMN and fills no claim field.
    let e = row_with(&[
        ("paper", "havs"),
        ("id", "table2:*"),
        ("date", "2026-12-07"),
        ("commit", "c"),
        ("reason", "why"),
        ("old_metric", "total_ms"),
        ("old_compare", "exact"),
        ("old_direction", "two-sided"),
    ])
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("h.csv: line 2:") && e.contains("TABLE:COLUMN"),
        "{e}"
    );
    let e = row("0.5", "exact").unwrap_err().to_string();
    assert!(
        e.contains("line 2:") && e.contains("only a relative rule"),
        "{e}"
    );
}

/// The check must be able to fail: one changed rule field without a row, a moved id without
/// one, a row at a commit outside the two versions.
#[test]
fn a_rule_change_without_its_row_is_found() {
    let head = "paper,id,source,cites,claim,metric,datasets,a,b,expect,tolerance,hardware\n";
    let v = |tol: &str, id: &str| {
        read_version(&format!(
            "{head}havs,{id},paper,§5,x,kbuffer_pixels_k_gt2,spx2,kbuffer-analysis,,a=havs_table2.pixels_needing_k_gt_2,{tol},none\n"
        ))
        .unwrap()
    };
    let row = |id: &str, old_id: &str, tol: &str, commit: &str| {
        rules::parse_history(
            &format!(
                "{}\nhavs,{id},2026-12-03,{commit},why,{old_id},kbuffer_pixels_k_gt2,spx2,kbuffer-analysis,,a=havs_table2.pixels_needing_k_gt_2,{tol},measured,none,,,,\n",
                rules::HISTORY_HEADER.join(",")
            ),
            "h.csv",
        )
        .unwrap()
    };
    let mut yes = |_: &str| true;
    // The tolerance changed: no row, found; its row, not found; a row with another old value
    // or at a commit outside the versions, found.
    assert_eq!(
        uncovered(&v("0.05", "H5"), &v("0.02", "H5"), &[], &mut yes).len(),
        1
    );
    assert!(uncovered(
        &v("0.05", "H5"),
        &v("0.02", "H5"),
        &row("H5", "", "0.05", "c"),
        &mut yes
    )
    .is_empty());
    assert_eq!(
        uncovered(
            &v("0.05", "H5"),
            &v("0.02", "H5"),
            &row("H5", "", "0.1", "c"),
            &mut yes
        )
        .len(),
        1
    );
    let mut never = |_: &str| false;
    assert_eq!(
        uncovered(
            &v("0.05", "H5"),
            &v("0.02", "H5"),
            &row("H5", "", "0.05", "c"),
            &mut never
        )
        .len(),
        1
    );
    // Unchanged: nothing to find.
    assert!(uncovered(&v("0.05", "H5"), &v("0.05", "H5"), &[], &mut yes).is_empty());
    // The claim moved from H5 to H9: its removal and its move need a row naming H5.
    let moved = uncovered(&v("0.05", "H5"), &v("0.05", "H9"), &[], &mut yes);
    assert_eq!(moved.len(), 2, "{moved:?}");
    assert!(uncovered(
        &v("0.05", "H5"),
        &v("0.05", "H9"),
        &row("H9", "H5", "0.05", "c"),
        &mut yes
    )
    .is_empty());
}
