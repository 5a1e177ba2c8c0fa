//! No new giant: `scripts/code_limits.py` fails on a source file over 800 lines, a non-test
//! function over 150 lines (100 in `harness/src`) that `scripts/code_limits_allow.txt` does not
//! list, on a listed one that grew, and on a listed one now within its limit. The other tests
//! build small trees around the limits and see the check flip.

use std::ffi::OsStr;
use std::fs;
use std::path::Path;

use tetbench_tests::run_script;

#[test]
fn no_new_giant_file_or_function() {
    let (ok, text) = run_script("code_limits.py", &[]);
    assert!(ok, "{text}");
}

/// A function of exactly `lines` lines whose body holds braces in a string, a raw string, a
/// char and a comment, which the brace matching must skip.
fn function(name: &str, lines: usize) -> String {
    let mut f = format!("pub fn {name}() {{\n");
    f += "    let _ = \"}\"; let _ = r#\"}\"#; let _ = '}'; // }\n";
    for i in 0..lines - 3 {
        f += &format!("    let _x{i} = {i};\n");
    }
    f + "}\n"
}

fn limits(dir: &Path, files: &[(&str, String)], allow: &str) -> (bool, String) {
    for (path, text) in files {
        let path = dir.join(path);
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(path, text).unwrap();
    }
    let allow_file = dir.join("allow.txt");
    fs::write(&allow_file, allow).unwrap();
    let args: [&OsStr; 4] = [
        "--root".as_ref(),
        dir.as_os_str(),
        "--allow".as_ref(),
        allow_file.as_os_str(),
    ];
    run_script("code_limits.py", &args)
}

#[test]
fn a_function_over_its_limit_fails_the_check() {
    let tests_mod = |f: String| format!("#[cfg(test)]\nmod tests {{\n{f}}}\n");
    for (path, text, giant) in [
        ("a/src/lib.rs", function("big", 150), None),
        (
            "a/src/lib.rs",
            function("big", 151),
            Some("a/src/lib.rs:big 151"),
        ),
        ("a/src/lib.rs", tests_mod(function("big", 400)), None),
        ("a/src/tests.rs", function("big", 400), None),
        (
            "a/src/lib.rs",
            format!("struct S;\nimpl S {{\n{}}}\n", function("big", 160)),
            Some("a/src/lib.rs:S::big 160"),
        ),
        ("harness/src/x.rs", function("big", 100), None),
        (
            "harness/src/x.rs",
            function("big", 101),
            Some("harness/src/x.rs:big 101"),
        ),
        ("a/src/lib.rs", "//\n".repeat(800), None),
        ("a/src/lib.rs", "//\n".repeat(801), Some("a/src/lib.rs 801")),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let (ok, out) = limits(dir.path(), &[(path, text)], "");
        assert_eq!(ok, giant.is_none(), "{path} {giant:?}: {out}");
        if let Some(g) = giant {
            assert!(out.contains(&format!("new giant: {g} lines")), "{out}");
        }
    }
}

#[test]
fn the_list_of_giants_may_only_shrink() {
    let file = "a/src/lib.rs";
    for (lines, listed, ok, why) in [
        (160, 160, true, None),
        (155, 160, true, None),
        (
            161,
            160,
            false,
            Some("grew: a/src/lib.rs:big 161 lines, listed at 160"),
        ),
        (
            150,
            160,
            false,
            Some("within its limit now (remove its line): a/src/lib.rs:big"),
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let (passed, out) = limits(
            dir.path(),
            &[(file, function("big", lines))],
            &format!("# giants\n{file}:big {listed}\n"),
        );
        assert_eq!(passed, ok, "{lines} listed at {listed}: {out}");
        if let Some(why) = why {
            assert!(out.contains(why), "{out}");
        }
    }
}
