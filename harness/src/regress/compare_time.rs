//! The time verdicts of `tetbench compare` ([`crate::regress::compare`]): asv's rule (Mann–Whitney U
//! plus a factor threshold) on one metric's samples, Holm's adjustment over a family of such
//! tests, and the run-wide factor that is divided out of a run that drifted as a whole.

use serde::{Deserialize, Serialize};

use crate::results::stats::{holm_adjust, mann_whitney_p, median};

/// Fewer groups than this give no run-wide factor: a median of one or two groups would be
/// the change being looked for, not the machine's.
pub const MIN_GROUPS_FOR_DRIFT: usize = 5;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    Faster,
    Slower,
    NoChange,
    /// Fewer than `MIN_ROUNDS` rounds on a side: no verdict.
    TooFewSamples,
    /// Separate runs whose groups scatter too much to gate on time
    /// ([`crate::regress::compare::time_noise`]): no verdict.
    TooNoisy,
}

impl Verdict {
    pub fn label(self) -> &'static str {
        match self {
            Verdict::Faster => "faster",
            Verdict::Slower => "slower",
            Verdict::NoChange => "no change",
            Verdict::TooFewSamples => "too few independent samples",
            Verdict::TooNoisy => "too noisy to judge",
        }
    }
}

/// One time metric of one row (or pooled over a group's viewpoints).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TimeTest {
    pub metric: String,
    pub base_median: f64,
    pub new_median: f64,
    /// new median / base median.
    pub ratio: f64,
    pub p_value: Option<f64>,
    /// `p_value` after Holm's adjustment over the family of gating tests it belongs to (the
    /// groups, or the rows' `total_ms`); the verdict uses it when present.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub p_adjusted: Option<f64>,
    pub verdict: Verdict,
    /// The samples divided by BASE's median (what the ratio plots show).
    pub base_ratios: Vec<f64>,
    pub new_ratios: Vec<f64>,
}

/// The asv-style decision on two samples of one metric.
pub fn time_test(metric: &str, base: &[f64], new: &[f64], threshold: f64, alpha: f64) -> TimeTest {
    let (bm, nm) = (median(base), median(new));
    let scale = |v: &[f64]| v.iter().map(|x| x / bm).collect::<Vec<_>>();
    let p = mann_whitney_p(base, new);
    let ratio = nm / bm;
    let enough = base.len() >= 2 && new.len() >= 2;
    TimeTest {
        metric: metric.to_string(),
        base_median: bm,
        new_median: nm,
        ratio,
        p_value: p,
        p_adjusted: None,
        verdict: decide(enough, ratio, p, threshold, alpha),
        base_ratios: scale(base),
        new_ratios: scale(new),
    }
}

/// asv's rule: a change needs both p < α and a ratio of medians beyond the threshold.
fn decide(enough: bool, ratio: f64, p: Option<f64>, threshold: f64, alpha: f64) -> Verdict {
    let significant = p.is_some_and(|p| p < alpha);
    if !enough || !ratio.is_finite() {
        Verdict::TooFewSamples
    } else if significant && ratio >= threshold {
        Verdict::Slower
    } else if significant && ratio <= 1.0 / threshold {
        Verdict::Faster
    } else {
        Verdict::NoChange
    }
}

impl TimeTest {
    /// Replaces the unpaired decision by the paired one ([`paired_t_tests`]): its ratio and p.
    pub fn with_paired(mut self, ratio: f64, p: Option<f64>, threshold: f64, alpha: f64) -> Self {
        if self.verdict != Verdict::TooFewSamples {
            self.ratio = ratio;
            self.p_value = p;
            self.verdict = decide(true, ratio, p, threshold, alpha);
        }
        self
    }

    /// The p-value as printed: raw, and the Holm-adjusted one that decides when there is one.
    pub fn p_label(&self) -> String {
        match self.p_adjusted {
            Some(a) => format!("{} (Holm {})", fmt_p(self.p_value), fmt_p(Some(a))),
            None => fmt_p(self.p_value),
        }
    }

    /// Decides again with the family-adjusted p-value ([`holm_adjust`]).
    pub fn with_family_p(
        mut self,
        p_adjusted: Option<f64>,
        threshold: f64,
        alpha: f64,
    ) -> TimeTest {
        if self.verdict != Verdict::TooFewSamples {
            self.p_adjusted = p_adjusted;
            self.verdict = decide(true, self.ratio, p_adjusted, threshold, alpha);
        }
        self
    }
}

