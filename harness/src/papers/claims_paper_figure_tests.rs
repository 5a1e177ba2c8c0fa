//! Claims judged against the paper's own figures and on enough frames: H3 against the paper's
//! spx2 share, H7 and F1 re-judged from the committed H200 rows (one frame each: too few; the
//! same numbers on five frames decide) with their old rules beside.

use super::claims_tests::{eval, verdict_of};
use crate::papers::claims_report;
use crate::papers::session::{Extra, Measured};
use crate::papers::verdict::Verdict;

/// H3 compares spx2's share of pixels needing k > 6 with the paper's spx2 figure (512 of 512²,
/// 0.195 %): our 314 holds; 1,400 pixels (0.53 %), which held against the old 0.6 % of torso,
/// does not; the old rule beside reads holds.
#[test]
fn h3_is_judged_against_the_papers_spx2_figure_not_torsos() {
    use crate::papers::havs::analysis::{HavsAnalyses, KbufferRow};
    let with = |k_gt6: u64| {
        let x = Extra::with_own(HavsAnalyses {
            kbuffer: vec![KbufferRow {
                dataset: "spx2".into(),
                fragments: 6_615_778,
                pixels_k_gt2: 10_626,
                pixels_k_gt6: k_gt6,
                ..Default::default()
            }],
            kbuffer_views: 14,
            kbuffer_resolution: 512,
            ..Default::default()
        });
        eval("havs", &Measured::default(), &x)
    };
    assert_eq!(verdict_of(&with(314), "H3", Some("spx2")), Verdict::Holds);
    let r = with(1_400);
    assert_eq!(verdict_of(&r, "H3", Some("spx2")), Verdict::DoesNotHold);
    let h3 = r.iter().find(|r| r.claim.id == "H3").unwrap();
    let old: Vec<Verdict> = h3.earlier.iter().map(|(_, e)| e.verdict).collect();
    assert_eq!(
        old,
        vec![Verdict::Holds],
        "the old rule against torso's 0.6 %"
    );
}

/// The committed H200 rows of one paper's reproduction (`reports/baselines/…/reproduce`).
fn h200(paper: &str) -> Measured {
    let runs = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../reports/baselines/nvidia-h200-2026-12-04/reproduce")
        .join(paper)
        .join("runs");
    let mut m = Measured::default();
    let mut dirs: Vec<_> = std::fs::read_dir(&runs)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    dirs.sort();
    for dir in dirs {
        let f = crate::results::ResultsFile::read(&dir).unwrap();
        m.rows.extend(f.rows);
        if m.calibration.is_none() {
            m.calibration = f.machine.calibration;
        }
    }
    m
}

/// `m` with five frames behind every row (the numbers unchanged).
fn five_frames(m: &Measured) -> Measured {
    let mut m = m.clone();
    for r in &mut m.rows {
        r.frames = r.frames.max(5);
    }
    m
}

