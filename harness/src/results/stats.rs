//! The statistics `compare` and `history` decide with: the Mann–Whitney U test and the factor
//! threshold, as asv (airspeed velocity) decides "faster / slower / no change".
//!
//! Why Mann–Whitney and not criterion's bootstrap: frame times of a GPU renderer are skewed
//! (a few frames hit a page-in, a shader recompile or a busy neighbour) and a run has few of
//! them (3 in the default suite, 10 in the papers' setting). A rank test assumes nothing about
//! the distribution, its exact form is valid for the smallest samples, and it ignores how far
//! an outlier lies; a bootstrap interval from 3–10 samples is too ragged to trust. The factor
//! threshold then keeps statistically real but practically irrelevant shifts (2 % on a busy
//! machine) from being called regressions.

/// Median of a non-empty slice (mean of the middle two for an even count); NaN when empty.
pub fn median(v: &[f64]) -> f64 {
    crate::results::metrics::summarize(v).map_or(f64::NAN, |s| s.median)
}

/// Share `q` ∈ [0, 1] quantile by linear interpolation; NaN when empty.
pub fn quantile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let x = q.clamp(0.0, 1.0) * (s.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x.fract());
    if i + 1 < s.len() {
        s[i] * (1.0 - f) + s[i + 1] * f
    } else {
        s[i]
    }
}

/// Largest sample sizes for which the exact null distribution is used.
const EXACT_MAX: usize = 20;

/// Two-sided p-value of the Mann–Whitney U test of `a` against `b`: exact (by counting
/// arrangements) for samples of up to 20 without ties, else the normal approximation with tie
/// and continuity corrections. `None` when either sample is empty.
pub fn mann_whitney_p(a: &[f64], b: &[f64]) -> Option<f64> {
    let (m, n) = (a.len(), b.len());
    if m == 0 || n == 0 {
        return None;
    }
    // U of `a`: pairs where a wins, ties counting one half.
    let mut u = 0.0f64;
    for x in a {
        for y in b {
            u += if x > y {
                1.0
            } else if x == y {
                0.5
            } else {
                0.0
            };
        }
    }
    let mut all: Vec<f64> = a.iter().chain(b).copied().collect();
    all.sort_by(f64::total_cmp);
    let mut tie_term = 0.0;
    let mut i = 0;
    while i < all.len() {
        let j = (i..all.len())
            .find(|&j| all[j] != all[i])
            .unwrap_or(all.len());
        let t = (j - i) as f64;
        tie_term += t * t * t - t;
        i = j;
    }
    if tie_term == 0.0 && m <= EXACT_MAX && n <= EXACT_MAX {
        let counts = u_distribution(m, n);
        let total: f64 = counts.iter().sum();
        let u = u.round() as usize;
        let lower: f64 = counts[..=u].iter().sum::<f64>() / total;
        let upper: f64 = counts[u..].iter().sum::<f64>() / total;
        return Some((2.0 * lower.min(upper)).min(1.0));
    }
    let (mf, nf) = (m as f64, n as f64);
    let big_n = mf + nf;
    let var = mf * nf / 12.0 * ((big_n + 1.0) - tie_term / (big_n * (big_n - 1.0)));
    if var <= 0.0 {
        return Some(1.0);
    }
    let z = ((u - mf * nf / 2.0).abs() - 0.5).max(0.0) / var.sqrt();
    Some(statrs::function::erf::erfc(z / std::f64::consts::SQRT_2).min(1.0))
}

/// Number of arrangements of m + n distinct values giving each U = 0..=m·n (the recurrence
/// f(m, n, u) = f(m−1, n, u−n) + f(m, n−1, u), Mann & Whitney 1947).
fn u_distribution(m: usize, n: usize) -> Vec<f64> {
    // table[i][j] = distribution for sizes (i, j)
    let mut table: Vec<Vec<Vec<f64>>> = vec![vec![vec![]; n + 1]; m + 1];
    for i in 0..=m {
        for j in 0..=n {
            table[i][j] = if i == 0 || j == 0 {
                vec![1.0]
            } else {
                let mut d = vec![0.0; i * j + 1];
                for (u, c) in table[i - 1][j].iter().enumerate() {
                    d[u + j] += c;
                }
                for (u, c) in table[i][j - 1].iter().enumerate() {
                    d[u] += c;
                }
                d
            };
        }
    }
    std::mem::take(&mut table[m][n])
}

