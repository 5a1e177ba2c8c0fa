//! Tests of [`crate::regress::compare`]: drift correction, rounds as the unit of replication,
//! provenance warnings (kept apart so compare.rs stays readable).
use super::*;

/// A results set of one group per entry of `factors` (algorithm `alg{i}`), 3 viewpoints
/// each, `rounds` rounds of `frames` frames around 10 ms × factor with 3 % noise; frame j
/// of a round is further multiplied by `1 + drift·j` (the machine drifting during a round).
pub(crate) fn run_dir(
    dir: &Path,
    factors: &[f64],
    rounds: u32,
    frames: u32,
    drift: f64,
    seed: u64,
) {
    let machine = vec![1.0; rounds as usize];
    run_dir_with_machine(dir, factors, &machine, frames, drift, seed);
}

/// [`run_dir`] with the machine's speed per round: round r's frames are further multiplied by
/// `machine[r]` (the VM running a round slower or faster as a whole).
fn run_dir_with_machine(
    dir: &Path,
    factors: &[f64],
    machine: &[f64],
    frames: u32,
    drift: f64,
    seed: u64,
) {
    let rounds = machine.len() as u32;
    std::fs::create_dir_all(dir).unwrap();
    let mut rng = crate::results::stats::TestRng::new(seed);
    let mut rows = vec![];
    for (i, f) in factors.iter().enumerate() {
        for vp in ["+x", "+x+y+z", "-x+y-z"] {
            let mut row = crate::results::Row {
                algorithm: format!("alg{i}"),
                settings: "k=2".parse().unwrap(),
                dataset: "box:1k".into(),
                viewpoint: vp.into(),
                frames: rounds * frames,
                ..Default::default()
            };
            for m in machine {
                for j in 0..frames {
                    let t = 10.0 * f * m * (1.0 + drift * j as f64) * (1.0 + 0.03 * rng.normal());
                    row.samples.total_ms.push(t);
                }
            }
            row.total_ms = Some(median(&row.samples.total_ms));
            rows.push(row);
        }
    }
    let file = ResultsFile {
        control: None,
        schema_version: crate::results::SCHEMA_VERSION,
        machine: crate::results::machine::MachineInfo::collect(),
        run: crate::results::RunDescription {
            rounds,
            frames,
            ..Default::default()
        },
        finished_utc: None,
        rows,
        errors: vec![],
    };
    crate::results::write_json(dir, &file).unwrap();
}

fn options(out: &Path, drift_correction: bool, drift_limit: f64) -> CompareOptions {
    CompareOptions {
        threshold: 1.10,
        alpha: 0.05,
        normalised: false,
        drift_correction,
        drift_limit,
        paired: false,
        fail_on: FailOn::Regression,
        out: out.to_path_buf(),
    }
}

/// Eight groups; NEW ×1.3 as a whole (the machine drifting) and group 3 ×2 on top: with
/// the run-wide factor divided out only that group is slower; without, all of them; a
/// factor beyond --drift-limit is a regression of its own; and 2 groups give no factor.
#[test]
fn drift_is_divided_out_and_one_slower_group_still_stands_out() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    run_dir(&a, &[1.0; 8], 5, 1, 0.0, 1);
    let mut slow = [1.3; 8];
    slow[3] = 2.6;
    run_dir(&b, &slow, 5, 1, 0.0, 2);
    let out = tmp.path().join("out");
    let c = compare(&a, &b, &options(&out, true, 1.5)).unwrap();
    let f = c.run_factor.unwrap();
    assert!((f - 1.3).abs() < 0.03, "{f}");
    assert!(c.drift_corrected);
    let slower: Vec<&str> = c
        .groups
        .iter()
        .filter(|g| g.total.verdict == Verdict::Slower)
        .map(|g| g.algorithm.as_str())
        .collect();
    assert_eq!(slower, ["alg3"], "{:#?}", c.groups);
    assert!(c.groups.iter().all(|g| g.total.p_adjusted.is_some()));

    let absolute = compare(&a, &b, &options(&out, false, 1.5)).unwrap();
    assert!(!absolute.drift_corrected);
    assert!(absolute
        .groups
        .iter()
        .all(|g| g.total.verdict == Verdict::Slower));

    let limited = compare(&a, &b, &options(&out, true, 1.2)).unwrap();
    assert!(
        limited
            .regressions
            .iter()
            .any(|r| r.text.starts_with("run-wide")),
        "{:?}",
        limited.regressions
    );

    let (c2, d2) = (tmp.path().join("c2"), tmp.path().join("d2"));
    run_dir(&c2, &[1.0; 2], 5, 1, 0.0, 3);
    run_dir(&d2, &[1.3; 2], 5, 1, 0.0, 4);
    let few = compare(&c2, &d2, &options(&out, true, 1.5)).unwrap();
    assert_eq!(few.run_factor, None);
    assert!(few
        .groups
        .iter()
        .all(|g| g.total.verdict == Verdict::Slower));
}

