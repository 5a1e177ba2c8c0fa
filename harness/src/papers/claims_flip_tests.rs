//! Every measured claim that compares two runs' timings (`a<b`, `a>b`, `a/b in LO..HI`) or holds
//! one timing against a threshold (`a>N`, `a<N`) is fed rows that satisfy it and rows that do
//! not, on a hardware adapter with five frames a side: its verdict must flip from *holds* to
//! *does not hold*; so do G7's spread over the viewpoints, S2's stage share and the CPU sorts
//! of H1 and H2. The counts and image claims have their own flip tests (`claims_tests.rs`,
//! `sides.rs`); the normalised rates H7 and F1 are re-judged from the H200's rows there.

use crate::papers::claims::{self, Claim, ExpectSpec, Metric, VariantSpec};
use crate::papers::evidence::{evaluate_claims, no_analyses};
use crate::papers::rules::{Evidence, Normalise};
use crate::papers::session::{Extra, Measured};
use crate::papers::verdict::{Expect, Verdict};
use crate::results::Row;

const TETS: u64 = 100_000;

/// The frame time (ms) that gives `metric` the value `v` on a row of [`TETS`] tets.
fn time_for(metric: &Metric, v: f64) -> Option<f64> {
    match metric {
        Metric::TotalMs | Metric::GpuMs | Metric::CpuMs => Some(v),
        Metric::Fps => Some(1e3 / v),
        Metric::TetsPerSec | Metric::GpuTetsPerSec => Some(TETS as f64 * 1e3 / v),
        _ => None,
    }
}

/// One row of `spec` on `dataset` whose every time is `ms`, its five frames within ±0.5 %.
fn row(spec: &VariantSpec, dataset: &str, ms: f64) -> Row {
    let (lo, hi) = (Some(ms * 0.995), Some(ms * 1.005));
    Row {
        algorithm: spec.algorithm.clone(),
        settings: spec.settings.clone(),
        dataset: dataset.into(),
        tets: TETS,
        viewpoint: "+x".into(),
        total_ms: Some(ms),
        total_ms_min: lo,
        total_ms_max: hi,
        gpu_ms: Some(ms),
        gpu_ms_min: lo,
        gpu_ms_max: hi,
        cpu_ms: Some(ms),
        cpu_ms_min: lo,
        cpu_ms_max: hi,
        frames: 5,
        device_type: "DiscreteGpu".into(),
        ..Default::default()
    }
}

/// The verdict of `c` on its first data set (or on none, when its sides are pinned) when side
/// `a` measures `va` and side `b` (if any) `vb`.
fn verdict(c: &Claim, va: f64, vb: f64) -> (Verdict, String) {
    let d = c.datasets.first().cloned();
    let mut rows = vec![];
    for (spec, v) in [(Some(&c.a), va), (c.b.as_ref(), vb)] {
        let Some(spec) = spec else { continue };
        let on = spec.dataset.clone().or(d.clone()).expect("a data set");
        rows.push(row(spec, &on, time_for(&c.metric, v).unwrap()));
    }
    let m = Measured {
        rows,
        ..Default::default()
    };
    let r = evaluate_claims(&c.paper, &m, &Extra::default(), &no_analyses);
    let e = &r
        .iter()
        .find(|r| r.claim.id == c.id && r.dataset == d)
        .unwrap()
        .evaluation;
    (e.verdict, e.numbers.clone())
}

/// Values of (a, b) that satisfy the claim's rule and values that break it.
fn satisfying_and_breaking(expect: Expect) -> Option<((f64, f64), (f64, f64))> {
    Some(match expect {
        Expect::Less => ((100.0, 200.0), (200.0, 100.0)),
        Expect::Greater => ((200.0, 100.0), (100.0, 200.0)),
        Expect::Band(lo, hi) => (((lo + hi) / 2.0 * 100.0, 100.0), (hi * 3.0 * 100.0, 100.0)),
        Expect::Above(t) => ((t * 2.0, 0.0), (t / 2.0, 0.0)),
        Expect::Below(t) => ((t / 2.0, 0.0), (t * 2.0, 0.0)),
        Expect::Equals(_) => return None,
    })
}

