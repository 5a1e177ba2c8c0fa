//! The outputs of `tetbench compare`: a terminal table, `compare.md`, `compare.json` and
//! `compare.html` (with the ratio plots and the image-difference heatmaps).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use serde::Serialize;

use crate::plot::ratio::{ratio_plot, Direction, Strip};
use crate::regress::compare::{
    CompareOptions, Comparison, FailOn, Finding, RowComparison, RowStatus, TimeTest, Verdict,
};
use crate::results::write_file;

fn header(c: &Comparison) -> Vec<String> {
    let commit = |c: &Option<String>| {
        c.as_deref()
            .map(|s| &s[..s.len().min(10)])
            .unwrap_or("?")
            .to_string()
    };
    let mut lines = vec![
        format!("BASE {} — {} (commit {})", c.base, c.base_adapter, commit(&c.base_commit)),
        format!("NEW  {} — {} (commit {})", c.new, c.new_adapter, commit(&c.new_commit)),
        format!(
            "test: {}{}",
            c.test,
            if c.normalised {
                "; times NORMALISED by each machine's calibration (sample / roofline time)"
            } else {
                ""
            }
        ),
        match &c.time_refused {
            Some(why) => why.clone(),
            None => format!(
                "samples: one per round ({} rounds in BASE, {} in NEW)",
                c.rounds.base, c.rounds.new
            ),
        },
        match (&c.machine, c.run_factor) {
            (Some(m), f) => format!(
                "machine drift: ×{:.3} (NEW's machine over BASE's, from the control measured \
                 beside the rows); every round of both sides was divided by its own control \
                 before the tests. What remains run-wide: {}",
                m.factor,
                f.map_or("-".into(), |f| format!("×{f:.3} (median over the groups)"))
            ),
            (None, _) => drift_line(c),
        },
        c.control_missing.clone().unwrap_or_default(),
        across_lines(c).first().cloned().unwrap_or_default(),
        format!(
            "outcome: {} — {} regression(s), {} improvement(s), {} other change(s) in {} rows, {} groups",
            c.outcome().to_uppercase(),
            c.regressions.len(),
            c.improvements.len(),
            c.changes.len(),
            c.rows.len(),
            c.groups.len()
        ),
    ];
    lines.retain(|l| !l.is_empty());
    lines.extend(c.warnings.iter().map(|w| format!("WARNING: {w}")));
    lines
}

/// The line on the run-wide factor, for comparisons without a control on both sides.
/// The across-machines table (compare_across.rs): its summary first, then a line a group.
fn across_lines(c: &Comparison) -> Vec<String> {
    c.across
        .as_ref()
        .map(crate::regress::compare_across::lines)
        .unwrap_or_default()
}

fn drift_line(c: &Comparison) -> String {
    match (c.run_factor, c.drift_corrected, &c.pair_factors) {
        (f, true, Some(per_pair)) => format!(
            "drift per pair: NEW/BASE {} (median over the groups of each pair); each NEW \
                 round was divided by its own pair's factor before the tests (run-wide {})",
            per_pair
                .iter()
                .map(|f| format!("×{f:.3}"))
                .collect::<Vec<_>>()
                .join(", "),
            f.map_or("-".into(), |f| format!("×{f:.3}"))
        ),
        (Some(f), true, None) => format!(
            "run-wide factor: NEW/BASE ×{f:.3} (median over the groups); NEW's total_ms was \
                 divided by it before the tests, so ratios below are relative to the rest of the \
                 run (--no-drift-correction: absolute)"
        ),
        (Some(f), false, _) => {
            format!("run-wide factor: NEW/BASE ×{f:.3} (median over the groups); not divided out")
        }
        (None, _, _) => "run-wide factor: too few groups to estimate; absolute times tested".into(),
    }
}

fn time_cell(t: Option<&TimeTest>) -> String {
    match t {
        Some(t) => format!("×{:.3} p={} {}", t.ratio, t.p_label(), t.verdict.label()),
        None => "-".into(),
    }
}

fn metric<'a>(r: &'a RowComparison, name: &str) -> Option<&'a TimeTest> {
    r.times.iter().find(|t| t.metric == name)
}

/// What a group's test was made on: paired rounds (`ab`) or the viewpoints' round values.
fn groups_basis(c: &Comparison) -> &'static str {
    if c.pair_factors.is_some() {
        "total_ms, paired: one ln(NEW/BASE) per pair, t-test pooled over the groups"
    } else {
        "total_ms pooled over viewpoints"
    }
}

