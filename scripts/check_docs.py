#!/usr/bin/env python3
"""Checks the documentation stays navigable: every relative link in README.md, ARCHITECTURE.md
and docs/*.md names a file that exists and, with #anchor, a heading of that page (GitHub's
anchor rule); the README names the two set-up scripts, which exist, and stays a short
introduction (at most MAX_README_LINES lines; the reference belongs in docs/).

Usage: scripts/check_docs.py [REPO_ROOT]. Prints each problem as FILE: what, exits 1 if any.
Standard library only, so CI runs it before anything is installed."""

import glob
import os
import re
import sys

MAX_README_LINES = 250
SETUP_SCRIPTS = ("scripts/bench.sh", "scripts/test.sh")

FENCE = re.compile(r"^(```|~~~)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
LINK = re.compile(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def github_anchor(heading):
    """GitHub's heading id: lower case, punctuation but '-' and '_' dropped, spaces to '-'."""
    text = re.sub(r"`", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def prose_lines(path):
    """The lines outside fenced code blocks, with their 1-based numbers."""
    inside = False
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if FENCE.match(line):
                inside = not inside
                continue
            if not inside:
                yield number, line


def anchors(path):
    seen = {}
    ids = set()
    for _, line in prose_lines(path):
        m = HEADING.match(line)
        if m:
            base = github_anchor(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            ids.add(base if n == 0 else f"{base}-{n}")
    return ids


def check(root):
    problems = []
    pages = [os.path.join(root, p) for p in ("README.md", "ARCHITECTURE.md")]
    pages += sorted(glob.glob(os.path.join(root, "docs", "*.md")))
    for page in pages:
        if not os.path.exists(page):
            problems.append(f"{os.path.relpath(page, root)}: missing")
            continue
        for number, line in prose_lines(page):
            # Inline code may hold text that looks like a link; it is not one.
            for m in LINK.finditer(re.sub(r"`[^`]*`", "", line)):
                target = m.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):
                    continue  # http:, https:, mailto:
                path, _, anchor = target.partition("#")
                resolved = page
                if path:
                    resolved = os.path.normpath(os.path.join(os.path.dirname(page), path))
                where = f"{os.path.relpath(page, root)}:{number}"
                if not os.path.exists(resolved):
                    problems.append(f"{where}: link to {target}: no such file")
                elif anchor and resolved.endswith(".md") and anchor not in anchors(resolved):
                    problems.append(f"{where}: link to {target}: no heading with that anchor")
    readme = os.path.join(root, "README.md")
    if os.path.exists(readme):
        with open(readme, encoding="utf-8") as f:
            text = f.read()
        lines = text.count("\n")
        if lines > MAX_README_LINES:
            problems.append(f"README.md: {lines} lines, more than {MAX_README_LINES}: "
                            "move reference text to docs/")
        for script in SETUP_SCRIPTS:
            if f"./{script}" not in text:
                problems.append(f"README.md: does not name ./{script}")
            if not os.access(os.path.join(root, script), os.X_OK):
                problems.append(f"{script}: the README names it, but it is missing or "
                                "not executable")
    return problems


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    problems = check(os.path.abspath(root))
    for p in problems:
        print(p)
    if problems:
        print(f"check_docs: {len(problems)} problem(s)", file=sys.stderr)
        return 1
    print("check_docs: links, anchors and the README's shape are fine", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
