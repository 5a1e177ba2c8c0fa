//! The one aggregation every report reads: rows grouped per variant
//! (algorithm + typed settings) × data set × viewport (width × height, projection), over their
//! viewpoints (the papers average over the 14 fixed viewpoints, HAVS §6), with the spreads the
//! HTML and Markdown summaries, the charts, the papers' tables and `analyze` show, and the
//! suspect rows of [`crate::results::suspect`]. Like criterion's one analysis feeding several
//! reports: nothing downstream groups rows again.

use crate::results::stats::{spread, Spread};
use crate::results::Row;

/// What rows are grouped by: one variant on one data set at one viewport. `tetbench compare`
/// and `history` match their groups across runs by the same key.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupKey {
    pub algorithm: String,
    pub settings: render_core::Settings,
    pub dataset: String,
    pub width: u32,
    pub height: u32,
    pub projection: String,
}

impl GroupKey {
    pub fn of(row: &Row) -> GroupKey {
        GroupKey {
            algorithm: row.algorithm.clone(),
            settings: row.settings.clone(),
            dataset: row.dataset.clone(),
            width: row.width,
            height: row.height,
            projection: row.projection.clone(),
        }
    }

    pub fn matches(&self, row: &Row) -> bool {
        self.algorithm == row.algorithm
            && self.settings == row.settings
            && self.dataset == row.dataset
            && self.width == row.width
            && self.height == row.height
            && self.projection == row.projection
    }

    /// The distinct groups of `rows`, in the order they first appear.
    pub fn distinct<'a>(rows: impl IntoIterator<Item = &'a Row>) -> Vec<GroupKey> {
        let mut groups: Vec<GroupKey> = vec![];
        for r in rows {
            if !groups.iter().any(|g| g.matches(r)) {
                groups.push(GroupKey::of(r));
            }
        }
        groups
    }
}

/// One group's numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct Aggregate {
    pub algorithm: String,
    pub settings: render_core::Settings,
    pub dataset: String,
    pub width: u32,
    pub height: u32,
    pub projection: String,
    pub tets: u64,
    pub rows: usize,
    pub failed: usize,
    /// The first failed row's error (what a chart says instead of a value).
    pub error: String,
    /// Rows flagged by [`crate::results::suspect::flags`].
    pub suspect: usize,
    pub total_ms: Option<Spread>,
    pub cpu_ms: Option<Spread>,
    pub gpu_ms: Option<Spread>,
    pub fps: Option<Spread>,
    pub tets_per_sec: Option<Spread>,
    /// The tets/s each row would read at its roofline (`tets / roofline_ms`): the fastest the
    /// backend's calibrated peaks allow for the work the row reported (docs/roofline.md).
    pub bound_tets_per_sec: Option<Spread>,
    pub psnr_db: Option<Spread>,
    pub rmse: Option<Spread>,
    pub bad_pixel_share: Option<Spread>,
    pub bytes_per_tet: Option<f64>,
    /// Largest GPU bytes over the viewpoints.
    pub gpu_bytes: Option<u64>,
}

impl Aggregate {
    /// `algorithm settings` as one label.
    pub fn series(&self) -> String {
        crate::results::names::series_label(&self.algorithm, &self.settings.to_string())
    }

    /// The data set, with the viewport when `aggs` span several (a table row would otherwise
    /// read like a duplicate).
    pub fn place(&self, aggs: &[Aggregate]) -> String {
        let several = aggs.iter().any(|a| {
            (a.width, a.height, &a.projection) != (self.width, self.height, &self.projection)
        });
        if several {
            format!(
                "{} @ {}×{} {}",
                self.dataset, self.width, self.height, self.projection
            )
            .trim_end()
            .to_string()
        } else {
            self.dataset.clone()
        }
    }
}

/// Groups rows by [`GroupKey`], in order of first appearance.
pub fn aggregate(rows: &[Row]) -> Vec<Aggregate> {
    let suspect = crate::results::suspect::flags(rows);
    let mut keys: Vec<GroupKey> = vec![];
    let mut members: Vec<Vec<usize>> = vec![];
    for (i, r) in rows.iter().enumerate() {
        match keys.iter().position(|k| k.matches(r)) {
            Some(j) => members[j].push(i),
            None => {
                keys.push(GroupKey::of(r));
                members.push(vec![i]);
            }
        }
    }
    keys.into_iter()
        .zip(members)
        .map(|(k, m)| {
            let g: Vec<&Row> = m.iter().map(|&i| &rows[i]).collect();
            Aggregate {
                tets: g[0].tets,
                rows: g.len(),
                failed: g.iter().filter(|r| !r.ok()).count(),
                error: g
                    .iter()
                    .find(|r| !r.ok())
                    .map(|r| r.error_text())
                    .unwrap_or_default(),
                suspect: m.iter().filter(|&&i| suspect[i]).count(),
                total_ms: spread(g.iter().filter_map(|r| r.total_ms)),
                cpu_ms: spread(g.iter().filter_map(|r| r.cpu_ms)),
                gpu_ms: spread(g.iter().filter_map(|r| r.gpu_ms)),
                fps: spread(g.iter().filter_map(|r| r.fps)),
                tets_per_sec: spread(g.iter().filter_map(|r| r.tets_per_sec)),
                bound_tets_per_sec: spread(g.iter().filter_map(|r| {
                    r.roofline_ms
                        .filter(|&ms| ms > 0.0)
                        .map(|ms| r.tets as f64 / (ms * 1e-3))
                })),
                psnr_db: spread(g.iter().filter_map(|r| r.psnr_db)),
                rmse: spread(g.iter().filter_map(|r| r.rmse)),
                bad_pixel_share: spread(g.iter().filter_map(|r| r.bad_pixel_share)),
                bytes_per_tet: g.iter().find_map(|r| r.bytes_per_tet),
                gpu_bytes: g.iter().filter_map(|r| r.gpu_bytes).max(),
                algorithm: k.algorithm,
                settings: k.settings,
                dataset: k.dataset,
                width: k.width,
                height: k.height,
                projection: k.projection,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::test_row;

    /// Viewpoints of one variant, data set and viewport are one group; another viewport is
    /// another group; a row whose PSNR is far below the best of its image counts as suspect
    /// even when its `suspect` column is empty (results merged from several runs).
    #[test]
    fn groups_per_variant_data_set_and_viewport() {
        let mut rows: Vec<Row> = (0..3).map(test_row).collect();
        let mut big = test_row(0);
        big.width *= 2;
        rows.push(big);
        for r in &mut rows {
            r.psnr_db = Some(50.0);
        }
        let mut other = test_row(0);
        other.algorithm = "other".into();
        other.psnr_db = Some(15.0);
        rows.push(other);
        let a = aggregate(&rows);
        assert_eq!(a.len(), 3);
        assert_eq!((a[0].rows, a[1].rows, a[2].rows), (3, 1, 1));
        assert_eq!((a[0].suspect, a[2].suspect), (0, 1));
        assert!(a[1].place(&a).contains('@'));
    }
}
