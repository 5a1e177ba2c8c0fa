//! Suspect rows: a rendering whose error is far out of line with the other algorithms on the
//! same image, so that a broken renderer cannot hide in a green run (HAVS at 13.7 dB on a mesh where GATOR and
//! fragment PT reach 52 dB once went unnoticed).
//!
//! Rows are compared per image: same data set, viewpoint and viewport. A row is suspect when
//! its PSNR is below [`FLOOR_DB`] outright, or below [`FINE_DB`] and more than [`GAP_DB`] below
//! the best PSNR of that image. Rows without a PSNR (failed, or `--no-reference`) are never suspect: failures are
//! reported on their own.

use std::fmt;
use std::str::FromStr;

use render_core::Settings;

use crate::results::outcome::TextColumn;
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

/// Why a row's image is suspect. The figures are kept at the tenth of a dB its text shows, so
/// a row read back from a file equals the row written.
#[derive(Debug, Clone, PartialEq)]
pub enum Suspect {
    /// The PSNR is below `floor_db` ([`FLOOR_DB`] when it was judged).
    BelowFloor { psnr_db: f64, floor_db: f64 },
    /// The PSNR is `gap_db` below the best row of the same image, that of `best_algorithm`
    /// with `best_settings` at `best_db`.
    BelowBest {
        psnr_db: f64,
        gap_db: f64,
        best_algorithm: String,
        best_settings: Settings,
        best_db: f64,
    },
}

/// `x` as its text to one decimal shows it.
fn tenth(x: f64) -> f64 {
    format!("{x:.1}").parse().unwrap_or(x)
}

impl fmt::Display for Suspect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Suspect::BelowFloor { psnr_db, floor_db } => {
                write!(f, "PSNR {psnr_db:.1} dB is below {floor_db} dB")
            }
            Suspect::BelowBest {
                psnr_db,
                gap_db,
                best_algorithm,
                best_settings,
                best_db,
            } => write!(
                f,
                "PSNR {psnr_db:.1} dB is {gap_db:.1} dB below the best on this image \
                 ({best_algorithm} {best_settings} {best_db:.1} dB)"
            ),
        }
    }
}

impl FromStr for Suspect {
    type Err = String;
    /// The text [`Display`](fmt::Display) writes.
    fn from_str(text: &str) -> Result<Suspect, String> {
        let bad = || "not a suspect row's reason (PSNR … dB is … below …)".to_string();
        let db = |t: &str| -> Result<f64, String> {
            t.strip_suffix(" dB")
                .and_then(|t| t.parse().ok())
                .ok_or_else(bad)
        };
        let rest = text.strip_prefix("PSNR ").ok_or_else(bad)?;
        let (psnr, rest) = rest.split_once(" dB is ").ok_or_else(bad)?;
        let psnr_db: f64 = psnr.parse().map_err(|_| bad())?;
        if let Some(floor) = rest.strip_prefix("below ") {
            return Ok(Suspect::BelowFloor {
                psnr_db,
                floor_db: db(floor)?,
            });
        }
        let (gap, best) = rest
            .split_once(" below the best on this image (")
            .ok_or_else(bad)?;
        let best = best.strip_suffix(" dB)").ok_or_else(bad)?;
        let (who, best_db) = best.rsplit_once(' ').ok_or_else(bad)?;
        let (best_algorithm, best_settings) = who.split_once(' ').ok_or_else(bad)?;
        Ok(Suspect::BelowBest {
            psnr_db,
            gap_db: db(gap)?,
            best_algorithm: best_algorithm.to_string(),
            best_settings: best_settings.parse().map_err(|e| format!("{e}"))?,
            best_db: best_db.parse().map_err(|_| bad())?,
        })
    }
}

impl TextColumn for Suspect {
    const FIELD: &'static str = "suspect";
}

/// Why `row` is suspect among `others` (which may include `row` itself), or `None`.
pub fn reason(row: &Row, others: &[Row]) -> Option<Suspect> {
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
        return Some(Suspect::BelowFloor {
            psnr_db: tenth(psnr),
            floor_db: FLOOR_DB,
        });
    }
    match best {
        Some((bp, b)) if psnr < FINE_DB && bp - psnr > GAP_DB => Some(Suspect::BelowBest {
            psnr_db: tenth(psnr),
            gap_db: tenth(bp - psnr),
            best_algorithm: b.algorithm.clone(),
            best_settings: b.settings.clone(),
            best_db: tenth(bp),
        }),
        _ => None,
    }
}

/// Suspect rows: the row's own `suspect` column, or — for results written before the column
/// existed, or rows merged from several runs — the same rule applied to these rows. One flag
/// per row.
pub fn flags(rows: &[Row]) -> Vec<bool> {
    rows.iter()
        .map(|r| r.suspect.is_some() || reason(r, rows).is_some())
        .collect()
}

/// Sets every row's `suspect` column from all rows of the run; returns how many are suspect.
pub fn mark_all(rows: &mut [Row]) -> usize {
    let reasons: Vec<Option<Suspect>> = rows.iter().map(|r| reason(r, rows)).collect();
    let n = reasons.iter().flatten().count();
    for (row, why) in rows.iter_mut().zip(reasons) {
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
        assert!(rows[0].suspect.is_none() && rows[1].suspect.is_none());
        assert_eq!(
            rows[2].suspect.as_ref().unwrap().to_string(),
            "PSNR 13.7 dB is below 20 dB"
        );
        // 17 dB below the best of its own image: within the gap.
        assert!(rows[3].suspect.is_none());
        assert!(rows[5].suspect.is_none());
        // A 30 dB gap above the floor is flagged and names the best row.
        rows[3].psnr_db = Some(21.0);
        assert_eq!(mark_all(&mut rows), 2);
        let why = rows[3].suspect.as_ref().unwrap().to_string();
        assert_eq!(
            why,
            "PSNR 21.0 dB is 31.0 dB below the best on this image \
             (gator-pt variant=a;sort=radix 52.0 dB)"
        );
        // The text reads back to the same reason.
        assert_eq!(
            why.parse::<Suspect>().as_ref(),
            Ok(rows[3].suspect.as_ref().unwrap())
        );
        // Next to a row at the 99 dB cap, 45 dB is still fine.
        rows[4].psnr_db = Some(99.0);
        rows[3].psnr_db = Some(45.0);
        assert_eq!(mark_all(&mut rows), 1);
        assert!(rows[3].suspect.is_none());
    }

    #[test]
    fn a_reason_that_does_not_parse_is_an_error() {
        let floor = "PSNR 13.7 dB is below 20 dB".parse::<Suspect>().unwrap();
        assert_eq!(floor.to_string(), "PSNR 13.7 dB is below 20 dB");
        for bad in [
            "",
            "too dark",
            "PSNR x dB is below 20 dB",
            "PSNR 1.0 dB is 3 dB",
        ] {
            assert!(bad.parse::<Suspect>().is_err(), "{bad}");
        }
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
