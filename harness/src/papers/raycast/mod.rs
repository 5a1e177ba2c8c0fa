//! Tiled ray casting with depth peeling (Bernardon, Pagot, Comba, Silva): Tables 3–6 and the
//! 144 bytes/tet of §3.1.
//!
//! Plan (from `reports/papers/raycast.md`): spx1, blunt and f117 at 512², every tiling from
//! 1×1 to 6×6, the 2D pre-integration table (Tables 3–5) and the 3D one (Table 6), over the
//! camera positions (we use the 14 viewpoints). The tables here are the paper | ours | ratio
//! comparisons of `reproduce`; `tetbench analyze raycast RUN_DIR` (`analyze/raycast.rs`) prints
//! the same four tables for any finished run, with peel layers and steps per ray beside them
//! and our other data sets as extra rows. Settings `tiles` (`NxN`), `table` (`2d|3d`), `k`;
//! counter `passes_max` (the most passes any tile of a frame ran, spent per peeling layer as
//! the paper does). Table 4's difference from the paper is split into measured parts
//! ([`passes_parts`]): the restart per layer, k and the tiling, each from a run of its own.

use crate::papers::session::{Extra, Measured, Report, RunSpec};
use crate::papers::table::{Cell, CompRow, Comparison, Metric, PaperRow};
use crate::papers::transcription::{self, PaperTable};
use crate::papers::{Paper, PaperModule};

mod heatmap;
mod passes;
use passes::{PASSES_RUN, TILED_RUN, WALKS_RUN};

pub const PAPER: Paper = Paper {
    id: "raycast",
    title: "Tiled ray casting with depth peeling (Bernardon, Pagot, Comba, Silva)",
    citation: "F. F. Bernardon, C. A. Pagot, J. L. D. Comba, C. T. Silva, \"GPU-based Tiled Ray Casting using Depth Peeling\", journal of graphics tools (tech. report UUSCI-2004-006). Provenance: reports/papers/raycast.md.",
    hardware: "one machine with an ATI Radeon 9700 Pro 128 MB and an NVIDIA GeForce 6800 GT 256 MB, DirectX 9 / HLSL; CPU not stated; 512², 2D pre-integration table except Table 6.",
    algorithm: "raycast",
    datasets: &["spx1", "bluntfin", "f117"],
    sections: &["Abstract", "§1", "§2", "§2.1", "§2.2", "§2.3", "§2.4", "§3", "§3.1", "§3.1 (its Table 1)", "§3.2", "§4", "§5", "Table 1", "Table 2", "Table 3", "Table 4", "Table 5", "Table 6", "Tables 5–6"],
    analyze_about: "Tiled ray casting (Bernardon et al.) Tables 3–6, bytes per tet and claims from finished runs.",
};

const DATASETS: [(&str, &str); 3] = [("spx1", "spx1"), ("blunt", "bluntfin"), ("f117", "f117")];
const TILINGS: [&str; 6] = ["1x1", "2x2", "3x3", "4x4", "5x5", "6x6"];
/// §3.1: 9 RGBA32F texels per tet.
const PAPER_BYTES_PER_TET: f64 = 144.0;

/// The peeling layers of Table 4's runs, which keep them out of the timing tables.
const PASSES_LAYERS: &str = "32";

/// R8's positive control: R8's 2D-table variant (5×5 tiles, one pass per step, the main run's
/// k) with the table's entry unscaled by the segment's length (§2.2), which R8's rule must
/// reject against the 3D table's image.
const CONTROL_SETTINGS: &str = "tiles=5x5;table=2d;mode=passes;et=on;k=8;unscaled=1";

/// A run of Table 4's counts with `settings`: the paper's viewport and views in every mode.
fn passes_run(name: &str, settings: &str) -> RunSpec {
    RunSpec {
        full_viewport: true,
        full_views: true,
        ..RunSpec::new(
            name,
            "raycast",
            &DATASETS.map(|(_, d)| d),
            "14",
            Some(settings),
        )
    }
}

/// The tiled ray casting paper.
pub struct Raycast;

