//! The papers' claims as data (`reports/papers/claims.csv`) and their evaluation with the one
//! verdict rule of [`super::verdict`].
//!
//! Each claim names the section or table it rests on, says in our words what the paper
//! claims, and says what it compares: a metric, the data sets (one verdict per data set), the
//! variants of each side spelled out (`algorithm:key=value;…`, optionally `@dataset` to pin a
//! side to one data set), what it expects (`a<b`, `a>b`, `a>N`, `a<N`, `a in LO..HI`,
//! `a/b in LO..HI`, `a=N`, or `a=TABLE.COLUMN`: the paper's own cell for the data set), its
//! relative tolerance and what it depends on (`none`, `cpu`, `gpu`). `source` is `paper` for
//! what the paper states and `ours` for a reading of its numbers that its text does not make.
//!
//! Metrics read from a run's rows: `total_ms`, `gpu_ms`, `cpu_ms`, `fps`, `tets_per_sec`,
//! `gpu_tets_per_sec`, `bytes_per_tet`, `gpu_bytes`, `psnr_db`, `counter:NAME`,
//! `counter_per_tet:NAME`, `stage:NAME`,
//! `stage_share:NAME` (the stage over the most expensive other stage), `view_range:METRIC`
//! (range over the viewpoints divided by their mean) and `view_max:METRIC` / `view_min:METRIC`
//! (the largest / smallest over the viewpoints); from two sides' images, `pair_psnr_db` and
//! `pair_bad_pixel_share` (side `a`'s image against side `b`'s, [`super::sides::pair_side`]).
//! Other metrics (the CPU analyses: sorts,
//! the k-buffer, the classifier, data set sizes) come from the paper's own measurements.

use anyhow::{bail, Context as _};
use render_core::Settings;

pub use super::claims_report::{markdown, tally, tally_apart};
use super::sides::{is_pair_metric, pair_side};
pub use super::sides::{row_sample, side_from_rows};
use super::verdict::{self, Check, Evaluation, Expect, Hardware, Side};
use crate::results::Row;

/// The claims file, compiled in like the tables.
pub const CLAIMS_CSV: &str = include_str!("../../../reports/papers/claims.csv");
const FILE: &str = "reports/papers/claims.csv";

/// The rule history (`reports/papers/rule_history.csv`), compiled in like the claims.
pub const RULE_HISTORY_CSV: &str = include_str!("../../../reports/papers/rule_history.csv");
const HISTORY_FILE: &str = "reports/papers/rule_history.csv";

/// What a claim's evidence is: only a measurement can make a claim hold.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Evidence {
    /// An outcome the code produces and could get wrong.
    Measured,
    /// An input chosen to equal the paper's (a stand-in's counts, a fixed layout constant):
    /// checked, but it cannot fail unless the construction is broken.
    ByConstruction,
    /// Arithmetic on other claims' numbers (their ids).
    Derived(Vec<String>),
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
    /// is *as constructed*; a derived one *follows*. Verdicts that decide nothing (noise, not
    /// testable, not checkable) keep their word.
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
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Normalise {
    /// Compared as measured.
    None,
    /// A rate of the paper's GPU judged relative to the fill rate: the paper's figure is
    /// scaled by our calibrated fill rate over its GPU's published one
    /// (`reports/papers/hardware.csv`). A GPU claim so normalised is judged on any adapter,
    /// a software rasteriser included: its calibration measures the same cores it renders on.
    Fill,
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

/// A claim's rule: what it expects, its tolerance and its normalisation, as written.
#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    pub expect: ExpectSpec,
    pub expect_text: String,
    pub tolerance: f64,
    pub normalise: Normalise,
}

impl Rule {
    pub fn describe(&self) -> String {
        let mut s = format!("`{}`", self.expect_text);
        if self.tolerance > 0.0 {
            s.push_str(&format!(", tolerance {}", self.tolerance));
        }
        if self.normalise != Normalise::None {
            s.push_str(&format!(", normalised by {}", self.normalise.label()));
        }
        s
    }
}