/// The rows with something to say: a status other than no change.
fn notable(c: &Comparison) -> Vec<&RowComparison> {
    c.rows
        .iter()
        .filter(|r| r.status != RowStatus::NoChange)
        .collect()
}

/// The terminal summary: header, group table, then only the rows with something to say.
pub fn terminal(c: &Comparison) -> String {
    let mut s = header(c).join("\n");
    s.push_str(&format!("\n\ngroups ({}):\n", groups_basis(c)));
    let w = c
        .groups
        .iter()
        .map(|g| g.algorithm.len() + g.settings.len() + g.dataset.len() + 4)
        .max()
        .unwrap_or(10);
    for g in &c.groups {
        let name = format!("{} {} @ {}", g.algorithm, g.settings, g.dataset);
        let _ = writeln!(s, "  {name:<w$}  {}", time_cell(Some(&g.total)));
    }
    if let [_, groups @ ..] = across_lines(c).as_slice() {
        let _ = writeln!(s, "\nacross machines, information only:");
        for l in groups {
            let _ = writeln!(s, "  {l}");
        }
    }
    let notable = notable(c);
    let _ = writeln!(
        s,
        "\nrows with a change ({} of {}):",
        notable.len(),
        c.rows.len()
    );
    for r in notable {
        let _ = writeln!(
            s,
            "  {:<12} {} {} @ {} {}: {}",
            r.status,
            r.algorithm,
            r.settings,
            r.dataset,
            r.viewpoint,
            r.notes.join("; ")
        );
    }
    s.push('\n');
    s
}

fn markdown(c: &Comparison) -> String {
    let mut s = String::from("# tetbench compare\n\n");
    for l in header(c) {
        let _ = writeln!(s, "- {l}");
    }
    for (title, list) in [
        ("Regressions", &c.regressions),
        ("Improvements", &c.improvements),
        ("Other changes", &c.changes),
    ] {
        if !list.is_empty() {
            let _ = writeln!(s, "\n## {title}\n");
            for l in list.iter() {
                let _ = writeln!(s, "- {}", l.text);
            }
        }
    }
    if let Some(a) = &c.across {
        s.push_str("\n## Across machines (information only)\n\n");
        s.push_str("| algorithm | settings | data set | rows | raw NEW/BASE | control-normalised |\n|---|---|---|---:|---:|---:|\n");
        for g in &a.groups {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {:.3} | {:.3} |",
                g.algorithm, g.settings, g.dataset, g.rows, g.raw_ratio, g.control_ratio
            );
        }
    }
    s.push_str(&format!("\n## Groups ({})\n\n", groups_basis(c)));
    s.push_str("| algorithm | settings | data set | views | base ms | new ms | ratio | p (Holm) | verdict |\n|---|---|---|---:|---:|---:|---:|---:|---|\n");
    for g in &c.groups {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.3} | {:.3} | {:.3} | {} | {} |",
            g.algorithm,
            g.settings,
            g.dataset,
            g.viewpoints,
            g.total.base_median,
            g.total.new_median,
            g.total.ratio,
            g.total.p_label(),
            g.total.verdict.label()
        );
    }
    // Only the rows with something to say: the page is meant for a pull-request comment.
    let notable = notable(c);
    let _ = write!(
        s,
        "\n## Rows with a change ({} of {})\n\n",
        notable.len(),
        c.rows.len()
    );
    if notable.is_empty() {
        return s;
    }
    s.push_str("| status | algorithm | settings | data set | view | total_ms | cpu_ms | gpu_ms | PSNR Δ dB | changed px | work and bytes | notes |\n|---|---|---|---|---|---|---|---|---:|---:|---|---|\n");
    for r in notable {
        let img = r.image.as_ref();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.status,
            r.algorithm,
            r.settings,
            r.dataset,
            r.viewpoint,
            time_cell(metric(r, "total_ms")),
            time_cell(metric(r, "cpu_ms")),
            time_cell(metric(r, "gpu_ms")),
            img.and_then(|i| i.psnr_delta_db)
                .map(|d| format!("{d:+.3}"))
                .unwrap_or_else(|| "-".into()),
            img.and_then(|i| i.changed_pixels.map(|p| p.to_string()).or(i
                .pixels_changed
                .map(|b| if b { "yes".into() } else { "0".into() })))
                .unwrap_or_else(|| "-".into()),
            work_cell(r),
            r.notes.join("; ")
        );
    }
    s
}

