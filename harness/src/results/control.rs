//! The control as a results set holds it ([`crate::calibrate::control`] measures it): every
//! sample with when it was taken, each row's rounds' figures, the per-figure median and best,
//! one number for the machine's speed ([`speed_factor`]), and what priced a row's roofline
//! ([`Pricing`]).

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::results::machine::Figure;
use crate::results::stats::median;

/// The figures of one control measurement (rates, or the rasterisation's costs).
pub type Figures = BTreeMap<Figure, f64>;

/// One control measurement, as `results.json` keeps it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ControlSample {
    /// The data set whose rounds it brackets.
    pub dataset: String,
    /// Taken before this round of the data set (the number of rounds: after the last).
    pub round: u32,
    /// Rows in the results when it was taken (with one variant at a time, what orders the
    /// samples between the variants' rows).
    pub rows_before: usize,
    /// Seconds since the run started.
    pub at_s: f64,
    /// When it was taken (ISO 8601 UTC).
    pub utc: String,
    /// Wall time the control took (s).
    pub seconds: f64,
    pub figures: Figures,
}

/// The run's control (`results.json`'s `control`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Control {
    /// The probes it times ([`crate::calibrate::probes::Probe::name`]).
    pub probes: Vec<String>,
    /// Wall time (s) preparing the probes took, once per run (choosing each probe's fastest
    /// configuration included).
    #[serde(default)]
    pub setup_seconds: f64,
    pub samples: Vec<ControlSample>,
}

impl Control {
    /// The per-figure median over every sample: what `control_factor` compares a row with.
    pub fn median(&self) -> Figures {
        median_figures(self.samples.iter().map(|s| &s.figures))
    }

    /// Seconds the control took over the run, its preparation included.
    pub fn seconds(&self) -> f64 {
        self.setup_seconds + self.samples.iter().map(|s| s.seconds).sum::<f64>()
    }

    /// The control of each round of a row: `rounds` rounds of `dataset`, the row `index`-th in
    /// the results (one variant at a time: the samples around it in file order). Empty when
    /// a round has no sample around it.
    pub fn rounds_of(&self, dataset: &str, rounds: u32, index: usize) -> Vec<Figures> {
        let of_set: Vec<&ControlSample> = self
            .samples
            .iter()
            .filter(|s| s.dataset == dataset)
            .collect();
        let around: Vec<Vec<&ControlSample>> = if rounds > 1 {
            (0..rounds)
                .map(|r| {
                    of_set
                        .iter()
                        .copied()
                        .filter(|s| s.round == r || s.round == r + 1)
                        .collect()
                })
                .collect()
        } else {
            let before = of_set.iter().rev().find(|s| s.rows_before <= index);
            let after = of_set.iter().find(|s| s.rows_before > index);
            vec![before.into_iter().chain(after).copied().collect()]
        };
        if around.iter().any(Vec::is_empty) {
            return vec![];
        }
        around
            .iter()
            .map(|samples| best_figures(samples.iter().map(|s| &s.figures)))
            .collect()
    }
}

/// Figure by figure the fastest of several measurements.
pub fn best_figures<'a>(all: impl Iterator<Item = &'a Figures>) -> Figures {
    let mut out = Figures::new();
    for figures in all {
        for (&f, &v) in figures {
            let speed = f.speed(v);
            let e = out.entry(f).or_insert(v);
            if speed > f.speed(*e) {
                *e = v;
            }
        }
    }
    out
}

/// Figure by figure the median (of speeds) over several measurements.
pub fn median_figures<'a>(all: impl Iterator<Item = &'a Figures>) -> Figures {
    let mut speeds: BTreeMap<Figure, Vec<f64>> = BTreeMap::new();
    for figures in all {
        for (&f, &v) in figures {
            if f.speed(v) > 0.0 {
                speeds.entry(f).or_default().push(f.speed(v));
            }
        }
    }
    speeds
        .into_iter()
        .map(|(f, s)| (f, f.from_speed(median(&s))))
        .collect()
}

/// How much faster `a` is than `b`: the geometric mean over the figures both measured of
/// speed(a) / speed(b) (`None`: no figure in common). One number for "the machine".
pub fn speed_factor(a: &Figures, b: &Figures) -> Option<f64> {
    let logs: Vec<f64> = a
        .iter()
        .filter_map(|(f, &va)| {
            let (sa, sb) = (f.speed(va), f.speed(*b.get(f)?));
            (sa > 0.0 && sb > 0.0).then(|| (sa / sb).ln())
        })
        .collect();
    (!logs.is_empty()).then(|| (logs.iter().sum::<f64>() / logs.len() as f64).exp())
}

/// A row's figures over its rounds: per figure the median of its rounds' controls.
pub fn row_figures(rounds: &[Figures]) -> Figures {
    median_figures(rounds.iter())
}

/// What a row's roofline was priced with (`priced_with` in the results).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum Pricing {
    /// Not priced (no calibration, or no work counted).
    #[default]
    None,
    /// The cached calibration: a results set without a control.
    Calibration,
    /// The control of the row's own rounds; `scaled`: the priced figures the control did not
    /// measure, taken from the calibration times the control's factor.
    Control { scaled: Vec<Figure> },
}

impl std::fmt::Display for Pricing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Pricing::None => Ok(()),
            Pricing::Calibration => f.write_str("calibration"),
            Pricing::Control { scaled } if scaled.is_empty() => f.write_str("control"),
            Pricing::Control { scaled } => {
                let names: Vec<&str> = scaled.iter().map(|s| s.name()).collect();
                write!(f, "control, scaled {}", names.join(" "))
            }
        }
    }
}

impl std::str::FromStr for Pricing {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let figure = |name: &str| {
            Figure::ALL
                .into_iter()
                .find(|f| f.name() == name)
                .ok_or_else(|| format!("priced_with: unknown figure {name:?}"))
        };
        match s {
            "" => Ok(Pricing::None),
            "calibration" => Ok(Pricing::Calibration),
            "control" => Ok(Pricing::Control { scaled: vec![] }),
            other => match other.strip_prefix("control, scaled ") {
                Some(list) => Ok(Pricing::Control {
                    scaled: list.split(' ').map(figure).collect::<Result<_, _>>()?,
                }),
                None => Err(format!("priced_with: {other:?} is not a pricing")),
            },
        }
    }
}

impl Serialize for Pricing {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for Pricing {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

impl JsonSchema for Pricing {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Pricing".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "type": "string",
            "description": "What priced the roofline: empty, `calibration`, `control`, or \
                            `control, scaled FIGURE…`"
        })
    }
}
