//! The numbers behind a paper's claims: the run's rows, the data set sizes, and for the
//! metrics that are not in rows, the paper's own CPU analyses (its module answers for them:
//! this file names no paper).

use super::session::{Extra, Measured};
use crate::papers::claims::{self, AnalysisSide, ClaimResult, Metric, VariantSpec};
use crate::papers::verdict::{Sample, Side};

/// For papers without CPU analyses of their own.
pub fn no_analyses(_: &Metric, _: &VariantSpec, _: Option<&str>) -> Option<Result<Side, String>> {
    None
}

/// A side of exactly one value without noise (a count, a byte size).
pub fn exact_side(label: String, key: &str, v: f64) -> Result<Side, String> {
    Ok(Side::new(label, vec![Sample::exact(key, v)]))
}

/// Every claim of `paper` evaluated on what was measured: the run's rows, the data set
/// sizes, and `own`, the paper's CPU analyses, for the metrics that are not in rows.
pub fn evaluate_claims(
    paper: &str,
    m: &Measured,
    x: &Extra,
    own: &AnalysisSide,
) -> Vec<ClaimResult> {
    let analysis = |metric: &Metric, spec: &VariantSpec, d: Option<&str>| {
        own(metric, spec, d).or_else(|| analysis_side(x, metric, spec, d))
    };
    let why = |a: &str, d: &str| m.why(a, d);
    claims::evaluate_all(
        paper,
        &claims::Inputs {
            rows: &m.rows,
            analysis: &analysis,
            why_missing: &why,
            software_adapter: claims::software_adapter(&m.rows),
            our_peaks: m
                .calibration
                .as_ref()
                .and_then(|c| crate::papers::hardware::control_peaks(&c.adapter, &m.rows))
                .or_else(|| {
                    m.calibration
                        .as_ref()
                        .map(crate::papers::hardware::our_peaks)
                }),
            cached_peaks: m
                .calibration
                .as_ref()
                .filter(|_| m.rows.iter().any(|r| !r.round_control.is_empty()))
                .map(crate::papers::hardware::our_peaks),
            row_dirs: &m.row_dirs,
        },
    )
}

/// A claim's side from the data set sizes (`None`: not one; the rows answer).
fn analysis_side(
    x: &Extra,
    metric: &Metric,
    spec: &VariantSpec,
    dataset: Option<&str>,
) -> Option<Result<Side, String>> {
    let exact =
        |label: String, key: &str, v: f64| Ok(Side::new(label, vec![Sample::exact(key, v)]));
    let need = |d: Option<&str>| {
        d.map(String::from)
            .ok_or_else(|| format!("{metric} needs a data set"))
    };
    Some(match spec.algorithm.as_str() {
        "dataset" => (|| {
            let d = need(dataset)?;
            let (_, points, tets) = x
                .sizes
                .iter()
                .find(|(n, _, _)| *n == d)
                .ok_or_else(|| format!("data set {d}: not loaded"))?;
            match metric.analysis_name().unwrap_or_default() {
                "dataset_tets" => exact(format!("{d} as loaded, tets"), &d, *tets as f64),
                // The split's own count: what we load plus the zero-volume tets we drop.
                "dataset_tets_split" => {
                    let dropped = x.dropped_by_loader(&d);
                    exact(
                        format!("{d}: {tets} tets loaded + {dropped} of zero volume dropped"),
                        &d,
                        (*tets + dropped) as f64,
                    )
                }
                "dataset_vertices" => exact(format!("{d} as loaded, vertices"), &d, *points as f64),
                _ => Err(format!("dataset has no metric {metric}")),
            }
        })(),
        _ => return None,
    })
}
