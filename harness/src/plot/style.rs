//! How each algorithm variant looks in every chart: one colour family per algorithm, a shade
//! and a marker per variant, and a short legend label with its full settings in a key table.
//!
//! Styles are derived from the algorithm's name and the variant's settings, never from the
//! order in which rows appear, so the same variant looks the same in every chart of a run and
//! in every run. A variant's preferred slot is its position among the algorithm's default
//! variants (then among every variant it offers, then a hash of its settings); only when two
//! variants present together want the same slot does the later one (in a fixed order) move to
//! the next free slot, so no two variants of one chart set share a style.

use std::collections::BTreeMap;

use plotters::style::RGBColor;

use crate::results::names::stable_hash;

/// Shades per colour family and marker shapes: 4 × 8 = 32 distinct styles per algorithm.
pub const SHADES: usize = 4;
pub const SLOTS: usize = SHADES * Marker::ALL.len();

/// Longest legend label; longer ones are replaced by `algorithm #N` (the key table has all).
pub const MAX_LABEL_CHARS: usize = 30;

/// Marker shapes, each distinguishable in black and white.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Marker {
    Circle,
    Square,
    TriangleUp,
    Diamond,
    TriangleDown,
    Hexagon,
    Cross,
    Plus,
}

impl Marker {
    pub const ALL: [Marker; 8] = [
        Marker::Circle,
        Marker::Square,
        Marker::TriangleUp,
        Marker::Diamond,
        Marker::TriangleDown,
        Marker::Hexagon,
        Marker::Cross,
        Marker::Plus,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Marker::Circle => "circle",
            Marker::Square => "square",
            Marker::TriangleUp => "triangle-up",
            Marker::Diamond => "diamond",
            Marker::TriangleDown => "triangle-down",
            Marker::Hexagon => "hexagon",
            Marker::Cross => "cross",
            Marker::Plus => "plus",
        }
    }
}

/// The categorical colours of charts whose series are not algorithm variants (a history
/// chart's series, a paper figure's resolutions): matplotlib's "tab10", in its order.
pub const CATEGORICAL: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// A categorical colour by index, cycling.
pub fn categorical(i: usize) -> RGBColor {
    CATEGORICAL[i % CATEGORICAL.len()]
}

/// Verdict colours of the comparison charts: slower red, faster green, no change blue.
pub const SLOWER: RGBColor = CATEGORICAL[3];
pub const FASTER: RGBColor = CATEGORICAL[2];
pub const NO_CHANGE: RGBColor = CATEGORICAL[0];
/// BASE's samples in a ratio plot.
pub const BASELINE_GREY: RGBColor = RGBColor(140, 140, 140);
/// The papers' numbers beside ours in a paper's bar charts (grey), and ours (blue).
pub const PAPER_VALUE: RGBColor = CATEGORICAL[7];
pub const OUR_VALUE: RGBColor = CATEGORICAL[0];

/// Counts drawn as colour (the tile heat maps of a paper's figure): the error heatmaps' ramp
/// (`results::metrics::ramp`), dark at `t` = 0, pale yellow at 1.
pub fn sequential(t: f64) -> RGBColor {
    let [r, g, b] = crate::results::metrics::ramp(t);
    RGBColor(r, g, b)
}

/// A tile that counted nothing, drawn apart from the ramp.
pub const EMPTY_TILE: RGBColor = RGBColor(225, 225, 225);
/// The outline of the busiest tile of a heat map: a hue the ramp does not hold.
pub const BUSIEST_TILE: RGBColor = CATEGORICAL[9];

/// The text colour that reads on `c`: black on light colours, white on dark ones (relative
/// luminance, Rec. 709 weights, on the sRGB values).
pub fn ink_on(c: RGBColor) -> RGBColor {
    let y = 0.2126 * c.0 as f64 + 0.7152 * c.1 as f64 + 0.0722 * c.2 as f64;
    if y > 140.0 {
        RGBColor(0, 0, 0)
    } else {
        RGBColor(255, 255, 255)
    }
}

/// A colour family: four shades of one hue, dark to light, all readable on white.
type Family = [RGBColor; SHADES];