/// One row of compare.html, every cell already formatted (the template escapes them).
#[derive(Serialize)]
struct HtmlRow {
    class: String,
    status: String,
    algorithm: String,
    settings: String,
    dataset: String,
    viewpoint: String,
    total_ms: String,
    cpu_ms: String,
    gpu_ms: String,
    psnr_delta: String,
    heatmap: String,
    changed_pixels: u64,
    image_verdict: String,
    work: String,
    notes: String,
}

#[derive(Serialize)]
struct HtmlSection {
    title: &'static str,
    lines: Vec<String>,
}

/// The work changes of a row, one `counter base→new` each.
fn work_cell(r: &RowComparison) -> String {
    r.work
        .iter()
        .map(|w| w.describe())
        .collect::<Vec<_>>()
        .join(", ")
}

fn texts(findings: &[Finding]) -> Vec<String> {
    findings.iter().map(|f| f.text.clone()).collect()
}

#[derive(Serialize)]
struct ComparePage {
    header: Vec<String>,
    sections: Vec<HtmlSection>,
    rows: Vec<HtmlRow>,
}

/// compare.html, from `templates/compare.html` (every value escaped, crate::report::html).
fn html(c: &Comparison) -> anyhow::Result<String> {
    let rows = c
        .rows
        .iter()
        .map(|r| {
            let img = r.image.as_ref();
            let heatmap = img.map(|i| i.heatmap.clone()).unwrap_or_default();
            HtmlRow {
                class: r.status.label().replace(' ', "-"),
                status: r.status.to_string(),
                algorithm: r.algorithm.clone(),
                settings: r.settings.to_string(),
                dataset: r.dataset.clone(),
                viewpoint: r.viewpoint.clone(),
                total_ms: time_cell(metric(r, "total_ms")),
                cpu_ms: time_cell(metric(r, "cpu_ms")),
                gpu_ms: time_cell(metric(r, "gpu_ms")),
                psnr_delta: img
                    .and_then(|i| i.psnr_delta_db)
                    .map(|d| format!("{d:+.3}"))
                    .unwrap_or_default(),
                changed_pixels: img.and_then(|i| i.changed_pixels).unwrap_or(0),
                image_verdict: img.map(|i| i.verdict.to_string()).unwrap_or_default(),
                heatmap,
                work: work_cell(r),
                notes: r.notes.join("; "),
            }
        })
        .collect();
    crate::report::html::render(
        "compare.html",
        ComparePage {
            header: header(c),
            sections: vec![
                HtmlSection {
                    title: "Regressions",
                    lines: texts(&c.regressions),
                },
                HtmlSection {
                    title: "Improvements",
                    lines: texts(&c.improvements),
                },
                HtmlSection {
                    title: "Other changes",
                    lines: texts(&c.changes),
                },
                HtmlSection {
                    title: "Across machines (information only)",
                    lines: across_lines(c).into_iter().skip(1).collect(),
                },
            ],
            rows,
        },
    )
}

/// Writes compare.md, compare.json, compare.html and the ratio plots into `out`.
pub fn write_outputs(c: &Comparison, out: &Path) -> anyhow::Result<()> {
    let write = |name: &str, text: String| {
        let p = out.join(name);
        write_file(&p, text)
    };
    write("compare.md", markdown(c))?;
    write("compare.json", serde_json::to_string_pretty(c)? + "\n")?;
    let charts = out.join("charts");
    std::fs::create_dir_all(&charts)
        .with_context(|| format!("cannot create {}", charts.display()))?;
    let groups: Vec<Strip> = c
        .groups
        .iter()
        .map(|g| Strip {
            label: format!("{} {} @ {}", g.algorithm, g.settings, g.dataset),
            base: g.total.base_ratios.clone(),
            new: g.total.new_ratios.clone(),
            verdict: g.total.verdict.label().to_string(),
            direction: direction(g.total.verdict),
        })
        .collect();
    ratio_plot(
        &charts,
        "ratio_groups",
        "total_ms per group",
        &groups,
        c.threshold,
    )?;
    let rows: Vec<Strip> = c
        .rows
        .iter()
        .filter_map(|r| {
            let t = metric(r, "total_ms")?;
            Some(Strip {
                label: format!(
                    "{} {} @ {} {}",
                    r.algorithm, r.settings, r.dataset, r.viewpoint
                ),
                base: t.base_ratios.clone(),
                new: t.new_ratios.clone(),
                verdict: t.verdict.label().to_string(),
                direction: direction(t.verdict),
            })
        })
        .collect();
    ratio_plot(
        &charts,
        "ratio_rows",
        "total_ms per row",
        &rows,
        c.threshold,
    )?;
    write("compare.html", html(c)?)
}

