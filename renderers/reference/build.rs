//! Hashes the reference renderer's own code at build time (blake3 over every `src/**/*.rs` of
//! this crate in path order, the crate version, and the files of render-core's `preintegration/`
//! in path order, whose segment integrator the reference calls for every step) and exposes it as
//! `REFERENCE_CODE_HASH`: the cache key includes it, so cached images never outlive the code
//! that made them.

use std::path::{Path, PathBuf};

fn rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rs_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let mut files = Vec::new();
    rs_files(&root.join("src"), &mut files);
    files.sort();
    let integrator = root.join("../core/src/preintegration");
    let mut integrator_files = Vec::new();
    rs_files(&integrator, &mut integrator_files);
    integrator_files.sort();
    files.extend(integrator_files);
    let mut h = blake3::Hasher::new();
    h.update(b"version\0");
    h.update(
        std::env::var("CARGO_PKG_VERSION")
            .unwrap_or_default()
            .as_bytes(),
    );
    for f in &files {
        let rel = f.strip_prefix(&root).unwrap_or(f);
        // A missing file hashes as absent (and cargo reruns when it appears).
        let bytes = std::fs::read(f).unwrap_or_default();
        h.update(b"\0file\0");
        h.update(rel.to_string_lossy().as_bytes());
        h.update(b"\0");
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
        println!("cargo:rerun-if-changed={}", f.display());
    }
    // New files under src/ change the directory, which cargo also watches.
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed={}", integrator.display());
    println!("cargo:rerun-if-changed=Cargo.toml");
    println!(
        "cargo:rustc-env=REFERENCE_CODE_HASH={}",
        h.finalize().to_hex()
    );
}