#[test]
fn every_timing_claim_flips_when_its_measurement_does() {
    let mut checked = vec![];
    for c in claims::all().unwrap() {
        let ExpectSpec::Fixed(expect) = c.expect else {
            continue;
        };
        let timed = time_for(&c.metric, 1.0).is_some();
        let rows_only = [Some(&c.a), c.b.as_ref()]
            .into_iter()
            .flatten()
            .all(|s| crate::algorithms::describe(&s.algorithm).is_some());
        if c.evidence != Evidence::Measured
            || c.normalise != Normalise::None
            || !timed
            || !rows_only
        {
            continue;
        }
        let Some((good, bad)) = satisfying_and_breaking(expect) else {
            continue;
        };
        let (v, numbers) = verdict(&c, good.0, good.1);
        assert_eq!(v, Verdict::Holds, "{} {}: {numbers}", c.paper, c.id);
        let (v, numbers) = verdict(&c, bad.0, bad.1);
        assert_eq!(v, Verdict::DoesNotHold, "{} {}: {numbers}", c.paper, c.id);
        checked.push(format!("{} {}", c.paper, c.id));
    }
    // HAVS H6, H8–H10, GATOR G4–G6, fragment PT F4–F6, ray casting R1–R3, splatting S1.
    assert!(checked.len() >= 14, "only {checked:?}");
}

/// The claim `id` of `paper` on its first data set over `rows` (a hardware adapter's).
fn verdict_on(paper: &str, id: &str, rows: Vec<Row>) -> (Verdict, String) {
    let c = claims::all()
        .unwrap()
        .into_iter()
        .find(|c| c.paper == paper && c.id == id)
        .unwrap();
    let m = Measured {
        rows,
        ..Default::default()
    };
    let r = evaluate_claims(paper, &m, &Extra::default(), &no_analyses);
    let e = &r
        .iter()
        .find(|r| {
            r.claim.id == id && r.dataset.as_deref() == c.datasets.first().map(|s| s.as_str())
        })
        .unwrap()
        .evaluation;
    (e.verdict, e.numbers.clone())
}

#[test]
fn the_spread_over_viewpoints_and_the_share_of_a_stage_flip_too() {
    let g7 = claims::all()
        .unwrap()
        .into_iter()
        .find(|c| c.id == "G7")
        .unwrap();
    // G7: timings over the viewpoints within 5 % of their mean.
    let views = |times: [f64; 2]| {
        ["+x", "-y"]
            .iter()
            .zip(times)
            .map(|(view, ms)| Row {
                viewpoint: view.to_string(),
                ..row(&g7.a, &g7.datasets[0], ms)
            })
            .collect::<Vec<_>>()
    };
    let (v, n) = verdict_on("gator", "G7", views([100.0, 102.0]));
    assert_eq!(v, Verdict::Holds, "{n}");
    let (v, n) = verdict_on("gator", "G7", views([100.0, 120.0]));
    assert_eq!(v, Verdict::DoesNotHold, "{n}");
    // S2: the sort is the most expensive stage.
    let s2 = claims::all()
        .unwrap()
        .into_iter()
        .find(|c| c.id == "S2")
        .unwrap();
    let staged = |stages: &str| {
        vec![Row {
            stages: stages.into(),
            ..row(&s2.a, &s2.datasets[0], 100.0)
        }]
    };
    let (v, n) = verdict_on("splat", "S2", staged("buckets=2;sort=6;splat=3"));
    assert_eq!(v, Verdict::Holds, "{n}");
    let (v, n) = verdict_on("splat", "S2", staged("buckets=2;sort=1;splat=3"));
    assert_eq!(v, Verdict::DoesNotHold, "{n}");
}

#[test]
fn the_cpu_sort_claims_flip_with_the_sorts_timed() {
    use crate::papers::havs::{self, analysis};
    let sorts = |radix_ms: f64, quick_ms: f64| {
        let sort = |name: &'static str, ms: f64| analysis::SortRow {
            name,
            ms,
            min_ms: ms * 0.99,
            max_ms: ms * 1.01,
            repeats: 5,
            keys_per_sec: 1e6 / (ms * 1e-3),
        };
        Extra::with_own(analysis::HavsAnalyses {
            sorts: vec![
                sort("quicksort", quick_ms),
                sort("radix sort (HAVS §5.1, one core)", radix_ms),
            ],
            kbuffer: vec![],
            kbuffer_views: 0,
            kbuffer_resolution: 0,
        })
    };
    let verdicts = |x: &Extra| {
        let r = evaluate_claims("havs", &Measured::default(), x, &|metric, spec, d| {
            havs::claim_side(x, metric, spec, d)
        });
        ["H1", "H2"].map(|id| {
            r.iter()
                .find(|r| r.claim.id == id)
                .unwrap()
                .evaluation
                .verdict
        })
    };
    // 1 M floats in 20 ms (50 M/s, quicksort 80 ms): both hold; in 100 ms (10 M/s, below
    // §5.1's 15 M/s, and slower than quicksort's 80 ms): neither.
    assert_eq!(verdicts(&sorts(20.0, 80.0)), [Verdict::Holds; 2]);
    assert_eq!(verdicts(&sorts(100.0, 80.0)), [Verdict::DoesNotHold; 2]);
}