/// An earlier rule of a claim, replaced on `date` at `commit` for `reason`.
#[derive(Debug, Clone, PartialEq)]
pub struct RuleChange {
    pub paper: String,
    pub id: String,
    pub date: String,
    pub commit: String,
    pub reason: String,
    pub old: Rule,
}

/// Parses a rule history; errors name the file, the line and what is wrong.
pub fn parse_history(text: &str, file: &str) -> anyhow::Result<Vec<RuleChange>> {
    let mut reader = super::transcription::reader_with_header(
        text,
        file,
        &[
            "paper",
            "id",
            "date",
            "commit",
            "reason",
            "old_expect",
            "old_tolerance",
            "old_normalise",
        ],
    )?;
    let mut out = vec![];
    for (i, rec) in reader.records().enumerate() {
        let line = i + 2;
        let rec = rec.with_context(|| format!("{file}: line {line}"))?;
        let f = |j: usize| rec.get(j).unwrap_or("").trim().to_string();
        let err = |what: String| anyhow::anyhow!("{file}: line {line}: {what}");
        for (name, j) in [
            ("paper", 0),
            ("id", 1),
            ("date", 2),
            ("commit", 3),
            ("reason", 4),
        ] {
            if f(j).is_empty() {
                return Err(err(format!("{name} is empty")));
            }
        }
        let tolerance: f64 = f(6)
            .parse()
            .map_err(|_| err(format!("old_tolerance {:?} is not a number", f(6))))?;
        out.push(RuleChange {
            paper: f(0),
            id: f(1),
            date: f(2),
            commit: f(3),
            reason: f(4),
            old: Rule {
                expect: ExpectSpec::parse(&f(5)).map_err(err)?,
                expect_text: f(5),
                tolerance,
                normalise: Normalise::parse(&f(7)).map_err(err)?,
            },
        });
    }
    Ok(out)
}

/// Every rule change of the compiled-in history.
pub fn history() -> anyhow::Result<Vec<RuleChange>> {
    parse_history(RULE_HISTORY_CSV, HISTORY_FILE)
}

/// Whether the paper states the claim or we read it off its numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    Paper,
    Ours,
}

/// One side of a claim: an algorithm (or one of the papers' CPU analyses) and the settings
/// that pick its variant.
#[derive(Debug, Clone, PartialEq)]
pub struct VariantSpec {
    pub algorithm: String,
    pub settings: Settings,
    /// Pins the side to one data set whatever the claim's data sets are.
    pub dataset: Option<String>,
}

impl VariantSpec {
    pub fn parse(text: &str) -> Result<VariantSpec, String> {
        let (body, dataset) = match text.split_once('@') {
            Some((b, d)) => (b, Some(d.trim().to_string())),
            None => (text, None),
        };
        let (algorithm, settings) = match body.split_once(':') {
            Some((a, s)) => (a.trim(), s),
            None => (body.trim(), ""),
        };
        if algorithm.is_empty() {
            return Err(format!("{text:?}: no algorithm"));
        }
        // The papers' CPU analyses (`sort-analysis`) are not algorithms: their settings are
        // typed by inference.
        let settings = crate::algorithms::parse_settings(algorithm, settings)
            .map_err(|e| format!("{text:?}: {e}"))?;
        Ok(VariantSpec {
            algorithm: algorithm.to_string(),
            settings,
            dataset,
        })
    }

    pub fn settings_text(&self) -> String {
        self.settings.to_string()
    }

    /// `algorithm settings on dataset`: what a verdict names.
    pub fn label(&self, dataset: Option<&str>) -> String {
        let mut s = self.algorithm.clone();
        if !self.settings.is_empty() {
            s.push(' ');
            s.push_str(&self.settings_text());
        }
        if let Some(d) = dataset {
            s.push_str(" on ");
            s.push_str(d);
        }
        s
    }

    /// The value this side asks for a setting, if it pins it.
    pub fn setting(&self, key: &str) -> Option<String> {
        self.settings.text(key)
    }

