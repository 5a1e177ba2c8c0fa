//! Every cell of every reproduced table judged by its table's rule: the rules
//! (`reports/papers/cell_rules.csv`, written before the run and kept under the claims' rule
//! history), the one verdict of a cell ([`judge`]) and the counts the reports' headlines give
//! ([`CellCounts`]). It knows nothing of the papers or of the tables' shape: `table.rs` hands it
//! one cell at a time.

use std::sync::LazyLock;

use super::transcription::deserialize_rows;

/// The cell rules, compiled in like the claims.
pub const CELL_RULES_CSV: &str = include_str!("../../../reports/papers/cell_rules.csv");
pub const CELL_RULES_FILE: &str = "reports/papers/cell_rules.csv";

/// The rule file's columns.
pub const CELL_RULES_HEADER: &[&str] = &[
    "paper",
    "table",
    "column",
    "compare",
    "tolerance",
    "direction",
    "why",
];

/// The `column` of a rule that covers every column of its table no other line names.
pub const EVERY_OTHER_COLUMN: &str = "*";

/// How a column's cells are compared with the paper's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compare {
    /// Ours must equal the paper's (in the rule's direction).
    Exact,
    /// A count the paper prints rounded ("2.9 K"): ours rounded to the paper's significant
    /// digits must equal it.
    Rounded,
    /// Ours within a relative tolerance of the paper's (in the rule's direction).
    Relative,
    /// A time or a rate of the paper's hardware: not compared on this adapter (ours/paper shown).
    Timing,
    /// Follows from the data layout or the draw call, not measured: not compared (ours/paper
    /// shown), as a claim on such a counter is never a hold.
    Construction,
}

const COMPARE_WORDS: [(&str, Compare); 5] = [
    ("exact", Compare::Exact),
    ("rounded", Compare::Rounded),
    ("relative", Compare::Relative),
    ("timing", Compare::Timing),
    ("construction", Compare::Construction),
];

impl Compare {
    pub fn parse(text: &str) -> Result<Compare, String> {
        COMPARE_WORDS
            .iter()
            .find(|(w, _)| *w == text.trim())
            .map(|(_, c)| *c)
            .ok_or_else(|| {
                format!(
                    "compare {text:?} is not one of {}",
                    COMPARE_WORDS.map(|(w, _)| w).join(", ")
                )
            })
    }

    pub fn word(self) -> &'static str {
        COMPARE_WORDS.iter().find(|(_, c)| *c == self).unwrap().0
    }

    /// Whether the rule compares ours with the paper's at all.
    pub fn compares(self) -> bool {
        !matches!(self, Compare::Timing | Compare::Construction)
    }
}

/// Which side of the paper's value ours may lie on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    TwoSided,
    /// Ours ≤ paper (plus the tolerance).
    AtMost,
    /// Ours ≥ paper (minus the tolerance).
    AtLeast,
}

const DIRECTION_WORDS: [(&str, Direction); 3] = [
    ("two-sided", Direction::TwoSided),
    ("ours<=paper", Direction::AtMost),
    ("ours>=paper", Direction::AtLeast),
];

impl Direction {
    pub fn parse(text: &str) -> Result<Direction, String> {
        DIRECTION_WORDS
            .iter()
            .find(|(w, _)| *w == text.trim())
            .map(|(_, d)| *d)
            .ok_or_else(|| {
                format!(
                    "direction {text:?} is not one of {}",
                    DIRECTION_WORDS.map(|(w, _)| w).join(", ")
                )
            })
    }

    pub fn word(self) -> &'static str {
        DIRECTION_WORDS.iter().find(|(_, d)| *d == self).unwrap().0
    }

    /// Whether a signed difference (ours − paper, relative or absolute) lies within `tol`
    /// (a difference at the tolerance itself, up to rounding, is within).
    fn admits(self, d: f64, tol: f64) -> bool {
        let tol = tol + 1e-12;
        match self {
            Direction::TwoSided => d.abs() <= tol,
            Direction::AtMost => d <= tol,
            Direction::AtLeast => d >= -tol,
        }
    }
}

