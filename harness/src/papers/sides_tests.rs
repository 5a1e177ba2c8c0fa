//! Tests of the claims' sides (sides.rs) through the evidence they feed (evidence.rs): kept
//! apart so that sides.rs, which evidence.rs imports, imports nothing back.
use std::path::Path;

use render_core::Image;

use crate::papers::claims::{self, Claim};
use crate::papers::evidence::evaluate_claims;
use crate::papers::session::{Extra, Measured};
use crate::papers::verdict::Verdict;
use crate::results::samples::write_f32_image;
use crate::results::Row;

/// A rendering-like image: a soft disc of colour over a transparent background.
pub(crate) fn disc(size: u32) -> Image {
    let mut img = Image::new(size, size);
    let c = size as f32 / 2.0;
    for y in 0..size {
        for x in 0..size {
            let r = ((x as f32 - c).powi(2) + (y as f32 - c).powi(2)).sqrt() / c;
            let a = (1.0 - r).clamp(0.0, 1.0) * 0.8;
            img.pixels[(y * size + x) as usize] = [a * 0.9, a * 0.5, a * 0.2, a];
        }
    }
    img
}

/// One row of `spec`'s variant on `dataset` at `view`, its image written under `dir`.
pub(crate) fn row_with_image(
    dir: &Path,
    spec: &claims::VariantSpec,
    dataset: &str,
    view: &str,
    img: &Image,
) -> Row {
    let name = format!(
        "images/{}-{}-{}.f32.zz",
        spec.algorithm,
        crate::results::names::slug(&spec.settings_text()),
        crate::results::names::slug(view)
    );
    std::fs::create_dir_all(dir.join("images")).unwrap();
    write_f32_image(&dir.join(&name), img).unwrap();
    Row {
        algorithm: spec.algorithm.clone(),
        settings: spec.settings.clone(),
        dataset: dataset.into(),
        tets: 1000,
        viewpoint: view.into(),
        width: img.width,
        height: img.height,
        frames: 1,
        device_type: "DiscreteGpu".into(),
        image_f32: name,
        ..Default::default()
    }
}

/// The verdict of `claim` on its first data set, with side `a`'s image at the second of
/// two viewpoints changed by `change` (the first viewpoint's images agree).
fn verdict_with(claim: &Claim, change: impl Fn(&mut Image)) -> (Verdict, String) {
    let dir = tempfile::tempdir().unwrap();
    let d = claim.datasets[0].as_str();
    let b = claim.b.as_ref().unwrap();
    let mut m = Measured::default();
    for view in ["+x", "-y"] {
        let reference = disc(32);
        let mut ours = reference.clone();
        if view == "-y" {
            change(&mut ours);
        }
        let rows = [
            row_with_image(dir.path(), &claim.a, d, view, &ours),
            row_with_image(dir.path(), b, d, view, &reference),
        ];
        m.push_run(dir.path(), rows);
    }
    let results = evaluate_claims(&claim.paper, &m, &Extra::default(), &discriminating);
    let r = results
        .iter()
        .find(|r| r.claim.id == claim.id && r.dataset.as_deref() == Some(d))
        .unwrap();
    (r.evaluation.verdict, r.evaluation.numbers.clone())
}

/// Our own analysis, answering only where a claim's sides discriminate: every such figure
/// on the bound's side that lets them differ (H12: max k 7, over the 6 of its side a).
pub(crate) fn discriminating(
    metric: &claims::Metric,
    spec: &claims::VariantSpec,
    d: Option<&str>,
) -> Option<Result<crate::papers::verdict::Side, String>> {
    use crate::papers::verdict::Expect;
    let c = claims::all()
        .unwrap()
        .into_iter()
        .filter_map(|c| c.discriminates)
        .find(|x| &x.metric == metric && &x.spec == spec)?;
    let v = match c.bound {
        Expect::Above(n) => n + 1.0,
        Expect::Below(n) => n - 1.0,
        _ => unreachable!(),
    };
    Some(crate::papers::evidence::exact_side(
        format!("{spec} on {}", d.unwrap_or("–")),
        d.unwrap_or("–"),
        v,
    ))
}

fn image_claims() -> Vec<Claim> {
    let all: Vec<Claim> = claims::all()
        .unwrap()
        .into_iter()
        .filter(|c| c.metric.is_pair())
        .collect();
    assert!(all.len() >= 6, "{} image-quality claims", all.len());
    all
}

#[test]
fn every_image_quality_claim_flips_when_one_viewpoint_of_its_image_changes() {
    for c in image_claims() {
        let (v, numbers) = verdict_with(&c, |_| {});
        assert_eq!(v, Verdict::Holds, "{} {}: {numbers}", c.paper, c.id);
        // A visible change: every covered pixel 0.05 brighter (PSNR about 27 dB on the
        // covered share of the image, every covered pixel off by more than 1/255).
        let (v, numbers) = verdict_with(&c, |img| {
            for p in &mut img.pixels {
                if p[3] > 0.01 {
                    p[0] += 0.05;
                    p[1] += 0.05;
                    p[2] += 0.05;
                }
            }
        });
        assert_eq!(v, Verdict::DoesNotHold, "{} {}: {numbers}", c.paper, c.id);
        assert!(numbers.contains("at -y"), "{} {}: {numbers}", c.paper, c.id);
    }
}