impl PaperModule for Raycast {
    fn paper(&self) -> &'static Paper {
        &PAPER
    }

    fn plan(&self) -> Vec<RunSpec> {
        vec![
            // The paper's configuration only: one pass per ray step (§2.3) and early ray
            // termination as in its code (opacity 0.95), k at its default. Our `mode=loop` is
            // not in its tables.
            RunSpec::new(
                "raycast",
                "raycast",
                &DATASETS.map(|(_, d)| d),
                "14",
                Some(&format!(
                    "tiles={};table=2d|3d;mode=passes;et=on;k=8",
                    TILINGS.join("|")
                )),
            ),
            // Table 4's passes are counts: at the paper's viewport and views in every mode,
            // up to 32 peeling layers so that no re-entry is dropped (the paper peels until no
            // face is left). The passes mode at k = 8 and k = 1 on one tile, at k = 8 on 6×6
            // tiles, and the loop mode's longest walk: the count and the parts of its
            // difference. One pass per step is slow on a CPU rasteriser (seconds a frame at
            // 512²), but these are counts: they need the paper's viewport and views.
            passes_run("passes", PASSES_RUN),
            passes_run("passes-tiled", TILED_RUN),
            passes_run("walks", WALKS_RUN),
            // R8's positive control, at the main run's viewpoints and viewport so that each of
            // its images pairs with a 3D-table image.
            RunSpec::new(
                "raycast-control",
                "raycast",
                &DATASETS.map(|(_, d)| d),
                "14",
                Some(CONTROL_SETTINGS),
            ),
        ]
    }

    fn tables(&self, m: &Measured, x: &Extra) -> Report {
        tables(m, x)
    }
}

fn rows_of<'a>(
    m: &'a Measured,
    dataset: &str,
    tiles: Option<&str>,
    table: Option<&str>,
) -> Vec<&'a crate::results::Row> {
    m.rows
        .iter()
        .filter(|r| r.algorithm == "raycast" && r.dataset == dataset && r.ok())
        // The passes run (Table 4) is not part of the timing tables, nor is R8's positive
        // control (the unscaled 2D table).
        .filter(|r| !r.settings.is("layers", PASSES_LAYERS))
        .filter(|r| {
            !crate::algorithms::perturbed_beyond("raycast", &r.settings, &Default::default())
        })
        .filter(|r| tiles.is_none_or(|t| r.settings.is("tiles", t)))
        .filter(|r| table.is_none_or(|t| r.settings.is("table", t)))
        .collect()
}

fn min_max(v: impl Iterator<Item = f64>) -> (Option<f64>, Option<f64>) {
    let v: Vec<f64> = v.filter(|x| x.is_finite()).collect();
    (
        v.iter().copied().reduce(f64::min),
        v.iter().copied().reduce(f64::max),
    )
}

/// Tables 3–6, the bytes per tet of §3.1, Fig. 5 and the paper's claims from what was measured.
pub fn tables(m: &Measured, x: &Extra) -> Report {
    let t3 = transcription::embedded("raycast_table3");
    // The paper's GPUs, in Table 3's order: its tables of times have a row per GPU and data set.
    let mut gpus: Vec<String> = t3
        .keys()
        .iter()
        .filter_map(|k| k.split(" / ").next().map(String::from))
        .collect();
    gpus.dedup();
    Report {
        comparisons: vec![
            table3(m, &t3, &gpus),
            // Table 4: passes from the passes runs (the paper's viewport and views in every
            // mode), with the parts of the difference.
            passes::table4(m, &transcription::embedded("raycast_table4")),
            table_ms(m, &gpus, 5, "2d"),
            table_ms(m, &gpus, 6, "3d"),
            memory(m),
        ],
        claims: crate::papers::evidence::evaluate_claims(
            PAPER.id,
            m,
            x,
            &crate::papers::evidence::no_analyses,
        ),
        notes: vec![],
        // Fig. 5: the passes per tile of the tiled passes run, beside the figure's description.
        figures: vec![heatmap::fig5(m)],
    }
}

