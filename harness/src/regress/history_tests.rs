//! Tests of [`crate::regress::history`]: step detection, the pairs, the one-adapter rule
//! (kept apart so history.rs stays readable).
use super::*;

/// A ×1.3 level change in a noisy series is one step at the right place; the same series
/// without it has none; a step between two runs of one commit is not allowed.
#[test]
fn steps_are_found_where_the_level_changes() {
    let wobble = [1.0, 1.03, 0.98, 1.01, 0.97, 1.02, 1.0, 0.99];
    let flat: Vec<f64> = wobble.iter().chain(&wobble).map(|w| 10.0 * w).collect();
    let none = vec![false; flat.len()];
    let p = step_penalty(&flat, 1.10);
    assert!(detect_steps(&flat, &none, p, 1.10).is_empty());
    let stepped: Vec<f64> = flat
        .iter()
        .enumerate()
        .map(|(i, v)| if i >= 8 { v * 1.3 } else { *v })
        .collect();
    let p = step_penalty(&stepped, 1.10);
    assert_eq!(detect_steps(&stepped, &none, p, 1.10), [8]);
    // Run 8 measured the same commit as run 7: the step moves to where the code changed.
    let mut same = none.clone();
    same[8] = true;
    let at = detect_steps(&stepped, &same, p, 1.10);
    assert!(!at.contains(&8), "{at:?}");
    // All one commit: no step at all.
    assert!(detect_steps(&stepped, &vec![true; stepped.len()], p, 1.10).is_empty());
}

/// The DP grown backwards with running heaps finds what the direct one (every segment's
/// cost from a sorted copy) finds, exact ties included (case 14 has one), on noisy series
/// with and without steps.
#[test]
fn the_fast_fit_finds_what_the_direct_one_finds() {
    fn direct(values: &[f64], same: &[bool], penalty: f64, threshold: f64) -> Vec<usize> {
        let y: Vec<f64> = values.iter().map(|v| v.max(1e-12).ln()).collect();
        let n = y.len();
        let cost = |a: usize, b: usize| {
            let m = median(&y[a..b]);
            y[a..b].iter().map(|v| (v - m).abs()).sum::<f64>()
        };
        let (mut best, mut from) = (vec![0.0f64; n + 1], vec![0usize; n + 1]);
        for j in 1..=n {
            let costs: Vec<f64> = (0..j)
                .map(|i| {
                    if i > 0 && same[i] {
                        f64::INFINITY
                    } else {
                        best[i] + cost(i, j) + penalty
                    }
                })
                .collect();
            (best[j], from[j]) = least(&costs);
        }
        let mut starts = vec![];
        let mut j = n;
        while j > 0 {
            starts.push(from[j]);
            j = from[j];
        }
        starts.reverse();
        let (mut steps, mut seg) = (vec![], 0);
        for (k, &s) in starts.iter().enumerate().skip(1) {
            let end = starts.get(k + 1).copied().unwrap_or(n);
            if (median(&y[s..end]) - median(&y[seg..s])).abs() >= threshold.ln() {
                steps.push(s);
                seg = s;
            }
        }
        steps
    }
    // A fixed pseudo-random sequence (an LCG): noise of ±10 %, levels ×1.3 and ×0.7.
    let mut state = 12345u64;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut found = 0;
    for case in 0..40 {
        let n = 20 + case * 3;
        let values: Vec<f64> = (0..n)
            .map(|i| {
                let level = match case % 4 {
                    0 => 1.0,
                    1 if i >= n / 3 => 1.3,
                    2 if i >= n / 2 => 0.7,
                    3 if i >= n / 4 && i < 3 * n / 4 => 1.5,
                    _ => 1.0,
                };
                // Every fifth case rounds to few distinct values: ties in the costs.
                let v = 10.0 * level * (0.9 + 0.2 * uniform());
                if case % 5 == 0 {
                    v.round()
                } else {
                    v
                }
            })
            .collect();
        let same: Vec<bool> = (0..n).map(|i| i % 7 == 3).collect();
        for threshold in [1.05, 1.10] {
            let p = step_penalty(&values, threshold);
            let fast = detect_steps(&values, &same, p, threshold);
            assert_eq!(fast, direct(&values, &same, p, threshold), "case {case}");
            found += fast.len();
        }
    }
    assert!(found > 20, "the cases hold steps to find: {found}");
}

