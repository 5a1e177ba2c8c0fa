//! What every paper's report is made of: comparison tables (paper | ours | ours/paper, or an
//! exact verdict for tables that do not depend on the GPU), their Markdown, HTML and bar
//! charts. The paper's claims and their verdicts are [`crate::papers::claims`].

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;

/// How a metric is compared with the paper's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MetricKind {
    /// Depends on the hardware: shown as ours/paper.
    Measured,
    /// Does not depend on the GPU: ours must equal the paper's.
    Exact,
    /// A count the paper prints rounded ("2.9 K"): ours rounded to the paper's significant
    /// digits must equal it.
    RoundedAsPrinted,
}

/// One metric (column group) of a comparison table.
#[derive(Debug, Clone)]
pub struct Metric {
    pub name: String,
    /// Digits after the decimal point when printed.
    pub digits: usize,
    pub kind: MetricKind,
}

impl Metric {
    pub fn new(name: impl Into<String>, digits: usize) -> Metric {
        Metric {
            name: name.into(),
            digits,
            kind: MetricKind::Measured,
        }
    }
    pub fn exact(name: impl Into<String>, digits: usize) -> Metric {
        Metric {
            kind: MetricKind::Exact,
            ..Metric::new(name, digits)
        }
    }
    pub fn rounded(name: impl Into<String>) -> Metric {
        Metric {
            kind: MetricKind::RoundedAsPrinted,
            ..Metric::new(name, 0)
        }
    }
    fn compared_exactly(&self) -> bool {
        self.kind != MetricKind::Measured
    }
    /// Whether ours equals the paper's under this metric's rule.
    pub fn agrees(&self, paper: f64, ours: f64) -> bool {
        match self.kind {
            MetricKind::RoundedAsPrinted => round_sig(ours, significant_digits(paper)) == paper,
            _ => paper == ours,
        }
    }
}

/// Significant digits of a value printed rounded (trailing zeros of an integer do not count).
fn significant_digits(v: f64) -> i32 {
    let mut x = v.abs().round() as u64;
    if x == 0 {
        return 1;
    }
    while x.is_multiple_of(10) {
        x /= 10;
    }
    x.to_string().len() as i32
}

fn round_sig(v: f64, digits: i32) -> f64 {
    if v == 0.0 {
        return 0.0;
    }
    // Divide or multiply by an exact power of ten so 1,500,282 → 1,500,000 exactly.
    let e = v.abs().log10().floor() as i32 - (digits - 1);
    if e >= 0 {
        let p = 10f64.powi(e);
        (v / p).round() * p
    } else {
        let p = 10f64.powi(-e);
        (v * p).round() / p
    }
}

/// One cell pair: the paper's value and ours.
#[derive(Debug, Clone, Default)]
pub struct Cell {
    pub paper: Option<f64>,
    pub ours: Option<f64>,
    /// Why ours is empty (algorithm not built in, row failed, …).
    pub why_no_ours: Option<String>,
    /// Why the transcription calls the paper's value uncertain.
    pub uncertain: Option<String>,
}

impl Cell {
    pub fn new(paper: Option<f64>, ours: Option<f64>) -> Cell {
        Cell {
            paper,
            ours,
            ..Default::default()
        }
    }
    pub fn missing(paper: Option<f64>, why: impl Into<String>) -> Cell {
        Cell {
            paper,
            ours: None,
            why_no_ours: Some(why.into()),
            uncertain: None,
        }
    }
    pub fn uncertain(mut self, why: Option<String>) -> Cell {
        self.uncertain = why;
        self
    }
    pub fn ratio(&self) -> Option<f64> {
        match (self.paper, self.ours) {
            (Some(p), Some(o)) if p != 0.0 && p.is_finite() && o.is_finite() => Some(o / p),
            _ => None,
        }
    }
}

/// A row: a label (data set, algorithm, sort…), whether it was measured on a stand-in, one
/// cell per metric.
#[derive(Debug, Clone)]
pub struct CompRow {
    pub label: String,
    pub standin: bool,
    pub cells: Vec<Cell>,
}