/// What `compare` prints on stdout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CompareFormat {
    /// The terminal table.
    Text,
    /// compare.json.
    Json,
    /// compare.md: fit for a pull-request comment.
    Md,
}

/// `tetbench compare`: prints the table (or the JSON or Markdown), writes
/// compare.{md,json,html}, returns whether the `--fail-on` condition was met.
pub fn run_command(
    base: &Path,
    new: &Path,
    opt: &CompareOptions,
    format: CompareFormat,
) -> anyhow::Result<bool> {
    let cmp = crate::regress::compare::compare(base, new, opt)?;
    std::fs::create_dir_all(&opt.out)
        .with_context(|| format!("cannot create {}", opt.out.display()))?;
    write_outputs(&cmp, &opt.out)?;
    match format {
        CompareFormat::Text => {
            print!("{}", terminal(&cmp));
            println!("wrote {}/compare.{{md,json,html}}", opt.out.display());
        }
        CompareFormat::Json => print!("{}", serde_json::to_string_pretty(&cmp)? + "\n"),
        CompareFormat::Md => print!("{}", markdown(&cmp)),
    }
    gate(&cmp, opt.fail_on)
}

/// Whether `--fail-on` is met (exit 3). A regression of work, image or memory is exact and
/// gates even on a noisy machine; without one, separate runs too noisy to judge time
/// ([`crate::regress::compare::time_noise`]) are an error (exit 1) under `--fail-on
/// regression` or `change`: the gate could not do its job, and exit 0 would pretend it had.
pub fn gate(cmp: &Comparison, fail_on: FailOn) -> anyhow::Result<bool> {
    if cmp.information_only() {
        return Ok(false);
    }
    let met = match fail_on {
        FailOn::Never => return Ok(false),
        FailOn::Regression => !cmp.regressions.is_empty(),
        FailOn::Change => cmp.outcome() != "no change",
    };
    if !met && cmp.too_noisy {
        anyhow::bail!(
            "{}",
            cmp.time_refused
                .as_deref()
                .unwrap_or("the runs are too noisy to gate on time")
        );
    }
    Ok(met)
}