/// A row's samples split into one median per round.
#[test]
fn rounds_are_the_samples() {
    let row = Row {
        samples: crate::results::FrameSamples {
            total_ms: vec![1.0, 2.0, 3.0, 10.0, 20.0, 30.0],
            ..Default::default()
        },
        ..Default::default()
    };
    assert_eq!(
        round_values(&row, "total_ms", 2, false).unwrap(),
        [2.0, 20.0]
    );
    assert_eq!(round_values(&row, "total_ms", 1, false).unwrap(), [6.5]);
    // Samples that do not split into the rounds (a failed round) decide nothing.
    assert_eq!(round_values(&row, "total_ms", 4, false).unwrap(), [6.5]);
}

/// one round of 15 frames, NEW's frames drifting up by 2 % per frame and one
/// group even ×1.5 slower: frames of one round are one sample, so no time verdict and no
/// time regression; the same slowdown in 5 rounds is found, and 5 rounds without it are
/// clean (the input flips the verdict).
#[test]
fn one_round_never_gates_on_time_and_five_rounds_find_a_slowdown() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |s: &str| tmp.path().join(s);
    let out = p("out");
    let mut slow = [1.0; 8];
    slow[5] = 1.5;
    for seed in 0..5 {
        run_dir(&p("a1"), &[1.0; 8], 1, 15, 0.0, 10 + seed);
        run_dir(&p("b1"), &slow, 1, 15, 0.02, 20 + seed);
        let c = compare(&p("a1"), &p("b1"), &options(&out, true, 1.5)).unwrap();
        assert!(c.regressions.is_empty(), "{:?}", c.regressions);
        assert_eq!(c.rounds, Rounds { base: 1, new: 1 });
        let why = c.time_refused.as_deref().unwrap();
        assert!(
            why.contains("too few independent samples (1 rounds"),
            "{why}"
        );
        assert!(c
            .groups
            .iter()
            .all(|g| g.total.verdict == Verdict::TooFewSamples));
        assert!(c
            .rows
            .iter()
            .all(|r| r.times.iter().all(|t| t.verdict == Verdict::TooFewSamples)));
    }

    run_dir(&p("a5"), &[1.0; 8], 5, 3, 0.0, 1);
    run_dir(&p("b5"), &slow, 5, 3, 0.0, 2);
    run_dir(&p("c5"), &[1.0; 8], 5, 3, 0.0, 3);
    let found = compare(&p("a5"), &p("b5"), &options(&out, true, 1.5)).unwrap();
    assert_eq!(found.time_refused, None);
    assert!(
        found
            .regressions
            .iter()
            .any(|r| r.text.starts_with("slower: alg5 ")),
        "{:?}",
        found.regressions
    );
    let clean = compare(&p("a5"), &p("c5"), &options(&out, true, 1.5)).unwrap();
    assert!(clean.regressions.is_empty(), "{:?}", clean.regressions);
}

/// A dirty or debug side is named in the warnings; a clean release build is not.
#[test]
fn dirty_or_debug_sides_are_warned() {
    let mut f = ResultsFile {
        control: None,
        schema_version: crate::results::SCHEMA_VERSION,
        machine: crate::results::machine::MachineInfo::collect(),
        run: Default::default(),
        finished_utc: None,
        rows: vec![],
        errors: vec![],
    };
    f.machine.git_dirty = Some(false);
    f.machine.build_profile = Some("release".into());
    assert!(provenance_warnings("NEW", &f).is_empty());
    f.machine.git_dirty = Some(true);
    f.machine.build_profile = Some("debug".into());
    let w = provenance_warnings("NEW", &f);
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(
        w[0].contains("dirty") && w[1].contains("debug build"),
        "{w:?}"
    );
}

