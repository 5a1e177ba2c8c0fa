//! The algorithms `tetbench run` knows: name → constructors of its default variants (one
//! renderer per combination of the paper's settings that the tables compare) and of every
//! variant it offers (what `--settings` selects from).
//!
//! To add an algorithm, add one line to [`TABLE`].

use render_core::Renderer;

type Variants = fn() -> Vec<Box<dyn Renderer>>;

/// Name on the command line and in result rows → (default variants, every variant), each in
/// the order they are run.
const TABLE: &[(&str, Variants, Variants)] = &[
    ("gator-pt", gator_pt::default_variants, all_gator_variants),
    ("havs", havs::default_variants, havs::all_variants),
    (
        "fragment-pt",
        fragment_pt::default_variants,
        fragment_pt::all_variants,
    ),
    ("raycast", raycast::default_variants, raycast::all_variants),
    ("splat", splat::default_variants, splat::all_variants),
    ("vtk-pt", vtk_peer::pt_variants, vtk_peer::pt_variants),
    (
        "vtk-raycast",
        vtk_peer::raycast_default_variants,
        vtk_peer::raycast_all_variants,
    ),
    (
        "vtk-zsweep",
        vtk_peer::zsweep_default_variants,
        vtk_peer::zsweep_all_variants,
    ),
];

/// Peers: other software's renderers measured beside tetbench's (`--peers vtk`). They are not
/// part of "all algorithms" and are marked as peers in the reports.
pub const PEERS: &[(&str, &[&str])] = &[("vtk", &["vtk-pt", "vtk-raycast", "vtk-zsweep"])];

/// Whether `name` is a peer (another package's renderer, or an external renderer given with
/// `--external`) rather than a tetbench algorithm.
pub fn is_peer(name: &str) -> bool {
    peer_kind(name).is_some()
}

/// The kind of peer `name` is: its group in [`PEERS`] (`vtk`), or `external` for a renderer
/// given with `--external` (or met in results with the `peer=external` setting).
pub fn peer_kind(name: &str) -> Option<&'static str> {
    if let Some((group, _)) = PEERS.iter().find(|(_, names)| names.contains(&name)) {
        return Some(group);
    }
    let known = EXTERNAL_NAMES.lock().unwrap_or_else(|p| p.into_inner());
    known.iter().any(|n| n == name).then_some("external")
}

/// Names of external renderers this process has met. The name alone is what reports and
/// charts ask about, so `--external` and results read back register them here.
static EXTERNAL_NAMES: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());

/// Registers `name` as an external renderer (a peer of kind `external`).
pub fn note_external(name: &str) {
    let mut known = EXTERNAL_NAMES.lock().unwrap_or_else(|p| p.into_inner());
    if !known.iter().any(|n| n == name) {
        known.push(name.to_string());
    }
}

/// Registers the algorithm of every row whose settings carry the external marker
/// (`peer=external`), so results read back mark those rows as peers too.
pub fn note_external_rows<'a>(rows: impl IntoIterator<Item = (&'a str, &'a str)>) {
    let marker = format!(
        "{}={}",
        external_peer::PEER_SETTING.0,
        external_peer::PEER_SETTING.1
    );
    for (algorithm, settings) in rows {
        if settings.split(';').any(|s| s == marker) {
            note_external(algorithm);
        }
    }
}

/// The algorithms of a peer group (`vtk`), or an error listing the groups.
pub fn peer_group(group: &str) -> anyhow::Result<&'static [&'static str]> {
    PEERS
        .iter()
        .find(|(g, _)| *g == group)
        .map(|(_, names)| *names)
        .ok_or_else(|| {
            let groups: Vec<&str> = PEERS.iter().map(|(g, _)| *g).collect();
            anyhow::anyhow!("unknown peer group {group:?}; known: {}", groups.join(", "))
        })
}

fn all_gator_variants() -> Vec<Box<dyn Renderer>> {
    gator_pt::variants(&render_core::visibility::VisibilityOrder::ALL)
}

/// Every algorithm's name, in table order.
pub fn names() -> Vec<&'static str> {
    TABLE.iter().map(|(n, _, _)| *n).collect()
}

fn entry(name: &str) -> anyhow::Result<&'static (&'static str, Variants, Variants)> {
    TABLE
        .iter()
        .find(|(n, _, _)| *n == name)
        .ok_or_else(|| anyhow::anyhow!("unknown algorithm {name:?}; known: {}", names().join(", ")))
}

