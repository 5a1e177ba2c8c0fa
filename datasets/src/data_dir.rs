//! Where the real data sets are: `TETBENCH_DATA`, else `../shared/datasets` (from the working
//! directory, the executable's ancestors, or the crate's source). Apart from the registry, the
//! tests of the readers use it too, so it depends on no other module.

use std::path::{Path, PathBuf};

fn is_data_dir(p: &Path) -> bool {
    p.is_dir()
}

/// The default data directory (see the module documentation), if one exists.
pub fn default_data_dir() -> Option<PathBuf> {
    if let Some(v) = std::env::var_os("TETBENCH_DATA") {
        return Some(PathBuf::from(v));
    }
    let rel = PathBuf::from("../shared/datasets");
    if is_data_dir(&rel) {
        return Some(rel);
    }
    if let Ok(exe) = std::env::current_exe() {
        for anc in exe.ancestors().skip(1) {
            let c = anc.join("shared/datasets");
            if is_data_dir(&c) {
                return Some(c);
            }
        }
    }
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/datasets");
    is_data_dir(&src).then_some(src)
}

/// A file from the data directory, for tests and benches: `Some(path)` when it exists; else a
/// printed `SKIPPED` line and `None` — or a panic naming the file when the environment sets
/// `TETBENCH_REQUIRE_DATA=1` (CI, where the data directory is always laid out, so a missing file
/// is a failure rather than a quiet pass).
pub fn test_data_file(name: &str) -> Option<PathBuf> {
    let found = default_data_dir()
        .map(|d| d.join(name))
        .filter(|p| p.is_file());
    if found.is_none() {
        let where_ = default_data_dir()
            .map(|d| d.display().to_string())
            .unwrap_or_else(|| "no data directory (set TETBENCH_DATA)".into());
        if std::env::var("TETBENCH_REQUIRE_DATA").is_ok_and(|v| v == "1") {
            panic!("TETBENCH_REQUIRE_DATA=1 but data file {name} is absent ({where_})");
        }
        eprintln!("SKIPPED: data file {name} is absent ({where_})");
    }
    found
}
