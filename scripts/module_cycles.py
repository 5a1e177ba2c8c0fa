#!/usr/bin/env python3
"""Prints the module dependency graph of a Rust crate's src/ and its cycles.

Every file is a node, named by its module path: `a.rs` and `a/mod.rs` are `a`, `a/b.rs` is
`a::b`, so the files inside a folder module are nodes of their own. An edge A -> B is a path in
A's code (comments and literals blanked, scripts/rust_source.py) that names module B or an item
of it: `crate::b::…`, `super::…`, `self::…`, or `child::…` for a module A declares, in a `use`
tree or anywhere in the code. A name a module re-exports (`pub use m::{Name}`, in lib.rs or in
a folder's mod.rs) counts as the module it comes from; a module's re-export of its own
descendants' items (a folder's facade) is no edge. Paths inside an inline `mod NAME { … }`
resolve `super` to the file's module first.

Two graphs are printed: the library code alone, and with the test code included (`#[cfg(test)]`
items, `tests.rs` and `*_tests.rs` files, which count as their module's tests). Each ends in
`cycles: N` and lists the elementary cycles.

`--check` reads every workspace member's src/ and compares the cycles (tests included) with
scripts/module_cycles_allow.txt (`SRC: a -> b -> a`, one a line): the cycles known today, which
may only go. It fails on a cycle not listed and on a listed one that is gone.

Usage: scripts/module_cycles.py [datasets/src] | scripts/module_cycles.py --check
"""
import argparse
import re
import sys
import tomllib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from rust_source import ATTRS, block_end, mask  # noqa: E402

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


def item_end(code, start):
    """Offset just past the item that starts at `start`: its `;` or its closing brace."""
    if re.match(r"\s*(?:pub(?:\([^)]*\))?\s+)?use\b", code[start:]):
        j = code.find(";", start)
        return len(code) if j < 0 else j + 1
    depth = 0
    for j in range(start, len(code)):
        ch = code[j]
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif depth == 0 and ch == "{":
            return block_end(code, j)
        elif depth == 0 and ch == ";":
            return j + 1
    return len(code)


def split_tests(code):
    """(library code, test code): each `#[cfg(test)]` item goes to the second, blanked in the first."""
    lib, test = list(code), [" " if c != "\n" else c for c in code]
    for m in re.finditer(r"#\[cfg\(test\)\]\s*" + ATTRS, code):
        for j in range(m.start(), item_end(code, m.end())):
            test[j], lib[j] = code[j], (" " if code[j] != "\n" else "\n")
    return "".join(lib), "".join(test)


def inline_mods(code):
    """(start, end) of inline `mod NAME { … }` blocks."""
    out = []
    for m in re.finditer(r"\bmod\s+" + IDENT + r"\s*\{", code):
        out.append((m.end() - 1, block_end(code, m.end() - 1)))
    return out


def expand_use(tree):
    """The paths of a `use` tree: `a::{b, c::{d as e, self}}` -> [(a,b), (a,c,d) as e, (a,c)]."""
    tree = re.sub(r"\s+", " ", tree).strip()
    out = []

    def walk(prefix, s):
        s = s.strip()
        if not s:
            return
        if "{" in s:
            head, _, rest = s.partition("{")
            head = head.strip().rstrip(":").strip()
            pre = prefix + [p.strip() for p in head.split("::") if p.strip()]
            body = rest[: rest.rfind("}")]
            depth, item = 0, ""
            for c in body:
                depth += {"{": 1, "}": -1}.get(c, 0)
                if c == "," and depth == 0:
                    walk(pre, item)
                    item = ""
                else:
                    item += c
            walk(pre, item)
            return
        path, _, alias = s.partition(" as ")
        segs = [p.strip() for p in path.split("::") if p.strip()]
        if segs and segs[-1] == "self":
            segs = segs[:-1]
        full = prefix + segs
        if full:
            out.append((tuple(full), alias.strip() or full[-1]))

    walk([], tree.lstrip(":"))
    return out


MOD_DECL = re.compile(r"((?:#\[[^\]]*\]\s*)*)(?:pub(?:\([^)]*\))?\s+)?mod\s+(" + IDENT + r")\s*;")


