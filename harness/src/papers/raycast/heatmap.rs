//! The paper's Fig. 5 drawn from our runs: per data set of Table 4, the passes each of the
//! 6×6 tiles ran on the viewpoint with the most passes, read as numbers from the file each row
//! of the tiled passes run names (`Row::tile_counts`), drawn as a heat map
//! (`plot::tile_map`) beside what the paper's figure shows and how ours differs.

use crate::papers::session::{is_standin, Figure, Measured, Panel};
use crate::results::Row;
use render_core::TileCounts;

use super::passes::TILED_RUN;
use super::DATASETS;

/// The tiled passes run's rows of `dataset`, with the run folder each came from.
fn tiled_rows<'a>(m: &'a Measured, dataset: &str) -> Vec<(&'a Row, Option<&'a std::path::Path>)> {
    let want = crate::algorithms::parse_settings("raycast", TILED_RUN).expect("our own settings");
    m.rows
        .iter()
        .enumerate()
        .filter(|(_, r)| r.algorithm == "raycast" && r.dataset == dataset && r.ok())
        .filter(|(_, r)| r.settings.includes(&want))
        .map(|(i, r)| (r, m.row_dirs.get(i).and_then(|d| d.as_deref())))
        .collect()
}

/// The per-tile counts of `row` read from its run folder, checked against the row's own
/// `passes_max`: the file is the frame's, not another's.
fn counts_of(row: &Row, dir: Option<&std::path::Path>) -> Result<TileCounts, String> {
    let vp = &row.viewpoint;
    if row.tile_counts.is_empty() {
        return Err(format!(
            "the row of viewpoint {vp} names no per-tile counts"
        ));
    }
    let dir = dir.ok_or_else(|| format!("the row of viewpoint {vp} has no run folder"))?;
    let c =
        crate::results::tile_counts::read(dir, &row.tile_counts).map_err(|e| format!("{e:#}"))?;
    let busiest = c.busiest().map_or(0, |b| b.count) as f64;
    match row.counter("passes_max") {
        Some(max) if c.name == "passes" && max == busiest => Ok(c),
        max => Err(format!(
            "{}: its busiest tile counts {busiest} {}, the row of viewpoint {vp} has passes_max {}",
            row.tile_counts,
            c.name,
            max.map_or("none".into(), |m| format!("{m}"))
        )),
    }
}

/// The panel of one data set: the viewpoint with the most passes (the first of equals).
fn panel(m: &Measured, paper: &str, dataset: &str) -> Panel {
    let rows = tiled_rows(m, dataset);
    let busiest = rows.iter().enumerate().max_by(|(i, a), (j, b)| {
        let p = |r: &Row| r.counter("passes_max").unwrap_or(-1.0);
        p(a.0).total_cmp(&p(b.0)).then(j.cmp(i))
    });
    let standin = if is_standin(dataset) {
        ", stand-in"
    } else {
        ""
    };
    let label = format!("{paper} ({dataset}{standin})");
    let Some((_, (row, dir))) = busiest else {
        return Panel {
            label: dataset.into(),
            title: label,
            caption: String::new(),
            grid: Err(m.why("raycast", dataset)),
        };
    };
    let grid = counts_of(row, *dir);
    let caption = match &grid {
        Ok(c) => {
            let b = c.busiest().expect("a checked grid has tiles");
            let empty = c.counts.iter().filter(|&&n| n == 0).count();
            let mean = c.counts.iter().map(|&n| n as f64).sum::<f64>() / c.counts.len() as f64;
            format!(
                "{label}, viewpoint {vp}: the most passes of the {n} viewpoints measured. Busiest tile: row {r}, column {col} (from the top left), {count} passes{ties}; {empty} of {tiles} tiles ran none (no ray entered them); {mean:.1} passes per tile on average.",
                vp = row.viewpoint,
                n = rows.len(),
                r = b.row + 1,
                col = b.column + 1,
                count = b.count,
                ties = crate::plot::tile_map::tie_note(c),
                tiles = c.counts.len(),
            )
        }
        Err(_) => String::new(),
    };
    Panel {
        label: dataset.into(),
        title: format!("{label}, viewpoint {}: passes per tile", row.viewpoint),
        caption,
        grid,
    }
}