const BLUES: Family = [
    RGBColor(8, 48, 107),
    RGBColor(33, 102, 172),
    RGBColor(66, 146, 198),
    RGBColor(107, 174, 214),
];
const ORANGES: Family = [
    RGBColor(127, 39, 4),
    RGBColor(204, 76, 2),
    RGBColor(236, 112, 20),
    RGBColor(254, 153, 41),
];
const GREENS: Family = [
    RGBColor(0, 68, 27),
    RGBColor(35, 132, 67),
    RGBColor(65, 171, 93),
    RGBColor(120, 198, 121),
];
const PURPLES: Family = [
    RGBColor(63, 0, 125),
    RGBColor(106, 81, 163),
    RGBColor(128, 125, 186),
    RGBColor(158, 154, 200),
];
const MAGENTAS: Family = [
    RGBColor(103, 0, 31),
    RGBColor(206, 18, 86),
    RGBColor(231, 41, 138),
    RGBColor(223, 101, 176),
];
const GREYS: Family = [
    RGBColor(37, 37, 37),
    RGBColor(82, 82, 82),
    RGBColor(115, 115, 115),
    RGBColor(150, 150, 150),
];
const BROWNS: Family = [
    RGBColor(84, 48, 5),
    RGBColor(140, 81, 10),
    RGBColor(191, 129, 45),
    RGBColor(210, 170, 100),
];
const TEALS: Family = [
    RGBColor(1, 70, 54),
    RGBColor(1, 108, 89),
    RGBColor(2, 129, 138),
    RGBColor(54, 144, 192),
];

/// The palette of a description's hue.
fn hue_family(hue: render_core::Hue) -> Family {
    use render_core::Hue;
    match hue {
        Hue::Blues => BLUES,
        Hue::Oranges => ORANGES,
        Hue::Greens => GREENS,
        Hue::Purples => PURPLES,
        Hue::Magentas => MAGENTAS,
        Hue::Browns => BROWNS,
        Hue::Teals => TEALS,
        Hue::Greys => GREYS,
    }
}

/// Algorithms this build does not describe (results of other builds, external renderers
/// that are not peers) get one of these by a hash of their name (stable, but two unknown
/// algorithms may then share a family).
const SPARE_FAMILIES: [Family; 2] = [BROWNS, TEALS];

/// Whether `algorithm` is an outside peer (VTK's mappers) rather than one of
/// tetbench's own renderers. Peers are drawn in greys with hollow markers.
/// Names outside the algorithm table that start with `vtk-` (rows from other builds) count too.
pub fn is_peer(algorithm: &str) -> bool {
    crate::algorithms::is_peer(algorithm) || algorithm.starts_with("vtk-")
}

/// Peers share the grey family, so each peer's slots start at its own offset (its place among
/// the peers × 4): `vtk-pt`, `vtk-raycast` and `vtk-zsweep` never share a style.
fn peer_slot_offset(algorithm: &str) -> usize {
    let peers: Vec<&str> = crate::algorithms::peer_groups()
        .into_iter()
        .flat_map(|(_, names)| names)
        .collect();
    let index = peers
        .iter()
        .position(|p| *p == algorithm)
        .unwrap_or((stable_hash(algorithm) % 8) as usize);
    4 * index
}

/// The order of variants in legends and CSVs: own algorithms in the table's order, then
/// unknown ones by name, then peers; within an algorithm by style slot.
pub fn order_key(
    book: &StyleBook,
    algorithm: &str,
    settings: &str,
) -> (bool, usize, String, usize) {
    let names = crate::algorithms::names();
    (
        is_peer(algorithm),
        names
            .iter()
            .position(|n| *n == algorithm)
            .unwrap_or(names.len()),
        algorithm.to_string(),
        book.get(algorithm, settings).slot,
    )
}

fn family(algorithm: &str) -> Family {
    if is_peer(algorithm) {
        return GREYS;
    }
    crate::algorithms::describe(algorithm)
        .map(|d| hue_family(d.hue))
        .unwrap_or_else(|| {
            SPARE_FAMILIES[(stable_hash(algorithm) % SPARE_FAMILIES.len() as u64) as usize]
        })
}