/// `ab`'s pairs: BASE's and NEW's round i ran side by side and share the machine's speed of
/// that moment (here ×0.75–×1.3 from pair to pair), and group 3 is ×1.2 slower in NEW. Paired,
/// each pair's own factor is divided out and only group 3 is slower; with the run-wide factor
/// the machine's scatter between rounds hides it. A same-build pair stays clean either way.
#[test]
fn paired_rounds_divide_out_each_pairs_drift() {
    let tmp = tempfile::tempdir().unwrap();
    let [a, b, same] = ["a", "b", "same"].map(|n| tmp.path().join(n));
    let machine = [1.0, 1.3, 0.75, 1.2, 0.8];
    run_dir_with_machine(&a, &[1.0; 8], &machine, 1, 0.0, 1);
    let mut slow = [1.0; 8];
    slow[3] = 1.2;
    run_dir_with_machine(&b, &slow, &machine, 1, 0.0, 2);
    run_dir_with_machine(&same, &[1.0; 8], &machine, 1, 0.0, 3);
    let out = tmp.path().join("out");
    let slower = |c: &Comparison| -> Vec<String> {
        c.groups
            .iter()
            .filter(|g| g.total.verdict == Verdict::Slower)
            .map(|g| g.algorithm.clone())
            .collect()
    };
    let paired = CompareOptions {
        paired: true,
        ..options(&out, true, 1.5)
    };
    let c = compare(&a, &b, &paired).unwrap();
    let factors = c
        .pair_factors
        .clone()
        .expect("8 groups, 5 pairs: a factor per pair");
    assert_eq!(factors.len(), 5);
    assert!(
        factors.iter().all(|f| (f - 1.0).abs() < 0.05),
        "{factors:?}"
    );
    assert_eq!(slower(&c), ["alg3"], "{:#?}", c.groups);
    assert_eq!(
        slower(&compare(&a, &same, &paired).unwrap()),
        Vec::<String>::new()
    );

    // Unpaired (`compare` of two separate runs): NEW's rounds met the machine in another
    // order, and one run-wide factor leaves the rounds' scatter in the samples.
    let [b2, same2] = ["b2", "same2"].map(|n| tmp.path().join(n));
    let shuffled = [0.75, 1.0, 1.2, 0.8, 1.3];
    run_dir_with_machine(&b2, &slow, &shuffled, 1, 0.0, 2);
    run_dir_with_machine(&same2, &[1.0; 8], &shuffled, 1, 0.0, 3);
    let unpaired = compare(&a, &b2, &options(&out, true, 1.5)).unwrap();
    assert!(unpaired.pair_factors.is_none());
    assert_eq!(
        slower(&unpaired),
        Vec::<String>::new(),
        "{:#?}",
        unpaired.groups
    );
    assert_eq!(
        slower(&compare(&a, &same2, &paired).unwrap()),
        Vec::<String>::new()
    );
}

