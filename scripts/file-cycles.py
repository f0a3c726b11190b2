#!/usr/bin/env python3
"""The workspace's structure drawing: which source file uses which, per crate, and any import cycle.

Issue 31 asks that no two files (or longer chains of files) of a crate import each other. This
script reads every crate's `src/` (and the Python extension's `python/src/`), resolves each
`use crate::..`, `use super::..`, `use self::..` and each inline `crate::a::b` path to the file that
defines the item (following `pub use` re-exports of a parent module to the file that defines the
item), and prints the strongly connected components of more than one file. Test modules
(`#[cfg(test)] mod .. { }` to the end of the file) are not part of the production graph.

    scripts/file-cycles.py            # prints cycles; exit 1 if any
    scripts/file-cycles.py --dot      # the whole graph as Graphviz dot on stdout
    scripts/file-cycles.py --root DIR # another tree laid out as this one (the test's fixtures)

The test `crates/isotrack-cli/tests/structure.rs` runs it on the workspace (no cycle) and on a
small tree with one (found, exit 1).

Written by hand (a small Python script, no dependency) because the Rust tools that draw module
graphs (cargo-modules) need a compiler toolchain build of their own and report modules, not files,
and we want this check cheap enough for CI.
"""

import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


def strip_comments(text):
    """Drops // and /* */ comments and string literals' contents (paths in strings are not uses)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif c == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            out.append('""')
            i += 1
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not text[i - 1].isalnum()):
            m = re.match(r'r(#*)"', text[i:])
            end = '"' + m.group(1)
            j = text.find(end, i + len(m.group(0)))
            i = n if j < 0 else j + len(end)
            out.append('""')
        elif c == "'" and re.match(r"'(\\.|[^\\'])'", text[i:i + 4]):
            m = re.match(r"'(\\.|[^\\'])'", text[i:])
            i += len(m.group(0))
            out.append("' '")
        else:
            out.append(c)
            i += 1
    return "".join(out)


def drop_test_modules(text):
    """Removes each `#[cfg(test)] mod NAME { ... }` block (brace-matched; comments and strings are
    already stripped, so braces balance)."""
    pat = re.compile(r"#\[cfg\(test\)\]\s*(pub(\([^)]*\))?\s+)?mod\s+" + IDENT + r"\s*\{")
    while True:
        m = pat.search(text)
        if not m:
            return text
        depth, i = 1, m.end()
        while i < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[i], 0)
            i += 1
        text = text[: m.start()] + text[i:]


def parse_use_tree(s):
    """`a::{b, c::d as e, f::*}` -> [[a,b], [a,c,d], [a,f,*]]."""
    toks = re.findall(IDENT + r"|::|\{|\}|,|\*", s)
    pos = 0

    def tree(prefix):
        nonlocal pos
        paths, cur = [], list(prefix)
        while pos < len(toks):
            t = toks[pos]
            if t == "{":
                pos += 1
                while pos < len(toks) and toks[pos] != "}":
                    paths += tree(cur)
                    if pos < len(toks) and toks[pos] == ",":
                        pos += 1
                pos += 1
                return paths
            if t in (",", "}"):
                break
            if t == "::":
                pos += 1
                continue
            if t == "as":
                pos += 2
                continue
            cur.append(t)
            pos += 1
        if cur != list(prefix) or not paths:
            paths.append(cur)
        return paths

    return tree([])


class Crate:
    def __init__(self, src):
        self.src = src
        self.files = {}  # module path tuple -> file
        for dirpath, _, names in os.walk(src):
            for name in names:
                if not name.endswith(".rs") or name == "main.rs":
                    continue
                rel = os.path.relpath(os.path.join(dirpath, name), src)[:-3].split(os.sep)
                if rel == ["lib"]:
                    mod = ()
                elif rel[-1] == "mod":
                    mod = tuple(rel[:-1])
                else:
                    mod = tuple(rel)
                self.files[mod] = os.path.join(dirpath, name)
        self.text, self.reexports = {}, {}
        for mod, path in self.files.items():
            with open(path, encoding="utf-8") as f:
                text = drop_test_modules(strip_comments(f.read()))
            self.text[mod] = text
            rex = {}
            for m in re.finditer(r"\bpub(\([^)]*\))?\s+use\s+([^;]+);", text):
                for p in parse_use_tree(m.group(2)):
                    if not p or p[-1] == "*":
                        continue
                    if p[0] not in ("crate", "super", "self") and \
                            tuple(mod) + (p[0],) not in self.files:
                        rex[p[-1]] = None  # another crate's item
                        continue
                    rex[p[-1]] = self.absolute(mod, p)
            self.reexports[mod] = rex

    def absolute(self, mod, path):
        mod = list(mod)
        if path[0] == "crate":
            return path[1:]
        if path[0] == "self":
            return mod + path[1:]
        if path[0] == "super":
            i = 0
            while i < len(path) and path[i] == "super":
                mod, i = mod[:-1], i + 1
            return mod + path[i:]
        return mod + path  # a child module named without `self::`

    def resolve(self, path, depth=0):
        """The module whose file defines `path`'s item (or the deepest module it names)."""
        mod = ()
        for i, seg in enumerate(path):
            if mod + (seg,) in self.files:
                mod = mod + (seg,)
                continue
            rex = self.reexports.get(mod, {})
            if seg in rex and depth < 16 and rex[seg] != list(mod) + [seg]:
                if rex[seg] is None:
                    return None  # re-exported from another crate: no edge in this one
                return self.resolve(rex[seg] + path[i + 1:], depth + 1)
            return mod
        return mod

    def edges(self):
        out = {}
        for mod, text in self.text.items():
            targets = set()
            # `pub use` re-exports declare the API; they are not a use of the item (followed in
            # `resolve` instead).
            uses = list(re.finditer(r"(?<!pub )(?<!\) )\buse\s+([^;]+);", text))
            for m in uses:
                for p in parse_use_tree(m.group(1)):
                    if not p or p[0] not in ("crate", "super", "self"):
                        if p and tuple(mod) + (p[0],) in self.files:
                            p = ["self"] + p
                        else:
                            continue
                    targets.add(self.resolve(self.absolute(mod, [s for s in p if s != "*"])))
            body = re.sub(r"\buse\s+[^;]+;", "", text)
            for m in re.finditer(r"(?<![\w:])(" + IDENT + r")((?:::" + IDENT + r")+)", body):
                head = m.group(1)
                if head in ("crate", "super", "self"):
                    p = [head] + m.group(2).split("::")[1:]
                elif tuple(mod) + (head,) in self.files:
                    # a child module named bare (`moving::report(..)`, also inside macros)
                    p = ["self", head] + m.group(2).split("::")[1:]
                else:
                    continue
                targets.add(self.resolve(self.absolute(mod, p)))
            targets.discard(tuple(mod))
            targets.discard(None)
            out[mod] = sorted(targets)
        return out


