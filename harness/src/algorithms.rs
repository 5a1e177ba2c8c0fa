//! The algorithms `tetbench run` knows: one [`AlgorithmDescription`] per algorithm crate, in
//! [`REGISTRY`]. A description declares the algorithm's parameter grid, so variant selection
//! and settings parsing work without building a renderer; renderers are built from typed
//! [`Settings`] only for the variants that run.
//!
//! To add an algorithm: its crate (with its `DESCRIPTION`), its dependency line in
//! `harness/Cargo.toml`, and one line in [`REGISTRY`] (docs/adding-an-algorithm.md).

use render_core::{AlgorithmDescription, Origin, Renderer, Settings};
pub use render_core::{SettingsFilter, ValueKind};

/// Every algorithm, in the order reports list them: tetbench's own, then the peers.
pub static REGISTRY: &[&AlgorithmDescription] = &[
    &gator_pt::DESCRIPTION,
    &havs::DESCRIPTION,
    &fragment_pt::DESCRIPTION,
    &raycast::DESCRIPTION,
    &splat::DESCRIPTION,
    &vtk_peer::PT,
    &vtk_peer::RAYCAST,
    &vtk_peer::ZSWEEP,
];

/// The description of `name`, if this build has it.
pub fn describe(name: &str) -> Option<&'static AlgorithmDescription> {
    REGISTRY.iter().copied().find(|d| d.name == name)
}

/// The description of `name`, or an error listing the known names.
pub fn description(name: &str) -> anyhow::Result<&'static AlgorithmDescription> {
    describe(name)
        .ok_or_else(|| anyhow::anyhow!("unknown algorithm {name:?}; known: {}", names().join(", ")))
}

/// Every algorithm's name, in registry order.
pub fn names() -> Vec<&'static str> {
    REGISTRY.iter().map(|d| d.name).collect()
}

/// The peer groups (`vtk`) with their algorithms, in registry order.
pub fn peer_groups() -> Vec<(&'static str, Vec<&'static str>)> {
    let mut groups: Vec<(&'static str, Vec<&'static str>)> = vec![];
    for d in REGISTRY {
        if let Origin::Peer(g) = d.origin {
            match groups.iter_mut().find(|(name, _)| *name == g) {
                Some((_, v)) => v.push(d.name),
                None => groups.push((g, vec![d.name])),
            }
        }
    }
    groups
}

/// Settings text of `algorithm` (the CSV column, old results) as typed settings: values typed
/// as the algorithm declares them, inferred for an algorithm this build does not know.
pub fn parse_settings(algorithm: &str, text: &str) -> anyhow::Result<Settings> {
    let declared = describe(algorithm);
    Ok(Settings::parse_with(text, |k| {
        declared.and_then(|d| d.kind_of(k))
    })?)
}

/// Whether `settings` of `algorithm` carry a perturbation (a positive control's key,
/// `AlgorithmDescription::perturbations`) that `named` does not name: such a row is only the
/// control's, never a configuration's that the tables look up by its other settings.
pub fn perturbed_beyond(algorithm: &str, settings: &Settings, named: &Settings) -> bool {
    describe(algorithm).is_some_and(|d| {
        d.perturbations
            .iter()
            .any(|k| settings.get(k).is_some() && named.get(k).is_none())
    })
}

/// `settings` with each value retyped as `algorithm` declares it (results loaded from JSON
/// written before a parameter's type was declared).
pub fn retype(algorithm: &str, settings: Settings) -> Settings {
    match describe(algorithm) {
        Some(d) => settings.retyped(|k| d.kind_of(k)),
        None => settings,
    }
}

/// The counters `algorithm` declares nondeterministic for `settings` on an adapter of
/// `device_type` (`AlgorithmDescription::nondeterministic_counters`); none for an algorithm
/// this build does not know.
pub fn nondeterministic_counters(
    algorithm: &str,
    settings: &Settings,
    device_type: &str,
) -> &'static [&'static str] {
    describe(algorithm).map_or(&[], |d| {
        (d.nondeterministic_counters)(settings, render_core::Shading::of_device_type(device_type))
    })
}

