//! A variant's settings as typed values, from the command line to the result row.
//!
//! [`Settings`] is the one place that parses and formats settings text (`k=6;sort=cpu-radix`,
//! the CSV `settings` column and `--settings` filters); everything else reads typed values
//! ([`Settings::int`], [`Settings::text`]). HAVS's k is an integer from the renderer to the
//! row's JSON map (`{"k": 6, …}`) and back.

use std::fmt;

use serde::{Deserialize, Serialize};

/// One setting's value: an integer (HAVS's k, a grid size) or a word (`cpu-radix`, `5x5`, `on`).
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(untagged)]
pub enum SettingValue {
    Int(i64),
    Text(String),
}

impl SettingValue {
    /// The value read from text without a declaration: a plain decimal integer is an
    /// [`SettingValue::Int`] (written back identically), anything else a word.
    pub fn infer(text: &str) -> SettingValue {
        match text.parse::<i64>() {
            Ok(i) if i.to_string() == text => SettingValue::Int(i),
            _ => SettingValue::Text(text.to_string()),
        }
    }

    pub fn as_int(&self) -> Option<i64> {
        match self {
            SettingValue::Int(i) => Some(*i),
            SettingValue::Text(_) => None,
        }
    }
}

impl fmt::Display for SettingValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SettingValue::Int(i) => write!(f, "{i}"),
            SettingValue::Text(t) => f.write_str(t),
        }
    }
}

macro_rules! int_value {
    ($($t:ty),*) => {$(
        impl From<$t> for SettingValue {
            fn from(v: $t) -> SettingValue {
                SettingValue::Int(v as i64)
            }
        }
    )*};
}
int_value!(u8, u16, u32, u64, usize, i32, i64);

impl From<&str> for SettingValue {
    fn from(v: &str) -> SettingValue {
        SettingValue::Text(v.to_string())
    }
}

impl From<String> for SettingValue {
    fn from(v: String) -> SettingValue {
        SettingValue::Text(v)
    }
}

impl From<bool> for SettingValue {
    /// Switches are written `on`/`off`, as the papers' tables name them.
    fn from(v: bool) -> SettingValue {
        SettingValue::Text(if v { "on" } else { "off" }.to_string())
    }
}

/// One named knob of the paper with its value, as a renderer declares it.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    pub key: &'static str,
    pub value: SettingValue,
}

impl Setting {
    pub fn new(key: &'static str, value: impl Into<SettingValue>) -> Setting {
        Setting {
            key,
            value: value.into(),
        }
    }
}

/// A variant's settings in its declared order. Written as `key=value;key=value` (the CSV
/// column, legends) and as a JSON map in `results.json`; old results with the text form
/// still load.
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Settings(Vec<(String, SettingValue)>);

impl Settings {
    pub fn new() -> Settings {
        Settings::default()
    }

    /// Parses `key=value;key=value` (`,` also separates). A value's type comes from
    /// `declared(key)` when it names one, else from [`SettingValue::infer`].
    pub fn parse_with(
        text: &str,
        declared: impl Fn(&str) -> Option<ValueKind>,
    ) -> Result<Settings, SettingsError> {
        let mut out = Settings::new();
        for part in split_terms(text) {
            let (key, value) = part
                .split_once('=')
                .ok_or_else(|| SettingsError(format!("{part:?} is not key=value")))?;
            let (key, value) = (key.trim(), value.trim());
            if key.is_empty() || value.is_empty() {
                return Err(SettingsError(format!("{part:?} needs a key and a value")));
            }
            if out.get(key).is_some() {
                return Err(SettingsError(format!("{key:?} is given twice")));
            }
            let value = match declared(key) {
                Some(kind) => kind.parse(key, value)?,
                None => SettingValue::infer(value),
            };
            out.0.push((key.to_string(), value));
        }
        Ok(out)
    }

    /// Parses settings text with no declarations (values typed by [`SettingValue::infer`]).
    pub fn parse(text: &str) -> Result<Settings, SettingsError> {
        Settings::parse_with(text, |_| None)
    }

    /// Adds (or replaces) one setting, keeping the first position of its key.
    pub fn with(mut self, key: &str, value: impl Into<SettingValue>) -> Settings {
        self.set(key, value);
        self
    }

    pub fn set(&mut self, key: &str, value: impl Into<SettingValue>) {
        let value = value.into();
        match self.0.iter_mut().find(|(k, _)| k == key) {
            Some(slot) => slot.1 = value,
            None => self.0.push((key.to_string(), value)),
        }
    }

    pub fn get(&self, key: &str) -> Option<&SettingValue> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    /// An integer setting (HAVS's k, a grid size), if present and an integer.
    pub fn int(&self, key: &str) -> Option<i64> {
        self.get(key).and_then(SettingValue::as_int)
    }

