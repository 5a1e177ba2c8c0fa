//! The one rule that turns measured numbers into a verdict on a paper's claim.
//!
//! Eight verdicts, nothing else: *holds*, *does not hold*, *within noise* (the difference lies
//! inside the samples' spread or the claim's tolerance), *too few frames* (a timed side has
//! fewer than [`MIN_FRAMES`] frames behind a sample: its spread is not known well enough to
//! decide anything, an ordering, a ratio or a threshold), *not discriminating* (our own
//! analysis of the data set says the two sides cannot differ there), *insensitive* (the claim's
//! positive control, a known perturbation, passes the rule too), *not testable on this adapter* (a
//! claim about GPU speed measured on a software rasteriser: the numbers are shown, the verdict
//! is withheld) and *not checkable* (a side is missing, with why). Every
//! [`Evaluation`] carries the numbers it used and the variants (algorithm and settings) of each
//! side, so a reader can redo it.

use std::fmt::Write as _;

/// The verdict vocabulary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    Holds,
    DoesNotHold,
    WithinNoise,
    TooFewFrames,
    /// The two sides cannot differ on this data set (the claim's `discriminates` bound fails
    /// on our own analysis of it): whatever they read is no evidence.
    NotDiscriminating,
    /// The rule would have held, but its positive control (a known perturbation run on the
    /// same data) passes it too: the rule cannot tell a fault here.
    Insensitive,
    NotTestableOnThisAdapter,
    NotCheckable,
}

/// The frames a timed sample needs before a verdict rests on it: a timing or threshold claim
/// decides only with at least this many frames a side, and a margin beyond their spread.
pub const MIN_FRAMES: u32 = 5;

impl Verdict {
    pub fn label(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::DoesNotHold => "does not hold",
            Verdict::WithinNoise => "within noise",
            Verdict::TooFewFrames => "too few frames",
            Verdict::NotDiscriminating => "not discriminating",
            Verdict::Insensitive => "insensitive",
            Verdict::NotTestableOnThisAdapter => "not testable on this adapter",
            Verdict::NotCheckable => "not checkable",
        }
    }

    /// Every verdict, in the order reports count them.
    pub const ALL: [Verdict; 8] = [
        Verdict::Holds,
        Verdict::DoesNotHold,
        Verdict::WithinNoise,
        Verdict::TooFewFrames,
        Verdict::NotDiscriminating,
        Verdict::Insensitive,
        Verdict::NotTestableOnThisAdapter,
        Verdict::NotCheckable,
    ];
}

/// What a claim's verdict depends on besides the method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum Hardware {
    /// Geometry and counts: the same on every machine.
    None,
    /// CPU speed: our CPU is a real one, so the claim is tested (against a different CPU).
    Cpu,
    /// GPU hardware: its speed, or what its concurrency does (HAVS's fragment race):
    /// meaningless on a software rasteriser.
    Gpu,
}

impl TryFrom<String> for Hardware {
    type Error = String;
    fn try_from(s: String) -> Result<Hardware, String> {
        match s.as_str() {
            "none" => Ok(Hardware::None),
            "cpu" => Ok(Hardware::Cpu),
            "gpu" => Ok(Hardware::Gpu),
            s => Err(format!("hardware {s:?} is not none, cpu or gpu")),
        }
    }
}

/// One measurement of one side: a viewpoint's (or one run's) median and its frames' range.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    pub key: String,
    pub value: f64,
    pub min: f64,
    pub max: f64,
    /// Timed frames behind `value`: 1 means no spread is known; 0 marks a value that has no
    /// noise at all (a count, a byte size).
    pub frames: u32,
}

impl Sample {
    /// A value without noise (a count, a byte size).
    pub fn exact(key: impl Into<String>, value: f64) -> Sample {
        Sample {
            key: key.into(),
            value,
            min: value,
            max: value,
            frames: 0,
        }
    }
}

/// One side of a claim: what was measured (the label names the algorithm and its variant) and
/// its samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Side {
    pub label: String,
    pub samples: Vec<Sample>,
}

impl Side {
    pub fn new(label: impl Into<String>, samples: Vec<Sample>) -> Side {
        Side {
            label: label.into(),
            samples,
        }
    }

    /// Mean of the samples' values.
    pub fn centre(&self) -> f64 {
        self.samples.iter().map(|s| s.value).sum::<f64>() / self.samples.len().max(1) as f64
    }

