//! GATOR (Wylie, Moreland, Fisk, Crossno 2002): Tables 1–3.
//!
//! Plan (from `reports/papers/gator.md`): Table 1, the 14-case truth table, checked against the
//! classifier's CPU twin on random projected tets (no GPU); Table 2, the data sets' vertex and
//! tet counts; Table 3, GPU time per frame and tets/s of constant and linear cells on Blunt
//! Fin, Oxygen Post and Delta Wing, sort excluded, averaged over many viewpoints (we use the 14;
//! the paper's viewport is not stated, we use 512²).

pub mod geometry;

use crate::papers::claims::VariantSpec;
use crate::papers::evidence::exact_side;
use crate::papers::session::{find, is_standin, Extra, Measured, Report, RunSpec, Session};
use crate::papers::spec;
use crate::papers::table::{Cell, CompRow, Comparison, Metric};
use crate::papers::transcription;
use crate::papers::verdict::Side;
use crate::papers::{Paper, PaperModule};

pub const PAPER: Paper = Paper {
    id: "gator",
    title: "GATOR — Tetrahedral Projection using Vertex Shaders (Wylie et al. 2002)",
    citation: "B. Wylie, K. Moreland, L. A. Fisk, P. Crossno, Proc. IEEE/ACM VolVis 2002, pp. 7–12. Provenance: reports/papers/gator.md.",
    hardware: "Dell 530, Pentium 4 2 GHz, Windows 2000, nVidia GeForce4 (VisionTek; model not stated), OpenGL vertex programs over AGP; viewport not stated; many viewpoints averaged (spread under 5 %).",
    algorithm: "gator-pt",
    datasets: &["bluntfin", "post", "deltawing"],
    sections: &["Abstract", "§1", "§2", "§3", "§3.1", "§3.2", "§3.3", "§3.4", "§3.5", "§4", "§5", "Table 1", "Table 2", "Table 3"],
    analyze_about: "GATOR (Wylie et al. 2002) Tables 1–3 and claims from finished runs.",
};

/// The paper's data set names → registry names.
const DATASETS: [(&str, &str); 3] = [
    ("Blunt Fin", "bluntfin"),
    ("Oxygen Post", "post"),
    ("Delta Wing", "deltawing"),
];

/// One distinct outcome of the classifier's CPU twin: our case number, the Shirley–Tuchman
/// class (1: three triangles, 2: four) and the test outcomes in the paper's order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct ObservedCase {
    pub case: u8,
    pub class: u8,
    pub tests: [bool; 4],
}

/// Our case number for each of the paper's Table 1 rows (row 1 first). `classify.rs` numbers
/// the cases by their outcomes in its own test order — `case = 2·(4·t1 + 2·t2 + t3) + 1 + t4`,
/// 13 and 14 for the two rows where tests 1 and 2 both hold — and its t3 is the paper's test 4,
/// its t4 the paper's test 3. Written out from the paper's rows, so a classifier that swapped
/// two cases fails the check.
pub const OUR_CASE_OF_PAPER_ROW: [u8; 14] = [14, 13, 9, 11, 7, 5, 3, 1, 10, 12, 8, 6, 4, 2];

/// Random projected tets classified by the CPU twin: the distinct outcomes, with the tests in
/// the paper's order (the paper's test 3, |V0→middle| > |V0→I|, is our t4; its test 4,
/// cross1.z > 0, is our t3).
pub fn observed_truth_table(samples: usize) -> Vec<ObservedCase> {
    observed_truth_table_with(samples, &gator_pt::classify_cpu)
}

/// [`observed_truth_table`] of another classifier (a test's broken one).
pub fn observed_truth_table_with(
    samples: usize,
    classify: &dyn Fn([[f64; 3]; 4]) -> gator_pt::Classification,
) -> Vec<ObservedCase> {
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut rnd = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut seen: Vec<ObservedCase> = vec![];
    for _ in 0..samples {
        let p: [[f64; 3]; 4] = std::array::from_fn(|_| [rnd(), rnd(), rnd()]);
        let c = classify(p);
        let [t1, t2, t3, t4] = c.tests;
        let o = ObservedCase {
            case: c.case,
            class: c.class,
            tests: [t1, t2, t4, t3],
        };
        if !seen.contains(&o) {
            seen.push(o);
        }
    }
    seen.sort();
    seen
}

