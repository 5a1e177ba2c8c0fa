//! The algorithms `tetbench run` knows: name → constructor of its default variants (one
//! renderer per combination of the paper's settings that the tables compare).
//!
//! To add an algorithm, add one line to [`TABLE`].

use render_core::Renderer;

type Variants = fn() -> Vec<Box<dyn Renderer>>;

/// Name on the command line and in result rows → its variants, in the order they are run.
const TABLE: &[(&str, Variants)] = &[
    ("gator-pt", gator_pt::default_variants),
    ("havs", havs::default_variants),
    ("fragment-pt", fragment_pt::default_variants),
];

/// Every algorithm's name, in table order.
pub fn names() -> Vec<&'static str> {
    TABLE.iter().map(|(n, _)| *n).collect()
}

/// The default variants of `name`, or an error listing the known names.
pub fn variants(name: &str) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
    match TABLE.iter().find(|(n, _)| *n == name) {
        Some((_, make)) => Ok(make()),
        None => anyhow::bail!("unknown algorithm {name:?}; known: {}", names().join(", ")),
    }
}

/// A `--settings` filter: `key=value;key=value`, where a value may list alternatives
/// (`k=2|6`). A variant is kept when, for every key it has, its value is one of those asked
/// for; keys a variant does not have are ignored for it, so one filter can span algorithms
/// (`--settings k=6` narrows HAVS and leaves GATOR alone).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SettingsFilter {
    pub terms: Vec<(String, Vec<String>)>,
}

impl SettingsFilter {
    pub fn parse(text: &str) -> anyhow::Result<SettingsFilter> {
        let mut terms = vec![];
        for part in text
            .split([';', ','])
            .map(str::trim)
            .filter(|p| !p.is_empty())
        {
            let Some((k, v)) = part.split_once('=') else {
                anyhow::bail!("--settings: {part:?} is not key=value (e.g. variant=linear;k=2|6)");
            };
            let values: Vec<String> = v
                .split('|')
                .map(|s| s.trim().to_string())
                .filter(|s| !s.is_empty())
                .collect();
            if k.trim().is_empty() || values.is_empty() {
                anyhow::bail!("--settings: {part:?} needs a key and at least one value");
            }
            terms.push((k.trim().to_string(), values));
        }
        Ok(SettingsFilter { terms })
    }

    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Whether a renderer with these settings passes the filter.
    pub fn accepts(&self, settings: &[render_core::Setting]) -> bool {
        self.terms
            .iter()
            .all(|(k, values)| match settings.iter().find(|s| s.key == k) {
                Some(s) => values.contains(&s.value),
                None => true,
            })
    }

    /// Keys that none of `all` has: almost certainly a typo, reported as an error.
    pub fn unknown_keys(&self, all: &[Vec<render_core::Setting>]) -> Vec<String> {
        self.terms
            .iter()
            .filter(|(k, _)| !all.iter().flatten().any(|s| s.key == k))
            .map(|(k, _)| k.clone())
            .collect()
    }
}

impl std::fmt::Display for SettingsFilter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
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
    use render_core::Setting;

    #[test]
    fn filter_matches_alternatives_and_ignores_foreign_keys() {
        let f = SettingsFilter::parse("variant=linear; k=2|6").unwrap();
        let gator = vec![Setting::new("variant", "linear")];
        let gator_c = vec![Setting::new("variant", "constant")];
        let havs6 = vec![Setting::new("k", "6")];
        let havs4 = vec![Setting::new("k", "4")];
        assert!(f.accepts(&gator));
        assert!(!f.accepts(&gator_c));
        assert!(f.accepts(&havs6));
        assert!(!f.accepts(&havs4));
        assert!(f.unknown_keys(&[gator, havs6]).is_empty());
        assert_eq!(
            SettingsFilter::parse("colour=red")
                .unwrap()
                .unknown_keys(&[gator_c]),
            vec!["colour"]
        );
        assert!(SettingsFilter::parse("variant").is_err());
        assert!(SettingsFilter::parse("=x").is_err());
        assert!(SettingsFilter::parse("").unwrap().is_empty());
        assert_eq!(f.to_string(), "variant=linear;k=2|6");
    }

    #[test]
    fn unknown_algorithm_lists_the_known_ones() {
        let e = variants("no-such").err().unwrap().to_string();
        assert!(e.contains("gator-pt"), "{e}");
    }
}