    /// Mean of the samples' ranges (max − min of their frames).
    pub fn spread(&self) -> f64 {
        self.samples.iter().map(|s| s.max - s.min).sum::<f64>() / self.samples.len().max(1) as f64
    }

    /// The fewest frames behind a timed sample (`None`: no sample is timed; counts and sizes
    /// have no frames).
    pub fn fewest_frames(&self) -> Option<u32> {
        self.samples
            .iter()
            .filter(|s| s.frames > 0)
            .map(|s| s.frames)
            .min()
    }

    fn describe(&self) -> String {
        if self.samples.iter().all(|s| s.frames == 0) {
            return format!("{} = {}", self.label, fmt(self.centre()));
        }
        let frames = self.samples.iter().map(|s| s.frames).min().unwrap_or(0);
        format!(
            "{} = {} (spread {}, {} sample(s), ≥{frames} frame(s) each)",
            self.label,
            fmt(self.centre()),
            fmt(self.spread()),
            self.samples.len()
        )
    }
}

/// What the claim expects of side `a` (and `b` where there is one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Expect {
    /// a < b.
    Less,
    /// a > b.
    Greater,
    /// a > threshold.
    Above(f64),
    /// a < threshold.
    Below(f64),
    /// a / b (or a alone, without b) within [lo, hi].
    Band(f64, f64),
    /// a equals the value (an exact count), within the tolerance.
    Equals(f64),
}

/// A claim's check: what it expects, its relative tolerance, what it depends on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Check {
    pub expect: Expect,
    pub tolerance: f64,
    pub hardware: Hardware,
}

/// A verdict with the numbers and variants it rests on.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    pub verdict: Verdict,
    /// The sides' values, spreads and the comparison, in words.
    pub numbers: String,
    /// Each side's label (algorithm, variant, data set).
    pub variants: Vec<String>,
}

impl Evaluation {
    pub fn not_checkable(why: impl Into<String>) -> Evaluation {
        Evaluation {
            verdict: Verdict::NotCheckable,
            numbers: why.into(),
            variants: vec![],
        }
    }
}

fn fmt(v: f64) -> String {
    if v == 0.0 || (v.abs() >= 0.01 && v.abs() < 1e6) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.3e}")
    }
}

/// The rule. `a` and `b` are the sides, or why one is missing; `software_adapter` says whether
/// the GPU numbers came from a software rasteriser.
pub fn evaluate(
    check: &Check,
    a: Result<&Side, String>,
    b: Option<Result<&Side, String>>,
    software_adapter: bool,
) -> Evaluation {
    let a = match a {
        Ok(s) if !s.samples.is_empty() => s,
        Ok(s) => return Evaluation::not_checkable(format!("{}: no measurement", s.label)),
        Err(why) => return Evaluation::not_checkable(why),
    };
    let b = match b {
        None => None,
        Some(Ok(s)) if !s.samples.is_empty() => Some(s),
        Some(Ok(s)) => return Evaluation::not_checkable(format!("{}: no measurement", s.label)),
        Some(Err(why)) => return Evaluation::not_checkable(why),
    };
    let mut variants = vec![a.label.clone()];
    variants.extend(b.map(|b| b.label.clone()));
    let (verdict, mut numbers) = decide(check, a, b);
    if check.hardware == Hardware::Gpu && software_adapter {
        let _ = write!(
            numbers,
            "; a claim on GPU hardware (its speed, or fragments shaded concurrently) measured on a software rasteriser: on this adapter it would read \"{}\"",
            verdict.label()
        );
        return Evaluation {
            verdict: Verdict::NotTestableOnThisAdapter,
            numbers,
            variants,
        };
    }
    Evaluation {
        verdict,
        numbers,
        variants,
    }
}

/// The verdict on the numbers alone (hardware aside).
impl Verdict {
    /// Holds or does not hold: a decided claim.
    fn of_hold(holds: bool) -> Verdict {
        if holds {
            Verdict::Holds
        } else {
            Verdict::DoesNotHold
        }
    }
}

