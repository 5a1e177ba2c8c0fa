//! What every paper's report is made of: comparison tables (paper | ours | each cell's verdict
//! under its column's rule, or ours/paper where the rule does not compare), their Markdown, HTML
//! and bar charts. The paper's claims and their verdicts are [`crate::papers::claims`].

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;

use super::cells::{self, CellCounts, CellRule, CellVerdict, NotCompared};
use super::transcription::PaperTable;

/// One metric (column group) of a comparison table. How its cells are judged is its rule in
/// `reports/papers/cell_rules.csv` ([`super::cells`]), found by the paper, the table's key and
/// this name.
#[derive(Debug, Clone)]
pub struct Metric {
    pub name: String,
    /// Digits after the decimal point when printed.
    pub digits: usize,
}

impl Metric {
    pub fn new(name: impl Into<String>, digits: usize) -> Metric {
        Metric {
            name: name.into(),
            digits,
        }
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
    /// Keeps `why` as the reason where ours is missing.
    pub fn missing_because(mut self, why: &str) -> Cell {
        self.why_no_ours = self.ours.is_none().then(|| why.to_string());
        self
    }
    pub fn ratio(&self) -> Option<f64> {
        match (self.paper, self.ours) {
            (Some(p), Some(o)) if p != 0.0 && p.is_finite() && o.is_finite() => Some(o / p),
            _ => None,
        }
    }
}

/// One row of a paper's transcribed table and why ours may be missing on it: each of its cells
/// pairs the paper's value in a column (with the transcription's doubt about it) with ours.
pub struct PaperRow<'t> {
    pub table: &'t PaperTable,
    pub key: &'t str,
    pub why: String,
}

