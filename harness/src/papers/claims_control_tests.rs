//! Flip tests of the two verdicts that say a pair claim could not have failed: *not
//! discriminating* (our own analysis of the data set says the sides cannot differ there) and
//! *insensitive* (the claim's positive control passes its rule too). HAVS H12 is the claim: k =
//! 6 against k = 16, which can only differ where some pixel needs more than 6 entries, with k =
//! 1 on spx2 as the perturbation its rule must reject. HAVS H13 (the racy pass, a GPU claim)
//! shows a control judged beside a verdict withheld on the software rasteriser.

use render_core::Image;

use crate::papers::claims::{self, Claim, ClaimResult, Metric, VariantSpec};
use crate::papers::claims_report;
use crate::papers::evidence::{evaluate_claims, exact_side};
use crate::papers::session::{Extra, Measured};
use crate::papers::sides_tests::{dim_disc, disc, row_with_image};
use crate::papers::verdict::{Side, Verdict};
use crate::results::Row;

fn h12() -> Claim {
    claims::all()
        .unwrap()
        .into_iter()
        .find(|c| c.paper == "havs" && c.id == "H12")
        .unwrap()
}

/// Every pixel of the covered image brighter by `by` (0: the image itself).
fn brighter(by: f32) -> Image {
    let mut img = disc(32);
    for p in &mut img.pixels {
        if p[3] > 0.01 {
            p[0] += by;
            p[1] += by;
            p[2] += by;
        }
    }
    img
}

/// H12's verdicts on spx2 and f117 with k = 6 and k = 16 drawing the same image, `max_k` our
/// analysis of each data set, and (where given) the k = 1 control's image on spx2.
fn judge(max_k: &[(&str, f64)], control: Option<&Image>) -> Vec<ClaimResult> {
    let c = h12();
    let dir = tempfile::tempdir().unwrap();
    let mut m = Measured::default();
    for d in ["spx2", "f117"] {
        let mut rows = vec![
            row_with_image(dir.path(), &c.a, d, "+x", &disc(32)),
            row_with_image(dir.path(), c.b.as_ref().unwrap(), d, "+x", &disc(32)),
        ];
        if let (Some(img), "spx2") = (control, d) {
            rows.push(row_with_image(
                dir.path(),
                c.control.as_ref().unwrap(),
                d,
                "+x",
                img,
            ));
        }
        m.push_run(dir.path(), rows);
    }
    let analysis =
        |metric: &Metric, spec: &VariantSpec, d: Option<&str>| -> Option<Result<Side, String>> {
            if spec.algorithm != "kbuffer-analysis" || metric.to_string() != "kbuffer_max_k" {
                return None;
            }
            let d = d?;
            let (_, k) = max_k.iter().find(|(n, _)| *n == d)?;
            Some(exact_side(format!("k analysis of {d}"), d, *k))
        };
    evaluate_claims("havs", &m, &Extra::default(), &analysis)
        .into_iter()
        .filter(|r| r.claim.id == "H12")
        .collect()
}

fn on<'r>(results: &'r [ClaimResult], d: &str) -> &'r ClaimResult {
    results
        .iter()
        .find(|r| r.dataset.as_deref() == Some(d))
        .unwrap()
}

