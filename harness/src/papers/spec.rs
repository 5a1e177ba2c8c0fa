//! What a claim names, typed: its metric ([`Metric`]), its sides ([`VariantSpec`]) and what it
//! expects ([`ExpectSpec`]). `claims.rs` reads them from `reports/papers/claims.csv` and the
//! rule history; `sides.rs` reads a run's rows by them. Both import this module; it imports
//! neither.

use std::fmt;

use render_core::Settings;

use super::verdict::Expect;
use crate::results::Row;

/// The metrics the papers' CPU analyses answer (their modules' `claim_side`), not a run's rows.
pub const ANALYSIS_METRICS: &[&str] = &[
    "sort_ms",
    "sort_keys_per_sec",
    "kbuffer_fragments",
    "kbuffer_pixels_k_gt2",
    "kbuffer_pixels_k_gt6",
    "kbuffer_share_k_gt6",
    "kbuffer_max_k",
    "classifier_mismatches",
    "classifier_geometry_mismatches",
    "dataset_tets",
    "dataset_tets_split",
    "dataset_vertices",
];

/// A claim's metric. Read from a run's rows: the row figures, `counter:NAME`,
/// `counter_per_tet:NAME`, `stage:NAME`, `stage_share:NAME` (the stage over the most expensive
/// other stage), `view_range:METRIC` (range over the viewpoints divided by their mean) and
/// `view_max:METRIC` / `view_min:METRIC`; from two sides' images, `pair_psnr_db`,
/// `pair_psnr_covered_db` and `pair_bad_pixel_share`; from the papers' CPU analyses, one of [`ANALYSIS_METRICS`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Metric {
    TotalMs,
    GpuMs,
    CpuMs,
    Fps,
    TetsPerSec,
    GpuTetsPerSec,
    BytesPerTet,
    /// Every device byte the row's renderer allocated (persistent and per frame).
    GpuBytes,
    PsnrDb,
    Counter(String),
    CounterPerTet(String),
    Stage(String),
    StageShare(String),
    ViewRange(Box<Metric>),
    ViewMax(Box<Metric>),
    ViewMin(Box<Metric>),
    /// PSNR (dB) of side `a`'s image against side `b`'s, the lowest over the viewpoints.
    PairPsnrDb,
    /// PSNR (dB) of side `a`'s image against side `b`'s over the covered pixels only (either
    /// image's α above one 8-bit step), with the peak at `b`'s brightest colour channel: the
    /// error against the picture's own range, not diluted by the background or by a dim
    /// transfer function. The lowest over the viewpoints.
    PairPsnrCoveredDb,
    /// Share of covered pixels of `a` off by more than one 8-bit step from `b`, the largest
    /// over the viewpoints.
    PairBadPixelShare,
    /// A figure of a paper's CPU analyses (one of [`ANALYSIS_METRICS`]).
    Analysis(&'static str),
}

const PLAIN: &[(&str, Metric)] = &[
    ("total_ms", Metric::TotalMs),
    ("gpu_ms", Metric::GpuMs),
    ("cpu_ms", Metric::CpuMs),
    ("fps", Metric::Fps),
    ("tets_per_sec", Metric::TetsPerSec),
    ("gpu_tets_per_sec", Metric::GpuTetsPerSec),
    ("bytes_per_tet", Metric::BytesPerTet),
    ("gpu_bytes", Metric::GpuBytes),
    ("psnr_db", Metric::PsnrDb),
    ("pair_psnr_db", Metric::PairPsnrDb),
    ("pair_psnr_covered_db", Metric::PairPsnrCoveredDb),
    ("pair_bad_pixel_share", Metric::PairBadPixelShare),
];

type Named = fn(String) -> Metric;
const NAMED: &[(&str, Named)] = &[
    ("counter:", Metric::Counter),
    ("counter_per_tet:", Metric::CounterPerTet),
    ("stage:", Metric::Stage),
    ("stage_share:", Metric::StageShare),
];

type Over = fn(Box<Metric>) -> Metric;
const OVER_VIEWS: &[(&str, Over)] = &[
    ("view_range:", Metric::ViewRange),
    ("view_max:", Metric::ViewMax),
    ("view_min:", Metric::ViewMin),
];

