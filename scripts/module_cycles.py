#!/usr/bin/env python3
"""Prints the module dependency graph of a Rust crate's src/ and its cycles.

An edge A -> B is a `use crate::B...` or a `crate::B::` path in A's source (comments
stripped). `crate::Name` for a name the crate root re-exports (`pub use m::{Name}` in lib.rs)
counts as an edge to `m`. Two graphs are printed: the library code alone, and with the
`#[cfg(test)]` modules (and `tests.rs` files) included. A folder module (`m/mod.rs`, `m/x.rs`) counts as one node `m`.

Usage: scripts/module_cycles.py [datasets/src]
"""
import re
import sys
from pathlib import Path


def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return "\n".join(re.sub(r"//.*", "", line) for line in text.splitlines())


def split_tests(text):
    """(library part, test part): everything from the first `#[cfg(test)]` on is test code."""
    i = text.find("#[cfg(test)]")
    return (text, "") if i < 0 else (text[:i], text[i:])


def use_targets(text):
    """First path segments after `crate::`, including those in `use crate::{a::x, b}` groups."""
    out = set()
    for m in re.finditer(r"\bcrate::\{", text):
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        group = text[m.end():j - 1]
        # top-level items of the group only
        depth, item, items = 0, "", []
        for c in group:
            if c == "{":
                depth += 1
            elif c == "}":
                depth -= 1
            if c == "," and depth == 0:
                items.append(item)
                item = ""
            else:
                item += c
        items.append(item)
        for it in items:
            seg = re.match(r"\s*([A-Za-z_][A-Za-z0-9_]*)", it)
            if seg:
                out.add(seg.group(1))
    for m in re.finditer(r"\bcrate::([A-Za-z_][A-Za-z0-9_]*)", text):
        out.add(m.group(1))
    return out


def root_reexports(lib):
    names = {}
    for m in re.finditer(r"pub\s+use\s+([a-z_][a-z0-9_]*)::(\{[^}]*\}|[A-Za-z_][A-Za-z0-9_]*)", lib):
        mod, items = m.group(1), m.group(2).strip("{}")
        for it in items.split(","):
            it = it.strip()
            if it:
                names[it.split(" as ")[-1].strip()] = mod
    return names


def cycles(graph):
    """All elementary cycles (small graphs: plain DFS from each node, smallest node first)."""
    found = []
    nodes = sorted(graph)
    for start in nodes:
        stack = [(start, [start])]
        while stack:
            node, path = stack.pop()
            for nxt in sorted(graph.get(node, ())):
                if nxt == start:
                    found.append(path + [start])
                elif nxt > start and nxt not in path:
                    stack.append((nxt, path + [nxt]))
    return sorted(found, key=lambda c: (len(c), c))


def main():
    src = Path(sys.argv[1] if len(sys.argv) > 1 else "datasets/src")
    lib = strip_comments((src / "lib.rs").read_text())
    modules = set(re.findall(r"\bmod\s+([a-z_][a-z0-9_]*)\s*;", lib))
    reexp = root_reexports(lib)
    lib_graph = {m: set() for m in modules}
    all_graph = {m: set() for m in modules}
    for f in sorted(src.rglob("*.rs")):
        rel = f.relative_to(src)
        if rel == Path("lib.rs"):
            continue
        mod = rel.parts[0].removesuffix(".rs")
        if rel.name == "tests.rs":  # a folder module's `#[cfg(test)] mod tests;`
            body, tests = "", strip_comments(f.read_text())
        else:
            body, tests = split_tests(strip_comments(f.read_text()))
        for part, graphs in ((body, (lib_graph, all_graph)), (tests, (all_graph,))):
            for seg in use_targets(part):
                target = seg if seg in modules else reexp.get(seg)
                if target and target != mod:
                    for g in graphs:
                        g.setdefault(mod, set()).add(target)
    for title, g in (("library code", lib_graph), ("library + #[cfg(test)] code", all_graph)):
        print(f"== {title}")
        for m in sorted(g):
            print(f"  {m} -> {', '.join(sorted(g[m])) or '(none)'}")
        cs = cycles(g)
        print(f"  cycles: {len(cs)}")
        for c in cs:
            print("    " + " -> ".join(c))


if __name__ == "__main__":
    main()
