//! The papers' claims as data (`reports/papers/claims.csv`, read with serde into [`Claim`]) and
//! their evaluation with the one verdict rule of [`super::verdict`].
//!
//! Each claim names the section or table it rests on, says in our words what the paper
//! claims, and says what it compares: a metric ([`Metric`]), the data sets (one verdict per
//! data set), the variants of each side spelled out (`algorithm:key=value;…`, optionally
//! `@dataset` to pin a side to one data set), what it expects (`a<b`, `a>b`, `a>N`, `a<N`,
//! `a in LO..HI`, `a/b in LO..HI`, `a=N`, or `a=TABLE.COLUMN`: the paper's own cell for the data
//! set), its relative tolerance and what it depends on (`none`, `cpu`, `gpu`). `source` is
//! `paper` for what the paper states and `ours` for a reading of its numbers that its text does
//! not make. Its rule and the rule's history are in [`super::rules`].

use anyhow::bail;

#[cfg(test)]
use super::rules::parse_history;
use super::rules::{history, Evidence, Normalise, Rule, RuleChange, HISTORY_FILE};
use super::sides::{pair_side, side_from_rows};
pub use super::sides::{software_adapter, AnalysisSide, Inputs};
pub use super::spec::{Discriminates, ExpectSpec, Metric, VariantSpec};
use super::transcription::deserialize_rows;
use super::verdict::{self, Check, Evaluation, Expect, Hardware, Side};

/// The claims file, compiled in like the tables.
pub const CLAIMS_CSV: &str = include_str!("../../../reports/papers/claims.csv");
pub const FILE: &str = "reports/papers/claims.csv";

/// The claims file's columns.
pub const HEADER: &[&str] = &[
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
    "discriminates",
    "control",
];

/// Whether the paper states the claim or we read it off its numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum Source {
    Paper,
    Ours,
}

impl TryFrom<String> for Source {
    type Error = String;
    fn try_from(s: String) -> Result<Source, String> {
        match s.as_str() {
            "paper" => Ok(Source::Paper),
            "ours" => Ok(Source::Ours),
            s => Err(format!("source {s:?} is not paper or ours")),
        }
    }
}

/// One line of the claims file as serde reads it.
#[derive(serde::Deserialize)]
struct Record {
    paper: String,
    id: String,
    source: Source,
    cites: String,
    claim: String,
    metric: Metric,
    datasets: String,
    a: VariantSpec,
    b: Option<VariantSpec>,
    expect: String,
    tolerance: f64,
    hardware: Hardware,
    evidence: Evidence,
    normalise: Normalise,
    discriminates: Option<Discriminates>,
    control: Option<VariantSpec>,
}

/// One claim of a paper.
#[derive(Debug, Clone, PartialEq)]
pub struct Claim {
    pub paper: String,
    pub id: String,
    pub source: Source,
    pub cites: String,
    pub text: String,
    pub metric: Metric,
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
    /// Where the two sides can differ at all (`None`: on every data set).
    pub discriminates: Option<Discriminates>,
    /// A known perturbation replacing side `a` that the rule must reject (`None`: none).
    pub control: Option<VariantSpec>,
    /// Earlier rules of this claim, oldest first (`reports/papers/rule_history.csv`).
    pub history: Vec<RuleChange>,
}

impl Claim {
    /// The claim's rule as it stands.
    pub fn rule(&self) -> Rule {
        Rule {
            metric: self.metric.clone(),
            datasets: self.datasets.clone(),
            a: self.a.clone(),
            b: self.b.clone(),
            expect: self.expect.clone(),
            expect_text: self.expect_text.clone(),
            tolerance: self.tolerance,
            evidence: self.evidence.clone(),
            normalise: self.normalise,
            discriminates: self.discriminates.clone(),
            control: self.control.clone(),
        }
    }

    /// The claim under another rule (an earlier one of its history).
    pub fn with_rule(&self, rule: &Rule) -> Claim {
        Claim {
            metric: rule.metric.clone(),
            datasets: rule.datasets.clone(),
            a: rule.a.clone(),
            b: rule.b.clone(),
            expect: rule.expect.clone(),
            expect_text: rule.expect_text.clone(),
            tolerance: rule.tolerance,
            evidence: rule.evidence.clone(),
            normalise: rule.normalise,
            discriminates: rule.discriminates.clone(),
            control: rule.control.clone(),
            history: vec![],
            ..self.clone()
        }
    }
}

