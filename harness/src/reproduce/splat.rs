//! Image-space sheet-buffered splatting on the GPU (Grau & Tost 2007): Table 1.
//!
//! Plan (from `reports/papers/splat.md`): the six voxel volumes of Table 1 (stand-ins with the
//! paper's dimensions and effective-voxel counts; the originals are not available), the camera
//! moving (an orbit), CPU-built and GPU-built buckets. Viewport and frames are not stated; we
//! use 512². `tetbench analyze splat RUN_DIR` (`analyze/splat.rs`) prints Table 1's columns for
//! whatever volumes a run holds (ironProt, HeadMRVolume); this module compares the paper's six
//! rows. Setting `buckets=cpu|gpu`.

use datasets::standins::{self, Recipe};

use super::papers;
use super::table::{Cell, CompRow, Comparison, Metric, Ordering};
use super::{find, Extra, Measured, Paper, Report, RunSpec, Session};

pub const PAPER: Paper = Paper {
    id: "splat",
    title: "Image-space Sheet-Buffered Splatting on the GPU (Grau & Tost 2007)",
    citation: "S. Grau, D. Tost, UPC Barcelona, 2007 (venue not in the source). Provenance: reports/papers/splat.md.",
    hardware: "Pentium Dual Core 3.2 GHz, \"3.2 Gb\" memory, NVIDIA GeForce 7900 GTX 512 MB, OpenGL; camera moving, semi-transparent rendering; viewport and frame count not stated.",
    algorithm: "splat",
    reproduce,
};

/// Table 1 rows: paper name → registry name of the stand-in volume.
const VOLUMES: [(&str, &str); 6] = [
    ("Lobster", "lobster"),
    ("Engine", "engine"),
    ("BostonTeapot", "teapot"),
    ("Aneurism", "aneurism"),
    ("Bonsai", "bonsai"),
    ("StagBeetle", "stagbeetle"),
];

fn reproduce(s: &mut Session) -> anyhow::Result<Report> {
    let mut m = Measured::default();
    s.run(
        &RunSpec {
            name: "splat".into(),
            algorithms: vec!["splat".into()],
            datasets: VOLUMES.map(|(_, d)| d.to_string()).to_vec(),
            viewpoints: "orbit:14".into(),
            resolution: 512,
            settings: Some("buckets=cpu|gpu".into()),
        },
        &mut m,
    )?;
    Ok(tables(&m, &Extra::default()))
}

pub fn tables(m: &Measured, _x: &Extra) -> Report {
    let mut report = Report::default();
    let t = papers::table("splat_table1").expect("embedded paper CSV parses (tested)");
    let aggs = m.aggregates();
    let mut rows = vec![];
    for (paper, d) in VOLUMES {
        let (dims, effective) = match standins::find(d).map(|s| s.recipe) {
            Some(Recipe::Volume { dims, effective }) => (Some(dims), Some(effective)),
            _ => (None, None),
        };
        let fps = |b: &str| {
            find(&aggs, "splat", d, &[("buckets", b)]).and_then(|a| a.fps.map(|s| s.mean))
        };
        let why = m.why("splat", d);
        let mut cells = vec![];
        for (i, col) in ["dim_x_voxels", "dim_y_voxels", "dim_z_voxels"]
            .iter()
            .enumerate()
        {
            cells.push(Cell {
                paper: t.value(paper, col),
                ours: dims.map(|v| v[i] as f64),
                why_no_ours: None,
                uncertain: t.uncertain(paper, col),
            });
        }
        cells.push(Cell {
            paper: t.value(paper, "effective_voxels"),
            ours: effective.map(|e| e as f64),
            why_no_ours: None,
            uncertain: t.uncertain(paper, "effective_voxels"),
        });
        for (b, col) in [("cpu", "cpu_buckets_fps"), ("gpu", "gpu_buckets_fps")] {
            let ours = fps(b);
            cells.push(Cell {
                paper: t.value(paper, col),
                ours,
                why_no_ours: ours.is_none().then(|| why.clone()),
                uncertain: t.uncertain(paper, col),
            });
        }
        let (pc, pg) = (cells[4].paper, cells[5].paper);
        let (oc, og) = (cells[4].ours, cells[5].ours);
        report.orderings.push(Ordering {
            claim: format!(
                "Table 1, ms per frame on {paper}: GPU buckets < CPU buckets (paper: {:.2}× faster)",
                pg.zip(pc).map(|(g, c)| g / c).unwrap_or(f64::NAN)
            ),
            items: vec![
                ("GPU buckets".into(), pg.map(|f| 1e3 / f), og.map(|f| 1e3 / f)),
                ("CPU buckets".into(), pc.map(|f| 1e3 / f), oc.map(|f| 1e3 / f)),
            ],
        });
        rows.push(CompRow {
            label: format!("{paper} ({d})"),
            standin: true,
            cells,
        });
    }
    report.comparisons.push(Comparison {
        key: "table1".into(),
        title: "Table 1 — fps with CPU-built and GPU-built buckets".into(),
        conditions: "Paper: camera moving, semi-transparent, GeForce 7900 GTX. Ours: an orbit of viewpoints at 512² (unless the mode above says otherwise), `buckets=cpu|gpu`. Every volume is a generated stand-in with the paper's grid and exactly its (rounded) effective-voxel count.".into(),
        metrics: vec![
            Metric::exact("x", 0),
            Metric::exact("y", 0),
            Metric::exact("z", 0),
            Metric::rounded("effective voxels"),
            Metric::new("CPU buckets fps", 1),
            Metric::new("GPU buckets fps", 1),
        ],
        rows,
        notes: vec![],
    });
    report
}
