//! Settings text is parsed in one place, `render_core::Settings`: no other code of
//! the harness, the renderers or the peers splits a settings string or looks a key up in one.
//! A grep, so it can fail: the patterns below are what the hand-written parsers it replaced
//! looked like (`settings.split(';')`, `value_of(&row.settings, …)`, `settings.contains("k=")`).

use std::path::Path;

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The lines of `text` that parse settings text by hand.
fn offending_lines(text: &str) -> Vec<String> {
    let flat: Vec<&str> = text.lines().collect();
    let mut out = vec![];
    for (i, line) in flat.iter().enumerate() {
        // A call chain may continue on the next line (`settings\n    .split(';')`).
        let joined = format!(
            "{}{}",
            line.trim(),
            flat.get(i + 1).map_or("", |l| l.trim())
        );
        let hand_parsed = (joined.contains("settings.split(")
            || joined.contains("settings.split_once(")
            || joined.contains("settings.contains(\"")
            || joined.contains("settings.starts_with(")
            || (joined.contains("value_of(") && joined.contains("settings")))
            && !line.trim_start().starts_with("//");
        if hand_parsed {
            out.push(format!("{}: {}", i + 1, line.trim()));
        }
    }
    out
}

#[test]
fn no_code_outside_settings_parses_settings_text() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = vec![];
    for dir in [
        "harness/src",
        "harness/tests",
        "peers",
        "renderers",
        "tests",
    ] {
        rust_files(&root.join(dir), &mut files);
    }
    let mut found = vec![];
    for f in files {
        if f.ends_with("settings_parsing.rs") || f.ends_with("core/src/settings.rs") {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        for l in offending_lines(&text) {
            found.push(format!("{}:{l}", f.display()));
        }
    }
    assert!(
        found.is_empty(),
        "settings text parsed by hand:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_grep_finds_the_parsers_it_replaced() {
    for bad in [
        "let k = row.settings.split(';').find(|kv| kv.starts_with(\"k=\"));",
        "let v = value_of(&a.settings, \"variant\");",
        "if r.settings.contains(\"variant=constant\") {}",
        "let parts = settings\n    .split(';')\n    .collect();",
    ] {
        assert!(!offending_lines(bad).is_empty(), "{bad}");
    }
    assert!(offending_lines("let k = row.settings.int(\"k\");").is_empty());
}
