//! compare's samples of time: one value per round ([`round_values`]), how many rounds each
//! side holds ([`Rounds`]), and the pooled test per group of viewpoints ([`group_tests`]) that
//! gates (see [`crate::regress::compare`] for why rounds, not frames, are the samples).

use render_core::Settings;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::regress::compare_setup::{key, CompareOptions};
use crate::regress::compare_time::{paired_t_tests, scaled, time_test, TimeTest, Verdict};
use crate::results::aggregate::GroupKey;
use crate::results::description::as_text;
use crate::results::stats::median;
use crate::results::{ResultsFile, Row};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GroupComparison {
    pub algorithm: String,
    #[serde(serialize_with = "as_text")]
    #[schemars(with = "String")]
    pub settings: Settings,
    pub dataset: String,
    /// The group's viewport ([`GroupKey`]): one variant at two sizes is two groups.
    #[serde(default)]
    pub width: u32,
    #[serde(default)]
    pub height: u32,
    #[serde(default)]
    pub projection: String,
    pub viewpoints: usize,
    /// Pooled `total_ms` test over the viewpoints.
    pub total: TimeTest,
}

/// Fewer rounds than this on either side and time is not judged: 2 vs 2 values cannot reach
/// p < 0.05 even pooled over a few viewpoints, and one round is one moment of the machine.
pub const MIN_ROUNDS: u32 = 3;

/// How many independent samples (rounds) each side's rows hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Rounds {
    pub base: u32,
    pub new: u32,
}

impl Rounds {
    pub fn of(base: &ResultsFile, new: &ResultsFile) -> Rounds {
        Rounds {
            base: base.run.rounds.max(1),
            new: new.run.rounds.max(1),
        }
    }

    /// Whether time may be judged at all.
    pub fn enough(self) -> bool {
        self.base.min(self.new) >= MIN_ROUNDS
    }

    /// Why time is not judged (`None`: it is).
    pub fn refusal(self) -> Option<String> {
        (!self.enough()).then(|| {
            format!(
                "time: too few independent samples ({} rounds; BASE {}, NEW {}): frames of one \
                 round are one sample, so no time verdict and no time gate; run both sides with \
                 --rounds {MIN_ROUNDS} or more",
                self.base.min(self.new),
                self.base,
                self.new
            )
        })
    }
}

impl Default for Rounds {
    fn default() -> Self {
        Rounds { base: 1, new: 1 }
    }
}

/// The samples of `metric`, divided by the row's roofline time when normalising.
fn metric_samples(r: &Row, metric: &str, normalised: bool) -> anyhow::Result<Vec<f64>> {
    let s = r.samples.metric(metric);
    if !normalised || s.is_empty() {
        return Ok(s.to_vec());
    }
    let roof = r.roofline_ms.filter(|t| *t > 0.0).ok_or_else(|| {
        anyhow::anyhow!(
            "--normalised: row {} {} {} {} has no roofline (was the run calibrated?)",
            r.algorithm,
            r.settings,
            r.dataset,
            r.viewpoint
        )
    })?;
    Ok(s.iter().map(|x| x / roof).collect())
}

/// One value per round of `metric` (the median of that round's frames), divided by the row's
/// roofline time when normalising. A row's samples hold its rounds one after the other
/// (`run::DatasetContext::run_variants`); samples that do not split evenly into `rounds`
/// (a round failed) give one value, which decides nothing.
pub fn round_values(
    r: &Row,
    metric: &str,
    rounds: u32,
    normalised: bool,
) -> anyhow::Result<Vec<f64>> {
    let s = metric_samples(r, metric, normalised)?;
    let rounds = rounds.max(1) as usize;
    if s.is_empty() {
        return Ok(s);
    }
    if s.len() % rounds != 0 {
        return Ok(vec![median(&s)]);
    }
    Ok(s.chunks(s.len() / rounds).map(median).collect())
}

/// [`time_test`], with the verdict withheld when the runs have too few rounds.
pub(crate) fn round_test(
    metric: &str,
    base: &[f64],
    new: &[f64],
    opt: &CompareOptions,
    rounds: Rounds,
) -> TimeTest {
    let mut t = time_test(metric, base, new, opt.threshold, opt.alpha);
    if !rounds.enough() {
        t.verdict = Verdict::TooFewSamples;
    }
    t
}

