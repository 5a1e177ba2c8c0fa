//! docs/github-actions-shards.yml, the workflow users copy: valid YAML, a matrix
//! job that runs `--shard i/N` with N taken from the matrix, and a merge job after it that
//! runs `report --merge` also when a shard failed (so the merge names the missing one).

use yaml_rust2::{Yaml, YamlLoader};

const WORKFLOW: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../docs/github-actions-shards.yml"
);

/// Every `run:` of a job, joined.
fn runs(job: &Yaml) -> String {
    job["steps"]
        .as_vec()
        .map(|steps| {
            steps
                .iter()
                .filter_map(|s| s["run"].as_str())
                .collect::<Vec<_>>()
                .join("\n")
        })
        .unwrap_or_default()
}

/// What is wrong with a sharding workflow's text (nothing, for a good one).
fn problems(text: &str) -> Vec<String> {
    let docs = match YamlLoader::load_from_str(text) {
        Ok(d) => d,
        Err(e) => return vec![format!("not YAML: {e}")],
    };
    let [w] = &docs[..] else {
        return vec![format!("{} YAML documents, expected one", docs.len())];
    };
    let mut wrong = vec![];
    let mut need = |ok: bool, what: &str| {
        if !ok {
            wrong.push(what.to_string());
        }
    };
    let shard = &w["jobs"]["shard"];
    let list: Vec<i64> = shard["strategy"]["matrix"]["shard"]
        .as_vec()
        .map(|l| l.iter().filter_map(Yaml::as_i64).collect())
        .unwrap_or_default();
    need(
        !list.is_empty() && list == (1..=list.len() as i64).collect::<Vec<_>>(),
        "jobs.shard.strategy.matrix.shard lists 1..=N",
    );
    need(
        shard["strategy"]["fail-fast"].as_bool() == Some(false),
        "fail-fast: false (the other shards finish when one fails)",
    );
    let run = runs(shard);
    need(
        run.contains("--shard ${{ matrix.shard }}/${{ strategy.job-total }}"),
        "the shard job runs --shard ${{ matrix.shard }}/${{ strategy.job-total }}",
    );
    need(
        run.contains("--out out/shard-${{ matrix.shard }}"),
        "each shard writes out/shard-I",
    );
    let merge = &w["jobs"]["merge"];
    need(
        merge["needs"].as_str() == Some("shard"),
        "the merge job needs the shard job",
    );
    need(
        merge["if"].as_str() == Some("${{ !cancelled() }}"),
        "the merge job runs also after a failed shard (if: ${{ !cancelled() }})",
    );
    need(
        runs(merge).contains("tetbench report --merge shards/shard-* --out out/merged"),
        "the merge job runs tetbench report --merge shards/shard-*",
    );
    wrong
}

#[test]
fn the_workflow_shards_and_merges() {
    let text = std::fs::read_to_string(WORKFLOW).unwrap_or_else(|e| panic!("{WORKFLOW}: {e}"));
    assert_eq!(problems(&text), Vec::<String>::new(), "{WORKFLOW}");
}

/// Each check reads what it claims to: a workflow changed in one place fails that check.
#[test]
fn a_changed_workflow_fails_the_check() {
    let text = std::fs::read_to_string(WORKFLOW).unwrap();
    for (from, to, check) in [
        ("--shard ${{ matrix.shard }}", "--frames 1", "runs --shard"),
        (
            "tetbench report --merge shards",
            "tetbench report shards",
            "report --merge",
        ),
        (
            "if: ${{ !cancelled() }}\n    runs-on",
            "runs-on",
            "also after a failed shard",
        ),
        ("fail-fast: false", "fail-fast: true", "fail-fast"),
        ("shard: [1, 2, 3, 4]", "shard: [1, 3, 4]", "1..=N"),
        ("jobs:", "jobs: [", "not YAML"),
    ] {
        assert!(text.contains(from), "{from:?} is not in {WORKFLOW}");
        let found = problems(&text.replacen(from, to, 1));
        assert!(
            found.iter().any(|p| p.contains(check)),
            "{from:?} → {to:?}: {found:?}"
        );
    }
}
