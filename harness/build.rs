//! Embeds the build's provenance in the binary: the commit, whether the tracked
//! files differed from it, the build profile and the compiler. Read at run time these were
//! wrong for a copied binary (no commit) and for a stale one (whatever is checked out now).
//!
//! Hand-written rather than `vergen-gitcl`/`built`: it is the git command line and four
//! `rustc-env` lines, and it must also rerun when a tracked source changes (for the dirty
//! flag), which those crates leave to the caller anyway.

use std::path::PathBuf;
use std::process::Command;

#[path = "src/results/git_state.rs"]
mod git_state;
use git_state::{git, SOURCE_PATHS};

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let root = manifest
        .parent()
        .expect("harness lives in the workspace")
        .to_path_buf();

    let commit = git(&root, &["rev-parse", "HEAD"]);
    // Dirty: a tracked file differs from the commit, or a source folder holds a file git
    // does not track (`git_state::dirty`, tested there).
    let dirty = git_state::dirty(&root);
    println!(
        "cargo:rustc-env=TETBENCH_GIT_COMMIT={}",
        commit.clone().unwrap_or_default()
    );
    println!(
        "cargo:rustc-env=TETBENCH_GIT_DIRTY={}",
        dirty.map(|d| d.to_string()).unwrap_or_default()
    );
    println!(
        "cargo:rustc-env=TETBENCH_BUILD_PROFILE={}",
        std::env::var("PROFILE").unwrap_or_default()
    );
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = Command::new(rustc)
        .arg("--version")
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    println!("cargo:rustc-env=TETBENCH_RUSTC_VERSION={version}");
    // What `tetbench --version` prints after the package version.
    let state = match dirty {
        Some(true) => "dirty: uncommitted changes",
        Some(false) => "clean",
        None => "dirty flag unknown",
    };
    println!(
        "cargo:rustc-env=TETBENCH_VERSION_LINE={} (commit {}, {state}; {} build, {version})",
        std::env::var("CARGO_PKG_VERSION").unwrap_or_default(),
        commit.as_deref().unwrap_or("unknown"),
        std::env::var("PROFILE").unwrap_or_default(),
    );

    // Rerun when HEAD moves (a checkout: HEAD; a commit: the branch's ref, or packed-refs
    // after a gc), when the index changes, and when a tracked source changes (the dirty flag).
    // `--git-path` resolves all of them inside a worktree's own and the common git directory.
    if commit.is_some() {
        for name in ["HEAD", "index", "packed-refs"] {
            if let Some(p) = git(&root, &["rev-parse", "--git-path", name]) {
                println!("cargo:rerun-if-changed={}", root.join(p).display());
            }
        }
        if let Some(head_ref) = git(&root, &["symbolic-ref", "-q", "HEAD"]) {
            if let Some(p) = git(&root, &["rev-parse", "--git-path", &head_ref]) {
                println!("cargo:rerun-if-changed={}", root.join(p).display());
            }
        }
        for path in SOURCE_PATHS {
            println!("cargo:rerun-if-changed={}", root.join(path).display());
        }
    } else {
        println!("cargo:rerun-if-changed=build.rs");
    }
}
