#!/usr/bin/env python3
"""Checks the documentation stays navigable: every relative link in README.md, ARCHITECTURE.md
and docs/*.md names a file that exists and, with #anchor, a heading of that page (GitHub's
anchor rule); the README names the two set-up scripts, which exist, and stays a short
introduction (at most MAX_README_LINES lines; the reference belongs in docs/).

The manual states how things are now; the lab book (docs/notes/) keeps dated investigations.
So README.md, ARCHITECTURE.md and docs/*.md may hold no dated heading (an ISO date, a day and
month with a year, or an "Again after/at ..." section) and no issue reference ("issue 43",
"issues 25 and 43", "#43", "issue-43", in text, code blocks or file names they link); every
note in docs/notes/ (README.md there is its index) names its date (YYYY-MM-DD) and its commit
(a hash in backticks after the word "commit") in its first NOTE_HEADER_LINES lines. Links in
the notes are checked like the manual's.

Usage: scripts/check_docs.py [REPO_ROOT]. Prints each problem as FILE: what, exits 1 if any.
Standard library only, so CI runs it before anything is installed."""

import glob
import os
import re
import sys

MAX_README_LINES = 250
SETUP_SCRIPTS = ("scripts/bench.sh", "scripts/test.sh")
NOTE_HEADER_LINES = 5

MONTHS = ("January|February|March|April|May|June|July|August|September|October|November|"
          "December")
DATED_HEADING = re.compile(
    rf"\b\d{{4}}-\d{{2}}-\d{{2}}\b|\b\d{{1,2}} ({MONTHS}) \d{{4}}\b|\b({MONTHS}) \d{{1,2}},? \d{{4}}\b"
    r"|^Again (after|at)\b", re.IGNORECASE)
# "issue 43", "Issue 43's", "issues 25 and 43", "issue-43", "issue #43", and a bare "#43" (one
# to four digits, not part of a word, a link anchor or a hex colour such as #1f77b4).
ISSUE_REF = re.compile(r"\bissues?[ -]#?\d+\b|(?<![\w#/&])#\d{1,4}\b(?![\w-])", re.IGNORECASE)
NOTE_DATE = re.compile(r"\b\d{4}-\d{2}-\d{2}\b")
NOTE_COMMIT = re.compile(r"\bcommit\b[^`]*`[0-9a-f]{7,40}`", re.IGNORECASE)

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


def manual_problems(page, rel):
    """Dated headings and issue references in a page of the manual (not a note)."""
    problems = []
    inside = False
    with open(page, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if FENCE.match(line):
                inside = not inside
            heading = None if inside else HEADING.match(line)
            if heading and DATED_HEADING.search(heading.group(2)):
                problems.append(f"{rel}:{number}: dated heading \"{heading.group(2)}\": "
                                "the manual says how things are now; a dated investigation "
                                "belongs in docs/notes/")
            for m in ISSUE_REF.finditer(line):
                problems.append(f"{rel}:{number}: names an issue (\"{m.group(0)}\"): a reader "
                                "has no issue tracker; say what it is")
    return problems


def note_problems(note, rel):
    """A note's first lines must give its date and the commit it measured."""
    with open(note, encoding="utf-8") as f:
        head = "".join(line for _, line in zip(range(NOTE_HEADER_LINES), f))
    problems = []
    if not NOTE_DATE.search(head):
        problems.append(f"{rel}: no date (YYYY-MM-DD) in its first {NOTE_HEADER_LINES} lines")
    if not NOTE_COMMIT.search(head):
        problems.append(f"{rel}: no commit (\"commit `abc1234`\") in its first "
                        f"{NOTE_HEADER_LINES} lines")
    return problems


def check(root):
    problems = []
    manual = [os.path.join(root, p) for p in ("README.md", "ARCHITECTURE.md")]
    manual += sorted(glob.glob(os.path.join(root, "docs", "*.md")))
    notes = sorted(glob.glob(os.path.join(root, "docs", "notes", "*.md")))
    for page in manual:
        if os.path.exists(page):
            problems += manual_problems(page, os.path.relpath(page, root))
    for note in notes:
        if os.path.basename(note) != "README.md":
            problems += note_problems(note, os.path.relpath(note, root))
    for page in manual + notes:
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
    print("check_docs: links, anchors, the README's shape, the manual's present tense "
          "and the notes' dates and commits are fine", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