/// A table in the paper's shape with our values beside the paper's.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// File-safe id (`table3`), used for chart names.
    pub key: String,
    pub title: String,
    /// The paper's conditions and ours for this table.
    pub conditions: String,
    pub metrics: Vec<Metric>,
    pub rows: Vec<CompRow>,
    pub notes: Vec<String>,
}

impl Comparison {
    /// The metrics compared exactly, over every non-stand-in cell where both have a value:
    /// `Some(true)` if all agree, `None` when no such cell exists.
    pub fn verdict(&self) -> Option<bool> {
        let mut any = false;
        for r in self.rows.iter().filter(|r| !r.standin) {
            for (m, c) in self.metrics.iter().zip(&r.cells) {
                if !m.compared_exactly() {
                    continue;
                }
                if let (Some(p), Some(o)) = (c.paper, c.ours) {
                    any = true;
                    if !m.agrees(p, o) {
                        return Some(false);
                    }
                }
            }
        }
        any.then_some(true)
    }
}

impl Comparison {
    /// The columns the exact verdict compares (exact metrics).
    pub fn compared_columns(&self) -> Vec<&str> {
        self.metrics
            .iter()
            .filter(|m| m.compared_exactly())
            .map(|m| m.name.as_str())
            .collect()
    }

    /// The columns that depend on the hardware: shown as ours/paper, never part of a match.
    pub fn not_compared_columns(&self) -> Vec<&str> {
        self.metrics
            .iter()
            .filter(|m| !m.compared_exactly())
            .map(|m| m.name.as_str())
            .collect()
    }

    /// "Compared: tets. Not compared (they depend on the hardware): fps, tets/s."
    pub fn columns_sentence(&self) -> String {
        let mut s = format!("Compared: {}.", self.compared_columns().join(", "));
        let not = self.not_compared_columns();
        if !not.is_empty() {
            s.push_str(&format!(
                " Not compared (they depend on the hardware; ours/paper shown): {}.",
                not.join(", ")
            ));
        }
        s
    }

    /// The table's one-line verdict for the index, naming the columns it compared and those
    /// it did not: `table1: tets match (fps, tets/s not compared)` (`None`: no exact column).
    pub fn summary(&self) -> Option<String> {
        let v = self.verdict()?;
        let mut s = format!(
            "{}: {} {}",
            self.key,
            self.compared_columns().join(", "),
            if v { "match" } else { "differ" }
        );
        let not = self.not_compared_columns();
        if !not.is_empty() {
            s.push_str(&format!(" ({} not compared)", not.join(", ")));
        }
        Some(s)
    }
}

/// A number as printed in tables: fixed digits, `–` for none.
pub fn num(v: Option<f64>, digits: usize) -> String {
    match v {
        Some(x) if x.is_finite() => {
            if x.abs() >= 1e5 && digits == 0 {
                format!("{:.0}", x)
            } else {
                format!("{x:.digits$}")
            }
        }
        _ => "–".into(),
    }
}

fn ratio_text(c: &Cell) -> String {
    c.ratio().map(|r| format!("{r:.3}")).unwrap_or("–".into())
}

fn exact_text(m: &Metric, c: &Cell) -> &'static str {
    match (c.paper, c.ours) {
        (Some(p), Some(o)) if m.agrees(p, o) => "matches",
        (Some(_), Some(_)) => "does not match",
        _ => "–",
    }
}

