//! File-safe names and labels the run loop, the reports and the analyses share. This module
//! depends on nothing else in the crate, so any module may use it.

use std::path::Path;

/// 64-bit FNV-1a of `s`'s bytes (the `fnv` crate): a hash that does not change between Rust
/// releases, runs or machines, unlike `std`'s `DefaultHasher`. Shard assignment, chart styles
/// and the build cache's worktree names rest on it; their values are those of the hand-written
/// FNV-1a it replaced (same offset basis and prime, bytes only, no terminator).
pub fn stable_hash(s: &str) -> u64 {
    use std::hash::Hasher;
    let mut h = fnv::FnvHasher::default();
    h.write(s.as_bytes());
    h.finish()
}

/// Turns a name into something safe for file names and URLs: `box:20k` → `box_20k`,
/// `variant=linear;order=radix` → `variant_linear_order_radix`.
pub fn slug(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            'a'..='z' | 'A'..='Z' | '0'..='9' | '.' | '-' => out.push(c),
            _ => out.push('_'),
        }
    }
    if out.chars().all(|c| c == '.') {
        out.insert(0, '_');
    }
    out
}

/// A viewpoint's folder name: `+` → `p`, `-` → `m` (`+x-y` → `pxmy`), so that the names stay
/// distinct and no folder starts with a dash.
pub fn viewpoint_slug(name: &str) -> String {
    slug(&name.replace('+', "p").replace('-', "m"))
}

/// A data set's label in rows: the name as given (`spx`, `box:20k`), or a file's name.
pub fn dataset_label(spec: &str) -> String {
    let p = Path::new(spec);
    if spec.contains(std::path::MAIN_SEPARATOR) || spec.contains('/') {
        p.file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_else(|| spec.to_string())
    } else {
        spec.to_string()
    }
}

pub fn series_label(algorithm: &str, settings: &str) -> String {
    if settings.is_empty() {
        algorithm.to_string()
    } else {
        format!("{algorithm} {settings}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The published FNV-1a 64 test vectors, which the three hand-written copies it replaced
    /// also gave: shard assignments, chart styles and cache names keep their values.
    #[test]
    fn stable_hash_is_fnv1a_64() {
        assert_eq!(stable_hash(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(stable_hash("a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(stable_hash("foobar"), 0x8594_4171_f739_67e8);
    }
}