    /// A setting as written (`cpu-radix`, `5x5`, `6`).
    pub fn text(&self, key: &str) -> Option<String> {
        self.get(key).map(|v| v.to_string())
    }

    /// An integer setting a constructor needs: missing or a word is an error naming it.
    pub fn require_int(&self, key: &str) -> Result<i64, SettingsError> {
        match self.get(key) {
            Some(SettingValue::Int(i)) => Ok(*i),
            Some(v) => Err(SettingsError(format!("{key}={v}: {key} takes an integer"))),
            None => Err(SettingsError(format!("{key} is missing from {self}"))),
        }
    }

    /// A setting a constructor needs, as written; missing is an error naming it.
    pub fn require_text(&self, key: &str) -> Result<String, SettingsError> {
        self.text(key)
            .ok_or_else(|| SettingsError(format!("{key} is missing from {self}")))
    }

    /// An `on`/`off` switch a constructor needs.
    pub fn require_switch(&self, key: &str) -> Result<bool, SettingsError> {
        match self.require_text(key)?.as_str() {
            "on" => Ok(true),
            "off" => Ok(false),
            v => Err(SettingsError(format!("{key}={v}: {key} is on or off"))),
        }
    }

    /// Whether every setting of `want` has the same value here (a partial match: `want`
    /// pins some keys, the rest may be anything).
    pub fn includes(&self, want: &Settings) -> bool {
        want.iter().all(|(k, v)| self.get(k) == Some(v))
    }

    /// Whether the setting `key` is written `value`.
    pub fn is(&self, key: &str, value: &str) -> bool {
        self.get(key).is_some_and(|v| v.to_string() == value)
    }

    pub fn iter(&self) -> impl Iterator<Item = (&str, &SettingValue)> {
        self.0.iter().map(|(k, v)| (k.as_str(), v))
    }

    pub fn keys(&self) -> impl Iterator<Item = &str> {
        self.0.iter().map(|(k, _)| k.as_str())
    }

    pub fn len(&self) -> usize {
        self.0.len()
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The same settings with every value retyped by `declared` (old results whose text
    /// inferred a different type than the algorithm declares, e.g. a length `2` that the
    /// splatter declares as a word).
    pub fn retyped(self, declared: impl Fn(&str) -> Option<ValueKind>) -> Settings {
        Settings(
            self.0
                .into_iter()
                .map(|(k, v)| {
                    let typed = declared(&k)
                        .and_then(|kind| kind.parse(&k, &v.to_string()).ok())
                        .unwrap_or(v);
                    (k, typed)
                })
                .collect(),
        )
    }
}

impl std::str::FromStr for Settings {
    type Err = SettingsError;
    fn from_str(text: &str) -> Result<Settings, SettingsError> {
        Settings::parse(text)
    }
}

impl From<Vec<Setting>> for Settings {
    fn from(list: Vec<Setting>) -> Settings {
        list.into_iter()
            .fold(Settings::new(), |s, x| s.with(x.key, x.value))
    }
}

impl fmt::Display for Settings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (k, v)) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(";")?;
            }
            write!(f, "{k}={v}")?;
        }
        Ok(())
    }
}

impl Serialize for Settings {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for Settings {
    /// A map (`{"k": 6, "sort": "cpu-radix"}`, in document order) or, from results written
    /// before settings were typed, the text form.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Settings, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = Settings;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map of settings or `key=value;…` text")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Settings, E> {
                Settings::parse(v).map_err(E::custom)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut m: A,
            ) -> Result<Settings, A::Error> {
                let mut out = Settings::new();
                while let Some((k, v)) = m.next_entry::<String, SettingValue>()? {
                    out.0.push((k, v));
                }
                Ok(out)
            }
        }
        d.deserialize_any(Visit)
    }
}

fn split_terms(text: &str) -> impl Iterator<Item = &str> {
    text.split([';', ','])
        .map(str::trim)
        .filter(|p| !p.is_empty())
}

/// The type a parameter's values have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ValueKind {
    Int,
    Text,
}

impl ValueKind {
    pub fn parse(self, key: &str, text: &str) -> Result<SettingValue, SettingsError> {
        match self {
            ValueKind::Int => text
                .parse::<i64>()
                .map(SettingValue::Int)
                .map_err(|_| SettingsError(format!("{key}={text}: {key} takes an integer"))),
            ValueKind::Text => Ok(SettingValue::Text(text.to_string())),
        }
    }
}

/// Settings text that does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("settings: {0}")]
pub struct SettingsError(pub String);

/// A `--settings` filter: `key=value;key=value`, where a value may list alternatives
/// (`k=2|6`). A variant is kept when, for every key it has, its value is one of those asked
/// for; keys a variant does not have are ignored for it, so one filter can span algorithms
/// (`--settings k=6` narrows HAVS and leaves GATOR alone).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SettingsFilter {
    pub terms: Vec<(String, Vec<String>)>,
}