    pub(crate) fn matches(&self, row: &Row) -> bool {
        row.algorithm == self.algorithm
            && self
                .settings
                .iter()
                .all(|(k, v)| row.settings.get(k) == Some(v))
    }
}

/// What a claim expects, before the paper's cells are looked up.
#[derive(Debug, Clone, PartialEq)]
pub enum ExpectSpec {
    Fixed(Expect),
    /// `a=TABLE.COLUMN`: equal to the paper's cell of the data set's row.
    PaperCell {
        table: String,
        column: String,
    },
}

impl ExpectSpec {
    pub fn parse(text: &str) -> Result<ExpectSpec, String> {
        let t = text.replace(' ', "");
        let num = |s: &str| {
            s.parse::<f64>()
                .map_err(|_| format!("expect {text:?}: {s:?} is not a number"))
        };
        let band = |s: &str| -> Result<(f64, f64), String> {
            let (lo, hi) = s
                .split_once("..")
                .ok_or_else(|| format!("expect {text:?}: a band is LO..HI"))?;
            Ok((num(lo)?, num(hi)?))
        };
        Ok(ExpectSpec::Fixed(match t.as_str() {
            "a<b" => Expect::Less,
            "a>b" => Expect::Greater,
            _ if t.starts_with("a/bin") => {
                let (lo, hi) = band(&t[5..])?;
                Expect::Band(lo, hi)
            }
            _ if t.starts_with("ain") => {
                let (lo, hi) = band(&t[3..])?;
                Expect::Band(lo, hi)
            }
            _ if t.starts_with("a>") => Expect::Above(num(&t[2..])?),
            _ if t.starts_with("a<") => Expect::Below(num(&t[2..])?),
            _ if t.starts_with("a=") => {
                let v = &t[2..];
                if let Ok(x) = v.parse::<f64>() {
                    Expect::Equals(x)
                } else {
                    let (table, column) = v
                        .split_once('.')
                        .ok_or_else(|| format!("expect {text:?}: a=N or a=TABLE.COLUMN"))?;
                    return Ok(ExpectSpec::PaperCell {
                        table: table.to_string(),
                        column: column.to_string(),
                    });
                }
            }
            _ => return Err(format!("expect {text:?} is not one of a<b, a>b, a>N, a<N, a in LO..HI, a/b in LO..HI, a=N, a=TABLE.COLUMN")),
        }))
    }

    /// Whether the claim compares two sides.
    pub fn needs_b(&self) -> bool {
        matches!(self, ExpectSpec::Fixed(Expect::Less | Expect::Greater))
    }
}

/// One claim of a paper.
#[derive(Debug, Clone, PartialEq)]
pub struct Claim {
    pub paper: String,
    pub id: String,
    pub source: Source,
    pub cites: String,
    pub text: String,
    pub metric: String,
    /// One verdict per data set; empty: one verdict (sides pinned with `@` or no data set).
    pub datasets: Vec<String>,
    pub a: VariantSpec,
    pub b: Option<VariantSpec>,
    pub expect: ExpectSpec,
    pub tolerance: f64,
    pub hardware: Hardware,
    /// The expectation as written in the file.
    pub expect_text: String,
    pub evidence: Evidence,
    pub normalise: Normalise,
    /// Earlier rules of this claim, oldest first (`reports/papers/rule_history.csv`).
    pub history: Vec<RuleChange>,
}

impl Claim {
    /// The claim's rule as it stands.
    pub fn rule(&self) -> Rule {
        Rule {
            expect: self.expect.clone(),
            expect_text: self.expect_text.clone(),
            tolerance: self.tolerance,
            normalise: self.normalise,
        }
    }

    /// The claim under another rule (an earlier one of its history).
    pub fn with_rule(&self, rule: &Rule) -> Claim {
        Claim {
            expect: rule.expect.clone(),
            expect_text: rule.expect_text.clone(),
            tolerance: rule.tolerance,
            normalise: rule.normalise,
            history: vec![],
            ..self.clone()
        }
    }
}

