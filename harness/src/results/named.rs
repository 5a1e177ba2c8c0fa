//! A row's named figures — its stages' median times and its counters' median values — as a
//! typed map in the order the renderer reported them (a stage list reads as the pipeline).
//!
//! In `results.json` they are a JSON object (`{"sort": 1.5, "draw": 3}`); `results.csv` keeps
//! the text form `name=value;…` in one cell, and files written before the maps were typed
//! (that text form in JSON) still load.

use std::fmt;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Named values in report order. Names are unique (a second `insert` of a name replaces it).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NamedValues(Vec<(String, f64)>);

impl NamedValues {
    pub fn new() -> NamedValues {
        NamedValues(vec![])
    }

    /// The value of `name`, if present.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }

    /// Sets `name` to `value`: in place when present, else at the end.
    pub fn insert(&mut self, name: impl Into<String>, value: f64) {
        let name = name.into();
        match self.0.iter_mut().find(|(n, _)| *n == name) {
            Some(slot) => slot.1 = value,
            None => self.0.push((name, value)),
        }
    }

    pub fn iter(&self) -> impl Iterator<Item = (&str, f64)> {
        self.0.iter().map(|(n, v)| (n.as_str(), *v))
    }

    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.0.iter().map(|(n, _)| n.as_str())
    }

    /// Parses the text form `name=value;name=value` (empty text: no values). A value that is
    /// not a number is an error naming it.
    pub fn parse(text: &str) -> Result<NamedValues, String> {
        let mut out = NamedValues::new();
        for term in text.split(';').map(str::trim).filter(|t| !t.is_empty()) {
            let (name, value) = term
                .split_once('=')
                .ok_or_else(|| format!("{term:?} is not name=value"))?;
            let value: f64 = value
                .trim()
                .parse()
                .map_err(|_| format!("{name}: {value:?} is not a number"))?;
            out.insert(name.trim(), value);
        }
        Ok(out)
    }
}

impl<S: Into<String>> FromIterator<(S, f64)> for NamedValues {
    fn from_iter<I: IntoIterator<Item = (S, f64)>>(iter: I) -> NamedValues {
        let mut out = NamedValues::new();
        for (n, v) in iter {
            out.insert(n, v);
        }
        out
    }
}

impl std::str::FromStr for NamedValues {
    type Err = String;
    fn from_str(text: &str) -> Result<NamedValues, String> {
        NamedValues::parse(text)
    }
}

impl From<&str> for NamedValues {
    /// The text form, for tests and fixtures; text that does not parse gives no values.
    fn from(text: &str) -> NamedValues {
        NamedValues::parse(text).unwrap_or_default()
    }
}

/// A value as the text form writes it: whole numbers without a fraction, others to 4 places.
pub fn trim_float(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        format!("{v:.4}")
    }
}

impl fmt::Display for NamedValues {
    /// The text form `name=value;…` (the `results.csv` cell).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (n, v)) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(";")?;
            }
            write!(f, "{n}={}", trim_float(*v))?;
        }
        Ok(())
    }
}

impl Serialize for NamedValues {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (n, v) in &self.0 {
            // JSON has no NaN: a value that could not be taken (NaN) is written as null.
            map.serialize_entry(n, &v.is_finite().then_some(*v))?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for NamedValues {
    /// A map (in document order), or the text form (CSV cells, older `results.json`).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<NamedValues, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = NamedValues;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map of names to numbers or `name=value;…` text")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<NamedValues, E> {
                NamedValues::parse(v).map_err(E::custom)
            }
            fn visit_unit<E: serde::de::Error>(self) -> Result<NamedValues, E> {
                Ok(NamedValues::new())
            }
            fn visit_none<E: serde::de::Error>(self) -> Result<NamedValues, E> {
                Ok(NamedValues::new())
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut m: A,
            ) -> Result<NamedValues, A::Error> {
                let mut out = NamedValues::new();
                while let Some((k, v)) = m.next_entry::<String, Option<f64>>()? {
                    out.insert(k, v.unwrap_or(f64::NAN));
                }
                Ok(out)
            }
        }
        d.deserialize_any(Visit)
    }
}

/// How JSON Schema sees the maps: names to numbers (null: not taken), or the text form of
/// files written before they were typed.
#[derive(JsonSchema)]
#[allow(dead_code)]
#[schemars(untagged)]
enum NamedValuesSchema {
    Map(std::collections::BTreeMap<String, Option<f64>>),
    Text(String),
}

impl JsonSchema for NamedValues {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "NamedValues".into()
    }

    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        NamedValuesSchema::json_schema(g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_and_map_forms_read_alike_and_keep_order() {
        let text = "sort=1.5;draw=3;fragments=120";
        let v = NamedValues::parse(text).unwrap();
        assert_eq!(v.to_string(), "sort=1.5000;draw=3;fragments=120");
        assert_eq!(v.get("draw"), Some(3.0));
        assert_eq!(v.names().collect::<Vec<_>>(), ["sort", "draw", "fragments"]);
        let json = serde_json::to_string(&v).unwrap();
        assert_eq!(json, r#"{"sort":1.5,"draw":3.0,"fragments":120.0}"#);
        let back: NamedValues = serde_json::from_str(&json).unwrap();
        assert_eq!(back, v);
        let old: NamedValues = serde_json::from_str(&format!("{text:?}")).unwrap();
        assert_eq!(old, v);
        assert!(NamedValues::parse("a=x").unwrap_err().contains("a"));
    }
}
