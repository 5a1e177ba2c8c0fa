//! Fragment PT (Marroquim, Maximo, Farias, Esperança 2006): Tables 1–2 and the 20 bytes/tet
//! of §4.
//!
//! Plan (from `reports/papers/fragment-pt.md`): Table 1, fps and tets/s of the method on Spx,
//! Blunt, Comb, Post, Spx2, Fuel and Brain at 512² while the model rotates (an orbit of
//! viewpoints; the bucket sort of §3.2, which the method uses while the view changes; shading
//! not stated, we use the average-scalar mode); Table 2, fps on Blunt and Post beside GATOR and
//! the ray casters (HARC: `raycast` where built in; HARC PPI and VICP have no tetbench
//! algorithm). Fig. 8 (performance against viewport size) is `tetbench analyze resolution`
//! ([`fig8`]).

use crate::papers::session::{find_variant, Extra, Measured, Report, RunSpec, Session};
use crate::papers::table::{Cell, CompRow, Comparison, Metric, PaperRow};
use crate::papers::transcription;
use crate::papers::{Paper, PaperModule};
use crate::report::Aggregate;

pub mod fig8;

pub const PAPER: Paper = Paper {
    id: "fragment-pt",
    title: "Fragment PT — GPU-Based Cell Projection for Interactive Volume Rendering (Marroquim et al. 2006)",
    citation: "R. Marroquim, A. Maximo, R. Farias, C. Esperança, SIBGRAPI 2006. Provenance: reports/papers/fragment-pt.md.",
    hardware: "Pentium IV 3.6 GHz, 2 GB, nVidia GeForce 6800 256 MB, PCI Express 16x, Linux, OpenGL 2.0/GLSL; 512² viewport, model rotating during timing.",
    algorithm: "fragment-pt",
    datasets: &["spx", "bluntfin", "comb", "post", "spx2", "fuel", "brain"],
    sections: &["Abstract", "§1", "§2", "§3", "§3.1", "§3.2", "§3.3", "§3.4", "§4", "§5", "Table 1", "Table 1 caption", "Table 2"],
    analyze_about: "Fragment PT (Marroquim et al. 2006) Tables 1–2, bytes per tet and claims from finished runs.",
};

/// Table 1 rows: paper name → registry name.
const DATASETS: [(&str, &str); 7] = [
    ("Spx", "spx"),
    ("Blunt", "bluntfin"),
    ("Comb", "comb"),
    ("Post", "post"),
    ("Spx2", "spx2"),
    ("Fuel", "fuel"),
    ("Brain", "brain"),
];
const FRAGMENT_SETTINGS: &str = "shading=average;sort=bucket";
/// The order of still frames (§3.2), against which F8 judges the bucket sort's image.
const MERGE_SETTINGS: &str = "shading=average;sort=merge";
/// F8's positive control: the bucket sort with a tenth of the paper's about 20 slabs (§4), which
/// F8's rule must reject against the merge-sorted image.
const CONTROL_SETTINGS: &str = "shading=average;sort=bucket;slabs=2";
/// Table 2 rows → tetbench algorithm and settings (None: no tetbench algorithm).
const TABLE2: [(&str, Option<&str>, &str); 5] = [
    ("GPU CP for Int. VR", Some("fragment-pt"), FRAGMENT_SETTINGS),
    ("GATOR", Some("gator-pt"), "variant=linear;sort=radix"),
    // HARC is Weiler et al.'s ray caster: one tile and the 3D pre-integration table, as they
    // ran it (named, so no default variant stands in silently).
    (
        "HARC",
        Some("raycast"),
        "tiles=1x1;table=3d;mode=passes;et=on",
    ),
    ("HARC PPI", None, ""),
    ("VICP", None, ""),
];
/// §4: 16 B per tet texel + 16 B per vertex texel, quoted as about 20 B per tet.
const PAPER_BYTES_PER_TET: f64 = 20.0;

