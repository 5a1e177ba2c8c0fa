//! Every `#[repr(C)]` struct a renderer uploads to the GPU (bytemuck `Pod`) against the WGSL
//! struct it mirrors: the WGSL is parsed with naga (the version wgpu compiles it with), and
//! the struct's size and each member's offset and size must equal what the Rust compiler laid
//! out (`size_of`, `offset_of!`, listed by each crate's `gpu_layouts()`). This replaces the
//! "keep in step" comments: a field added, removed, reordered or retyped on one side only fails
//! here, not as a silently wrong picture.
//!
//! Padding members (names starting with `_` or `pad`) may be split differently on the two
//! sides (`_pad: [u32; 3]` against `_pad0.._pad2`); every other member is matched in order.

use render_core::gpu_layout::RustLayout;

/// The WGSL files of each crate, composed as the crate composes them before compiling.
fn wgsl_source(file: &str) -> String {
    match file {
        "gpu_sort.wgsl" => include_str!("../renderers/core/src/gpu_sort.wgsl").into(),
        "pass1.wgsl" => include_str!("../renderers/fragment-pt/src/pass1.wgsl").into(),
        "pass2.wgsl" => include_str!("../renderers/fragment-pt/src/pass2.wgsl").into(),
        "gator.wgsl" => include_str!("../renderers/gator-pt/src/gator.wgsl").into(),
        // havs.rs: `const K` in front, the shared k-buffer after (any K: the uniforms do not
        // depend on it).
        "havs.wgsl" => format!(
            "const K: u32 = 6u;\n{}\n{}",
            include_str!("../renderers/havs/src/havs.wgsl"),
            include_str!("../renderers/havs/src/kbuffer.wgsl")
        ),
        "keys.wgsl" => include_str!("../renderers/havs/src/keys.wgsl").into(),
        "common.wgsl" => include_str!("../renderers/raycast/src/common.wgsl").into(),
        "cast.wgsl" => format!(
            "{}\n{}",
            include_str!("../renderers/raycast/src/common.wgsl"),
            include_str!("../renderers/raycast/src/cast.wgsl")
        ),
        "frame.wgsl" => include_str!("../renderers/splat/src/frame.wgsl").into(),
        "splat.wgsl" => include_str!("../renderers/splat/src/splat.wgsl").into(),
        other => panic!("no WGSL file {other} is known to the layout test"),
    }
}

#[derive(Debug)]
struct Member {
    name: String,
    offset: usize,
    size: usize,
}

/// The declarations of `source` a struct's layout can depend on: its `struct`, `const` and
/// `alias` items. The renderers prepend generated code (the chunked storage accessors of
/// `render_core::bind::ChunkedBuffer`, `const K`) to their WGSL at pipeline creation, so the
/// functions of a file alone do not parse; the layout never depends on them.
fn type_declarations(source: &str) -> String {
    let mut out = String::new();
    let mut rest = source;
    while let Some(i) = ["struct ", "const ", "alias "]
        .iter()
        .filter_map(|k| {
            rest.match_indices(k)
                .find(|(i, _)| *i == 0 || rest.as_bytes()[i - 1] == b'\n')
                .map(|(i, _)| i)
        })
        .min()
    {
        let item = &rest[i..];
        let end = if item.starts_with("struct ") {
            item.find('}').map(|e| e + 1)
        } else {
            item.find(';').map(|e| e + 1)
        }
        .unwrap_or(item.len());
        out.push_str(&item[..end]);
        out.push('\n');
        rest = &item[end..];
    }
    out
}

/// Size and members of WGSL struct `name` in `source`, as naga lays it out.
fn wgsl_layout(file: &str, source: &str, name: &str) -> (usize, Vec<Member>) {
    let decls = type_declarations(source);
    let module = naga::front::wgsl::parse_str(&decls)
        .unwrap_or_else(|e| panic!("{file}: {}", e.emit_to_string(&decls)));
    let gctx = module.to_ctx();
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() != Some(name) {
            continue;
        }
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{file}: {name} is not a struct");
        };
        let members = members
            .iter()
            .map(|m| Member {
                name: m.name.clone().unwrap_or_default(),
                offset: m.offset as usize,
                size: module.types[m.ty].inner.size(gctx) as usize,
            })
            .collect();
        return (*span as usize, members);
    }
    panic!("{file}: no struct {name}");
}

