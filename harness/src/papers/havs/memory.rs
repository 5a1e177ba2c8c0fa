//! Claim H11 (§3 and §5.4: HAVS keeps no connectivity, hence its very low memory overhead):
//! what the memory ledger measured, split by a least-squares line into a fixed part (tables,
//! uniforms) and a part per tet, so that a verdict that differs between data sets is explained
//! from the rows rather than from a guess.

use crate::papers::session::Measured;

/// One renderer H11 compares: (label, algorithm, settings that pick the variant).
type Side = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

/// The two renderers H11 compares.
const SIDES: [Side; 2] = [
    (
        "HAVS (k = 2)",
        "havs",
        &[("k", "2"), ("mode", "fragment-race")],
    ),
    (
        "The ray caster (5×5 tiles, 2D table)",
        "raycast",
        &[("tiles", "5x5"), ("table", "2d")],
    ),
];

/// Per data set (first row of each), the tets and persistent device bytes of `algorithm`'s
/// rows whose settings hold every pair of `pick`.
fn ledger_points(m: &Measured, algorithm: &str, pick: &[(&str, &str)]) -> Vec<(String, f64, f64)> {
    let mut out: Vec<(String, f64, f64)> = vec![];
    for r in &m.rows {
        let chosen = r.algorithm == algorithm && pick.iter().all(|(k, v)| r.settings.is(k, v));
        if !chosen || !r.ok() || r.tets == 0 || out.iter().any(|(d, ..)| *d == r.dataset) {
            continue;
        }
        if let Some(bytes) = r.gpu_bytes_persistent {
            out.push((r.dataset.clone(), r.tets as f64, bytes as f64));
        }
    }
    out
}

/// The least-squares line `bytes = fixed + per_tet · tets` (`None` without two distinct tet
/// counts).
fn fixed_and_per_tet(points: &[(String, f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    let mean_t = points.iter().map(|p| p.1).sum::<f64>() / n;
    let mean_b = points.iter().map(|p| p.2).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.1 - mean_t).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.1 - mean_t) * (p.2 - mean_b)).sum();
    (points.len() >= 2 && sxx > 0.0).then(|| {
        let per_tet = sxy / sxx;
        (mean_b - per_tet * mean_t, per_tet)
    })
}

/// The note under the claims: both renderers' bytes per tet on each data set, and each one's
/// fixed part and bytes per tet from the line through its data sets.
pub fn memory_note(m: &Measured) -> Option<String> {
    let mut parts = vec![];
    for (label, algorithm, pick) in SIDES {
        let points = ledger_points(m, algorithm, pick);
        if points.is_empty() {
            return None;
        }
        let per_set: Vec<String> = points
            .iter()
            .map(|(d, tets, bytes)| format!("{d} {:.1} B/tet", bytes / tets))
            .collect();
        let line = fixed_and_per_tet(&points).map_or(String::new(), |(fixed, per_tet)| {
            format!(
                "; a line through them: {:.1} MiB fixed plus {per_tet:.1} B per tet",
                fixed / (1u64 << 20) as f64
            )
        });
        parts.push(format!("{label}: {}{line}", per_set.join(", ")));
    }
    Some(format!(
        "Memory (claim H11), persistent device bytes from the ledger over the tets. {}. A fixed part (pre-integration table, sort and count buffers sized once) weighs most on the smallest mesh; the part per tet is what grows with the data.",
        parts.join(". ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The line through exact points gives back their fixed part and slope.
    #[test]
    fn the_line_recovers_a_fixed_part_and_bytes_per_tet() {
        let p = |t: f64| (format!("{t}"), t, 4_000_000.0 + 50.0 * t);
        let (fixed, per_tet) = fixed_and_per_tet(&[p(1e5), p(1e6), p(3e6)]).unwrap();
        assert!((fixed - 4e6).abs() < 1e-3 && (per_tet - 50.0).abs() < 1e-9);
        assert!(fixed_and_per_tet(&[p(1e5)]).is_none());
    }
}
