use std::path::Path;

use super::*;
use crate::results::Row;

fn row(algorithm: &str, settings: &str, view: u32, rate: f64) -> Row {
    let tets = 100_000;
    Row {
        algorithm: algorithm.into(),
        settings: crate::algorithms::parse_settings(algorithm, settings).unwrap(),
        dataset: "spx".into(),
        tets,
        viewpoint: format!("v{view}"),
        width: 512,
        height: 512,
        total_ms: Some(tets as f64 / rate * 1e3),
        tets_per_sec: Some(rate),
        ..Row::default()
    }
}

const LOOP: &str = "tiles=5x5;table=3d;mode=loop;et=off;layers=8";

/// Ours at 150, 160, 170 K tets/s; the peer at 90, 100, 110 K: medians 160 K and 100 K.
fn run_rows() -> Vec<Row> {
    let mut rows = vec![];
    for (v, (ours, peer)) in [(150e3, 90e3), (160e3, 100e3), (170e3, 110e3)]
        .into_iter()
        .enumerate()
    {
        rows.push(row("raycast", LOOP, v as u32, ours));
        rows.push(row("vtk-pt", "sort=cell-centre", v as u32, peer));
    }
    rows
}

fn target(at_least: f64) -> Target {
    Target {
        name: "loop vs PT".into(),
        ours: Side {
            algorithm: "raycast".into(),
            settings: "mode=loop;table=3d".into(),
        },
        peer: Side {
            algorithm: "vtk-pt".into(),
            settings: String::new(),
        },
        datasets: vec!["spx".into()],
        at_least,
    }
}

fn cell(rows: &[Row], at_least: f64) -> Cell {
    judge(&target(at_least), "run", &aggregate(rows), "spx")
        .unwrap()
        .unwrap()
}

/// The ratio is of medians over viewpoints; moving the peer's median viewpoint alone turns
/// "met" into "missed", and our median viewpoint alone turns it back.
#[test]
fn a_verdict_flips_with_one_row() {
    let rows = run_rows();
    let c = cell(&rows, 1.6);
    assert_eq!(c.ratio, Some(1.6));
    assert_eq!(c.verdict, Verdict::Met);

    let mut slower_peer = rows.clone();
    slower_peer[3] = row("vtk-pt", "sort=cell-centre", 1, 101e3);
    assert_eq!(cell(&slower_peer, 1.6).verdict, Verdict::Missed);

    let mut faster_ours = slower_peer.clone();
    faster_ours[2] = row("raycast", LOOP, 1, 165e3);
    assert_eq!(cell(&faster_ours, 1.6).verdict, Verdict::Met);

    // The rule's own number decides too.
    assert_eq!(cell(&rows, 1.61).verdict, Verdict::Missed);
}

/// No verdict without both sides whole: a failed row on either side, or a side with no rows.
#[test]
fn no_verdict_on_incomplete_evidence() {
    let mut rows = run_rows();
    rows[1].error = Some(crate::results::Failure::new(
        crate::results::Stage::Render,
        "renderer crashed",
    ));
    rows[1].tets_per_sec = None;
    let c = cell(&rows, 1.0);
    assert!(
        matches!(&c.verdict, Verdict::NoEvidence(why) if why.contains("1 of 3 vtk-pt rows failed")),
        "{c:?}"
    );

    let ours_only: Vec<Row> = run_rows()
        .into_iter()
        .filter(|r| r.algorithm == "raycast")
        .collect();
    assert!(matches!(
        cell(&ours_only, 1.0).verdict,
        Verdict::NoEvidence(_)
    ));

    // A data set neither side ran is no cell of that input, and a target no input covers says so.
    let file = TargetFile {
        source: "test".into(),
        targets: vec![Target {
            datasets: vec!["bluntfin".into()],
            ..target(1.0)
        }],
    };
    let cells = judge_all(&file, &[("run".into(), aggregate(&run_rows()))]).unwrap();
    assert_eq!(cells.len(), 1);
    assert!(matches!(&cells[0].verdict, Verdict::NoEvidence(w) if w.contains("no input")));
}

/// The ceiling is our rate at the roofline over the peer's rate, and the fraction needed is
/// the target over that ceiling.
#[test]
fn ceiling_and_fraction_needed_come_from_the_roofline() {
    let mut rows = run_rows();
    for r in rows.iter_mut().filter(|r| r.algorithm == "raycast") {
        // 100,000 tets in 1/3 ms: 300 M tets/s at the bound.
        r.roofline_ms = Some(1.0 / 3.0);
    }
    let c = cell(&rows, 1.5);
    let ceiling = c.ceiling.unwrap();
    assert!((ceiling - 3000.0).abs() < 1e-6, "{ceiling}");
    assert!((c.fraction_needed().unwrap() - 0.0005).abs() < 1e-12);
    assert_eq!(cell(&run_rows(), 1.5).ceiling, None);
}