#[test]
fn a_pair_whose_sides_cannot_differ_reads_not_discriminating() {
    let c = h12();
    assert!(c.discriminates.is_some() && c.control.is_some());
    // Our analysis: spx2 needs up to 15 entries, the f117 stand-in 1.
    let r = judge(&[("spx2", 15.0), ("f117", 1.0)], None);
    assert_eq!(on(&r, "spx2").evaluation.verdict, Verdict::Holds);
    let f117 = &on(&r, "f117").evaluation;
    assert_eq!(f117.verdict, Verdict::NotDiscriminating, "{}", f117.numbers);
    assert!(
        f117.numbers.contains("= 1: the two sides cannot differ")
            && f117.numbers.contains("it would read \"holds\""),
        "{}",
        f117.numbers
    );
    // Not a hold, and counted apart in the headline.
    let tally = claims_report::tally(&r);
    let count = |v: Verdict| tally.iter().find(|(x, _)| *x == v).unwrap().1;
    assert_eq!(count(Verdict::NotDiscriminating), 1);
    assert_eq!(count(Verdict::Holds), 1);
    assert!(
        crate::papers::reproduce::tally_text(&r).contains("1 not discriminating"),
        "{}",
        crate::papers::reproduce::tally_text(&r)
    );
    // The same claim on the same images, f117's analysis now needing 7 entries: judged.
    let r = judge(&[("spx2", 15.0), ("f117", 7.0)], None);
    assert_eq!(on(&r, "f117").evaluation.verdict, Verdict::Holds);
    // Exactly at the hardware's k: still not discriminating.
    let r = judge(&[("spx2", 15.0), ("f117", 6.0)], None);
    assert_eq!(
        on(&r, "f117").evaluation.verdict,
        Verdict::NotDiscriminating
    );
    // Without our analysis of the data set, whether the sides can differ is not known.
    let r = judge(&[("spx2", 15.0)], None);
    let e = &on(&r, "f117").evaluation;
    assert_eq!(e.verdict, Verdict::NotCheckable);
    assert!(e.numbers.contains("not known"), "{}", e.numbers);
}

#[test]
fn a_positive_control_that_passes_the_rule_makes_the_hold_insensitive() {
    let k = [("spx2", 15.0), ("f117", 1.0)];
    // k = 1 visibly off (about 27 dB): the rule rejects it, and the hold stands with it.
    let r = judge(&k, Some(&brighter(0.05)));
    let spx2 = on(&r, "spx2");
    assert_eq!(spx2.evaluation.verdict, Verdict::Holds);
    assert_eq!(spx2.control.as_ref().unwrap().verdict, Verdict::DoesNotHold);
    assert!(
        spx2.evaluation
            .numbers
            .contains("the rule rejects it, as it must"),
        "{}",
        spx2.evaluation.numbers
    );
    let md = claims_report::markdown(&r);
    assert!(
        md.contains("holds (positive control: does not hold)"),
        "{md}"
    );
    // The control only on the data set it names: f117 has none.
    assert!(on(&r, "f117").control.is_none());
    // k = 1 drawing what k = 16 draws: the rule cannot tell a fault, the hold is insensitive.
    let r = judge(&k, Some(&brighter(0.0)));
    let spx2 = on(&r, "spx2");
    assert_eq!(spx2.evaluation.verdict, Verdict::Insensitive);
    assert_eq!(spx2.control.as_ref().unwrap().verdict, Verdict::Holds);
    assert!(
        spx2.evaluation.numbers.contains("the rule is insensitive"),
        "{}",
        spx2.evaluation.numbers
    );
    // A control that was not run shows nothing either way and says so.
    let r = judge(&k, None);
    let spx2 = on(&r, "spx2");
    assert_eq!(spx2.evaluation.verdict, Verdict::Holds);
    assert!(
        spx2.evaluation.numbers.contains("not run"),
        "{}",
        spx2.evaluation.numbers
    );
}

#[test]
fn discriminates_parses_and_refuses_with_why() {
    let d = claims::Discriminates::parse("kbuffer-analysis kbuffer_max_k>6").unwrap();
    assert!(d.admits(7.0) && !d.admits(6.0));
    assert_eq!(d.to_string(), "kbuffer-analysis kbuffer_max_k>6");
    let below = claims::Discriminates::parse("kbuffer-analysis kbuffer_max_k<3").unwrap();
    assert!(below.admits(2.0) && !below.admits(3.0));
    for bad in [
        "kbuffer_max_k>6",
        "kbuffer-analysis kbuffer_max_k=6",
        "kbuffer-analysis kbuffer_max_k>six",
        "kbuffer-analysis nonsense>6",
    ] {
        let e = claims::Discriminates::parse(bad).unwrap_err();
        assert!(
            e.contains("discriminates") || e.contains("metric"),
            "{bad}: {e}"
        );
    }
}

