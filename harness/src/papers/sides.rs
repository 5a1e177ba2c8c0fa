//! A claim's sides from a run's rows: one value per row ([`row_sample`]), reductions over the
//! viewpoints, and image pairs: two sides' images of the same data set and viewpoint compared
//! as `compare` compares an image with the reference ([`pair_side`], docs/reproduction.md,
//! "Image-quality words").

use std::path::Path;

use render_core::Settings;

use super::spec::{Metric, VariantSpec};
use super::verdict::{Sample, Side};
use crate::results::metrics::{compare, ImageError};
use crate::results::Row;

/// A side from the paper's CPU analyses for (metric, variant, data set), or `None` when the
/// metric is not one of them.
pub type AnalysisSide<'a> =
    dyn Fn(&Metric, &VariantSpec, Option<&str>) -> Option<Result<Side, String>> + 'a;

/// Where a claim's numbers come from: the run's rows, the paper's own analyses, and why an
/// algorithm has no rows.
pub struct Inputs<'a> {
    pub rows: &'a [Row],
    /// A side from the paper's CPU analyses (`None`: the metric is not one of them).
    pub analysis: &'a AnalysisSide<'a>,
    /// Why `algorithm` has no value on a data set.
    pub why_missing: &'a dyn Fn(&str, &str) -> String,
    /// Whether the GPU numbers came from a software rasteriser.
    pub software_adapter: bool,
    /// Our adapter's calibrated peaks (`None`: the runs were not calibrated).
    pub our_peaks: Option<super::hardware::OurPeaks>,
    /// The run folder each row's image paths are relative to, by the row's index in `rows`
    /// (`None` or missing: its images cannot be read).
    pub row_dirs: &'a [Option<std::path::PathBuf>],
}

/// Whether rows were measured on a software rasteriser (lavapipe, WARP, SwiftShader report a
/// CPU device type).
pub fn software_adapter(rows: &[Row]) -> bool {
    rows.iter()
        .any(|r| r.device_type.eq_ignore_ascii_case("cpu"))
}

/// The label naming one variant, and its rows with their indices in `inputs.rows`.
type VariantRows<'r> = (String, Vec<(usize, &'r Row)>);

/// The rows of the one variant that matches `spec` on `dataset`, with their indices in
/// `inputs.rows`, and the label naming that variant.
fn one_variant<'r>(
    spec: &VariantSpec,
    dataset: &str,
    inputs: &Inputs<'r>,
) -> Result<VariantRows<'r>, String> {
    let label = spec.label(Some(dataset));
    let rows: Vec<(usize, &Row)> = inputs
        .rows
        .iter()
        .enumerate()
        .filter(|(_, r)| r.dataset == dataset && r.ok() && spec.matches(r))
        .collect();
    let mut variants: Vec<&Settings> = rows.iter().map(|(_, r)| &r.settings).collect();
    variants.sort();
    variants.dedup();
    if variants.len() > 1 {
        return Err(format!(
            "{label}: {} variants match ({}); the claim must name one",
            variants.len(),
            variants
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(" | ")
        ));
    }
    if rows.is_empty() {
        return Err(format!(
            "{label}: {}",
            (inputs.why_missing)(&spec.algorithm, dataset)
        ));
    }
    Ok((
        format!("{} {} on {dataset}", spec.algorithm, variants[0]),
        rows,
    ))
}

/// The image of row `i` of `inputs.rows`, read from its run's folder.
fn row_image(inputs: &Inputs, i: usize, row: &Row) -> Result<render_core::Image, String> {
    let dir: &Path = inputs
        .row_dirs
        .get(i)
        .and_then(|d| d.as_deref())
        .ok_or_else(|| {
            format!(
                "{} at {}: no run folder is known for its image",
                row.algorithm, row.viewpoint
            )
        })?;
    let path = crate::results::samples::row_image(dir, row).ok_or_else(|| {
        format!(
            "{} {} at {}: no image on disk ({:?} under {})",
            row.algorithm,
            row.settings,
            row.viewpoint,
            row.image_f32,
            dir.display()
        )
    })?;
    crate::results::samples::read_f32_image(&path).map_err(|e| format!("{}: {e:#}", path.display()))
}

