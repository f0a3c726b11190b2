#!/usr/bin/env python3
"""Usage: scripts/doc-links.py [REPO]: every relative link in README.md, ARCHITECTURE.md,
BENCHMARKS.md and docs/*.md names a file that exists inside the repository (fenced and inline
code are not links). Prints each broken one as FILE:LINE; exit 1 if any."""
import glob, os, re, sys
root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else ".")
files = ["README.md", "ARCHITECTURE.md", "BENCHMARKS.md"] + sorted(glob.glob("docs/*.md", root_dir=root))
inline = re.compile(r'\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\)')
refdef = re.compile(r'(?:^|\n\n)[ ]{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s|$)')
bad = n = 0
for f in files:
    text = open(os.path.join(root, f), encoding="utf-8").read()
    blank = lambda m: re.sub(r"[^\n]", " ", m.group(0))
    text = re.sub(r"^(```|~~~).*?^\1", blank, text, flags=re.S | re.M)
    text = re.sub(r"`[^`\n]*`", blank, text)
    for m in list(inline.finditer(text)) + list(refdef.finditer(text)):
        target = m.group(1)
        if re.match(r"^[a-zA-Z][a-zA-Z+.-]*:", target) or target.startswith("#"):
            continue
        n += 1
        path = target.split("#")[0]
        full = os.path.normpath(os.path.join(root, os.path.dirname(f), path))
        if not (os.path.exists(full) and (full + os.sep).startswith(root + os.sep)):
            bad += 1
            print(f"{f}:{text.count(chr(10), 0, m.start(1)) + 1}: {target}: no such file")
print(f"{len(files)} files, {n} relative links, {bad} broken")
sys.exit(1 if bad else 0)
