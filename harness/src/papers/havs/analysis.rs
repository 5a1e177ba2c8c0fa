//! Reproductions of Callahan, Ikits, Comba and Silva (2005), "Hardware-assisted visibility
//! sorting for unstructured volume rendering" (HAVS):
//!
//! * `tetbench analyze sort` — Table 1: sorting 1 M random floats with shellsort, heapsort,
//!   quicksort, the LSD radix sort of §5.1 and the standard library's sort (ms, keys/s);
//! * `tetbench analyze kbuffer --datasets spx,bluntfin,comb,post` — Table 2: the sorted faces
//!   rasterised at 512² into an exact A-buffer (a CPU model): total fragments, longest
//!   per-pixel list, largest k needed, pixels needing k > 2 and k > 6, maxima over the 14
//!   viewpoints; and Fig. 6's maps of where k > 2 and k > 6 are needed.
//!
//! Each writes what it measured; the comparison with the paper beside it is written by the one
//! writer of that table, [`super::table1`] and [`super::table2`], which `tetbench reproduce havs`
//! uses too (Tables 3–5 are `reproduce havs`, or `tetbench analyze havs RUN_DIR` for finished
//! runs). The paper's figures come from its transcribed tables (`reports/papers/havs_table*.csv`,
//! provenance in `reports/papers/havs.md`); `tetbench reproduce havs` runs the paper's own data
//! sets.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context as _;
use rayon::prelude::*;
use render_core::{fixed_viewpoints, Camera, Optics, Projection, TransferFunction};

use crate::papers::session::{Extra, Measured};
use crate::papers::table::markdown;

/// What the paper reports that we could verify: its abstract's range of rates.
pub const PAPER_RATE_RANGE_TETS_PER_SEC: (f64, f64) = (1.0e6, 6.0e6);

#[derive(Debug, clap::Args)]
pub struct SortArgs {
    /// Number of random float keys (the paper sorts 1 M).
    #[arg(long, default_value_t = 1_000_000)]
    pub keys: usize,
    /// Timed repetitions per sort (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Where `havs_table1.csv` and `havs_table1.md` go.
    #[arg(long, default_value = "tetbench-out")]
    pub out: PathBuf,
}

/// HAVS's CPU analyses besides the runs (Tables 1 and 2), kept in [`Extra::own`].
#[derive(Debug, Clone, Default)]
pub struct HavsAnalyses {
    /// Table 1: each sort's median, fastest and slowest run.
    pub sorts: Vec<SortRow>,
    /// Table 2 rows.
    pub kbuffer: Vec<KbufferRow>,
    /// How many viewpoints and what viewport the k analysis used.
    pub kbuffer_views: usize,
    pub kbuffer_resolution: u32,
}

/// The analyses `x` holds (empty when HAVS's were not run).
pub fn of(x: &Extra) -> &HavsAnalyses {
    static NONE: HavsAnalyses = HavsAnalyses {
        sorts: Vec::new(),
        kbuffer: Vec::new(),
        kbuffer_views: 0,
        kbuffer_resolution: 0,
    };
    x.own::<HavsAnalyses>().unwrap_or(&NONE)
}

/// One row of Table 1.
#[derive(Debug, Clone)]
pub struct SortRow {
    pub name: &'static str,
    /// Median over the repeats, and the fastest and slowest repeat.
    pub ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub repeats: u32,
    pub keys_per_sec: f64,
}

/// xorshift64*: deterministic keys without another dependency.
fn random_keys(n: usize, seed: u64) -> Vec<f32> {
    let mut x = seed.max(1);
    (0..n)
        .map(|_| {
            x ^= x >> 12;
            x ^= x << 25;
            x ^= x >> 27;
            let r = x.wrapping_mul(0x2545_f491_4f6c_dd1d);
            // Distances as HAVS sorts them: positive, spread over a few orders of magnitude.
            ((r >> 40) as f32 / (1u64 << 24) as f32) * 100.0 + 0.01
        })
        .collect()
}

