//! The claims' verdicts as the reports show them: the headline counts of measured claims
//! ([`tally`]), the claims by construction and derived ones apart ([`tally_apart`]), and the
//! Markdown table of every verdict ([`markdown`]).

use super::claims::{ClaimResult, Source};
use super::rules::{Evidence, RuleChange};
use super::verdict;

/// Counts of each verdict of the measured claims, in [`verdict::Verdict::ALL`]'s order:
/// the headline. Claims by construction and derived ones are counted apart ([`tally_apart`]).
pub fn tally(results: &[ClaimResult]) -> Vec<(verdict::Verdict, usize)> {
    verdict::Verdict::ALL
        .iter()
        .map(|v| {
            (
                *v,
                results
                    .iter()
                    .filter(|r| {
                        r.claim.evidence == Evidence::Measured && r.evaluation.verdict == *v
                    })
                    .count(),
            )
        })
        .collect()
}

/// Counts of the claims that are not measured, by kind and word: (`by construction`,
/// [(`as constructed`, 6)]), (`derived`, [(`follows`, 5)]).
pub fn tally_apart(results: &[ClaimResult]) -> Vec<(&'static str, Vec<(&'static str, usize)>)> {
    let mut out = vec![];
    for (kind, is) in [
        (
            "by construction",
            (|e: &Evidence| *e == Evidence::ByConstruction) as fn(&Evidence) -> bool,
        ),
        ("derived", |e: &Evidence| matches!(e, Evidence::Derived(_))),
    ] {
        let mut words: Vec<(&'static str, usize)> = vec![];
        for r in results.iter().filter(|r| is(&r.claim.evidence)) {
            let w = r.word();
            match words.iter_mut().find(|(x, _)| *x == w) {
                Some((_, n)) => *n += 1,
                None => words.push((w, 1)),
            }
        }
        if !words.is_empty() {
            out.push((kind, words));
        }
    }
    out
}

/// The verdicts as a Markdown table: claim, where, evidence, rule, verdict (in the word of its
/// evidence kind), the numbers and variants used, and each earlier rule with its verdict.
pub fn markdown(results: &[ClaimResult]) -> String {
    use std::fmt::Write as _;
    let mut md = String::from(
        "| claim | cites | evidence | rule | data set | verdict | numbers (variants named) |\n|---|---|---|---|---|---|---|\n",
    );
    for r in results {
        let c = &r.claim;
        let label = match c.source {
            Source::Paper => format!("**{}** {}", c.id, c.text),
            Source::Ours => format!("**{}** (ours, not the paper's) {}", c.id, c.text),
        };
        let mut rule = c.rule().describe();
        let mut verdict = r.word().to_string();
        if let Some(control) = &r.control {
            let _ = write!(verdict, " (positive control: {})", control.verdict.label());
        }
        for (h, e) in &r.earlier {
            let Some(old) = &h.old else { continue };
            let _ = write!(
                rule,
                "; until {} ({}{}): {}",
                h.date,
                h.commit,
                h.old_id
                    .as_ref()
                    .map_or(String::new(), |id| format!(", as {id}")),
                old.describe_against(&c.rule())
            );
            // The earlier verdict in the word of the earlier rule's evidence kind.
            let _ = write!(
                verdict,
                "; by the rule before {}: {}",
                h.commit,
                old.evidence.word(e.verdict)
            );
        }
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} |",
            cell(&label),
            cell(&c.cites),
            cell(&c.evidence.label()),
            cell(&rule),
            r.dataset.as_deref().unwrap_or("–"),
            cell(&verdict),
            cell(&r.evaluation.numbers)
        );
    }
    let changes: Vec<&RuleChange> = {
        let mut v: Vec<&RuleChange> = vec![];
        for (h, _) in results.iter().flat_map(|r| &r.earlier) {
            if !v.contains(&h) {
                v.push(h);
            }
        }
        v
    };
    let verdict_rule = super::rules::verdict_rule_changes();
    if !changes.is_empty() || !verdict_rule.is_empty() {
        md.push_str("\nRule history (`reports/papers/rule_history.csv`):\n\n");
        for h in verdict_rule {
            let _ = writeln!(
                md,
                "- Every claim: the verdict rule changed on {} (commit {}): {}",
                h.date, h.commit, h.reason
            );
        }
        for h in changes {
            let Some(old) = &h.old else { continue };
            let _ = writeln!(
                md,
                "- {} {}: until {} (commit {}) the rule was {}{}. Why it changed: {}",
                h.paper,
                h.id,
                h.date,
                h.commit,
                old.describe(),
                h.old_id
                    .as_ref()
                    .map_or(String::new(), |id| format!(" (as {id})")),
                h.reason
            );
        }
    }
    md
}

fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}