/// A side from two variants' images (`metric` is [`Metric::PairPsnrDb`] or
/// [`Metric::PairBadPixelShare`]): for every viewpoint `a` was rendered at, its image against `b`'s
/// at the same viewpoint and viewport; the worst viewpoint is the side's one value (lowest PSNR,
/// largest bad-pixel share), every viewpoint's figures are in the label.
pub fn pair_side(
    metric: &Metric,
    a: &VariantSpec,
    b: &VariantSpec,
    dataset: &str,
    inputs: &Inputs,
) -> Result<Side, String> {
    let (a_label, a_rows) = one_variant(a, dataset, inputs)?;
    let (b_label, b_rows) = one_variant(b, dataset, inputs)?;
    let mut views: Vec<(String, ImageError)> = vec![];
    for (ia, ra) in &a_rows {
        // Every image of `a` is judged: one without its pair is a missing measurement.
        let Some((ib, rb)) = b_rows.iter().find(|(_, rb)| {
            rb.viewpoint == ra.viewpoint && rb.width == ra.width && rb.height == ra.height
        }) else {
            return Err(format!(
                "{a_label} against {b_label}: {b_label} has no image at {} and {}x{}",
                ra.viewpoint, ra.width, ra.height
            ));
        };
        let e = compare(&row_image(inputs, *ia, ra)?, &row_image(inputs, *ib, rb)?)
            .map_err(|e| format!("{a_label} against {b_label} at {}: {e:#}", ra.viewpoint))?;
        views.push((ra.viewpoint.clone(), e));
    }
    let worst_psnr = *metric == Metric::PairPsnrDb;
    let value = |e: &ImageError| {
        if worst_psnr {
            e.psnr_db
        } else {
            e.bad_pixel_share
        }
    };
    // The first of the worst viewpoints: the lowest PSNR, or the largest share of bad pixels.
    let (view, worst) = views
        .iter()
        .min_by(|a, b| {
            let (a, b) = (value(&a.1), value(&b.1));
            if worst_psnr {
                a.total_cmp(&b)
            } else {
                b.total_cmp(&a)
            }
        })
        .expect("one_variant returns at least one row");
    let each: Vec<String> = views
        .iter()
        .map(|(v, e)| {
            format!(
                "{v}: {:.2} dB, {} of {} covered pixels off by more than 1/255",
                e.psnr_db, e.bad_pixels, e.covered_pixels
            )
        })
        .collect();
    Ok(Side::new(
        format!(
            "{a_label} against {b_label}, {metric} {} over {} viewpoint(s) (at {view}; {})",
            if worst_psnr { "lowest" } else { "largest" },
            views.len(),
            each.join("; ")
        ),
        vec![Sample::exact(view.clone(), value(worst))],
    ))
}