/// Fig. 5: the heat maps and what they stand beside.
pub(super) fn fig5(m: &Measured) -> Figure {
    let standins: Vec<&str> = DATASETS
        .iter()
        .filter(|(_, d)| is_standin(d))
        .map(|(p, _)| *p)
        .collect();
    let standins = match standins.as_slice() {
        [] => String::new(),
        [one] => format!("; {one} is a generated stand-in for the paper's mesh"),
        many => format!(
            "; {} are generated stand-ins for the paper's meshes",
            many.join(", ")
        ),
    };
    let text = format!(
        "**What the paper's figure shows.** Fig. 5 (described in §4) pictures the tiled ray caster at work on SPX split into 36 tiles: its images mark every tile with the number of ray-casting passes that tile needed before all of its rays had left the mesh. It prints no number elsewhere, so there is nothing to compare tile by tile; what we can show is the same quantity from our own frames.\n\n**How ours differs.** We draw each data set of Table 4, not SPX alone{standins}. The paper does not give its camera positions; of our 14 fixed viewpoints we draw, per data set, the one whose busiest tile ran the most passes. Our passes are counted the way the paper spends them (§2.3, §3.2): per peeling layer, rounds of k passes with a count of the tile's active rays after each round, here k = 8 (the paper does not state its k), up to 32 layers, 512², settings `{TILED_RUN}`. A pass count does not depend on the GPU. The numbers drawn are the renderer's own per-tile counts, written beside each frame's pass map; a grey tile is one no ray entered."
    );
    Figure {
        key: "fig5".into(),
        title: "Fig. 5 — ray-casting passes per tile, 6×6 tiles".into(),
        text,
        panels: DATASETS.iter().map(|(p, d)| panel(m, p, d)).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use render_core::{fixed_viewpoints, Camera, Optics, Projection, Renderer, TransferFunction};
    use std::sync::Arc;

    /// Renders `mesh` from each of `views` with the tiled run's settings at `size`², writes
    /// each frame's counts as the run does, and returns the rows (on spx1) and per view the
    /// GPU's counts and the CPU twin's.
    fn run(dir: &std::path::Path, views: &[usize], size: u32) -> (Vec<Row>, Vec<[Vec<u32>; 2]>) {
        let gpu = render_core::Gpu::new().expect("an adapter (lavapipe)");
        let mesh = Arc::new(datasets::generate::from_spec("shell:2k", 1).unwrap());
        let optics = Optics::for_mesh(TransferFunction::preset("low-opacity").unwrap(), &mesh);
        let settings = crate::algorithms::parse_settings("raycast", TILED_RUN).unwrap();
        let s = raycast::RaycastSettings::from_settings(&settings).unwrap();
        let mut r = raycast::Raycast::new(s);
        r.prepare(&gpu, &mesh, &optics).unwrap();
        let layout = r.layout(&mesh, &optics).unwrap();
        let (mut rows, mut counts) = (vec![], vec![]);
        for &v in views {
            let vp = &fixed_viewpoints()[v];
            let camera = Camera::fit(&mesh.bounds(), vp, Projection::default(), size, size);
            let stats = r.render(&gpu, &camera).unwrap();
            let d = r.pass_data(&gpu).unwrap();
            let twin = raycast::twin::tile_passes(&layout, &d, s.tiles, s.k);
            let numbers = r.tile_counts(&gpu).unwrap().unwrap();
            let rel = format!("images/v{v}");
            std::fs::create_dir_all(dir.join(&rel)).unwrap();
            let path =
                crate::results::tile_counts::write(&dir.join(&rel), &rel, "raycast", &numbers)
                    .unwrap();
            let max = stats
                .counters
                .iter()
                .find(|(k, _)| k == "passes_max")
                .unwrap()
                .1;
            rows.push(Row {
                algorithm: "raycast".into(),
                settings: settings.clone(),
                dataset: "spx1".into(),
                viewpoint: format!("v{v}"),
                frames: 1,
                counters: format!("passes_max={max}").as_str().into(),
                tile_counts: path,
                ..Default::default()
            });
            counts.push([d.tile_passes, twin]);
        }
        (rows, counts)
    }

    #[test]
    fn fig5_draws_the_gpus_and_the_twins_counts_and_follows_one_changed_count() {
        let dir = tempfile::tempdir().unwrap();
        // The first diagonal (corner tiles empty) and an axis.
        let (rows, counts) = run(dir.path(), &[6, 0], 48);
        let mut m = Measured::default();
        m.push_run(dir.path(), rows.clone());
        let fig = fig5(&m);
        assert_eq!(fig.panels.len(), DATASETS.len());
        let spx1 = &fig.panels[0];
        let grid = spx1.grid.as_ref().unwrap();
        // The view drawn is the one with the most passes, its numbers the GPU's and the twin's.
        let most = (0..2)
            .max_by_key(|&i| (counts[i][0].iter().max().copied(), std::cmp::Reverse(i)))
            .unwrap();
        assert!(spx1.title.contains(&rows[most].viewpoint), "{}", spx1.title);
        assert_eq!(grid.counts, counts[most][0]);
        assert_eq!(grid.counts, counts[most][1]);
        assert_eq!(grid.tiles, [6, 6]);
        assert_ne!(counts[0][0], counts[1][0], "two views, two grids");
        let b = grid.busiest().unwrap();
        assert!(
            spx1.caption.contains(&format!(
                "row {}, column {} (from the top left), {} passes",
                b.row + 1,
                b.column + 1,
                b.count
            )),
            "{}",
            spx1.caption
        );
        // The data sets without rows say why.
        assert!(fig.panels[1].grid.is_err() && fig.panels[2].grid.is_err());
        // One count of a tile below the busiest changed in the file: the drawn grid follows.
        let file = dir.path().join(&rows[most].tile_counts);
        let mut changed: TileCounts =
            serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        let i = changed.counts.iter().position(|&n| n < b.count).unwrap();
        changed.counts[i] += 1;
        std::fs::write(&file, serde_json::to_string(&changed).unwrap()).unwrap();
        let after = fig5(&m);
        let grid2 = after.panels[0].grid.as_ref().unwrap();
        assert_eq!(grid2.counts, changed.counts);
        assert_ne!(grid2.counts, counts[most][0]);
        let drawn = crate::plot::tile_map::texts(&crate::plot::tile_map::svg("t", grid2).unwrap());
        assert!(drawn.contains(&changed.counts[i].to_string()));
        // A count above the row's own passes_max: the file is not that frame's, and the panel
        // says so, naming the file.
        changed.counts[i] = b.count + 8;
        std::fs::write(&file, serde_json::to_string(&changed).unwrap()).unwrap();
        let e = fig5(&m).panels[0].grid.clone().unwrap_err();
        assert!(
            e.contains(&rows[most].tile_counts) && e.contains("passes_max"),
            "{e}"
        );
    }
}
