//! Unit tests of the claims file's loading and of side selection, from `claims.rs`.

use super::*;
use crate::papers::sides::row_sample;
use crate::results::Row;
use render_core::Settings;

#[test]
fn a_claim_on_a_layout_or_draw_call_counter_cannot_be_measured() {
    let head = HEADER.join(",");
    let with = |evidence: &str| {
        parse(
            &format!(
                "{head}\nraycast,R4,paper,§3.1,x,counter:mesh_bytes_per_tet,spx1,raycast:tiles=5x5,,a=144,0,none,{evidence},none,,\ngator,G9,paper,§3.4,x,counter_per_tet:triangles_drawn,post,gator-pt:variant=linear,,a=4,0,none,{evidence},none,,\nraycast,R9,paper,§3.1,x,counter:steps_max,spx1,raycast:tiles=5x5,,a=144,0,none,measured,none,,\n"
            ),
            "claims.csv",
        )
        .unwrap()
    };
    let e = check_counter_evidence(&with("measured"), "claims.csv")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("R4") && e.contains("mesh_bytes_per_tet") && e.contains("data layout"),
        "{e}"
    );
    let only_g9 = with("measured").split_off(1);
    let e = check_counter_evidence(&only_g9, "claims.csv")
        .unwrap_err()
        .to_string();
    assert!(e.contains("G9") && e.contains("draw call"), "{e}");
    // As constructed they load; a measured counter (the longest walk) stays measured.
    check_counter_evidence(&with("construction"), "claims.csv").unwrap();
}

#[test]
fn a_bad_claims_file_is_refused_with_file_and_line() {
    let head = format!("{}\n", HEADER.join(","));
    let bad =
        format!("{head}havs,H1,paper,§5.1,x,total_ms,spx2,havs:k=2,,a<b,0,gpu,measured,none,,\n");
    let e = parse(&bad, "claims.csv").unwrap_err().to_string();
    assert!(
        e.contains("claims.csv: line 2") && e.contains("second side"),
        "{e}"
    );
    let bad = format!("{head}havs,H1,maybe,§5.1,x,total_ms,spx2,havs,,a>1,0,gpu,measured,none,,\n");
    let e = parse(&bad, "c").unwrap_err().to_string();
    assert!(e.contains("source") && e.contains("line 2"), "{e}");
    let bad = format!("{head}havs,H1,paper,§5.1,x,total_ms,spx2,havs,,a>1,0,gpu,guessed,none,,\n");
    assert!(parse(&bad, "c")
        .unwrap_err()
        .to_string()
        .contains("evidence"));
    let twice = format!(
        "{head}havs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu,measured,none,,\nhavs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu,measured,none,,\n"
    );
    assert!(parse(&twice, "c")
        .unwrap_err()
        .to_string()
        .contains("twice"));
    // A derived claim must name claims that exist; a rule change must name a claim.
    let derived =
        format!("{head}havs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu,derived:H9,none,,\n");
    let mut c = parse(&derived, "c").unwrap();
    let e = attach_history(&mut c, vec![], "h").unwrap_err().to_string();
    assert!(e.contains("derived from H9"), "{e}");
    let h = parse_history(
        &format!(
            "{}\nhavs,H2,2026-12-04,abc,why,,total_ms,,havs,,a>2,0,measured,none,,,,\n",
            crate::papers::rules::HISTORY_HEADER.join(",")
        ),
        "h.csv",
    )
    .unwrap();
    let mut c = parse(
        &format!("{head}havs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu,measured,none,,\n"),
        "c",
    )
    .unwrap();
    let e = attach_history(&mut c, h, "h.csv").unwrap_err().to_string();
    assert!(e.contains("havs H2 is not a claim"), "{e}");
    // A metric outside the language fails the load, naming the file, the line and the
    // column; the same line with a known metric loads.
    let metric = |m: &str| {
        format!(
            "{head}havs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu,measured,none,,\nhavs,H2,paper,§5.1,x,{m},,havs,,a>1,0,gpu,measured,none,,\n"
        )
    };
    let e = parse(&metric("stage_shar:sort"), "claims.csv")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("claims.csv: line 3: metric \"stage_shar:sort\" is not one of"),
        "{e}"
    );
    let ok = parse(&metric("stage_share:sort"), "claims.csv").unwrap();
    assert_eq!(ok[1].metric, Metric::StageShare("sort".into()));
}