impl SettingsFilter {
    pub fn parse(text: &str) -> Result<SettingsFilter, SettingsError> {
        let mut terms = vec![];
        for part in split_terms(text) {
            let Some((k, v)) = part.split_once('=') else {
                return Err(SettingsError(format!(
                    "{part:?} is not key=value (e.g. variant=linear;k=2|6)"
                )));
            };
            let values: Vec<String> = v
                .split('|')
                .map(|s| s.trim().to_string())
                .filter(|s| !s.is_empty())
                .collect();
            if k.trim().is_empty() || values.is_empty() {
                return Err(SettingsError(format!(
                    "{part:?} needs a key and at least one value"
                )));
            }
            terms.push((k.trim().to_string(), values));
        }
        Ok(SettingsFilter { terms })
    }

    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The values asked for `key`, if the filter names it.
    pub fn values(&self, key: &str) -> Option<&[String]> {
        self.terms
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_slice())
    }

    /// Whether a variant with these settings passes the filter.
    pub fn accepts(&self, settings: &Settings) -> bool {
        self.terms.iter().all(|(k, values)| match settings.get(k) {
            Some(v) => values.contains(&v.to_string()),
            None => true,
        })
    }

    /// Keys that none of `all` has: almost certainly a typo, reported as an error.
    pub fn unknown_keys<'a>(
        &self,
        all: impl IntoIterator<Item = &'a Settings> + Clone,
    ) -> Vec<String> {
        self.terms
            .iter()
            .filter(|(k, _)| !all.clone().into_iter().any(|s| s.get(k).is_some()))
            .map(|(k, _)| k.clone())
            .collect()
    }
}

impl fmt::Display for SettingsFilter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = self
            .terms
            .iter()
            .map(|(k, v)| format!("{k}={}", v.join("|")))
            .collect();
        write!(f, "{}", parts.join(";"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_and_json_round_trip_keep_types_and_order() {
        let s = Settings::parse("k=6;sort=cpu-radix;tiles=5x5;radius=1.5").unwrap();
        assert_eq!(s.int("k"), Some(6));
        assert_eq!(s.text("sort").as_deref(), Some("cpu-radix"));
        assert_eq!(s.int("tiles"), None);
        assert_eq!(s.to_string(), "k=6;sort=cpu-radix;tiles=5x5;radius=1.5");
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(
            json,
            r#"{"k":6,"sort":"cpu-radix","tiles":"5x5","radius":"1.5"}"#
        );
        assert_eq!(serde_json::from_str::<Settings>(&json).unwrap(), s);
        // Results written before typed settings: the text form still loads.
        let old: Settings = serde_json::from_str(r#""k=6;sort=cpu-radix""#).unwrap();
        assert_eq!(old.int("k"), Some(6));
    }

    #[test]
    fn declared_kinds_decide_types_and_reject_bad_values() {
        let kind = |k: &str| match k {
            "k" => Some(ValueKind::Int),
            "radius" => Some(ValueKind::Text),
            _ => None,
        };
        let s = Settings::parse_with("k=2;radius=2", kind).unwrap();
        assert_eq!(s.get("radius"), Some(&SettingValue::Text("2".into())));
        assert!(Settings::parse_with("k=two", kind).is_err());
        assert_eq!(
            Settings::parse("radius=2").unwrap().retyped(kind),
            Settings::new().with("radius", "2")
        );
        // Leading zeros or signs are words, so text round-trips exactly.
        assert_eq!(SettingValue::infer("007"), SettingValue::Text("007".into()));
        assert!(Settings::parse("k").is_err());
        assert!(Settings::parse("k=1;k=2").is_err());
    }

    #[test]
    fn filter_matches_alternatives_and_ignores_foreign_keys() {
        let f = SettingsFilter::parse("variant=linear; k=2|6").unwrap();
        let gator = Settings::new().with("variant", "linear");
        let gator_c = Settings::new().with("variant", "constant");
        let havs6 = Settings::new().with("k", 6u32);
        let havs4 = Settings::new().with("k", 4u32);
        assert!(f.accepts(&gator));
        assert!(!f.accepts(&gator_c));
        assert!(f.accepts(&havs6));
        assert!(!f.accepts(&havs4));
        assert!(f.unknown_keys([&gator, &havs6]).is_empty());
        assert_eq!(
            SettingsFilter::parse("colour=red")
                .unwrap()
                .unknown_keys([&gator_c]),
            vec!["colour"]
        );
        assert!(SettingsFilter::parse("variant").is_err());
        assert!(SettingsFilter::parse("=x").is_err());
        assert!(SettingsFilter::parse("").unwrap().is_empty());
        assert_eq!(f.to_string(), "variant=linear;k=2|6");
    }
}
