//! Suspect rows: a rendering whose error is far out of line with the other algorithms on the
//! same image, so that a broken renderer cannot hide in a green run (HAVS at 13.7 dB on a mesh where GATOR and
//! fragment PT reach 52 dB once went unnoticed).
//!
//! Rows are compared per image: same data set, viewpoint and viewport. A row is suspect when
//! its PSNR is below [`FLOOR_DB`] outright, or below [`FINE_DB`] and more than [`GAP_DB`] below
//! the best PSNR of that image. Rows without a PSNR (failed, or `--no-reference`) are never suspect: failures are
//! reported on their own.

use crate::results::Row;

/// How far below the best row of the same image a PSNR may fall before the row is suspect.
/// The methods differ legitimately by up to ~15–20 dB on one image (constant vs linear cells in
/// GATOR, a 2D vs 3D table, HAVS with k = 2 on a mesh needing more); 20 dB (10× the RMSE) is
/// beyond what any setting explains.
pub const GAP_DB: f64 = 20.0;

/// Below this PSNR an image is visibly wrong whatever the others do (RMSE > 0.1 of full scale).
pub const FLOOR_DB: f64 = 20.0;

/// At or above this PSNR (RMSE ≤ 1 % of full scale, invisible) a row is never suspect: next to
/// a row at the 99 dB cap, every merely excellent row would otherwise be "20 dB below the best".
pub const FINE_DB: f64 = 40.0;

fn same_image(a: &Row, b: &Row) -> bool {
    a.dataset == b.dataset
        && a.viewpoint == b.viewpoint
        && a.width == b.width
        && a.height == b.height
}

/// Why `row` is suspect among `others` (which may include `row` itself), or `None`.
pub fn reason(row: &Row, others: &[Row]) -> Option<String> {
    let psnr = row.psnr_db?;
    let best = others
        .iter()
        .filter(|o| same_image(o, row))
        .filter_map(|o| o.psnr_db.map(|p| (p, o)))
        .fold(None::<(f64, &Row)>, |acc, (p, o)| match acc {
            Some((bp, _)) if bp >= p => acc,
            _ => Some((p, o)),
        });
    if psnr < FLOOR_DB {
        return Some(format!("PSNR {psnr:.1} dB is below {FLOOR_DB} dB"));
    }
    match best {
        Some((bp, b)) if psnr < FINE_DB && bp - psnr > GAP_DB => Some(format!(
            "PSNR {psnr:.1} dB is {:.1} dB below the best on this image ({} {} {bp:.1} dB)",
            bp - psnr,
            b.algorithm,
            b.settings
        )),
        _ => None,
    }
}

/// Suspect rows: the row's own `suspect` column, or — for results written before the column
/// existed, or rows merged from several runs — the same rule applied to these rows. One flag
/// per row.
pub fn flags(rows: &[Row]) -> Vec<bool> {
    rows.iter()
        .map(|r| !r.suspect.is_empty() || reason(r, rows).is_some())
        .collect()
}

/// Sets every row's `suspect` column from all rows of the run; returns how many are suspect.
pub fn mark_all(rows: &mut [Row]) -> usize {
    let reasons: Vec<String> = rows
        .iter()
        .map(|r| reason(r, rows).unwrap_or_default())
        .collect();
    let mut n = 0;
    for (row, why) in rows.iter_mut().zip(reasons) {
        n += usize::from(!why.is_empty());
        row.suspect = why;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::test_row;

    fn row(algorithm: &str, viewpoint: &str, psnr: Option<f64>) -> Row {
        let mut r = test_row(0);
        r.algorithm = algorithm.into();
        r.viewpoint = viewpoint.into();
        r.psnr_db = psnr;
        r
    }

    #[test]
    fn a_row_far_below_the_best_of_its_image_is_flagged() {
        let mut rows = vec![
            row("gator-pt", "+x", Some(52.0)),
            row("fragment-pt", "+x", Some(51.0)),
            row("havs", "+x", Some(13.7)),
            row("havs", "+y", Some(35.0)),
            row("gator-pt", "+y", Some(52.0)),
            row("broken", "+y", None),
        ];
        assert_eq!(mark_all(&mut rows), 1);
        assert!(rows[0].suspect.is_empty() && rows[1].suspect.is_empty());
        assert!(
            rows[2].suspect.contains("below 20 dB"),
            "{}",
            rows[2].suspect
        );
        // 17 dB below the best of its own image: within the gap.
        assert!(rows[3].suspect.is_empty());
        assert!(rows[5].suspect.is_empty());
        // A 30 dB gap above the floor is flagged and names the best row.
        rows[3].psnr_db = Some(21.0);
        assert_eq!(mark_all(&mut rows), 2);
        assert!(
            rows[3].suspect.contains("31.0 dB below the best"),
            "{}",
            rows[3].suspect
        );
        assert!(rows[3].suspect.contains("gator-pt"));
        // Next to a row at the 99 dB cap, 45 dB is still fine.
        rows[4].psnr_db = Some(99.0);
        rows[3].psnr_db = Some(45.0);
        assert_eq!(mark_all(&mut rows), 1);
        assert!(rows[3].suspect.is_empty());
    }

    #[test]
    fn other_images_do_not_count() {
        let mut a = row("havs", "+x", Some(30.0));
        let mut b = row("gator-pt", "+x", Some(60.0));
        b.width = 16;
        a.dataset = "spx".into();
        assert_eq!(reason(&a, &[a.clone(), b.clone()]), None);
    }
}