impl Metric {
    pub fn parse(text: &str) -> Result<Metric, String> {
        let t = text.trim();
        if let Some((_, m)) = PLAIN.iter().find(|(n, _)| *n == t) {
            return Ok(m.clone());
        }
        if let Some(name) = ANALYSIS_METRICS.iter().find(|n| **n == t) {
            return Ok(Metric::Analysis(name));
        }
        for (prefix, make) in NAMED {
            if let Some(name) = t.strip_prefix(prefix) {
                let ok = !name.is_empty()
                    && name
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                if !ok {
                    return Err(format!("metric {t:?}: {prefix}NAME needs a name"));
                }
                return Ok(make(name.to_string()));
            }
        }
        for (prefix, make) in OVER_VIEWS {
            if let Some(inner) = t.strip_prefix(prefix) {
                let inner = Metric::parse(inner)?;
                if !inner.from_one_row() {
                    return Err(format!(
                        "metric {t:?}: {prefix} reduces a metric of one row, not {inner}"
                    ));
                }
                return Ok(make(Box::new(inner)));
            }
        }
        Err(format!(
            "metric {t:?} is not one of {}, {}, {} or a CPU analysis' {}",
            PLAIN.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "),
            NAMED
                .iter()
                .map(|(p, _)| format!("{p}NAME"))
                .collect::<Vec<_>>()
                .join(", "),
            OVER_VIEWS
                .iter()
                .map(|(p, _)| format!("{p}METRIC"))
                .collect::<Vec<_>>()
                .join(", "),
            ANALYSIS_METRICS.join(", ")
        ))
    }

    /// Whether it compares the images of the claim's two sides (its `b` is then the image
    /// compared with, not a second value).
    pub fn is_pair(&self) -> bool {
        matches!(
            self,
            Metric::PairPsnrDb | Metric::PairPsnrCoveredDb | Metric::PairBadPixelShare
        )
    }

    /// Whether one row gives it (not a reduction over viewpoints, an image pair or an
    /// analysis).
    pub fn from_one_row(&self) -> bool {
        !matches!(
            self,
            Metric::ViewRange(_)
                | Metric::ViewMax(_)
                | Metric::ViewMin(_)
                | Metric::PairPsnrDb
                | Metric::PairPsnrCoveredDb
                | Metric::PairBadPixelShare
                | Metric::Analysis(_)
        )
    }

    /// Whether its value comes from timed frames (a time, a rate from a time, a stage), so
    /// that a verdict on it needs enough frames a side ([`super::verdict::MIN_FRAMES`]).
    pub fn is_timed(&self) -> bool {
        matches!(
            self,
            Metric::TotalMs
                | Metric::GpuMs
                | Metric::CpuMs
                | Metric::Fps
                | Metric::TetsPerSec
                | Metric::GpuTetsPerSec
                | Metric::Stage(_)
                | Metric::StageShare(_)
                | Metric::ViewRange(_)
                | Metric::Analysis("sort_ms" | "sort_keys_per_sec")
        )
    }

    /// The name of an analysis' figure (`None`: not one).
    pub fn analysis_name(&self) -> Option<&'static str> {
        match self {
            Metric::Analysis(n) => Some(n),
            _ => None,
        }
    }

    /// The work counter it reads, if any (`counter:NAME`, `counter_per_tet:NAME`, or one of
    /// them over the viewpoints).
    pub fn counter(&self) -> Option<&str> {
        match self {
            Metric::Counter(n) | Metric::CounterPerTet(n) => Some(n),
            Metric::ViewRange(m) | Metric::ViewMax(m) | Metric::ViewMin(m) => m.counter(),
            _ => None,
        }
    }
}

impl<'de> serde::Deserialize<'de> for Metric {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Metric, D::Error> {
        let text = String::deserialize(d)?;
        Metric::parse(&text).map_err(serde::de::Error::custom)
    }
}

impl fmt::Display for Metric {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some((n, _)) = PLAIN.iter().find(|(_, m)| m == self) {
            return f.write_str(n);
        }
        match self {
            Metric::Counter(n) => write!(f, "counter:{n}"),
            Metric::CounterPerTet(n) => write!(f, "counter_per_tet:{n}"),
            Metric::Stage(n) => write!(f, "stage:{n}"),
            Metric::StageShare(n) => write!(f, "stage_share:{n}"),
            Metric::ViewRange(m) => write!(f, "view_range:{m}"),
            Metric::ViewMax(m) => write!(f, "view_max:{m}"),
            Metric::ViewMin(m) => write!(f, "view_min:{m}"),
            Metric::Analysis(n) => f.write_str(n),
            _ => unreachable!("every plain metric is in PLAIN"),
        }
    }
}

/// One side of a claim: an algorithm (or one of the papers' CPU analyses) and the settings
/// that pick its variant.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(try_from = "String")]
pub struct VariantSpec {
    pub algorithm: String,
    pub settings: Settings,
    /// Pins the side to one data set whatever the claim's data sets are.
    pub dataset: Option<String>,
}

