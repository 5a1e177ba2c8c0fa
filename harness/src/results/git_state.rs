//! The git state a build is made from: its commit and whether the tree was dirty. `build.rs`
//! includes this file (`#[path]`) to embed the state in the binary (read back by
//! `MachineInfo`); the tests here check the rule "an untracked source file makes the tree
//! dirty" on a real repository.

use std::path::Path;
use std::process::Command;

/// What the binary is built from, relative to the workspace root: a change here (tracked or
/// not) makes the tree dirty and reruns the build script.
pub const SOURCE_PATHS: [&str; 8] = [
    "harness",
    "datasets",
    "renderers",
    "peers",
    "tests",
    "scripts",
    "Cargo.toml",
    "Cargo.lock",
];

/// `git -C root args…`'s trimmed standard output, `None` when git fails or is absent.
pub fn git(root: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(root)
        .args(args)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// Whether the tree at `root` differs from its commit: a tracked file changed, or a source
/// folder ([`SOURCE_PATHS`]) holds a file git does not track (a new module the commit lacks;
/// ignored build outputs do not count). `None` outside a git checkout.
pub fn dirty(root: &Path) -> Option<bool> {
    git(root, &["rev-parse", "HEAD"])?;
    let tracked = git(root, &["status", "--porcelain", "--untracked-files=no"])?;
    let mut untracked_args = vec!["status", "--porcelain", "--untracked-files=all", "--"];
    untracked_args.extend(SOURCE_PATHS);
    let untracked = git(root, &untracked_args)?;
    Some(!tracked.is_empty() || !untracked.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-commit repository with `harness/src/lib.rs` tracked and `target/` ignored.
    fn repository() -> tempfile::TempDir {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        let run = |args: &[&str]| {
            let ok = Command::new("git")
                .arg("-C")
                .arg(root)
                .args(args)
                .output()
                .unwrap()
                .status
                .success();
            assert!(ok, "git {args:?}");
        };
        run(&["init", "-q"]);
        std::fs::create_dir_all(root.join("harness/src")).unwrap();
        std::fs::write(root.join("harness/src/lib.rs"), "// lib\n").unwrap();
        std::fs::write(root.join(".gitignore"), "target/\n").unwrap();
        run(&["add", "."]);
        run(&[
            "-c",
            "user.name=t",
            "-c",
            "user.email=t@t",
            "-c",
            "commit.gpgsign=false",
            "commit",
            "-q",
            "-m",
            "one",
        ]);
        tmp
    }

    /// Clean as committed; an untracked file in a source folder makes it dirty, as does a
    /// changed tracked file; untracked files outside the sources or ignored ones do not.
    #[test]
    fn an_untracked_source_file_makes_the_tree_dirty() {
        let repo = repository();
        let root = repo.path();
        assert_eq!(dirty(root), Some(false));
        std::fs::create_dir_all(root.join("target")).unwrap();
        std::fs::write(root.join("target/out.o"), "x").unwrap();
        std::fs::write(root.join("notes.txt"), "x").unwrap();
        assert_eq!(dirty(root), Some(false), "ignored and non-source files");
        std::fs::write(root.join("harness/src/new_module.rs"), "// new\n").unwrap();
        assert_eq!(dirty(root), Some(true), "an untracked module");
        std::fs::remove_file(root.join("harness/src/new_module.rs")).unwrap();
        assert_eq!(dirty(root), Some(false));
        std::fs::write(root.join("harness/src/lib.rs"), "// changed\n").unwrap();
        assert_eq!(dirty(root), Some(true), "a changed tracked file");
        let outside = tempfile::tempdir().unwrap();
        assert_eq!(dirty(outside.path()), None, "not a checkout");
    }
}