/// How a column's cells are judged: the comparison, its tolerance and direction, validated
/// together (a relative rule has a tolerance, the others none; a rule that does not compare
/// has no direction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct How {
    pub compare: Compare,
    /// Relative tolerance (`relative` only; 0 otherwise).
    pub tolerance: f64,
    pub direction: Direction,
}

impl How {
    /// From the rule file's (or the history's) three fields.
    pub fn from_fields(
        compare: &str,
        tolerance: Option<f64>,
        direction: &str,
    ) -> Result<How, String> {
        let compare = Compare::parse(compare)?;
        let direction = direction.trim();
        let tolerance = match (compare, tolerance) {
            (Compare::Relative, Some(t)) if t.is_finite() && t >= 0.0 => t,
            (Compare::Relative, t) => {
                return Err(format!(
                    "a relative rule needs a tolerance ≥ 0, not {}",
                    t.map_or("none".into(), |t| t.to_string())
                ))
            }
            (_, Some(t)) => {
                return Err(format!(
                    "tolerance {t}: only a relative rule has one ({} has none)",
                    compare.word()
                ))
            }
            (_, None) => 0.0,
        };
        let direction = match compare {
            Compare::Exact | Compare::Relative => Direction::parse(direction)?,
            Compare::Rounded if matches!(direction, "" | "two-sided") => Direction::TwoSided,
            Compare::Rounded => return Err("a rounded rule is two-sided".into()),
            _ if direction.is_empty() => Direction::TwoSided,
            _ => {
                return Err(format!(
                    "direction {direction:?}: a {} rule compares nothing",
                    compare.word()
                ))
            }
        };
        Ok(How {
            compare,
            tolerance,
            direction,
        })
    }

    /// Whether ours agrees with the paper's under this rule (`false` for a rule that does not
    /// compare).
    pub fn agrees(&self, paper: f64, ours: f64) -> bool {
        match self.compare {
            Compare::Exact => self.direction.admits(ours - paper, 0.0),
            Compare::Rounded => round_sig(ours, significant_digits(paper)) == paper,
            Compare::Relative => self.direction.admits(relative(paper, ours), self.tolerance),
            Compare::Timing | Compare::Construction => false,
        }
    }

    /// `exact, two-sided`, `relative 2 %, ours<=paper`, `timing`.
    pub fn describe(&self) -> String {
        match self.compare {
            Compare::Relative => format!(
                "relative {} %, {}",
                self.tolerance * 100.0,
                self.direction.word()
            ),
            Compare::Exact => format!("exact, {}", self.direction.word()),
            c => c.word().to_string(),
        }
    }
}

