//! The JSON Schemas of every JSON file tetbench writes for other programs to read, generated
//! from the Rust types (`schemars`) and committed in `docs/`: `results.json`, `compare.json`,
//! `history.json`, `ab.json` and `bisect.json`. Each file carries a `schema_version`; each
//! schema rejects unknown fields and requires the core ones. The tests regenerate every schema
//! (`TETBENCH_BLESS=1 cargo test -p harness --lib schemas::` rewrites them) and validate real
//! outputs against the committed copies, and a mutated field against them must fail.

use std::path::PathBuf;

/// Generates one output's JSON Schema.
pub type SchemaOf = fn() -> serde_json::Value;

/// Each output by name (`docs/NAME.schema.json`) and the function that generates its schema.
pub const SCHEMAS: [(&str, SchemaOf); 5] = [
    ("results", crate::results::json_schema),
    ("compare", crate::regress::compare::json_schema),
    ("history", crate::regress::history::json_schema),
    ("ab", crate::regress::ab::json_schema),
    ("bisect", crate::regress::bisect::json_schema),
];

/// Where the schema of output `name` is committed.
pub fn doc_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../docs/{name}.schema.json"))
}

/// Validates `value` against the committed schema of output `name` (a full draft 2020-12
/// validator); the error lists what failed where.
#[cfg(test)]
pub fn validate(name: &str, value: &serde_json::Value) -> Result<(), String> {
    let path = doc_path(name);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let schema: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let url = format!("file:///{name}.schema.json");
    let mut compiler = boon::Compiler::new();
    let mut schemas = boon::Schemas::new();
    compiler
        .add_resource(&url, schema)
        .map_err(|e| e.to_string())?;
    let index = compiler
        .compile(&url, &mut schemas)
        .map_err(|e| format!("{name} schema: {e}"))?;
    schemas.validate(value, index).map_err(|e| format!("{e:#}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Value};
    use std::path::Path;

    use crate::regress::compare::{CompareOptions, FailOn};

    /// docs/*.schema.json are what the types generate.
    #[test]
    fn checked_in_schemas_match_the_types() {
        for (name, schema) in SCHEMAS {
            let path = doc_path(name);
            let text = serde_json::to_string_pretty(&schema()).unwrap() + "\n";
            if std::env::var_os("TETBENCH_BLESS").is_some() {
                std::fs::write(&path, &text).unwrap();
            }
            let stored = std::fs::read_to_string(&path).unwrap_or_default();
            assert!(
                stored == text,
                "{} is out of date: regenerate it with TETBENCH_BLESS=1 cargo test -p harness \
                 --lib schemas::",
                path.display()
            );
        }
    }

    /// A named change to a valid document that must make it invalid.
    type Mutation = (&'static str, fn(&mut Value));

    /// `value` validates as `name`, and each mutation of it does not.
    fn validates_and_mutations_fail(name: &str, value: &Value, mutations: &[Mutation]) {
        validate(name, value).unwrap_or_else(|e| panic!("{name}: {e}"));
        for (what, mutate) in mutations {
            let mut bad = value.clone();
            mutate(&mut bad);
            assert!(
                validate(name, &bad).is_err(),
                "{name} with {what} still validates"
            );
        }
    }

    /// A results.json written by a real run (the committed baseline) validates against
    /// docs/results.schema.json (generated from the types); with
    /// `total_ms` renamed, an unknown field, or a required field missing, it does not.
    #[test]
    fn a_real_results_file_validates_and_a_renamed_column_does_not() {
        let baselines = Path::new(env!("CARGO_MANIFEST_DIR")).join("../reports/baselines");
        let dir = std::fs::read_dir(&baselines)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| p.join(crate::results::JSON_FILE).is_file())
            .expect("a committed baseline");
        crate::results::ResultsFile::read(&dir).unwrap();
        let real: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(crate::results::JSON_FILE)).unwrap(),
        )
        .unwrap();
        validate("results", &real).unwrap();
        let mutations: [Mutation; 4] = [
            ("total_ms renamed", |v| {
                let row = v["rows"][0].as_object_mut().unwrap();
                let t = row.remove("total_ms").unwrap();
                row.insert("total_msec".into(), t);
            }),
            ("an unknown machine field", |v| {
                v["machine"]["gpu_temperature"] = serde_json::json!(80);
            }),
            ("no algorithm", |v| {
                v["rows"][0].as_object_mut().unwrap().remove("algorithm");
            }),
            ("a counter as a word", |v| {
                v["rows"][0]["counters"] = serde_json::json!({"fragments": "many"});
            }),
        ];
        for (what, mutate) in mutations {
            let mut bad = real.clone();
            mutate(&mut bad);
            assert!(
                validate("results", &bad).is_err(),
                "results.json with {what} still validates"
            );
        }
    }

    fn options(out: &Path) -> CompareOptions {
        CompareOptions {
            threshold: 1.10,
            alpha: 0.05,
            normalised: false,
            drift_correction: true,
            drift_limit: 1.5,
            paired: false,
            fail_on: FailOn::Never,
            out: out.to_path_buf(),
        }
    }

    /// Two result sets of six groups; NEW's first row renders one fragment more.
    fn two_runs(tmp: &Path) -> (PathBuf, PathBuf) {
        use crate::regress::compare::tests::run_dir;
        let (a, b) = (tmp.join("a"), tmp.join("b"));
        run_dir(&a, &[1.0; 6], 3, 2, 0.0, 1);
        run_dir(&b, &[1.0, 1.0, 1.0, 1.0, 1.0, 1.6], 3, 2, 0.0, 2);
        for (dir, fragments) in [(&a, 1000.0), (&b, 1001.0)] {
            let mut f = crate::results::ResultsFile::read(dir).unwrap();
            f.rows[0].counters.insert("fragments", fragments);
            crate::results::write_json(dir, &f).unwrap();
        }
        (a, b)
    }

    /// compare.json as written by `compare`: validates; without schema_version, with a
    /// finding's ratio as text, or with a field the schema lacks, it does not.
    #[test]
    fn compare_json_validates_and_mutated_fields_fail() {
        let tmp = tempfile::tempdir().unwrap();
        let (a, b) = two_runs(tmp.path());
        let out = tmp.path().join("cmp");
        crate::regress::compare_report::run_command(
            &a,
            &b,
            &options(&out),
            crate::regress::compare_report::CompareFormat::Json,
        )
        .unwrap();
        let written: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("compare.json")).unwrap())
                .unwrap();
        let regressions = written["regressions"].as_array().unwrap();
        assert!(
            regressions
                .iter()
                .any(|f| f["metric"] == "fragments" && f["verdict"] == "more"),
            "{regressions:?}"
        );
        assert!(regressions.iter().any(|f| f["metric"] == "total_ms"));
        validates_and_mutations_fail(
            "compare",
            &written,
            &[
                ("no schema_version", |v| {
                    v.as_object_mut().unwrap().remove("schema_version");
                }),
                ("a ratio as text", |v| {
                    v["regressions"][0]["ratio"] = json!("×1.5");
                }),
                ("a sentence as a regression", |v| {
                    v["regressions"][0] = json!("slower: alg5");
                }),
                ("an unknown field", |v| {
                    v["rows"][0]["extra"] = json!(1);
                }),
                ("an unknown status", |v| {
                    v["rows"][0]["status"] = json!("worse-ish");
                }),
            ],
        );
    }

    /// history.json, ab.json and bisect.json as their commands build them.
    #[test]
    fn history_ab_and_bisect_json_validate_and_mutated_fields_fail() {
        let tmp = tempfile::tempdir().unwrap();
        let (a, b) = two_runs(tmp.path());
        let out = tmp.path().join("history");
        crate::regress::history_page::run_command(&[a.clone(), b.clone()], &out, 1.10, 0.05)
            .unwrap();
        let history: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("history.json")).unwrap())
                .unwrap();
        validates_and_mutations_fail(
            "history",
            &history,
            &[
                ("no schema_version", |v| {
                    v.as_object_mut().unwrap().remove("schema_version");
                }),
                ("a point's time as text", |v| {
                    v["series"][0]["points"][0]["total_ms"] = json!("10 ms");
                }),
            ],
        );

        let cmp =
            crate::regress::compare::compare(&a, &b, &options(&tmp.path().join("c"))).unwrap();
        let ab = crate::regress::ab::AbReport {
            schema_version: crate::regress::ab::SCHEMA_VERSION,
            base: "HEAD~1".into(),
            new: "HEAD".into(),
            base_binary: "/x/base".into(),
            new_binary: "/x/new".into(),
            pairs: 3,
            run_args: vec!["--algorithms".into(), "havs".into()],
            drift: vec![],
            outcome: cmp.outcome().into(),
            regressions: cmp.regressions.clone(),
            seconds: 12.5,
        };
        validates_and_mutations_fail(
            "ab",
            &serde_json::to_value(&ab).unwrap(),
            &[
                ("pairs as text", |v| v["pairs"] = json!("three")),
                ("a finding without its verdict", |v| {
                    v["regressions"][0]
                        .as_object_mut()
                        .unwrap()
                        .remove("verdict");
                }),
            ],
        );
        let bisect = crate::regress::bisect::BisectReport {
            schema_version: crate::regress::bisect::SCHEMA_VERSION,
            good: "v1".into(),
            bad: "v2".into(),
            candidates: 1,
            steps: vec![crate::regress::bisect::Step {
                commit: "abc".into(),
                subject: "slower".into(),
                regression: true,
                regressions: cmp.regressions.clone(),
                dir: "step-01".into(),
            }],
            first_bad: Some("abc".into()),
            first_bad_subject: Some("slower".into()),
        };
        validates_and_mutations_fail(
            "bisect",
            &serde_json::to_value(&bisect).unwrap(),
            &[
                ("no schema_version", |v| {
                    v.as_object_mut().unwrap().remove("schema_version");
                }),
                ("a step's verdict as text", |v| {
                    v["steps"][0]["regression"] = json!("yes");
                }),
            ],
        );
    }
}