/// The paper's Table 1 rows: test outcomes (None = X, either).
pub fn paper_rows() -> Vec<[Option<bool>; 4]> {
    let t = transcription::table("gator_table1").expect("embedded paper CSV parses (tested)");
    let cols = ["test1_bool", "test2_bool", "test3_bool", "test4_bool"];
    t.keys()
        .iter()
        .map(|k| cols.map(|c| t.value(k, c).map(|v| v == 1.0)))
        .collect()
}

/// Triangles the paper's row implies: its test 3 is the class-2 test (four triangles); rows
/// where it fails or does not matter (X: tests 1 and 2 both hold, always class 1) take three.
pub fn paper_row_triangles(row: &[Option<bool>; 4]) -> u8 {
    if row[2] == Some(true) {
        4
    } else {
        3
    }
}

/// Table 1 checked both ways: every observed outcome must fit exactly one paper row, carry our
/// case number for that row and its triangle count, and every paper row must be observed.
/// Returns the mismatches, in words (empty: the table holds).
pub fn table1_mismatches(observed: &[ObservedCase], rows: &[[Option<bool>; 4]]) -> Vec<String> {
    let fits =
        |p: &[Option<bool>; 4], o: &[bool; 4]| (0..4).all(|i| p[i].is_none_or(|v| v == o[i]));
    let mut out = vec![];
    for o in observed {
        let hits: Vec<usize> = (0..rows.len())
            .filter(|&i| fits(&rows[i], &o.tests))
            .collect();
        let [row] = hits[..] else {
            out.push(format!(
                "our case {} (tests {:?}) fits paper rows {:?}",
                o.case,
                o.tests.map(u8::from),
                hits.iter().map(|i| i + 1).collect::<Vec<_>>()
            ));
            continue;
        };
        let expected_case = OUR_CASE_OF_PAPER_ROW.get(row).copied().unwrap_or(0);
        if o.case != expected_case {
            out.push(format!(
                "tests {:?} are the paper's case {}, ours says case {} (expected {expected_case})",
                o.tests.map(u8::from),
                row + 1,
                o.case
            ));
        }
        let triangles = if o.class == 2 { 4 } else { 3 };
        if triangles != paper_row_triangles(&rows[row]) {
            out.push(format!(
                "paper case {}: {} triangles, ours {triangles}",
                row + 1,
                paper_row_triangles(&rows[row])
            ));
        }
    }
    for (i, p) in rows.iter().enumerate() {
        if !observed.iter().any(|o| fits(p, &o.tests)) {
            out.push(format!("paper case {} never observed", i + 1));
        }
    }
    out
}

/// GATOR's CPU analyses besides the runs, kept in [`Extra::own`].
#[derive(Debug, Clone, Default)]
pub struct GatorAnalyses {
    /// Table 1: the classifier's distinct outcomes on random tets (`None`: not run).
    pub truth_table: Option<Vec<ObservedCase>>,
    /// G1: the classifier against the projected hull on the paper's meshes and views.
    pub geometry: Vec<geometry::GeometryCheck>,
}

/// The analyses `x` holds (empty when GATOR's were not run).
pub fn analyses_of(x: &Extra) -> &GatorAnalyses {
    static NONE: GatorAnalyses = GatorAnalyses {
        truth_table: None,
        geometry: Vec::new(),
    };
    x.own::<GatorAnalyses>().unwrap_or(&NONE)
}

/// The viewport of the geometric check (the plan's; only its aspect matters).
const GEOMETRY_RESOLUTION: u32 = 512;