/// The default variants of `name`, built, or an error listing the known names.
pub fn variants(name: &str) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
    description(name)?.default_variants()
}

/// Every variant `name` offers (what `--settings` selects from), built, in grid order.
pub fn all_variants(name: &str) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
    description(name)?.all_variants()
}

/// The settings of the variants of `name` that `filter` selects
/// ([`AlgorithmDescription::select`]); nothing is built.
pub fn selected_settings(name: &str, filter: &SettingsFilter) -> anyhow::Result<Vec<Settings>> {
    Ok(description(name)?.select(filter))
}

/// The variants of `name` that `filter` selects, built.
pub fn selected_variants(
    name: &str,
    filter: &SettingsFilter,
) -> anyhow::Result<Vec<Box<dyn Renderer>>> {
    let d = description(name)?;
    d.build_each(&d.select(filter))
}

/// Whether `name` is a peer (another package's renderer, or an external renderer given with
/// `--external`) rather than a tetbench algorithm.
pub fn is_peer(name: &str) -> bool {
    peer_kind(name).is_some()
}

/// The kind of peer `name` is: its group in [`REGISTRY`] (`vtk`), or `external` for a renderer
/// given with `--external` (or met in results with the `peer=external` setting).
pub fn peer_kind(name: &str) -> Option<&'static str> {
    if let Some(Origin::Peer(group)) = describe(name).map(|d| d.origin) {
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
pub fn note_external_rows<'a>(rows: impl IntoIterator<Item = (&'a str, &'a Settings)>) {
    let (key, value) = external_peer::PEER_SETTING;
    for (algorithm, settings) in rows {
        if settings.is(key, value) {
            note_external(algorithm);
        }
    }
}