/// Table 1: each sort orders the indices of `n` random keys, `repeats` times; median ms.
pub fn sort_times(n: usize, repeats: usize) -> anyhow::Result<Vec<SortRow>> {
    use render_core::sort::*;
    let keys = random_keys(n, 0x5eed);
    let mut expect: Vec<u32> = (0..n as u32).collect();
    expect.sort_by(|&a, &b| keys[a as usize].total_cmp(&keys[b as usize]));
    let sorted_keys: Vec<f32> = expect.iter().map(|&i| keys[i as usize]).collect();
    type SortFn = Box<dyn Fn(&[f32], &mut Vec<u32>)>;
    let radix = std::cell::RefCell::new(RadixScratch::default());
    let radix_serial = std::cell::RefCell::new(RadixScratch::default());
    let sorts: Vec<(&'static str, SortFn)> = vec![
        ("shellsort", Box::new(shellsort_indices)),
        ("heapsort", Box::new(heapsort_indices)),
        ("quicksort", Box::new(quicksort_indices)),
        (
            "radix sort (HAVS §5.1, one core)",
            Box::new(move |k, i| radix_sort_indices_serial(k, i, &mut radix_serial.borrow_mut())),
        ),
        (
            "radix sort (split over all cores; what the renderers use)",
            Box::new(move |k, i| radix_sort_indices(k, i, &mut radix.borrow_mut())),
        ),
        ("std sort_unstable_by", Box::new(std_sort_indices)),
    ];
    let mut rows = vec![];
    for (name, sort) in sorts {
        let mut times = vec![];
        let mut idx = Vec::with_capacity(n);
        for _ in 0..repeats.max(1) {
            let t = Instant::now();
            sort(&keys, &mut idx);
            times.push(t.elapsed().as_secs_f64() * 1e3);
            let got: Vec<f32> = idx.iter().map(|&i| keys[i as usize]).collect();
            anyhow::ensure!(got == sorted_keys, "{name} did not sort the keys");
        }
        times.sort_by(f64::total_cmp);
        let ms = times[times.len() / 2];
        rows.push(SortRow {
            name,
            ms,
            min_ms: times[0],
            max_ms: times[times.len() - 1],
            repeats: times.len() as u32,
            keys_per_sec: n as f64 / (ms * 1e-3),
        });
    }
    Ok(rows)
}

pub fn run_sort(args: SortArgs) -> anyhow::Result<()> {
    let rows = sort_times(args.keys, args.repeats)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let csv_path = args.out.join("havs_table1.csv");
    let mut w = csv::Writer::from_path(&csv_path)
        .with_context(|| format!("cannot create {}", csv_path.display()))?;
    w.write_record(["sort", "keys", "ms", "keys_per_sec"])?;
    for r in &rows {
        w.write_record([
            r.name.to_string(),
            args.keys.to_string(),
            r.ms.to_string(),
            r.keys_per_sec.to_string(),
        ])?;
    }
    w.flush()?;
    let mut md = format!(
        "HAVS Table 1: sorting {} random floats (indices by key), median of {} runs, {} ({} cores).\n\n\
         | sort | ms (ours) | M keys/s (ours) |\n|---|---:|---:|\n",
        args.keys,
        args.repeats,
        cpu_name(),
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
    );
    for r in &rows {
        writeln!(
            md,
            "| {} | {:.1} | {:.1} |",
            r.name,
            r.ms,
            r.keys_per_sec / 1e6
        )?;
    }
    md.push('\n');
    let extra = Extra::with_own(HavsAnalyses {
        sorts: rows,
        ..HavsAnalyses::default()
    });
    md.push_str(&markdown(&super::table1(&extra).judge(super::PAPER.id)));
    let md_path = args.out.join("havs_table1.md");
    std::fs::write(&md_path, &md).with_context(|| format!("cannot write {}", md_path.display()))?;
    println!("{md}");
    Ok(())
}

fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

#[derive(Debug, clap::Args)]
pub struct KbufferArgs {
    /// Data sets (registry names or files), comma-separated.
    /// (`onion:10k` is the sliver stress case: nested sliver shells.)
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "spx,bluntfin,comb,post,onion:10k"
    )]
    pub datasets: Vec<String>,
    /// Image size (square), 512 as in the paper.
    #[arg(long, default_value_t = 512)]
    pub resolution: u32,
    /// Where `havs_table2.csv`, `havs_table2.md` and the Fig. 6 maps go.
    #[arg(long, default_value = "tetbench-out")]
    pub out: PathBuf,
}

/// Table 2 for one data set: maxima over the viewpoints.
#[derive(Debug, Clone, Default)]
pub struct KbufferRow {
    pub dataset: String,
    pub tets: u64,
    pub faces: u64,
    pub fragments: u64,
    pub max_list: u32,
    /// k as the paper measures it (insertion depth + 1, §5.2).
    pub max_k: u32,
    pub pixels_k_gt2: u64,
    pub pixels_k_gt6: u64,
    /// The exact minimum k of our k-buffer twin (never above the paper's measure).
    pub exact_max_k: u32,
    pub exact_pixels_k_gt2: u64,
    pub exact_pixels_k_gt6: u64,
    pub worst_viewpoint: String,
}