def sccs(graph):
    index, low, stack, on, comps, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, []):
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
            comps.append(comp)

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            visit(v)
    return [c for c in comps if len(c) > 1]


def crates():
    for name in sorted(os.listdir(os.path.join(ROOT, "crates"))):
        src = os.path.join(ROOT, "crates", name, "src")
        if os.path.isdir(src):
            yield name, src
    src = os.path.join(ROOT, "python", "src")
    if os.path.isdir(src):
        yield "python", src


def main():
    global ROOT
    args = sys.argv[1:]
    if "--root" in args:
        i = args.index("--root")
        if i + 1 >= len(args):
            print("error: --root takes a directory", file=sys.stderr)
            return 2
        ROOT = os.path.abspath(args[i + 1])
        del args[i:i + 2]
    dot = "--dot" in args
    found = 0
    if dot:
        print("digraph files {\n  rankdir=LR;")
    for name, src in crates():
        c = Crate(src)
        g = c.edges()
        rel = {m: os.path.relpath(p, ROOT) for m, p in c.files.items()}
        if dot:
            print(f'  subgraph "cluster_{name}" {{ label="{name}";')
            for m, ts in sorted(g.items()):
                for t in ts:
                    print(f'    "{rel[m]}" -> "{rel[t]}";')
            print("  }")
        for comp in sccs(g):
            found += 1
            files = sorted(rel[m] for m in comp)
            links = [f"{rel[a]} -> {rel[b]}" for a in comp for b in g[a] if b in comp]
            print(f"cycle in {name}: " + ", ".join(files), file=sys.stderr)
            for link in sorted(links):
                print(f"    {link}", file=sys.stderr)
    if dot:
        print("}")
    if not dot:
        print(f"{found} file cycle(s)" if found else "no file cycles", file=sys.stderr)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
