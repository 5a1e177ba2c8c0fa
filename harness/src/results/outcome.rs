//! What became of a row, as typed values: why it failed ([`Failure`]) and which resource of
//! the roofline bounds it ([`Bound`]); why its image is suspect is [`crate::results::suspect`]'s.
//!
//! Both files keep each as one text column, empty when there is none (`""`, an empty CSV cell),
//! written by `Display` and read back by `FromStr`; a value that does not parse fails the load,
//! naming the field and the text ([`from_text`]).

use std::fmt;
use std::str::FromStr;

use serde::{Deserializer, Serializer};

use crate::results::description::from_text;

/// A row column held as `Option<T>`: its name in the files, for the error of a bad value.
pub trait TextColumn: fmt::Display + FromStr<Err: fmt::Display> {
    const FIELD: &'static str;
}

/// Writes `Some(v)` as `v`'s text and `None` as the empty text
/// (`#[serde(serialize_with = "opt_as_text")]`).
pub fn opt_as_text<T: fmt::Display, S: Serializer>(
    value: &Option<T>,
    s: S,
) -> Result<S::Ok, S::Error> {
    match value {
        Some(v) => s.collect_str(v),
        None => s.serialize_str(""),
    }
}

/// Reads what [`opt_as_text`] wrote (`#[serde(deserialize_with = "opt_from_text")]`).
pub fn opt_from_text<'de, T: TextColumn, D: Deserializer<'de>>(
    d: D,
) -> Result<Option<T>, D::Error> {
    from_text(d, T::FIELD, |text| match text {
        "" => Ok(None),
        text => text.parse().map(Some),
    })
}

/// The resource of the roofline that bounds a row (`tetbench calibrate`,
/// [`crate::calibrate::RESOURCES`]): the one whose work alone takes longest.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Bound {
    TriangleSetup,
    Fill,
    Rasterisation,
    SplatFill,
    RaySteps,
    CpuSort,
    GpuSort,
    Classification,
    /// The per-frame GPU bytes at the copy bandwidth.
    Memory,
}

impl Bound {
    pub const ALL: [Bound; 9] = [
        Bound::TriangleSetup,
        Bound::Fill,
        Bound::Rasterisation,
        Bound::SplatFill,
        Bound::RaySteps,
        Bound::CpuSort,
        Bound::GpuSort,
        Bound::Classification,
        Bound::Memory,
    ];

    /// The name the files, the reports and `docs/roofline.md` use.
    pub fn name(self) -> &'static str {
        match self {
            Bound::TriangleSetup => "triangle setup",
            Bound::Fill => "fill",
            Bound::Rasterisation => "rasterisation",
            Bound::SplatFill => "splat fill",
            Bound::RaySteps => "ray steps",
            Bound::CpuSort => "cpu sort",
            Bound::GpuSort => "gpu sort",
            Bound::Classification => "classification",
            Bound::Memory => "memory",
        }
    }
}

impl fmt::Display for Bound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Bound {
    type Err = String;
    fn from_str(text: &str) -> Result<Bound, String> {
        Bound::ALL
            .into_iter()
            .find(|b| b.name() == text)
            .ok_or_else(|| {
                let names: Vec<&str> = Bound::ALL.iter().map(|b| b.name()).collect();
                format!("not a resource of the roofline ({})", names.join(", "))
            })
    }
}

impl TextColumn for Bound {
    const FIELD: &'static str = "bound_by";
}

/// Where a row failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stage {
    /// The renderer could not be prepared for the data set: the row has no frames.
    Prepare,
    /// A frame, or measuring it (image, metrics, files): the row has no figures.
    Render,
    /// The reference image could not be had: the row keeps its times, without error metrics.
    Reference,
    /// Rounds merged into one row (`ab`): one or more of them failed or was missing.
    Rounds,
}

/// Why a row failed: where, and the error's message.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    pub stage: Stage,
    pub message: String,
}

const PREPARE: &str = "prepare failed: ";
const REFERENCE: &str = "reference for ";

impl Failure {
    pub fn new(stage: Stage, message: impl Into<String>) -> Failure {
        Failure {
            stage,
            message: message.into(),
        }
    }
}

impl fmt::Display for Failure {
    /// The text the files keep: the message after the stage's prefix (`prepare failed: `,
    /// `reference for `; the rounds' messages start with `round N: `, a frame's with nothing).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let prefix = match self.stage {
            Stage::Prepare => PREPARE,
            Stage::Reference => REFERENCE,
            Stage::Render | Stage::Rounds => "",
        };
        write!(f, "{prefix}{}", self.message)
    }
}

/// `round N: …`, the text a merged row's failures start with.
fn is_rounds(text: &str) -> bool {
    text.strip_prefix("round ")
        .and_then(|t| t.split_once(": "))
        .is_some_and(|(n, _)| n.parse::<u32>().is_ok())
}

impl FromStr for Failure {
    type Err = std::convert::Infallible;
    /// Any text is a failure; its prefix says the stage (none: a frame's).
    fn from_str(text: &str) -> Result<Failure, Self::Err> {
        Ok(if let Some(m) = text.strip_prefix(PREPARE) {
            Failure::new(Stage::Prepare, m)
        } else if let Some(m) = text.strip_prefix(REFERENCE) {
            Failure::new(Stage::Reference, m)
        } else if is_rounds(text) {
            Failure::new(Stage::Rounds, text)
        } else {
            Failure::new(Stage::Render, text)
        })
    }
}

impl TextColumn for Failure {
    const FIELD: &'static str = "error";
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_forms_read_back_to_the_same_value() {
        for b in Bound::ALL {
            assert_eq!(b.name().parse::<Bound>(), Ok(b));
        }
        assert!("warp".parse::<Bound>().unwrap_err().contains("ray steps"));
        for f in [
            Failure::new(Stage::Prepare, "out of memory"),
            Failure::new(Stage::Reference, "box:1k +x: lost"),
            Failure::new(Stage::Rounds, "round 2: device lost; round 3: missing"),
            Failure::new(Stage::Render, "device lost"),
        ] {
            assert_eq!(f.to_string().parse::<Failure>().unwrap(), f);
        }
        assert_eq!(
            "round x: y".parse::<Failure>().unwrap().stage,
            Stage::Render
        );
    }
}