/// Parses a claims file; errors name the file, the line and what is wrong.
pub fn parse(text: &str, file: &str) -> anyhow::Result<Vec<Claim>> {
    let mut reader = super::transcription::reader_with_header(
        text,
        file,
        &[
            "paper",
            "id",
            "source",
            "cites",
            "claim",
            "metric",
            "datasets",
            "a",
            "b",
            "expect",
            "tolerance",
            "hardware",
            "evidence",
            "normalise",
        ],
    )?;
    let mut claims: Vec<Claim> = vec![];
    for (i, rec) in reader.records().enumerate() {
        let line = i + 2;
        let rec = rec.with_context(|| format!("{file}: line {line}"))?;
        let f = |j: usize| rec.get(j).unwrap_or("").trim().to_string();
        let err = |what: String| anyhow::anyhow!("{file}: line {line}: {what}");
        let source = match f(2).as_str() {
            "paper" => Source::Paper,
            "ours" => Source::Ours,
            s => return Err(err(format!("source {s:?} is not paper or ours"))),
        };
        let hardware = match f(11).as_str() {
            "none" => Hardware::None,
            "cpu" => Hardware::Cpu,
            "gpu" => Hardware::Gpu,
            s => return Err(err(format!("hardware {s:?} is not none, cpu or gpu"))),
        };
        let tolerance: f64 = f(10)
            .parse()
            .map_err(|_| err(format!("tolerance {:?} is not a number", f(10))))?;
        if !(0.0..1.0).contains(&tolerance) {
            return Err(err(format!("tolerance {tolerance} is not in [0, 1)")));
        }
        let a = VariantSpec::parse(&f(7)).map_err(err)?;
        let b = match f(8) {
            s if s.is_empty() => None,
            s => Some(VariantSpec::parse(&s).map_err(err)?),
        };
        let expect = ExpectSpec::parse(&f(9)).map_err(err)?;
        let evidence = Evidence::parse(&f(12)).map_err(err)?;
        let normalise = Normalise::parse(&f(13)).map_err(err)?;
        let ratio = f(9).replace(' ', "").starts_with("a/b");
        let pair = is_pair_metric(&f(5));
        if pair && (expect.needs_b() || ratio) {
            return Err(err(format!(
                "metric {} compares a's image with b's: expect a>N, a<N, a=N or a in LO..HI, not {:?}",
                f(5),
                f(9)
            )));
        }
        let needs_b = expect.needs_b() || ratio || pair;
        if needs_b != b.is_some() {
            return Err(err(format!(
                "expect {:?} {} a second side (column b)",
                f(9),
                if needs_b { "needs" } else { "takes no" }
            )));
        }
        for (name, value) in [
            ("paper", f(0)),
            ("id", f(1)),
            ("cites", f(3)),
            ("claim", f(4)),
            ("metric", f(5)),
        ] {
            if value.is_empty() {
                return Err(err(format!("{name} is empty")));
            }
        }
        let claim = Claim {
            paper: f(0),
            id: f(1),
            source,
            cites: f(3),
            text: f(4),
            metric: f(5),
            datasets: f(6)
                .split(';')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect(),
            a,
            b,
            expect,
            tolerance,
            hardware,
            expect_text: f(9),
            evidence,
            normalise,
            history: vec![],
        };
        if claims
            .iter()
            .any(|c| c.paper == claim.paper && c.id == claim.id)
        {
            return Err(err(format!("{} {} appears twice", claim.paper, claim.id)));
        }
        claims.push(claim);
    }
    Ok(claims)
}

/// Every claim of the compiled-in file, each with its rule history.
pub fn all() -> anyhow::Result<Vec<Claim>> {
    let mut claims = parse(CLAIMS_CSV, FILE)?;
    attach_history(&mut claims, history()?, HISTORY_FILE)?;
    Ok(claims)
}