fn decide(check: &Check, a: &Side, b: Option<&Side>) -> (Verdict, String) {
    let tol = check.tolerance.max(0.0);
    let mut text = a.describe();
    if let Some(b) = b {
        let _ = write!(text, " vs {}", b.describe());
    }
    let fewest = [Some(a), b]
        .into_iter()
        .flatten()
        .filter_map(Side::fewest_frames)
        .min();
    if let Some(n) = fewest.filter(|n| *n < MIN_FRAMES) {
        let _ = write!(
            text,
            "; {n} frame(s) behind a sample: a timing decides on at least {MIN_FRAMES} frames a side"
        );
        return (Verdict::TooFewFrames, text);
    }
    match (check.expect, b) {
        (Expect::Less | Expect::Greater, Some(b)) => {
            let want_less = check.expect == Expect::Less;
            let diff = b.centre() - a.centre();
            let noise = a.spread().max(b.spread());
            let scale = a.centre().abs().min(b.centre().abs());
            let _ = write!(
                text,
                "; difference {} (noise {}, tolerance {})",
                fmt(diff.abs()),
                fmt(noise),
                fmt(tol * scale)
            );
            if diff.abs() <= noise || diff.abs() <= tol * scale {
                return (Verdict::WithinNoise, text);
            }
            let holds = (diff > 0.0) == want_less;
            (Verdict::of_hold(holds), text)
        }
        (Expect::Above(t) | Expect::Below(t), _) => {
            let v = a.centre();
            let margin = a.spread().max(tol * t.abs());
            let _ = write!(text, "; threshold {} (margin {})", fmt(t), fmt(margin));
            if (v - t).abs() <= margin {
                return (Verdict::WithinNoise, text);
            }
            let above = v > t;
            let holds = above == matches!(check.expect, Expect::Above(_));
            (Verdict::of_hold(holds), text)
        }
        (Expect::Band(lo, hi), b) => {
            let (lo, hi) = (lo * (1.0 - tol), hi * (1.0 + tol));
            let (ca, ha) = (a.centre(), a.spread() / 2.0);
            let (r_lo, r_hi, r) = match b {
                Some(b) => {
                    let (cb, hb) = (b.centre(), b.spread() / 2.0);
                    let lo_den = (cb - hb).max(f64::MIN_POSITIVE);
                    ((ca - ha) / (cb + hb), (ca + ha) / lo_den, ca / cb)
                }
                None => (ca - ha, ca + ha, ca),
            };
            let _ = write!(
                text,
                "; {} {} (range {}–{}) against the band {}–{}",
                if b.is_some() { "ratio" } else { "value" },
                fmt(r),
                fmt(r_lo),
                fmt(r_hi),
                fmt(lo),
                fmt(hi)
            );
            if r_lo >= lo && r_hi <= hi {
                (Verdict::Holds, text)
            } else if r_hi < lo || r_lo > hi {
                (Verdict::DoesNotHold, text)
            } else {
                (Verdict::WithinNoise, text)
            }
        }
        (Expect::Equals(v), _) => {
            let ours = a.centre();
            let ok = (ours - v).abs() <= tol * v.abs();
            let _ = write!(
                text,
                "; expected {}{}",
                fmt(v),
                if tol > 0.0 {
                    format!(" within {}%", fmt(tol * 100.0))
                } else {
                    " exactly".into()
                }
            );
            (Verdict::of_hold(ok), text)
        }
        (Expect::Less | Expect::Greater, None) => (
            Verdict::NotCheckable,
            format!("{text}; an ordering needs two sides"),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn side(label: &str, values: &[(f64, f64, f64)], frames: u32) -> Side {
        Side::new(
            label,
            values
                .iter()
                .enumerate()
                .map(|(i, &(value, min, max))| Sample {
                    key: format!("v{i}"),
                    value,
                    min,
                    max,
                    frames,
                })
                .collect(),
        )
    }

    fn check(expect: Expect, tolerance: f64, hardware: Hardware) -> Check {
        Check {
            expect,
            tolerance,
            hardware,
        }
    }

    fn verdict(c: &Check, a: &Side, b: Option<&Side>, software: bool) -> Verdict {
        evaluate(c, Ok(a), b.map(Ok), software).verdict
    }

    #[test]
    fn an_ordering_inside_the_spread_is_noise_and_outside_it_decides() {
        let c = check(Expect::Less, 0.0, Hardware::Cpu);
        // HAVS k=2 vs k=6 on spx2 as once reported: 2207.5 vs 2209.6 ms with frames spread
        // over ±20 ms.
        let k2 = side("havs k=2", &[(2207.5, 2190.0, 2230.0)], 5);
        let k6 = side("havs k=6", &[(2209.6, 2188.0, 2231.0)], 5);
        assert_eq!(verdict(&c, &k2, Some(&k6), false), Verdict::WithinNoise);
        // The same spread, k=6 100 ms slower: decided.
        let k6_slow = side("havs k=6", &[(2309.6, 2290.0, 2330.0)], 5);
        assert_eq!(verdict(&c, &k2, Some(&k6_slow), false), Verdict::Holds);
        assert_eq!(
            verdict(&c, &k6_slow, Some(&k2), false),
            Verdict::DoesNotHold
        );
        let g = check(Expect::Greater, 0.0, Hardware::Cpu);
        assert_eq!(verdict(&g, &k6_slow, Some(&k2), false), Verdict::Holds);
    }

    #[test]
    fn fewer_than_five_frames_a_side_decide_nothing() {
        let c = check(Expect::Less, 0.0, Hardware::Cpu);
        let a = side("a", &[(100.0, 100.0, 100.0)], 1);
        let b = side("b", &[(200.0, 200.0, 200.0)], 1);
        let e = evaluate(&c, Ok(&a), Some(Ok(&b)), false);
        assert_eq!(e.verdict, Verdict::TooFewFrames);
        assert!(e.numbers.contains("at least 5 frames"), "{}", e.numbers);
        assert_eq!(e.variants, vec!["a".to_string(), "b".to_string()]);
        // Four frames a side: still too few; five: decided, the same numbers.
        let (a4, b4) = (
            side("a", &[(100.0, 99.0, 101.0)], 4),
            side("b", &[(200.0, 199.0, 201.0)], 4),
        );
        assert_eq!(verdict(&c, &a4, Some(&b4), false), Verdict::TooFewFrames);
        let (a5, b5) = (
            side("a", &[(100.0, 99.0, 101.0)], 5),
            side("b", &[(200.0, 199.0, 201.0)], 5),
        );
        assert_eq!(verdict(&c, &a5, Some(&b5), false), Verdict::Holds);
        // One side short is enough to withhold it.
        assert_eq!(verdict(&c, &a5, Some(&b4), false), Verdict::TooFewFrames);
        // A ratio band is no different.
        let band = check(Expect::Band(1.5, 2.5), 0.0, Hardware::Cpu);
        assert_eq!(verdict(&band, &b, Some(&a), false), Verdict::TooFewFrames);
        assert_eq!(verdict(&band, &b5, Some(&a5), false), Verdict::Holds);
        // A threshold on one frame decided with zero margin before; now it waits for five
        // frames and then needs a margin beyond their spread.
        let above = check(Expect::Above(100.0), 0.0, Hardware::Cpu);
        let one = side("a", &[(101.0, 101.0, 101.0)], 1);
        assert_eq!(verdict(&above, &one, None, false), Verdict::TooFewFrames);
        let close = side("a", &[(101.0, 99.0, 103.0)], 5);
        assert_eq!(verdict(&above, &close, None, false), Verdict::WithinNoise);
        let clear = side("a", &[(110.0, 109.0, 111.0)], 5);
        assert_eq!(verdict(&above, &clear, None, false), Verdict::Holds);
        // Counts and sizes have no frames: decided as before.
        let count = Side::new("bytes", vec![Sample::exact("x", 101.0)]);
        assert_eq!(verdict(&above, &count, None, false), Verdict::Holds);
    }

    #[test]
    fn the_claims_tolerance_absorbs_small_differences() {
        let a = side("a", &[(100.0, 99.9, 100.1)], 5);
        let b = side("b", &[(104.0, 103.9, 104.1)], 5);
        let strict = check(Expect::Less, 0.0, Hardware::Cpu);
        let loose = check(Expect::Less, 0.05, Hardware::Cpu);
        assert_eq!(verdict(&strict, &a, Some(&b), false), Verdict::Holds);
        assert_eq!(verdict(&loose, &a, Some(&b), false), Verdict::WithinNoise);
        // Exact counts: 2 % absorbs 6,568,992 against 6,615,778; 0.5 % does not.
        let ours = Side::new("fragments", vec![Sample::exact("spx2", 6_568_992.0)]);
        let two = check(Expect::Equals(6_615_778.0), 0.02, Hardware::None);
        let half = check(Expect::Equals(6_615_778.0), 0.005, Hardware::None);
        assert_eq!(verdict(&two, &ours, None, true), Verdict::Holds);
        assert_eq!(verdict(&half, &ours, None, true), Verdict::DoesNotHold);
        // Thresholds: 16 M/s against "more than 15 M/s" holds; with a 10 % tolerance it is
        // too close to call; 12 M/s does not hold.
        let rate = Side::new("radix", vec![Sample::exact("1M", 16e6)]);
        let above = check(Expect::Above(15e6), 0.0, Hardware::Cpu);
        assert_eq!(verdict(&above, &rate, None, false), Verdict::Holds);
        let above_tol = check(Expect::Above(15e6), 0.1, Hardware::Cpu);
        assert_eq!(
            verdict(&above_tol, &rate, None, false),
            Verdict::WithinNoise
        );
        let slow = Side::new("radix", vec![Sample::exact("1M", 12e6)]);
        assert_eq!(verdict(&above, &slow, None, false), Verdict::DoesNotHold);
        let below = check(Expect::Below(15e6), 0.0, Hardware::Cpu);
        assert_eq!(verdict(&below, &slow, None, false), Verdict::Holds);
    }

    #[test]
    fn gpu_claims_on_a_software_adapter_are_not_testable_but_show_their_numbers() {
        let a = side("a", &[(100.0, 99.0, 101.0)], 5);
        let b = side("b", &[(200.0, 199.0, 201.0)], 5);
        let gpu = check(Expect::Less, 0.0, Hardware::Gpu);
        let e = evaluate(&gpu, Ok(&a), Some(Ok(&b)), true);
        assert_eq!(e.verdict, Verdict::NotTestableOnThisAdapter);
        assert!(e.numbers.contains("would read \"holds\""), "{}", e.numbers);
        // The same claim on a hardware adapter, and a geometric claim on the software one.
        assert_eq!(verdict(&gpu, &a, Some(&b), false), Verdict::Holds);
        let geometry = check(Expect::Less, 0.0, Hardware::None);
        assert_eq!(verdict(&geometry, &a, Some(&b), true), Verdict::Holds);
    }

    #[test]
    fn missing_sides_are_not_checkable_with_why() {
        let a = side("a", &[(1.0, 1.0, 1.0)], 5);
        let c = check(Expect::Less, 0.0, Hardware::None);
        let e = evaluate(&c, Ok(&a), Some(Err("raycast not measured".into())), false);
        assert_eq!(e.verdict, Verdict::NotCheckable);
        assert!(e.numbers.contains("raycast not measured"));
        let empty = Side::new("b", vec![]);
        assert_eq!(verdict(&c, &a, Some(&empty), false), Verdict::NotCheckable);
        assert_eq!(verdict(&c, &a, None, false), Verdict::NotCheckable);
    }

    #[test]
    fn a_band_straddled_by_the_spread_is_noise() {
        let band = check(Expect::Band(2.0, 2.5), 0.0, Hardware::Cpu);
        let cpu = side("cpu", &[(10.0, 9.9, 10.1)], 5);
        let inside = side("gpu", &[(22.0, 21.9, 22.1)], 5);
        let straddling = side("gpu", &[(20.5, 19.0, 22.0)], 5);
        let outside = side("gpu", &[(40.0, 39.9, 40.1)], 5);
        assert_eq!(verdict(&band, &inside, Some(&cpu), false), Verdict::Holds);
        assert_eq!(
            verdict(&band, &straddling, Some(&cpu), false),
            Verdict::WithinNoise
        );
        assert_eq!(
            verdict(&band, &outside, Some(&cpu), false),
            Verdict::DoesNotHold
        );
        // One side alone against the band.
        let alone = check(Expect::Band(18.0, 22.0), 0.0, Hardware::None);
        let b19 = Side::new("B/tet", vec![Sample::exact("x", 19.5)]);
        let b23 = Side::new("B/tet", vec![Sample::exact("x", 23.5)]);
        assert_eq!(verdict(&alone, &b19, None, false), Verdict::Holds);
        assert_eq!(verdict(&alone, &b23, None, false), Verdict::DoesNotHold);
    }
}
