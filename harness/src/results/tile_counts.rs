//! The per-tile counts a renderer reports ([`render_core::TileCounts`]) as the run writes them:
//! `….NAME.json` beside the row's rendering, named in the row's `tile_counts` column. This
//! file is their one writer and one reader.

use std::path::Path;

use anyhow::Context;
use render_core::TileCounts;

/// Writes `counts` as `STEM.NAME.json` into `dir` (the folder `rel` names, relative to the
/// output directory) and returns the path the row names, relative to the output directory.
pub fn write(dir: &Path, rel: &str, stem: &str, counts: &TileCounts) -> anyhow::Result<String> {
    if let Some(problem) = counts.problem() {
        anyhow::bail!("the renderer's tile counts are inconsistent: {problem}");
    }
    let name = format!("{stem}.{}.json", counts.name);
    let path = dir.join(&name);
    let text = serde_json::to_string(counts).context("encoding tile counts")?;
    std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(format!("{rel}/{name}"))
}

/// Reads the counts a row names: `rel` relative to the run folder `run_dir`. An unreadable,
/// malformed or inconsistent file is an error that names it.
pub fn read(run_dir: &Path, rel: &str) -> anyhow::Result<TileCounts> {
    let path = run_dir.join(rel);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let counts: TileCounts = serde_json::from_str(&text)
        .with_context(|| format!("{} is not a tile counts file", path.display()))?;
    if let Some(problem) = counts.problem() {
        anyhow::bail!("{}: {problem}", path.display());
    }
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts() -> TileCounts {
        TileCounts {
            name: "passes".into(),
            width: 8,
            height: 8,
            tiles: [2, 2],
            tile_size: [4, 4],
            counts: vec![0, 8, 16, 8],
        }
    }

    #[test]
    fn written_counts_read_back_and_bad_files_name_themselves() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("images/v")).unwrap();
        let rel = write(&dir.path().join("images/v"), "images/v", "ray", &counts()).unwrap();
        assert_eq!(rel, "images/v/ray.passes.json");
        assert_eq!(read(dir.path(), &rel).unwrap(), counts());
        // Inconsistent on either side: refused, naming the file when reading.
        let mut bad = counts();
        bad.counts.pop();
        assert!(write(dir.path(), ".", "x", &bad).is_err());
        let path = dir.path().join(&rel);
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, text.replace("[0,8,16,8]", "[0,8,16]")).unwrap();
        let e = format!("{:#}", read(dir.path(), &rel).unwrap_err());
        assert!(
            e.contains("ray.passes.json") && e.contains("3 counts"),
            "{e}"
        );
        std::fs::write(&path, "{").unwrap();
        let e = format!("{:#}", read(dir.path(), &rel).unwrap_err());
        assert!(e.contains("is not a tile counts file"), "{e}");
        let e = format!("{:#}", read(dir.path(), "gone.json").unwrap_err());
        assert!(e.contains("gone.json"), "{e}");
    }
}