/// The fragment PT paper.
pub struct FragmentPt;

impl PaperModule for FragmentPt {
    fn paper(&self) -> &'static Paper {
        &PAPER
    }

    fn plan(&self) -> Vec<RunSpec> {
        let run = |name: &str, datasets: &[&str], settings: &str| {
            RunSpec::new(name, "fragment-pt", datasets, "orbit:14", Some(settings))
        };
        let (brain, others): (Vec<&str>, Vec<&str>) = DATASETS
            .map(|(_, d)| d)
            .into_iter()
            .partition(|d| *d == "brain");
        // Claim F8: the merge sort the paper draws still frames with, and its positive control,
        // on the data sets of F2, at the main run's viewpoints and viewport so each image pairs
        // with a bucket-sorted one.
        let f2: Vec<&str> = others.iter().copied().filter(|d| *d != "fuel").collect();
        let mut plan = vec![
            run("fragment-pt", &others, FRAGMENT_SETTINGS),
            run("fragment-pt-merge", &f2, MERGE_SETTINGS),
            run("fragment-pt-control", &f2, CONTROL_SETTINGS),
            // §5's 5.5 M tets on a 256 MB board (claim F7) is judged on the device bytes of
            // the Brain row, which depend on the viewport: 512² in every mode.
            RunSpec {
                full_viewport: true,
                ..run("fragment-pt-brain", &brain, FRAGMENT_SETTINGS)
            },
        ];
        for (label, alg, settings) in TABLE2.iter().skip(1) {
            let Some(alg) = alg else { continue };
            let name = format!("table2-{}", crate::results::names::slug(label));
            let settings = (!settings.is_empty()).then_some(*settings);
            plan.push(RunSpec::new(
                name,
                alg,
                &["bluntfin", "post"],
                "orbit:14",
                settings,
            ));
        }
        plan
    }

    fn analyses(&self, s: &mut Session, m: &mut Measured) -> anyhow::Result<Extra> {
        let mut x = Extra::default();
        for (_, d) in DATASETS {
            if let Some(ds) = s.load(d, m) {
                let (points, tets) = (ds.mesh.num_points(), ds.mesh.num_tets());
                x.sizes.push((d.to_string(), points as u64, tets as u64));
            }
        }
        Ok(x)
    }

    fn tables(&self, m: &Measured, x: &Extra) -> Report {
        tables(m, x)
    }
}

/// Tables 1–2, the bytes per tet of §4 and the paper's claims from what was measured.
pub fn tables(m: &Measured, x: &Extra) -> Report {
    let aggs = m.aggregates();
    Report {
        comparisons: vec![table1(m, x, &aggs), memory(m), table2(m, &aggs)],
        claims: crate::papers::evidence::evaluate_claims(
            PAPER.id,
            m,
            x,
            &crate::papers::evidence::no_analyses,
        ),
        notes: vec![],
        figures: vec![],
    }
}

/// Table 1: the data sets' sizes and the method's rates while the model rotates.
fn table1(m: &Measured, x: &Extra, aggs: &[Aggregate]) -> Comparison {
    let t = transcription::embedded("fragment-pt_table1");
    let rows = DATASETS
        .iter()
        .map(|&(paper, d)| {
            let a = find_variant(aggs, "fragment-pt", d, FRAGMENT_SETTINGS);
            let size = x.size(d);
            let row = PaperRow::new(&t, paper, m.why("fragment-pt", d));
            let cells = vec![
                row.cell("vertices", size.map(|s| s.0 as f64)),
                row.cell("tets", size.map(|s| s.1 as f64)),
                row.cell("fps", a.and_then(|a| a.fps.map(|s| s.mean))),
                row.cell(
                    "tets_per_sec",
                    a.and_then(|a| a.tets_per_sec.map(|s| s.mean)),
                ),
            ];
            CompRow::on(format!("{paper} ({d})"), d, cells)
        })
        .collect();
    Comparison {
        key: "table1".into(),
        title: "Table 1 — data sets and average rates while rotating".into(),
        conditions: format!(
            "Paper: 512², model rotating, counts printed rounded (compared after rounding ours the same way). Ours: `{FRAGMENT_SETTINGS}` (the bucket sort the paper uses while the view changes; shading not stated), an orbit of viewpoints, mean over them; fps = 1000 / median total frame ms."
        ),
        metrics: vec![
            Metric::new("vertices", 0),
            Metric::new("tets", 0),
            Metric::new("fps", 2),
            Metric::new("tets/s", 0),
        ],
        rows,
        notes: vec!["Fuel and Brain are stand-ins at the paper's sizes: a synthetic 64³ volume and HeadMRVolume resampled to 98³, 6 tets per cube.".into()],
    }
}

