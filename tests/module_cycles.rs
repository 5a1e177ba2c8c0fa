//! No new import cycle between the modules of any crate: `scripts/module_cycles.py --check`
//! reads every workspace member's `src/` (each file a node, `use crate::…`, `super::…`,
//! `self::…` and child paths as edges, tests included) and fails on a cycle that
//! `scripts/module_cycles_allow.txt` does not list, or on a listed one that is gone. The other
//! tests build small crates with and without a cycle and see the check flip.

use std::ffi::OsStr;
use std::fs;
use std::path::Path;

use tetbench_tests::run_script;

#[test]
fn no_crate_has_a_new_import_cycle() {
    let (ok, text) = run_script("module_cycles.py", &["--check".as_ref()]);
    assert!(ok, "{text}");
}

/// A workspace of one crate `a` whose folder module `f` holds `x.rs` and `y.rs`; `x` imports
/// `y`, and `y` imports `x` when `cycle` is set (through a `use` group or a plain path).
fn crate_with(dir: &Path, y_body: &str, allow: &str) {
    let src = dir.join("a/src");
    fs::create_dir_all(src.join("f")).unwrap();
    fs::write(dir.join("Cargo.toml"), "[workspace]\nmembers = [\"a\"]\n").unwrap();
    fs::write(src.join("lib.rs"), "pub mod f;\n").unwrap();
    // The folder's mod.rs uses its children and they use it: containment, not a cycle.
    fs::write(
        src.join("f/mod.rs"),
        "pub mod x;\npub mod y;\npub struct Shared;\npub fn go() { x::X::new(); }\n",
    )
    .unwrap();
    fs::write(
        src.join("f/x.rs"),
        "use super::y::Y; // crate::f::y\npub struct X(Y, super::Shared);\n\
         impl X { pub fn new() {} }\n",
    )
    .unwrap();
    fs::write(src.join("f/y.rs"), y_body).unwrap();
    fs::write(dir.join("allow.txt"), allow).unwrap();
}

fn check(dir: &Path) -> (bool, String) {
    let allow = dir.join("allow.txt");
    let args: [&OsStr; 5] = [
        "--check".as_ref(),
        "--root".as_ref(),
        dir.as_os_str(),
        "--allow".as_ref(),
        allow.as_os_str(),
    ];
    run_script("module_cycles.py", &args)
}

const CYCLE: &str = "a/src: f::x -> f::y -> f::x";

#[test]
fn a_cycle_inside_a_folder_module_fails_the_check() {
    let no_cycle = "pub struct Y;\nconst S: &str = \"crate::f::x\";\n";
    for (y, cycle) in [
        (no_cycle, false),
        ("use crate::f::{x::X, self};\npub struct Y;\n", true),
        (
            "pub struct Y;\nfn f() { let _ = super::x::X::new(); }\n",
            true,
        ),
        // Only the tests import `x`: still a cycle, of the code with its tests.
        (
            "pub struct Y;\n#[cfg(test)]\nmod tests {\n    use super::super::x::X;\n}\n",
            true,
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        crate_with(dir.path(), y, "");
        let (ok, text) = check(dir.path());
        assert_eq!(ok, !cycle, "{y}\n{text}");
        assert_eq!(
            text.contains(&format!("new cycle: {CYCLE}")),
            cycle,
            "{text}"
        );
    }
}

#[test]
fn the_list_of_known_cycles_may_only_shrink() {
    let cycle = "use super::x::X;\npub struct Y;\n";
    let dir = tempfile::tempdir().unwrap();
    crate_with(dir.path(), cycle, &format!("# known\n{CYCLE}\n"));
    let (ok, text) = check(dir.path());
    assert!(ok, "a listed cycle passes: {text}");

    // Fixed but still listed: the check asks for its line to go.
    let dir = tempfile::tempdir().unwrap();
    crate_with(dir.path(), "pub struct Y;\n", &format!("{CYCLE}\n"));
    let (ok, text) = check(dir.path());
    assert!(
        !ok && text.contains(&format!("gone (remove its line): {CYCLE}")),
        "{text}"
    );
}