/// A side from a run's rows: exactly one variant must match the spec (a claim that does not
/// pin its variant is refused, never decided by whichever variant came first).
pub fn side_from_rows(
    metric: &Metric,
    spec: &VariantSpec,
    dataset: &str,
    inputs: &Inputs,
) -> Result<Side, String> {
    let (label, indexed) = one_variant(spec, dataset, inputs)?;
    let rows: Vec<&Row> = indexed.into_iter().map(|(_, r)| r).collect();
    let (inner, largest) = match metric {
        Metric::ViewMax(inner) => (Some(inner), true),
        Metric::ViewMin(inner) => (Some(inner), false),
        _ => (None, false),
    };
    if let Some(inner) = inner {
        let values: Vec<(String, f64)> = rows
            .iter()
            .filter_map(|r| Some((r.viewpoint.clone(), row_sample(inner, r).ok()?.value)))
            .collect();
        let pick = values
            .iter()
            .cloned()
            .reduce(|a, b| if (b.1 > a.1) == largest { b } else { a });
        let Some((view, v)) = pick else {
            return Err(format!("{label}: no {inner} in its rows"));
        };
        return Ok(Side::new(
            format!(
                "{label}, {inner} {} over {} viewpoint(s) (at {view})",
                if largest { "largest" } else { "smallest" },
                values.len()
            ),
            vec![Sample::exact(view, v)],
        ));
    }
    if let Metric::ViewRange(inner) = metric {
        let values: Vec<f64> = rows
            .iter()
            .filter_map(|r| row_sample(inner, r).ok().map(|s| s.value))
            .collect();
        if values.len() < 2 {
            return Err(format!(
                "{label}: {metric} needs at least two viewpoints, has {}",
                values.len()
            ));
        }
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        // A spread of timings keeps the fewest frames behind them: too few decide nothing.
        let frames = rows
            .iter()
            .filter_map(|r| row_sample(inner, r).ok())
            .map(|s| s.frames)
            .min()
            .unwrap_or(0);
        return Ok(Side::new(
            format!(
                "{label}, {inner} range/mean over {} viewpoints",
                values.len()
            ),
            vec![Sample {
                frames,
                ..Sample::exact("views", (hi - lo) / mean)
            }],
        ));
    }
    let mut samples = vec![];
    let mut first_err = None;
    for r in rows {
        match row_sample(metric, r) {
            Ok(s) => samples.push(s),
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    if samples.is_empty() {
        return Err(format!(
            "{label}: {}",
            first_err.unwrap_or_else(|| format!("no {metric}"))
        ));
    }
    Ok(Side::new(format!("{label}, {metric}"), samples))
}

/// One row's value of a metric, with its frames' range where the row has one.
pub fn row_sample(metric: &Metric, r: &Row) -> Result<Sample, String> {
    let key = r.viewpoint.clone();
    let timed = |v: Option<f64>, lo: Option<f64>, hi: Option<f64>| -> Result<Sample, String> {
        let v = v.ok_or_else(|| format!("no {metric} in its rows"))?;
        Ok(Sample {
            key: key.clone(),
            value: v,
            min: lo.unwrap_or(v),
            max: hi.unwrap_or(v),
            frames: r.frames.max(1),
        })
    };
    // A rate from a time: the slowest frame gives the lowest rate.
    let rate = |num: f64, s: Sample| Sample {
        value: num / s.value,
        min: num / s.max,
        max: num / s.min,
        ..s
    };
    let exact = |v: Option<f64>| {
        v.map(|v| Sample::exact(key.clone(), v))
            .ok_or_else(|| format!("no {metric} in its rows"))
    };
    let total = || timed(r.total_ms, r.total_ms_min, r.total_ms_max);
    let gpu = || timed(r.gpu_ms, r.gpu_ms_min, r.gpu_ms_max);
    match metric {
        Metric::TotalMs => total(),
        Metric::GpuMs => gpu(),
        Metric::CpuMs => timed(r.cpu_ms, r.cpu_ms_min, r.cpu_ms_max),
        Metric::Fps => Ok(rate(1e3, total()?)),
        Metric::TetsPerSec => Ok(rate(r.tets as f64 * 1e3, total()?)),
        Metric::GpuTetsPerSec => Ok(rate(r.tets as f64 * 1e3, gpu()?)),
        Metric::BytesPerTet => exact(r.bytes_per_tet),
        Metric::GpuBytes => exact(r.gpu_bytes.map(|b| b as f64)),
        Metric::PsnrDb => exact(r.psnr_db),
        Metric::Counter(name) => exact(r.counter(name)),
        Metric::CounterPerTet(name) => {
            if r.tets == 0 {
                return Err(format!("{metric}: the row has no tets"));
            }
            exact(r.counter(name).map(|v| v / r.tets as f64))
        }
        Metric::Stage(name) => timed(r.stage_ms(name), None, None).map_err(|_| no_stage(name, r)),
        Metric::StageShare(name) => {
            let this = r.stage_ms(name).ok_or_else(|| no_stage(name, r))?;
            let other = r
                .stages
                .iter()
                .filter(|(k, _)| *k != name)
                .map(|(_, v)| v)
                .fold(0.0f64, f64::max);
            if other <= 0.0 {
                return Err(format!("no stage besides {name} in its rows"));
            }
            timed(Some(this / other), None, None)
        }
        _ => Err(format!("{metric} is not a figure of one row")),
    }
}

fn no_stage(name: &str, r: &Row) -> String {
    let have: Vec<&str> = r.stages.names().collect();
    format!(
        "no stage named {name} in its rows (stages timed: {})",
        if have.is_empty() {
            "none".to_string()
        } else {
            have.join(", ")
        }
    )
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use render_core::Image;

    use crate::papers::claims::{self, Claim};
    use crate::papers::evidence::{evaluate_claims, no_analyses};
    use crate::papers::session::{Extra, Measured};
    use crate::papers::verdict::Verdict;
    use crate::results::samples::write_f32_image;
    use crate::results::Row;

    /// A rendering-like image: a soft disc of colour over a transparent background.
    fn disc(size: u32) -> Image {
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
    fn row_with_image(
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
        let results = evaluate_claims(&claim.paper, &m, &Extra::default(), &no_analyses);
        let r = results
            .iter()
            .find(|r| r.claim.id == claim.id && r.dataset.as_deref() == Some(d))
            .unwrap();
        (r.evaluation.verdict, r.evaluation.numbers.clone())
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
        let r = evaluate_claims(&c.paper, &m, &Extra::default(), &no_analyses);
        let e = &r.iter().find(|r| r.claim.id == c.id).unwrap().evaluation;
        assert_eq!(e.verdict, Verdict::NotCheckable);
        assert!(e.numbers.contains("no run folder"), "{}", e.numbers);
    }

    #[test]
    fn an_image_pair_refuses_an_expectation_of_two_values() {
        let header = claims::CLAIMS_CSV.lines().next().unwrap();
        let line =
            "havs,X1,paper,§4,t,pair_psnr_db,spx2,havs:k=2,havs:k=6,a<b,0,none,measured,none";
        let e = claims::parse(&format!("{header}\n{line}\n"), "test.csv").unwrap_err();
        assert!(
            format!("{e:#}").contains("compares a's image with b's"),
            "{e:#}"
        );
        let line = "havs,X1,paper,§4,t,pair_psnr_db,spx2,havs:k=2,,a>40,0,none,measured,none";
        let e = claims::parse(&format!("{header}\n{line}\n"), "test.csv").unwrap_err();
        assert!(format!("{e:#}").contains("needs a second side"), "{e:#}");
    }
}