/// Mean, median, minimum and maximum over the viewpoints of a group.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    pub mean: f64,
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Spread {
    /// One value: every statistic is that value (a plot's single point).
    pub fn single(v: f64) -> Spread {
        Spread {
            mean: v,
            median: v,
            min: v,
            max: v,
        }
    }
}

pub fn spread(values: impl Iterator<Item = f64>) -> Option<Spread> {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    Some(Spread {
        mean: v.iter().sum::<f64>() / v.len() as f64,
        median: median(&v),
        min: v.iter().copied().fold(f64::INFINITY, f64::min),
        max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    })
}

/// Holm–Bonferroni step-down adjustment of a family of p-values (`None` stays `None` and is
/// not counted in the family). `compare` tests 32 groups in the default suite: at α = 0.05
/// without a correction, 1.6 of them would be called "slower" by chance alone on an unchanged
/// commit. Holm controls the chance of *any* false call at α and is never less powerful than
/// plain Bonferroni; it assumes nothing about how the tests depend on each other (groups of
/// one run share the machine's state, so they are not independent).
pub fn holm_adjust(p: &[Option<f64>]) -> Vec<Option<f64>> {
    let mut order: Vec<usize> = (0..p.len()).filter(|&i| p[i].is_some()).collect();
    order.sort_by(|&a, &b| p[a].unwrap().total_cmp(&p[b].unwrap()));
    let m = order.len();
    let mut out = vec![None; p.len()];
    let mut running = 0.0f64;
    for (rank, &i) in order.iter().enumerate() {
        let adjusted = ((m - rank) as f64 * p[i].unwrap()).min(1.0);
        // Step-down: an adjusted p is never smaller than the one before it.
        running = running.max(adjusted);
        out[i] = Some(running);
    }
    out
}

/// A small seeded generator for the tests' synthetic samples (xorshift64* + Box–Muller).
#[cfg(test)]
pub(crate) struct TestRng(u64);

#[cfg(test)]
impl TestRng {
    pub fn new(seed: u64) -> TestRng {
        TestRng(seed.max(1))
    }
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact values: 3 vs 3 completely separated has P = 2/20; identical ranks interleaved
    /// give p = 1.
    #[test]
    fn exact_small_samples() {
        let p = mann_whitney_p(&[1.0, 2.0, 3.0], &[4.0, 5.0, 6.0]).unwrap();
        assert!((p - 0.1).abs() < 1e-12, "{p}");
        let p = mann_whitney_p(&[1.0, 4.0, 5.0], &[2.0, 3.0, 6.0]).unwrap();
        assert!(p > 0.6, "{p}");
        // 5 vs 5 separated: 2/252.
        let p = mann_whitney_p(&[1., 2., 3., 4., 5.], &[6., 7., 8., 9., 10.]).unwrap();
        assert!((p - 2.0 / 252.0).abs() < 1e-12, "{p}");
    }

    /// Holm's adjustment on a worked example: sorted p 0.01, 0.02, 0.03 in a family of 3
    /// become 0.03, 0.04, 0.04 (the last raised to keep the step-down monotone), in input order.
    #[test]
    fn holm_worked_example() {
        let adj = holm_adjust(&[Some(0.03), None, Some(0.01), Some(0.02)]);
        let want = [Some(0.04), None, Some(0.03), Some(0.04)];
        for (a, w) in adj.iter().zip(want) {
            match (a, w) {
                (Some(a), Some(w)) => assert!((a - w).abs() < 1e-12, "{adj:?}"),
                (None, None) => {}
                _ => panic!("{adj:?}"),
            }
        }
        assert_eq!(
            holm_adjust(&[Some(0.9), Some(0.8)]),
            vec![Some(1.0), Some(1.0)]
        );
    }

    /// The normal approximation agrees with the exact test where both apply (20 vs 20).
    #[test]
    fn normal_approximation_agrees() {
        let mut rng = TestRng::new(7);
        let a: Vec<f64> = (0..20).map(|_| rng.normal()).collect();
        let b: Vec<f64> = (0..20).map(|_| rng.normal() + 0.8).collect();
        let exact = mann_whitney_p(&a, &b).unwrap();
        let mut a2 = a.clone();
        a2.push(a[0]); // a tie forces the approximation (21 vs 20)
        let approx = mann_whitney_p(&a2, &b).unwrap();
        assert!((exact - approx).abs() < 0.02, "{exact} vs {approx}");
    }

    #[test]
    fn quantiles() {
        assert_eq!(quantile(&[3.0, 1.0, 2.0], 0.5), 2.0);
        assert_eq!(quantile(&[1.0, 2.0], 0.25), 1.25);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
    }
}