/// A claim's side from GATOR's CPU analyses (`classifier-twin`); `None`: not one of them.
pub fn claim_side(
    x: &Extra,
    metric: &spec::Metric,
    spec: &VariantSpec,
    dataset: Option<&str>,
) -> Option<Result<Side, String>> {
    if spec.algorithm != "classifier-twin" {
        return None;
    }
    let a = analyses_of(x);
    Some(match metric.analysis_name().unwrap_or_default() {
        "classifier_mismatches" => match &a.truth_table {
            None => Err("the classifier was not run (`tetbench reproduce gator` runs it)".into()),
            Some(observed) => {
                let mismatches = table1_mismatches(observed, &paper_rows());
                exact_side(
                    format!(
                        "gator-pt classifier (CPU twin), {} distinct outcomes, mismatches{}{}",
                        observed.len(),
                        if mismatches.is_empty() { "" } else { ": " },
                        mismatches.join("; ")
                    ),
                    "table1",
                    mismatches.len() as f64,
                )
            }
        },
        "classifier_geometry_mismatches" => {
            let Some(d) = dataset else {
                return Some(Err(format!("{metric} needs a data set")));
            };
            match a.geometry.iter().find(|g| g.dataset == d) {
                None => Err(format!(
                    "the classifier was not checked against geometry on {d} (`tetbench reproduce gator` does)"
                )),
                Some(g) => exact_side(
                    format!(
                        "gator-pt classifier (CPU twin) against the projected hull on {d}, {} viewpoints: {} projected tets compared ({} too close to degenerate to call, {} behind the eye), {} class and {} thick-vertex mismatches{}{}",
                        g.viewpoints,
                        g.compared,
                        g.ambiguous,
                        g.behind_eye,
                        g.class_mismatches,
                        g.thick_vertex_mismatches,
                        if g.examples.is_empty() { "" } else { ", e.g. " },
                        g.examples.join("; ")
                    ),
                    d,
                    g.mismatches() as f64,
                ),
            }
        }
        _ => Err(format!("classifier-twin has no metric {metric}")),
    })
}

/// The GATOR paper.
pub struct Gator;

impl PaperModule for Gator {
    fn paper(&self) -> &'static Paper {
        &PAPER
    }

    fn plan(&self) -> Vec<RunSpec> {
        vec![RunSpec {
            name: "gator".into(),
            algorithms: vec!["gator-pt".into()],
            datasets: DATASETS.map(|(_, d)| d.to_string()).to_vec(),
            viewpoints: "14".into(),
            resolution: 512,
            tf: None,
            settings: Some("variant=constant|linear".into()),
            quick_settings: None,
            full_viewport: false,
            full_views: false,
        }]
    }

    fn analyses(&self, s: &mut Session, m: &mut Measured) -> anyhow::Result<Extra> {
        let mut own = GatorAnalyses {
            truth_table: Some(observed_truth_table(200_000)),
            geometry: vec![],
        };
        s.log.push(
            "Table 1: 200,000 random projected tets through the classifier's CPU twin".into(),
        );
        let views = render_core::fixed_viewpoints();
        let mut x = Extra::default();
        let registry = datasets::registry::Registry::new(s.data_dir.clone());
        for (_, d) in DATASETS {
            match registry.resolve(&s.dataset(d), &datasets::LoadOptions::default()) {
                Ok(ds) => {
                    x.sizes.push((
                        d.to_string(),
                        ds.mesh.num_points() as u64,
                        ds.mesh.num_tets() as u64,
                    ));
                    x.dropped
                        .push((d.to_string(), ds.mesh.repair.degenerate_dropped as u64));
                    // G1: every tet from the paper's views (the 14; it averages "many"), at
                    // full size in every mode: no GPU, a few seconds.
                    let t0 = std::time::Instant::now();
                    let g = geometry::check_mesh(
                        d,
                        &ds.mesh,
                        &views,
                        GEOMETRY_RESOLUTION,
                        &gator_pt::classify_cpu,
                    );
                    s.log.push(format!(
                        "G1: the classifier against the projected hull on {d}, {} viewpoints, {} tets compared, {:.0} s",
                        views.len(),
                        g.compared,
                        t0.elapsed().as_secs_f64()
                    ));
                    own.geometry.push(g);
                }
                Err(e) => m
                    .errors
                    .push(format!("data set \"{d}\" could not be loaded: {e}")),
            }
        }
        x.own = Some(std::sync::Arc::new(own));
        Ok(x)
    }

    fn tables(&self, m: &Measured, x: &Extra) -> Report {
        tables(m, x)
    }
}

