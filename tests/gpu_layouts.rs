//! Every `#[repr(C)]` struct a renderer uploads to the GPU (bytemuck `Pod`) against the WGSL
//! struct it mirrors: the WGSL is parsed with naga (the version wgpu compiles it with), and
//! the struct's size and each member's offset and size must equal what the Rust compiler laid
//! out (`size_of`, `offset_of!`, listed by each crate's `gpu_layouts()`). This replaces the
//! "keep in step" comments: a field added, removed, reordered or retyped on one side only fails
//! here, not as a silently wrong picture.
//!
//! Padding members (names starting with `_` or `pad`) may be split differently on the two
//! sides (`_pad: [u32; 3]` against `_pad0.._pad2`); every other member is matched in order.

use render_core::gpu_layout::{GpuLayouts, RustLayout};

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

/// Differences between a Rust layout and its WGSL struct in `sources` (empty: they agree).
fn differences(rust: &RustLayout, sources: &GpuLayouts) -> Vec<String> {
    let (file, name) = rust
        .wgsl
        .split_once("::")
        .unwrap_or_else(|| panic!("{}: wgsl {:?} is not FILE::STRUCT", rust.rust, rust.wgsl));
    let source = sources
        .source(file)
        .unwrap_or_else(|| panic!("{}: the crate gives no source of {file}", rust.rust));
    let (size, wgsl) = wgsl_layout(file, source, name);
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

fn check(crate_name: &str, layouts: &GpuLayouts) {
    let mut bad = vec![];
    for l in &layouts.structs {
        let d = differences(l, layouts);
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
    let layouts = render_core::gpu_sort::gpu_layouts();
    assert!(!layouts.structs.is_empty());
    check("render-core", &layouts);
}

/// Every algorithm of the registry, through its description: a new algorithm is checked
/// without a line here. Each of tetbench's own uploads at least one struct.
#[test]
fn every_algorithms_structs_match_their_wgsl() {
    for d in harness::algorithms::REGISTRY {
        let layouts = (d.gpu_layouts)();
        assert!(
            d.is_peer() || !layouts.structs.is_empty(),
            "{}: no GPU struct declared",
            d.name
        );
        check(d.name, &layouts);
    }
}

/// The check itself sees a moved member, a wrong size and a missing member.
#[test]
fn the_check_finds_a_moved_member_a_wrong_size_and_a_missing_member() {
    let layouts = havs::gpu_layouts();
    let real = layouts.structs[0].clone();
    assert!(differences(&real, &layouts).is_empty());
    let mut moved = real.clone();
    moved.members[3].offset += 4;
    assert!(!differences(&moved, &layouts).is_empty());
    let mut bigger = real.clone();
    bigger.size += 16;
    assert!(!differences(&bigger, &layouts).is_empty());
    let mut missing = real;
    missing.members.remove(4);
    assert!(!differences(&missing, &layouts).is_empty());
}