/// `ab --no-drift-correction`, for a change that moves half the matrix: 3 pairs, the machine
/// ×0.95–×1.05 from pair to pair, groups 0–3 ×0.8 in NEW and groups 4–7 unchanged (the
/// control). The paired test on absolute times finds exactly the four faster groups; the
/// groups' scatter around the run-wide factor is the change itself, not noise, and must not
/// withhold time (before 32b0b77 it did: `ab` of c94ce65 read "too noisy to judge" on every
/// group).
#[test]
fn paired_rounds_on_absolute_times_judge_a_change_to_half_the_groups() {
    let tmp = tempfile::tempdir().unwrap();
    let [a, b, same] = ["a", "b", "same"].map(|n| tmp.path().join(n));
    let machine = [1.0, 1.05, 0.95];
    run_dir_with_machine(&a, &[1.0; 8], &machine, 3, 0.0, 11);
    let mut fast = [1.0; 8];
    fast[..4].fill(0.8);
    run_dir_with_machine(&b, &fast, &machine, 3, 0.0, 12);
    run_dir_with_machine(&same, &[1.0; 8], &machine, 3, 0.0, 13);
    let out = tmp.path().join("out");
    let absolute = CompareOptions {
        paired: true,
        ..options(&out, false, 1.5)
    };
    let faster = |c: &Comparison| -> Vec<String> {
        c.groups
            .iter()
            .filter(|g| g.total.verdict == Verdict::Faster)
            .map(|g| g.algorithm.clone())
            .collect()
    };
    let c = compare(&a, &b, &absolute).unwrap();
    assert!(!c.too_noisy, "{:?}", c.time_refused);
    assert!(!c.drift_corrected && c.pair_factors.is_none());
    assert_eq!(
        faster(&c),
        ["alg0", "alg1", "alg2", "alg3"],
        "{:#?}",
        c.groups
    );
    assert!(c.test.contains("absolute times"), "{}", c.test);
    // Rows are judged by the same paired test, its variance pooled over the rows: the twelve
    // rows of the faster groups read faster and no other row changes. A rank test of 3 rounds
    // against 3 (the rows' test before) cannot go below p = 0.1: none of them could.
    let improved: Vec<&str> = c
        .rows
        .iter()
        .filter(|r| r.status == RowStatus::Improvement)
        .map(|r| r.algorithm.as_str())
        .collect();
    assert_eq!(improved.len(), 12, "{:#?}", c.rows);
    assert!(improved
        .iter()
        .all(|a| ["alg0", "alg1", "alg2", "alg3"].contains(a)));
    let same_build = compare(&a, &same, &absolute).unwrap();
    assert!(
        same_build
            .groups
            .iter()
            .all(|g| g.total.verdict == Verdict::NoChange),
        "{:#?}",
        same_build.groups
    );
    assert!(
        same_build
            .rows
            .iter()
            .all(|r| r.status == RowStatus::NoChange),
        "{:#?}",
        same_build.rows
    );
    // The same rounds judged as separate runs keep the old rule: the scatter is taken for
    // noise and time is withheld.
    let separate = compare(&a, &b, &options(&out, false, 1.5)).unwrap();
    assert!(separate.too_noisy);
}

/// [`run_dir_with_machine`] with a control beside the rows: round r's control measured the
/// machine at speed `control[r]` (1 = BASE's usual speed) on two figures.
fn run_dir_controlled(dir: &Path, factors: &[f64], machine: &[f64], control: &[f64], seed: u64) {
    use crate::calibrate::control::{Control, ControlSample, Figures};
    use crate::results::machine::Figure;
    run_dir_with_machine(dir, factors, machine, 1, 0.0, seed);
    let figures = |speed: f64| -> Figures {
        [
            (Figure::FillFragmentsPerSec, 1e9 * speed),
            (Figure::RayStepsPerSec, 1e8 * speed),
        ]
        .into()
    };
    let mut file = ResultsFile::read(dir).unwrap();
    for row in &mut file.rows {
        row.round_control = control.iter().map(|s| figures(*s)).collect();
    }
    file.control = Some(Control {
        probes: vec!["fill".into(), "ray steps".into()],
        setup_seconds: 0.0,
        samples: control
            .iter()
            .enumerate()
            .map(|(r, s)| ControlSample {
                dataset: "box:1k".into(),
                round: r as u32,
                rows_before: 0,
                at_s: r as f64,
                utc: String::new(),
                seconds: 0.1,
                figures: figures(*s),
            })
            .collect(),
    });
    crate::results::write_json(dir, &file).unwrap();
}