/// S5's verdict on engine with the bricked image equal to the one-brick image, and its
/// misaligned control's image `control`: a small dim volume (8 px radius in 64², brightest
/// channel 0.1), as the splatting stand-ins draw a small share of the viewport in dim light.
fn s5_with_control(control: &Image) -> ClaimResult {
    let c = claims::all()
        .unwrap()
        .into_iter()
        .find(|c| c.paper == "splat" && c.id == "S5")
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let volume = dim_disc(64, 8.0, 0.1);
    let rows = vec![
        row_with_image(dir.path(), &c.a, "engine", "+x", &volume),
        row_with_image(dir.path(), c.b.as_ref().unwrap(), "engine", "+x", &volume),
        row_with_image(
            dir.path(),
            c.control.as_ref().unwrap(),
            "engine",
            "+x",
            control,
        ),
    ];
    let mut m = Measured::default();
    m.push_run(dir.path(), rows);
    let none = |_: &Metric, _: &VariantSpec, _: Option<&str>| None;
    evaluate_claims("splat", &m, &Extra::default(), &none)
        .into_iter()
        .find(|r| r.claim.id == "S5" && r.dataset.as_deref() == Some("engine"))
        .unwrap()
}

/// The dim volume with every covered pixel's colour raised by `by`.
fn dim_shifted(by: f32) -> Image {
    let mut img = dim_disc(64, 8.0, 0.1);
    for p in img.pixels.iter_mut().filter(|p| p[3] > 0.0) {
        for c in &mut p[..3] {
            *c += by;
        }
    }
    img
}

#[test]
fn the_changed_pixel_share_rejects_a_control_that_both_psnrs_let_pass() {
    // A control 0.005 off at every covered pixel (more than one 8-bit step): every covered
    // pixel changes on the display, so the share rule rejects it and the claim's hold counts.
    // Over the covered pixels at the image's peak it still reads about 26 dB (rejected by the
    // rule before too) and above 50 dB over the whole image at peak 1 (passed: insensitive by
    // the first rule).
    let r = s5_with_control(&dim_shifted(0.005));
    assert_eq!(r.claim.metric, Metric::PairBadPixelShare);
    let control = r.control.as_ref().unwrap();
    assert_eq!(control.verdict, Verdict::DoesNotHold, "{}", control.numbers);
    assert_eq!(
        r.evaluation.verdict,
        Verdict::Holds,
        "{}",
        r.evaluation.numbers
    );
    // The control's own figures are in the verdict text.
    assert!(
        r.evaluation.numbers.contains("positive control")
            && r.evaluation
                .numbers
                .contains("over the 208 covered pixels at peak 0.096")
            && r.evaluation.numbers.contains("dB over the image at peak 1"),
        "{}",
        r.evaluation.numbers
    );
    let (first, before) = r
        .earlier
        .iter()
        .find(|(h, _)| {
            h.old
                .as_ref()
                .is_some_and(|o| o.metric == Metric::PairPsnrDb && o.control.is_some())
        })
        .expect("S5's history keeps the whole-image rule with its control");
    assert_eq!(before.verdict, Verdict::Insensitive, "{}", before.numbers);
    let md = claims_report::markdown(std::slice::from_ref(&r));
    assert!(
        md.contains("holds (positive control: does not hold)")
            && md.contains(&format!("by the rule before {}: insensitive", first.commit)),
        "{md}"
    );
    // A control 0.003 off: under one 8-bit step at every pixel, so no pixel changes on the
    // display and the share rule passes it (insensitive), while the covered PSNR at the
    // image's peak (about 30 dB) rejects it: the two rules part here, and the report keeps
    // the covered PSNR's verdict beside.
    let r = s5_with_control(&dim_shifted(0.003));
    assert_eq!(
        r.control.as_ref().unwrap().verdict,
        Verdict::Holds,
        "{}",
        r.evaluation.numbers
    );
    assert_eq!(r.evaluation.verdict, Verdict::Insensitive);
    assert!(r.earlier.iter().any(|(h, e)| h
        .old
        .as_ref()
        .is_some_and(|o| o.metric == Metric::PairPsnrCoveredDb)
        && e.verdict == Verdict::Holds));
}