/// The default variants of `name`, or an error listing the known names.
pub fn variants(name: &str) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
    Ok((entry(name)?.1)())
}

/// Every variant `name` offers (what `--settings` selects from), in table order.
pub fn all_variants(name: &str) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
    Ok((entry(name)?.2)())
}

/// The variants of `name` that `filter` selects. Drawn from every variant the algorithm offers:
/// a setting the filter names must take one of the listed values; a setting it does not name
/// keeps the values the default variants use. So no filter gives exactly the defaults,
/// `sort=mpvonc` gives GATOR's two cell models with the exact order, and `k=8` gives HAVS k = 8
/// with both sorts and otherwise default settings.
pub fn selected_variants(
    name: &str,
    filter: &SettingsFilter,
) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
    let (_, defaults, all) = entry(name)?;
    let defaults = defaults();
    if filter.is_empty() {
        return Ok(defaults);
    }
    let default_settings: Vec<Vec<render_core::Setting>> =
        defaults.iter().map(|r| r.settings()).collect();
    let default_has = |s: &render_core::Setting| {
        default_settings
            .iter()
            .flatten()
            .any(|d| d.key == s.key && d.value == s.value)
    };
    Ok(all()
        .into_iter()
        .filter(|r| {
            r.settings().iter().all(|s| match filter.values(s.key) {
                Some(values) => values.contains(&s.value),
                None => default_has(s),
            })
        })
        .collect())
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

    /// The values asked for `key`, if the filter names it.
    pub fn values(&self, key: &str) -> Option<&[String]> {
        self.terms
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_slice())
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
    fn external_renderers_are_peers_once_met() {
        assert_eq!(peer_kind("vtk-pt"), Some("vtk"));
        assert!(!is_peer("mine-from-a-test"));
        note_external_rows([
            ("mine-from-a-test", "peer=external;step=1"),
            ("havs", "k=2"),
        ]);
        assert_eq!(peer_kind("mine-from-a-test"), Some("external"));
        assert!(!is_peer("havs"));
    }

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

    fn settings_of(name: &str, filter: &str) -> Vec<String> {
        let f = SettingsFilter::parse(filter).unwrap();
        selected_variants(name, &f)
            .unwrap()
            .iter()
            .map(|r| {
                r.settings()
                    .iter()
                    .map(|s| format!("{}={}", s.key, s.value))
                    .collect::<Vec<_>>()
                    .join(";")
            })
            .collect()
    }

    #[test]
    fn filters_select_beyond_the_defaults_and_keep_other_defaults() {
        // No filter: exactly the defaults.
        for name in names() {
            assert_eq!(
                selected_variants(name, &SettingsFilter::default())
                    .unwrap()
                    .len(),
                variants(name).unwrap().len()
            );
        }
        assert_eq!(
            settings_of("gator-pt", "sort=mpvonc|bucket"),
            [
                "variant=constant;sort=bucket",
                "variant=linear;sort=bucket",
                "variant=constant;sort=mpvonc",
                "variant=linear;sort=mpvonc"
            ]
        );
        let havs = settings_of("havs", "k=8|16");
        assert_eq!(havs.len(), 4, "{havs:?}");
        assert!(havs
            .iter()
            .all(|s| s.contains("tags=two") && s.contains("mode=") && s.contains("et=on")));
        let race = settings_of("havs", "k=6;sort=cpu-radix;mode=race-free");
        assert_eq!(race.len(), 1, "{race:?}");
        let frag = settings_of("fragment-pt", "sort=mpvonc");
        assert_eq!(frag.len(), 2, "{frag:?}");
    }

    #[test]
    fn peers_are_registered_and_marked() {
        for (_, peers) in PEERS {
            for p in *peers {
                assert!(names().contains(p) && is_peer(p), "{p}");
                assert_eq!(variants(p).unwrap()[0].algorithm(), *p);
            }
        }
        assert!(!is_peer("gator-pt"));
        assert_eq!(peer_group("vtk").unwrap().len(), 3);
        assert!(peer_group("paraview")
            .unwrap_err()
            .to_string()
            .contains("vtk"));
    }

    #[test]
    fn unknown_algorithm_lists_the_known_ones() {
        let e = variants("no-such").err().unwrap().to_string();
        assert!(e.contains("gator-pt"), "{e}");
    }
}