/// The same build, NEW on a machine ×2.19 slower (a compile beside it), which its control
/// shows too: the machine, not a regression (exit 0); and the rule flips when the rows move
/// alone, every algorithm alike ×1.4 with the control unchanged: a regression common to every
/// algorithm (exit 3), which the run-wide factor of the old rule divided out as drift.
#[test]
fn the_control_tells_the_machine_from_a_change_common_to_every_algorithm() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, busy, slower) = (
        tmp.path().join("a"),
        tmp.path().join("busy"),
        tmp.path().join("slower"),
    );
    let ones = [1.0; 5];
    run_dir_controlled(&a, &[1.0; 8], &ones, &ones, 1);
    run_dir_controlled(&busy, &[1.0; 8], &[2.19; 5], &[1.0 / 2.19; 5], 2);
    run_dir_controlled(&slower, &[1.4; 8], &ones, &ones, 3);
    let opt = options(&tmp.path().join("out"), true, 1.5);

    let machine = compare(&a, &busy, &opt).unwrap();
    let m = machine.machine.as_ref().expect("both sides have a control");
    assert!((m.factor - 2.19).abs() < 1e-9, "{}", m.factor);
    assert!(machine.regressions.is_empty(), "{:#?}", machine.regressions);
    // compare_report::gate: no regression and not too noisy is exit 0.
    assert!(!machine.too_noisy);

    let code = compare(&a, &slower, &opt).unwrap();
    assert!((code.machine.as_ref().unwrap().factor - 1.0).abs() < 1e-9);
    assert!(
        code.regressions
            .iter()
            .any(|r| r.group == "run-wide" && r.text.contains("common to every algorithm")),
        "{:#?}",
        code.regressions
    );

    // The old rule, where NEW has no control: ×1.4 is under --drift-limit 1.5 and divided out.
    let old = tmp.path().join("old");
    run_dir(&old, &[1.4; 8], 5, 1, 0.0, 3);
    let without = compare(&a, &old, &opt).unwrap();
    assert!(without.machine.is_none());
    assert!(without
        .control_missing
        .as_deref()
        .unwrap()
        .starts_with("NEW has no control"));
    assert!(without.regressions.is_empty(), "{:#?}", without.regressions);
}

/// Two adapters: with a control on both sides, compare prints raw and control-normalised
/// ratios as information and never gates, even on rows ×1.4 slower with the machine
/// unchanged (which on one adapter is a regression); without NEW's control it refuses.
#[test]
fn two_adapters_are_compared_as_information_only() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, other) = (tmp.path().join("a"), tmp.path().join("other"));
    let ones = [1.0; 5];
    run_dir_controlled(&a, &[1.0; 8], &ones, &ones, 1);
    run_dir_controlled(&other, &[1.4; 8], &[0.5; 5], &[2.0; 5], 2);
    let mut file = ResultsFile::read(&other).unwrap();
    let own_adapter = file.machine.adapter.clone();
    let another = render_core::AdapterDescription {
        name: "Some Other GPU".into(),
        backend: "Vulkan".into(),
        device_type: "DiscreteGpu".into(),
        driver: String::new(),
        driver_info: String::new(),
    };
    file.machine.adapter = Some(another.clone());
    crate::results::write_json(&other, &file).unwrap();
    let opt = options(&tmp.path().join("out"), true, 1.5);
    let c = compare(&a, &other, &opt).unwrap();
    assert!(c.information_only());
    assert_eq!(c.outcome(), "information only");
    let across = c.across.as_ref().unwrap();
    assert!((across.machine_factor - 0.5).abs() < 1e-9);
    for g in &across.groups {
        assert!((g.raw_ratio / 0.7 - 1.0).abs() < 0.05, "{g:?}");
        assert!((g.control_ratio / 1.4 - 1.0).abs() < 0.05, "{g:?}");
    }
    // compare_report::gate returns at once on information only: exit 0.
    assert!(
        !c.regressions.is_empty(),
        "the ×1.4 is still found, as information"
    );
    // The same NEW on BASE's adapter gates: the ×1.4 is common to every algorithm.
    file.machine.adapter = own_adapter;
    crate::results::write_json(&other, &file).unwrap();
    let c = compare(&a, &other, &opt).unwrap();
    assert!(!c.information_only());
    assert!(!c.regressions.is_empty());
    // Another adapter without NEW's control: refused.
    file.machine.adapter = Some(another);
    file.control = None;
    crate::results::write_json(&other, &file).unwrap();
    let e = compare(&a, &other, &opt).unwrap_err().to_string();
    assert!(e.contains("--normalised"), "{e}");
}