/// The pooled `total_ms` test per group of [`GroupKey`] (variant × data set × viewport, the
/// reports' groups); the samples are compare's own, per round.
pub(crate) fn group_tests(
    base: &[Row],
    new: &[Row],
    opt: &CompareOptions,
    scale: &[f64],
    rounds: Rounds,
) -> anyhow::Result<Vec<GroupComparison>> {
    let mut out = vec![];
    // Per group, per pair: the median over its rows of ln(NEW/BASE), NEW already divided by
    // its pair's drift (only when `scale` holds one factor per pair).
    let mut paired_logs: Vec<Option<Vec<f64>>> = vec![];
    let pairs = scale.len();
    for (group, matched) in group_round_values(base, new, rounds, opt)? {
        let (mut bs, mut ns, mut views) = (vec![], vec![], 0);
        let mut per_pair: Vec<Vec<f64>> = vec![vec![]; pairs];
        for (bv, nv) in matched {
            let nv = scaled(nv, scale);
            let m = median(&bv);
            if bv.is_empty() || nv.is_empty() || m.is_nan() || m <= 0.0 {
                continue;
            }
            views += 1;
            if pairs > 1 && bv.len() == pairs && nv.len() == pairs {
                for (i, (b, n)) in bv.iter().zip(&nv).enumerate() {
                    if *b > 0.0 && *n > 0.0 {
                        per_pair[i].push((n / b).ln());
                    }
                }
            }
            bs.extend(bv.iter().map(|x| x / m));
            ns.extend(nv.iter().map(|x| x / m));
        }
        if views == 0 {
            continue;
        }
        paired_logs.push(
            (pairs > 1 && per_pair.iter().all(|v| !v.is_empty()))
                .then(|| per_pair.iter().map(|v| median(v)).collect()),
        );
        out.push(GroupComparison {
            total: round_test("total_ms", &bs, &ns, opt, rounds),
            algorithm: group.algorithm,
            settings: group.settings,
            dataset: group.dataset,
            width: group.width,
            height: group.height,
            projection: group.projection,
            viewpoints: views,
        });
    }
    // Paired rounds: every group judged by the paired t-test instead (when each has a value
    // per pair and there are enough groups to pool the variance).
    let logs: Option<Vec<Vec<f64>>> = paired_logs.into_iter().collect();
    if let Some(tests) = logs.as_deref().and_then(paired_t_tests) {
        for (g, (ratio, p)) in out.iter_mut().zip(tests) {
            g.total = g
                .total
                .clone()
                .with_paired(ratio, p, opt.threshold, opt.alpha);
        }
    }
    Ok(out)
}

/// One matched row's `total_ms` round values: BASE's, then NEW's as measured (not yet scaled).
type RoundPair = (Vec<f64>, Vec<f64>);

/// Per group of [`GroupKey`] (in BASE's order), the round values of each BASE row and its NEW
/// row (rows only in BASE are left out).
fn group_round_values(
    base: &[Row],
    new: &[Row],
    rounds: Rounds,
    opt: &CompareOptions,
) -> anyhow::Result<Vec<(GroupKey, Vec<RoundPair>)>> {
    GroupKey::distinct(base)
        .into_iter()
        .map(|group| {
            let mut matched = vec![];
            for b in base.iter().filter(|r| group.matches(r)) {
                let Some(n) = new.iter().find(|n| key(n) == key(b)) else {
                    continue;
                };
                matched.push((
                    round_values(b, "total_ms", rounds.base, opt.normalised)?,
                    round_values(n, "total_ms", rounds.new, opt.normalised)?,
                ));
            }
            Ok((group, matched))
        })
        .collect()
}

/// Per group, its NEW/BASE in each pair of rounds: the median over its rows of the row's NEW
/// round value over its BASE round value. Rows whose values do not line up with the rounds (a
/// round failed) are left out; a group left with none is skipped.
pub(crate) fn group_pair_ratios(
    base: &[Row],
    new: &[Row],
    rounds: Rounds,
    opt: &CompareOptions,
) -> anyhow::Result<Vec<Vec<f64>>> {
    let pairs = rounds.base as usize;
    let mut out = vec![];
    for (_, matched) in group_round_values(base, new, rounds, opt)? {
        let mut per_pair: Vec<Vec<f64>> = vec![vec![]; pairs];
        for (bv, nv) in matched {
            if bv.len() != pairs || nv.len() != pairs {
                continue;
            }
            for (i, (b, n)) in bv.iter().zip(&nv).enumerate() {
                if *b > 0.0 && n.is_finite() {
                    per_pair[i].push(n / b);
                }
            }
        }
        if per_pair.iter().all(|v| !v.is_empty()) {
            out.push(per_pair.iter().map(|v| median(v)).collect());
        }
    }
    Ok(out)
}
