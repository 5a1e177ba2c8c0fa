//! Helpers shared by the cross-crate tests.

use std::path::PathBuf;

#[path = "malformed_vtk.rs"]
pub mod malformed_vtk;

/// The data directory of the papers' data sets, or `None` (and a printed reason) when absent;
/// with `TETBENCH_REQUIRE_DATA=1` a missing directory fails the test instead
/// (`datasets::registry::test_data_file`).
pub fn data_dir() -> Option<PathBuf> {
    datasets::registry::test_data_file("MANIFEST.md").and_then(|p| p.parent().map(PathBuf::from))
}

/// One file of the data directory, or `None` with a printed skip (a failure under
/// `TETBENCH_REQUIRE_DATA=1`).
pub fn data_file(name: &str) -> Option<PathBuf> {
    datasets::registry::test_data_file(name)
}