#[test]
fn h7_and_f1_rejudged_from_the_committed_h200_rows_show_their_old_rules_beside() {
    let committed = h200("havs");
    assert!(
        committed.calibration.is_some(),
        "the H200 runs carry their calibration"
    );
    // The committed rows are quick-mode rows, one frame each: too few to decide a rate.
    let r = eval("havs", &committed, &Extra::default());
    assert_eq!(verdict_of(&r, "H7", Some("f117")), Verdict::TooFewFrames);
    // The same numbers as if each row had five frames (their spread still zero) decide.
    let m = five_frames(&committed);
    let r = eval("havs", &m, &Extra::default());
    for d in ["f117", "kew", "spx2", "torso", "fighter"] {
        let h7 = r
            .iter()
            .find(|r| r.claim.id == "H7" && r.dataset.as_deref() == Some(d))
            .unwrap();
        assert_eq!(
            h7.evaluation.verdict,
            Verdict::Holds,
            "{}",
            h7.evaluation.numbers
        );
        assert!(h7
            .evaluation
            .numbers
            .contains("normalised by the fill rate"));
        // The whole band (until 16f45b8) read "does not hold" on the H200; the lower end
        // alone, unnormalised, "holds".
        let old: Vec<(&str, Verdict)> = h7
            .earlier
            .iter()
            .map(|(h, e)| (h.commit.as_str(), e.verdict))
            .collect();
        assert_eq!(old[0], ("16f45b8", Verdict::DoesNotHold), "{d}: {old:?}");
        assert_eq!(old[1].1, Verdict::Holds, "{d}: {old:?}");
    }
    let md = claims_report::markdown(&r);
    assert!(
        md.contains("by the rule before 16f45b8: does not hold") && md.contains("Rule history"),
        "{md}"
    );
    // A GPU 1000 times slower than the H200 measured: below the normalised threshold.
    let mut slow = m.clone();
    for row in &mut slow.rows {
        row.gpu_ms = row.gpu_ms.map(|g| g * 1000.0);
        row.gpu_ms_min = row.gpu_ms_min.map(|g| g * 1000.0);
        row.gpu_ms_max = row.gpu_ms_max.map(|g| g * 1000.0);
    }
    let r = eval("havs", &slow, &Extra::default());
    assert_eq!(verdict_of(&r, "H7", Some("f117")), Verdict::DoesNotHold);
    // The same rows against a calibrated fill rate 1000 times higher: also below.
    let mut fast_peak = m.clone();
    if let Some(c) = &mut fast_peak.calibration {
        c.fill_fragments_per_sec *= 1000.0;
    }
    let r = eval("havs", &fast_peak, &Extra::default());
    assert_eq!(verdict_of(&r, "H7", Some("f117")), Verdict::DoesNotHold);
    // Without a calibration the normalised claim is not checkable, with why.
    let mut uncalibrated = m.clone();
    uncalibrated.calibration = None;
    let r = eval("havs", &uncalibrated, &Extra::default());
    assert_eq!(verdict_of(&r, "H7", Some("f117")), Verdict::NotCheckable);

    // F1 on the H200: whole frames of fragment PT against 2.0 M tets/s, normalised.
    let f = five_frames(&h200("fragment-pt"));
    let r = eval("fragment-pt", &f, &Extra::default());
    for d in ["bluntfin", "comb", "post", "spx2"] {
        assert_eq!(verdict_of(&r, "F1", Some(d)), Verdict::Holds, "{d}");
    }
}

/// A normalised claim scales by the control of the rows it judges, not by the cached
/// calibration: the same H200 rows hold with a control at the calibration's fill rate and do
/// not with one a thousand times faster, while the cached calibration's verdict ("holds") is
/// printed beside.
#[test]
fn normalised_claims_use_the_control_of_their_rows() {
    use crate::results::machine::Figure;
    let m = five_frames(&h200("havs"));
    let fill = m.calibration.as_ref().unwrap().fill_fragments_per_sec;
    let with_control = |fill: f64| {
        let mut c = m.clone();
        for row in &mut c.rows {
            row.round_control = vec![[(Figure::FillFragmentsPerSec, fill)].into(); 3];
        }
        c
    };
    let h7 = |m: &Measured| {
        eval("havs", m, &Extra::default())
            .into_iter()
            .find(|r| r.claim.id == "H7" && r.dataset.as_deref() == Some("f117"))
            .unwrap()
            .evaluation
    };
    let same = h7(&with_control(fill));
    assert_eq!(same.verdict, Verdict::Holds, "{}", same.numbers);
    assert!(
        same.numbers
            .contains("the control measured beside the judged rows"),
        "{}",
        same.numbers
    );
    let faster = h7(&with_control(fill * 1000.0));
    assert_eq!(faster.verdict, Verdict::DoesNotHold, "{}", faster.numbers);
    assert!(
        faster.numbers.contains("by the cached calibration")
            && faster.numbers.contains("it would read: holds"),
        "{}",
        faster.numbers
    );
}