/// The table as Markdown: per metric the paper's value, ours, and ours/paper (or the exact
/// verdict), then the footnotes (stand-ins, uncertain cells, missing values).
pub fn markdown(c: &Comparison) -> String {
    let mut md = format!("### {}\n\n{}\n\n", c.title, c.conditions);
    let mut head = String::from("| row |");
    let mut rule = String::from("|---|");
    for m in &c.metrics {
        let third = if m.compared_exactly() {
            "verdict"
        } else {
            "ours/paper"
        };
        let _ = write!(head, " {0} paper | {0} ours | {third} |", m.name);
        rule.push_str("---:|---:|---:|");
    }
    let _ = writeln!(md, "{head}\n{rule}");
    let mut footnotes: Vec<String> = vec![];
    let mut mark = |text: String| -> String {
        let i = match footnotes.iter().position(|f| *f == text) {
            Some(i) => i,
            None => {
                footnotes.push(text);
                footnotes.len() - 1
            }
        };
        format!("[{}]", i + 1)
    };
    for r in &c.rows {
        let label = if r.standin {
            format!("{} (stand-in)", r.label)
        } else {
            r.label.clone()
        };
        let _ = write!(md, "| {label} |");
        for (m, cell) in c.metrics.iter().zip(&r.cells) {
            let mut p = num(cell.paper, m.digits);
            if let Some(u) = &cell.uncertain {
                p.push_str(&format!(" ?{}", mark(format!("uncertain: {u}"))));
            }
            let mut o = num(cell.ours, m.digits);
            if let Some(w) = &cell.why_no_ours {
                o.push_str(&format!(" {}", mark(w.clone())));
            }
            let t = if m.compared_exactly() {
                let v = exact_text(m, cell);
                if r.standin && v != "–" {
                    format!("{v} (stand-in)")
                } else {
                    v.to_string()
                }
            } else {
                ratio_text(cell)
            };
            let _ = write!(md, " {p} | {o} | {t} |");
        }
        md.push('\n');
    }
    if c.metrics.iter().any(|m| m.compared_exactly()) {
        let v = match c.verdict() {
            Some(true) => {
                "**ours matches the paper** in every cell of the compared columns both have (stand-in rows excluded)"
            }
            Some(false) => {
                "**ours does not match the paper** in at least one cell of the compared columns (stand-in rows excluded)"
            }
            None => "no cell could be compared",
        };
        let _ = writeln!(md, "\nVerdict: {v}. {}", c.columns_sentence());
    }
    if !footnotes.is_empty() {
        md.push('\n');
        for (i, f) in footnotes.iter().enumerate() {
            let _ = writeln!(md, "[{}] {f}  ", i + 1);
        }
    }
    for n in &c.notes {
        let _ = writeln!(md, "\n{n}");
    }
    md
}

/// A report page from its Markdown: pulldown-cmark (tables on) renders the body, and raw HTML
/// in the Markdown — a data set or file name such as `<img src=x onerror=alert(1)>` quoted in a
/// table — is turned into text before rendering, so only the Markdown's own structure becomes
/// markup. The page around it comes from `templates/markdown.html` (crate::report::html).
pub fn markdown_to_html(md: &str, title: &str) -> anyhow::Result<String> {
    use pulldown_cmark::{Event, Options, Parser};
    let events = Parser::new_ext(md, Options::ENABLE_TABLES).map(|e| match e {
        Event::Html(raw) | Event::InlineHtml(raw) => Event::Text(raw),
        e => e,
    });
    let mut body = String::new();
    pulldown_cmark::html::push_html(&mut body, events);
    #[derive(serde::Serialize)]
    struct Page<'a> {
        title: &'a str,
        body: minijinja::Value,
    }
    crate::report::html::render(
        "markdown.html",
        Page {
            title,
            // Escaped by pulldown-cmark above: every text and attribute, raw HTML included.
            body: minijinja::Value::from_safe_string(body),
        },
    )
}