fn row(settings: &str, viewpoint: &str, total: f64, frames: u32) -> Row {
    Row {
        algorithm: "raycast".into(),
        settings: Settings::parse(settings).unwrap(),
        dataset: "spx1".into(),
        tets: 1000,
        viewpoint: viewpoint.into(),
        total_ms: Some(total),
        total_ms_min: Some(total - 1.0),
        total_ms_max: Some(total + 1.0),
        frames,
        device_type: "DiscreteGpu".into(),
        ..Default::default()
    }
}

fn inputs(rows: &[Row]) -> Inputs<'_> {
    Inputs {
        rows,
        analysis: &|_, _, _| None,
        why_missing: &|a, d| format!("{a} not measured on {d}"),
        software_adapter: software_adapter(rows),
        our_peaks: None,
        cached_peaks: None,
        row_dirs: &[],
    }
}

#[test]
fn a_claim_that_does_not_pin_its_variant_is_not_decided_by_the_first_one_found() {
    let rows = vec![
        row("tiles=5x5;table=2d;mode=passes", "+x", 100.0, 5),
        row("tiles=5x5;table=2d;mode=loop", "+x", 300.0, 5),
        row("tiles=1x1;table=2d;mode=passes", "+x", 200.0, 5),
    ];
    let loose = VariantSpec::parse("raycast:tiles=5x5").unwrap();
    let e = side_from_rows(&Metric::TotalMs, &loose, "spx1", &inputs(&rows)).unwrap_err();
    assert!(e.contains("2 variants match"), "{e}");
    let pinned = VariantSpec::parse("raycast:tiles=5x5;mode=passes").unwrap();
    let s = side_from_rows(&Metric::TotalMs, &pinned, "spx1", &inputs(&rows)).unwrap();
    assert!(s.label.contains("mode=passes"), "{}", s.label);
    assert_eq!(s.centre(), 100.0);
    // Pinned to the loop variant the ordering flips.
    let claim = |a: &str| Claim {
        paper: "raycast".into(),
        id: "X".into(),
        source: Source::Ours,
        cites: "§4".into(),
        text: "t".into(),
        metric: Metric::TotalMs,
        datasets: vec!["spx1".into()],
        a: VariantSpec::parse(a).unwrap(),
        b: Some(VariantSpec::parse("raycast:tiles=1x1").unwrap()),
        expect: ExpectSpec::Fixed(Expect::Less),
        tolerance: 0.0,
        hardware: Hardware::Gpu,
        expect_text: "a<b".into(),
        evidence: Evidence::Measured,
        normalise: Normalise::None,
        discriminates: None,
        control: None,
        history: vec![],
    };
    let v = |a: &str| evaluate(&claim(a), &inputs(&rows))[0].evaluation.verdict;
    assert_eq!(v("raycast:tiles=5x5;mode=passes"), verdict::Verdict::Holds);
    assert_eq!(
        v("raycast:tiles=5x5;mode=loop"),
        verdict::Verdict::DoesNotHold
    );
    assert_eq!(v("raycast:tiles=5x5"), verdict::Verdict::NotCheckable);
}

#[test]
fn rates_invert_the_frame_range_and_stage_shares_name_missing_stages() {
    let mut r = row("tiles=1x1", "+x", 100.0, 3);
    let fps = row_sample(&Metric::Fps, &r).unwrap();
    assert_eq!(fps.value, 10.0);
    assert!(fps.min < 10.0 && fps.max > 10.0);
    r.stages = "wait=9;buckets=3;splat=1".into();
    let e = row_sample(&Metric::StageShare("sort".into()), &r).unwrap_err();
    assert!(e.contains("wait, buckets, splat"), "{e}");
    assert_eq!(
        row_sample(&Metric::StageShare("wait".into()), &r)
            .unwrap()
            .value,
        3.0
    );
    assert!(row_sample(&Metric::PairPsnrDb, &r).is_err());
}
