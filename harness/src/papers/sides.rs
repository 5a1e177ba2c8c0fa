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
    /// Our adapter's figures that normalised claims scale by: the control measured beside the
    /// rows where they carry one, else the cached calibration (`None`: neither).
    pub our_peaks: Option<super::hardware::OurPeaks>,
    /// The cached calibration, where `our_peaks` is the control: its verdict is printed beside.
    pub cached_peaks: Option<super::hardware::OurPeaks>,
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

/// Image error over the pixels that show the volume, against the picture's own range: PSNR of
/// `a` against `b` over the covered pixels (either image's α above one 8-bit step, as
/// [`compare`] counts them), the peak at `b`'s brightest clamped colour channel (never below
/// one 8-bit step). [`compare`]'s PSNR takes every pixel and peak 1, so the black background
/// and a dim transfer function dilute its error; this one is the same RGB error read as a
/// viewer reads the picture, at the volume's pixels and the image's range
/// (docs/reproduction.md, "Image-quality words").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoveredError {
    pub psnr_db: f64,
    pub rmse: f64,
    /// `b`'s brightest colour channel (clamped to [0, 1], at least one 8-bit step).
    pub peak: f64,
    pub covered_pixels: u64,
}

/// [`CoveredError`] of `a` against `b` (same size, as [`compare`] requires).
pub fn covered_error(a: &render_core::Image, b: &render_core::Image) -> CoveredError {
    use render_core::image_error::{channel_error, ONE_STEP, PSNR_CAP_DB};
    // Clamped as `compare` clamps; a NaN counts as full scale (covered, maximal), never as
    // agreement.
    let unit = |v: f32| {
        if v.is_nan() {
            1.0
        } else {
            (v as f64).clamp(0.0, 1.0)
        }
    };
    let mut sum_sq = 0.0f64;
    let mut covered = 0u64;
    let mut peak = ONE_STEP;
    for (p, r) in a.pixels.iter().zip(&b.pixels) {
        for c in &r[..3] {
            peak = peak.max(unit(*c));
        }
        if unit(p[3]) > ONE_STEP || unit(r[3]) > ONE_STEP {
            covered += 1;
            sum_sq += (0..3)
                .map(|c| channel_error(p[c], r[c]).powi(2))
                .sum::<f64>();
        }
    }
    let rmse = (sum_sq / (3 * covered.max(1)) as f64).sqrt();
    let psnr_db = if rmse > 0.0 {
        (20.0 * (peak / rmse).log10()).min(PSNR_CAP_DB)
    } else {
        PSNR_CAP_DB
    };
    CoveredError {
        psnr_db,
        rmse,
        peak,
        covered_pixels: covered,
    }
}

/// One viewpoint of an image pair: [`compare`]'s figures and the covered ones.
#[derive(Debug, Clone, Copy)]
struct PairView {
    whole: ImageError,
    covered: CoveredError,
}

impl PairView {
    fn value(&self, metric: &Metric) -> f64 {
        match metric {
            Metric::PairPsnrDb => self.whole.psnr_db,
            Metric::PairPsnrCoveredDb => self.covered.psnr_db,
            _ => self.whole.bad_pixel_share,
        }
    }

    /// Every figure of the viewpoint, whichever the metric: a reader sees how far from the
    /// rule each reading is.
    fn describe(&self) -> String {
        let (w, c) = (&self.whole, &self.covered);
        format!(
            "{:.2} dB over the {} covered pixels at peak {:.3}, {:.2} dB over the image at peak 1, {} of {} covered pixels off by more than 1/255, largest change {:.3}",
            c.psnr_db, c.covered_pixels, c.peak, w.psnr_db, w.bad_pixels, w.covered_pixels, w.max_abs_error
        )
    }
}

/// A side from two variants' images (`metric` is one of the pair metrics,
/// [`Metric::is_pair`]): for every viewpoint `a` was rendered at, its image against `b`'s at
/// the same viewpoint and viewport; the worst viewpoint is the side's one value (lowest PSNR,
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
    let mut views: Vec<(String, PairView)> = vec![];
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
        let (ima, imb) = (row_image(inputs, *ia, ra)?, row_image(inputs, *ib, rb)?);
        let whole = compare(&ima, &imb)
            .map_err(|e| format!("{a_label} against {b_label} at {}: {e:#}", ra.viewpoint))?;
        let covered = covered_error(&ima, &imb);
        views.push((ra.viewpoint.clone(), PairView { whole, covered }));
    }
    let worst_is_lowest = *metric != Metric::PairBadPixelShare;
    // The first of the worst viewpoints: the lowest PSNR, or the largest share of bad pixels.
    let (view, worst) = views
        .iter()
        .min_by(|a, b| {
            let (a, b) = (a.1.value(metric), b.1.value(metric));
            if worst_is_lowest {
                a.total_cmp(&b)
            } else {
                b.total_cmp(&a)
            }
        })
        .expect("one_variant returns at least one row");
    let each: Vec<String> = views
        .iter()
        .map(|(v, e)| format!("{v}: {}", e.describe()))
        .collect();
    Ok(Side::new(
        format!(
            "{a_label} against {b_label}, {metric} {} over {} viewpoint(s) (at {view}; {})",
            if worst_is_lowest { "lowest" } else { "largest" },
            views.len(),
            each.join("; ")
        ),
        vec![Sample::exact(view.clone(), worst.value(metric))],
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