/// H13's verdict on spx2 on an adapter of `device_type`: the racy and the race-free pass at
/// k = 6 drawing the same image, and the racy pass at k = 1 (its positive control) drawing
/// `control`.
fn h13_with_control(device_type: &str, control: &Image) -> ClaimResult {
    let c = claims::all()
        .unwrap()
        .into_iter()
        .find(|c| c.paper == "havs" && c.id == "H13")
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let perturbed = c.control.as_ref().expect("H13 has a positive control");
    let rows: Vec<Row> = [
        (&c.a, &disc(32)),
        (c.b.as_ref().unwrap(), &disc(32)),
        (perturbed, control),
    ]
    .into_iter()
    .map(|(spec, img)| Row {
        device_type: device_type.into(),
        ..row_with_image(dir.path(), spec, "spx2", "+x", img)
    })
    .collect();
    let mut m = Measured::default();
    m.push_run(dir.path(), rows);
    let none = |_: &Metric, _: &VariantSpec, _: Option<&str>| None;
    evaluate_claims("havs", &m, &Extra::default(), &none)
        .into_iter()
        .find(|r| r.claim.id == "H13" && r.dataset.as_deref() == Some("spx2"))
        .unwrap()
}

#[test]
fn a_gpu_claims_image_control_is_judged_beside_its_withheld_verdict() {
    // On the software rasteriser the race cannot happen, so H13's own verdict is withheld;
    // its control is still judged, since whether the rule sees k = 1's image does not depend
    // on the adapter. A visibly changed control: rejected, and printed beside the verdict.
    let r = h13_with_control("Cpu", &brighter(0.05));
    assert_eq!(r.evaluation.verdict, Verdict::NotTestableOnThisAdapter);
    let control = r.control.as_ref().expect("judged on the software adapter");
    assert_eq!(control.verdict, Verdict::DoesNotHold, "{}", control.numbers);
    assert!(
        r.evaluation
            .numbers
            .contains("the rule rejects it, as it must"),
        "{}",
        r.evaluation.numbers
    );
    let md = claims_report::markdown(std::slice::from_ref(&r));
    assert!(
        md.contains("not testable on this adapter (positive control: does not hold)"),
        "{md}"
    );
    // A control that draws the claim's image passes the rule: the text says the rule is
    // insensitive, while the claim's own verdict stays withheld (it is not a hold that the
    // control could undo).
    let r = h13_with_control("Cpu", &brighter(0.0));
    assert_eq!(r.evaluation.verdict, Verdict::NotTestableOnThisAdapter);
    assert_eq!(r.control.as_ref().unwrap().verdict, Verdict::Holds);
    assert!(
        r.evaluation.numbers.contains("the rule is insensitive"),
        "{}",
        r.evaluation.numbers
    );
    // On a GPU the claim is judged: the same images hold, and the passing control makes the
    // hold insensitive; the rejected one lets it stand.
    let r = h13_with_control("DiscreteGpu", &brighter(0.0));
    assert_eq!(r.evaluation.verdict, Verdict::Insensitive);
    let r = h13_with_control("DiscreteGpu", &brighter(0.05));
    assert_eq!(r.evaluation.verdict, Verdict::Holds);
    assert_eq!(r.control.as_ref().unwrap().verdict, Verdict::DoesNotHold);
}
