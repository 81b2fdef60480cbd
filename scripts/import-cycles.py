#!/usr/bin/env python3
"""Lists the file-level `crate::` / `super::` import edges of a Rust crate and fails on any cycle.

An edge A -> B means a file A names an item through a path that resolves to file B (`use crate::x::y`,
`crate::x::Y` written inline, `super::...`). A module's `mod child;` declaration is not an edge, but a
re-export (`pub use child::Item`) is: a parent that re-exports a child and a child that imports the parent
form a cycle. Test modules (`#[cfg(test)] mod ... { }`) are skipped unless `--tests` is given; comments
and string literals are ignored.

Usage: python3 scripts/import-cycles.py [--tests] [--edges] CRATE_DIR   (e.g. crates/presrs-core)
Exit status 1 when a cycle exists. Standard library only.
"""

import os
import re
import sys


def strip_comments_and_strings(text):
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r'r#*"(?:.|\n)*?"#*', '""', text)
    text = re.sub(r'"(?:\\.|[^"\\])*"', '""', text)
    # Char literals such as '{' would unbalance the brace matching below.
    text = re.sub(r"'(?:\\.|[^'\\])'", "' '", text)
    # Visibility paths (`pub(in crate::m)`) name a scope, not a dependency.
    return re.sub(r"pub\(in [\w:]+\)", "pub", text)


def strip_test_modules(text):
    out, i = [], 0
    for m in re.finditer(r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+\w+\s*\{", text):
        if m.start() < i:
            continue
        out.append(text[i : m.start()])
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        i = j
    out.append(text[i:])
    return "".join(out)


def expand(path):
    """`a::{b, c::{d, e}}` -> [a::b, a::c::d, a::c::e] (aliases and globs dropped)."""
    path = re.sub(r"\s+", "", re.sub(r"\s+as\s+\w+", "", path))
    m = re.match(r"^(.*?)\{(.*)\}$", path)
    if not m:
        return [path.rstrip(":").removesuffix("::*")]
    prefix, inner = m.groups()
    parts, depth, cur = [], 0, ""
    for ch in inner:
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
            continue
        depth += {"{": 1, "}": -1}.get(ch, 0)
        cur += ch
    parts.append(cur)
    result = []
    for part in filter(None, parts):
        if part == "self":
            result.append(prefix.rstrip(":"))
        else:
            result.extend(expand(prefix + part))
    return result


def module_files(src):
    """Module path (tuple) -> file, for every file under src."""
    files = {}
    for root, _, names in os.walk(src):
        for name in names:
            if not name.endswith(".rs"):
                continue
            rel = os.path.relpath(os.path.join(root, name), src)
            parts = rel[:-3].split(os.sep)
            if parts[-1] in ("lib", "main", "mod"):
                parts = parts[:-1]
            files[tuple(parts)] = rel
    return files


def resolve(segments, files):
    """The file of the longest module prefix of `segments`."""
    for n in range(len(segments), -1, -1):
        if tuple(segments[:n]) in files:
            return files[tuple(segments[:n])]
    return None


def inline_modules(text):
    """(start, end, name) of every inline `mod name { ... }` block."""
    spans = []
    for m in re.finditer(r"\bmod\s+(\w+)\s*\{", text):
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        spans.append((m.start(), j, m.group(1)))
    return spans


def absolute_paths(module, text, files):
    """Every `crate::`/`super::`/`self::`/child path in `text`, made absolute (a list of segments)."""
    spans = inline_modules(text)
    found = []
    uses = [(m.start(), p) for m in re.finditer(r"\buse\s+([^;]+);", text) for p in expand(m.group(1))]
    inline = [(m.start(), m.group(1)) for m in re.finditer(r"(?<![\w:])((?:crate|super)(?:::\w+)+)", text)]
    for pos, path in uses + inline:
        here = list(module) + [name for start, end, name in spans if start < pos < end]
        segs = path.split("::")
        if segs[0] == "crate":
            absolute = segs[1:]
        elif segs[0] in ("super", "self"):
            base = here
            while segs and segs[0] in ("super", "self"):
                base = base[:-1] if segs[0] == "super" else base
                segs = segs[1:]
            absolute = base + segs
        elif len(segs) > 1 and tuple(here + [segs[0]]) in files:
            # `pub use child::Item` in a parent module.
            absolute = here + segs
        else:
            continue
        found.append(absolute)
    return found


def edges(src, tests):
    files = module_files(src)
    texts = {}
    for module, rel in files.items():
        with open(os.path.join(src, rel), encoding="utf-8") as f:
            text = strip_comments_and_strings(f.read())
        texts[module] = text if tests else strip_test_modules(text)
    # Re-exports (`pub use a::b::Item;`, also `pub(crate) use`) are looked through: naming `m::Item` depends
    # on the file that defines `Item`, not on the facade `m` that re-exports it.
    reexports = {}
    for module, text in texts.items():
        for m in re.finditer(r"\bpub(?:\([^)]*\))?\s+use\s+([^;]+);", text):
            for path in expand(m.group(1)):
                segs = path.split("::")
                if segs[0] == "crate":
                    target = segs[1:]
                elif segs[0] == "super":
                    target = list(module)[:-1] + segs[1:]
                elif segs[0] == "self":
                    target = list(module) + segs[1:]
                elif tuple(list(module) + [segs[0]]) in files:
                    target = list(module) + segs
                else:
                    continue
                reexports[tuple(list(module) + [segs[-1]])] = target

    def through(absolute, depth=0):
        key = tuple(absolute)
        for n in range(len(key), 0, -1):
            if key[:n] in reexports and depth < 20:
                return through(list(reexports[key[:n]]) + list(key[n:]), depth + 1)
        return absolute

    found = {}
    for module, rel in files.items():
        targets = set()
        for absolute in absolute_paths(module, texts[module], files):
            target = resolve(through(absolute), files)
            if target and target != rel:
                targets.add(target)
        found[rel] = targets
    return found


def cycles(graph):
    """Strongly connected components with more than one file (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def main(argv):
    tests = "--tests" in argv
    show = "--edges" in argv
    dirs = [a for a in argv if not a.startswith("--")]
    if len(dirs) != 1:
        print(__doc__, file=sys.stderr)
        return 2
    src = os.path.join(dirs[0], "src")
    graph = edges(src, tests)
    if show:
        for v in sorted(graph):
            for w in sorted(graph[v]):
                print(f"{v} -> {w}")
    found = cycles(graph)
    for comp in found:
        inner = [f"{v} -> {w}" for v in comp for w in sorted(graph[v]) if w in comp]
        print("cycle among " + ", ".join(comp) + ":\n    " + "\n    ".join(inner))
    if not found:
        print(f"no import cycles among the {len(graph)} files of {src}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
