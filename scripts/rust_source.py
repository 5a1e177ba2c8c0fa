"""Reading Rust source without a parser: shared by module_cycles.py and code_limits.py.

`mask` blanks out comments, string, byte-string, raw-string and char literals (keeping every
newline, so offsets and line numbers stay those of the file): what is left is code whose braces,
`fn` and `use` can be matched with plain scanning. `block_end` finds the brace that closes a
block; `test_regions` the `#[cfg(test)] mod NAME { … }` blocks and `#[test]` functions.
"""
import re


_RAW = re.compile(r'(?:b|c)?r(#*)"')


def _blank(s):
    return "".join(c if c == "\n" else " " for c in s)


def mask(text):
    """The source with comments and literals replaced by spaces (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        nxt = text[i + 1] if i + 1 < n else ""
        if c == "/" and nxt == "/":
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(_blank(text[i:j]))
            i = j
        elif c == "/" and nxt == "*":
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(_blank(text[i:j]))
            i = j
        elif (m := _RAW.match(text, i)) and not _ident_before(text, i):
            close = '"' + m.group(1)
            j = text.find(close, m.end())
            j = n if j < 0 else j + len(close)
            out.append(m.group(0)[0] + _blank(text[i + 1:j]))
            i = j
        elif c == '"' or (c in "bc" and nxt == '"' and not _ident_before(text, i)):
            j = i + (1 if c == '"' else 2)
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(text[i] + _blank(text[i + 1:j]))
            i = j
        elif c == "'" or (c == "b" and nxt == "'" and not _ident_before(text, i)):
            q = i if c == "'" else i + 1
            if q + 1 < n and text[q + 1] == "\\":  # escaped char literal
                j = q + 2
                while j < n and text[j] != "'":
                    j += 1
                j = min(j + 1, n)
            elif q + 2 < n and text[q + 2] == "'":  # one-character literal
                j = q + 3
            else:  # a lifetime or a label
                out.append(text[i:q + 1])
                i = q + 1
                continue
            out.append(text[i:q + 1] + _blank(text[q + 1:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def _ident_before(text, i):
    return i > 0 and (text[i - 1].isalnum() or text[i - 1] == "_")


def block_end(code, open_at):
    """Offset just past the brace matching the `{` at `open_at` in masked code."""
    depth = 0
    for j in range(open_at, len(code)):
        if code[j] == "{":
            depth += 1
        elif code[j] == "}":
            depth -= 1
            if depth == 0:
                return j + 1
    return len(code)


def body_open(code, start):
    """Offset of the `{` opening the body of the item whose header starts at `start`, or None
    when the header ends in `;` first (a declaration). Brackets and parentheses may hold `;`
    (`[u8; 4]`) and are skipped."""
    depth = 0
    for j in range(start, len(code)):
        ch = code[j]
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif depth == 0 and ch == "{":
            return j
        elif depth == 0 and ch == ";":
            return None
    return None


def line_of(code, offset):
    return code.count("\n", 0, offset) + 1


ATTRS = r"(?:#\[[^\]]*\]\s*)*"


def test_regions(code):
    """(start, end) offsets of `#[cfg(test)] mod NAME { … }` blocks and `#[test]` functions."""
    out = []
    for m in re.finditer(r"#\[cfg\(test\)\]\s*" + ATTRS + r"(?:pub(?:\([^)]*\))?\s+)?mod\s+\w+\s*\{", code):
        out.append((m.start(), block_end(code, m.end() - 1)))
    for m in re.finditer(r"#\[(?:\w+::)?test\]\s*" + ATTRS + r"(?:async\s+)?fn\s", code):
        open_at = body_open(code, m.end())
        if open_at is not None:
            out.append((m.start(), block_end(code, open_at)))
    return out


def is_test_file(rel):
    """Files that hold only tests: `tests.rs`, `*_tests.rs`, anything under a `tests/` folder."""
    parts = rel.split("/")
    return parts[-1] == "tests.rs" or parts[-1].endswith("_tests.rs") or "tests" in parts[:-1]
