//! The report of a run, written into its output directory from `results.json` alone (so
//! `tetbench report OUT` can redo it): the charts of [`crate::plot`] (speed vs error first) in
//! `charts/`, and an `index.html` with the machine, the charts and their key, the summary and
//! full tables (peers and suspect rows marked), and every image beside its reference and error
//! heatmap.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;

use crate::algorithms::is_peer;
use crate::metrics::{HEATMAP_MAX_ERROR, ONE_STEP, PSNR_CAP_DB};
use crate::results::{ResultsFile, Row};

pub use crate::names::series_label;
pub use crate::stats::{spread, Spread};

/// One algorithm × settings × data set, over its viewpoints (the papers average over the 14
/// fixed viewpoints, HAVS §6).
#[derive(Debug, Clone, PartialEq)]
pub struct Aggregate {
    pub algorithm: String,
    pub settings: String,
    pub dataset: String,
    pub tets: u64,
    pub rows: usize,
    pub failed: usize,
    /// Rows flagged by [`crate::suspect`].
    pub suspect: usize,
    pub total_ms: Option<Spread>,
    pub cpu_ms: Option<Spread>,
    pub gpu_ms: Option<Spread>,
    pub fps: Option<Spread>,
    pub tets_per_sec: Option<Spread>,
    pub psnr_db: Option<Spread>,
    pub rmse: Option<Spread>,
    pub bad_pixel_share: Option<Spread>,
    pub bytes_per_tet: Option<f64>,
    pub gpu_bytes: Option<u64>,
}

impl Aggregate {
    /// `algorithm settings` as one label.
    pub fn series(&self) -> String {
        series_label(&self.algorithm, &self.settings)
    }
}