/// Bar charts paper vs ours, one PNG per metric of `c` that has values on both sides, on a
/// log scale (papers' GPUs and ours differ by orders of magnitude). Returns the file names
/// written (relative to `dir`).
pub fn write_charts(dir: &Path, c: &Comparison) -> anyhow::Result<Vec<String>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut written = vec![];
    for (mi, m) in c.metrics.iter().enumerate() {
        // Exact metrics (counts, truth values) are compared in the table, not charted.
        if m.compared_exactly() {
            continue;
        }
        let bars: Vec<(String, Option<f64>, Option<f64>)> = c
            .rows
            .iter()
            .map(|r| {
                let cell = &r.cells[mi];
                let label = if r.standin {
                    format!("{}*", r.label)
                } else {
                    r.label.clone()
                };
                (
                    label,
                    cell.paper.filter(|v| *v > 0.0),
                    cell.ours.filter(|v| *v > 0.0),
                )
            })
            .filter(|(_, p, o)| p.is_some() || o.is_some())
            .collect();
        if !bars.iter().any(|(_, p, _)| p.is_some()) || !bars.iter().any(|(_, _, o)| o.is_some()) {
            continue;
        }
        let name = format!("{}_{}.png", c.key, crate::results::names::slug(&m.name));
        let path = dir.join(&name);
        let title = format!("{} — {}", c.title, m.name);
        crate::plot::paper_bars::draw(&path, &title, &m.name, &bars)
            .with_context(|| format!("writing {}", path.display()))?;
        written.push(name);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn comparison(exact: bool, ours: f64) -> Comparison {
        Comparison {
            key: "t".into(),
            title: "T".into(),
            conditions: "c".into(),
            metrics: vec![if exact {
                Metric::exact("ms", 1)
            } else {
                Metric::new("ms", 1)
            }],
            rows: vec![
                CompRow {
                    label: "a".into(),
                    standin: false,
                    cells: vec![Cell::new(Some(2.0), Some(ours))],
                },
                CompRow {
                    label: "b".into(),
                    standin: true,
                    cells: vec![Cell::missing(Some(3.0), "not built").uncertain(Some("x".into()))],
                },
            ],
            notes: vec![],
        }
    }

    #[test]
    fn tables_ratios_and_verdicts() {
        let md = markdown(&comparison(false, 4.0));
        assert!(md.contains("| a | 2.0 | 4.0 | 2.000 |"), "{md}");
        assert!(
            md.contains("| b (stand-in) | 3.0 ?[1] | – [2] | – |"),
            "{md}"
        );
        assert!(md.contains("[2] not built"), "{md}");
        assert_eq!(comparison(true, 2.0).verdict(), Some(true));
        assert_eq!(comparison(true, 2.5).verdict(), Some(false));
        let r = Metric::rounded("tets");
        assert!(r.agrees(2900.0, 2896.0) && r.agrees(187000.0, 187318.0));
        assert!(r.agrees(1_500_000.0, 1_500_282.0) && !r.agrees(950_000.0, 941_192.0));
        assert!(markdown(&comparison(true, 2.0)).contains("| a | 2.0 | 2.0 | matches |"));
        let html = markdown_to_html(&markdown(&comparison(false, 4.0)), "t").unwrap();
        assert!(
            html.contains("<table>") && html.contains("2.000</td>"),
            "{html}"
        );
    }

    /// Markup in a data set's name, in an image's alt text or path, lands as text.
    #[test]
    fn markup_in_a_report_lands_as_text() {
        use crate::report::html::{assert_no_live_markup, HOSTILE_NAME};
        let md = format!(
            "# Report\n\n| data set | tets |\n|---|---:|\n| {HOSTILE_NAME} | 3 |\n\n{HOSTILE_NAME}\n\n\
             ![x\" onerror=\"alert(1)](charts/a.png)\n"
        );
        let html = markdown_to_html(&md, HOSTILE_NAME).unwrap();
        assert_no_live_markup(&html);
        assert!(!html.contains("\" onerror"), "{html}");
        assert!(
            html.contains("<table>") && html.contains("<img src=\"charts/a.png\""),
            "{html}"
        );
    }

    #[test]
    fn charts_are_written() {
        let dir = tempfile::tempdir().unwrap();
        let files = write_charts(dir.path(), &comparison(false, 4.0)).unwrap();
        assert_eq!(files, vec!["t_ms.png"]);
        assert!(write_charts(dir.path(), &comparison(true, 4.0))
            .unwrap()
            .is_empty());
        assert!(
            std::fs::metadata(dir.path().join("t_ms.png"))
                .unwrap()
                .len()
                > 1000
        );
    }
}