/// Gives each claim its earlier rules; a change naming no claim is an error, and a derived
/// claim must name claims that exist.
pub fn attach_history(
    claims: &mut [Claim],
    history: Vec<RuleChange>,
    file: &str,
) -> anyhow::Result<()> {
    for h in history {
        let Some(c) = claims
            .iter_mut()
            .find(|c| c.paper == h.paper && c.id == h.id)
        else {
            bail!("{file}: {} {} is not a claim of {FILE}", h.paper, h.id);
        };
        c.history.push(h);
    }
    for c in claims.iter() {
        if let Evidence::Derived(ids) = &c.evidence {
            for id in ids {
                if !claims.iter().any(|o| o.paper == c.paper && &o.id == id) {
                    bail!(
                        "{FILE}: {} {} is derived from {id}, which is not a claim of {}",
                        c.paper,
                        c.id,
                        c.paper
                    );
                }
            }
        }
    }
    Ok(())
}

/// The claims of one paper, in the file's order.
pub fn of(paper: &str) -> Vec<Claim> {
    all()
        .expect("reports/papers/claims.csv parses (tested)")
        .into_iter()
        .filter(|c| c.paper == paper)
        .collect()
}

/// A claim's verdict on one data set (or on none).
#[derive(Debug, Clone, PartialEq)]
pub struct ClaimResult {
    pub claim: Claim,
    pub dataset: Option<String>,
    pub evaluation: Evaluation,
    /// The same numbers under each earlier rule of the claim's history.
    pub earlier: Vec<(RuleChange, Evaluation)>,
}

impl ClaimResult {
    /// The verdict in the word of the claim's evidence kind.
    pub fn word(&self) -> &'static str {
        self.claim.evidence.word(self.evaluation.verdict)
    }
}

/// Where the numbers come from: the run's rows, the paper's own analyses, and why an
/// algorithm has no rows.
/// A side from the paper's CPU analyses for (metric, variant, data set), or `None` when the
/// metric is not one of them.
pub type AnalysisSide<'a> =
    dyn Fn(&str, &VariantSpec, Option<&str>) -> Option<Result<Side, String>> + 'a;

pub struct Inputs<'a> {
    pub rows: &'a [Row],
    /// A side from the paper's CPU analyses (`None`: the metric is not one of them).
    pub analysis: &'a AnalysisSide<'a>,
    /// Why `algorithm` has no value on a data set.
    pub why_missing: &'a dyn Fn(&str, &str) -> String,
    /// Whether the GPU numbers came from a software rasteriser.
    pub software_adapter: bool,
    /// Our adapter's calibrated peaks (`None`: the runs were not calibrated).
    pub our_peaks: Option<super::hardware::OurPeaks>,
    /// The run folder each row's image paths are relative to, by the row's index in `rows`
    /// (`None` or missing: its images cannot be read).
    pub row_dirs: &'a [Option<std::path::PathBuf>],
}

/// Whether rows were measured on a software rasteriser (lavapipe, WARP, SwiftShader report a
/// CPU device type).
pub fn software_adapter(rows: &[Row]) -> bool {
    rows.iter()
        .any(|r| r.device_type.eq_ignore_ascii_case("cpu"))
}

/// Evaluates every claim of `paper`.
pub fn evaluate_all(paper: &str, inputs: &Inputs) -> Vec<ClaimResult> {
    of(paper)
        .into_iter()
        .flat_map(|c| evaluate(&c, inputs))
        .collect()
}

/// One verdict per data set of the claim.
pub fn evaluate(claim: &Claim, inputs: &Inputs) -> Vec<ClaimResult> {
    let datasets: Vec<Option<String>> = if claim.datasets.is_empty() {
        vec![None]
    } else {
        claim.datasets.iter().cloned().map(Some).collect()
    };
    datasets
        .into_iter()
        .map(|d| {
            let evaluation = evaluate_one(claim, d.as_deref(), inputs);
            let earlier = claim
                .history
                .iter()
                .map(|h| {
                    (
                        h.clone(),
                        evaluate_one(&claim.with_rule(&h.old), d.as_deref(), inputs),
                    )
                })
                .collect();
            ClaimResult {
                claim: claim.clone(),
                dataset: d,
                evaluation,
                earlier,
            }
        })
        .collect()
}