/// Slot `s` → (shade, marker), a bijection on 0..SLOTS: the first eight slots all get
/// different markers (and cycle the shades), so an algorithm's first variants differ in shape
/// even when printed in grey.
fn slot_style(slot: usize) -> (usize, Marker) {
    let m = slot % Marker::ALL.len();
    let q = slot / Marker::ALL.len();
    ((q + m) % SHADES, Marker::ALL[m])
}

/// The look of one variant.
#[derive(Debug, Clone, PartialEq)]
pub struct Style {
    pub color: RGBColor,
    pub marker: Marker,
    /// Peers: outline only.
    pub hollow: bool,
    /// Short label for legends (unique within its book).
    pub label: String,
    pub slot: usize,
}

impl Style {
    pub fn hex(&self) -> String {
        let RGBColor(r, g, b) = self.color;
        format!("#{r:02x}{g:02x}{b:02x}")
    }
}

/// A variant: algorithm name and its settings string.
pub type VariantKey = (String, String);

/// The styles of every variant present in a set of results.
#[derive(Debug, Clone, Default)]
pub struct StyleBook {
    styles: BTreeMap<VariantKey, Style>,
}

/// Settings texts of an algorithm's default and of all its variants, from its declared grid
/// (empty when this build does not describe the algorithm, e.g. results of another version).
fn known_settings(algorithm: &str) -> (Vec<String>, Vec<String>) {
    let texts = |grid: Vec<render_core::Settings>| grid.iter().map(|s| s.to_string()).collect();
    match crate::algorithms::describe(algorithm) {
        Some(d) => (texts((d.default_grid)()), texts((d.full_grid)())),
        None => (vec![], vec![]),
    }
}

/// The preferred slot of a variant and a sort key that puts default variants first.
fn preferred(settings: &str, defaults: &[String], all: &[String]) -> (usize, usize) {
    if let Some(i) = defaults.iter().position(|s| s == settings) {
        return (0, i % SLOTS);
    }
    if let Some(i) = all.iter().position(|s| s == settings) {
        return (1, (defaults.len() + i) % SLOTS);
    }
    (2, (stable_hash(settings) % SLOTS as u64) as usize)
}

/// `k=2` for numbers, the bare value otherwise.
fn value_text(key: &str, value: &str) -> String {
    if value.parse::<f64>().is_ok() {
        format!("{key}={value}")
    } else {
        value.to_string()
    }
}

/// A legend's settings as (key, value) texts; text that does not parse (a foreign results
/// file) is shown whole.
fn parse_settings(settings: &str) -> Vec<(String, String)> {
    match render_core::Settings::parse(settings) {
        Ok(s) => s
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        Err(_) => vec![(settings.to_string(), String::new())],
    }
}

