//! The numbers behind a paper's claims: the run's rows, and for the metrics that are not in
//! rows, the paper's own CPU analyses (sorts, k-buffer, classifier, data set sizes).

use super::gator;
use super::session::{Extra, Measured};
use crate::papers::claims::{self, ClaimResult, VariantSpec};
use crate::papers::verdict::{Sample, Side};

/// Every claim of `paper` evaluated on what was measured: the run's rows, and the paper's CPU
/// analyses for the metrics that are not in rows.
pub fn evaluate_claims(paper: &str, m: &Measured, x: &Extra) -> Vec<ClaimResult> {
    let analysis =
        |metric: &str, spec: &VariantSpec, d: Option<&str>| analysis_side(x, metric, spec, d);
    let why = |a: &str, d: &str| m.why(a, d);
    claims::evaluate_all(
        paper,
        &claims::Inputs {
            rows: &m.rows,
            analysis: &analysis,
            why_missing: &why,
            software_adapter: claims::software_adapter(&m.rows),
        },
    )
}

/// A claim's side from the CPU analyses (`None`: not an analysis; the rows answer).
fn analysis_side(
    x: &Extra,
    metric: &str,
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
        "sort-analysis" => {
            let name = spec.setting("sort").unwrap_or_default();
            // Table 1's radix sort is §5.1's one-core LSD sort.
            let prefix = if name == "radixsort" {
                "radix sort (HAVS §5.1, one core)"
            } else {
                name.as_str()
            };
            let Some(r) = x.sorts.iter().find(|r| r.name.starts_with(prefix)) else {
                return Some(Err(format!(
                    "sort {name}: not measured (`tetbench reproduce havs` times the sorts)"
                )));
            };
            let keys = r.keys_per_sec * r.ms * 1e-3;
            let (value, min, max) = match metric {
                "sort_ms" => (r.ms, r.min_ms, r.max_ms),
                "sort_keys_per_sec" => (
                    r.keys_per_sec,
                    keys / (r.max_ms * 1e-3),
                    keys / (r.min_ms * 1e-3),
                ),
                _ => return Some(Err(format!("sort-analysis has no metric {metric}"))),
            };
            Ok(Side::new(
                format!(
                    "{} ({keys:.0} floats, median of {} runs)",
                    r.name, r.repeats
                ),
                vec![Sample {
                    key: "sort".into(),
                    value,
                    min,
                    max,
                    frames: r.repeats,
                }],
            ))
        }
        "kbuffer-analysis" => (|| {
            let d = need(dataset)?;
            let r = x.kbuffer.iter().find(|r| r.dataset == d).ok_or_else(|| {
                format!("k-buffer analysis of {d}: not run (`tetbench reproduce havs` runs it)")
            })?;
            let pixels = f64::from(x.kbuffer_resolution).powi(2);
            let v = match metric {
                "kbuffer_fragments" => r.fragments as f64,
                "kbuffer_pixels_k_gt2" => r.pixels_k_gt2 as f64,
                "kbuffer_pixels_k_gt6" => r.pixels_k_gt6 as f64,
                "kbuffer_share_k_gt6" => r.pixels_k_gt6 as f64 / pixels.max(1.0),
                "kbuffer_max_k" => r.max_k as f64,
                _ => return Err(format!("kbuffer-analysis has no metric {metric}")),
            };
            exact(
                format!(
                    "k-buffer analysis of {d}, {} viewpoints at {}²",
                    x.kbuffer_views, x.kbuffer_resolution
                ),
                &d,
                v,
            )
        })(),
        "classifier-twin" => match &x.truth_table {
            None => Err("the classifier was not run (`tetbench reproduce gator` runs it)".into()),
            Some(observed) => {
                let mismatches = gator::table1_mismatches(observed, &gator::paper_rows());
                exact(
                    format!(
                        "gator-pt classifier (CPU twin), {} distinct outcomes, mismatches{}{}",
                        observed.len(),
                        if mismatches.is_empty() { "" } else { ": " },
                        mismatches.join("; ")
                    ),
                    "table1",
                    mismatches.len() as f64,
                )
            }
        },
        "dataset" => (|| {
            let d = need(dataset)?;
            let (_, points, tets) = x
                .sizes
                .iter()
                .find(|(n, _, _)| *n == d)
                .ok_or_else(|| format!("data set {d}: not loaded"))?;
            match metric {
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
