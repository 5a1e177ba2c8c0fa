//! How a run was asked for ([`RunDescription`]), as `results.json` keeps it: typed values
//! (the viewpoint list, the settings filter, the shard) written as the text the command line
//! takes, and read back through the same parsers, so a field that does not parse fails the
//! load instead of reading as an empty default.

use std::fmt;
use std::str::FromStr;

use anyhow::anyhow;
use render_core::{fixed_viewpoints, orbit_viewpoints, Viewpoint};
use schemars::JsonSchema;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::algorithms::SettingsFilter;

/// How the run was asked for, stored with the results so a report says what it shows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RunDescription {
    pub command_line: Vec<String>,
    pub algorithms: Vec<String>,
    pub datasets: Vec<String>,
    #[schemars(with = "String")]
    pub viewpoints: Viewpoints,
    pub width: u32,
    pub height: u32,
    /// Timed frames per viewpoint in each round.
    pub frames: u32,
    pub warmup: u32,
    /// Passes over each data set's variants (`run --rounds`; files from before it: 1).
    #[serde(default = "one_round")]
    pub rounds: u32,
    pub transfer_function: String,
    pub projection: String,
    #[serde(serialize_with = "as_text", deserialize_with = "settings_filter")]
    #[schemars(with = "String")]
    pub settings_filter: SettingsFilter,
    pub reference: bool,
    /// `i/N` when this run is one shard of a larger matrix (`run --shard`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schemars(with = "Option<String>")]
    pub shard: Option<Shard>,
    /// The runs `report --merge` put together (empty for a plain run).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub merged_from: Vec<MergedRun>,
}

/// Where the rows of a merged results set came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MergedRun {
    pub dir: String,
    #[schemars(with = "Option<String>")]
    pub shard: Option<Shard>,
    pub adapter: Option<String>,
    pub git_commit: Option<String>,
    pub date_utc: String,
    pub rows: usize,
}

fn one_round() -> u32 {
    1
}

/// Writes a value as its text (`Display`): the command line's form of a run's fields, and
/// `key=value;…` for a variant's [`render_core::Settings`] in the JSON outputs that keep them
/// as text (`#[serde(serialize_with = "as_text")]`).
pub fn as_text<T: fmt::Display, S: Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(value)
}

/// Reads `field`'s text through `parse`; a failure names the field and the text.
pub(crate) fn from_text<'de, T, E, D>(
    d: D,
    field: &str,
    parse: impl FnOnce(&str) -> Result<T, E>,
) -> Result<T, D::Error>
where
    E: fmt::Display,
    D: Deserializer<'de>,
{
    let text = String::deserialize(d)?;
    parse(&text).map_err(|e| serde::de::Error::custom(format!("{field} {text:?}: {e}")))
}

fn settings_filter<'de, D: Deserializer<'de>>(d: D) -> Result<SettingsFilter, D::Error> {
    from_text(d, "settings_filter", SettingsFilter::parse)
}

/// Shard `index` (1-based) of `count`: `run --shard i/N`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl FromStr for Shard {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> anyhow::Result<Shard> {
        let bad = || anyhow!("expected i/N with 1 ≤ i ≤ N, e.g. 2/4");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Serialize for Shard {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        as_text(self, s)
    }
}

impl<'de> Deserialize<'de> for Shard {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Shard, D::Error> {
        from_text(d, "shard", str::parse)
    }
}

/// The viewpoints of a run: the `--viewpoints` text as given (what `results.json` keeps and
/// two runs compare) and the list it names. `14` (or `fixed`): the 14 fixed viewpoints;
/// `axes` (6) or `diagonals` (8); `orbit:N`: N frames around the up axis; or a comma-separated
/// list of fixed viewpoint names (`+x,-y,+x+y-z`). The default is `14`.
#[derive(Debug, Clone)]
pub struct Viewpoints {
    spec: String,
    list: Vec<Viewpoint>,
}

impl Viewpoints {
    pub fn list(&self) -> &[Viewpoint] {
        &self.list
    }

    /// The viewpoints' names, in order.
    pub fn names(&self) -> Vec<String> {
        self.list.iter().map(|v| v.name.clone()).collect()
    }
}

impl Default for Viewpoints {
    fn default() -> Viewpoints {
        Viewpoints {
            spec: "14".into(),
            list: fixed_viewpoints(),
        }
    }
}

/// Two runs have the same viewpoints when they were asked for in the same words.
impl PartialEq for Viewpoints {
    fn eq(&self, other: &Viewpoints) -> bool {
        self.spec == other.spec
    }
}

impl std::ops::Deref for Viewpoints {
    type Target = [Viewpoint];
    fn deref(&self) -> &[Viewpoint] {
        &self.list
    }
}

impl<'a> IntoIterator for &'a Viewpoints {
    type Item = &'a Viewpoint;
    type IntoIter = std::slice::Iter<'a, Viewpoint>;
    fn into_iter(self) -> Self::IntoIter {
        self.list.iter()
    }
}

impl fmt::Display for Viewpoints {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.spec)
    }
}

impl FromStr for Viewpoints {
    type Err = anyhow::Error;
    fn from_str(text: &str) -> anyhow::Result<Viewpoints> {
        let spec = text.trim();
        let fixed = fixed_viewpoints();
        let list = match spec {
            "14" | "fixed" | "all" => fixed,
            "axes" | "6" => fixed[..6].to_vec(),
            "diagonals" | "8" => fixed[6..].to_vec(),
            _ => match spec.strip_prefix("orbit:") {
                Some(n) => orbit(n)?,
                None => named(spec, &fixed)?,
            },
        };
        Ok(Viewpoints {
            spec: text.to_string(),
            list,
        })
    }
}