/// §4: the model's bytes per tet against the paper's 20.
fn memory(m: &Measured) -> Comparison {
    let rows = DATASETS
        .iter()
        .map(|&(paper, d)| {
            let model = m.counter("fragment-pt", d, "model_bytes_per_tet");
            let cell = Cell::new(Some(PAPER_BYTES_PER_TET), model)
                .missing_because(&m.why("fragment-pt", d))
                .uncertain(Some(
                    "the paper's 20 assumes about 4 tets per vertex".into(),
                ));
            CompRow::on(format!("{paper} ({d})"), d, vec![cell])
        })
        .collect();
    Comparison {
        key: "memory".into(),
        title: "§4 — GPU bytes per tet of the model (vertex and tet textures)".into(),
        conditions: "Paper (§4): 16 B per tet texel + 16 B per vertex texel, about 20 B/tet at about four tets per vertex. Ours: the renderer's `model_bytes_per_tet` counter (tet indices + vertices), which does not depend on the GPU. Claims F2 (about 20) and F3 (under the ray casters' 96 and 144) give the verdicts.".into(),
        metrics: vec![Metric::new("B/tet", 1)],
        rows,
        notes: brain_bytes_note(m).into_iter().collect(),
    }
}

/// Table 2: fps on Blunt and Post beside the other methods.
fn table2(m: &Measured, aggs: &[Aggregate]) -> Comparison {
    let t = transcription::embedded("fragment-pt_table2");
    let rows = TABLE2
        .iter()
        .map(|&(label, alg, settings)| {
            let cells = [("blunt_fps", "bluntfin"), ("post_fps", "post")]
                .map(|(col, d)| {
                    let why = match alg {
                        Some(a) => m.why(a, d),
                        None => "no tetbench algorithm implements it".into(),
                    };
                    let ours = alg
                        .and_then(|a| find_variant(aggs, a, d, settings))
                        .and_then(|a| a.fps.map(|s| s.mean));
                    PaperRow::new(&t, label, why).cell(col, ours)
                })
                .to_vec();
            let settings = Some(settings).filter(|s| !s.is_empty());
            CompRow::method(label, alg, settings, cells)
        })
        .collect();
    Comparison {
        key: "table2".into(),
        title: "Table 2 — fps against other methods".into(),
        conditions: "Paper: 512², model rotating; competitors' code from their authors (HARC PPI) or reimplemented. Ours: the same orbit and viewport for every algorithm; GATOR with linear cells and the centroid radix sort. The paper's HARC is Weiler et al.'s ray caster; tetbench's `raycast` is the tiled one (Bernardon et al.), the closest we have.".into(),
        metrics: vec![Metric::new("Blunt fps", 2), Metric::new("Post fps", 2)],
        rows,
        notes: vec![],
    }
}

/// The bytes of a 256 MB board (claim F7).
const BOARD_BYTES: f64 = 268_435_456.0;

