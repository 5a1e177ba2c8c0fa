//! `tetbench datasets …`: inspect, convert and list data sets.
//!
//! - `info PATH_OR_NAME [--scalar NAME] [--json]`: counts, repairs, scalar range, bounds,
//!   convexity and shape statistics of any loadable file, named data set or generator spec.
//! - `convert IN OUT.vtu`: writes any of them as VTK XML so ParaView can open it.
//! - `list`: the registry and which files are present in the data directory.
//!
//! Errors (a `datasets::LoadError` naming the file, where and what) are returned to the caller,
//! which prints them and exits non-zero.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use datasets::registry::Registry;
use datasets::write_vtu::{write_vtu_with, VtuFormat, VtuOptions};
use datasets::{Dataset, LoadOptions};
use serde_json::json;

/// The `datasets` subcommands.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum DatasetsCommand {
    /// Print what a data set holds: counts, repairs, scalar, bounds, convexity, slivers.
    Info {
        /// A file path, a named data set (see `list`) or a generator spec such as box:200k.
        target: String,
        /// Point array to use as the scalar (PLOT3D: a Q quantity such as velocity_magnitude).
        #[arg(long)]
        scalar: Option<String>,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Write a data set as VTK XML (.vtu) for ParaView.
    Convert {
        /// A file path, a named data set or a generator spec.
        input: String,
        /// Output file; must end in .vtu.
        output: PathBuf,
        /// Point array to use as the scalar.
        #[arg(long)]
        scalar: Option<String>,
        /// Array layout: appended (raw binary, the default), binary (inline base64) or ascii.
        #[arg(long, default_value = "appended")]
        format: String,
        /// zlib-compress binary arrays.
        #[arg(long)]
        compress: bool,
    },
    /// List the named data sets and generator specs, and which files are present.
    List {
        /// Print a JSON array instead of a table.
        #[arg(long)]
        json: bool,
    },
}

/// Runs a `datasets` subcommand; `data_dir` is the global `--data-dir` (None: the default
/// resolution of [`datasets::registry::default_data_dir`]).
pub fn run(cmd: DatasetsCommand, data_dir: Option<PathBuf>) -> anyhow::Result<()> {
    let registry = Registry::new(data_dir);
    match cmd {
        DatasetsCommand::Info {
            target,
            scalar,
            json,
        } => {
            let ds = load(&registry, &target, scalar)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&info_json(&ds))?);
            } else {
                print!("{}", info_text(&ds));
            }
        }
        DatasetsCommand::Convert {
            input,
            output,
            scalar,
            format,
            compress,
        } => {
            let summary = convert(&registry, &input, &output, scalar, &format, compress)?;
            println!("{summary}");
        }
        DatasetsCommand::List { json } => {
            let entries = registry.entries();
            if json {
                println!("{}", serde_json::to_string_pretty(&entries)?);
            } else {
                print!("{}", list_text(&registry));
            }
        }
    }
    Ok(())
}

fn load(registry: &Registry, target: &str, scalar: Option<String>) -> anyhow::Result<Dataset> {
    let options = LoadOptions {
        scalar,
        ..Default::default()
    };
    Ok(registry.resolve(target, &options)?)
}

/// The `info --json` object.
pub fn info_json(ds: &Dataset) -> serde_json::Value {
    let m = &ds.mesh;
    let (lo, hi) = m.scalar_range();
    let b = m.bounds();
    let q = m.quality();
    let mut v = json!({
        "name": m.name,
        "source": ds.source,
        "points": m.num_points(),
        "tets": m.num_tets(),
        "boundary_faces": m.boundary_faces().len(),
        "degenerate_dropped": m.repair.degenerate_dropped,
        "inverted_fixed": m.repair.inverted_fixed,
        "unused_points": m.repair.unused_points,
        "scalar": m.scalar_name,
        "scalar_min": lo,
        "scalar_max": hi,
        "bounds": { "min": b.min, "max": b.max },
        "convex": m.is_convex(),
        "quality": q,
        "warnings": m.repair.warnings,
        "content_hash": m.content_hash(),
    });
    if let Some(vg) = &ds.volume {
        v["volume"] = json!({ "dims": vg.dims, "spacing": vg.spacing, "origin": vg.origin });
    }
    v
}

/// The `info` text.
pub fn info_text(ds: &Dataset) -> String {
    let m = &ds.mesh;
    let (lo, hi) = m.scalar_range();
    let b = m.bounds();
    let q = m.quality();
    let mut s = String::new();
    let mut line = |k: &str, v: String| s.push_str(&format!("{k:<20} {v}\n"));
    line("name", m.name.clone());
    line("source", ds.source.clone());
    line("points", m.num_points().to_string());
    line("tets", m.num_tets().to_string());
    line("boundary faces", m.boundary_faces().len().to_string());
    line(
        "degenerate dropped",
        m.repair.degenerate_dropped.to_string(),
    );
    line("inverted fixed", m.repair.inverted_fixed.to_string());
    line("unused points", m.repair.unused_points.to_string());
    line("scalar", format!("{} in [{lo}, {hi}]", m.scalar_name));
    line(
        "bounds",
        format!(
            "[{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}]",
            b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]
        ),
    );
    line(
        "convex",
        if m.is_convex() {
            "yes".into()
        } else {
            "no".into()
        },
    );
    line(
        "edge length",
        format!(
            "min {:.4e}, mean {:.4e}, max {:.4e}",
            q.min_edge, q.mean_edge, q.max_edge
        ),
    );
    line(
        "aspect ratio",
        format!(
            "mean {:.3}, max {:.3}; slivers (> {}) {} ({:.2} %)",
            q.mean_aspect_ratio,
            q.max_aspect_ratio,
            datasets::QualityStats::SLIVER_ASPECT,
            q.slivers,
            100.0 * q.slivers as f64 / m.num_tets().max(1) as f64
        ),
    );
    if let Some(vg) = &ds.volume {
        line(
            "voxel grid",
            format!(
                "{}×{}×{}, spacing {:?}, origin {:?}",
                vg.dims[0], vg.dims[1], vg.dims[2], vg.spacing, vg.origin
            ),
        );
    }
    for w in &m.repair.warnings {
        line("warning", w.clone());
    }
    s
}