fn is_padding(name: &str) -> bool {
    name.starts_with('_') || name.starts_with("pad")
}

/// Differences between a Rust layout and its WGSL struct (empty: they agree).
fn differences(rust: &RustLayout) -> Vec<String> {
    let (file, name) = rust
        .wgsl
        .split_once("::")
        .unwrap_or_else(|| panic!("{}: wgsl {:?} is not FILE::STRUCT", rust.rust, rust.wgsl));
    let (size, wgsl) = wgsl_layout(file, &wgsl_source(file), name);
    let mut out = vec![];
    if size != rust.size {
        out.push(format!("size: Rust {} bytes, WGSL {size}", rust.size));
    }
    let r: Vec<_> = rust
        .members
        .iter()
        .filter(|m| !is_padding(m.name))
        .collect();
    let w: Vec<_> = wgsl.iter().filter(|m| !is_padding(&m.name)).collect();
    if r.len() != w.len() {
        out.push(format!(
            "members: Rust {:?}, WGSL {:?}",
            r.iter().map(|m| m.name).collect::<Vec<_>>(),
            w.iter().map(|m| &m.name).collect::<Vec<_>>()
        ));
    }
    for (a, b) in r.iter().zip(&w) {
        if a.offset != b.offset || a.size != b.size {
            out.push(format!(
                "Rust {} at {} ({} bytes) vs WGSL {} at {} ({} bytes)",
                a.name, a.offset, a.size, b.name, b.offset, b.size
            ));
        }
    }
    // Padding must only fill what the other side leaves between members.
    let covered = |ms: &mut dyn Iterator<Item = (usize, usize)>| {
        let mut bytes = vec![false; size.max(rust.size)];
        for (o, s) in ms {
            for b in bytes.iter_mut().skip(o).take(s) {
                *b = true;
            }
        }
        bytes
    };
    let rb = covered(&mut r.iter().map(|m| (m.offset, m.size)));
    let wb = covered(&mut w.iter().map(|m| (m.offset, m.size)));
    if rb != wb {
        out.push("the non-padding members cover different bytes".into());
    }
    out
}

fn check(crate_name: &str, layouts: Vec<RustLayout>) {
    assert!(!layouts.is_empty());
    let mut bad = vec![];
    for l in &layouts {
        let d = differences(l);
        if !d.is_empty() {
            bad.push(format!(
                "{crate_name}: {} vs {}: {}",
                l.rust,
                l.wgsl,
                d.join("; ")
            ));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn render_core_gpu_sort_structs_match_their_wgsl() {
    check("render-core", render_core::gpu_sort::gpu_layouts());
}

#[test]
fn havs_structs_match_their_wgsl() {
    check("havs", havs::gpu_layouts());
}

#[test]
fn gator_pt_structs_match_their_wgsl() {
    check("gator-pt", gator_pt::gpu_layouts());
}

#[test]
fn fragment_pt_structs_match_their_wgsl() {
    check("fragment-pt", fragment_pt::gpu_layouts());
}

#[test]
fn raycast_structs_match_their_wgsl() {
    check("raycast", raycast::resources::gpu_layouts());
}

#[test]
fn splat_structs_match_their_wgsl() {
    check("splat", splat::gpu_layouts());
}

/// The check itself sees a moved member, a wrong size and a missing member.
#[test]
fn the_check_finds_a_moved_member_a_wrong_size_and_a_missing_member() {
    let real = havs::gpu_layouts().remove(0);
    assert!(differences(&real).is_empty());
    let mut moved = real.clone();
    moved.members[3].offset += 4;
    assert!(!differences(&moved).is_empty());
    let mut bigger = real.clone();
    bigger.size += 16;
    assert!(!differences(&bigger).is_empty());
    let mut missing = real;
    missing.members.remove(4);
    assert!(!differences(&missing).is_empty());
}
