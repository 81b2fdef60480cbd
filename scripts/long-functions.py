#!/usr/bin/env python3
"""Lists the functions of Rust crates that are longer than N lines, outside tests.

A function's length runs from the line of its `fn` keyword to the line of its closing brace (attributes
and doc comments are not counted). Comments, string and char literals are blanked before the braces are
matched, so a `{` inside a string does not count. Test code is skipped: `#[cfg(test)]` items (modules or
functions) and the `tests/`, `benches/` and `examples/` folders. Nested functions are listed on their own
and also count towards the function that holds them.

Usage: python3 scripts/long-functions.py [--max N] [CRATE_DIR ...]   (default N=80, every crate under crates/)
Prints one line per long function, longest first within each crate, then a count per crate. It reports and
always exits 0 (it is a measure, not a gate). Standard library only.
"""

import os
import re
import sys

SKIPPED_FOLDERS = {"tests", "benches", "examples", "target"}


def blank(text, start, end):
    """The text from start to end with everything but newlines replaced by spaces (line numbers kept)."""
    return "".join(c if c == "\n" else " " for c in text[start:end])


def mask_comments_and_literals(text):
    """The source with comments, strings and char literals blanked; same length, same line breaks."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(blank(text, i, j))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(blank(text, i, j))
            i = j
        elif (m := re.compile(r'b?r(#*)"').match(text, i)) and (i == 0 or not text[i - 1].isalnum()):
            closing = '"' + m.group(1)
            j = text.find(closing, m.end())
            j = n if j < 0 else j + len(closing)
            out.append(blank(text, i, j))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append(blank(text, i, j + 1))
            i = j + 1
        elif c == "'" and (m := re.compile(r"'(?:\\u\{[0-9a-fA-F]+\}|\\.|[^'\\\n])'").match(text, i)):
            out.append(blank(text, i, m.end()))
            i = m.end()
        else:
            out.append(c)
            i += 1
    return "".join(out)


def matching_brace(text, open_at):
    """The index just past the brace that closes the one at open_at."""
    depth, j = 0, open_at
    while j < len(text):
        depth += {"{": 1, "}": -1}.get(text[j], 0)
        j += 1
        if depth == 0:
            break
    return j


def test_spans(text):
    """The (start, end) spans of `#[cfg(test)]` items that have a body in braces."""
    spans = []
    for m in re.finditer(r"#\[cfg\(test\)\]", text):
        open_at = text.find("{", m.end())
        semicolon = text.find(";", m.end())
        if open_at < 0 or (0 <= semicolon < open_at):
            continue  # `#[cfg(test)] mod tests;` or a `use`: the file itself is skipped by name
        spans.append((m.start(), matching_brace(text, open_at)))
    return spans


def functions(text):
    """(name, first line, line count) of every `fn` item with a body in the masked text."""
    found = []
    for m in re.finditer(r"\bfn\s+(\w+)", text):
        depth, j = 0, m.end()
        # The body starts at the first `{` outside parentheses and angle brackets; a `;` first means no body.
        while j < len(text):
            ch = text[j]
            if ch in "(<[":
                depth += 1
            elif ch in ")]" or (ch == ">" and text[j - 1] != "-"):
                depth -= 1
            elif depth <= 0 and ch in "{;":
                break
            j += 1
        if j >= len(text) or text[j] == ";":
            continue
        end = matching_brace(text, j)
        first = text.count("\n", 0, m.start()) + 1
        last = text.count("\n", 0, end - 1) + 1
        found.append((m.group(1), m.start(), first, last - first + 1))
    return found


def rust_files(crate_dir):
    for root, dirs, files in os.walk(crate_dir):
        dirs[:] = sorted(d for d in dirs if d not in SKIPPED_FOLDERS)
        for name in sorted(files):
            if name.endswith(".rs") and name != "tests.rs":
                yield os.path.join(root, name)


def long_functions(crate_dir, max_lines):
    rows = []
    for path in rust_files(crate_dir):
        with open(path, encoding="utf-8") as f:
            text = mask_comments_and_literals(f.read())
        spans = test_spans(text)
        for name, offset, line, count in functions(text):
            if count > max_lines and not any(s <= offset < e for s, e in spans):
                rows.append((count, os.path.relpath(path, crate_dir), line, name))
    return sorted(rows, key=lambda r: (-r[0], r[1], r[2]))


def main(argv):
    max_lines, crates = 80, []
    args = iter(argv)
    for arg in args:
        if arg == "--max":
            max_lines = int(next(args))
        elif arg in ("-h", "--help"):
            print(__doc__)
            return 0
        else:
            crates.append(arg)
    if not crates:
        crates = sorted(os.path.join("crates", d) for d in os.listdir("crates"))
        crates = [c for c in crates if os.path.isdir(os.path.join(c, "src"))]
    total = 0
    for crate in crates:
        rows = long_functions(crate, max_lines)
        total += len(rows)
        for count, path, line, name in rows:
            print(f"{count:5} {crate}/{path}:{line} {name}")
        print(f"{crate}: {len(rows)} function(s) over {max_lines} lines")
    print(f"total: {total} function(s) over {max_lines} lines")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