fn evaluate_one(claim: &Claim, dataset: Option<&str>, inputs: &Inputs) -> Evaluation {
    let expect = match &claim.expect {
        ExpectSpec::Fixed(e) => *e,
        ExpectSpec::PaperCell { table, column } => {
            let Some(d) = dataset else {
                return Evaluation::not_checkable(format!(
                    "{} {}: a=TABLE.COLUMN needs a data set",
                    claim.paper, claim.id
                ));
            };
            let row = super::transcription::paper_name(&claim.paper, d).unwrap_or(d);
            match super::transcription::table(table)
                .ok()
                .and_then(|t| t.value(row, column))
            {
                Some(v) => Expect::Equals(v),
                None => {
                    return Evaluation::not_checkable(format!(
                        "the paper gives no {table} {column} for {row}"
                    ))
                }
            }
        }
    };
    let (expect, normalised) = match normalise(claim, expect, inputs) {
        Ok(x) => x,
        Err(why) => return Evaluation::not_checkable(why),
    };
    let check = Check {
        expect,
        tolerance: claim.tolerance,
        hardware: claim.hardware,
    };
    let (a, b) = match (&claim.b, dataset) {
        // An image pair is one side: a's image against b's.
        (Some(b), Some(d)) if is_pair_metric(&claim.metric) => {
            (pair_side(&claim.metric, &claim.a, b, d, inputs), None)
        }
        _ => (
            side(claim, &claim.a, dataset, inputs),
            claim.b.as_ref().map(|b| side(claim, b, dataset, inputs)),
        ),
    };
    let mut e = verdict::evaluate(
        &check,
        a.as_ref().map_err(Clone::clone),
        b.as_ref().map(|r| r.as_ref().map_err(Clone::clone)),
        // A normalised rate is judged against the adapter's own calibrated peak.
        inputs.software_adapter && claim.normalise == Normalise::None,
    );
    if let Some(n) = normalised {
        if e.verdict != verdict::Verdict::NotCheckable {
            e.numbers.push_str("; ");
            e.numbers.push_str(&n);
        }
    }
    e
}

/// The expectation scaled to our adapter by the claim's normalisation, and the sentence that
/// says how (`None`: not normalised).
fn normalise(
    claim: &Claim,
    expect: Expect,
    inputs: &Inputs,
) -> Result<(Expect, Option<String>), String> {
    match claim.normalise {
        Normalise::None => Ok((expect, None)),
        Normalise::Fill => {
            let paper = super::hardware::paper_gpu(&claim.paper)
                .and_then(|g| Some((g.fill_pixels_per_sec?, g)))
                .ok_or_else(|| {
                    format!(
                        "{} {}: normalised by the fill rate, but reports/papers/hardware.csv gives no fill rate for the {} paper's GPU",
                        claim.paper, claim.id, claim.paper
                    )
                })?;
            let ours = inputs.our_peaks.as_ref().ok_or_else(|| {
                format!(
                    "{} {}: normalised by the fill rate, but the runs carry no calibration (run without --no-calibrate)",
                    claim.paper, claim.id
                )
            })?;
            let f = ours.fill_fragments_per_sec / paper.0;
            let scaled = match expect {
                Expect::Above(t) => Expect::Above(t * f),
                Expect::Below(t) => Expect::Below(t * f),
                Expect::Equals(t) => Expect::Equals(t * f),
                Expect::Band(lo, hi) if claim.b.is_none() => Expect::Band(lo * f, hi * f),
                _ => {
                    return Err(format!(
                        "{} {}: a comparison of two sides measured here needs no normalisation",
                        claim.paper, claim.id
                    ))
                }
            };
            Ok((
                scaled,
                Some(format!(
                    "normalised by the fill rate: the paper's figure ({}) × our calibrated {:.3e} blended fragments/s ({}) / the {}'s published {:.3e} pixels/s = ×{:.3}",
                    claim.expect_text, ours.fill_fragments_per_sec, ours.adapter, paper.1.gpu, paper.0, f
                )),
            ))
        }
    }
}