/// Adjusts the p-values of a family of gating tests together and decides each again.
pub fn adjust_family<'a>(
    tests: impl Iterator<Item = &'a mut TimeTest>,
    threshold: f64,
    alpha: f64,
) {
    let mut tests: Vec<&mut TimeTest> = tests.collect();
    let raw: Vec<Option<f64>> = tests
        .iter()
        .map(|t| t.p_value.filter(|_| t.verdict != Verdict::TooFewSamples))
        .collect();
    for (t, p) in tests.iter_mut().zip(holm_adjust(&raw)) {
        let adjusted = (**t).clone().with_family_p(p, threshold, alpha);
        **t = adjusted;
    }
}

/// NEW's round values divided by the drift: one factor for the whole run, or one per round
/// when the rounds were paired with BASE's ([`pair_factors`]). Values that do not line up with
/// the rounds (a round failed, so the row has one value) take the median of the factors.
pub fn scaled(v: Vec<f64>, factors: &[f64]) -> Vec<f64> {
    match factors {
        [] | [1.0] => v,
        [f] => v.into_iter().map(|x| x / f).collect(),
        per_round if per_round.len() == v.len() => {
            v.into_iter().zip(per_round).map(|(x, f)| x / f).collect()
        }
        per_round => {
            let f = median(per_round);
            v.into_iter().map(|x| x / f).collect()
        }
    }
}

/// The drift of each pair of rounds run side by side (`tetbench ab`: BASE's round i and NEW's
/// round i ran one after the other): per pair, the median over the groups of the group's
/// NEW/BASE (itself the median over its rows). `ratios[g][i]` is group g's ratio in pair i;
/// `None` with fewer than [`MIN_GROUPS_FOR_DRIFT`] groups, or when the groups disagree on the
/// number of pairs.
///
/// Why per pair: on the 2-core VM two rounds of one build a few seconds apart differ as a
/// whole by ×0.8–×1.2 (docs/regression.md, "A/B power"), and the pair that shares that moment
/// shares that factor; dividing it out of each pair, rather than one median out of the whole
/// run, leaves a group's residual scatter instead of the machine's.
pub fn pair_factors(ratios: &[Vec<f64>]) -> Option<Vec<f64>> {
    let pairs = ratios.first()?.len();
    if ratios.len() < MIN_GROUPS_FOR_DRIFT || pairs == 0 || ratios.iter().any(|r| r.len() != pairs)
    {
        return None;
    }
    Some(
        (0..pairs)
            .map(|i| median(&ratios.iter().map(|r| r[i]).collect::<Vec<_>>()))
            .collect(),
    )
}

/// The median of the groups' ratios, from at least [`MIN_GROUPS_FOR_DRIFT`] groups.
///
/// Why: on the 2-core development VM two runs of the same commit a minute apart differ as a
/// whole by ×0.89–×1.25 (ten pairs of default-suite runs, nothing else running), while the
/// frames inside one run agree to a few per cent; no test on the samples can tell such a drift
/// from a change. One renderer made slower leaves the median of 32 groups where it was, so
/// dividing it out keeps every per-group decision about that group. A change that slows
/// every algorithm alike shows in the factor itself, judged against `--drift-limit`.
pub fn run_wide_factor<'a>(group_totals: impl Iterator<Item = &'a TimeTest>) -> Option<f64> {
    let ratios: Vec<f64> = group_totals
        .filter(|t| t.verdict != Verdict::TooFewSamples && t.ratio.is_finite())
        .map(|t| t.ratio)
        .collect();
    (ratios.len() >= MIN_GROUPS_FOR_DRIFT).then(|| median(&ratios))
}

/// The paired test of `tetbench ab`, per group: `logs[g][i]` is group g's ln(NEW/BASE) in
/// pair i with that pair's drift already divided out. Each pair is one independent sample (the
/// viewpoints of a group were reduced to their median within the pair: they ran in the same
/// seconds and are not independent of each other). A one-sample t-test of the mean against 0,
/// with the variance pooled over all groups (df = groups × (pairs − 1)). Returns per group the
/// ratio exp(mean) and the two-sided p; `None` with fewer than 3 pairs or
/// [`MIN_GROUPS_FOR_DRIFT`] groups.
///
/// Why pooled and parametric: five pairs give a group five samples, and no rank test on five
/// can go below p = 1/16 two-sided, let alone below α after Holm over a dozen groups; a t-test
/// on five with its own variance has 4 degrees of freedom and a critical t near 7 after Holm.
/// Pooling the variance over the groups (their scatter comes from the same machine) gives tens
/// of degrees of freedom. Measured on the 2-core VM (docs/regression.md, "A/B power"):
/// the residual per-pair scatter is 0.10–0.20 in ln units for every group.
pub fn paired_t_tests(logs: &[Vec<f64>]) -> Option<Vec<(f64, Option<f64>)>> {
    if logs.len() < MIN_GROUPS_FOR_DRIFT {
        return None;
    }
    pooled_t_tests(logs)
}