impl<'t> PaperRow<'t> {
    pub fn new(table: &'t PaperTable, key: &'t str, why: String) -> PaperRow<'t> {
        PaperRow { table, key, why }
    }

    /// The paper's value in `column` beside `ours`.
    pub fn cell(&self, column: &str, ours: Option<f64>) -> Cell {
        Cell::new(self.table.value(self.key, column), ours)
            .missing_because(&self.why)
            .uncertain(self.table.uncertain(self.key, column))
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

impl CompRow {
    /// A row of one method of a comparison: `label (algorithm settings)`, or the label alone
    /// where no tetbench algorithm implements the method.
    pub fn method(
        label: &str,
        algorithm: Option<&str>,
        settings: Option<&str>,
        cells: Vec<Cell>,
    ) -> CompRow {
        let label = match (algorithm, settings) {
            (Some(a), Some(s)) => format!("{label} ({a} {s})"),
            (Some(a), None) => format!("{label} ({a})"),
            (None, _) => label.to_string(),
        };
        CompRow {
            label,
            standin: false,
            cells,
        }
    }

    /// A row measured on `dataset`, marked where that is a generated stand-in.
    pub fn on(label: impl Into<String>, dataset: &str, cells: Vec<Cell>) -> CompRow {
        CompRow {
            label: label.into(),
            standin: datasets::standins::is_generated(dataset),
            cells,
        }
    }
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

/// A table's cells judged by their rules (`reports/papers/cell_rules.csv`, [`cells`]): the
/// one judging of every paper's tables, which the table's verdict columns, its counts and the
/// report's findings read.
pub struct Judged<'a, 'r> {
    pub comparison: &'a Comparison,
    /// Per metric, its rule (`None`: no line of the file covers it).
    pub rules: Vec<Option<&'r CellRule>>,
    /// Per row, per metric: the verdict (`None`: the paper prints no value there).
    pub verdicts: Vec<Vec<Option<CellVerdict>>>,
}

impl Comparison {
    /// Its cells judged by the compiled-in rules of `paper`.
    pub fn judge(&self, paper: &str) -> Judged<'_, 'static> {
        self.judge_with(cells::rules(), paper)
    }

    /// Its cells judged by `rules`.
    pub fn judge_with<'r>(&self, rules: &'r [CellRule], paper: &str) -> Judged<'_, 'r> {
        let rules: Vec<Option<&CellRule>> = self
            .metrics
            .iter()
            .map(|m| cells::rule_for(rules, paper, &self.key, &m.name))
            .collect();
        let verdicts = self
            .rows
            .iter()
            .map(|r| {
                rules
                    .iter()
                    .zip(&r.cells)
                    .map(|(rule, c)| {
                        let how = rule.map(|r| &r.how);
                        cells::judge(how, r.standin, c.paper, c.ours, c.why_no_ours.as_deref())
                    })
                    .collect()
            })
            .collect();
        Judged {
            comparison: self,
            rules,
            verdicts,
        }
    }
}

impl Judged<'_, '_> {
    /// How many of its cells took each verdict.
    pub fn counts(&self) -> CellCounts {
        let mut n = CellCounts::default();
        for v in self.verdicts.iter().flatten().flatten() {
            n.add(v);
        }
        n
    }

    /// The table's line for the index: `table2: 1 of 5 cells within the rule; …`.
    pub fn summary(&self) -> String {
        format!("{}: {}", self.comparison.key, self.counts().headline())
    }

    /// Each cell outside its rule, as one line: where, both values, the difference, the rule,
    /// and its explanation (none is measured in the code yet: "unexplained").
    pub fn findings(&self) -> Vec<String> {
        let c = self.comparison;
        let mut out = vec![];
        for (row, verdicts) in c.rows.iter().zip(&self.verdicts) {
            for (i, v) in verdicts.iter().enumerate() {
                if *v != Some(CellVerdict::Outside) {
                    continue;
                }
                let (m, cell) = (&c.metrics[i], &row.cells[i]);
                let (paper, ours) = (cell.paper.unwrap_or(0.0), cell.ours.unwrap_or(0.0));
                let rule = self.rules[i].map_or(String::new(), |r| r.how.describe());
                out.push(format!(
                    "{} {}, {}: ours {}, paper {} ({}); rule {rule}: unexplained",
                    c.key,
                    row.label,
                    m.name,
                    num(Some(ours), m.digits),
                    num(Some(paper), m.digits),
                    difference(paper, ours)
                ));
            }
        }
        out
    }

    /// Whether column `i`'s rule compares (a timing or a layout column does not, and shows
    /// ours/paper instead; a column without a rule shows that it has none).
    fn compares(&self, i: usize) -> bool {
        self.rules[i].is_none_or(|r| r.how.compare.compares())
    }

    /// `fragments, max A: exact, two-sided (why); …` for the columns under each rule.
    fn rules_sentence(&self) -> String {
        let mut groups: Vec<(&CellRule, Vec<&str>)> = vec![];
        for (m, r) in self.comparison.metrics.iter().zip(&self.rules) {
            let Some(r) = r else { continue };
            match groups.iter_mut().find(|(g, _)| std::ptr::eq(*g, *r)) {
                Some((_, cols)) => cols.push(&m.name),
                None => groups.push((r, vec![&m.name])),
            }
        }
        groups
            .iter()
            .map(|(r, cols)| format!("{}: {} ({})", cols.join(", "), r.how.describe(), r.why))
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// `−38.7 %` (or the absolute difference where the paper's value is 0).
fn difference(paper: f64, ours: f64) -> String {
    if paper != 0.0 {
        format!("{:+.1} %", cells::relative(paper, ours) * 100.0)
    } else {
        format!("{:+}", ours - paper)
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

/// A compared cell's verdict as the table prints it.
fn verdict_text(v: Option<&CellVerdict>, c: &Cell) -> String {
    match v {
        Some(CellVerdict::Within) => "within".into(),
        Some(CellVerdict::Outside) => match (c.paper, c.ours) {
            (Some(p), Some(o)) => format!("outside ({})", difference(p, o)),
            _ => "outside".into(),
        },
        Some(CellVerdict::NotCompared(NotCompared::StandIn)) => "stand-in".into(),
        Some(CellVerdict::NotCompared(NotCompared::NoRule)) => "no rule".into(),
        _ => "–".into(),
    }
}

/// The table as Markdown: per metric the paper's value, ours, and the cell's verdict under
/// its rule (or ours/paper for a column the rule does not compare), then the counts, the
/// rules, and the footnotes (stand-ins, uncertain cells, missing values).
pub fn markdown(j: &Judged) -> String {
    let c = j.comparison;
    let mut md = format!("### {}\n\n{}\n\n", c.title, c.conditions);
    let mut head = String::from("| row |");
    let mut rule = String::from("|---|");
    for (i, m) in c.metrics.iter().enumerate() {
        let third = if j.compares(i) {
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
    for (r, verdicts) in c.rows.iter().zip(&j.verdicts) {
        let label = if r.standin {
            format!("{} (stand-in)", r.label)
        } else {
            r.label.clone()
        };
        let _ = write!(md, "| {label} |");
        for (i, (m, cell)) in c.metrics.iter().zip(&r.cells).enumerate() {
            let mut p = num(cell.paper, m.digits);
            if let Some(u) = &cell.uncertain {
                p.push_str(&format!(" ?{}", mark(format!("uncertain: {u}"))));
            }
            let mut o = num(cell.ours, m.digits);
            if let Some(w) = &cell.why_no_ours {
                o.push_str(&format!(" {}", mark(w.clone())));
            }
            let t = if j.compares(i) {
                verdict_text(verdicts[i].as_ref(), cell)
            } else {
                ratio_text(cell)
            };
            let _ = write!(md, " {p} | {o} | {t} |");
        }
        md.push('\n');
    }
    let _ = writeln!(
        md,
        "\nCells: {}. Rules (`{}`): {}.",
        j.counts().headline(),
        cells::CELL_RULES_FILE,
        j.rules_sentence()
    );
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
pub fn write_charts(dir: &Path, j: &Judged) -> anyhow::Result<Vec<String>> {
    let c = j.comparison;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut written = vec![];
    for (mi, m) in c.metrics.iter().enumerate() {
        // Columns the rule compares (counts, truth values) are judged in the table, not charted.
        if j.compares(mi) {
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

    /// One rule for column `ms` of table `t` of paper `p`.
    fn rules(compare: &str) -> Vec<CellRule> {
        let how = match compare {
            "exact" => "exact,,two-sided",
            "relative" => "relative,0.1,two-sided",
            _ => "timing,,",
        };
        cells::parse_rules(
            &format!("paper,table,column,compare,tolerance,direction,why\np,t,ms,{how},why not\n"),
            "r.csv",
        )
        .unwrap()
    }

    fn comparison(ours: f64) -> Comparison {
        Comparison {
            key: "t".into(),
            title: "T".into(),
            conditions: "c".into(),
            metrics: vec![Metric::new("ms", 1)],
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
        let timing = rules("timing");
        let md = markdown(&comparison(4.0).judge_with(&timing, "p"));
        assert!(md.contains("| a | 2.0 | 4.0 | 2.000 |"), "{md}");
        assert!(
            md.contains("| b (stand-in) | 3.0 ?[1] | – [2] | – |"),
            "{md}"
        );
        assert!(md.contains("[2] not built"), "{md}");
        assert!(
            md.contains("Cells: 0 of 0 cells within the rule; not compared: 2 on this adapter (timings). Rules (`reports/papers/cell_rules.csv`): ms: timing (why not)."),
            "{md}"
        );
        let exact = rules("exact");
        assert!(markdown(&comparison(2.0).judge_with(&exact, "p"))
            .contains("| a | 2.0 | 2.0 | within |"));
        // A table of another paper or key has no rule here: its cells say so.
        let none = comparison(2.0);
        let j = none.judge_with(&exact, "q");
        assert_eq!(j.counts().no_rule, 2);
        assert!(markdown(&j).contains("| a | 2.0 | 2.0 | no rule |"));
        let html = markdown_to_html(&md, "t").unwrap();
        assert!(
            html.contains("<table>") && html.contains("2.000</td>"),
            "{html}"
        );
    }

    /// One measured value changed: the cell's verdict, the table's count and its finding flip.
    #[test]
    fn a_changed_value_flips_the_cell_and_the_count() {
        let exact = rules("exact");
        let (same, off) = (comparison(2.0), comparison(2.5));
        let (same, off) = (same.judge_with(&exact, "p"), off.judge_with(&exact, "p"));
        assert_eq!(same.verdicts[0][0], Some(CellVerdict::Within));
        assert_eq!(off.verdicts[0][0], Some(CellVerdict::Outside));
        // The stand-in row is not compared, with its reason, in both.
        assert_eq!(
            off.verdicts[1][0],
            Some(CellVerdict::NotCompared(NotCompared::StandIn))
        );
        assert_eq!(
            same.summary(),
            "t: 1 of 1 cells within the rule; not compared: 1 on stand-ins"
        );
        assert_eq!(
            off.summary(),
            "t: 0 of 1 cells within the rule; not compared: 1 on stand-ins"
        );
        assert!(same.findings().is_empty());
        assert_eq!(
            off.findings(),
            ["t a, ms: ours 2.5, paper 2.0 (+25.0 %); rule exact, two-sided: unexplained"]
        );
        assert!(markdown(&off).contains("| a | 2.0 | 2.5 | outside (+25.0 %) |"));
        // Within a relative tolerance of 10 %, 2.1 holds and 2.5 does not.
        let rel = rules("relative");
        assert_eq!(comparison(2.1).judge_with(&rel, "p").counts().within, 1);
        assert_eq!(comparison(2.5).judge_with(&rel, "p").counts().outside, 1);
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
        let (timing, exact, c) = (rules("timing"), rules("exact"), comparison(4.0));
        let files = write_charts(dir.path(), &c.judge_with(&timing, "p")).unwrap();
        assert_eq!(files, vec!["t_ms.png"]);
        assert!(write_charts(dir.path(), &c.judge_with(&exact, "p"))
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