class Crate:
    """The crate's files found from lib.rs through their `mod NAME;` declarations (`#[path]`
    followed). A file declared under `#[cfg(test)]` is test code of the module declaring it."""

    def __init__(self, src):
        self.src = src
        self.units = []  # (module path, node it counts for, library code, test code)
        self.modules = {()}
        root = src / "lib.rs"
        if root.exists():
            self._walk(root, (), (), False)
        self.reexports = {}
        for mod, _, lib, _ in self.units:
            self.reexports.setdefault(mod, {}).update(self._reexports(mod, lib))

    def _walk(self, path, mod, node, is_test):
        text = path.read_text(encoding="utf-8", errors="replace")
        code = mask(text)
        lib, test = ("", code) if is_test else split_tests(code)
        self.units.append((mod, node, lib, test))
        if path.name in ("lib.rs", "main.rs", "mod.rs"):
            folder = path.parent
        else:
            folder = path.parent / path.stem
        for m in MOD_DECL.finditer(code):
            attrs = text[m.start(1):m.end(1)]
            name = m.group(2)
            given = re.search(r'#\[path\s*=\s*"([^"]*)"\]', attrs)
            if given:
                child = path.parent / given.group(1)
            elif (folder / f"{name}.rs").exists():
                child = folder / f"{name}.rs"
            else:
                child = folder / name / "mod.rs"
            if not child.exists():
                continue
            child_test = is_test or "cfg(test)" in re.sub(r"\s", "", attrs)
            child_mod = mod + (name,)
            self.modules.add(child_mod)
            self._walk(child, child_mod, node if child_test else child_mod, child_test)

    def _reexports(self, mod, code):
        names = {}
        for m in re.finditer(r"\bpub(?:\([^)]*\))?\s+use\s+([^;]*);", code):
            for path, alias in expand_use(m.group(1)):
                names[alias] = (mod, path)
        return names

    def resolve(self, mod, segs, inline_depth=0, follow=4):
        """The module a path names from module `mod`, or None when it leaves the crate."""
        segs = list(segs)
        if not segs:
            return None
        if segs[0] == "crate":
            base, rest = (), segs[1:]
        elif segs[0] == "self":
            base, rest = mod, segs[1:]
        elif segs[0] == "super":
            k = 0
            while k < len(segs) and segs[k] == "super":
                k += 1
            up = max(0, k - inline_depth)
            if up > len(mod):
                return None
            base, rest = mod[: len(mod) - up], segs[k:]
        elif mod + (segs[0],) in self.modules:
            base, rest = mod, segs
        else:
            return None
        cur = base
        for i, seg in enumerate(rest):
            if cur + (seg,) in self.modules:
                cur = cur + (seg,)
                continue
            target = self.reexports.get(cur, {}).get(seg)
            if target and follow:
                found = self.resolve(target[0], target[1], 0, follow - 1)
                if found is not None:
                    return found
            break
        return cur

    def edges(self, mod, code):
        targets = set()
        inline = inline_mods(code)

        def depth(at):
            return sum(1 for s, e in inline if s < at < e)

        for m in re.finditer(r"\buse\s+([^;]*);", code):
            d = depth(m.start())
            for path, _ in expand_use(m.group(1)):
                t = self.resolve(mod, path, d)
                if t is not None:
                    targets.add(t)
        rest = re.sub(r"\buse\s+[^;]*;", lambda m: " " * len(m.group(0)), code)
        for m in re.finditer(r"(?<![\w:])(" + IDENT + r")((?:\s*::\s*" + IDENT + r")+)", rest):
            segs = [m.group(1)] + re.findall(IDENT, m.group(2))
            t = self.resolve(mod, segs, depth(m.start()))
            if t is not None:
                targets.add(t)
        return targets

    def graphs(self):
        """(library graph, graph with the tests) over the nodes, named `a::b`."""
        def name(m):
            return "::".join(m)

        nodes = sorted({node for _, node, _, _ in self.units if node})
        lib_graph = {name(n): set() for n in nodes}
        all_graph = {name(n): set() for n in nodes}
        for mod, node, lib, test in self.units:
            for code, graphs in ((lib, (lib_graph, all_graph)), (test, (all_graph,))):
                for t in self.edges(mod, code):
                    if t[: len(node)] == node or not t:
                        continue
                    for g in graphs:
                        g.setdefault(name(node), set()).add(name(t))
        lib_graph.pop("", None)
        all_graph.pop("", None)
        return lib_graph, all_graph


def cycles(graph):
    """All elementary cycles (small graphs: plain DFS from each node, smallest node first)."""
    found = []
    for start in sorted(graph):
        stack = [(start, [start])]
        while stack:
            node, path = stack.pop()
            for nxt in sorted(graph.get(node, ())):
                if nxt == start:
                    found.append(path + [start])
                elif nxt > start and nxt not in path:
                    stack.append((nxt, path + [nxt]))
    return sorted(found, key=lambda c: (len(c), c))


def workspace_sources(root):
    """The `src/` folders of the workspace's members (root Cargo.toml) that have a lib.rs."""
    with open(root / "Cargo.toml", "rb") as f:
        members = tomllib.load(f).get("workspace", {}).get("members", [])
    return [f"{m}/src" for m in members if (root / m / "src" / "lib.rs").exists()]


def read_allow(path):
    allow = set()
    if path.exists():
        for line in path.read_text().splitlines():
            line = line.strip()
            if line and not line.startswith("#"):
                allow.add(line)
    return allow


def check(root, allow_path):
    """Every member's cycles (tests included) against the list of known ones: fails on a cycle
    not listed and on a listed one that is gone (remove its line). Returns the exit code."""
    allow = read_allow(allow_path)
    found = set()
    for src in workspace_sources(root):
        _, all_graph = Crate(root / src).graphs()
        found |= {f"{src}: {' -> '.join(c)}" for c in cycles(all_graph)}
    problems = [f"new cycle: {c}" for c in sorted(found - allow)]
    problems += [f"gone (remove its line): {c}" for c in sorted(allow - found)]
    print(f"import cycles in {len(workspace_sources(root))} crates: {len(found)}, listed {len(allow)}")
    for p in problems:
        print("  " + p)
    return 1 if problems else 0


def main():
    here = Path(__file__).resolve().parent
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("src", nargs="?", default="datasets/src", help="a crate's src/ to print")
    ap.add_argument("--check", action="store_true", help="check every workspace member instead")
    ap.add_argument("--root", type=Path, default=here.parent)
    ap.add_argument("--allow", type=Path, default=here / "module_cycles_allow.txt")
    args = ap.parse_args()
    if args.check:
        sys.exit(check(args.root, args.allow))
    lib_graph, all_graph = Crate(Path(args.src)).graphs()
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
