//! A claim's rule and its history: what it compares and how it decides (metric, data sets,
//! sides, expectation, tolerance, evidence kind, normalisation), and every earlier rule with
//! the date, the commit and the reason it changed (`reports/papers/rule_history.csv`,
//! docs/reproduction.md, "Rules and their history"). The same history holds the changes of
//! the table cells' rules (`reports/papers/cell_rules.csv`, [`super::cells`]): such a row's id
//! is `TABLE:COLUMN` and it fills `old_compare`, `old_tolerance` and `old_direction` only.

use super::cells::How;
use super::spec::{Discriminates, ExpectSpec, Metric, VariantSpec};
use super::transcription::deserialize_rows;
use super::verdict;

/// The rule history, compiled in like the claims.
pub const RULE_HISTORY_CSV: &str = include_str!("../../../reports/papers/rule_history.csv");
pub const HISTORY_FILE: &str = "reports/papers/rule_history.csv";

/// The history's columns.
pub const HISTORY_HEADER: &[&str] = &[
    "paper",
    "id",
    "date",
    "commit",
    "reason",
    "old_id",
    "old_metric",
    "old_datasets",
    "old_a",
    "old_b",
    "old_expect",
    "old_tolerance",
    "old_evidence",
    "old_normalise",
    "old_discriminates",
    "old_control",
    "old_compare",
    "old_direction",
];

/// The `paper` and `id` of a history row that changes the verdict rule itself, for every
/// claim of a kind (the frames a timing needs), not one claim's rule.
pub const EVERY_CLAIM: &str = "*";

/// What a claim's evidence is: only a measurement can make a claim hold.
#[derive(Debug, Clone, PartialEq, Eq, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum Evidence {
    /// An outcome the code produces and could get wrong.
    Measured,
    /// An input chosen to equal the paper's (a stand-in's counts, a fixed layout constant):
    /// checked, but it cannot fail unless the construction is broken.
    ByConstruction,
    /// Arithmetic on other claims' numbers (their ids).
    Derived(Vec<String>),
}

impl TryFrom<String> for Evidence {
    type Error = String;
    fn try_from(s: String) -> Result<Evidence, String> {
        Evidence::parse(&s)
    }
}

impl Evidence {
    pub fn parse(text: &str) -> Result<Evidence, String> {
        match text.trim() {
            "measured" => Ok(Evidence::Measured),
            "construction" => Ok(Evidence::ByConstruction),
            t => match t.strip_prefix("derived:") {
                Some(ids) if !ids.trim().is_empty() => Ok(Evidence::Derived(
                    ids.split('+').map(|s| s.trim().to_string()).collect(),
                )),
                _ => Err(format!(
                    "evidence {t:?} is not measured, construction or derived:ID[+ID…]"
                )),
            },
        }
    }

    /// The word of the kind, as reports list it.
    pub fn label(&self) -> String {
        match self {
            Evidence::Measured => "measured".into(),
            Evidence::ByConstruction => "by construction".into(),
            Evidence::Derived(ids) => format!("derived from {}", ids.join(", ")),
        }
    }

    /// The word a verdict takes for this kind: a measured claim *holds*; one by construction
    /// is *as constructed*; a derived one *follows*. Verdicts that decide nothing (noise, too
    /// few frames, not discriminating, not testable, not checkable) keep their word.
    pub fn word(&self, v: verdict::Verdict) -> &'static str {
        use verdict::Verdict::*;
        match (self, v) {
            (Evidence::Measured, v) => v.label(),
            (Evidence::ByConstruction, Holds) => "as constructed",
            (Evidence::ByConstruction, DoesNotHold) => "not as constructed",
            (Evidence::Derived(_), Holds) => "follows",
            (Evidence::Derived(_), DoesNotHold) => "does not follow",
            (_, v) => v.label(),
        }
    }
}

/// How a rate measured on the paper's GPU is compared across hardware (see
/// docs/reproduction.md, "Across hardware").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum Normalise {
    /// Compared as measured.
    None,
    /// A rate of the paper's GPU judged relative to the fill rate: the paper's figure is
    /// scaled by our calibrated fill rate over its GPU's published one
    /// (`reports/papers/hardware.csv`). A GPU claim so normalised is judged on any adapter,
    /// a software rasteriser included: its calibration measures the same cores it renders on.
    Fill,
}