/// Checks that a rule's parts fit together: a pair metric takes a single expectation, and a
/// second side is there exactly when the expectation or the metric needs one.
pub fn check_rule(rule: &Rule) -> Result<(), String> {
    let ratio = rule.expect_text.replace(' ', "").starts_with("a/b");
    let pair = rule.metric.is_pair();
    if pair && (rule.expect.needs_b() || ratio) {
        return Err(format!(
            "metric {} compares a's image with b's: expect a>N, a<N, a=N or a in LO..HI, not {:?}",
            rule.metric, rule.expect_text
        ));
    }
    let needs_b = rule.expect.needs_b() || ratio || pair;
    if needs_b != rule.b.is_some() {
        return Err(format!(
            "expect {:?} {} a second side (column b)",
            rule.expect_text,
            if needs_b { "needs" } else { "takes no" }
        ));
    }
    Ok(())
}

/// Parses a claims file; errors name the file, the line and what is wrong.
pub fn parse(text: &str, file: &str) -> anyhow::Result<Vec<Claim>> {
    let mut claims: Vec<Claim> = vec![];
    for (line, r) in deserialize_rows::<Record>(text, file, HEADER)? {
        let err = |what: String| anyhow::anyhow!("{file}: line {line}: {what}");
        if !(0.0..1.0).contains(&r.tolerance) {
            return Err(err(format!("tolerance {} is not in [0, 1)", r.tolerance)));
        }
        for (name, value) in [
            ("paper", &r.paper),
            ("id", &r.id),
            ("cites", &r.cites),
            ("claim", &r.claim),
        ] {
            if value.is_empty() {
                return Err(err(format!("{name} is empty")));
            }
        }
        let claim = Claim {
            expect: ExpectSpec::parse(&r.expect).map_err(err)?,
            paper: r.paper,
            id: r.id,
            source: r.source,
            cites: r.cites,
            text: r.claim,
            metric: r.metric,
            datasets: super::rules::split_datasets(&r.datasets),
            a: r.a,
            b: r.b,
            tolerance: r.tolerance,
            hardware: r.hardware,
            expect_text: r.expect,
            evidence: r.evidence,
            normalise: r.normalise,
            discriminates: r.discriminates,
            control: r.control,
            history: vec![],
        };
        check_rule(&claim.rule()).map_err(err)?;
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
    check_counter_evidence(&claims, FILE)?;
    Ok(claims)
}

/// A claim on a counter that its renderer's description declares not measured (the bytes a
/// data layout reserves, the triangles a draw call issues by its own arguments) cannot be
/// `measured`: it can only be as constructed, so it never counts as a hold.
pub fn check_counter_evidence(claims: &[Claim], file: &str) -> anyhow::Result<()> {
    for c in claims.iter().filter(|c| c.evidence == Evidence::Measured) {
        let Some(name) = c.metric.counter() else {
            continue;
        };
        for spec in [Some(&c.a), c.b.as_ref()].into_iter().flatten() {
            let Some(d) = crate::algorithms::describe(&spec.algorithm) else {
                continue;
            };
            let e = d.evidence_of(name);
            if e != render_core::CounterEvidence::Measured {
                bail!(
                    "{file}: {} {}: counter {name} of {} {} (its description), so the claim cannot be measured: write evidence construction",
                    c.paper,
                    c.id,
                    spec.algorithm,
                    e.label()
                );
            }
        }
    }
    Ok(())
}

/// Gives each claim its earlier rules; a change naming no claim is an error, and a derived
/// claim must name claims that exist. Changes of the verdict rule itself name no claim.
pub fn attach_history(
    claims: &mut [Claim],
    history: Vec<RuleChange>,
    file: &str,
) -> anyhow::Result<()> {
    for h in history
        .into_iter()
        .filter(|h| !h.is_verdict_rule() && !h.is_cell_rule())
    {
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
    /// The claim's positive control on this data set, where it has one: the rule applied with
    /// side `a` replaced by a known perturbation, which it must reject.
    pub control: Option<Evaluation>,
    /// The same numbers under each earlier rule of the claim's history.
    pub earlier: Vec<(RuleChange, Evaluation)>,
}

impl ClaimResult {
    /// The verdict in the word of the claim's evidence kind.
    pub fn word(&self) -> &'static str {
        self.claim.evidence.word(self.evaluation.verdict)
    }
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
            let (evaluation, control) = judge(claim, d.as_deref(), inputs);
            let earlier = claim
                .history
                .iter()
                .filter_map(|h| {
                    let old = claim.with_rule(h.old.as_ref()?);
                    Some((h.clone(), judge(&old, d.as_deref(), inputs).0))
                })
                .collect();
            ClaimResult {
                claim: claim.clone(),
                dataset: d,
                evaluation,
                control,
                earlier,
            }
        })
        .collect()
}