/// Converts `input` to `output` (.vtu); returns a one-line summary.
pub fn convert(
    registry: &Registry,
    input: &str,
    output: &Path,
    scalar: Option<String>,
    format: &str,
    compress: bool,
) -> anyhow::Result<String> {
    if output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
        != Some("vtu")
    {
        bail!("{}: the output must be a .vtu file", output.display());
    }
    let format = match format {
        "appended" | "raw" => VtuFormat::Appended,
        "binary" | "base64" => VtuFormat::Binary,
        "ascii" => VtuFormat::Ascii,
        other => bail!("unknown --format {other:?} (appended, binary or ascii)"),
    };
    let ds = load(registry, input, scalar)?;
    let options = VtuOptions {
        format,
        compress,
        ..VtuOptions::default()
    };
    write_vtu_with(&ds.mesh, output, &options)?;
    let bytes = std::fs::metadata(output)
        .with_context(|| format!("{}: written but cannot be read", output.display()))?
        .len();
    Ok(format!(
        "wrote {} ({} points, {} tets, scalar {:?}, {} bytes)",
        output.display(),
        ds.mesh.num_points(),
        ds.mesh.num_tets(),
        ds.mesh.scalar_name,
        bytes
    ))
}

/// The `list` table.
pub fn list_text(registry: &Registry) -> String {
    let mut s = match &registry.data_dir {
        Some(d) => format!("data directory: {}\n", d.display()),
        None => "data directory: none found (use --data-dir or set TETBENCH_DATA)\n".to_string(),
    };
    s.push_str(&format!(
        "{:<14} {:<8} {:<40} {}\n",
        "name", "present", "files", "description"
    ));
    for e in registry.entries() {
        let files = if e.files.is_empty() {
            "(generated)".to_string()
        } else {
            e.files.join(" + ")
        };
        s.push_str(&format!(
            "{:<14} {:<8} {:<40} {}\n",
            e.name,
            if e.present { "yes" } else { "MISSING" },
            files,
            e.description
        ));
    }
    s.push_str("generator specs: box|shell|tunnels|slivers:SIZE[:field=ml|blobs|radial|linear][:seed=N], SIZE like 50k or 1m\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn info_of_a_generated_shell() {
        let reg = Registry::new(None);
        let ds = load(&reg, "shell:2k", None).unwrap();
        let v = info_json(&ds);
        for key in [
            "points",
            "tets",
            "boundary_faces",
            "degenerate_dropped",
            "inverted_fixed",
            "scalar",
            "scalar_min",
            "scalar_max",
            "convex",
        ] {
            assert!(v.get(key).is_some(), "missing key {key}");
        }
        assert_eq!(v["tets"].as_u64().unwrap() as usize, ds.mesh.num_tets());
        assert_eq!(v["convex"], json!(false));
        assert_eq!(v["degenerate_dropped"], json!(0));
        let text = info_text(&ds);
        assert!(text.contains("convex               no"), "{text}");
        run(
            DatasetsCommand::Info {
                target: "box:1k".into(),
                scalar: None,
                json: true,
            },
            None,
        )
        .unwrap();
    }

    #[test]
    fn convert_writes_a_readable_vtu() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("m.vtu");
        let reg = Registry::new(None);
        for (format, compress) in [("appended", false), ("binary", true), ("ascii", false)] {
            let s = convert(&reg, "slivers:2k", &out, None, format, compress).unwrap();
            assert!(s.contains("tets"), "{s}");
            let back = reg
                .resolve(out.to_str().unwrap(), &LoadOptions::default())
                .unwrap();
            let orig = load(&reg, "slivers:2k", None).unwrap();
            assert_eq!(back.mesh.tets, orig.mesh.tets);
            assert_eq!(back.mesh.points, orig.mesh.points);
            assert_eq!(back.mesh.scalars, orig.mesh.scalars);
        }
        assert!(convert(
            &reg,
            "box:1k",
            &dir.path().join("m.vtk"),
            None,
            "appended",
            false
        )
        .is_err());
    }

    #[test]
    fn errors_and_list() {
        let dir = tempfile::tempdir().unwrap();
        let err = run(
            DatasetsCommand::Info {
                target: "bluntfin".into(),
                scalar: None,
                json: false,
            },
            Some(dir.path().into()),
        )
        .unwrap_err();
        assert!(err.to_string().contains("bluntfinxyz.bin"), "{err}");
        let bad = dir.path().join("bad.vtu");
        std::fs::write(
            &bad,
            "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid>",
        )
        .unwrap();
        let err = run(
            DatasetsCommand::Info {
                target: bad.display().to_string(),
                scalar: None,
                json: false,
            },
            None,
        )
        .unwrap_err();
        assert!(err.to_string().contains("bad.vtu"), "{err}");
        let text = list_text(&Registry::new(Some(dir.path().into())));
        assert!(
            text.contains("bluntfin") && text.contains("MISSING") && text.contains("shell:1m"),
            "{text}"
        );
        run(DatasetsCommand::List { json: true }, None).unwrap();
    }
}