impl TryFrom<String> for Normalise {
    type Error = String;
    fn try_from(s: String) -> Result<Normalise, String> {
        Normalise::parse(&s)
    }
}

impl Normalise {
    pub fn parse(text: &str) -> Result<Normalise, String> {
        match text.trim() {
            "none" | "" => Ok(Normalise::None),
            "fill" => Ok(Normalise::Fill),
            t => Err(format!("normalise {t:?} is not none or fill")),
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Normalise::None => "none",
            Normalise::Fill => "fill rate",
        }
    }
}

/// A claim's rule: what it compares and how it decides, as written.
#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    pub metric: Metric,
    /// One verdict per data set; empty: one verdict (sides pinned with `@` or no data set).
    pub datasets: Vec<String>,
    pub a: VariantSpec,
    pub b: Option<VariantSpec>,
    pub expect: ExpectSpec,
    pub expect_text: String,
    pub tolerance: f64,
    pub evidence: Evidence,
    pub normalise: Normalise,
    /// Where the two sides can differ at all (`None`: everywhere).
    pub discriminates: Option<Discriminates>,
    /// The positive control: a known perturbation that replaces side `a` and that the rule
    /// must reject (`None`: none).
    pub control: Option<VariantSpec>,
}

impl Rule {
    /// The decision part: expectation, tolerance, normalisation and, for a timed metric, the
    /// frames it needs.
    pub fn describe(&self) -> String {
        let mut s = format!("`{}`", self.expect_text);
        if self.tolerance > 0.0 {
            s.push_str(&format!(", tolerance {}", self.tolerance));
        }
        if self.normalise != Normalise::None {
            s.push_str(&format!(", normalised by {}", self.normalise.label()));
        }
        if self.metric.is_timed() {
            s.push_str(&format!(
                ", decided only on at least {} frames a side beyond their spread",
                verdict::MIN_FRAMES
            ));
        }
        if let Some(d) = &self.discriminates {
            s.push_str(&format!(", not discriminating where `{d}` fails"));
        }
        if let Some(c) = &self.control {
            s.push_str(&format!(
                ", positive control `{c}` as side a must not hold (else insensitive)"
            ));
        }
        s
    }

    /// [`Rule::describe`] plus whatever of metric, data sets, sides and evidence differs from
    /// `now` (an earlier rule beside the current one).
    pub fn describe_against(&self, now: &Rule) -> String {
        let mut s = self.describe();
        if self.metric != now.metric {
            s.push_str(&format!(", metric `{}`", self.metric));
        }
        if self.datasets != now.datasets {
            s.push_str(&format!(", data sets {}", datasets_text(&self.datasets)));
        }
        if self.a != now.a {
            s.push_str(&format!(", side a `{}`", self.a));
        }
        if self.b != now.b {
            let b = self
                .b
                .as_ref()
                .map_or("none".to_string(), |b| b.to_string());
            s.push_str(&format!(", side b `{b}`"));
        }
        if self.evidence != now.evidence {
            s.push_str(&format!(", evidence {}", self.evidence.label()));
        }
        if self.discriminates.is_none() && now.discriminates.is_some() {
            s.push_str(", judged on every data set");
        }
        if self.control.is_none() && now.control.is_some() {
            s.push_str(", no positive control");
        }
        s
    }
}

fn datasets_text(d: &[String]) -> String {
    if d.is_empty() {
        "none".into()
    } else {
        d.join(";")
    }
}

/// Splits a `datasets` cell (`a;b;c`).
pub fn split_datasets(text: &str) -> Vec<String> {
    text.split(';')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect()
}

/// An earlier rule of a claim, replaced on `date` at `commit` for `reason`. A row naming
/// [`EVERY_CLAIM`] changed the verdict rule itself and has no old rule of one claim.
#[derive(Debug, Clone, PartialEq)]
pub struct RuleChange {
    pub paper: String,
    pub id: String,
    pub date: String,
    pub commit: String,
    pub reason: String,
    /// The id the claim had before (`None`: the same).
    pub old_id: Option<String>,
    pub old: Option<Rule>,
    /// A cell rule's earlier rule (its id is `TABLE:COLUMN`); `None` for a claim's row.
    pub old_cell: Option<How>,
}

impl RuleChange {
    pub fn is_verdict_rule(&self) -> bool {
        self.paper == EVERY_CLAIM
    }

    /// Whether it changed a table cell rule, not a claim's.
    pub fn is_cell_rule(&self) -> bool {
        self.old_cell.is_some()
    }
}

