//! Helpers shared by the cross-crate tests.

use std::path::PathBuf;

/// The data directory of the papers' data sets, or `None` (and a printed reason) when absent.
pub fn data_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("TETBENCH_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/datasets"));
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "SKIPPED: data directory {} is absent (set TETBENCH_DATA)",
            dir.display()
        );
        None
    }
}