/// Six runs of two groups; the code changes at run 3 (a new commit) and makes alg0 ×1.5
/// slower: compare's test marks the pair, the fit puts one step at run 3 for alg0 and
/// none for alg1; the same six runs all of one commit have no step at all. The runs are
/// given out of order and put in order by date.
#[test]
fn history_marks_the_step_where_the_code_changed() {
    let tmp = tempfile::tempdir().unwrap();
    let write = |name: &str, k: usize, commit: &str, slow: f64| {
        let dir = tmp.path().join(name);
        std::fs::create_dir_all(&dir).unwrap();
        let mut rows = vec![];
        // alg0 at two sizes, only the 64² one made slower: one variant, two groups.
        for (g, f, size) in [(0, slow, 64), (0, 1.0, 128), (1, 1.0, 64)] {
            for (v, vp) in ["+x", "-x", "+y"].iter().enumerate() {
                let mut row = Row {
                    algorithm: format!("alg{g}"),
                    settings: "k=2".parse().unwrap(),
                    dataset: "box:1k".into(),
                    viewpoint: vp.to_string(),
                    width: size,
                    height: size,
                    ..Default::default()
                };
                row.samples.total_ms = (0..5)
                    .map(|r| 10.0 * f * (1.0 + 0.01 * (((k + v + r) * 7) % 5) as f64))
                    .collect();
                row.total_ms = Some(median(&row.samples.total_ms));
                rows.push(row);
            }
        }
        let mut machine = crate::results::machine::MachineInfo::collect();
        machine.git_commit = Some(commit.into());
        machine.date_utc = format!("2026-01-0{}T00:00:00Z", k + 1);
        let file = ResultsFile {
            control: None,
            schema_version: crate::results::SCHEMA_VERSION,
            machine,
            run: crate::results::RunDescription {
                rounds: 5,
                frames: 1,
                ..Default::default()
            },
            finished_utc: None,
            rows,
            errors: vec![],
        };
        crate::results::write_json(&dir, &file).unwrap();
        dir
    };
    let mut changed = vec![];
    let mut same = vec![];
    for k in (0..6).rev() {
        let (commit, slow) = if k < 3 { ("aaa", 1.0) } else { ("bbb", 1.5) };
        changed.push(write(&format!("c{k}"), k, commit, slow));
        same.push(write(&format!("s{k}"), k, "aaa", 1.0));
    }
    let out = tmp.path().join("out");
    let h = history(&changed, &out, 1.10, 0.05).unwrap();
    assert_eq!(h.runs[0].date_utc, "2026-01-01T00:00:00Z");
    assert_eq!(h.runs[3].label, "bbb 2026-01-04");
    let alg0 = &h.series[0];
    assert_eq!(alg0.algorithm, "alg0");
    let steps: Vec<usize> = alg0
        .points
        .iter()
        .filter(|p| p.step.is_some())
        .map(|p| p.run)
        .collect();
    assert_eq!(steps, [3]);
    assert!((alg0.points[3].step.unwrap() - 1.5).abs() < 0.05);
    assert!(
        alg0.points[3]
            .changes
            .iter()
            .any(|c| c.starts_with("slower")),
        "{:?}",
        alg0.points[3]
    );
    // The same variant at 128² did not change: no step, and not the 64² group's verdict.
    assert_eq!(
        (h.series[1].algorithm.as_str(), h.series[1].width),
        ("alg0", 128)
    );
    assert!(h.series[1]
        .points
        .iter()
        .all(|p| p.step.is_none() && p.changes.is_empty()));
    assert!(h.series[2].points.iter().all(|p| p.step.is_none()));
    let flat = history(&same, &out, 1.10, 0.05).unwrap();
    assert!(flat.series.iter().all(|s| s
        .points
        .iter()
        .all(|p| p.step.is_none() && p.changes.is_empty())));

    // Another adapter in the series is refused.
    let mut other = ResultsFile::read(&changed[0]).unwrap();
    other.machine.cpu_model = "another CPU".into();
    other.machine.adapter = Some(render_core::AdapterDescription {
        name: "Other GPU".into(),
        backend: "vulkan".into(),
        device_type: "DiscreteGpu".into(),
        driver: String::new(),
        driver_info: String::new(),
    });
    crate::results::write_json(&changed[0], &other).unwrap();
    let e = history(&changed, &out, 1.10, 0.05).unwrap_err().to_string();
    assert!(e.contains("another adapter"), "{e}");
}