/// Two runs of one data set: each has its own verdict, and the repeat table says 1 of 2 met
/// with the spread of the two ratios; one run alone has no repeat line.
#[test]
fn repeated_runs_are_summed_up_beside_their_verdicts() {
    let mut slower_peer = run_rows();
    slower_peer[3] = row("vtk-pt", "sort=cell-centre", 1, 101e3);
    let file = TargetFile {
        source: "test".into(),
        targets: vec![target(1.6)],
    };
    let two = [
        ("a".to_string(), aggregate(&run_rows())),
        ("b".to_string(), aggregate(&slower_peer)),
    ];
    let cells = judge_all(&file, &two).unwrap();
    assert_eq!(cells.len(), 2);
    assert_eq!(
        (cells[0].verdict.clone(), cells[1].verdict.clone()),
        (Verdict::Met, Verdict::Missed)
    );
    let table = repeat_table(&cells);
    assert!(
        table.contains("| loop vs PT | spx | 2 | 1 | 1.58–1.60 |"),
        "{table}"
    );
    // A Markdown table: every line of it starts with its first cell.
    assert!(
        table.contains("\n| target | data set | runs | met |"),
        "{table}"
    );
    assert_eq!(repeat_table(&cells[..1]), "");
}

/// A rule that selects two variants is an error, not a pick.
#[test]
fn a_side_must_select_one_variant() {
    let mut rows = run_rows();
    rows.push(row(
        "raycast",
        "tiles=5x5;table=3d;mode=loop;et=on;layers=8",
        0,
        1.0,
    ));
    let e = judge(&target(1.0), "run", &aggregate(&rows), "spx").unwrap_err();
    assert!(e.to_string().contains("selects 2 variants"), "{e}");
}

/// Bad rule files are refused with the file's name and what was wrong.
#[test]
fn bad_rule_files_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("not json", "not a target file"),
        (
            r#"{"source": "x", "targets": [], "extra": 1}"#,
            "not a target file",
        ),
        (
            r#"{"source": "x", "targets": [{"name": "t", "ours": {"algorithm": "a"}, "peer": {"algorithm": "b"}, "datasets": ["spx"], "at_least": 0}]}"#,
            "positive `at_least`",
        ),
        (
            r#"{"source": "x", "targets": [{"name": "t", "ours": {"algorithm": "a", "settings": "k"}, "peer": {"algorithm": "b"}, "datasets": ["spx"], "at_least": 1}]}"#,
            "bad settings",
        ),
    ];
    for (i, (text, want)) in cases.into_iter().enumerate() {
        let path = dir.path().join(format!("rules-{i}.json"));
        std::fs::write(&path, text).unwrap();
        let e = format!("{:#}", TargetFile::read(&path).unwrap_err());
        assert!(
            e.contains(&format!("rules-{i}.json")) && e.contains(want),
            "{e}"
        );
    }
    let e = read_rows(&dir.path().join("rules-0.json")).unwrap_err();
    assert!(format!("{e:#}").contains("rules-0.json"), "{e:#}");
}

/// The committed rules on the committed runs of 76a9a9f give the ratios tabled by hand for that
/// run (docs/notes/2026-12-06-vtk-targets-judged-by-the-tool.md), and the same verdicts. Two
/// cells read 0.01 higher here: the hand table divided rates already rounded to three figures
/// (1.47 M / 900.0 K = 1.63, 4.02 M / 1.07 M = 3.76), the tool divides the medians.
#[test]
fn committed_rules_reproduce_the_hand_table_of_76a9a9f() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let file = TargetFile::read(&root.join("docs/targets/lavapipe-vs-vtk.json")).unwrap();
    let inputs: Vec<(String, Vec<Aggregate>)> = ["spx", "bluntfin", "spx2"]
        .iter()
        .map(|d| {
            let path = root.join(format!("reports/peers/vtk/76a9a9f/{d}-14views-512.csv"));
            (d.to_string(), aggregate(&read_rows(&path).unwrap()))
        })
        .collect();
    let cells = judge_all(&file, &inputs).unwrap();
    let got: Vec<(String, String, String)> = cells
        .iter()
        .map(|c| {
            (
                c.dataset.clone(),
                format!("{:.2}", c.ratio.unwrap()),
                c.verdict.word(),
            )
        })
        .collect();
    let want = [
        ("spx", "6.81", "**met**"),
        ("bluntfin", "7.16", "**met**"),
        ("spx2", "7.16", "**met**"),
        ("spx", "0.47", "missed"),
        ("bluntfin", "1.64", "**met**"),
        ("spx2", "3.77", "**met**"),
        ("bluntfin", "0.58", "missed"),
        ("spx2", "0.79", "missed"),
    ];
    let want: Vec<(String, String, String)> = want
        .iter()
        .map(|(d, r, v)| (d.to_string(), r.to_string(), v.to_string()))
        .collect();
    assert_eq!(got, want);
    // Every cell has a ceiling: these runs carry their roofline.
    assert!(cells.iter().all(|c| c.ceiling.is_some()));
}