/// (ours − paper) / paper; a paper's zero admits only a zero.
pub fn relative(paper: f64, ours: f64) -> f64 {
    if paper != 0.0 {
        ours / paper - 1.0
    } else if ours == 0.0 {
        0.0
    } else {
        f64::INFINITY.copysign(ours)
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

/// One line of the rule file: the rule of one column of one table (or of every other column,
/// [`EVERY_OTHER_COLUMN`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CellRule {
    pub paper: String,
    /// The table's key (`table2`, `memory`).
    pub table: String,
    /// The column's name as the table prints it.
    pub column: String,
    pub how: How,
    /// Why this rule: written with it, printed with the table.
    pub why: String,
}

#[derive(serde::Deserialize)]
struct Record {
    paper: String,
    table: String,
    column: String,
    compare: String,
    tolerance: Option<f64>,
    direction: String,
    why: String,
}

/// Parses a rule file; an error names the file, the line and what is wrong.
pub fn parse_rules(text: &str, file: &str) -> anyhow::Result<Vec<CellRule>> {
    let mut out: Vec<CellRule> = vec![];
    for (line, r) in deserialize_rows::<Record>(text, file, CELL_RULES_HEADER)? {
        let err = |what: String| anyhow::anyhow!("{file}: line {line}: {what}");
        for (name, value) in [
            ("paper", &r.paper),
            ("table", &r.table),
            ("column", &r.column),
            ("why", &r.why),
        ] {
            if value.is_empty() {
                return Err(err(format!("{name} is empty")));
            }
        }
        let how = How::from_fields(&r.compare, r.tolerance, &r.direction).map_err(err)?;
        if out
            .iter()
            .any(|o| o.paper == r.paper && o.table == r.table && o.column == r.column)
        {
            return Err(err(format!(
                "{} {} {:?} has a rule already",
                r.paper, r.table, r.column
            )));
        }
        out.push(CellRule {
            paper: r.paper,
            table: r.table,
            column: r.column,
            how,
            why: r.why,
        });
    }
    Ok(out)
}

static RULES: LazyLock<Vec<CellRule>> = LazyLock::new(|| {
    parse_rules(CELL_RULES_CSV, CELL_RULES_FILE)
        .expect("reports/papers/cell_rules.csv parses (tested)")
});

/// Every rule of the compiled-in file.
pub fn rules() -> &'static [CellRule] {
    &RULES
}

/// The rule of a column: the line naming it, else its table's [`EVERY_OTHER_COLUMN`] line.
pub fn rule_for<'a>(
    rules: &'a [CellRule],
    paper: &str,
    table: &str,
    column: &str,
) -> Option<&'a CellRule> {
    let of_table = || {
        rules
            .iter()
            .filter(|r| r.paper == paper && r.table == table)
    };
    of_table()
        .find(|r| r.column == column)
        .or_else(|| of_table().find(|r| r.column == EVERY_OTHER_COLUMN))
}

/// Why a cell the paper prints was not compared.
#[derive(Debug, Clone, PartialEq)]
pub enum NotCompared {
    /// A timing column ([`Compare::Timing`]).
    OnThisAdapter,
    /// Follows from the layout or the draw call ([`Compare::Construction`]).
    ByConstruction,
    /// Measured on a generated stand-in, not the paper's data.
    StandIn,
    /// Ours has no value (why).
    NoValue(String),
    /// No line of the rule file covers the column.
    NoRule,
}

/// A cell's verdict under its rule.
#[derive(Debug, Clone, PartialEq)]
pub enum CellVerdict {
    Within,
    Outside,
    NotCompared(NotCompared),
}

impl CellVerdict {
    /// The verdict as a table prints it.
    pub fn label(&self) -> String {
        match self {
            CellVerdict::Within => "within the rule".into(),
            CellVerdict::Outside => "outside the rule".into(),
            CellVerdict::NotCompared(n) => match n {
                NotCompared::OnThisAdapter => "not compared on this adapter".into(),
                NotCompared::ByConstruction => "not compared (by construction)".into(),
                NotCompared::StandIn => "not compared (stand-in)".into(),
                NotCompared::NoValue(_) => "not compared (no value of ours)".into(),
                NotCompared::NoRule => format!("not compared (no rule in {CELL_RULES_FILE})"),
            },
        }
    }
}

/// The verdict of one cell the paper prints (`None`: the paper prints none, so it is no cell
/// of the paper's). Order: the rule's kind, then stand-in rows, then a missing value of ours,
/// then the comparison.
pub fn judge(
    rule: Option<&How>,
    standin: bool,
    paper: Option<f64>,
    ours: Option<f64>,
    why_no_ours: Option<&str>,
) -> Option<CellVerdict> {
    let paper = paper.filter(|p| p.is_finite())?;
    let not = |n| Some(CellVerdict::NotCompared(n));
    let Some(how) = rule else {
        return not(NotCompared::NoRule);
    };
    match how.compare {
        Compare::Timing => return not(NotCompared::OnThisAdapter),
        Compare::Construction => return not(NotCompared::ByConstruction),
        _ => {}
    }
    if standin {
        return not(NotCompared::StandIn);
    }
    let Some(ours) = ours.filter(|o| o.is_finite()) else {
        return not(NotCompared::NoValue(
            why_no_ours.unwrap_or("not measured").to_string(),
        ));
    };
    Some(if how.agrees(paper, ours) {
        CellVerdict::Within
    } else {
        CellVerdict::Outside
    })
}