impl StyleBook {
    /// Styles for every distinct (algorithm, settings) in `variants`.
    pub fn new<'a>(variants: impl IntoIterator<Item = (&'a str, &'a str)>) -> StyleBook {
        let mut by_alg: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for (a, s) in variants {
            let v = by_alg.entry(a.to_string()).or_default();
            if !v.iter().any(|x| x == s) {
                v.push(s.to_string());
            }
        }
        let mut styles = BTreeMap::new();
        for (alg, settings) in by_alg {
            let (defaults, all) = known_settings(&alg);
            let mut order: Vec<((usize, usize), String)> = settings
                .into_iter()
                .map(|s| (preferred(&s, &defaults, &all), s))
                .collect();
            order.sort();
            let labels = short_labels(&alg, order.iter().map(|(_, s)| s.as_str()));
            let fam = family(&alg);
            let offset = if is_peer(&alg) {
                peer_slot_offset(&alg)
            } else {
                0
            };
            let mut taken = [false; SLOTS];
            for (n, ((_, want), s)) in order.iter().enumerate() {
                let want = &((want + offset) % SLOTS);
                // More variants than slots wrap around and share; see SLOTS.
                let slot = if n < SLOTS {
                    (0..SLOTS)
                        .map(|d| (want + d) % SLOTS)
                        .find(|&c| !taken[c])
                        .unwrap_or(*want)
                } else {
                    *want
                };
                taken[slot] = true;
                let (shade, marker) = slot_style(slot);
                styles.insert(
                    (alg.clone(), s.clone()),
                    Style {
                        color: fam[shade],
                        marker,
                        hollow: is_peer(&alg),
                        label: labels[n].clone(),
                        slot,
                    },
                );
            }
        }
        StyleBook { styles }
    }

    /// The style of a variant; a variant not in the book (a caller error) gets black circles.
    pub fn get(&self, algorithm: &str, settings: &str) -> Style {
        self.styles
            .get(&(algorithm.to_string(), settings.to_string()))
            .cloned()
            .unwrap_or_else(|| Style {
                color: RGBColor(0, 0, 0),
                marker: Marker::Circle,
                hollow: false,
                label: crate::results::names::series_label(algorithm, settings),
                slot: 0,
            })
    }

    pub fn iter(&self) -> impl Iterator<Item = (&VariantKey, &Style)> {
        self.styles.iter()
    }

    pub fn len(&self) -> usize {
        self.styles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.styles.is_empty()
    }

    /// The key table as CSV: label, algorithm, settings, colour, marker, peer.
    pub fn key_csv(&self) -> String {
        let mut w = csv::Writer::from_writer(vec![]);
        let _ = w.write_record(["label", "algorithm", "settings", "color", "marker", "peer"]);
        for ((a, s), st) in &self.styles {
            let _ = w.write_record([
                st.label.as_str(),
                a,
                s,
                &st.hex(),
                st.marker.name(),
                if st.hollow { "yes" } else { "no" },
            ]);
        }
        String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
    }

    /// The key table (label with its colour → full settings) for the HTML pages.
    pub fn key_entries(&self) -> Vec<KeyEntry> {
        self.styles
            .iter()
            .map(|((a, s), st)| KeyEntry {
                label: st.label.clone(),
                algorithm: a.clone(),
                settings: s.clone(),
                color: st.hex(),
                marker: st.marker.name(),
                hollow: st.hollow,
            })
            .collect()
    }
}

/// Legend labels for one algorithm's variants: the algorithm's name followed by the values of
/// the settings that differ between the variants present (`havs k=2 cpu-radix`); `alg #N`
/// where that is too long or not unique.
fn short_labels<'a>(algorithm: &str, settings: impl Iterator<Item = &'a str>) -> Vec<String> {
    let parsed: Vec<Vec<(String, String)>> = settings.map(parse_settings).collect();
    if parsed.len() == 1 {
        return vec![algorithm.to_string()];
    }
    let mut keys: Vec<&str> = vec![];
    for p in &parsed {
        for (k, _) in p {
            if !keys.contains(&k.as_str()) {
                keys.push(k);
            }
        }
    }
    let value = |p: &Vec<(String, String)>, k: &str| {
        p.iter().find(|(pk, _)| pk == k).map(|(_, v)| v.clone())
    };
    let varying: Vec<&str> = keys
        .into_iter()
        .filter(|k| parsed.iter().any(|p| value(p, k) != value(&parsed[0], k)))
        .collect();
    let mut labels: Vec<String> = parsed
        .iter()
        .map(|p| {
            let mut l = algorithm.to_string();
            for k in &varying {
                if let Some(v) = value(p, k) {
                    l.push(' ');
                    l.push_str(&value_text(k, &v));
                }
            }
            l
        })
        .collect();
    for i in 0..labels.len() {
        let dup = labels.iter().filter(|l| **l == labels[i]).count() > 1;
        if dup || labels[i].chars().count() > MAX_LABEL_CHARS {
            labels[i] = format!("{algorithm} #{}", i + 1);
        }
    }
    labels
}

/// One line of the charts' key, as the HTML pages show it.
#[derive(Debug, serde::Serialize)]
pub struct KeyEntry {
    pub label: String,
    pub algorithm: String,
    pub settings: String,
    pub color: String,
    pub marker: &'static str,
    /// Hollow grey markers: an outside peer.
    pub hollow: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn suite_variants() -> Vec<(String, String)> {
        let mut v = vec![];
        for name in crate::algorithms::names() {
            for s in known_settings(name).0 {
                v.push((name.to_string(), s));
            }
        }
        v
    }

    fn book(v: &[(String, String)]) -> StyleBook {
        StyleBook::new(v.iter().map(|(a, s)| (a.as_str(), s.as_str())))
    }