#[derive(serde::Deserialize)]
struct HistoryRecord {
    paper: String,
    id: String,
    date: String,
    commit: String,
    reason: String,
    old_id: Option<String>,
    old_metric: Option<Metric>,
    old_datasets: String,
    old_a: Option<VariantSpec>,
    old_b: Option<VariantSpec>,
    old_expect: String,
    old_tolerance: Option<f64>,
    old_evidence: Option<Evidence>,
    old_normalise: Normalise,
    old_discriminates: Option<Discriminates>,
    old_control: Option<VariantSpec>,
    old_compare: String,
    old_direction: String,
}

/// Parses a rule history; errors name the file, the line and what is wrong.
pub fn parse_history(text: &str, file: &str) -> anyhow::Result<Vec<RuleChange>> {
    let mut out = vec![];
    for (line, r) in deserialize_rows::<HistoryRecord>(text, file, HISTORY_HEADER)? {
        let err = |what: String| anyhow::anyhow!("{file}: line {line}: {what}");
        for (name, value) in [
            ("paper", &r.paper),
            ("id", &r.id),
            ("date", &r.date),
            ("commit", &r.commit),
            ("reason", &r.reason),
        ] {
            if value.is_empty() {
                return Err(err(format!("{name} is empty")));
            }
        }
        let claim_fields = r.old_metric.is_some()
            || r.old_a.is_some()
            || !r.old_expect.is_empty()
            || r.old_evidence.is_some()
            || r.old_discriminates.is_some()
            || r.old_control.is_some();
        let old_cell = if r.old_compare.is_empty() {
            if !r.old_direction.is_empty() {
                return Err(err("old_direction without old_compare".into()));
            }
            None
        } else {
            if claim_fields || !r.id.contains(':') {
                return Err(err(format!(
                    "a cell rule's change (old_compare {:?}) names its TABLE:COLUMN as id and fills only old_compare, old_tolerance and old_direction",
                    r.old_compare
                )));
            }
            Some(How::from_fields(&r.old_compare, r.old_tolerance, &r.old_direction).map_err(err)?)
        };
        let old = if old_cell.is_some() {
            None
        } else if r.paper == EVERY_CLAIM {
            if claim_fields || r.old_tolerance.is_some() || r.id != EVERY_CLAIM {
                return Err(err(format!(
                    "a change of the verdict rule ({EVERY_CLAIM},{EVERY_CLAIM}) has no old rule of one claim"
                )));
            }
            None
        } else {
            let need = |name: &str| err(format!("{name} is empty"));
            Some(Rule {
                metric: r.old_metric.ok_or_else(|| need("old_metric"))?,
                datasets: split_datasets(&r.old_datasets),
                a: r.old_a.ok_or_else(|| need("old_a"))?,
                b: r.old_b,
                expect: ExpectSpec::parse(&r.old_expect).map_err(err)?,
                expect_text: r.old_expect,
                tolerance: r.old_tolerance.ok_or_else(|| need("old_tolerance"))?,
                evidence: r.old_evidence.ok_or_else(|| need("old_evidence"))?,
                normalise: r.old_normalise,
                discriminates: r.old_discriminates,
                control: r.old_control,
            })
        };
        out.push(RuleChange {
            paper: r.paper,
            id: r.id,
            date: r.date,
            commit: r.commit,
            reason: r.reason,
            old_id: r.old_id.filter(|s| !s.is_empty()),
            old,
            old_cell,
        });
    }
    Ok(out)
}

/// Every rule change of the compiled-in history.
pub fn history() -> anyhow::Result<Vec<RuleChange>> {
    parse_history(RULE_HISTORY_CSV, HISTORY_FILE)
}

/// The changes of the verdict rule itself (rows naming [`EVERY_CLAIM`]).
pub fn verdict_rule_changes() -> Vec<RuleChange> {
    history()
        .expect("reports/papers/rule_history.csv parses (tested)")
        .into_iter()
        .filter(RuleChange::is_verdict_rule)
        .collect()
}

/// The changes of `paper`'s table cell rules, oldest first.
pub fn cell_rule_changes(paper: &str) -> Vec<RuleChange> {
    history()
        .expect("reports/papers/rule_history.csv parses (tested)")
        .into_iter()
        .filter(|h| h.is_cell_rule() && h.paper == paper)
        .collect()
}