pub fn run_kbuffer(args: KbufferArgs, data_dir: Option<PathBuf>) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let registry = datasets::registry::Registry::new(data_dir);
    let tf = TransferFunction::preset("low-opacity").context("low-opacity preset")?;
    let csv_path = args.out.join("havs_table2.csv");
    let mut w = csv::Writer::from_path(&csv_path)
        .with_context(|| format!("cannot create {}", csv_path.display()))?;
    w.write_record([
        "dataset",
        "viewpoint",
        "width",
        "height",
        "tets",
        "faces",
        "fragments",
        "max_list",
        "max_k",
        "pixels_k_gt2",
        "pixels_k_gt6",
        "exact_max_k",
        "exact_pixels_k_gt2",
        "exact_pixels_k_gt6",
        "covered_pixels",
    ])?;
    let mut table = vec![];
    for spec in &args.datasets {
        let dataset = registry
            .resolve(spec, &datasets::LoadOptions::default())
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("loading data set {spec:?}"))?;
        let t0 = Instant::now();
        let (row, stats, worst) = kbuffer_row(
            spec,
            &dataset.mesh,
            &tf,
            args.resolution,
            &fixed_viewpoints(),
        );
        for (vp, s) in &stats {
            w.write_record([
                spec.clone(),
                vp.clone(),
                s.width.to_string(),
                s.height.to_string(),
                row.tets.to_string(),
                row.faces.to_string(),
                s.fragments.to_string(),
                s.max_list.to_string(),
                s.max_k.to_string(),
                s.pixels_k_gt2.to_string(),
                s.pixels_k_gt6.to_string(),
                s.exact_max_k.to_string(),
                s.exact_pixels_k_gt2.to_string(),
                s.exact_pixels_k_gt6.to_string(),
                s.covered_pixels.to_string(),
            ])?;
        }
        w.flush()?;
        if let Some(s) = worst {
            let path = args.out.join(format!(
                "havs_fig6_{}.png",
                crate::results::names::slug(spec)
            ));
            s.k_map_image()
                .save(&path)
                .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
        }
        eprintln!(
            "{spec}: 14 viewpoints in {:.1} s",
            t0.elapsed().as_secs_f64()
        );
        table.push(row);
    }
    let md = table2_markdown(&table, args.resolution, fixed_viewpoints().len());
    let md_path = args.out.join("havs_table2.md");
    std::fs::write(&md_path, &md).with_context(|| format!("cannot write {}", md_path.display()))?;
    println!("{md}");
    Ok(())
}

/// Table 2 for one mesh: the k-buffer statistics of every viewpoint (with its name), their
/// maxima as one row, and the statistics of the worst viewpoint (for its Fig. 6 map).
pub fn kbuffer_row(
    label: &str,
    mesh: &datasets::TetMesh,
    tf: &TransferFunction,
    resolution: u32,
    viewpoints: &[render_core::Viewpoint],
) -> (
    KbufferRow,
    Vec<(String, havs::abuffer::KStats)>,
    Option<havs::abuffer::KStats>,
) {
    let optics = Optics::for_mesh(tf.clone(), mesh);
    let geom = havs::tagged_geometry(mesh, &optics);
    let mut row = KbufferRow {
        dataset: label.to_string(),
        tets: mesh.num_tets() as u64,
        faces: geom.faces.len() as u64,
        ..Default::default()
    };
    let mut worst: Option<(u64, havs::abuffer::KStats)> = None;
    let mut all = vec![];
    for vp in viewpoints {
        let camera = Camera::fit(
            &mesh.bounds(),
            vp,
            Projection::default(),
            resolution,
            resolution,
        );
        let s = havs::abuffer::kbuffer_stats(&geom, &camera);
        row.fragments = row.fragments.max(s.fragments);
        row.max_list = row.max_list.max(s.max_list);
        row.max_k = row.max_k.max(s.max_k);
        row.pixels_k_gt2 = row.pixels_k_gt2.max(s.pixels_k_gt2);
        row.pixels_k_gt6 = row.pixels_k_gt6.max(s.pixels_k_gt6);
        row.exact_max_k = row.exact_max_k.max(s.exact_max_k);
        row.exact_pixels_k_gt2 = row.exact_pixels_k_gt2.max(s.exact_pixels_k_gt2);
        row.exact_pixels_k_gt6 = row.exact_pixels_k_gt6.max(s.exact_pixels_k_gt6);
        let score = s.pixels_k_gt2 * 1_000_000 + s.pixels_k_gt6;
        if worst.as_ref().is_none_or(|(b, _)| score > *b) {
            row.worst_viewpoint = vp.name.clone();
            worst = Some((score, s.clone()));
        }
        all.push((vp.name.clone(), s));
    }
    (row, all, worst.map(|(_, s)| s))
}