#[test]
fn a_change_below_the_rules_keeps_the_verdict() {
    for c in image_claims() {
        // Half an 8-bit step on every pixel: PSNR about 54 dB, no pixel off by a step.
        let (v, numbers) = verdict_with(&c, |img| {
            for p in &mut img.pixels {
                p[0] += 0.5 / 255.0;
            }
        });
        assert_eq!(v, Verdict::Holds, "{} {}: {numbers}", c.paper, c.id);
    }
}

#[test]
fn a_missing_image_or_a_different_viewport_is_not_checkable_and_says_why() {
    let c = image_claims().into_iter().next().unwrap();
    let (v, numbers) = verdict_with(&c, |img| *img = disc(16));
    assert_eq!(v, Verdict::NotCheckable, "{numbers}");
    assert!(
        numbers.contains("has no image at -y and 16x16"),
        "{numbers}"
    );
    // Rows without a run folder (read from elsewhere) name the missing image.
    let d = c.datasets[0].as_str();
    let mut m = Measured::default();
    let row = |spec: &claims::VariantSpec| Row {
        algorithm: spec.algorithm.clone(),
        settings: spec.settings.clone(),
        dataset: d.into(),
        viewpoint: "+x".into(),
        width: 8,
        height: 8,
        frames: 1,
        image_f32: "images/gone.f32.zz".into(),
        ..Default::default()
    };
    m.rows = vec![row(&c.a), row(c.b.as_ref().unwrap())];
    let r = evaluate_claims(&c.paper, &m, &Extra::default(), &discriminating);
    let e = &r.iter().find(|r| r.claim.id == c.id).unwrap().evaluation;
    assert_eq!(e.verdict, Verdict::NotCheckable);
    assert!(e.numbers.contains("no run folder"), "{}", e.numbers);
}

#[test]
fn an_image_pair_refuses_an_expectation_of_two_values() {
    let header = claims::CLAIMS_CSV.lines().next().unwrap();
    let line = "havs,X1,paper,§4,t,pair_psnr_db,spx2,havs:k=2,havs:k=6,a<b,0,none,measured,none,,";
    let e = claims::parse(&format!("{header}\n{line}\n"), "test.csv").unwrap_err();
    assert!(
        format!("{e:#}").contains("compares a's image with b's"),
        "{e:#}"
    );
    let line = "havs,X1,paper,§4,t,pair_psnr_db,spx2,havs:k=2,,a>40,0,none,measured,none,,";
    let e = claims::parse(&format!("{header}\n{line}\n"), "test.csv").unwrap_err();
    assert!(format!("{e:#}").contains("needs a second side"), "{e:#}");
}

/// A dim disc of radius `radius` pixels in a `size`² image, its brightest channel `peak`.
pub(crate) fn dim_disc(size: u32, radius: f32, peak: f32) -> Image {
    let mut img = Image::new(size, size);
    let c = size as f32 / 2.0;
    for y in 0..size {
        for x in 0..size {
            let r = ((x as f32 + 0.5 - c).powi(2) + (y as f32 + 0.5 - c).powi(2)).sqrt() / radius;
            if r < 1.0 {
                let a = 0.5 + 0.5 * (1.0 - r);
                img.pixels[(y * size + x) as usize] = [peak * a, peak * a * 0.6, peak * a * 0.3, a];
            }
        }
    }
    img
}

#[test]
fn the_covered_psnr_reads_the_error_at_the_volume_s_pixels_and_the_image_s_range() {
    use crate::papers::sides::covered_error;
    use crate::results::metrics::compare;
    // A small, dim volume: 8 px radius in 64², brightest channel 0.1 at the centre.
    let b = dim_disc(64, 8.0, 0.1);
    let covered = b.pixels.iter().filter(|p| p[3] > 1.0 / 255.0).count() as u64;
    let mut a = b.clone();
    for p in &mut a.pixels {
        if p[3] > 0.0 {
            p[0] += 0.01;
            p[1] += 0.01;
            p[2] += 0.01;
        }
    }
    let e = covered_error(&a, &b);
    assert_eq!(e.covered_pixels, covered);
    assert!(e.peak > 0.09 && e.peak <= 0.1, "{}", e.peak);
    // RMSE 0.01 over the covered pixels against a peak near 0.1: about 20 dB.
    assert!((e.rmse - 0.01).abs() < 1e-6, "{}", e.rmse);
    assert!((e.psnr_db - 20.0 * (e.peak / e.rmse).log10()).abs() < 1e-9);
    assert!(e.psnr_db < 21.0, "{}", e.psnr_db);
    // The same error over the whole image at peak 1 reads above 40 dB: the background and
    // the dim light dilute it.
    assert!(compare(&a, &b).unwrap().psnr_db > 45.0);
    // The same image, or a background change below one 8-bit step, reads the cap.
    assert_eq!(covered_error(&b, &b).psnr_db, 99.0);
    let mut haze = b.clone();
    for p in &mut haze.pixels {
        if p[3] == 0.0 {
            p[0] = 0.5 / 255.0;
            p[3] = 0.5 / 255.0;
        }
    }
    assert_eq!(covered_error(&haze, &b).psnr_db, 99.0);
    // A NaN pixel counts as covered and maximally wrong.
    let mut nan = b.clone();
    nan.pixels[0] = [f32::NAN, 0.0, 0.0, f32::NAN];
    let n = covered_error(&nan, &b);
    assert_eq!(n.covered_pixels, covered + 1);
    assert!(n.psnr_db < 20.0, "{}", n.psnr_db);
    // Both images empty: nothing to see, nothing wrong.
    let empty = Image::new(8, 8);
    let z = covered_error(&empty, &empty);
    assert_eq!((z.covered_pixels, z.psnr_db), (0, 99.0));
}
