//! `docs/dependencies.md` names every crate the repository's `Cargo.toml` files depend on, and
//! no other: its table of crates is read (the backticked names of each row's first
//! cell) and compared with the dependencies of every manifest — the workspace's, each
//! member's, and the fuzz crate's — in every dependency table (normal, dev, build, per target).
//! Crates of the repository itself (path dependencies, workspace members) are not listed.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every Cargo.toml under `dir`, except build output and hidden folders.
fn manifests(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().to_string_lossy().into_owned();
        let path = e.path();
        if path.is_dir() {
            if !name.starts_with('.') && name != "target" && !name.starts_with("target-") {
                manifests(&path, out);
            }
        } else if name == "Cargo.toml" {
            out.push(path);
        }
    }
}

/// The dependency tables of a manifest: `[dependencies]` and friends, `[workspace.dependencies]`
/// and `[target.'cfg(…)'.dependencies]`.
fn dependency_tables(doc: &toml::Table) -> Vec<&toml::Table> {
    fn kinds<'a>(t: &'a toml::Table, out: &mut Vec<&'a toml::Table>) {
        for k in ["dependencies", "dev-dependencies", "build-dependencies"] {
            if let Some(toml::Value::Table(d)) = t.get(k) {
                out.push(d);
            }
        }
    }
    let mut tables = vec![];
    kinds(doc, &mut tables);
    if let Some(toml::Value::Table(w)) = doc.get("workspace") {
        kinds(w, &mut tables);
    }
    if let Some(toml::Value::Table(targets)) = doc.get("target") {
        for t in targets.values() {
            if let toml::Value::Table(t) = t {
                kinds(t, &mut tables);
            }
        }
    }
    tables
}

/// (external crates, the repository's own crates) over every manifest.
fn dependencies() -> (BTreeSet<String>, BTreeSet<String>) {
    let mut files = vec![];
    manifests(&root(), &mut files);
    assert!(files.len() >= 10, "found only {files:?}");
    let (mut external, mut own) = (BTreeSet::new(), BTreeSet::new());
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let doc: toml::Table =
            toml::from_str(&text).unwrap_or_else(|e| panic!("{} is not TOML: {e}", f.display()));
        if let Some(name) = doc
            .get("package")
            .and_then(|p| p.get("name"))
            .and_then(|n| n.as_str())
        {
            own.insert(name.to_string());
        }
        for table in dependency_tables(&doc) {
            for (name, spec) in table {
                // A renamed dependency (`alias = { package = "real" }`) is the real crate.
                let real = spec.get("package").and_then(|p| p.as_str()).unwrap_or(name);
                if spec.get("path").is_some() {
                    own.insert(real.to_string());
                } else {
                    external.insert(real.to_string());
                }
            }
        }
    }
    // `foo.workspace = true` inherits the workspace's entry, which decides path or not.
    let external = external.difference(&own).cloned().collect();
    (external, own)
}

/// The crates `docs/dependencies.md` lists: backticked names in the first cell of the rows of
/// its "The crates" table, outside brackets.
fn documented() -> BTreeSet<String> {
    let text = std::fs::read_to_string(root().join("docs/dependencies.md")).unwrap();
    let section = text
        .split("## The crates")
        .nth(1)
        .expect("docs/dependencies.md has no \"## The crates\" section");
    let section = section.split("\n## ").next().unwrap();
    let mut names = BTreeSet::new();
    for line in section.lines().filter(|l| l.starts_with("| `")) {
        let first = line.split('|').nth(1).unwrap();
        // Brackets hold notes (features, "dev"), not crates: `plotters` (bitmap + SVG, `ab_glyph`).
        let mut depth = 0;
        let first: String = first
            .chars()
            .filter(|c| {
                match c {
                    '(' => depth += 1,
                    ')' => depth -= 1,
                    _ => return depth == 0,
                }
                false
            })
            .collect();
        for (i, part) in first.split('`').enumerate() {
            // Odd parts are inside backticks; a version may follow a name (`wgpu` 30).
            if i % 2 == 1 {
                names.insert(part.trim().to_string());
            }
        }
    }
    names
}

#[test]
fn every_dependency_is_documented_and_nothing_else() {
    let (deps, _) = dependencies();
    let doc = documented();
    let missing: Vec<&String> = deps.difference(&doc).collect();
    let stale: Vec<&String> = doc.difference(&deps).collect();
    assert!(
        missing.is_empty(),
        "docs/dependencies.md does not list {missing:?} (depended on by a Cargo.toml)"
    );
    assert!(
        stale.is_empty(),
        "docs/dependencies.md lists {stale:?}, which no Cargo.toml depends on"
    );
    assert!(deps.contains("wgpu") && deps.contains("naga") && deps.contains("libfuzzer-sys"));
}

/// The check sees a crate that is added: a manifest's new dependency is missing from the doc.
#[test]
fn a_new_dependency_is_seen() {
    let doc: toml::Table = toml::from_str(
        "[package]\nname = \"x\"\n[dependencies]\nnew-crate = \"1\"\nown = { path = \"../own\" }\n\
         [target.'cfg(unix)'.dev-dependencies]\nunix-only = \"1\"\n",
    )
    .unwrap();
    let names: Vec<String> = dependency_tables(&doc)
        .iter()
        .flat_map(|t| t.keys().cloned())
        .collect();
    assert_eq!(names, ["new-crate", "own", "unix-only"]);
    assert!(!documented().contains("new-crate"));
}