/// What `analyze kbuffer` measured (one row per data set, maxima over the viewpoints), then,
/// where any of its data sets is one of the paper's, Table 2 as [`super::table2`] writes it.
pub fn table2_markdown(rows: &[KbufferRow], resolution: u32, viewpoints: usize) -> String {
    let mut md = format!(
        "HAVS Table 2: k-buffer analysis, faces sorted by centroid distance and rasterised at \
         {resolution}² into an exact A-buffer; maxima over the {viewpoints} viewpoints. \
         \"k\": as the paper measures it (§5.2), the deepest insertion of a fragment into the \
         pixel's ordered A-buffer plus one for compositing. \"exact k\": the smallest number \
         of entries with which our k-buffer completes every pixel's sort exactly (never more).\n\n\
         | data set | tets | faces | fragments | max A-buffer list | max k | pixels k > 2 | pixels k > 6 | max exact k | pixels exact k > 2 | pixels exact k > 6 | worst view (Fig. 6 map) |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n"
    );
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.dataset,
            r.tets,
            r.faces,
            r.fragments,
            r.max_list,
            r.max_k,
            r.pixels_k_gt2,
            r.pixels_k_gt6,
            r.exact_max_k,
            r.exact_pixels_k_gt2,
            r.exact_pixels_k_gt6,
            r.worst_viewpoint
        );
    }
    md.push('\n');
    let extra = Extra::with_own(HavsAnalyses {
        kbuffer: rows.to_vec(),
        kbuffer_views: viewpoints,
        kbuffer_resolution: resolution,
        ..HavsAnalyses::default()
    });
    let table = super::table2(&Measured::default(), &extra);
    let papers_own: Vec<&str> = table.rows.iter().map(|r| r.label.as_str()).collect();
    if rows
        .iter()
        .any(|r| papers_own.contains(&r.dataset.as_str()))
    {
        md.push_str(&markdown(&table.judge(super::PAPER.id)));
    } else {
        let _ = writeln!(
            md,
            "None of these is one of the paper's data sets ({}): `tetbench reproduce havs` \
             measures those and compares them with the paper.",
            papers_own.join(", ")
        );
    }
    md
}

/// The k-buffer statistics of several viewpoints in parallel (used by tests of the analysis).
pub fn kbuffer_stats_views(
    geom: &havs::abuffer::Geometry,
    cameras: &[Camera],
) -> Vec<havs::abuffer::KStats> {
    cameras
        .par_iter()
        .map(|c| havs::abuffer::kbuffer_stats(geom, c))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table1_sorts_correctly_and_reports_rates() {
        // Above the parallel threshold, so both radix sorts take their own path.
        let rows = sort_times(100_000, 1).unwrap();
        assert_eq!(rows.len(), 6);
        assert!(rows.iter().all(|r| r.keys_per_sec > 0.0 && r.ms >= 0.0));
    }

    #[test]
    fn kbuffer_stats_of_a_grid_count_every_fragment() {
        // A 3×3×3-cell grid seen along an axis: every ray through the interior meets the
        // same number of faces, and the table's bookkeeping adds up.
        let dims = [4usize, 4, 4];
        let mut points = vec![];
        for k in 0..4 {
            for j in 0..4 {
                for i in 0..4 {
                    points.push([i as f32, j as f32, k as f32]);
                }
            }
        }
        let n = points.len();
        let mesh = datasets::TetMesh::new(
            "g",
            points,
            vec![0.0; n],
            "s",
            datasets::volume::structured_tets(dims),
        )
        .unwrap();
        let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
        let geom = havs::tagged_geometry(&mesh, &optics);
        let cams: Vec<Camera> = fixed_viewpoints()
            .iter()
            .take(2)
            .map(|vp| Camera::fit(&mesh.bounds(), vp, Projection::Orthographic, 48, 48))
            .collect();
        for s in kbuffer_stats_views(&geom, &cams) {
            assert!(s.fragments > 0 && s.covered_pixels > 0);
            assert!(s.max_k >= 1 && s.max_list >= 2);
            assert!(s.pixels_k_gt6 <= s.pixels_k_gt2 && s.pixels_k_gt2 <= s.covered_pixels);
            assert_eq!(s.k_map.len(), 48 * 48);
        }
    }
}