pub fn tables(m: &Measured, x: &Extra) -> Report {
    let mut report = Report::default();
    let load = |n: &str| transcription::table(n).expect("embedded paper CSV parses (tested)");

    // Table 1: per paper row, the outcomes of the case our classifier numbers as that row,
    // and the triangle counts.
    let t = load("gator_table1");
    let cols = ["test1_bool", "test2_bool", "test3_bool", "test4_bool"];
    let rows_p = paper_rows();
    let own = analyses_of(x);
    let observed = own.truth_table.as_deref().unwrap_or(&[]);
    let rows: Vec<CompRow> = t
        .keys()
        .iter()
        .enumerate()
        .map(|(i, k)| {
            let ours_case = OUR_CASE_OF_PAPER_ROW[i];
            let hits: Vec<&ObservedCase> =
                observed.iter().filter(|o| o.case == ours_case).collect();
            let why = if own.truth_table.is_none() {
                Some("not run (`tetbench reproduce gator` classifies random tets)".to_string())
            } else if hits.is_empty() {
                Some(format!("our case {ours_case} was never observed"))
            } else {
                None
            };
            let mut cells: Vec<Cell> = (0..4)
                .map(|c| {
                    // An X cell takes whatever ours gives; a cell where two observed outcomes
                    // of one case differ is shown as missing.
                    let values: Vec<bool> = hits.iter().map(|o| o.tests[c]).collect();
                    let ours = match (rows_p[i][c], values.first()) {
                        (_, None) => None,
                        (None, _) => None,
                        (Some(_), Some(&v)) if values.iter().all(|&w| w == v) => {
                            Some(v as u8 as f64)
                        }
                        _ => None,
                    };
                    Cell {
                        paper: t.value(k, cols[c]),
                        ours,
                        why_no_ours: why.clone().filter(|_| rows_p[i][c].is_some()),
                        uncertain: t.uncertain(k, cols[c]),
                    }
                })
                .collect();
            let tri: Option<f64> = hits.first().map(|o| if o.class == 2 { 4.0 } else { 3.0 });
            cells.push(Cell {
                paper: Some(paper_row_triangles(&rows_p[i]) as f64),
                ours: tri,
                why_no_ours: why,
                uncertain: None,
            });
            CompRow {
                label: format!("case {k} (our case {ours_case})"),
                standin: false,
                cells,
            }
        })
        .collect();
    let mismatches = table1_mismatches(observed, &rows_p);
    let mut notes = vec![format!(
        "{} distinct (case, class, outcome) triples observed; X (don't care) cells accept either value and are left out of the comparison. The paper prints no triangle counts: a row's count follows from its test 3, the class-2 test (four triangles; otherwise three).",
        observed.len()
    )];
    if own.truth_table.is_some() {
        notes.push(if mismatches.is_empty() {
            "Every observed outcome fits exactly one paper row, with that row's case number and triangle count, and every row is observed.".into()
        } else {
            format!("Mismatches: {}.", mismatches.join("; "))
        });
    }
    let mut metrics: Vec<Metric> = cols
        .iter()
        .map(|c| Metric::new(c.replace("_bool", ""), 0))
        .collect();
    metrics.push(Metric::new("triangles", 0));
    report.comparisons.push(Comparison {
        key: "table1".into(),
        title: "Table 1 — truth table of the 14 projection cases".into(),
        conditions: "No GPU involved: the paper's four tests (test 3: the intersection is nearer V0 than the middle vertex; test 4: cross1.z > 0) against the outcomes of our classifier's CPU twin (the same tests and table as the vertex shader) on 200,000 random projected tets; each paper row is compared with the case our classifier numbers as that row.".into(),
        metrics,
        rows,
        notes,
    });

    // Table 2: data set sizes.
    let t = load("gator_table2");
    let rows = DATASETS
        .iter()
        .map(|(paper, d)| {
            let size = x.sizes.iter().find(|(n, _, _)| n == d);
            let why = size.is_none().then(|| m.why("gator-pt", d));
            // The paper counts the five-tet split of every hexahedron; our loader then drops the
            // tets of zero volume (and counts them), so the split's count is loaded + dropped.
            let split_tets = size.map(|s| s.2 + x.dropped_by_loader(d));
            CompRow {
                label: format!("{paper} ({d})"),
                standin: is_standin(d),
                cells: vec![
                    Cell {
                        paper: t.value(paper, "vertices"),
                        ours: size.map(|s| s.1 as f64),
                        why_no_ours: why.clone(),
                        uncertain: t.uncertain(paper, "vertices"),
                    },
                    Cell {
                        paper: t.value(paper, "tetrahedra"),
                        ours: split_tets.map(|n| n as f64),
                        why_no_ours: why,
                        uncertain: t.uncertain(paper, "tetrahedra"),
                    },
                ],
            }
        })
        .collect();
    report.comparisons.push(Comparison {
        key: "table2".into(),
        title: "Table 2 — data sets".into(),
        conditions: "Vertices as tetbench loads the meshes; tets as the five-tet split of each PLOT3D hexahedron produces them, which is what the paper counts (our loader afterwards drops the tets of zero volume; the notes give how many).".into(),
        metrics: vec![Metric::new("vertices", 0), Metric::new("tets (split)", 0)],
        rows,
        notes: {
            let mut notes: Vec<String> = DATASETS
                .iter()
                .filter_map(|(paper, d)| {
                    let (_, _, loaded) = x.sizes.iter().find(|(n, _, _)| n == d)?;
                    let dropped = x.dropped_by_loader(d);
                    (dropped > 0).then(|| {
                        format!("{paper}: the split gives {} tets; {dropped} of them have zero volume (degenerate hexahedra of the grid) and the loader drops them, so {loaded} are rendered.", loaded + dropped)
                    })
                })
                .collect();
            notes.push("Delta Wing is a generated stand-in with the paper's tet count; its vertex count differs by construction.".into());
            notes
        },
    });

    // Table 3: GPU seconds per frame and tets/s, constant and linear cells.
    let t = load("gator_table3");
    let aggs = m.aggregates();
    let gpu = |d: &str, v: &str| {
        find(&aggs, "gator-pt", d, &[("variant", v)])
            .and_then(|a| a.gpu_ms.map(|s| (a.tets as f64, s.mean)))
    };
    let mut rows = vec![];
    for (paper, d) in DATASETS {
        let mut cells = vec![];
        for v in ["constant", "linear"] {
            let g = gpu(d, v);
            let why = g.is_none().then(|| m.why("gator-pt", d));
            let (tc, rc) = (format!("{v}_gpu_time_s"), format!("{v}_tets_per_sec"));
            cells.push(Cell {
                paper: t.value(paper, &tc),
                ours: g.map(|(_, ms)| ms / 1e3),
                why_no_ours: why.clone(),
                uncertain: t.uncertain(paper, &tc),
            });
            cells.push(Cell {
                paper: t.value(paper, &rc),
                ours: g.map(|(n, ms)| n / (ms * 1e-3)),
                why_no_ours: why,
                uncertain: t.uncertain(paper, &rc),
            });
        }
        rows.push(CompRow {
            label: format!("{paper} ({d})"),
            standin: is_standin(d),
            cells,
        });
    }
    report.comparisons.push(Comparison {
        key: "table3".into(),
        title: "Table 3 — GPU time per frame, constant vs linear cells".into(),
        conditions: "Paper: vertex program + glFinish, visibility sort excluded, averaged over many viewpoints, viewport not stated. Ours: GPU time from timestamp queries (CPU radix sort excluded), mean over the viewpoints, 512² unless the mode above says otherwise.".into(),
        metrics: vec![
            Metric::new("constant s/frame", 3),
            Metric::new("constant tets/s", 0),
            Metric::new("linear s/frame", 3),
            Metric::new("linear tets/s", 0),
        ],
        rows,
        notes: linear_data_note(m).into_iter().collect(),
    });
    report.claims = crate::papers::evidence::evaluate_claims(PAPER.id, m, x, &|metric, spec, d| {
        claim_side(x, metric, spec, d)
    });
    report
}

/// Claim G10 (§4: linear cells carry four times the data per cell): the device bytes per tet
/// of both variants as measured, and why they are equal here.
fn linear_data_note(m: &Measured) -> Option<String> {
    let bytes = |variant: &str| {
        m.rows
            .iter()
            .filter(|r| r.algorithm == "gator-pt" && r.ok() && r.settings.is("variant", variant))
            .find_map(|r| Some((r.dataset.clone(), r.bytes_per_tet?)))
    };
    let ((d, linear), (_, constant)) = (bytes("linear")?, bytes("constant")?);
    Some(format!(
        "Data per cell (claim G10): on {d} the linear variant holds {linear:.1} device bytes per tet, the constant one {constant:.1} (ratio {:.2}). Both read the same per-vertex scalars and look colour and extinction up in the shader from one transfer-function table; the paper's linear cells send colour and extinction for each of the four vertices over AGP instead of once per cell (§4), which is what it counts four times. Ours does not reproduce that cost.",
        linear / constant
    ))
}