/// The t-test of [`paired_t_tests`] for any number of series (at least one) of one length
/// (at least 3): each series' mean against 0, the variance pooled over the series given.
/// compare's rows use it per group of viewpoints (a row's pairs scatter like its group's,
/// not like another algorithm's).
pub fn pooled_t_tests(logs: &[Vec<f64>]) -> Option<Vec<(f64, Option<f64>)>> {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    let n = logs.first()?.len();
    if n < 3 || logs.iter().any(|l| l.len() != n) {
        return None;
    }
    let mean = |l: &[f64]| l.iter().sum::<f64>() / l.len() as f64;
    let df = (logs.len() * (n - 1)) as f64;
    let ss: f64 = logs
        .iter()
        .map(|l| {
            let m = mean(l);
            l.iter().map(|x| (x - m) * (x - m)).sum::<f64>()
        })
        .sum();
    let se = (ss / df).sqrt() / (n as f64).sqrt();
    let t_dist = StudentsT::new(0.0, 1.0, df).ok()?;
    Some(
        logs.iter()
            .map(|l| {
                let m = mean(l);
                let p = if se > 0.0 {
                    Some((2.0 * (1.0 - t_dist.cdf((m / se).abs()))).min(1.0))
                } else {
                    Some(if m == 0.0 { 1.0 } else { 0.0 })
                };
                (m.exp(), p)
            })
            .collect(),
    )
}

pub fn fmt_p(p: Option<f64>) -> String {
    match p {
        Some(p) if p < 0.001 => format!("{p:.1e}"),
        Some(p) => format!("{p:.3}"),
        None => "-".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::stats::TestRng;

    /// Frame times with 8 % multiplicative noise and occasional 30 % spikes, as on a busy
    /// machine.
    fn noisy(rng: &mut TestRng, n: usize, ms: f64) -> Vec<f64> {
        (0..n)
            .map(|_| {
                let spike = if rng.uniform() < 0.1 { 1.3 } else { 1.0 };
                ms * (1.0 + 0.08 * rng.normal()).max(0.5) * spike
            })
            .collect()
    }

    #[test]
    fn a_20_percent_slowdown_is_found() {
        let mut rng = TestRng::new(12);
        let base = noisy(&mut rng, 10, 10.0);
        let new = noisy(&mut rng, 10, 12.0);
        let t = time_test("total_ms", &base, &new, 1.10, 0.05);
        assert_eq!(t.verdict, Verdict::Slower, "{t:?}");
        let t = time_test("total_ms", &new, &base, 1.10, 0.05);
        assert_eq!(t.verdict, Verdict::Faster, "{t:?}");
    }

    #[test]
    fn two_samplings_of_one_distribution_show_no_change() {
        for seed in 1..=20 {
            let mut rng = TestRng::new(seed);
            let a = noisy(&mut rng, 10, 10.0);
            let b = noisy(&mut rng, 10, 10.0);
            let t = time_test("total_ms", &a, &b, 1.10, 0.05);
            assert_eq!(t.verdict, Verdict::NoChange, "seed {seed}: {t:?}");
        }
    }

    /// Eight groups, five pairs, 5 % scatter per pair: the group made ×1.25 slower stands out,
    /// the others do not; fewer than three pairs decide nothing.
    #[test]
    fn paired_t_finds_the_slower_group_only() {
        let mut rng = TestRng::new(7);
        let logs: Vec<Vec<f64>> = (0..8)
            .map(|g| {
                let shift = if g == 3 { 1.25f64.ln() } else { 0.0 };
                (0..5).map(|_| shift + 0.05 * rng.normal()).collect()
            })
            .collect();
        let tests = paired_t_tests(&logs).unwrap();
        for (g, (ratio, p)) in tests.iter().enumerate() {
            let p = p.unwrap();
            if g == 3 {
                assert!(*ratio > 1.15 && p < 1e-4, "{ratio} {p}");
            } else {
                assert!(p > 0.001, "group {g}: {ratio} {p}");
            }
        }
        let short: Vec<Vec<f64>> = logs.iter().map(|l| l[..2].to_vec()).collect();
        assert!(paired_t_tests(&short).is_none());
        assert!(paired_t_tests(&logs[..4]).is_none());
    }

    /// One sample is never enough to decide.
    #[test]
    fn one_number_decides_nothing() {
        let t = time_test("total_ms", &[10.0], &[20.0], 1.10, 0.05);
        assert_eq!(t.verdict, Verdict::TooFewSamples);
    }
}