    #[test]
    fn slots_map_to_distinct_styles() {
        let mut seen = std::collections::HashSet::new();
        for s in 0..SLOTS {
            assert!(seen.insert(slot_style(s)), "slot {s} repeats a style");
        }
    }

    /// No two variants of the default suite share a colour and marker, and every label fits.
    #[test]
    fn default_suite_styles_are_distinct_and_labels_short() {
        let v = suite_variants();
        let b = book(&v);
        assert_eq!(b.len(), v.len());
        let mut seen = std::collections::HashSet::new();
        let mut labels = std::collections::HashSet::new();
        for (_, st) in b.iter() {
            assert!(
                seen.insert((st.color, st.marker, st.hollow)),
                "style repeated: {st:?}"
            );
            assert!(labels.insert(st.label.clone()), "label repeated: {st:?}");
            assert!(st.label.chars().count() <= MAX_LABEL_CHARS, "{}", st.label);
        }
    }

    /// Every variant HAVS offers (112 > 32 slots) cannot all differ, but every set of at most
    /// 32 of them can: the first 32 in table order get distinct styles.
    #[test]
    fn up_to_32_variants_of_one_algorithm_never_share() {
        for name in crate::algorithms::names() {
            let all: Vec<(String, String)> = known_settings(name)
                .1
                .into_iter()
                .take(SLOTS)
                .map(|s| (name.to_string(), s))
                .collect();
            let b = book(&all);
            let styles: std::collections::HashSet<_> =
                b.iter().map(|(_, s)| (s.color, s.marker)).collect();
            assert_eq!(styles.len(), all.len(), "{name}");
        }
    }

    /// The same variant keeps its style whatever else is in the run and in whatever order the
    /// rows come.
    #[test]
    fn styles_are_stable_across_runs_and_orders() {
        let v = suite_variants();
        let full = book(&v);
        let mut reversed = v.clone();
        reversed.reverse();
        let rev = book(&reversed);
        // A run of HAVS alone, one of fragment PT's sorts only, and one with an extra peer.
        let havs_only: Vec<_> = v.iter().filter(|(a, _)| a == "havs").cloned().collect();
        let frag_bucket: Vec<_> = v
            .iter()
            .filter(|(a, s)| a == "fragment-pt" && s.contains("sort=bucket"))
            .cloned()
            .collect();
        let mut with_peer = v.clone();
        with_peer.push(("vtk-pt".into(), "".into()));
        let peer = book(&with_peer);
        for (a, s) in &v {
            let st = full.get(a, s);
            let same = |o: &Style| o.color == st.color && o.marker == st.marker;
            assert!(same(&rev.get(a, s)), "{a} {s}");
            assert!(same(&peer.get(a, s)), "{a} {s}");
            if a == "havs" {
                assert!(same(&book(&havs_only).get(a, s)), "{a} {s}");
            }
            if frag_bucket.contains(&(a.clone(), s.clone())) {
                assert!(same(&book(&frag_bucket).get(a, s)), "{a} {s}");
            }
        }
        let p = peer.get("vtk-pt", "");
        assert!(p.hollow);
        assert_eq!(p.label, "vtk-pt");
        assert!(
            !full
                .get("havs", &v.iter().find(|x| x.0 == "havs").unwrap().1)
                .hollow
        );
    }

    #[test]
    fn labels_name_what_differs() {
        let l = short_labels(
            "havs",
            [
                "k=2;sort=cpu-radix;tags=two",
                "k=6;sort=cpu-radix;tags=two",
                "k=2;sort=gpu-radix;tags=two",
            ]
            .into_iter(),
        );
        assert_eq!(
            l,
            [
                "havs k=2 cpu-radix",
                "havs k=6 cpu-radix",
                "havs k=2 gpu-radix"
            ]
        );
        assert_eq!(short_labels("x", ["a=1"].into_iter()), ["x"]);
        let long = short_labels(
            "fragment-pt",
            [
                "alpha=aaaaaaaaaaaa;beta=bbbbbbbbbbbb",
                "alpha=cccccccccccc;beta=dddddddddddd",
            ]
            .into_iter(),
        );
        assert_eq!(long, ["fragment-pt #1", "fragment-pt #2"]);
    }
}
