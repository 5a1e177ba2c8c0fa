#!/usr/bin/env python3
"""Checks the documentation stays navigable: every relative link in README.md, ARCHITECTURE.md
and docs/*.md names a file that exists and, with #anchor, a heading of that page (GitHub's
anchor rule); the README names the two set-up scripts, which exist, and stays a short
introduction (at most MAX_README_LINES lines; the reference belongs in docs/).

The manual states how things are now; the lab book (docs/notes/) keeps dated investigations.
So README.md, ARCHITECTURE.md and docs/*.md may hold no dated heading (an ISO date, a day and
month with a year, or an "Again after/at ..." section), no dated paragraph lead (a bold lead
with an ISO date in it or in a parenthesis right after it), no "since/until/before YYYY-MM-DD"
outside table rows (a rule-history table dates its rows), and no issue reference ("issue 43",
"issues 25 and 43", "#43", "issue-43", in text, code blocks or file names they link); every
note in docs/notes/ (README.md there is its index) names its date (YYYY-MM-DD) and its commit
(a hash in backticks after the word "commit") in its first NOTE_HEADER_LINES lines. Links in
the notes are checked like the manual's.

Usage: scripts/check_docs.py [REPO_ROOT]. Prints each problem as FILE: what, exits 1 if any.
scripts/check_docs.py --self-test checks the checker: a small tree that passes, and each rule
flipped by changing one line of it.
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
# A paragraph (or list item) that opens with a bold lead carrying a date, in the lead or in a
# parenthesis right after it: "**A ring of sheets** (2026-12-03, evening).", "**Measured
# 2026-12-03, 14:14 UTC**". Such a paragraph is a journal entry.
DATED_LEAD = re.compile(r"^\s*(?:[-*+]\s+|\d+\.\s+)?\*\*([^*]+)\*\*\s*(?:\(([^)]*)\))?")
ISO_DATE = re.compile(r"\b\d{4}-\d{2}-\d{2}\b")
# "since 2026-12-03", "until 2026-12-05", "before 2026-12-04": narration of when things changed.
DATED_CHANGE = re.compile(r"\b(since|until|before)\s+\d{4}-\d{2}-\d{2}\b", re.IGNORECASE)
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
    """Dated headings, dated paragraph leads, "since/until/before DATE" outside tables and issue
    references in a page of the manual (not a note)."""
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
            lead = None if inside else DATED_LEAD.match(line)
            if lead and any(g and ISO_DATE.search(g) for g in lead.groups()):
                problems.append(f"{rel}:{number}: dated paragraph lead \"{lead.group(0).strip()}\": "
                                "state the current figure; the story of how it came to be "
                                "belongs in a note in docs/notes/")
            # Table rows (a rule-history table, say) may date their entries.
            if not inside and not line.lstrip().startswith("|"):
                for m in DATED_CHANGE.finditer(line):
                    problems.append(f"{rel}:{number}: dated narration (\"{m.group(0)}\"): "
                                    "say how it is now; when it changed belongs in a note")
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


def self_test():
    """A tree that passes, then one change per rule that must fail it, and look-alikes that
    must not (a hex colour, an anchor, a date in prose, a note's own dated heading)."""
    import tempfile

    good = {
        "README.md": "# t\n\n./scripts/bench.sh ./scripts/test.sh [m](docs/page.md#now)\n",
        "ARCHITECTURE.md": "# a\n",
        "docs/page.md": "# Page\n\n## Now\n\nColour #1f77b4, [here](#now), measured on "
                        "2026-12-05 ([note](notes/2026-12-05-x.md)).\n\n"
                        "**A ring of sheets** (the splatter). Each bucket once.\n\n"
                        "| rule | commit | changed |\n|---|---|---|\n"
                        "| H5 | fc24378 (2026-12-03) | tolerance, since 2026-12-03 |\n\n"
                        "The fill is a compute pass.\n",
        "docs/notes/README.md": "# Notes\n\n[x](2026-12-05-x.md)\n",
        "docs/notes/2026-12-05-x.md": "# X\n\nDate: 2026-12-05. Commit: `abc1234`.\n\n"
                                      "Text.\n\n## Again after issue 43 (2026-12-05)\n\n"
                                      "**At abc1234** (2026-12-05, evening). Since 2026-12-03 "
                                      "a compute pass.\n",
        "scripts/bench.sh": "", "scripts/test.sh": "",
    }
    flips = [
        ("docs/page.md", "## Now", "## Now (2026-12-05, night)", "dated heading"),
        ("docs/page.md", "## Now", "## Now, 5 December 2026", "dated heading"),
        ("docs/page.md", "## Now", "## Again after the sort", "dated heading"),
        ("docs/page.md", "Colour", "As issue 43 asks, colour", "names an issue"),
        ("docs/page.md", "Colour", "Issues 25 and 43: colour", "names an issue"),
        ("docs/page.md", "Colour", "See #43. Colour", "names an issue"),
        ("README.md", "# t", "# t (issue-43)", "names an issue"),
        ("docs/notes/2026-12-05-x.md", "Date: 2026-12-05. ", "", "no date"),
        ("docs/notes/2026-12-05-x.md", "Commit: `abc1234`.", "", "no commit"),
        ("docs/page.md", "(#now)", "(#later)", "no heading with that anchor"),
        ("docs/page.md", "(the splatter)", "(2026-12-03, evening)", "dated paragraph lead"),
        ("docs/page.md", "**A ring of sheets**", "- **Measured 2026-12-03, 14:14 UTC**",
         "dated paragraph lead"),
        ("docs/page.md", "The fill is", "Since 2026-12-03 the fill is", "dated narration"),
        ("docs/page.md", "The fill is", "Until 2026-12-05 the fill was", "dated narration"),
        ("docs/page.md", "The fill is", "Before 2026-12-04 the fill was", "dated narration"),
    ]

    def problems_of(files):
        with tempfile.TemporaryDirectory() as root:
            for name, text in files.items():
                path = os.path.join(root, name)
                os.makedirs(os.path.dirname(path), exist_ok=True)
                with open(path, "w", encoding="utf-8") as f:
                    f.write(text)
                if name.endswith(".sh"):
                    os.chmod(path, 0o755)
            return check(root)

    failures = []
    found = problems_of(good)
    if found:
        failures.append(f"the good tree fails: {found}")
    for name, old, new, expected in flips:
        files = dict(good)
        assert old in files[name], (name, old)
        files[name] = files[name].replace(old, new, 1)
        found = problems_of(files)
        if not any(expected in p for p in found):
            failures.append(f"{name}: {old!r} -> {new!r} should give \"{expected}\", gave {found}")
    for f in failures:
        print(f)
    print(f"check_docs --self-test: {len(flips) + 1 - len(failures)} of {len(flips) + 1} cases "
          "as expected", file=sys.stderr)
    return 1 if failures else 0


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
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
