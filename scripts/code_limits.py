#!/usr/bin/env python3
"""Fails on a giant: a source file over 800 lines in any crate, a non-test function over 150
lines anywhere, or one over 100 lines in harness/src.

A function's length runs from its `fn` line to the line of its closing brace, found by brace
matching over the source with comments and literals blanked (scripts/rust_source.py). Test
code is exempt: `#[cfg(test)] mod NAME { … }` blocks, `#[test]` functions, and the files
`tests.rs`, `*_tests.rs` and those under a `tests/` folder. A function is named
`Type::name` inside an `impl` or `trait` (and `outer::inner` when nested).

Today's giants are listed in scripts/code_limits_allow.txt, one a line: `path lines` for a
file, `path:function lines` for a function. The list may only shrink: the check fails on a
giant not in it, on a listed one that grew, and on a listed one that is now within its limit
or gone (remove its line). `--update` rewrites the list with the current figures of the listed
giants, dropping the ones that were fixed; it never adds one.

Usage: scripts/code_limits.py [--root DIR] [--allow FILE] [--update]
"""
import argparse
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from rust_source import block_end, body_open, is_test_file, line_of, mask, test_regions  # noqa: E402

FILE_LIMIT = 800
FN_LIMIT = 150
HARNESS_FN_LIMIT = 100
HARNESS = "harness/src/"
SKIP_DIRS = {"target", "node_modules"}

CONTAINER = re.compile(
    r"^[ \t]*(?:pub(?:\([^)]*\))?\s+)?(?:unsafe\s+)?(?:default\s+)?(impl|trait)\b", re.M
)
FN = re.compile(r"\bfn\s+([A-Za-z_][A-Za-z0-9_]*)")


def container_name(kind, header):
    """The type an `impl` block is for, or a trait's name."""
    header = re.sub(r"\bwhere\b.*", "", header, flags=re.S)
    if kind == "trait":
        m = re.match(r"\s*([A-Za-z_]\w*)", header)
        return m.group(1) if m else "trait"
    header = re.sub(r"^\s*<", "<", header)
    if header.startswith("<"):  # impl<T: Bound<U>> …: drop the generics
        depth = 0
        for j, ch in enumerate(header):
            depth += {"<": 1, ">": -1}.get(ch, 0)
            if depth == 0:
                header = header[j + 1:]
                break
    target = re.split(r"\bfor\b", header)[-1]
    target = re.split(r"<", target)[0]
    idents = re.findall(r"[A-Za-z_]\w*", target)
    idents = [i for i in idents if i not in ("dyn", "mut", "const")]
    return idents[-1] if idents else "impl"


def functions(code):
    """(qualified name, first line, last line, start offset) of every function with a body."""
    containers = []
    for m in CONTAINER.finditer(code):
        open_at = body_open(code, m.end())
        if open_at is not None:
            name = container_name(m.group(1), code[m.end():open_at])
            containers.append((m.start(), block_end(code, open_at), name))
    fns = []
    for m in FN.finditer(code):
        open_at = body_open(code, m.end())
        if open_at is None:
            continue
        end = block_end(code, open_at)
        fns.append((m.start(), end, m.group(1)))
    out = []
    for start, end, name in fns:
        outer = sorted(
            (s, n) for s, e, n in containers + fns if s < start and end <= e
        )
        qual = "::".join([n for _, n in outer] + [name])
        out.append((qual, line_of(code, start), line_of(code, end - 1), start))
    return out


def giants(root):
    """{key: lines} of every file and non-test function over its limit under `root`."""
    found = {}
    for f in sorted(root.rglob("*.rs")):
        rel = f.relative_to(root).as_posix()
        if any(p in SKIP_DIRS or p.startswith(".") for p in rel.split("/")[:-1]):
            continue
        if is_test_file(rel):
            continue
        text = f.read_text(encoding="utf-8", errors="replace")
        lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
        if lines > FILE_LIMIT:
            found[rel] = lines
        code = mask(text)
        tests = test_regions(code)
        limit = HARNESS_FN_LIMIT if rel.startswith(HARNESS) else FN_LIMIT
        seen = {}
        for name, first, last, start in functions(code):
            if any(s <= start < e for s, e in tests):
                continue
            seen[name] = seen.get(name, 0) + 1
            if seen[name] > 1:
                name = f"{name}#{seen[name]}"
            n = last - first + 1
            if n > limit:
                found[f"{rel}:{name}"] = n
    return found


def read_allow(path):
    allow = {}
    if not path.exists():
        return allow
    for i, line in enumerate(path.read_text().splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        key, _, n = line.rpartition(" ")
        if not key or not n.isdigit():
            sys.exit(f"{path}:{i}: expected `path[:function] lines`, got {line!r}")
        allow[key.strip()] = int(n)
    return allow


def main():
    here = Path(__file__).resolve().parent
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", type=Path, default=here.parent)
    ap.add_argument("--allow", type=Path, default=here / "code_limits_allow.txt")
    ap.add_argument("--update", action="store_true")
    args = ap.parse_args()
    found = giants(args.root)
    allow = read_allow(args.allow)
    problems = []
    for key, n in sorted(found.items()):
        if key not in allow:
            problems.append(f"new giant: {key} {n} lines")
        elif n > allow[key]:
            problems.append(f"grew: {key} {n} lines, listed at {allow[key]}")
    for key, n in sorted(allow.items()):
        if key not in found:
            problems.append(f"within its limit now (remove its line): {key} (listed at {n})")
    if args.update:
        kept = {k: min(n, found[k]) for k, n in allow.items() if k in found}
        header = [l for l in args.allow.read_text().splitlines() if l.startswith("#")] if args.allow.exists() else []
        args.allow.write_text("\n".join(header + [f"{k} {n}" for k, n in sorted(kept.items())]) + "\n")
        problems = [p for p in problems if p.startswith(("new giant", "grew"))]
    print(f"files over {FILE_LIMIT} lines, functions over {FN_LIMIT} ({HARNESS_FN_LIMIT} in {HARNESS}): {len(found)}, listed {len(allow)}")
    for p in problems:
        print("  " + p)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