/// The claim's verdict on one data set: its rule on the measured sides, then whether the two
/// sides can differ there at all (a failed `discriminates` bound reads *not discriminating*),
/// then its positive control (a hold whose control passes too reads *insensitive*). The
/// control's own evaluation comes back beside it; an image pair's control is judged on every
/// adapter, beside a GPU claim's *not testable on this adapter* too.
fn judge(
    claim: &Claim,
    dataset: Option<&str>,
    inputs: &Inputs,
) -> (Evaluation, Option<Evaluation>) {
    let mut e = evaluate_one(claim, dataset, inputs);
    if let Some(d) = &claim.discriminates {
        let found = side_of(&d.metric, &d.spec, dataset, inputs);
        let side = match found {
            Ok(side) if !side.samples.is_empty() => side,
            Ok(side) => {
                return (
                    Evaluation::not_checkable(format!(
                        "whether the sides can differ here is not known: {} has no value",
                        side.label
                    )),
                    None,
                )
            }
            Err(why) => {
                return (
                    Evaluation::not_checkable(format!(
                        "whether the sides can differ here is not known: {why}"
                    )),
                    None,
                )
            }
        };
        let value = side.centre();
        if !d.admits(value) {
            e.numbers = format!(
                "{} = {value}: the two sides cannot differ here (they can only where `{d}`), so the pair decides nothing; measured all the same: {} (it would read \"{}\")",
                side.label,
                e.numbers,
                e.verdict.label()
            );
            e.verdict = verdict::Verdict::NotDiscriminating;
            return (e, None);
        }
    }
    let Some(perturbed) = claim
        .control
        .as_ref()
        .filter(|c| c.dataset.is_none() || c.dataset.as_deref() == dataset)
    else {
        return (e, None);
    };
    // An image pair's control shows whether the rule can see a known fault in images of this
    // data set, which does not depend on how the adapter schedules fragments: it is judged on
    // every adapter, also where a GPU claim's own verdict is withheld (HAVS's race, §4), and it
    // leaves that verdict as it is (only a hold becomes insensitive).
    let hardware = if claim.metric.is_pair() {
        Hardware::None
    } else {
        claim.hardware
    };
    let control = evaluate_one(
        &Claim {
            a: perturbed.clone(),
            discriminates: None,
            control: None,
            hardware,
            ..claim.clone()
        },
        dataset,
        inputs,
    );
    use verdict::Verdict::{DoesNotHold, Holds, Insensitive, NotCheckable};
    let outcome = match control.verdict {
        DoesNotHold => "the rule rejects it, as it must",
        NotCheckable => "not run, so the rule's sensitivity is not shown here",
        _ => "the rule does not reject it: the rule is insensitive here",
    };
    // The control's own figures, so that a reader sees how far from failing it is.
    e.numbers.push_str(&format!(
        "; positive control (side a = `{perturbed}`): {}, {outcome} ({})",
        control.verdict.label(),
        control.numbers
    ));
    if e.verdict == Holds && !matches!(control.verdict, DoesNotHold | NotCheckable) {
        e.verdict = Insensitive;
    }
    (e, Some(control))
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
    let raw_expect = expect;
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
        (Some(b), Some(d)) if claim.metric.is_pair() => {
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
            // Beside the control's verdict, the one the cached calibration would give.
            if let Some(cached) = &inputs.cached_peaks {
                let with_cache = Inputs {
                    our_peaks: Some(cached.clone()),
                    cached_peaks: None,
                    ..*inputs
                };
                if let Ok((expect, _)) = normalise(claim, raw_expect, &with_cache) {
                    let c = verdict::evaluate(
                        &Check { expect, ..check },
                        a.as_ref().map_err(Clone::clone),
                        b.as_ref().map(|r| r.as_ref().map_err(Clone::clone)),
                        false,
                    );
                    e.numbers.push_str(&format!(
                        "; by {} ({:.3e} fragments/s) it would read: {}",
                        cached.source,
                        cached.fill_fragments_per_sec,
                        c.verdict.label()
                    ));
                }
            }
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
                    "normalised by the fill rate: the paper's figure ({}) × our {:.3e} blended fragments/s ({}, {}) / the {}'s published {:.3e} pixels/s = ×{:.3}",
                    claim.expect_text, ours.fill_fragments_per_sec, ours.adapter, ours.source, paper.1.gpu, paper.0, f
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
    side_of(&claim.metric, spec, dataset, inputs)
}

/// The samples of `metric` for one side on one data set: the paper's analyses first, then
/// the run's rows.
fn side_of(
    metric: &Metric,
    spec: &VariantSpec,
    dataset: Option<&str>,
    inputs: &Inputs,
) -> Result<Side, String> {
    let d = spec.dataset.as_deref().or(dataset);
    if let Some(s) = (inputs.analysis)(metric, spec, d) {
        return s;
    }
    let Some(d) = d else {
        return Err(format!(
            "{}: metric {metric} needs a data set",
            spec.label(None),
        ));
    };
    side_from_rows(metric, spec, d, inputs)
}

#[cfg(test)]
#[path = "claims_unit_tests.rs"]
mod tests;