impl TryFrom<String> for VariantSpec {
    type Error = String;
    fn try_from(s: String) -> Result<VariantSpec, String> {
        VariantSpec::parse(&s)
    }
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

    /// Whether `row` is of this side's variant: every pinned setting equal, and no
    /// perturbation (a positive control's setting) on the row that the side does not name.
    pub(crate) fn matches(&self, row: &Row) -> bool {
        self.matches_variant(&row.algorithm, &row.settings)
    }

    /// [`Self::matches`] on a variant's algorithm and settings.
    pub(crate) fn matches_variant(&self, algorithm: &str, settings: &Settings) -> bool {
        algorithm == self.algorithm
            && self
                .settings
                .iter()
                .all(|(k, v)| settings.get(k) == Some(v))
            && !crate::algorithms::perturbed_beyond(algorithm, settings, &self.settings)
    }
}

impl fmt::Display for VariantSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.algorithm)?;
        if !self.settings.is_empty() {
            write!(f, ":{}", self.settings)?;
        }
        if let Some(d) = &self.dataset {
            write!(f, "@{d}")?;
        }
        Ok(())
    }
}

/// Where a pair claim's two sides can differ at all, decided from our own analysis of the data
/// set: `SPEC METRIC>N` or `SPEC METRIC<N` (HAVS H12: `kbuffer-analysis kbuffer_max_k>6`, k = 6
/// and k = 16 draw the same image where no pixel needs more than 6 entries). Where the bound
/// fails the claim reads *not discriminating* there.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(try_from = "String")]
pub struct Discriminates {
    /// What answers the figure (one of the papers' analyses, or a variant whose rows do).
    pub spec: VariantSpec,
    pub metric: Metric,
    /// [`Expect::Above`] or [`Expect::Below`].
    pub bound: Expect,
}

impl TryFrom<String> for Discriminates {
    type Error = String;
    fn try_from(s: String) -> Result<Discriminates, String> {
        Discriminates::parse(&s)
    }
}

impl Discriminates {
    pub fn parse(text: &str) -> Result<Discriminates, String> {
        let bad = |why: &str| {
            format!("discriminates {text:?}: {why} (write SPEC METRIC>N or SPEC METRIC<N)")
        };
        let (spec, cond) = text
            .trim()
            .split_once(' ')
            .ok_or_else(|| bad("no space after the spec"))?;
        let (at, above) = match (cond.find('>'), cond.find('<')) {
            (Some(i), None) => (i, true),
            (None, Some(i)) => (i, false),
            _ => return Err(bad("needs one > or <")),
        };
        let n: f64 = cond[at + 1..]
            .trim()
            .parse()
            .map_err(|_| bad("the bound is not a number"))?;
        Ok(Discriminates {
            spec: VariantSpec::parse(spec.trim())?,
            metric: Metric::parse(&cond[..at])?,
            bound: if above {
                Expect::Above(n)
            } else {
                Expect::Below(n)
            },
        })
    }

    /// Whether `value` lets the sides differ.
    pub fn admits(&self, value: f64) -> bool {
        match self.bound {
            Expect::Below(n) => value < n,
            Expect::Above(n) => value > n,
            _ => unreachable!("parse makes only Above or Below"),
        }
    }
}

impl fmt::Display for Discriminates {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (op, n) = match self.bound {
            Expect::Below(n) => ('<', n),
            Expect::Above(n) => ('>', n),
            _ => unreachable!("parse makes only Above or Below"),
        };
        write!(f, "{} {}{op}{n}", self.spec, self.metric)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_round_trip_and_bad_ones_say_what_is_allowed() {
        for t in [
            "total_ms",
            "counter:model_bytes_per_tet",
            "view_max:counter:steps_max",
            "view_range:gpu_ms",
            "stage_share:sort",
            "pair_psnr_db",
            "pair_psnr_covered_db",
            "kbuffer_share_k_gt6",
        ] {
            assert_eq!(Metric::parse(t).unwrap().to_string(), t);
        }
        assert_eq!(
            Metric::parse("view_max:counter:steps_max").unwrap(),
            Metric::ViewMax(Box::new(Metric::Counter("steps_max".into())))
        );
        let e = Metric::parse("totl_ms").unwrap_err();
        assert!(e.contains("totl_ms") && e.contains("counter:NAME"), "{e}");
        assert!(Metric::parse("counter:").is_err());
        assert!(Metric::parse("view_max:pair_psnr_db").is_err());
        assert!(Metric::parse("stage:").is_err());
    }

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
}