/// How many cells took each verdict: the headline's count of cells, typed (`summary.json`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct CellCounts {
    pub within: usize,
    pub outside: usize,
    /// Timing cells, counted apart.
    pub on_this_adapter: usize,
    pub by_construction: usize,
    pub stand_in: usize,
    pub no_value: usize,
    pub no_rule: usize,
}

impl CellCounts {
    pub fn add(&mut self, v: &CellVerdict) {
        match v {
            CellVerdict::Within => self.within += 1,
            CellVerdict::Outside => self.outside += 1,
            CellVerdict::NotCompared(n) => match n {
                NotCompared::OnThisAdapter => self.on_this_adapter += 1,
                NotCompared::ByConstruction => self.by_construction += 1,
                NotCompared::StandIn => self.stand_in += 1,
                NotCompared::NoValue(_) => self.no_value += 1,
                NotCompared::NoRule => self.no_rule += 1,
            },
        }
    }

    pub fn merge(&mut self, o: &CellCounts) {
        self.within += o.within;
        self.outside += o.outside;
        self.on_this_adapter += o.on_this_adapter;
        self.by_construction += o.by_construction;
        self.stand_in += o.stand_in;
        self.no_value += o.no_value;
        self.no_rule += o.no_rule;
    }

    /// `3 of 8 cells within the rule; not compared: 12 on this adapter (timings), 5 on
    /// stand-ins`.
    pub fn headline(&self) -> String {
        let mut s = format!(
            "{} of {} cells within the rule",
            self.within,
            self.within + self.outside
        );
        let apart: Vec<String> = [
            (self.on_this_adapter, "on this adapter (timings)"),
            (self.by_construction, "by construction"),
            (self.stand_in, "on stand-ins"),
            (self.no_value, "without a value of ours"),
            (self.no_rule, "without a rule"),
        ]
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, w)| format!("{n} {w}"))
        .collect();
        if !apart.is_empty() {
            s.push_str(&format!("; not compared: {}", apart.join(", ")));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "paper,table,column,compare,tolerance,direction,why\n";

    fn how(compare: &str, tol: Option<f64>, dir: &str) -> How {
        How::from_fields(compare, tol, dir).unwrap()
    }

    #[test]
    fn the_compiled_in_rules_parse() {
        assert!(!rules().is_empty());
    }

    /// A bad line fails the load naming the file, the line and what is wrong.
    #[test]
    fn a_bad_rule_line_fails_naming_the_line() {
        let good = "havs,table2,fragments,exact,,two-sided,counts\n";
        assert_eq!(
            parse_rules(&format!("{HEAD}{good}"), "r.csv")
                .unwrap()
                .len(),
            1
        );
        for (bad, what) in [
            (
                "havs,table2,max k,exactly,,two-sided,x\n",
                "compare \"exactly\"",
            ),
            (
                "havs,table2,max k,relative,,two-sided,x\n",
                "needs a tolerance",
            ),
            (
                "havs,table2,max k,relative,-1,two-sided,x\n",
                "needs a tolerance",
            ),
            (
                "havs,table2,max k,exact,0.1,two-sided,x\n",
                "only a relative rule",
            ),
            (
                "havs,table2,max k,exact,,sideways,x\n",
                "direction \"sideways\"",
            ),
            (
                "havs,table2,max k,timing,,two-sided,x\n",
                "compares nothing",
            ),
            ("havs,table2,max k,rounded,,ours<=paper,x\n", "two-sided"),
            ("havs,table2,max k,exact,,two-sided,\n", "why is empty"),
            (
                "havs,table2,fragments,exact,,two-sided,again\n",
                "has a rule already",
            ),
            (
                "havs,table2,max k,relative,lots,two-sided,x\n",
                "column tolerance",
            ),
        ] {
            let e = parse_rules(&format!("{HEAD}{good}{bad}"), "r.csv")
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("r.csv: line 3:") && e.contains(what),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn rules_agree_by_kind_and_direction() {
        let r = how("rounded", None, "");
        assert!(r.agrees(2900.0, 2896.0) && r.agrees(187000.0, 187318.0));
        assert!(r.agrees(1_500_000.0, 1_500_282.0) && !r.agrees(950_000.0, 941_192.0));
        let two = how("relative", Some(0.02), "two-sided");
        assert!(two.agrees(100.0, 98.0) && two.agrees(100.0, 102.0) && !two.agrees(100.0, 97.0));
        let le = how("relative", Some(0.02), "ours<=paper");
        assert!(le.agrees(100.0, 50.0) && le.agrees(100.0, 102.0) && !le.agrees(100.0, 103.0));
        let ge = how("exact", None, "ours>=paper");
        assert!(ge.agrees(5.0, 5.0) && ge.agrees(5.0, 9.0) && !ge.agrees(5.0, 4.0));
        assert!(how("relative", Some(0.1), "two-sided").agrees(0.0, 0.0));
        assert!(!how("relative", Some(0.1), "two-sided").agrees(0.0, 1.0));
        assert!(!how("timing", None, "").agrees(1.0, 1.0));
    }

    /// The verdict of a cell flips with its measured value; the rule's kind, a stand-in row
    /// and a missing value each take the cell out of the comparison, with the reason.
    #[test]
    fn a_cells_verdict_flips_with_its_value() {
        let exact = how("exact", None, "two-sided");
        let v = |ours| judge(Some(&exact), false, Some(512.0), ours, None);
        assert_eq!(v(Some(512.0)), Some(CellVerdict::Within));
        assert_eq!(v(Some(314.0)), Some(CellVerdict::Outside));
        assert_eq!(
            v(None),
            Some(CellVerdict::NotCompared(NotCompared::NoValue(
                "not measured".into()
            )))
        );
        assert_eq!(judge(Some(&exact), false, None, Some(1.0), None), None);
        assert_eq!(
            judge(Some(&exact), true, Some(512.0), Some(314.0), None),
            Some(CellVerdict::NotCompared(NotCompared::StandIn))
        );
        let timing = how("timing", None, "");
        assert_eq!(
            judge(Some(&timing), true, Some(3.0), Some(1.0), None),
            Some(CellVerdict::NotCompared(NotCompared::OnThisAdapter))
        );
        assert_eq!(
            judge(None, false, Some(3.0), Some(3.0), None),
            Some(CellVerdict::NotCompared(NotCompared::NoRule))
        );
        let mut n = CellCounts::default();
        for v in [v(Some(512.0)), v(Some(314.0)), v(None)].iter().flatten() {
            n.add(v);
        }
        assert_eq!(
            n.headline(),
            "1 of 2 cells within the rule; not compared: 1 without a value of ours"
        );
    }

    #[test]
    fn a_column_without_its_own_line_takes_the_tables_other_columns_rule() {
        let rules = parse_rules(
            &format!(
                "{HEAD}havs,table3,tets,exact,,two-sided,a count\nhavs,table3,*,timing,,,times\n"
            ),
            "r.csv",
        )
        .unwrap();
        assert_eq!(
            rule_for(&rules, "havs", "table3", "tets")
                .unwrap()
                .how
                .compare,
            Compare::Exact
        );
        assert_eq!(
            rule_for(&rules, "havs", "table3", "k=2 fps")
                .unwrap()
                .how
                .compare,
            Compare::Timing
        );
        assert!(rule_for(&rules, "havs", "table4", "fps").is_none());
    }
}