/// The colour a verdict's strip gets in the ratio plots.
fn direction(verdict: Verdict) -> Direction {
    match verdict {
        Verdict::Slower => Direction::Slower,
        Verdict::Faster => Direction::Faster,
        _ => Direction::Neither,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regress::compare::compare;
    use crate::results::samples;
    use crate::results::ResultsFile;

    /// Writes a one-row results set whose f32 image is `img`, with 5 frames around `ms`.
    fn results_dir(dir: &Path, img: &render_core::Image, ms: f64) {
        results_dir_named(dir, img, ms, "box:1k")
    }

    fn results_dir_named(dir: &Path, img: &render_core::Image, ms: f64, dataset: &str) {
        std::fs::create_dir_all(dir.join("images")).unwrap();
        let mut row = crate::results::Row {
            algorithm: "havs".into(),
            settings: "k=2".parse().unwrap(),
            dataset: dataset.into(),
            viewpoint: "+x".into(),
            total_ms: Some(ms),
            psnr_db: Some(60.0),
            gpu_bytes: Some(1000),
            image_f32: "images/a.f32.zz".into(),
            ..Default::default()
        };
        row.samples.total_ms = (0..5).map(|i| ms + 0.01 * i as f64).collect();
        samples::write_f32_image(&dir.join(&row.image_f32), img).unwrap();
        row.image_hash = samples::image_hash(img);
        let file = ResultsFile {
            control: None,
            schema_version: crate::results::SCHEMA_VERSION,
            machine: crate::results::machine::MachineInfo::collect(),
            run: Default::default(),
            finished_utc: None,
            rows: vec![row],
            errors: vec![],
        };
        crate::results::write_json(dir, &file).unwrap();
    }

    /// The default thresholds, gating on any change, writing into `out`.
    fn gate_on_change(out: std::path::PathBuf) -> CompareOptions {
        CompareOptions {
            threshold: 1.10,
            alpha: 0.05,
            normalised: false,
            drift_correction: true,
            paired: false,
            drift_limit: 1.5,
            fail_on: FailOn::Change,
            out,
        }
    }

    /// a data set named with markup lands in compare.html as text.
    #[test]
    fn markup_in_names_is_escaped() {
        use crate::report::html::{assert_no_live_markup, HOSTILE_NAME};
        let tmp = tempfile::tempdir().unwrap();
        let img = render_core::Image::new(8, 8);
        let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
        results_dir_named(&a, &img, 10.0, HOSTILE_NAME);
        results_dir_named(&b, &img, 10.0, HOSTILE_NAME);
        let opt = gate_on_change(tmp.path().join("out"));
        run_command(&a, &b, &opt, CompareFormat::Text).unwrap();
        let page = std::fs::read_to_string(tmp.path().join("out/compare.html")).unwrap();
        assert!(page.contains("<table>"), "the page has its table");
        assert_no_live_markup(&page);
    }

    /// Rendering is deterministic, so a single changed pixel — far below what PSNR or an
    /// 8-bit PNG shows — is reported, with its heatmap; identical runs show no change.
    #[test]
    fn a_one_pixel_image_change_is_reported() {
        let tmp = tempfile::tempdir().unwrap();
        let mut img = render_core::Image::new(16, 16);
        img.pixels
            .iter_mut()
            .for_each(|p| *p = [0.2, 0.3, 0.4, 0.5]);
        let mut changed = img.clone();
        changed.pixels[37][2] = f32::from_bits(changed.pixels[37][2].to_bits() + 1);
        let (a, b, c) = (
            tmp.path().join("a"),
            tmp.path().join("b"),
            tmp.path().join("c"),
        );
        results_dir(&a, &img, 10.0);
        results_dir(&b, &img, 10.0);
        results_dir(&c, &changed, 10.0);
        let opt = |out: &str| gate_on_change(tmp.path().join(out));
        let same = compare(&a, &b, &opt("ab")).unwrap();
        assert_eq!(same.outcome(), "no change", "{same:#?}");
        assert!(!run_command(&a, &b, &opt("ab"), CompareFormat::Text).unwrap());
        let diff = compare(&a, &c, &opt("ac")).unwrap();
        let row = &diff.rows[0];
        let image = row.image.as_ref().unwrap();
        assert_eq!(image.changed_pixels, Some(1));
        assert_eq!(image.pixels_changed, Some(true));
        assert_eq!(
            image.verdict,
            crate::regress::compare::ImageVerdict::Changed
        );
        assert_eq!(row.status, RowStatus::Changed);
        assert_eq!(diff.outcome(), "changed");
        // fail-on change gates it; the outputs name the heatmap.
        assert!(run_command(&a, &c, &opt("ac"), CompareFormat::Text).unwrap());
        assert!(tmp.path().join("ac").join(&image.heatmap).is_file());
        for f in [
            "compare.md",
            "compare.json",
            "compare.html",
            "charts/ratio_rows.png",
        ] {
            assert!(tmp.path().join("ac").join(f).is_file(), "{f}");
        }
    }

    /// The gate never fires on a comparison across adapters given as information: the same
    /// comparison with its across table taken away gates on its changed pixel.
    #[test]
    fn information_only_never_gates() {
        let tmp = tempfile::tempdir().unwrap();
        let img = render_core::Image::new(8, 8);
        let mut changed = img.clone();
        changed.pixels[3][0] = 1.0;
        let (a, c) = (tmp.path().join("a"), tmp.path().join("c"));
        results_dir(&a, &img, 10.0);
        results_dir(&c, &changed, 10.0);
        let mut cmp = compare(&a, &c, &gate_on_change(tmp.path().join("out"))).unwrap();
        assert!(gate(&cmp, FailOn::Change).unwrap());
        cmp.across = Some(crate::regress::compare_across::AcrossMachines {
            reason: "two adapters".into(),
            machine_factor: 1.0,
            information_only: true,
            groups: vec![],
        });
        assert_eq!(cmp.outcome(), "information only");
        assert!(!gate(&cmp, FailOn::Change).unwrap());
    }
}
