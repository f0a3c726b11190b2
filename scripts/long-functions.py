#!/usr/bin/env python3
"""Production functions longer than a limit (default 80 lines), longest first.

Issue 31 asks that a production function over ~80 lines be split by concept, unless it is a
parser whose straight line reads better (it then says why in a comment). This script reads every
`crates/*/src/**.rs` and `python/src/**.rs`, finds each `fn` with a body, and measures it from
its signature's first line to its closing brace. Test code is left out: `#[cfg(test)] mod .. { }`
blocks, files declared as `#[cfg(test)] mod name;`, and functions marked `#[test]` or
`#[cfg(test)]`.

    scripts/long-functions.py           # functions over 80 lines
    scripts/long-functions.py 60        # over another limit

Prints `lines  file:line  name`, what is left to split; then, apart, the functions kept long
with a reason: those with a comment `// Long by choice: WHY` on a line of their doc comment or
attributes just above `fn`, or on the first line of their body. Exit 0 always (a list to read,
not a gate: a parser may keep its straight line).
"""

import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def blank_out(text):
    """Comments, string and char literals replaced by spaces (line feeds kept), so that braces
    balance and line numbers stay those of the file."""
    out, i, n = list(text), 0, len(text)

    def clear(a, b):
        for k in range(a, b):
            if out[k] != "\n":
                out[k] = " "

    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            clear(i, j)
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
            clear(i, j)
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            end = '"' + m.group(1)
            j = text.find(end, i + len(m.group(0)))
            j = n if j < 0 else j + len(end)
            clear(i, j)
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            clear(i, j + 1)
            i = j + 1
        elif c == "'" and re.match(r"'(\\.|\\u\{[0-9a-fA-F]+\}|[^\\'])'", text[i:i + 12]):
            m = re.match(r"'(\\.|\\u\{[0-9a-fA-F]+\}|[^\\'])'", text[i:])
            clear(i, i + len(m.group(0)))
            i += len(m.group(0))
        else:
            i += 1
    return "".join(out)


def matching_brace(text, open_at):
    depth, i = 0, open_at
    while i < len(text):
        if text[i] == "{":
            depth += 1
        elif text[i] == "}":
            depth -= 1
            if depth == 0:
                return i
        i += 1
    return len(text) - 1


def test_spans(text):
    """Character spans of `#[cfg(test)] mod name { .. }` blocks."""
    spans = []
    for m in re.finditer(r"#\[cfg\(test\)\]\s*(pub(\([^)]*\))?\s+)?mod\s+\w+\s*\{", text):
        spans.append((m.start(), matching_brace(text, m.end() - 1)))
    return spans


def test_files(path, text):
    """Files declared as `#[cfg(test)] mod name;` from the file at `path`."""
    here = os.path.dirname(path)
    stem = os.path.splitext(os.path.basename(path))[0]
    sub = here if stem in ("lib", "mod", "main") else os.path.join(here, stem)
    out = set()
    for m in re.finditer(r"#\[cfg\(test\)\]\s*(pub(\([^)]*\))?\s+)?mod\s+(\w+)\s*;", text):
        name = m.group(3)
        out.add(os.path.normpath(os.path.join(sub, name + ".rs")))
        out.add(os.path.normpath(os.path.join(sub, name, "mod.rs")))
    return out


FN = re.compile(r"\bfn\s+(\w+)")


def functions(path, text):
    clean = blank_out(text)
    skip = test_spans(clean)
    for m in FN.finditer(clean):
        if any(a <= m.start() <= b for a, b in skip):
            continue
        # the body's `{` (a `;` first: a trait method's declaration, no body)
        j = m.end()
        depth = 0
        while j < len(clean):
            ch = clean[j]
            if ch in "(<[":
                depth += 1
            elif ch in ")>]":
                depth -= 1 if ch != ">" or clean[j - 1] != "-" else 0
            elif ch == ";" and depth <= 0:
                j = -1
                break
            elif ch == "{" and depth <= 0:
                break
            j += 1
        if j < 0 or j >= len(clean):
            continue
        before = clean[max(0, m.start() - 300):m.start()]
        if re.search(r"#\[(test|cfg\(test\))\]\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\([^)]*\))?\s+)?(?:const\s+|async\s+|unsafe\s+)*$", before):
            continue
        end = matching_brace(clean, j)
        first = clean.count("\n", 0, m.start()) + 1
        last = clean.count("\n", 0, end) + 1
        yield last - first + 1, first, m.group(1), kept_reason(text, first)


KEPT = re.compile(r"//\s*Long by choice:\s*(.*)")


def kept_reason(text, first):
    """The reason of a `// Long by choice: WHY` comment on the comment and attribute lines just
    above line `first` (1-based, the `fn` line) or on the first line of its body after the
    signature (`None` without one)."""
    lines = text.split("\n")

    def reason(i):
        """The reason starting on line `i`, with the `//` lines that continue it."""
        m = KEPT.search(lines[i])
        if not m:
            return None
        words = [m.group(1).strip()]
        for line in lines[i + 1:]:
            t = line.strip()
            if not t.startswith("//") or t.startswith("///"):
                break
            words.append(t[2:].strip())
        return " ".join(words)

    i = first - 2
    while i >= 0 and lines[i].strip().startswith(("//", "#[")):
        if KEPT.search(lines[i]):
            return reason(i)
        i -= 1
    j = first - 1
    while j < len(lines) and not lines[j].rstrip().endswith("{"):
        j += 1
    if j + 1 < len(lines) and KEPT.search(lines[j + 1]):
        return reason(j + 1)
    return None


def sources():
    for top in [os.path.join(ROOT, "crates", c, "src") for c in sorted(os.listdir(os.path.join(ROOT, "crates")))] + [
        os.path.join(ROOT, "python", "src")
    ]:
        for dirpath, _, names in os.walk(top):
            for name in sorted(names):
                if name.endswith(".rs"):
                    yield os.path.join(dirpath, name)


def main():
    limit = int(sys.argv[1]) if len(sys.argv) > 1 else 80
    paths = list(sources())
    texts = {}
    tests = set()
    for p in paths:
        with open(p, encoding="utf-8") as f:
            texts[p] = f.read()
        tests |= test_files(p, blank_out(texts[p]))
    rows, kept = [], []
    for p in paths:
        if os.path.normpath(p) in tests:
            continue
        for n, line, name, why in functions(p, texts[p]):
            if n > limit:
                (rows if why is None else kept).append((n, os.path.relpath(p, ROOT), line, name, why))
    for r in (rows, kept):
        r.sort(key=lambda r: (-r[0], r[1], r[2]))
    for n, p, line, name, _ in rows:
        print(f"{n:5}  {p}:{line}  {name}")
    if kept:
        print("kept, with a reason:")
        for n, p, line, name, why in kept:
            print(f"{n:5}  {p}:{line}  {name}  ({why})")
    print(
        f"{len(rows)} production function(s) over {limit} lines left to split"
        f" ({len(kept)} more kept, with a reason)",
        file=sys.stderr,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