/// Groups rows by (algorithm, settings, data set), in order of first appearance.
pub fn aggregate(rows: &[Row]) -> Vec<Aggregate> {
    let mut keys: Vec<(String, String, String)> = vec![];
    for r in rows {
        let k = (r.algorithm.clone(), r.settings.clone(), r.dataset.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(algorithm, settings, dataset)| {
            let g: Vec<&Row> = rows
                .iter()
                .filter(|r| {
                    r.algorithm == algorithm && r.settings == settings && r.dataset == dataset
                })
                .collect();
            Aggregate {
                tets: g[0].tets,
                rows: g.len(),
                failed: g.iter().filter(|r| !r.ok()).count(),
                suspect: g.iter().filter(|r| !r.suspect.is_empty()).count(),
                total_ms: spread(g.iter().filter_map(|r| r.total_ms)),
                cpu_ms: spread(g.iter().filter_map(|r| r.cpu_ms)),
                gpu_ms: spread(g.iter().filter_map(|r| r.gpu_ms)),
                fps: spread(g.iter().filter_map(|r| r.fps)),
                tets_per_sec: spread(g.iter().filter_map(|r| r.tets_per_sec)),
                psnr_db: spread(g.iter().filter_map(|r| r.psnr_db)),
                rmse: spread(g.iter().filter_map(|r| r.rmse)),
                bad_pixel_share: spread(g.iter().filter_map(|r| r.bad_pixel_share)),
                bytes_per_tet: g.iter().find_map(|r| r.bytes_per_tet),
                gpu_bytes: g.iter().filter_map(|r| r.gpu_bytes).max(),
                algorithm,
                settings,
                dataset,
            }
        })
        .collect()
}

/// Writes the charts (see [`crate::plot`]) and `index.html` into `out` for the results in
/// `file`.
pub fn write(out: &Path, file: &ResultsFile) -> anyhow::Result<()> {
    let mut inputs = crate::plot::data::Inputs::default();
    inputs.add(file, crate::plot::raw_results(out).as_ref());
    let charts = crate::plot::write_charts(&out.join("charts"), &inputs, crate::plot::Kind::All)?;
    let aggs = aggregate(&file.rows);
    let html = html(file, &aggs, &crate::plot::html_section(&charts, "charts"));
    let path = out.join("index.html");
    std::fs::write(&path, html).with_context(|| format!("cannot write {}", path.display()))
}

/// Re-renders the report of an earlier run (`tetbench report OUT`).
pub fn rewrite(out: &Path) -> anyhow::Result<()> {
    let file = ResultsFile::read(out)?;
    write(out, &file)
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// ` class="…"` for a table row: failed, suspect (issue 15's rule) and peer rows are marked.
fn row_class(failed: bool, suspect: bool, algorithm: &str) -> String {
    let mut c = vec![];
    if failed {
        c.push("failed");
    }
    if suspect {
        c.push("suspect");
    }
    if crate::plot::style::is_peer(algorithm) {
        c.push("peer");
    }
    if c.is_empty() {
        String::new()
    } else {
        format!(" class=\"{}\"", c.join(" "))
    }
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map(|v| format!("{v:.digits$}"))
        .unwrap_or_else(|| "–".into())
}

fn mb(v: Option<u64>) -> String {
    v.map(|b| format!("{:.2}", b as f64 / (1 << 20) as f64))
        .unwrap_or_else(|| "–".into())
}

fn html(file: &ResultsFile, aggs: &[Aggregate], charts: &str) -> String {
    let m = &file.machine;
    let r = &file.run;
    let mut h = String::new();
    let _ = write!(
        h,
        r#"<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>tetbench report</title>
<style>
body {{ font-family: "DejaVu Sans", sans-serif; margin: 1.5em; color: #222; }}
@font-face {{ font-family: "DejaVu Sans"; src: url("charts/DejaVuSans.ttf") format("truetype"); }}
table {{ border-collapse: collapse; font-size: 13px; margin: 0.5em 0 1.5em; }}
th, td {{ border: 1px solid #ccc; padding: 2px 6px; text-align: right; }}
th {{ background: #eee; }} td.l, th.l {{ text-align: left; }}
tr.failed td {{ background: #fdd; }}
tr.suspect td {{ background: #ffe4b5; }} tr.suspect td:first-child::after {{ content: " ⚠ suspect"; color: #b00; }}
.suspect figure {{ border: 2px solid #e69500; padding: 3px; }}
tr.peer td:first-child::after {{ content: " (peer)"; color: #666; font-style: italic; }}
figure.chart {{ margin: 0 0 14px; font-size: 13px; text-align: left; }}
figure.chart img {{ width: auto; height: auto; max-width: 100%; background: #fff; object-fit: initial; image-rendering: auto; }}
table.key td {{ text-align: left; }}
.swatch {{ display: inline-block; width: 12px; height: 12px; border: 2px solid transparent; vertical-align: middle; }}
dl {{ display: grid; grid-template-columns: max-content auto; gap: 2px 12px; font-size: 14px; }}
dt {{ font-weight: bold; }} dd {{ margin: 0; }}
.charts img {{ max-width: 100%; border: 1px solid #ddd; margin-bottom: 8px; }}
.view {{ margin: 0 0 1.2em; }}
.strip {{ display: flex; flex-wrap: wrap; gap: 10px; }}
figure {{ margin: 0; font-size: 11px; text-align: center; }}
figure img {{ width: 160px; height: 160px; object-fit: contain; background: #000; display: block; image-rendering: pixelated; }}
.pair {{ display: flex; gap: 2px; }}
</style></head><body>
<h1>tetbench report</h1>
"#
    );
    let mem = m
        .memory_bytes
        .map(|b| format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64))
        .unwrap_or_else(|| "unknown".into());
    let adapter = m
        .adapter
        .as_ref()
        .map(|a| {
            format!(
                "{} ({}, {}, driver {} {})",
                a.name, a.backend, a.device_type, a.driver, a.driver_info
            )
        })
        .unwrap_or_else(|| "unknown".into());
    let commit = match (&m.git_commit, m.git_dirty) {
        (Some(c), Some(true)) => format!("{c} (with uncommitted changes)"),
        (Some(c), _) => c.clone(),
        _ => "unknown".into(),
    };
    let _ = writeln!(
        h,
        "<h2>Machine and run</h2><dl>\
         <dt>GPU adapter</dt><dd>{}</dd><dt>CPU</dt><dd>{} ({} logical cores)</dd><dt>memory</dt><dd>{}</dd>\
         <dt>OS</dt><dd>{} {}</dd><dt>tetbench</dt><dd>{} at commit {}</dd><dt>started</dt><dd>{}</dd>\
         <dt>finished</dt><dd>{}</dd><dt>command</dt><dd><code>{}</code></dd>\
         <dt>viewpoints</dt><dd>{}</dd><dt>viewport</dt><dd>{}×{}, {}</dd><dt>frames</dt><dd>{} timed after {} warm-up</dd>\
         <dt>transfer function</dt><dd>{}</dd></dl>",
        esc(&adapter),
        esc(&m.cpu_model),
        m.cpu_cores,
        mem,
        esc(&m.os),
        esc(m.kernel.as_deref().unwrap_or("")),
        esc(&m.tetbench_version),
        esc(&commit),
        esc(&m.date_utc),
        esc(file.finished_utc.as_deref().unwrap_or("not finished (interrupted?)")),
        esc(&r.command_line.join(" ")),
        esc(&r.viewpoints),
        r.width,
        r.height,
        esc(&r.projection),
        r.frames,
        r.warmup,
        esc(&r.transfer_function),
    );
    if !file.errors.is_empty() {
        h.push_str("<h2>Errors</h2><ul>");
        for e in &file.errors {
            let _ = write!(h, "<li>{}</li>", esc(e));
        }
        h.push_str("</ul>\n");
    }

    h.push_str(charts);
    suspect_section(&mut h, file);

    h.push_str("<h2>Summary</h2><p>Mean over viewpoints (min–max in brackets).");
    if file.rows.iter().any(|r| is_peer(&r.algorithm)) {
        h.push_str(
            " <em>peer</em>: another package's renderer (VTK, through its Python package, or \
             an external renderer given with <code>--external</code>, \
             docs/external-renderers.md) measured in the same run; VTK reports no GPU memory.",
        );
    }
    h.push_str(
        "</p><table><tr>\
         <th class=l>algorithm</th><th class=l>settings</th><th class=l>data set</th><th>tets</th><th>rows</th>\
         <th>total ms</th><th>CPU ms</th><th>GPU ms</th><th>fps</th><th>M tets/s</th><th>PSNR dB</th>\
         <th>bad pixels %</th><th>bytes/tet</th><th>GPU MiB</th></tr>\n",
    );
    let suspect = crate::plot::data::suspect_flags(&file.rows);
    for a in aggs {
        let sp = |s: Option<Spread>, k: f64, d: usize| {
            s.map(|s| {
                format!(
                    "{:.d$} <small>({:.d$}–{:.d$})</small>",
                    s.mean * k,
                    s.min * k,
                    s.max * k
                )
            })
            .unwrap_or_else(|| "–".into())
        };
        let _ = writeln!(
            h,
            "<tr{}><td class=l>{}</td><td class=l>{}</td><td class=l>{}</td><td>{}</td><td>{}{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            row_class(
                a.failed > 0,
                file.rows.iter().zip(&suspect).any(|(r, s)| {
                    *s && r.algorithm == a.algorithm
                        && r.settings == a.settings
                        && r.dataset == a.dataset
                }),
                &a.algorithm
            ),
            algorithm_cell(&a.algorithm),
            esc(&a.settings),
            esc(&a.dataset),
            a.tets,
            a.rows,
            if a.failed > 0 { format!(" ({} failed)", a.failed) } else { String::new() },
            sp(a.total_ms, 1.0, 2),
            sp(a.cpu_ms, 1.0, 2),
            sp(a.gpu_ms, 1.0, 2),
            sp(a.fps, 1.0, 1),
            sp(a.tets_per_sec, 1e-6, 3),
            sp(a.psnr_db, 1.0, 2),
            sp(a.bad_pixel_share, 100.0, 2),
            opt(a.bytes_per_tet.filter(|_| !is_peer(&a.algorithm)), 1),
            mb(a.gpu_bytes.filter(|_| !is_peer(&a.algorithm))),
        );
    }
    h.push_str("</table>\n");

    let _ = writeln!(
        h,
        "<h2>Images</h2><p>Each rendering beside its error heatmap (largest channel error per pixel: black ≤ 1/255, \
         then a log scale up to ≥ {HEATMAP_MAX_ERROR} in pale yellow); the exact reference first. PSNR over \
         premultiplied linear RGB, capped at {PSNR_CAP_DB} dB; “bad” pixels are covered pixels off by more than \
         1/255 ({ONE_STEP:.4}) in any channel.</p>"
    );
    let mut views: Vec<(String, String)> = vec![];
    for row in &file.rows {
        let k = (row.dataset.clone(), row.viewpoint.clone());
        if !views.contains(&k) {
            views.push(k);
        }
    }
    for (dataset, viewpoint) in &views {
        let rows: Vec<&Row> = file
            .rows
            .iter()
            .filter(|r| &r.dataset == dataset && &r.viewpoint == viewpoint)
            .collect();
        let _ = write!(
            h,
            "<div class=view><h3>{} — {}</h3><div class=strip>",
            esc(dataset),
            esc(viewpoint)
        );
        if let Some(reference) = rows
            .iter()
            .find(|r| !r.reference_image.is_empty())
            .map(|r| &r.reference_image)
        {
            let _ = write!(
                h,
                "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"reference\" loading=lazy></a><figcaption>exact reference</figcaption></figure>",
                esc(reference)
            );
        }
        for row in rows {
            if row.image.is_empty() {
                continue;
            }
            let _ = write!(
                h,
                "<figure><div class=pair><a href=\"{0}\"><img src=\"{0}\" alt=\"image\" loading=lazy></a>",
                esc(&row.image)
            );
            if !row.heatmap.is_empty() {
                let _ = write!(
                    h,
                    "<a href=\"{0}\"><img src=\"{0}\" alt=\"error heatmap\" loading=lazy></a>",
                    esc(&row.heatmap)
                );
            }
            let _ = write!(
                h,
                "</div><figcaption>{}<br>PSNR {} dB · {} M tets/s</figcaption></figure>",
                esc(&series_label(&row.algorithm, &row.settings)),
                opt(row.psnr_db, 2),
                opt(row.tets_per_sec.map(|v| v * 1e-6), 3)
            );
        }
        h.push_str("</div></div>\n");
    }

    h.push_str(
        "<h2>All rows</h2><table><tr><th class=l>algorithm</th><th class=l>settings</th><th class=l>data set</th>\
         <th class=l>viewpoint</th><th>total ms</th><th>CPU ms</th><th>GPU ms</th><th>fps</th><th>M tets/s</th>\
         <th>GPU MiB</th><th>bytes/tet</th><th>RMSE</th><th>PSNR dB</th><th>max err</th><th>bad %</th>\
         <th class=l>stages (ms)</th><th class=l>error</th></tr>\n",
    );
    for (row, suspect) in file.rows.iter().zip(&suspect) {
        let _ = writeln!(
            h,
            "<tr{}><td class=l>{}</td><td class=l>{}</td><td class=l>{}</td><td class=l>{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td class=l>{}</td><td class=l>{}</td></tr>",
            row_class(!row.ok(), *suspect, &row.algorithm),
            algorithm_cell(&row.algorithm),
            esc(&row.settings),
            esc(&row.dataset),
            esc(&row.viewpoint),
            opt(row.total_ms, 2),
            opt(row.cpu_ms, 2),
            opt(row.gpu_ms, 2),
            opt(row.fps, 1),
            opt(row.tets_per_sec.map(|v| v * 1e-6), 3),
            mb(row.gpu_bytes),
            opt(row.bytes_per_tet, 1),
            opt(row.rmse, 5),
            opt(row.psnr_db, 2),
            opt(row.max_abs_error, 4),
            opt(row.bad_pixel_share.map(|v| v * 100.0), 2),
            esc(&row.stages),
            if row.suspect.is_empty() {
                esc(&row.error)
            } else {
                esc(&format!("SUSPECT: {}", row.suspect))
            },
        );
    }
    h.push_str("</table>\n<p>Raw data: <a href=\"results.csv\">results.csv</a>, <a href=\"results.json\">results.json</a>.</p>\n</body></html>\n");
    h
}

/// The summary as a Markdown table (for `tetbench analyze summary` and notes).
pub fn markdown_summary(aggs: &[Aggregate]) -> String {
    let mut s = String::from(
        "| algorithm | settings | data set | tets | total ms | CPU ms | GPU ms | fps | M tets/s | PSNR dB (min) | bytes/tet |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let m = |v: Option<Spread>, k: f64, d: usize| {
        v.map(|v| format!("{:.d$}", v.mean * k))
            .unwrap_or_else(|| "–".into())
    };
    for a in aggs {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} ({}) | {} |",
            a.algorithm,
            a.settings,
            a.dataset,
            a.tets,
            m(a.total_ms, 1.0, 2),
            m(a.cpu_ms, 1.0, 2),
            m(a.gpu_ms, 1.0, 2),
            m(a.fps, 1.0, 1),
            m(a.tets_per_sec, 1e-6, 3),
            m(a.psnr_db, 1.0, 2),
            a.psnr_db
                .map(|p| format!("{:.2}", p.min))
                .unwrap_or_else(|| "–".into()),
            opt(a.bytes_per_tet, 1),
        );
    }
    let suspect: Vec<&Aggregate> = aggs.iter().filter(|a| a.suspect > 0).collect();
    if !suspect.is_empty() {
        s.push_str("\n**Suspect** (PSNR far below the best algorithm on the same image; see `suspect` in results.csv):\n\n");
        for a in suspect {
            let _ = writeln!(
                s,
                "- {} {} on {}: {} of {} views",
                a.algorithm, a.settings, a.dataset, a.suspect, a.rows
            );
        }
    }
    s
}

/// The algorithm's name for the HTML tables, with peers (other packages' renderers) marked.
fn algorithm_cell(name: &str) -> String {
    if is_peer(name) {
        format!("{} <small class=peer>(peer)</small>", esc(name))
    } else {
        esc(name)
    }
}

/// Rows flagged by [`crate::suspect`], each with its heatmap first, then the rendering and the
/// reference, so a broken renderer is the first picture a reader sees after the charts.
fn suspect_section(h: &mut String, file: &ResultsFile) {
    let suspects: Vec<&Row> = file.rows.iter().filter(|r| !r.suspect.is_empty()).collect();
    if suspects.is_empty() {
        return;
    }
    let _ = write!(
        h,
        "<h2>Suspect rows ({})</h2><p>Image error far out of line with the other algorithms on \
         the same image: a renderer defect, or a mesh or setting the method cannot handle. \
         Heatmap first, then the rendering and the reference.</p><div class=\"strip suspect\">",
        suspects.len()
    );
    for row in suspects {
        h.push_str("<figure><div class=pair>");
        for (path, alt) in [
            (&row.heatmap, "error heatmap"),
            (&row.image, "image"),
            (&row.reference_image, "reference"),
        ] {
            if !path.is_empty() {
                let _ = write!(
                    h,
                    "<a href=\"{0}\"><img src=\"{0}\" alt=\"{alt}\" loading=lazy></a>",
                    esc(path)
                );
            }
        }
        let _ = write!(
            h,
            "</div><figcaption>{} {} on {} {}<br>{}</figcaption></figure>",
            esc(&row.algorithm),
            esc(&row.settings),
            esc(&row.dataset),
            esc(&row.viewpoint),
            esc(&row.suspect)
        );
    }
    h.push_str("</div>\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::MachineInfo;
    use crate::results::{test_row, RunDescription, SCHEMA_VERSION};

    fn file() -> ResultsFile {
        let mut rows = vec![];
        for i in 0..3 {
            let mut r = test_row(i);
            r.tets_per_sec = Some(1e6 * (i + 1) as f64);
            r.psnr_db = Some(40.0 + i as f64);
            r.image = format!("images/box_1k/v{i}/test.png");
            r.heatmap = format!("images/box_1k/v{i}/test.error.png");
            r.reference_image = format!("images/box_1k/v{i}/reference.png");
            rows.push(r);
        }
        let mut failed = test_row(3);
        failed.error = "out of memory <boom>".into();
        failed.tets_per_sec = None;
        rows.push(failed);
        ResultsFile {
            schema_version: SCHEMA_VERSION,
            machine: MachineInfo::collect(),
            run: RunDescription::default(),
            finished_utc: None,
            rows,
            errors: vec!["data set \"x\" could not be loaded".into()],
        }
    }

    #[test]
    fn aggregates_average_over_viewpoints() {
        let a = aggregate(&file().rows);
        assert_eq!(a.len(), 1);
        let t = a[0].tets_per_sec.unwrap();
        assert_eq!((t.mean, t.min, t.max), (2e6, 1e6, 3e6));
        assert_eq!(a[0].rows, 4);
        assert_eq!(a[0].failed, 1);
        assert!(markdown_summary(&a).contains("| test | variant=a;sort=radix | box:1k | 1000 |"));
    }

    #[test]
    fn report_has_charts_table_and_images() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), &file()).unwrap();
        let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
        for needle in [
            "charts/tets_per_sec.png",
            "charts/psnr.png",
            "images/box_1k/v2/test.png",
            "images/box_1k/v2/test.error.png",
            "images/box_1k/v0/reference.png",
            "out of memory &lt;boom&gt;",
        ] {
            assert!(html.contains(needle), "index.html lacks {needle}");
        }
        for f in [
            "tets_per_sec.png",
            "tets_per_sec.svg",
            "psnr.png",
            "psnr.svg",
            "DejaVuSans.ttf",
        ] {
            assert!(
                dir.path().join("charts").join(f).metadata().unwrap().len() > 1000,
                "{f}"
            );
        }
        let png = image::open(dir.path().join("charts/psnr.png"))
            .unwrap()
            .to_rgb8();
        // Not blank: the bars and text drew something other than the white background.
        assert!(png.pixels().filter(|p| p.0 != [255, 255, 255]).count() > 1000);
        let svg = std::fs::read_to_string(dir.path().join("charts/psnr.svg")).unwrap();
        assert!(svg.contains("@font-face") && svg.contains("DejaVu Sans"));
    }
}