/// The algorithms of a peer group (`vtk`), or an error listing the groups.
pub fn peer_group(group: &str) -> anyhow::Result<Vec<&'static str>> {
    let groups = peer_groups();
    match groups.iter().find(|(g, _)| *g == group) {
        Some((_, names)) => Ok(names.clone()),
        None => {
            let known: Vec<&str> = groups.iter().map(|(g, _)| *g).collect();
            anyhow::bail!("unknown peer group {group:?}; known: {}", known.join(", "))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn external_renderers_are_peers_once_met() {
        assert_eq!(peer_kind("vtk-pt"), Some("vtk"));
        assert!(!is_peer("mine-from-a-test"));
        let marked = Settings::parse("peer=external;step=1").unwrap();
        let havs = Settings::parse("k=2").unwrap();
        note_external_rows([("mine-from-a-test", &marked), ("havs", &havs)]);
        assert_eq!(peer_kind("mine-from-a-test"), Some("external"));
        assert!(!is_peer("havs"));
    }

    fn settings_of(name: &str, filter: &str) -> Vec<String> {
        let f = SettingsFilter::parse(filter).unwrap();
        selected_settings(name, &f)
            .unwrap()
            .iter()
            .map(Settings::to_string)
            .collect()
    }

    #[test]
    fn filters_select_beyond_the_defaults_and_keep_other_defaults() {
        // No filter: exactly the defaults.
        for d in REGISTRY {
            assert_eq!(
                selected_settings(d.name, &SettingsFilter::default()).unwrap(),
                (d.default_grid)()
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
        // A perturbation (the splatter's misaligned bricks) is selected only where named.
        let control = settings_of("splat", "sort=bitonic;brick=1000000;misalign=1");
        assert_eq!(control.len(), 1, "{control:?}");
        assert!(control[0].ends_with("brick=1000000;ese=on;misalign=1"));
        let bricked = settings_of("splat", "sort=bitonic;brick=1000000");
        assert!(!bricked.is_empty() && bricked.iter().all(|s| !s.contains("misalign")));
        assert!(settings_of("splat", "buckets=gpu|cpu")
            .iter()
            .all(|s| !s.contains("misalign")));
        // Fragment PT's slabs and the ray caster's unscaled table likewise.
        let control = settings_of("fragment-pt", "shading=average;sort=bucket;slabs=2");
        assert_eq!(control, ["shading=average;sort=bucket;slabs=2"]);
        let bucket = settings_of("fragment-pt", "sort=bucket");
        assert!(bucket.len() == 2 && bucket.iter().all(|s| !s.contains("slabs")));
        let control = settings_of("raycast", "tiles=5x5;table=2d;unscaled=1");
        assert_eq!(
            control,
            ["tiles=5x5;table=2d;mode=passes;et=on;layers=8;k=8;unscaled=1"]
        );
        let tables = settings_of("raycast", "tiles=5x5;table=2d|3d;mode=passes;et=on;k=8");
        assert!(tables.len() == 2 && tables.iter().all(|s| !s.contains("unscaled")));
        for name in ["splat", "fragment-pt", "raycast"] {
            let d = description(name).unwrap();
            for s in (d.default_grid)() {
                assert!(d.perturbations.iter().all(|k| s.get(k).is_none()), "{s}");
            }
            // The full grid holds each perturbation once: the control's variant.
            let perturbed = (d.full_grid)()
                .into_iter()
                .filter(|s| d.perturbations.iter().any(|k| s.get(k).is_some()))
                .count();
            assert_eq!(perturbed, 1, "{name}");
        }
    }

    /// Every grid point builds a renderer that reports exactly the settings it was built
    /// from, with each value of the declared type, and declares only its declared keys: the
    /// grid, the constructor and the row agree without any text in between.
    #[test]
    fn every_declared_variant_builds_and_reports_its_own_settings() {
        for d in REGISTRY {
            let grid = (d.full_grid)();
            assert!(!grid.is_empty(), "{}", d.name);
            for defaults in (d.default_grid)() {
                assert!(
                    grid.contains(&defaults),
                    "{}: default {defaults} not in the grid",
                    d.name
                );
            }
            for s in &grid {
                let r = (d.build)(s).unwrap_or_else(|e| panic!("{}: {s}: {e}", d.name));
                assert_eq!(r.algorithm(), d.name);
                assert_eq!(&r.settings(), s, "{}", d.name);
                for (k, v) in s.iter() {
                    let p = d
                        .param(k)
                        .unwrap_or_else(|| panic!("{}: {k} undeclared", d.name));
                    let int = matches!(v, render_core::SettingValue::Int(_));
                    assert_eq!(int, p.kind == ValueKind::Int, "{}: {k}={v}", d.name);
                }
                // The text form parses back to the same typed settings.
                assert_eq!(&d.parse_settings(&s.to_string()).unwrap(), s);
            }
        }
    }

    #[test]
    fn havs_k_is_an_integer_from_the_filter_to_the_row() {
        let f = SettingsFilter::parse("k=8").unwrap();
        let v = selected_variants("havs", &f).unwrap();
        assert!(v
            .iter()
            .all(|r| r.settings().get("k") == Some(&render_core::SettingValue::Int(8))));
        assert!(description("havs")
            .unwrap()
            .parse_settings("k=eight")
            .is_err());
        assert!(description("havs")
            .unwrap()
            .parse_settings("colour=red")
            .is_err());
        // Old results: a splat length written `2` is retyped to the declared word.
        let old = Settings::parse("radius=2;grid=32").unwrap();
        let typed = retype("splat", old);
        assert_eq!(typed.text("radius").as_deref(), Some("2"));
        assert_eq!(typed.int("radius"), None);
        assert_eq!(typed.int("grid"), Some(32));
    }

    #[test]
    fn peers_are_registered_and_marked() {
        for (_, peers) in peer_groups() {
            for p in peers {
                assert!(names().contains(&p) && is_peer(p), "{p}");
                assert_eq!(variants(p).unwrap()[0].algorithm(), p);
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