/// Every (paper's row key, data set) of a table per GPU: `GPU / paper name`.
fn gpu_rows<'a>(gpus: &'a [String]) -> impl Iterator<Item = (String, &'static str)> + 'a {
    gpus.iter().flat_map(|gpu| {
        DATASETS
            .iter()
            .map(move |(paper, d)| (format!("{gpu} / {paper}"), *d))
    })
}

/// Table 3: min/max fps and tets/s over views and tilings (2D table).
fn table3(m: &Measured, t3: &PaperTable, gpus: &[String]) -> Comparison {
    let rows = gpu_rows(gpus)
        .map(|(key, d)| {
            let r = rows_of(m, d, None, Some("2d"));
            let (fmin, fmax) = min_max(r.iter().filter_map(|r| r.fps));
            let (tmin, tmax) = min_max(r.iter().filter_map(|r| r.tets_per_sec));
            let row = PaperRow::new(t3, &key, m.why("raycast", d));
            let cells = vec![
                row.cell("min_fps", fmin),
                row.cell("max_fps", fmax),
                row.cell("min_tets_per_sec", tmin),
                row.cell("max_tets_per_sec", tmax),
            ];
            CompRow::on(format!("{key} ({d})"), d, cells)
        })
        .collect();
    Comparison {
        key: "table3".into(),
        title: "Table 3 — min/max fps and tets/s over camera positions and tilings (2D table)".into(),
        conditions: "Paper: per GPU, 512², min/max over camera positions and all tilings 1×1…6×6. Ours: min/max over our viewpoints and tilings on this adapter (the same values are compared with each of the paper's GPUs).".into(),
        metrics: vec![
            Metric::new("min fps", 2),
            Metric::new("max fps", 2),
            Metric::new("min tets/s", 0),
            Metric::new("max tets/s", 0),
        ],
        rows,
        notes: vec![],
    }
}

/// Tables 5 (`table` 2d) and 6 (3d): min/max ms per frame per tiling.
fn table_ms(m: &Measured, gpus: &[String], number: u32, table: &str) -> Comparison {
    let t = transcription::embedded(&format!("raycast_table{number}"));
    let rows = gpu_rows(gpus)
        .map(|(key, d)| {
            let row = PaperRow::new(&t, &key, m.why("raycast", d));
            let cells = TILINGS
                .iter()
                .flat_map(|tiles| {
                    let ms = rows_of(m, d, Some(tiles), Some(table));
                    let (lo, hi) = min_max(ms.iter().filter_map(|r| r.total_ms));
                    [
                        row.cell(&format!("tiles_{tiles}_min_ms"), lo),
                        row.cell(&format!("tiles_{tiles}_max_ms"), hi),
                    ]
                })
                .collect();
            CompRow::on(format!("{key} ({d})"), d, cells)
        })
        .collect();
    Comparison {
        key: format!("table{number}"),
        title: format!(
            "Table {number} — min/max ms per frame per tiling, {} pre-integration table",
            table.to_uppercase()
        ),
        conditions: "Paper: min–max over camera positions, per GPU. Ours: min/max of the median frame time over our viewpoints, per tiling.".into(),
        metrics: TILINGS
            .iter()
            .flat_map(|t| [Metric::new(format!("{t} min ms"), 0), Metric::new(format!("{t} max ms"), 0)])
            .collect(),
        rows,
        notes: vec![],
    }
}

/// Bytes per tet (§3.1), independent of the GPU.
fn memory(m: &Measured) -> Comparison {
    let rows = DATASETS
        .iter()
        .map(|&(paper, d)| {
            // The mesh layout alone (§3.1 counts the mesh textures, not the tables).
            let b = m.counter("raycast", d, "mesh_bytes_per_tet");
            let cell =
                Cell::new(Some(PAPER_BYTES_PER_TET), b).missing_because(&m.why("raycast", d));
            CompRow::on(format!("{paper} ({d})"), d, vec![cell])
        })
        .collect();
    Comparison {
        key: "memory".into(),
        title: "§3.1 — persistent GPU bytes per tet".into(),
        conditions: "Paper: 9 RGBA32F texels per tet = 144 B (Weiler et al.: 160 B). Ours: the `mesh_bytes_per_tet` counter (the mesh layout; the pre-integration tables are counted apart, as in the paper). Does not depend on the GPU.".into(),
        metrics: vec![Metric::new("B/tet", 1)],
        rows,
        notes: vec![],
    }
}