/// Claim F7's 256 MiB line against two readings of the paper's layout for `tets` tets: the model
/// alone resident (§4: 20 B/tet), and the model with pass 1's output for every tet at once
/// (§3.1: two RGBA32F render targets, one texel per tet, 32 B/tet more). Says which side of
/// the line each falls on, and so which readings the line can tell apart.
fn layout_readings(tets: f64) -> String {
    const MIB: f64 = 1048576.0;
    let model = 20.0 * tets;
    let described = 52.0 * tets;
    let side = |b: f64| if b <= BOARD_BYTES { "under" } else { "over" };
    let verdict = if (model <= BOARD_BYTES) != (described <= BOARD_BYTES) {
        "The 256 MiB line tells these two readings apart; it cannot tell the second from an allocation larger still, such as ours."
    } else {
        "The 256 MiB line cannot tell these two readings apart on this mesh."
    };
    format!(
        "Two readings of the paper's layout for this mesh: the model alone (§4, 20 B/tet) {:.1} MiB, {} 256 MiB; the model with pass 1's two RGBA32F records of every tet at once, as §3.1 describes pass 1 (52 B/tet) {:.1} MiB, {} it. {verdict} The paper describes the second and mentions no batching of pass 1, so by its own layout this mesh is {} its 256 MB board.",
        model / MIB,
        side(model),
        described / MIB,
        side(described),
        side(described),
    )
}

/// §5's 5.5 M tets on a 256 MB board (claim F7): where the Brain row's device bytes go, from
/// the renderer's ledger counters, beside what the paper's own textures would take.
fn brain_bytes_note(m: &Measured) -> Option<String> {
    let r = m
        .rows
        .iter()
        .find(|r| r.algorithm == "fragment-pt" && r.dataset == "brain" && r.ok())?;
    let total = r.gpu_bytes? as f64;
    let tets = r.tets as f64;
    const MIB: f64 = 1048576.0;
    let paper = layout_readings(tets);
    let head = format!(
        "Brain (claim F7, §5's 5.5 M tets on a 256 MB board), as allocated at {}²: {:.1} MiB in all for {} tets, {:.1} B/tet",
        r.width,
        total / MIB,
        r.tets,
        total / tets
    );
    let per = |name: &str| r.counter(name);
    Some(match (
        per("model_bytes_per_tet"),
        per("records_bytes_per_tet"),
        per("sort_bytes_per_tet"),
    ) {
        (Some(model), Some(records), Some(sort)) => format!(
            "{head}: the model {model:.1} B/tet (§4's 20), pass 1's per-tet records {records:.1} B/tet, the sort's depths and order {sort:.1} B/tet, tables, parameters and the target {:.1} B/tet. {paper}",
            total / tets - model - records - sort
        ),
        // Rows without the per-buffer counters: the split the row itself records.
        _ => format!(
            "{head}: {:.1} B/tet live as long as the mesh (the model and the tables), {:.1} B/tet are per-frame buffers (pass 1's per-tet records, the sort's buffers, the target). {paper}",
            r.gpu_bytes_persistent.unwrap_or(0) as f64 / tets,
            r.gpu_bytes_frame.unwrap_or(0) as f64 / tets
        ),
    })
}

#[cfg(test)]
mod layout_tests {
    use super::layout_readings;

    /// On Brain's 5,476,038 tets the model alone fits 256 MiB and the layout §3.1 describes
    /// does not, so the line tells them apart; on 4 M tets both fit and it cannot.
    #[test]
    fn the_256_mib_line_tells_the_readings_apart_only_where_it_falls_between_them() {
        let brain = layout_readings(5_476_038.0);
        assert!(brain.contains("104.4 MiB, under"), "{brain}");
        assert!(brain.contains("271.6 MiB, over"), "{brain}");
        assert!(brain.contains("tells these two readings apart"), "{brain}");
        assert!(
            brain.contains("this mesh is over its 256 MB board"),
            "{brain}"
        );
        let smaller = layout_readings(4_000_000.0);
        assert!(
            smaller.contains("cannot tell these two readings apart"),
            "{smaller}"
        );
        assert!(smaller.contains("this mesh is under"), "{smaller}");
    }
}