/// The samples of one side on one data set.
fn side(
    claim: &Claim,
    spec: &VariantSpec,
    dataset: Option<&str>,
    inputs: &Inputs,
) -> Result<Side, String> {
    let d = spec.dataset.as_deref().or(dataset);
    if let Some(s) = (inputs.analysis)(&claim.metric, spec, d) {
        return s;
    }
    let Some(d) = d else {
        return Err(format!(
            "{}: metric {} needs a data set",
            spec.label(None),
            claim.metric
        ));
    };
    side_from_rows(&claim.metric, spec, d, inputs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variant_specs_and_expectations_parse() {
        let v = VariantSpec::parse("havs:k=2;sort=cpu-radix@spx2").unwrap();
        assert_eq!(v.algorithm, "havs");
        assert_eq!(v.settings.int("k"), Some(2));
        assert_eq!(v.dataset.as_deref(), Some("spx2"));
        assert_eq!(v.label(Some("spx2")), "havs k=2;sort=cpu-radix on spx2");
        assert!(VariantSpec::parse("havs:k2").is_err());
        assert_eq!(
            ExpectSpec::parse("a/b in 2..2.5").unwrap(),
            ExpectSpec::Fixed(Expect::Band(2.0, 2.5))
        );
        assert_eq!(
            ExpectSpec::parse("a>15000000").unwrap(),
            ExpectSpec::Fixed(Expect::Above(15e6))
        );
        assert_eq!(
            ExpectSpec::parse("a=havs_table2.fragments_count").unwrap(),
            ExpectSpec::PaperCell {
                table: "havs_table2".into(),
                column: "fragments_count".into()
            }
        );
        assert!(ExpectSpec::parse("a≈b").is_err());
    }

    #[test]
    fn a_bad_claims_file_is_refused_with_file_and_line() {
        let head = "paper,id,source,cites,claim,metric,datasets,a,b,expect,tolerance,hardware,evidence,normalise\n";
        let bad =
            format!("{head}havs,H1,paper,§5.1,x,total_ms,spx2,havs:k=2,,a<b,0,gpu,measured,none\n");
        let e = parse(&bad, "claims.csv").unwrap_err().to_string();
        assert!(
            e.contains("claims.csv: line 2") && e.contains("second side"),
            "{e}"
        );
        let bad =
            format!("{head}havs,H1,maybe,§5.1,x,total_ms,spx2,havs,,a>1,0,gpu,measured,none\n");
        assert!(parse(&bad, "c").unwrap_err().to_string().contains("source"));
        let bad =
            format!("{head}havs,H1,paper,§5.1,x,total_ms,spx2,havs,,a>1,0,gpu,guessed,none\n");
        assert!(parse(&bad, "c")
            .unwrap_err()
            .to_string()
            .contains("evidence"));
        let twice = format!(
            "{head}havs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu,measured,none\nhavs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu,measured,none\n"
        );
        assert!(parse(&twice, "c")
            .unwrap_err()
            .to_string()
            .contains("twice"));
        // A derived claim must name claims that exist; a rule change must name a claim.
        let derived =
            format!("{head}havs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu,derived:H9,none\n");
        let mut c = parse(&derived, "c").unwrap();
        let e = attach_history(&mut c, vec![], "h").unwrap_err().to_string();
        assert!(e.contains("derived from H9"), "{e}");
        let h = parse_history(
            "paper,id,date,commit,reason,old_expect,old_tolerance,old_normalise\nhavs,H2,2026-12-04,abc,why,a>2,0,none\n",
            "h.csv",
        )
        .unwrap();
        let mut c = parse(
            &format!("{head}havs,H1,paper,§5.1,x,total_ms,,havs,,a>1,0,gpu,measured,none\n"),
            "c",
        )
        .unwrap();
        let e = attach_history(&mut c, h, "h.csv").unwrap_err().to_string();
        assert!(e.contains("havs H2 is not a claim"), "{e}");
    }

    fn row(settings: &str, viewpoint: &str, total: f64, frames: u32) -> Row {
        Row {
            algorithm: "raycast".into(),
            settings: Settings::parse(settings).unwrap(),
            dataset: "spx1".into(),
            tets: 1000,
            viewpoint: viewpoint.into(),
            total_ms: Some(total),
            total_ms_min: Some(total - 1.0),
            total_ms_max: Some(total + 1.0),
            frames,
            device_type: "DiscreteGpu".into(),
            ..Default::default()
        }
    }

    fn inputs(rows: &[Row]) -> Inputs<'_> {
        Inputs {
            rows,
            analysis: &|_, _, _| None,
            why_missing: &|a, d| format!("{a} not measured on {d}"),
            software_adapter: software_adapter(rows),
            our_peaks: None,
            row_dirs: &[],
        }
    }

    #[test]
    fn a_claim_that_does_not_pin_its_variant_is_not_decided_by_the_first_one_found() {
        let rows = vec![
            row("tiles=5x5;table=2d;mode=passes", "+x", 100.0, 5),
            row("tiles=5x5;table=2d;mode=loop", "+x", 300.0, 5),
            row("tiles=1x1;table=2d;mode=passes", "+x", 200.0, 5),
        ];
        let loose = VariantSpec::parse("raycast:tiles=5x5").unwrap();
        let e = side_from_rows("total_ms", &loose, "spx1", &inputs(&rows)).unwrap_err();
        assert!(e.contains("2 variants match"), "{e}");
        let pinned = VariantSpec::parse("raycast:tiles=5x5;mode=passes").unwrap();
        let s = side_from_rows("total_ms", &pinned, "spx1", &inputs(&rows)).unwrap();
        assert!(s.label.contains("mode=passes"), "{}", s.label);
        assert_eq!(s.centre(), 100.0);
        // Pinned to the loop variant the ordering flips.
        let claim = |a: &str| Claim {
            paper: "raycast".into(),
            id: "X".into(),
            source: Source::Ours,
            cites: "§4".into(),
            text: "t".into(),
            metric: "total_ms".into(),
            datasets: vec!["spx1".into()],
            a: VariantSpec::parse(a).unwrap(),
            b: Some(VariantSpec::parse("raycast:tiles=1x1").unwrap()),
            expect: ExpectSpec::Fixed(Expect::Less),
            tolerance: 0.0,
            hardware: Hardware::Gpu,
            expect_text: "a<b".into(),
            evidence: Evidence::Measured,
            normalise: Normalise::None,
            history: vec![],
        };
        let v = |a: &str| evaluate(&claim(a), &inputs(&rows))[0].evaluation.verdict;
        assert_eq!(v("raycast:tiles=5x5;mode=passes"), verdict::Verdict::Holds);
        assert_eq!(
            v("raycast:tiles=5x5;mode=loop"),
            verdict::Verdict::DoesNotHold
        );
        assert_eq!(v("raycast:tiles=5x5"), verdict::Verdict::NotCheckable);
    }

    #[test]
    fn rates_invert_the_frame_range_and_stage_shares_name_missing_stages() {
        let mut r = row("tiles=1x1", "+x", 100.0, 3);
        let fps = row_sample("fps", &r).unwrap();
        assert_eq!(fps.value, 10.0);
        assert!(fps.min < 10.0 && fps.max > 10.0);
        r.stages = "wait=9;buckets=3;splat=1".into();
        let e = row_sample("stage_share:sort", &r).unwrap_err();
        assert!(e.contains("wait, buckets, splat"), "{e}");
        assert_eq!(row_sample("stage_share:wait", &r).unwrap().value, 3.0);
        assert!(row_sample("no-such-metric", &r).is_err());
    }
}