fn orbit(n: &str) -> anyhow::Result<Vec<Viewpoint>> {
    let n: usize = n
        .parse()
        .map_err(|_| anyhow!("orbit:N needs a whole number of frames"))?;
    if n == 0 || n > 100_000 {
        anyhow::bail!("the orbit needs 1 to 100000 frames");
    }
    Ok(orbit_viewpoints(n))
}

fn named(spec: &str, fixed: &[Viewpoint]) -> anyhow::Result<Vec<Viewpoint>> {
    let mut out = vec![];
    for name in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match fixed.iter().find(|v| v.name == name) {
            Some(v) => out.push(v.clone()),
            None => anyhow::bail!(
                "unknown viewpoint {name:?}; use 14, axes, diagonals, orbit:N or names among {}",
                fixed
                    .iter()
                    .map(|v| v.name.as_str())
                    .collect::<Vec<_>>()
                    .join(",")
            ),
        }
    }
    if out.is_empty() {
        anyhow::bail!("no viewpoint named");
    }
    Ok(out)
}

impl Serialize for Viewpoints {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        as_text(self, s)
    }
}

impl<'de> Deserialize<'de> for Viewpoints {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Viewpoints, D::Error> {
        from_text(d, "viewpoints", str::parse)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::{test_row, ResultsFile, SCHEMA_VERSION};

    #[test]
    fn viewpoint_specs() {
        let parse = |s: &str| s.parse::<Viewpoints>();
        assert_eq!(parse("14").unwrap().len(), 14);
        assert_eq!(parse("axes").unwrap().len(), 6);
        assert_eq!(parse("orbit:36").unwrap().len(), 36);
        let v = parse("+x,+x+y+z,-x+y-z").unwrap();
        assert_eq!(v.names(), ["+x", "+x+y+z", "-x+y-z"]);
        assert_eq!(v.to_string(), "+x,+x+y+z,-x+y-z");
        assert!(parse("orbit:x").is_err());
        assert!(parse("orbit:0").is_err());
        assert!(parse("").is_err());
        assert_eq!(Viewpoints::default(), parse("14").unwrap());
        assert_eq!(Viewpoints::default().len(), 14);
        let e = parse("+w").unwrap_err().to_string();
        assert!(e.contains("unknown viewpoint"), "{e}");
    }

    #[test]
    fn shard_syntax() {
        assert_eq!(
            "2/4".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 4 }
        );
        for bad in ["0/2", "3/2", "x", "1/", "/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    fn file() -> ResultsFile {
        ResultsFile {
            control: None,
            schema_version: SCHEMA_VERSION,
            machine: crate::results::machine::MachineInfo::collect(),
            run: RunDescription {
                algorithms: vec!["havs".into()],
                datasets: vec!["box:1k".into()],
                viewpoints: "+x,-y".parse().unwrap(),
                settings_filter: SettingsFilter::parse("k=2|6;sort=cpu-radix").unwrap(),
                shard: Some("2/3".parse().unwrap()),
                ..RunDescription::default()
            },
            finished_utc: None,
            rows: vec![test_row(1)],
            errors: vec![],
        }
    }

    /// The typed fields are written as the command line's text and read back equal.
    #[test]
    fn a_run_description_round_trips_as_text() {
        let tmp = tempfile::tempdir().unwrap();
        let f = file();
        crate::results::write_json(tmp.path(), &f).unwrap();
        let text = std::fs::read_to_string(tmp.path().join("results.json")).unwrap();
        assert!(text.contains(r#""viewpoints": "+x,-y""#), "{text}");
        assert!(text.contains(r#""settings_filter": "k=2|6;sort=cpu-radix""#));
        assert!(text.contains(r#""shard": "2/3""#));
        let back = ResultsFile::read(tmp.path()).unwrap();
        assert_eq!(back.run, f.run);
        assert_eq!(back.run.viewpoints.names(), ["+x", "-y"]);
    }

    /// A field that does not parse fails the load, naming the file and the field; the same
    /// file with the field good loads.
    #[test]
    fn a_bad_field_fails_naming_file_and_field() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("results.json");
        crate::results::write_json(tmp.path(), &file()).unwrap();
        let good = std::fs::read_to_string(&path).unwrap();
        for (from, to, field) in [
            (r#""shard": "2/3""#, r#""shard": "4/3""#, "shard"),
            (
                r#""settings_filter": "k=2|6;sort=cpu-radix""#,
                r#""settings_filter": "k2""#,
                "settings_filter",
            ),
            (
                r#""viewpoints": "+x,-y""#,
                r#""viewpoints": "+w""#,
                "viewpoints",
            ),
        ] {
            assert!(good.contains(from), "{from}");
            std::fs::write(&path, good.replace(from, to)).unwrap();
            let e = format!("{:#}", ResultsFile::read(tmp.path()).unwrap_err());
            assert!(e.contains(&path.display().to_string()), "{e}");
            assert!(e.contains(&format!("{field} \"")), "{e}");
            std::fs::write(&path, &good).unwrap();
            assert!(ResultsFile::read(tmp.path()).is_ok());
        }
    }
}
